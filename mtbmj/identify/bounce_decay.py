"""A seat slam's ring-down as a decay law with viscous damping, Coulomb friction and the top-out stop.

The linear fit of :mod:`mtbmj.identify.bounce` reads one damped sinusoid. A real shock's ring-down
loses nearly the same amount each half cycle at first and then sticks: dry friction beside the oil.
This module reads the ring-down half cycle by half cycle instead.

**The law (derivation).** One end moves as ``m x'' + c x' + F_c sign(x') + k (x - x_eq) = 0``
(travel x, compression positive; x_eq the end's static position without friction). While the
velocity keeps one sign s the friction is a constant force, so the equation is a linear damped
oscillator about a shifted centre, ``m x'' + c x' + k (x - (x_eq - s d)) = 0`` with the friction band
``d = F_c / k`` (a length, mm here). Its solution from rest at an extremum x_n returns to rest after
exactly half a damped period pi / w_d (w_d = w_n sqrt(1 - zeta^2), zeta = c / (2 sqrt(k m))), with the
displacement from the centre reversed and scaled by ``r = exp(-pi zeta / sqrt(1 - zeta^2))``. After a
peak (s = -1, centre x_eq + d) and after a trough (s = +1, centre x_eq - d), with sigma_n = +1 at a
peak and -1 at a trough:

    x_{n+1} = c_n - r (x_n - c_n),   c_n = x_eq + sigma_n d.

In amplitudes a_n = |x_n - x_eq|: ``a_{n+1} = r a_n - (1 + r) d`` (pure friction, r = 1: 2 d per half
cycle, 4 d per cycle; pure oil, d = 0: the geometric decay r). In swings s_n = |x_{n+1} - x_n|, which
need no x_eq: ``s_{n+1} = r s_n - 2 (1 + r) d``. The motion sticks at the first extremum with
|x_n - x_eq| <= d (static friction taken equal to the sliding one). The half period is pi / w_d
whatever d is: friction changes the decay, not the timing.

**The extrema.** On the travel smoothed over 10 ms the slam is the largest compression (the fork's
within 0.25 s of the shock's), and the alternating turning points after it are found with the
hysteresis of :func:`mtbmj.identify.bounce.turning_points`. An extremum is *held* when the travel
stays within the hysteresis of it much longer than a free extremum does (more than twice a free
sinusoid's dwell at that amplitude and half period, plus 20 ms), or when it lies at full extension
(travel within the hysteresis of 0 mm: the top-out stop). The slam's own peak is forced, not free. The
free sequence starts at the first extremum after the slam that is neither held nor follows a held
one: **the half cycles that touch the top-out stop (or sit held) are excluded**, the one into the
stop and the one out of it (the end leaves the stop moving, not from rest, so that half cycle is not
free). It continues while the extrema come at the oscillation's pace (within 1.6 half periods) and
the swings decay (each level the vertex of a parabola fitted to the raw travel within a fifth of a
half period: the running extreme of a noisy signal is biased); a held extremum ends it: that is where the motion stuck, and its level (the
median of the held stretch, after its first half of a half period, when its spread is under 0.15 x
the hysteresis: at rest) is the sequence's last value; a stretch that still moves is not at rest.
So is an extremum from which the smoothed travel stays within 4 measurement floors for at least half a
half period (a free extremum stays that close a small share of it): at rest, whatever follows (a rider
shifting on the saddle steps the travel later; the step is not part of the rest). Another stop ends it
the same way.

**The fit.** Each relation x_n -> x_{n+1} is one residual; (zeta, d, x_eq) are fitted by least
squares on the whole sequence, three models: viscous only (d = 0), friction only (zeta = 0), both.
The residual scale is the larger of the fit's (RSS / dof) and the extrema's measurement floor
(the record's sample noise over the square root of the 10 ms smoothing's samples); the covariance is
s^2 (J^T J)^-1 with the Jacobian J at the optimum, and the 95 % intervals use Student's t at the fit's
degrees of freedom. The model is chosen by the **Bayesian information criterion**,
BIC = n ln(RSS / n) + (p + 1) ln n (n relations, p parameters, one more for the residual scale;
RSS floored at n x the measurement floor squared), among the models with at least one degree of
freedom; the lowest wins. A sequence that leaves every model without a degree of freedom is refused
with its count; so is a sequence whose chosen law does not decay (zeta and d both nil within
their intervals) or that grows.

**Across clicks.** A shock's friction (seals, bushings, linkage) does not change with the rebound
clicks: only the damper's oil path does. So records at several clicks are fitted together with one
friction band d common to all of them, an x_eq per record, and zeta either per record (the per-click
reading) or as ``zeta = zeta0 + slope x clicks`` (the law, fitted inside the same least squares).
That assumption is stated in the output.

**The first free half cycle's decay ratio** (what a rider sees as how fast it settles) is the ratio
of the second free swing to the first, s_1 / s_0, measured on the record and, from a law,
``r - 2 (1 + r) d / s_0`` at the record's own first swing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mtbmj.identify.bounce import SMOOTH_S, SWING_FRACTION, interval95, noise_mm, slam_peak, turning_points

MODELS = ("viscous", "friction", "both")
NONNEGATIVE = ("friction_band_mm", "zeta")  # bounded at 0 in every fit; their intervals are cut there
PACE = 1.6  # successive free extrema at most this many half periods apart
HOLD_FACTOR = 2.0  # an extremum held this many times a free extremum's dwell (plus HOLD_PAD_S) is held
HOLD_PAD_S = 0.020
STUCK_SPREAD = 0.15  # at rest: the smoothed travel's sd within this share of the hysteresis
REST_BAND = 4.0  # at rest also: from its turn on, the smoothed travel within this many measurement floors
REST_HALF = 0.5  # ... for at least this share of a half period (a free extremum stays there a small share)
IC = "BIC = n ln(RSS / n) + (p + 1) ln n over the half-cycle relations (lowest wins)"
LAW_FORM = ("x_{n+1} = c_n - r (x_n - c_n), c_n = x_eq + sigma_n d (sigma_n +1 after a peak, -1 after a trough), "
            "r = exp(-pi zeta / sqrt(1 - zeta^2)), d = F_c / k: viscous damping zeta and Coulomb friction band d "
            "(mm) per half cycle of m x'' + c x' + F_c sign(x') + k (x - x_eq) = 0")
COMMON_FRICTION = ("friction band d common to every record of an end (the shock's seals, bushings and linkage do "
                   "not change with the rebound clicks; only the damper's oil path does); zeta per record or "
                   "zeta = zeta0 + slope x clicks; x_eq per record")


def ratio(zeta: float) -> float:
    """The half-cycle amplitude ratio r of viscous damping ``zeta``."""
    zeta = min(max(zeta, 0.0), 0.999999)
    return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta))


def moving_average(x: np.ndarray, n: int) -> np.ndarray:
    """The centred mean of ``x`` over ``n`` samples, its ends padded with the end values (a copy where n <= 1)."""
    if n <= 1:
        return x.copy()
    padded = np.concatenate((np.full(n // 2, x[0]), x, np.full(n - 1 - n // 2, x[-1])))
    return np.convolve(padded, np.ones(n) / n, mode="valid")


@dataclass
class Extrema:
    """The free half-cycle extrema of one end's ring-down."""

    end: str
    slam_s: float
    levels_mm: np.ndarray  # the free sequence (peaks and troughs alternating)
    times_s: np.ndarray  # their times (nan for a stuck level)
    peak_first: bool  # the first free extremum is a peak (compression)
    stuck: bool  # the sequence ends where the motion stuck (held)
    excluded: list = field(default_factory=list)  # what was left out and why
    floor_mm: float = 0.0  # measurement floor of one extremum's level
    noise_mm: float = 0.0  # the record's sample noise
    half_period_s: float = float("nan")
    note: str = ""
    first_turn: int = 0  # the first free extremum's place among the turning points after the slam (1: the first)

    @property
    def sigma(self) -> np.ndarray:
        s = np.where(np.arange(self.levels_mm.size) % 2 == 0, 1.0, -1.0)
        return s if self.peak_first else -s

    @property
    def swings(self) -> np.ndarray:
        return np.abs(np.diff(self.levels_mm))

    def first_decay(self) -> float:
        sw = self.swings
        return float(sw[1] / sw[0]) if sw.size >= 2 and sw[0] > 0 else float("nan")


def _rest_run(xs: np.ndarray, i: int, band: float) -> np.ndarray:
    """The smoothed travel from ``i`` on while it stays within ``band`` of xs[i] (a rest, when long)."""
    off = np.flatnonzero(np.abs(xs[i:] - xs[i]) > band)
    return xs[i:i + (int(off[0]) if off.size else xs.size - i)]


def _dwell(xs: np.ndarray, i: int, tol: float) -> tuple[int, int]:
    """The contiguous stretch around ``i`` within ``tol`` of xs[i]."""
    lo = i
    while lo > 0 and abs(xs[lo - 1] - xs[i]) <= tol:
        lo -= 1
    hi = i
    while hi < xs.size - 1 and abs(xs[hi + 1] - xs[i]) <= tol:
        hi += 1
    return lo, hi


def extrema(time_s, x_mm, end: str, slam_index: int | None = None) -> Extrema:
    """The free extrema of one end's ring-down after the slam (see the module's text)."""
    t = np.asarray(time_s, float)
    x = np.asarray(x_mm, float)
    dt = float(t[1] - t[0])
    n_smooth = max(1, int(round(SMOOTH_S / dt)))
    xs = moving_average(x, n_smooth)
    peak = slam_peak(xs, dt, slam_index)
    noise = noise_mm(x)
    drop = xs[peak] - float(np.min(xs[peak:]))
    swing = max(SWING_FRACTION * drop, 5.0 * noise)
    floor_mm = max(noise / math.sqrt(n_smooth), 1e-6)
    out = Extrema(end, float(t[peak]), np.array([]), np.array([]), False, False, floor_mm=floor_mm, noise_mm=noise)
    idx = [peak] + turning_points(xs, peak, swing, falling=True)
    if len(idx) < 2:
        out.note = "no rebound after the slam"
        return out
    gaps = np.diff(t[idx[: min(len(idx), 4)]])
    half = float(np.median(gaps))  # first estimate of the half period (refined on the free sequence)

    def flat(seg: np.ndarray) -> bool:
        """At rest: the travel's spread (smoothed) within STUCK_SPREAD of the hysteresis (a ring-down
        still moving below the hysteresis is not stuck)."""
        return seg.size > 0 and float(np.std(seg)) <= STUCK_SPREAD * swing

    def kind(j: int) -> tuple[str, float]:
        """("free" | "stop" | "stuck", level): a stop is the top-out or a short hold, stuck a hold
        longer than a half period (or to the record's end)."""
        i = idx[j]
        lo, hi = _dwell(xs, i, swing)
        level = float(np.median(xs[lo:hi + 1]))
        dwell = (hi - lo) * dt
        settled = xs[min(hi, lo + int(0.5 * half / dt)):hi + 1]
        if (dwell > half or hi == xs.size - 1) and flat(settled):
            return "stuck", float(np.median(settled))  # where it rests (its noise averaged out)
        if xs[i] <= swing:  # full extension: the top-out stop (travel 0 whatever the calibration's scale)
            return "stop", level
        rest = _rest_run(xs, i, REST_BAND * floor_mm)
        if rest.size * dt >= REST_HALF * half:  # dead still from the turn on: at rest, whatever follows
            return "stuck", float(np.median(rest))
        nb = [abs(xs[idx[k]] - xs[i]) for k in (j - 1, j + 1) if 0 <= k < len(idx)]
        amp = 0.5 * float(np.mean(nb)) if nb else 0.0
        free = half if amp <= swing else 2.0 * half / math.pi * math.acos(1.0 - swing / amp)
        if dwell > HOLD_FACTOR * free + HOLD_PAD_S:
            return "stop", level
        return "free", vertex(i)

    def vertex(i: int) -> float:
        """The extremum's level: the vertex of a parabola fitted to the raw travel within a fifth of a
        half period either side (the running extreme of a noisy signal is biased by its noise)."""
        w = max(2, int(0.2 * half / dt))
        a, b = max(0, i - w), min(x.size, i + w + 1)
        tau = t[a:b] - t[i]
        c2, c1, c0 = np.polyfit(tau, x[a:b], 2)
        if c2 == 0.0 or abs(c1 / (2 * c2)) > tau.max():
            return float(xs[i])
        return float(c0 - c1 * c1 / (4 * c2))

    out.excluded.append(f"the slam's peak at {t[peak]:.3f} s (forced by the rider, not free)")
    start = 1
    while start < len(idx):
        what, level = kind(start)
        if what != "stop":
            break
        at = "the top-out stop" if xs[idx[start]] <= swing else "a held extremum"
        out.excluded.append(f"the half cycles into and out of {at} at {t[idx[start]]:.3f} s ({level:.1f} mm): the "
                            f"end leaves it moving, not from rest")
        start += 1
    if start >= len(idx):
        out.note = "no free extremum after the slam"
        return out
    what, level = kind(start)
    out.first_turn = start
    levels, times = [level], [float(t[idx[start]]) if what == "free" else float("nan")]
    stuck = what == "stuck"
    k = start
    while not stuck and k + 1 < len(idx):
        nxt = k + 1
        gap = t[idx[nxt]] - t[idx[k]]
        sw_new = abs(xs[idx[nxt]] - levels[-1])
        sw_old = abs(levels[-1] - levels[-2]) if len(levels) >= 2 else math.inf
        free_gaps = np.diff([v for v in times if math.isfinite(v)])
        h_est = float(np.median(free_gaps)) if free_gaps.size else half
        what, level = kind(nxt)
        if what == "stop":
            out.excluded.append(f"the half cycle into the stop (or hold) at {t[idx[nxt]]:.3f} s and all after it")
            break
        if gap > PACE * h_est and what != "stuck":
            out.excluded.append(f"the extrema from {t[idx[nxt]]:.3f} s on (a gap of {gap:.2f} s: another event)")
            break
        if sw_new > sw_old + swing:
            out.excluded.append(f"the extrema from {t[idx[nxt]]:.3f} s on (a swing larger than the one before: "
                                f"another event)")
            break
        levels.append(level)
        times.append(float(t[idx[nxt]]) if what == "free" else float("nan"))
        stuck = what == "stuck"
        k = nxt
    if not stuck and k == len(idx) - 1:
        # the last extremum before the motion sticks for good is no turning point (nothing turns after it)
        i = idx[k]
        m = i + (int(np.argmax(xs[i:])) if k % 2 == 1 else int(np.argmin(xs[i:])))  # idx[0] is the slam's peak
        lo, hi = _dwell(xs, m, swing)
        prev = abs(levels[-1] - levels[-2]) if len(levels) >= 2 else math.inf
        if abs(xs[m] - xs[i]) > swing and abs(xs[m] - xs[i]) <= prev + swing and (
                hi == xs.size - 1 or (hi - lo) * dt > half) and flat(xs[min(hi, lo + int(0.5 * half / dt)):hi + 1]):
            levels.append(float(np.median(xs[min(hi, lo + int(0.5 * half / dt)):hi + 1])))
            times.append(float("nan"))
            stuck = True
    if stuck and k + 1 < len(idx):
        out.excluded.append(f"the motion after it stuck (from {t[idx[k + 1]]:.3f} s on: another event or a creep)")
    out.levels_mm, out.times_s, out.stuck = np.array(levels), np.array(times), stuck
    out.peak_first = bool(len(levels) >= 2 and levels[0] > levels[1])
    ft = out.times_s[np.isfinite(out.times_s)]
    if ft.size >= 2:
        out.half_period_s = float(np.median(np.diff(ft)))
    return out


# --- the fit ---------------------------------------------------------------------------------

@dataclass
class DecayFit:
    """The decay law fitted on one or more sequences (one end)."""

    model: str
    names: list
    theta: np.ndarray
    cov: np.ndarray
    rss: float
    n: int
    dof: int
    scale_mm: float
    bic: float
    t95: float
    per_record: list  # (zeta, d, x_eq) per sequence at the optimum
    grad: object = field(default=None, repr=False)  # theta -> per-record params, for the delta method

    def value(self, name: str) -> tuple[float, float]:
        i = self.names.index(name)
        return float(self.theta[i]), float(math.sqrt(max(self.cov[i, i], 0.0)))

    def interval(self, name: str) -> list:
        """The 95 % interval of ``name`` (value -/+ t sd), cut at 0 for a quantity that cannot be
        negative (a friction band is a length, a damping ratio is not below 0): the fit itself is
        bounded there, and an interval reaching past it would print a length below zero."""
        v, sd = self.value(name)
        low = v - self.t95 * sd
        if name in NONNEGATIVE or name.startswith("zeta["):
            low = max(0.0, low)
        return [low, v + self.t95 * sd]


def _predict(levels: np.ndarray, sigma: np.ndarray, zeta: float, d: float, xeq: float) -> np.ndarray:
    r = ratio(zeta)
    c = xeq + sigma[:-1] * d
    return c - r * (levels[:-1] - c)


def _fit(seqs, model: str, mapping, names, x0, lower, upper) -> DecayFit | None:
    """Least squares of the half-cycle relations of ``seqs`` (Extrema) with parameters ``names``;
    ``mapping(theta)`` gives each sequence's (zeta, d, x_eq)."""
    from scipy.optimize import least_squares
    from scipy.stats import t as student

    n = sum(s.levels_mm.size - 1 for s in seqs)
    p = len(names)
    dof = n - p
    if dof < 1:
        return None

    def resid(theta):
        out = []
        for s, (z, d, xe) in zip(seqs, mapping(theta)):
            out.append(_predict(s.levels_mm, s.sigma, z, d, xe) - s.levels_mm[1:])
        return np.concatenate(out)

    best = None
    starts = [np.array(x0, float)]
    if "zeta" in " ".join(names):
        for z in (0.05, 0.3):
            alt = np.array(x0, float)
            for i, nm in enumerate(names):
                if nm.startswith("zeta"):
                    alt[i] = z if nm != "slope_per_click" else 0.0
            starts.append(alt)
    for s0 in starts:
        s0 = np.clip(s0, lower, upper)
        sol = least_squares(resid, s0, bounds=(lower, upper), x_scale="jac", xtol=1e-12, ftol=1e-12)
        if best is None or sol.cost < best.cost:
            best = sol
    theta = best.x
    r = resid(theta)
    jac = np.empty((r.size, p))
    for k in range(p):
        h = 1e-6 * max(abs(theta[k]), 1e-2)
        up, dn = theta.copy(), theta.copy()
        up[k] += h
        dn[k] -= h
        jac[:, k] = (resid(up) - resid(dn)) / (2 * h)
    floor = math.sqrt(sum(s.floor_mm ** 2 * (s.levels_mm.size - 1) for s in seqs) / n)
    rss = float(r @ r)
    s2 = max(rss / dof, floor ** 2)
    try:
        cov = np.linalg.pinv(jac.T @ jac) * s2
    except np.linalg.LinAlgError:
        return None
    bic = n * math.log(max(rss, n * floor ** 2) / n) + (p + 1) * math.log(n)
    return DecayFit(model, list(names), theta, cov, rss, n, dof, math.sqrt(s2), bic,
                    float(student.ppf(0.975, dof)), [tuple(v) for v in mapping(theta)])


def _start_level(seq) -> float:
    return float(np.mean(seq.levels_mm[-2:])) if seq.levels_mm.size >= 2 else float(seq.levels_mm[0])


def fit_sequence(seq: Extrema, model: str) -> DecayFit | None:
    """One record's decay law under ``model`` (viscous, friction or both); None without a degree of freedom."""
    xe0 = _start_level(seq)
    big = 1e3
    if model == "viscous":
        return _fit([seq], model, lambda th: [(th[0], 0.0, th[1])], ["zeta", "x_eq_mm"], [0.15, xe0],
                    [0.0, -big], [0.95, big])
    if model == "friction":
        return _fit([seq], model, lambda th: [(0.0, th[0], th[1])], ["friction_band_mm", "x_eq_mm"], [1.0, xe0],
                    [0.0, -big], [big, big])
    return _fit([seq], model, lambda th: [(th[0], th[1], th[2])], ["zeta", "friction_band_mm", "x_eq_mm"],
                [0.15, 1.0, xe0], [0.0, 0.0, -big], [0.95, big, big])


def fit_common(seqs, clicks, model: str, law: bool) -> DecayFit | None:
    """Sequences of one end at ``clicks`` fitted together: d common, x_eq per record, zeta per record
    (``law`` False) or zeta = zeta0 + slope x clicks (``law`` True)."""
    m = len(seqs)
    big = 1e3
    k = np.asarray(clicks, float)
    xe = [_start_level(s) for s in seqs]
    xnames = [f"x_eq_mm[{i}]" for i in range(m)]
    if law:
        zn, z0, zl, zu = ["zeta0", "slope_per_click"], [0.15, 0.0], [0.0, -1.0], [0.95, 1.0]
    else:
        zn, z0, zl, zu = [f"zeta[{i}]" for i in range(m)], [0.15] * m, [0.0] * m, [0.95] * m
    nz = len(zn)

    def zetas(th):
        if model == "friction":
            return np.zeros(m)
        return th[0] + th[1] * k if law else th[:m]

    if model == "viscous":
        names, x0, lo, hi = zn + xnames, z0 + xe, zl + [-big] * m, zu + [big] * m
        return _fit(seqs, model, lambda th: list(zip(zetas(th), [0.0] * m, th[nz:])), names, x0, lo, hi)
    if model == "friction":
        names, x0, lo, hi = ["friction_band_mm"] + xnames, [1.0] + xe, [0.0] + [-big] * m, [big] + [big] * m
        return _fit(seqs, model, lambda th: list(zip(zetas(th), [th[0]] * m, th[1:])), names, x0, lo, hi)
    names = zn + ["friction_band_mm"] + xnames
    return _fit(seqs, model, lambda th: list(zip(zetas(th), [th[nz]] * m, th[nz + 1:])), names,
                z0 + [1.0] + xe, zl + [0.0] + [-big] * m, zu + [big] + [big] * m)


def choose(fits: dict) -> str | None:
    """The model of lowest BIC among the fitted ones."""
    ok = {k: f for k, f in fits.items() if f is not None}
    return min(ok, key=lambda k: ok[k].bic) if ok else None


def predicted_first_decay(zeta: float, d: float, s0: float) -> float:
    """s_1 / s_0 of the law at a first free swing ``s0``: r - 2 (1 + r) d / s0."""
    r = ratio(zeta)
    return r - 2.0 * (1.0 + r) * d / s0


def first_decay_sd(zeta: float, zsd: float, d: float, dsd: float, s0: float, cov_zd: float = 0.0) -> float:
    """Delta-method sd of :func:`predicted_first_decay`."""
    h = 1e-6
    gz = (predicted_first_decay(zeta + h, d, s0) - predicted_first_decay(max(zeta - h, 0.0), d, s0)) / (
        zeta + h - max(zeta - h, 0.0))
    gd = -2.0 * (1.0 + ratio(zeta)) / s0
    return float(math.sqrt(max(gz * gz * zsd * zsd + gd * gd * dsd * dsd + 2 * gz * gd * cov_zd, 0.0)))


@dataclass
class EndDecay:
    """One record's end: its extrema, the three fits, the choice (or a refusal with its reason)."""

    seq: Extrema
    fits: dict
    chosen: str | None
    refusal: str = ""

    def zeta_d(self) -> tuple[float, float, float, float, float]:
        """(zeta, sd, d, sd, cov) of the chosen model (0 and 0 for a term it leaves out)."""
        f = self.fits[self.chosen]
        z, zsd = f.value("zeta") if "zeta" in f.names else (0.0, 0.0)
        d, dsd = f.value("friction_band_mm") if "friction_band_mm" in f.names else (0.0, 0.0)
        c = 0.0
        if "zeta" in f.names and "friction_band_mm" in f.names:
            c = float(f.cov[f.names.index("zeta"), f.names.index("friction_band_mm")])
        return z, zsd, d, dsd, c

    def summary(self) -> dict:
        s = self.seq
        out = {"law": LAW_FORM, "information_criterion": IC,
               "free_extrema_mm": [float(v) for v in s.levels_mm],
               "free_extrema_s": [None if not math.isfinite(v) else float(v) for v in s.times_s],
               "ends_stuck": s.stuck, "excluded": list(s.excluded),
               "measured_first_half_cycle_decay": None if not math.isfinite(s.first_decay()) else s.first_decay()}
        if math.isfinite(s.half_period_s):
            out["frequency_hz"] = 0.5 / s.half_period_s
        if self.refusal:
            out["model"] = None
            out["note"] = self.refusal
            return out
        f = self.fits[self.chosen]
        z, zsd, d, dsd, c = self.zeta_d()
        out.update({
            "model": self.chosen,
            "bic": {k: (None if v is None else v.bic) for k, v in self.fits.items()},
            "damping_ratio": z,
            "damping_ratio_ci95": [max(0.0, z - f.t95 * zsd), z + f.t95 * zsd] if "zeta" in f.names else [0.0, 0.0],
            "friction_band_mm": d,
            "friction_band_mm_ci95": ([max(0.0, d - f.t95 * dsd), d + f.t95 * dsd]
                                      if "friction_band_mm" in f.names else [0.0, 0.0]),
            "x_eq_mm": f.value("x_eq_mm")[0], "residual_scale_mm": f.scale_mm, "dof": f.dof})
        s0 = float(s.swings[0])
        pd = predicted_first_decay(z, d, s0)
        out["law_first_half_cycle_decay"] = pd
        out["law_first_half_cycle_decay_ci95"] = interval95(pd, first_decay_sd(z, zsd, d, dsd, s0, c))
        return out


MIN_SWING_NOISE = 20.0  # a ring-down's first free swing is at least this many times the record's noise


def fit_end(seq: Extrema) -> EndDecay:
    """The three models on one record's sequence, the choice by BIC, or a refusal with its reason."""
    if seq.note:
        return EndDecay(seq, {}, None, f"no decay law: {seq.note}")
    n = seq.levels_mm.size - 1
    if n >= 3 and seq.swings[0] < MIN_SWING_NOISE * seq.noise_mm:
        return EndDecay(seq, {}, None, f"no decay law: the first free swing ({seq.swings[0]:.2f} mm) is under "
                                       f"{MIN_SWING_NOISE:g} times the record's noise ({seq.noise_mm:.3f} mm): "
                                       f"not a ring-down")
    fits = {m: fit_sequence(seq, m) for m in MODELS}
    chosen = choose(fits)
    if chosen is None:
        how = (f"stuck after {n} free half cycle(s)" if seq.stuck else f"{n} free half cycle(s)")
        reason = (f"no decay law of its own: {how} (a two-parameter law needs 3 for one degree of freedom)"
                  + ("; stopping this soon is what friction does: friction-dominated" if seq.stuck else ""))
        return EndDecay(seq, fits, None, reason)
    ed = EndDecay(seq, fits, chosen)
    xe = fits[chosen].value("x_eq_mm")[0]
    if not seq.levels_mm.min() <= xe <= seq.levels_mm.max():
        ed.refusal = (f"no decay law: the fitted static position ({xe:.1f} mm) lies outside the extrema "
                      f"({seq.levels_mm.min():.1f} to {seq.levels_mm.max():.1f} mm): not a ring-down about one position")
        ed.chosen = None
    return ed


def slam_index(record) -> int:
    """The slam: the largest compression of the shock's smoothed travel (the fork's when no shock)."""
    lead = record.shock_mm if record.shock_mm is not None else record.fork_mm
    return int(np.argmax(moving_average(np.asarray(lead, float), max(1, int(round(SMOOTH_S * record.sample_rate_Hz))))))


def fit_record(record) -> dict:
    """end -> EndDecay of one ``TelemetryRecord`` (an absent sensor left out)."""
    slam = slam_index(record)
    out = {}
    for end, x in (("shock", record.shock_mm), ("fork", record.fork_mm)):
        if x is not None:
            out[end] = fit_end(extrema(record.time_s, x, end, slam))
    return out


def law_prediction(fit: DecayFit, clicks: float, s0: float) -> dict:
    """From a law fit (:func:`fit_common` with ``law`` True): zeta, the friction band and the first
    free half cycle's decay at ``clicks`` for a first free swing ``s0``, each with its sd (the law's
    parameter covariance) and the law's residual scale carried to the decay (the scatter of one
    record's extrema about any law): ``decay_sd_total``."""
    names = fit.names
    g = np.zeros(len(names))
    z, d = 0.0, 0.0
    if "zeta0" in names:
        i0 = names.index("zeta0")
        z = float(fit.theta[i0] + fit.theta[i0 + 1] * clicks)
        g[i0], g[i0 + 1] = 1.0, float(clicks)
    zsd = float(math.sqrt(max(g @ fit.cov @ g, 0.0)))
    gd = np.zeros(len(names))
    if "friction_band_mm" in names:
        j = names.index("friction_band_mm")
        d = float(fit.theta[j])
        gd[j] = 1.0
    dsd = float(math.sqrt(max(gd @ fit.cov @ gd, 0.0)))
    czd = float(g @ fit.cov @ gd)
    pd = predicted_first_decay(z, d, s0)
    psd = first_decay_sd(z, zsd, d, dsd, s0, czd)
    # one record's three extrema scattered by the residual scale: s1 / s0 = (x2 - x1) / (x1 - x0)
    r1 = pd
    msd = fit.scale_mm / s0 * math.sqrt((1 + r1) ** 2 + 1 + r1 * r1)
    return {"zeta": z, "zeta_sd": zsd, "friction_band_mm": d, "friction_band_sd": dsd, "decay": pd, "decay_sd": psd,
            "decay_sd_total": float(math.hypot(psd, msd))}


def held_out(seqs, clicks, i: int, model: str = "both") -> dict:
    """Sequence ``i`` held out: the law (``model``, friction common) fitted on the others predicts its
    first free half cycle's decay at its own first swing."""
    rest = [s for j, s in enumerate(seqs) if j != i]
    kr = [k for j, k in enumerate(clicks) if j != i]
    fit = fit_common(rest, kr, model, law=True)
    if fit is None:
        return {"clicks": clicks[i], "note": "no degree of freedom left"}
    seq = seqs[i]
    out = law_prediction(fit, clicks[i], float(seq.swings[0]))
    out.update({"clicks": clicks[i], "measured": seq.first_decay(), "fitted_on_clicks": kr})
    out["misses_by_sd_total"] = abs(out["measured"] - out["decay"]) / out["decay_sd_total"]
    return out


__all__ = ["COMMON_FRICTION", "DecayFit", "EndDecay", "Extrema", "IC", "LAW_FORM", "MODELS", "choose", "extrema", "moving_average",
           "first_decay_sd", "fit_common", "fit_end", "fit_record", "fit_sequence", "held_out", "law_prediction", "predicted_first_decay", "ratio",
           "slam_index"]

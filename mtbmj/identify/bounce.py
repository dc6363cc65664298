"""Field identification from a rider's own seat slams: the ring-down of each end after the slam.

A rider slams onto the seat and lets the bike oscillate. On each end's travel (fork, shock) the
slam is the largest compression (found on the shock, the fork's own peak within 0.25 s of it);
the free ring-down starts at the first rebound trough after it, or, where the end topped out
there (a trough at full extension is clipped, not free), where it leaves full extension. It ends
when the alternating turning points stop decaying (a swing larger than the one before, or a gap
of more than twice the half period, is another event), half a period after the last one.

Method: a least-squares fit of a damped sinusoid about a free rest level,

    x(t) = rest + exp(-a (t - t0)) (B cos(wd (t - t0)) + C sin(wd (t - t0))),

with zeta = a / sqrt(a^2 + wd^2), the damped natural frequency f_d = wd / (2 pi) and the undamped
f_n = sqrt(a^2 + wd^2) / (2 pi). Scaling the travel (another amplitude calibration) scales rest, B
and C and leaves zeta and f_d unchanged. The 95 % intervals come from the fit's covariance with
the residual variance, inflated by the residual's lag-1 autocorrelation rho (effective sample
size n (1 - rho) / (1 + rho)): the residual of a real slam is model error, smooth in time, not
independent noise.

Across records at several rebound clicks the damping ratio follows a law linear in clicks,
zeta(k) = zeta0 + slope k, fitted by weighted least squares (weights 1 / sd^2 of each record's
zeta; with more than two records the covariance is scaled by the reduced chi-square when it
exceeds 1). The spring and the sprung mass do not change with the clicks, so the undamped
frequency is the weighted mean of the records'; a predicted click's damped frequency is
f_n sqrt(1 - zeta^2). The predicted ring-down itself comes from the decay law with friction
(``mtbmj.identify.bounce_predict``: from the record's own state, inside the stroke).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mtbmj.errors import MtbmjError

ENDS = ("shock", "fork")
Z95 = 1.959963984540054  # two-sided 95 % of the normal distribution
SLAM_WINDOW_S = 0.25  # the fork's slam peak is sought this close to the shock's
SMOOTH_S = 0.010  # moving average before turning points are sought
SWING_FRACTION = 0.01  # a turning point needs a swing of this share of the slam's drop (and 5 x noise)
MIN_TURNS = 2  # turning points after the start: at least two half cycles (one whole cycle)
# A seat slam, told from the physics of what it is: an isolated large compression, then the
# suspension's free, decaying oscillation on its spring.
QUIET_BEFORE_S = (1.5, 0.5)  # the window before the slam's peak (s) in which the rider sits still
ISOLATION = 4.0  # the slam's compression above that window's level, against the window's spread (2.5-97.5 %)
MIN_SLAM_NOISE = 20.0  # the slam's compression against the record's noise
MIN_START_NOISE = 10.0  # the ring-down's first excursion from rest against the record's noise
# a sprung mass on a spring rings at sqrt(g / static deflection) / 2 pi: 6 Hz at 7 mm, 0.5 Hz at 1 m,
# a band that holds any bike's sag (and a progressive spring's stiffer tangent); wheel hop (10-20 Hz)
# and a rider's pedalling are outside it or fail the other tests
FREQUENCY_BAND_HZ = (0.5, 6.0)
MIN_EXPLAINED = 0.9  # the damped sinusoid explains at least this share of the ring-down's variance
METHOD = ("least-squares fit of a damped sinusoid x(t) = rest + exp(-zeta wn (t - t0)) (B cos(wd (t - t0)) + "
          "C sin(wd (t - t0))) to each end's free ring-down after the slam (from the first rebound trough, or "
          "where the end leaves full extension after topping out); zeta = a / sqrt(a^2 + wd^2), frequency_hz = "
          "wd / 2 pi (damped), undamped_frequency_hz = sqrt(a^2 + wd^2) / 2 pi; independent of the amplitude "
          "calibration; 95 % intervals from the fit covariance inflated for the residual's lag-1 autocorrelation "
          "(effective sample size n (1 - rho) / (1 + rho))")
LAW_FORM = "damping_ratio = zeta0 + slope_per_click * clicks (weighted least squares); undamped frequency constant"


class BounceError(MtbmjError):
    """A seat-slam record cannot be read as a ring-down: names the record and the cause."""


@dataclass
class RingDown:
    """One end's free ring-down after the slam and its fitted damped sinusoid (SI inside: s, and
    travel in mm as the record gives it)."""

    end: str
    slam_s: float
    t0_s: float
    t_end_s: float
    turns: int  # turning points after t0
    topped_out: bool
    note: str = ""
    zeta: float = float("nan")
    zeta_sd: float = float("nan")
    fd_Hz: float = float("nan")
    fd_sd: float = float("nan")
    fn_Hz: float = float("nan")
    fn_sd: float = float("nan")
    rest_mm: float = float("nan")
    x0_mm: float = float("nan")  # displacement from rest at t0
    v0_mm_per_s: float = float("nan")  # velocity at t0
    rms_mm: float = float("nan")
    rho: float = float("nan")
    params: tuple = field(default=(), repr=False)  # (a, wd, rest, B, C)

    @property
    def fitted(self) -> bool:
        return bool(self.params)

    def curve(self, t: np.ndarray) -> np.ndarray:
        a, wd, rest, b, c = self.params
        tau = np.asarray(t, float) - self.t0_s
        return rest + np.exp(-a * tau) * (b * np.cos(wd * tau) + c * np.sin(wd * tau))

    def summary(self) -> dict:
        out = {"damping_ratio": None, "damping_ratio_ci95": None, "frequency_hz": None, "frequency_hz_ci95": None,
               "undamped_frequency_hz": None, "undamped_frequency_hz_ci95": None}
        if self.fitted:
            out.update({
                "damping_ratio": self.zeta, "damping_ratio_ci95": interval95(self.zeta, self.zeta_sd),
                "frequency_hz": self.fd_Hz, "frequency_hz_ci95": interval95(self.fd_Hz, self.fd_sd),
                "undamped_frequency_hz": self.fn_Hz, "undamped_frequency_hz_ci95": interval95(self.fn_Hz, self.fn_sd),
                "rest_mm": self.rest_mm, "start_excursion_mm": self.x0_mm, "residual_rms_mm": self.rms_mm,
                "residual_lag1_autocorrelation": self.rho})
        out.update({"slam_s": self.slam_s, "fit_start_s": self.t0_s, "fit_end_s": self.t_end_s,
                    "cycles": self.turns / 2.0, "topped_out_after_slam": self.topped_out})
        if self.note:
            out["note"] = self.note
        return out


def interval95(value: float, sd: float) -> list:
    return [value - Z95 * sd, value + Z95 * sd]


def _smooth(x: np.ndarray, n: int) -> np.ndarray:
    if n <= 1:
        return x.copy()
    kernel = np.ones(n) / n
    padded = np.concatenate((np.full(n // 2, x[0]), x, np.full(n - 1 - n // 2, x[-1])))
    return np.convolve(padded, kernel, mode="valid")


def noise_mm(x: np.ndarray) -> float:
    """The record's sample-to-sample noise (robust: median absolute first difference / sqrt 2)."""
    d = np.diff(np.asarray(x, float))
    mad = 1.4826 * np.median(np.abs(d - np.median(d)))
    step = np.min(np.abs(d[d != 0])) if np.any(d != 0) else 0.0  # one count of the sensor
    return float(max(mad / math.sqrt(2.0), step))


def turning_points(x: np.ndarray, start: int, swing: float, falling: bool) -> list[int]:
    """Alternating extrema of ``x`` from ``start`` with hysteresis ``swing`` (first a trough when
    ``falling``): each index is where the running extreme stood when the signal turned by more
    than ``swing``."""
    points, best, i_best = [], x[start], start
    for i in range(start + 1, x.size):
        v = x[i]
        if falling:
            if v < best:
                best, i_best = v, i
            elif v > best + swing:
                points.append(i_best)
                falling, best, i_best = False, v, i
        else:
            if v > best:
                best, i_best = v, i
            elif v < best - swing:
                points.append(i_best)
                falling, best, i_best = True, v, i
    return points


def slam_peak(smoothed: np.ndarray, dt: float, slam_index: int | None = None) -> int:
    """The index of an end's deepest (smoothed) travel at the slam: within ``SLAM_WINDOW_S`` of the
    slam told (``slam_index``, found on the other end or on both), else the record's deepest."""
    if slam_index is None:
        return int(np.argmax(smoothed))
    w = int(round(SLAM_WINDOW_S / dt))
    lo, hi = max(0, slam_index - w), min(smoothed.size, slam_index + w + 1)
    return lo + int(np.argmax(smoothed[lo:hi]))


def ring_down(time_s: np.ndarray, x_mm: np.ndarray, end: str, slam_index: int | None = None) -> RingDown:
    """The free ring-down of one end's travel after the slam, fitted (or with a note saying why not)."""
    t = np.asarray(time_s, float)
    x = np.asarray(x_mm, float)
    dt = float(t[1] - t[0])
    xs = _smooth(x, max(1, int(round(SMOOTH_S / dt))))
    peak = slam_peak(xs, dt, slam_index)
    floor = 0.0  # full extension: travel 0 is count 0 whatever the amplitude calibration
    drop = xs[peak] - float(np.min(xs[peak:]))
    swing = max(SWING_FRACTION * drop, 5.0 * noise_mm(x))
    base = RingDown(end=end, slam_s=float(t[peak]), t0_s=float(t[peak]), t_end_s=float(t[peak]), turns=0,
                    topped_out=False)
    turns = turning_points(xs, peak, swing, falling=True)
    if not turns:
        base.note = "no rebound after the slam"
        return base
    trough = turns[0]
    topped = xs[trough] <= floor + swing
    start = trough
    if topped:  # clipped at full extension: the free motion starts where the end leaves it
        start = trough + int(np.argmax(xs[trough:] > floor + swing))
    chain = [i for i in turns[1:] if i > start]
    # the ring-down: turning points while the swings decay and come at the oscillation's pace
    kept: list[int] = []
    prev_i, prev_x, prev_swing = start, xs[start], math.inf
    for i in chain:
        half = _half_period(t, start, kept, topped)
        if abs(xs[i] - prev_x) > prev_swing or (half is not None and t[i] - t[prev_i] > 2.0 * half):
            break
        kept.append(i)
        prev_i, prev_x, prev_swing = i, xs[i], abs(xs[i] - prev_x)
    base.t0_s, base.topped_out, base.turns = float(t[start]), bool(topped), len(kept)
    if len(kept) < MIN_TURNS:
        base.t_end_s = float(t[kept[-1]]) if kept else float(t[start])
        base.note = (f"too few cycles: {len(kept)} turning point(s) after the free start "
                     f"(at least {MIN_TURNS}, one whole cycle, are needed); no fit")
        return base
    half = _half_period(t, start, kept, topped)
    stop = min(x.size - 1, int(np.searchsorted(t, t[kept[-1]] + half)))
    nxt = [i for i in turns if i > kept[-1]]
    if nxt and len(chain) > len(kept):  # the next event's turning point: stop before it moves away
        stop = min(stop, nxt[0])
    base.t_end_s = float(t[stop])
    return _judge(_fit(base, t[start:stop + 1], x[start:stop + 1], half), x[start:stop + 1], noise_mm(x))


def _judge(rd: RingDown, x: np.ndarray, noise: float) -> RingDown:
    """Keep a fitted ring-down only when it is the suspension's free oscillation: its frequency in
    ``FREQUENCY_BAND_HZ``, its damping ratio's 95 % interval inside 0 to 1 (the swings decay, and
    they oscillate), the fit explaining at least ``MIN_EXPLAINED`` of the motion, its first excursion
    ``MIN_START_NOISE`` times the noise, and its free start within one period of the slam. Otherwise
    the fit is withdrawn and the note says why."""
    if not rd.fitted:
        return rd
    lo, hi = interval95(rd.zeta, rd.zeta_sd)
    explained = 1.0 - rd.rms_mm ** 2 / max(float(np.var(x)), 1e-300)
    amplitude = math.hypot(rd.params[3], rd.params[4])
    f_lo, f_hi = FREQUENCY_BAND_HZ
    why = None
    if not f_lo <= rd.fd_Hz <= f_hi:
        why = (f"its frequency {rd.fd_Hz:.2f} Hz is outside {f_lo:g}-{f_hi:g} Hz, where a suspension rings on its "
               f"spring")
    elif not (0.0 < lo and hi < 1.0):
        why = (f"its damping ratio {rd.zeta:.3f} [{lo:.3f}, {hi:.3f}] (95 %) does not lie inside 0 to 1: the swings "
               f"do not decay measurably, or do not oscillate")
    elif explained < MIN_EXPLAINED:
        why = (f"a damped sinusoid explains {100 * max(explained, 0.0):.0f} % of its motion "
               f"(at least {100 * MIN_EXPLAINED:.0f} % for a free ring-down)")
    elif amplitude < MIN_START_NOISE * noise:
        why = (f"its first excursion ({amplitude:.2g} mm) is less than {MIN_START_NOISE:g} x the record's noise "
               f"({noise:.2g} mm)")
    elif rd.t0_s - rd.slam_s > 1.0 / rd.fd_Hz:
        why = (f"its free start comes {(rd.t0_s - rd.slam_s) * rd.fd_Hz:.1f} periods after the slam (at most one): "
               f"another event")
    if why is None:
        return rd
    note = f"no free ring-down: {why}; no fit"
    return RingDown(end=rd.end, slam_s=rd.slam_s, t0_s=rd.t0_s, t_end_s=rd.t_end_s, turns=rd.turns,
                    topped_out=rd.topped_out, note=note)


def _half_period(t: np.ndarray, start: int, kept: list[int], topped: bool) -> float | None:
    """Half the period as the turning points so far show it (from a clipped start, the stretch to
    the first one is not half a period)."""
    if len(kept) >= 2:
        return float(np.median(np.diff(t[kept])))
    if len(kept) == 1:
        return float(t[kept[0]] - t[start]) * (2.0 if topped else 1.0)
    return None


def _fit(rd: RingDown, t: np.ndarray, x: np.ndarray, half_s: float) -> RingDown:
    from scipy.optimize import least_squares

    tau = t - t[0]
    wd0 = math.pi / half_s

    def linear(a, wd):
        e = np.exp(-a * tau)
        m = np.column_stack((np.ones_like(tau), e * np.cos(wd * tau), e * np.sin(wd * tau)))
        coef, *_ = np.linalg.lstsq(m, x, rcond=None)
        return coef, m

    def resid_nl(p):
        coef, m = linear(*p)
        return m @ coef - x

    best = None
    for zeta0 in (0.05, 0.15, 0.3, 0.5):  # a few starts: the variable-projection problem is small
        a0 = zeta0 * wd0 / math.sqrt(1.0 - zeta0 ** 2)
        sol = least_squares(resid_nl, [a0, wd0], bounds=([0.0, 0.2 * wd0], [20.0 * wd0, 5.0 * wd0]), x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    a, wd = best.x
    (rest, b, c), _ = linear(a, wd)
    p = np.array([a, wd, rest, b, c])

    def model(q):
        e = np.exp(-q[0] * tau)
        return q[2] + e * (q[3] * np.cos(q[1] * tau) + q[4] * np.sin(q[1] * tau))

    r = model(p) - x
    n = x.size
    jac = np.empty((n, 5))
    for k in range(5):  # central differences on the full model
        h = 1e-6 * max(abs(p[k]), 1e-3)
        up, dn = p.copy(), p.copy()
        up[k] += h
        dn[k] -= h
        jac[:, k] = (model(up) - model(dn)) / (2 * h)
    s2 = float(r @ r) / max(1, n - 5)
    rho = lag1(r, upper=0.999999) if n > 2 else 0.0
    inflate = (1.0 + rho) / (1.0 - rho)
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2 * inflate
    except np.linalg.LinAlgError:
        rd.note = "the ring-down does not determine a damped sinusoid (singular fit); no fit"
        return rd
    w2 = a * a + wd * wd
    g_zeta = np.array([wd * wd, -a * wd]) / w2 ** 1.5
    g_fn = np.array([a, wd]) / math.sqrt(w2) / (2 * math.pi)
    c2 = cov[:2, :2]
    rd.params = tuple(float(v) for v in p)
    rd.zeta, rd.zeta_sd = float(a / math.sqrt(w2)), float(math.sqrt(max(g_zeta @ c2 @ g_zeta, 0.0)))
    rd.fd_Hz, rd.fd_sd = float(wd / (2 * math.pi)), float(math.sqrt(max(c2[1, 1], 0.0)) / (2 * math.pi))
    rd.fn_Hz, rd.fn_sd = float(math.sqrt(w2) / (2 * math.pi)), float(math.sqrt(max(g_fn @ c2 @ g_fn, 0.0)))
    rd.rest_mm, rd.x0_mm, rd.v0_mm_per_s = float(rest), float(b), float(-a * b + wd * c)
    rd.rms_mm, rd.rho = float(math.sqrt(float(r @ r) / n)), rho
    return rd


def lag1(r: np.ndarray, upper: float = 0.99) -> float:
    """The lag-1 autocorrelation of a residual ``r`` (its mean removed), within 0..``upper`` (0 for a
    residual that is all one value): a fit's residual smooth in time counts as fewer samples."""
    r = r - r.mean()
    den = float(r @ r)
    return float(np.clip((r[1:] @ r[:-1]) / den, 0.0, upper)) if den > 0 else 0.0


def find_slam(time_s: np.ndarray, x_mm: np.ndarray, name: str) -> int:
    """The index of the seat slam on ``x_mm`` (the lead end's travel): the largest compression, which
    must be isolated. The rider sits still before slamming: over ``QUIET_BEFORE_S`` before the peak
    the travel keeps its level, and the slam rises above that level by at least ``ISOLATION`` times
    the window's spread (its 2.5-97.5 % range) and ``MIN_SLAM_NOISE`` times the record's noise.
    A ride's largest hit (one of many), a pedalling stroke or noise is no seat slam: raises
    ``BounceError`` naming ``name``."""
    t = np.asarray(time_s, float)
    x = np.asarray(x_mm, float)
    if t.size < 3 or not np.all(np.isfinite(x)):
        raise BounceError(f"{name}: no seat slam: the travel is not a finite series of 3 or more samples")
    dt = float(t[1] - t[0])
    xs = _smooth(x, max(1, int(round(SMOOTH_S / dt))))
    peak = int(np.argmax(xs))
    early, late = QUIET_BEFORE_S
    if t[peak] - t[0] < early:
        raise BounceError(f"{name}: no seat slam told: the largest compression ({xs[peak]:.1f} mm at {t[peak]:.2f} s) "
                          f"comes {t[peak] - t[0]:.2f} s after the record starts; a seat slam is told by the rider "
                          f"sitting still before it ({early:g} s of record before the slam are needed)")
    window = xs[(t >= t[peak] - early) & (t <= t[peak] - late)]
    level = float(np.median(window))
    spread = float(np.percentile(window, 97.5) - np.percentile(window, 2.5))
    rise = float(xs[peak]) - level
    noise = noise_mm(x)
    need = max(ISOLATION * spread, MIN_SLAM_NOISE * noise)
    if not rise > need:
        raise BounceError(
            f"{name}: no seat slam: the largest compression ({xs[peak]:.1f} mm at {t[peak]:.2f} s) rises {rise:.1f} mm "
            f"above the travel {late:g}-{early:g} s before it, which moves by {spread:.1f} mm (noise {noise:.2g} mm); "
            f"a seat slam is an isolated compression of at least {ISOLATION:g} x that movement and "
            f"{MIN_SLAM_NOISE:g} x the noise ({need:.1f} mm)")
    return peak


def record_name(record) -> str:
    """What a record is called in lines and files: its ``name``, else its ``path``, else "record"."""
    return getattr(record, "name", None) or str(getattr(record, "path", "record"))


def fit_record(record) -> dict:
    """Each end's ring-down of one ``TelemetryRecord`` (end -> RingDown; an absent sensor is left out).
    Raises ``BounceError`` (naming the file) when the record holds no seat slam (:func:`find_slam`)
    or no end rings down freely after it."""
    series = {"shock": record.shock_mm, "fork": record.fork_mm}
    lead_end = "shock" if series["shock"] is not None else "fork"
    name = record_name(record)
    if series[lead_end] is None:
        raise BounceError(f"{name}: no sensor present")
    slam = find_slam(record.time_s, series[lead_end], f"{name} ({lead_end})")
    out = {}
    for end in ENDS:
        if series[end] is not None:
            out[end] = ring_down(record.time_s, series[end], end, slam_index=slam)
    if not any(rd.fitted for rd in out.values()):
        raise BounceError(f"{name}: no ring-down after the slam at {record.time_s[slam]:.2f} s: "
                          + "; ".join(f"{end}: {rd.note}" for end, rd in out.items()))
    return out


@dataclass
class ClickLaw:
    """zeta(k) = zeta0 + slope k, and the constant undamped frequency, of one end."""

    end: str
    clicks: tuple
    zeta0: float
    slope: float
    cov: np.ndarray
    fn_Hz: float
    fn_sd: float
    chi2_reduced: float | None

    def zeta(self, clicks: float) -> tuple[float, float]:
        g = np.array([1.0, float(clicks)])
        return float(self.zeta0 + self.slope * clicks), float(math.sqrt(max(g @ self.cov @ g, 0.0)))

    def frequency(self, clicks: float) -> tuple[float, float]:
        """Damped natural frequency (Hz) at ``clicks`` and its sd (from f_n's and zeta's)."""
        z, zsd = self.zeta(clicks)
        if not 0.0 <= z < 1.0:
            return float("nan"), float("nan")
        root = math.sqrt(1.0 - z * z)
        sd = math.hypot(root * self.fn_sd, self.fn_Hz * z / root * zsd)
        return self.fn_Hz * root, sd

    def summary(self) -> dict:
        sd0, sds = math.sqrt(self.cov[0, 0]), math.sqrt(self.cov[1, 1])
        return {"form": LAW_FORM, "fitted_on_clicks": list(self.clicks),
                "zeta0": self.zeta0, "zeta0_ci95": interval95(self.zeta0, sd0),
                "slope_per_click": self.slope, "slope_per_click_ci95": interval95(self.slope, sds),
                "covariance": self.cov.tolist(),
                "undamped_frequency_hz": self.fn_Hz, "undamped_frequency_hz_ci95": interval95(self.fn_Hz, self.fn_sd),
                "chi2_reduced": self.chi2_reduced}


def weighted_line(x, y, sd) -> tuple[np.ndarray, np.ndarray, float | None]:
    """(intercept and slope, their covariance, reduced chi-square or None) of y against x by
    weighted least squares (weights 1 / sd^2); with more than two points the covariance is scaled
    by the reduced chi-square when it exceeds 1."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    w = 1.0 / np.maximum(np.asarray(sd, float), 1e-12) ** 2
    X = np.column_stack((np.ones_like(x), x))
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    beta = cov @ X.T @ (w * y)
    chi2 = None
    if x.size > 2:
        chi2 = float(np.sum(w * (y - X @ beta) ** 2) / (x.size - 2))
        cov = cov * max(1.0, chi2)
    return beta, cov, chi2


def click_law(end: str, clicks, fits) -> ClickLaw:
    """The law of one end from fitted ring-downs at ``clicks`` (at least two distinct clicks)."""
    k = np.asarray(clicks, float)
    z = np.array([f.zeta for f in fits])
    sd = np.array([f.zeta_sd for f in fits])
    if np.unique(k).size < 2:
        raise BounceError(f"{end}: a law in clicks needs fitted ring-downs at two or more different clicks")
    beta, cov, chi2 = weighted_line(k, z, sd)
    fn = np.array([f.fn_Hz for f in fits])
    wf = 1.0 / np.maximum(np.array([f.fn_sd for f in fits]), 1e-12) ** 2
    fn_mean = float(np.sum(wf * fn) / np.sum(wf))
    fn_sd = float(math.sqrt(1.0 / np.sum(wf)))
    if fn.size > 1:  # the records' own spread, when larger than their stated intervals
        fn_sd = max(fn_sd, float(np.std(fn, ddof=1) / math.sqrt(fn.size)))
    return ClickLaw(end, tuple(float(c) for c in k), float(beta[0]), float(beta[1]), cov, fn_mean, fn_sd, chi2)


REBOUND_BAND = (0.75, 0.25)  # the first rebound's middle: from this share of the peak's height above rest to this


def first_rebound(time_s, x_mm, peak: int, rest_mm: float) -> dict:
    """The slam's first rebound read off the trace, no model (``fit bounce --replay``'s check of the
    damper): on the 10 ms-smoothed travel from the slam's peak (index ``peak``) to the first trough
    (where it first turns by 1 % of the slam's height, or the record's end), the largest extension
    speed (the smoothed travel's slope over 10 ms), the mean speed through the rebound's middle (from
    75 % to 25 % of the peak's height above ``rest_mm``: the same stroke for slams of the same height,
    where one spring pushes alike, so the slower the more rebound damping), the time to the trough
    and its level (``topped_out`` when it lies within 1 mm of full extension: the stroke clipped
    there, not free)."""
    t = np.asarray(time_s, float)
    dt = float(t[1] - t[0])
    xs = _smooth(np.asarray(x_mm, float), max(int(round(SMOOTH_S / dt)), 1))
    height = float(xs[peak] - rest_mm)
    if height <= 0.0:
        raise BounceError(f"the slam's peak ({xs[peak]:.1f} mm) is not above the rest before it ({rest_mm:.1f} mm)")
    turns = turning_points(xs, peak, 0.01 * height, falling=True)
    trough = turns[0] if turns else xs.size - 1
    h = max(int(round(SMOOTH_S / dt)) // 2, 1)  # the speed over the smoothing's own span: the noise's slope small
    i = np.arange(peak, trough + 1)
    v = (xs[np.minimum(i + h, xs.size - 1)] - xs[np.maximum(i - h, 0)]) / ((np.minimum(i + h, xs.size - 1)
                                                                             - np.maximum(i - h, 0)) * dt)
    hi, lo = (rest_mm + f * height for f in REBOUND_BAND)
    seg = xs[peak:trough + 1]

    def crossing(level):
        j = np.flatnonzero(seg <= level)
        if not j.size or j[0] == 0:
            return None
        j = int(j[0])
        return float(t[peak + j - 1] + (level - seg[j - 1]) * dt / (seg[j] - seg[j - 1]))

    a, b = crossing(hi), crossing(lo)
    return {"rebound_speed_mm_per_s": float(max(0.0, -float(np.min(v)))),
            "mid_rebound_speed_mm_per_s": None if a is None or b is None or b <= a else float((hi - lo) / (b - a)),
            "trough_s": float(t[trough] - t[peak]), "trough_mm": float(xs[trough]),
            "topped_out": bool(xs[trough] < 1.0), "peak_above_rest_mm": height}


SETTLED_AFTER_S = (1.0, 1.5)  # the level after the slam: its median over this window after the peak (s)


def rest_shift(time_s, x_mm, peak: int) -> tuple[float, float] | None:
    """(level before, level after) the slam (mm): the medians over ``QUIET_BEFORE_S`` before the peak
    and ``SETTLED_AFTER_S`` after it; None when the record ends before that."""
    t = np.asarray(time_s, float)
    x = np.asarray(x_mm, float)
    tp = t[peak]
    before = (t >= tp - QUIET_BEFORE_S[0]) & (t <= tp - QUIET_BEFORE_S[1])
    after = (t >= tp + SETTLED_AFTER_S[0]) & (t <= tp + SETTLED_AFTER_S[1])
    if not before.any() or t[-1] < tp + SETTLED_AFTER_S[1]:
        return None
    return float(np.median(x[before])), float(np.median(x[after]))


def rebound_check(entries) -> dict | None:
    """Do the records' own first rebounds (``first_rebound``'s middle speed, model-free) slow as the
    rebound clicks rise, and do the replayed dampers rise with them? ``entries``: per record a dict
    with "clicks", "record_rebound" and, when replayed, "damper_N_s_per_m". None with fewer than two
    distinct clicks. "records_order" / "replay_orders": strictly monotone in clicks (ties in clicks
    not compared); "line" states the outcome."""
    rows = sorted((e for e in entries
                   if e.get("record_rebound") and e["record_rebound"]["mid_rebound_speed_mm_per_s"]),
                  key=lambda e: e["clicks"])
    if len({e["clicks"] for e in rows}) < 2:
        return None
    pairs = [(a, b) for a, b in zip(rows, rows[1:]) if b["clicks"] > a["clicks"]]
    speed = [e["record_rebound"]["mid_rebound_speed_mm_per_s"] for e in rows]
    slows = all(b["record_rebound"]["mid_rebound_speed_mm_per_s"] < a["record_rebound"]["mid_rebound_speed_mm_per_s"]
                for a, b in pairs)
    done = [e for e in rows if "damper_N_s_per_m" in e]
    rises = None
    if len({e["clicks"] for e in done}) >= 2:
        rises = all(b["damper_N_s_per_m"] > a["damper_N_s_per_m"]
                    for a, b in zip(done, done[1:]) if b["clicks"] > a["clicks"])
    ks = ", ".join(f"{e['clicks']:g}" for e in rows)
    said = (f"the records' first rebounds {'slow' if slows else 'do not slow'} as the clicks rise (mid-rebound "
            f"speed {', '.join(f'{v:.0f}' for v in speed)} mm/s at {ks} clicks, model-free)")
    if not slows:
        line = f"{said}: the records themselves do not show more rebound damping at more clicks"
    elif rises is None:
        line = f"{said}; fewer than two replays to compare"
    else:
        cs = ", ".join(f"{e['damper_N_s_per_m']:.0f}" for e in done)
        dampers = f"replayed dampers {cs} N s/m at {', '.join(format(e['clicks'], 'g') for e in done)} clicks"
        line = (f"{said}, and the {dampers} rise with them" if rises else
                f"{said}, but the {dampers} do not rise with them: the replay does not read the rebound damper")
    return {"records_order": bool(slows), "replay_orders": rises, "mid_rebound_speed_mm_per_s": speed,
            "clicks": [e["clicks"] for e in rows], "line": line}


__all__ = ["BounceError", "ClickLaw", "RingDown", "click_law", "find_slam", "first_rebound", "fit_record",
           "rebound_check", "rest_shift", "lag1", "ring_down",
           "weighted_line",
           "METHOD", "LAW_FORM"]

"""A seat slam predicted at another rebound click setting, from the decay law with friction.

The law (:mod:`mtbmj.identify.bounce_decay`, fitted with the friction band d common to the records
and ``zeta = zeta0 + slope x clicks``) gives zeta and d at any click between the records'. The
frequency does not come from the half-cycle relations: each record's free extrema are timed (the
vertex of a parabola fitted to the raw travel, with its standard error), their spacing is half a
damped period ``pi / w_d``, and ``f_n = f_d / sqrt(1 - zeta^2)`` with the record's zeta is taken as
common to the records (the spring and the sprung mass do not change with the clicks): its mean over
the records, its sd the larger of the records' scatter over sqrt(n) and the timing's.

**A record's frequency is measured with the model's own error** (:func:`half_scatter`,
:func:`honest_timing`). The law holds one frequency for every half cycle. The records do not: within
one record single half periods differ by several per cent (friction, the rider's body), and rebound
halves run longer than compression ones (the clicks damp the rebound). A frequency read from vertex
times alone carries only their timing error (1-3 mHz). That is far too small, above all from one timed
half cycle, because the model is wrong by the scatter between half periods. So each half period is
taken as ``log h = a_record + shift x s + e`` (s = +1 rebound, -1 compression). The shift and e's sd
are pooled by least squares over the records with two half periods or more (a record's own mean
absorbs its level). The shift is left out where no record has both directions or the pool would have
no degree of freedom left. A record's frequency is ``1 / (2 exp(a))``, a its shifted half periods'
mean log. Its sd is the pooled scatter over sqrt(n), the shift's sd times the record's mean s (a
record with as many halves each way does not feel it), and the vertices' timing, in quadrature.
Its 95 % interval uses Student's t at the pool's dof. The pool is a property of the measurement,
not of the law: held out, it is taken over every record. Records with no pool (no record with two
half periods) keep the vertex timing (:func:`timing`). Checked in tests/test_bounce_predict.py: on
made records with direction-dependent damping and friction, the interval holds the exact frequency at
about its nominal rate, and a record on a stiffer spring is still told apart.

**A record's measured first half cycle's decay carries the model's own error too** (:func:`decay_scatter`,
:func:`measured_decay`). s_1 / s_0 is read from three vertex levels; their read error alone is a few
thousandths. But the law is a smooth law (viscous + Coulomb), and one half cycle's decay scatters about
it by far more (the rider's body, damping that differs by direction): what a law predicts is the
record's smooth law, and one half cycle is one draw about it. So each half cycle's decay
``s_{n+1} / s_n`` is taken about its own record's law, written in swings (``s_{n+1} = r s_n - 2 (1 + r) d``,
so ``s_{n+1} / s_n = r - D / s_n`` with D = 2 (1 + r) d: linear in r and D, fitted per record by least
squares), plus a shift by the direction of swing n, plus e. e's sd is pooled over the records with
three decays or more (each record's r and D absorb two); the shift is kept only where it is told apart
(beyond its 95 % interval at the pool's dof), else left out and its degree of freedom kept. A record's
measured first decay (corrected by the shift where kept) carries the pooled sd, the shift's sd and its
read error in quadrature; its 95 % interval uses Student's t at the pool's dof. Held out
(:func:`held_out_decay`), the miss is in the prediction's sd (``law_prediction``'s) and this one
combined. Checked in tests/test_bounce_predict.py on made records, the truth each record's click
setting's law fitted there on its noise-free ring-downs at three pushes: the interval holds it 17 times
in 18 (the read error alone: 2 in 18), and a click law with the wrong slope is still told apart at 0
and 8 clicks; a law without friction is not, from one first decay (a strict xfail).

**The predicted trace** starts from a record's own state: the record itself up to the slam's peak
(the compression stroke the rider made, which a rebound adjuster does not act on: an assumption),
then from rest at the peak the law's own motion, ``m x'' + c x' + F_c sign(x') + k (x - x_eq) = 0``
with the record's x_eq, integrated in closed form half cycle by half cycle (from rest at x_n the
motion is a damped oscillation about ``c_n = x_eq - s d``, s the direction it moves, until the
velocity is nil again). The stroke's ends are stops: a half cycle that reaches full extension (0 mm)
or full travel is cut there and the motion restarts from rest at the stop (a plastic stop); a rest
within d of x_eq is where it sticks. Where it reaches a stop and a record of the law reaches one too, the
trace from the peak is instead the two masses' of :mod:`mtbmj.identify.bounce_body` (the seated rider's
body holds the bike on its stop and drives it out; its share and damping fitted on those). So the trace never
leaves the stroke (a test checks it on every trace written).

**Intervals** (95 %): zeta and d from the law's covariance (delta method); the first half cycle's
decay as :func:`mtbmj.identify.bounce_decay.law_prediction` gives it (with the residual scale of one
record's extrema); the frequency from zeta's and f_n's sd; the rebound speed (the largest extension
speed after the slam's peak) as the 2.5 and 97.5 percentiles over 400 draws of (zeta, d, f_n) from
their normal distribution (seeded: the same numbers every run).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from mtbmj.errors import MtbmjError
from mtbmj.identify import bounce_decay as bd
from mtbmj.identify.bounce import Z95, interval95

DRAWS = 400
STOP_NEAR_MM = 0.05  # a stroke's end is reached when the law's motion comes this close to it
PARABOLA_SHARE = 0.2  # an extremum's time: parabola over this share of a half period either side


@dataclass
class Estimate:
    """A value with its 95 % interval."""

    value: float
    low: float
    high: float

    def contains(self, v: float) -> bool:
        return self.low <= v <= self.high


def vertex_time(t: np.ndarray, x: np.ndarray, ti: float, half_s: float) -> tuple[float, float]:
    """The time of the extremum near ``ti``: the vertex of a parabola fitted to the raw travel within
    PARABOLA_SHARE of a half period either side, and its standard error (from the fit's covariance)."""
    dt = float(t[1] - t[0])
    i = int(round((ti - t[0]) / dt))
    w = max(3, int(PARABOLA_SHARE * half_s / dt))
    a, b = max(0, i - w), min(x.size, i + w + 1)
    tau = t[a:b] - t[i]
    (c2, c1, c0), cov = np.polyfit(tau, x[a:b], 2, cov="unscaled")
    res = x[a:b] - np.polyval([c2, c1, c0], tau)
    s2 = max(float(res @ res) / max(1, tau.size - 3), 1e-12)
    g = np.array([c1 / (2 * c2 * c2), -1.0 / (2 * c2), 0.0])  # d(-c1 / 2 c2) / d(c2, c1, c0)
    sd = math.sqrt(max(float(g @ (cov * s2) @ g), 0.0))
    return float(t[i] - c1 / (2 * c2)), sd


@dataclass
class Timing:
    """One record's damped frequency from its free extrema's times."""

    frequency_hz: float
    sd: float
    n_times: int
    vertex_sd: float = float("nan")  # the part of sd from the vertices' timing alone


def timing(seq: bd.Extrema, t: np.ndarray, x: np.ndarray) -> Timing | None:
    """f_d of one record from its free extrema's times (a line through the times against their index,
    weighted by their standard errors); None with fewer than two timed extrema."""
    times = seq.times_s[np.isfinite(seq.times_s)]
    if times.size < 2:
        return None
    half0 = float(np.median(np.diff(times)))
    tv = np.array([vertex_time(t, x, ti, half0) for ti in times])
    n = np.arange(times.size, dtype=float)
    w = 1.0 / np.maximum(tv[:, 1], 1e-6) ** 2
    X = np.column_stack((np.ones_like(n), n))
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    beta = cov @ X.T @ (w * tv[:, 0])
    if times.size > 2:
        chi2 = float(np.sum(w * (tv[:, 0] - X @ beta) ** 2) / (times.size - 2))
        cov = cov * max(1.0, chi2)
    half, hsd = float(beta[1]), float(math.sqrt(cov[1, 1]))
    return Timing(0.5 / half, 0.5 * hsd / half ** 2, int(times.size), 0.5 * hsd / half ** 2)


@dataclass
class HalfScatter:
    """The half periods' own scatter, pooled over records: log h = a_i + shift x s + e (s = +1 for a
    rebound half, -1 for a compression half; e of sd ``rel_sd``, relative), ``dof`` its degrees of
    freedom; ``shift`` 0 (sd 0) where no record has both directions or the pool cannot spare a degree."""

    rel_sd: float
    dof: int
    shift: float
    shift_sd: float
    n_records: int

    @property
    def t95(self) -> float:
        """Student's t at the pool's degrees of freedom: a 95 % interval is the sd times this."""
        from scipy.stats import t as student

        return float(student.ppf(0.975, self.dof))

    def summary(self) -> dict:
        return {"relative_sd": self.rel_sd, "dof": self.dof, "t95": self.t95, "rebound_shift": self.shift,
                "rebound_shift_sd": self.shift_sd, "records_pooled": self.n_records, "model": HALF_MODEL}


HALF_MODEL = ("log h = a_record + shift x s + e, s = +1 rebound half / -1 compression half, e the scatter of one "
              "half period about its record's mean (pooled over the records with more than one half period); a "
              "record's frequency 1 / (2 exp(a)), its sd the scatter over sqrt(its halves), the shift's sd and the "
              "vertex timing's")


def timed_halves(seq: bd.Extrema, t: np.ndarray, x: np.ndarray) -> list:
    """The free half cycles of one record: (direction, from_mm, to_mm, seconds, sd) between vertex times
    (the sd from the two vertices' standard errors)."""
    times = seq.times_s[np.isfinite(seq.times_s)]
    if times.size < 2:
        return []
    half0 = float(np.median(np.diff(times)))
    tv = [vertex_time(t, x, ti, half0) for ti in times]
    lv = seq.levels_mm
    return [("compression" if lv[j + 1] > lv[j] else "rebound", float(lv[j]), float(lv[j + 1]),
             tv[j + 1][0] - tv[j][0], math.hypot(tv[j + 1][1], tv[j][1])) for j in range(times.size - 1)]


def half_scatter(halves_per_record) -> HalfScatter | None:
    """The pooled scatter of single half periods about their record's mean (``HALF_MODEL``), from each
    record's :func:`timed_halves`; None when no record has two half periods."""
    use = [h for h in halves_per_record if len(h) >= 2]
    if not use:
        return None
    both = any(len({q[0] for q in h}) == 2 for h in use)
    n = sum(len(h) for h in use)
    shift_on = both and n - len(use) - 1 >= 1
    cols = len(use) + (1 if shift_on else 0)
    X = np.zeros((n, cols))
    y = np.empty(n)
    k = 0
    for j, h in enumerate(use):
        for q in h:
            X[k, j] = 1.0
            if shift_on:
                X[k, -1] = 1.0 if q[0] == "rebound" else -1.0
            y[k] = math.log(q[3])
            k += 1
    beta = np.linalg.lstsq(X, y, rcond=None)[0]
    res = y - X @ beta
    dof = n - cols
    s2 = float(res @ res) / dof
    cov = s2 * np.linalg.inv(X.T @ X)
    shift, ssd = (float(beta[-1]), float(math.sqrt(cov[-1, -1]))) if shift_on else (0.0, 0.0)
    return HalfScatter(float(math.sqrt(s2)), int(dof), shift, ssd, len(use))


def honest_timing(halves: list, sc: HalfScatter | None) -> Timing | None:
    """A record's damped frequency from its half periods under the pooled scatter ``sc``: each half
    corrected by the rebound shift, their log mean a, f_d = 1 / (2 exp(a)); its sd from the scatter over
    sqrt(n), the shift's sd times the record's share of unbalanced halves, and the vertices' timing.
    None without a half period or without a pool."""
    if not halves or sc is None:
        return None
    s = np.array([1.0 if q[0] == "rebound" else -1.0 for q in halves])
    h = np.array([q[3] for q in halves])
    a = float(np.mean(np.log(h) - sc.shift * s))
    n = h.size
    vertex = float(math.sqrt(np.sum((np.array([q[4] for q in halves]) / h) ** 2)) / n)
    sd_a = math.sqrt(sc.rel_sd ** 2 / n + (float(np.mean(s)) * sc.shift_sd) ** 2 + vertex ** 2)
    f = 0.5 * math.exp(-a)
    return Timing(f, f * sd_a, n + 1, f * vertex)


@dataclass
class DecayScatter:
    """The per-half-cycle decays' own scatter about their record's law, pooled over records:
    ``s_{n+1} / s_n = r_record - D_record / s_n + shift x dir_n + e`` (``DECAY_MODEL``), e of sd ``sd``
    (decay units), ``dof`` its degrees of freedom; ``shift`` 0 (sd 0) where the directions are not told
    apart (the shift within its 95 % interval of 0, or no degree of freedom to spare)."""

    sd: float
    dof: int
    shift: float
    shift_sd: float
    n_records: int
    shift_tried: float = float("nan")  # the shift as fitted, kept or not
    shift_tried_sd: float = float("nan")

    @property
    def t95(self) -> float:
        from scipy.stats import t as student

        return float(student.ppf(0.975, self.dof))

    def summary(self) -> dict:
        return {"sd": self.sd, "dof": self.dof, "t95": self.t95, "rebound_first_shift": self.shift,
                "rebound_first_shift_sd": self.shift_sd, "shift_fitted": self.shift_tried,
                "shift_fitted_sd": self.shift_tried_sd, "records_pooled": self.n_records, "model": DECAY_MODEL}


DECAY_MODEL = ("s_{n+1} / s_n = r_record - D_record / s_n + shift x dir_n + e: one half cycle's decay (the swing after "
               "it over the swing before) about its record's viscous + Coulomb law (r = exp(-pi zeta / sqrt(1 - zeta^2)),"
               " D = 2 (1 + r) d, fitted per record), dir_n +1 where swing n is a rebound, -1 a compression (kept only "
               "where told apart), e the scatter pooled over the records with 3 decays or more; a record's measured "
               "first decay carries it and its vertices' read error in quadrature")
MIN_DECAYS = 3  # a record's decays in the pool: its law's two parameters and one degree of freedom


def half_decays(seq: bd.Extrema) -> list:
    """One record's per-half-cycle decays: (dir, s_n, s_{n+1}) with dir +1 where swing n is a rebound."""
    lv, sw = seq.levels_mm, seq.swings
    return [(1.0 if lv[n + 1] < lv[n] else -1.0, float(sw[n]), float(sw[n + 1])) for n in range(sw.size - 1)
            if sw[n] > 0]


def decay_scatter(seqs) -> DecayScatter | None:
    """The pooled scatter of per-half-cycle decays about each record's own law (``DECAY_MODEL``; linear
    least squares: r and D per record, the direction shift common); None when no record has MIN_DECAYS."""
    use = [h for h in (half_decays(s) for s in seqs) if len(h) >= MIN_DECAYS]
    if not use:
        return None
    n, m = sum(len(h) for h in use), len(use)

    def fit(shift_on: bool):
        X = np.zeros((n, 2 * m + shift_on))
        y = np.empty(n)
        k = 0
        for j, h in enumerate(use):
            for dirn, s0, s1 in h:
                X[k, 2 * j], X[k, 2 * j + 1] = 1.0, -1.0 / s0
                if shift_on:
                    X[k, -1] = dirn
                y[k] = s1 / s0
                k += 1
        beta = np.linalg.lstsq(X, y, rcond=None)[0]
        res = y - X @ beta
        dof = n - X.shape[1]
        s2 = float(res @ res) / dof
        return beta, s2 * np.linalg.pinv(X.T @ X), s2, dof

    beta, cov, s2, dof = fit(False)
    out = DecayScatter(float(math.sqrt(s2)), int(dof), 0.0, 0.0, m)
    both = len({q[0] for h in use for q in h}) == 2
    if both and dof >= 2:
        b1, c1, s21, dof1 = fit(True)
        shift, ssd = float(b1[-1]), float(math.sqrt(max(c1[-1, -1], 0.0)))
        out.shift_tried, out.shift_tried_sd = shift, ssd
        kept = DecayScatter(float(math.sqrt(s21)), int(dof1), shift, ssd, m, shift, ssd)
        if abs(shift) > kept.t95 * ssd:  # the directions told apart (at the shifted fit's dof): keep the shift
            out = kept
    return out


def read_sd(seq: bd.Extrema) -> float:
    """The sd of a record's measured first decay s_1 / s_0 from its three extrema's read error alone (each
    level's measurement floor): (x2 - x1) / (x1 - x0)."""
    sw = seq.swings
    if sw.size < 2 or sw[0] <= 0:
        return float("nan")
    q = float(sw[1] / sw[0])
    return float(seq.floor_mm / sw[0] * math.sqrt(q * q + (1 + q) ** 2 + 1))


def measured_decay(seq: bd.Extrema, sc: DecayScatter | None) -> tuple[float, float]:
    """A record's measured first half cycle's decay and its sd: with the pool ``sc``, corrected by the
    direction shift (where kept) and carrying the pooled scatter, the shift's sd and the read error in
    quadrature; without one, the read error alone."""
    val, rsd = seq.first_decay(), read_sd(seq)
    if sc is None or not math.isfinite(val):
        return val, rsd
    h = half_decays(seq)
    dirn = h[0][0] if h else 0.0
    return val - sc.shift * dirn, float(math.sqrt(sc.sd ** 2 + sc.shift_sd ** 2 + rsd ** 2))


def common_fn(timings, zetas) -> tuple[float, float]:
    """f_n common to the records: f_d / sqrt(1 - zeta^2) per record, their mean, and its sd (the
    larger of the records' scatter over sqrt(n) and the mean of their own sds over sqrt(n))."""
    fn = np.array([tm.frequency_hz / math.sqrt(1.0 - min(z, 0.99) ** 2) for tm, z in zip(timings, zetas)])
    sds = np.array([tm.sd for tm in timings])
    m = fn.size
    sd = float(np.sqrt(np.sum(sds ** 2)) / m)
    if m > 1:
        sd = max(sd, float(np.std(fn, ddof=1) / math.sqrt(m)))
    return float(np.mean(fn)), sd


def free_motion(x0: float, x_eq: float, d: float, zeta: float, fn_hz: float, stroke_mm: float,
                duration_s: float, dt: float, restitution: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The law's motion from rest at ``x0`` (mm) for ``duration_s``, sampled every ``dt`` from 0: closed
    form between velocity reversals, the stroke's ends as stops that return ``restitution`` of the
    speed that reached them (0: plastic), stuck at a rest within d of x_eq."""
    wn = 2 * math.pi * fn_hz
    zeta = min(max(zeta, 0.0), 0.999)
    wd = wn * math.sqrt(1 - zeta * zeta)
    a = zeta * wn
    tt = np.arange(int(duration_s / dt) + 1) * dt
    xx = np.empty_like(tt)
    t_seg, x_n, v_n = 0.0, float(x0), 0.0
    tau_fine = np.linspace(0.0, 2 * math.pi / wd, 4001)
    i = 0
    while i < tt.size:
        if v_n == 0.0 and abs(x_n - x_eq) <= d:  # at rest within the friction band: stuck for good
            xx[i:] = x_n
            break
        s = math.copysign(1.0, v_n) if v_n != 0.0 else (1.0 if x_eq > x_n else -1.0)  # its direction
        c = x_eq - s * d
        A = x_n - c
        B = (v_n + a * A) / wd

        def path(tau, A=A, B=B, c=c):
            e = np.exp(-a * tau)
            return (c + e * (A * np.cos(wd * tau) + B * np.sin(wd * tau)),
                    e * ((B * wd - a * A) * np.cos(wd * tau) - (A * wd + a * B) * np.sin(wd * tau)))

        xf, vf = path(tau_fine)
        rev = np.flatnonzero(s * vf[1:] <= 0.0)
        k_rev = int(rev[0]) + 1 if rev.size else tau_fine.size - 1
        out = np.flatnonzero((xf[:k_rev + 1] < 0.0) | (xf[:k_rev + 1] > stroke_mm))
        if out.size and out[0] > 0:  # a stop reached before the reversal: cut there (interpolated)
            k = int(out[0])
            bound = 0.0 if xf[k] < 0.0 else stroke_mm
            f = (bound - xf[k - 1]) / (xf[k] - xf[k - 1])
            seg_len = float(tau_fine[k - 1] + f * (tau_fine[k] - tau_fine[k - 1]))
            x_end = bound
            v_end = -restitution * float(path(seg_len)[1])
            if abs(v_end) * dt < 1e-6:
                v_end = 0.0
        else:
            k = k_rev
            f = vf[k - 1] / (vf[k - 1] - vf[k]) if vf[k - 1] != vf[k] else 1.0
            seg_len = float(tau_fine[k - 1] + f * (tau_fine[k] - tau_fine[k - 1]))
            x_end, v_end = float(path(seg_len)[0]), 0.0
        j = i
        while j < tt.size and tt[j] <= t_seg + seg_len:
            j += 1
        xx[i:j] = np.clip(path(tt[i:j] - t_seg)[0], 0.0, stroke_mm)
        i, t_seg, x_n, v_n = j, t_seg + seg_len, float(np.clip(x_end, 0.0, stroke_mm)), v_end
    return tt, xx


def rebound_speed(x_mm: np.ndarray, dt: float) -> float:
    """The largest extension speed (mm/s) of a trace from rest at its peak: on the first half cycle."""
    v = np.diff(x_mm) / dt
    k = np.flatnonzero(v > 0)  # the first compression ends the first rebound
    stop = int(k[0]) if k.size else v.size
    return float(max(0.0, -float(np.min(v[:max(stop, 1)]))))


class Body(NamedTuple):
    """The seated rider's body fitted on a law's records that reach a stop (``DecayLaw.body_share``)."""
    share: float  # of the moving mass
    rms_mm: float  # the fit's RMS on those records
    records: int  # how many
    zeta: float  # its damping ratio


@dataclass
class Prediction:
    """One end's ring-down predicted at ``clicks``, from ``source``'s own state."""

    end: str
    clicks: float
    source: str
    source_clicks: float
    zeta: Estimate
    friction_band_mm: Estimate
    frequency_hz: Estimate
    first_half_cycle_decay: Estimate
    rebound_speed_mm_per_s: Estimate
    x_eq_mm: float
    stroke_mm: float
    slam_s: float
    time_s: np.ndarray = field(repr=False)
    travel_mm: np.ndarray = field(repr=False)
    body: Body | None = None  # the trace through the stop is the two masses'

    def inside_stroke(self) -> bool:
        return bool(np.all(self.travel_mm >= 0.0) and np.all(self.travel_mm <= self.stroke_mm))

    def stop_reached_s(self) -> float | None:
        """When the law's motion after the slam's peak first reaches a stroke's end (None: never)."""
        after = self.time_s > self.slam_s
        near = STOP_NEAR_MM  # the closed form's samples straddle the instant it reaches the stop
        hit = np.flatnonzero(after & ((self.travel_mm <= near) | (self.travel_mm >= self.stroke_mm - near)))
        return float(self.time_s[hit[0]]) if hit.size else None

    def envelope_note(self) -> str:
        """One line when the trace leaves what the law was checked on: a stroke's end reached."""
        t = self.stop_reached_s()
        if t is None:
            return ""
        head = f"the predicted motion reaches the end of the stroke at {t:.3f} s: after it the trace is outside the law's envelope"
        from mtbmj.identify import bounce_body as bb

        if self.body is None:
            return (f"{head} (a plastic stop, no record to fit the seated rider's body on; the body holds the end on "
                    f"its stop and drives it out: 1.1-1.7 mm RMS off in tests/test_bounce_predict.py)")
        return (f"{head}: the bike held on its stop by the seated rider's body (two masses, the body {bb.share_words(self.body.share)} "
                f"of the moving mass at 5 Hz, damping ratio {bb.zeta_words(self.body.zeta)}, both fitted on {self.body.records} "
                f"record(s), {self.body.rms_mm:.2f} mm RMS there; 0.31-0.32 mm RMS off in tests/test_bounce_predict.py, the "
                f"noise 0.15 mm)")

    def summary(self) -> dict:
        out = {"clicks": self.clicks, "from_record": self.source, "from_clicks": self.source_clicks}
        for key, est in (("damping_ratio", self.zeta), ("friction_band_mm", self.friction_band_mm),
                         ("frequency_hz", self.frequency_hz), ("first_half_cycle_decay", self.first_half_cycle_decay),
                         ("rebound_speed_mm_per_s", self.rebound_speed_mm_per_s)):
            out[key], out[f"{key}_ci95"] = est.value, [est.low, est.high]
        out.update({"x_eq_mm": self.x_eq_mm, "stroke_mm": self.stroke_mm, "slam_s": self.slam_s,
                    "trace": (f"{self.source}'s own travel up to its slam's peak at {self.slam_s:.3f} s, then the "
                              f"law's motion from rest there " + (
                                  f"(plastic stops at 0 and {self.stroke_mm:g} mm, stuck within d of x_eq)" if
                                  self.body is None else
                                  f"with the seated rider's body (share {self.body.share:.3f}, damping ratio {self.body.zeta:.3f}): the bike held on a stop "
                                  f"or within the friction while the forces on it allow")),
                    "inside_stroke": self.inside_stroke(), "stop_reached_s": self.stop_reached_s()})
        if self.envelope_note():
            out["note"] = self.envelope_note()
        return out


@dataclass
class DecayLaw:
    """One end's law across clicks, ready to predict: the fit (friction common, zeta linear in clicks),
    the records' sequences, clicks and timings, and the common undamped frequency."""

    end: str
    fit: bd.DecayFit
    seqs: list
    clicks: list
    timings: list
    fn_hz: float
    fn_sd: float
    zetas: list = field(default_factory=list)  # the timed records' own zetas (per-record fit), as ``timings``
    timed: list = field(default_factory=list)  # the indices (into ``seqs``) of the timed records
    scatter: HalfScatter | None = None  # the half periods' pooled scatter the timings carry (None: vertex only)
    records: list = field(default_factory=list)  # the records and their travel (mm), as ``seqs``: the body's fit
    travels: list = field(default_factory=list)
    body: Body | None = None  # the seated body fitted on them (:meth:`body_share`)

    def body_share(self) -> tuple | None:
        """The seated body's share of the moving mass and its damping ratio
        (:func:`mtbmj.identify.bounce_body.fit_body`) fitted on this law's records whose law motion from their
        slam's peak reaches the top-out stop: (share, RMS mm, their count, damping ratio); None where none
        does. Fitted once."""
        from mtbmj.identify import bounce_body as bb

        if self.body is None:
            cases = []
            for seq, k, rec, x in zip(self.seqs, self.clicks, self.records, self.travels):
                z, d, _ = self.zeta_d(k)
                if not 0.0 <= z < 1.0:
                    continue
                dt, peak, x0 = peak_start(rec, seq, x, math.inf)
                xe = self.x_eq_of(seq, k)
                if free_motion(x0, xe, d, z, self.fn_hz, math.inf, bb.FIT_S, dt)[1].min() <= STOP_NEAR_MM:
                    cases.append((z, d, x0, xe, math.inf, np.asarray(x, float)[peak:], dt))
            fit = bb.fit_body(cases, self.fn_hz)
            self.body = Body(fit[0], fit[2], len(cases), fit[1]) if fit else Body(math.nan, math.nan, 0, math.nan)
        return self.body if self.body.records else None

    def zeta_d(self, clicks: float) -> tuple[float, float, np.ndarray]:
        """zeta and d at ``clicks`` and their 2 x 2 covariance."""
        names, th = self.fit.names, self.fit.theta
        g = np.zeros((2, len(names)))
        z = d = 0.0
        if "zeta0" in names:
            i0 = names.index("zeta0")
            z = float(th[i0] + th[i0 + 1] * clicks)
            g[0, i0], g[0, i0 + 1] = 1.0, float(clicks)
        if "friction_band_mm" in names:
            j = names.index("friction_band_mm")
            d = float(th[j])
            g[1, j] = 1.0
        return z, d, g @ self.fit.cov @ g.T

    def x_eq_of(self, seq: bd.Extrema, clicks: float) -> float:
        """A record's static position x_eq (mm) with the law's zeta and d at its ``clicks`` held: the
        least squares of its half-cycle relations in x_eq alone (linear: closed form); its last
        extremum when it has one relation or none."""
        z, d, _ = self.zeta_d(clicks)
        lv = seq.levels_mm
        if lv.size < 2:
            return float(lv[-1]) if lv.size else float("nan")
        r = bd.ratio(z)
        # x_{n+1} = (1 + r)(x_eq + sigma_n d) - r x_n: residual linear in x_eq
        target = lv[1:] + r * lv[:-1] - (1 + r) * seq.sigma[:-1] * d
        return float(np.mean(target) / (1 + r))

    def frequency(self, clicks: float) -> tuple[float, float]:
        z, _, cov = self.zeta_d(clicks)
        z = min(max(z, 0.0), 0.99)
        root = math.sqrt(1 - z * z)
        return self.fn_hz * root, math.hypot(root * self.fn_sd, self.fn_hz * z / root * math.sqrt(cov[0, 0]))

    def first_decay(self, clicks: float, s0: float) -> tuple[float, float]:
        p = bd.law_prediction(self.fit, clicks, s0)
        return p["decay"], p["decay_sd_total"]

    def predict(self, clicks: float, record, seq: bd.Extrema, x_eq: float, source_clicks: float,
                x_mm: np.ndarray, stroke_mm: float, after_s: float = 4.0) -> Prediction:
        """The ring-down at ``clicks`` from ``record``'s own state (its travel ``x_mm`` up to the slam's
        peak, its x_eq), ``after_s`` after the peak."""
        z, d, cov = self.zeta_d(clicks)
        if not 0.0 <= z < 1.0:
            raise MtbmjError(f"{self.end}: the decay law gives zeta {z:.3f} at {clicks:g} clicks (outside 0 to 1): no "
                             f"ring-down to predict there")
        t = np.asarray(record.time_s, float)
        dt, peak, x0 = peak_start(record, seq, x_mm, stroke_mm)
        fd, fsd = self.frequency(clicks)
        tt, xx = free_motion(x0, x_eq, d, z, self.fn_hz, stroke_mm, after_s, dt)
        body = None
        if (xx.min() <= STOP_NEAR_MM or xx.max() >= stroke_mm - STOP_NEAR_MM) and self.body_share() is not None:
            from mtbmj.identify import bounce_body as bb

            body = self.body_share()  # through the stop: the two masses (the closed form elsewhere: faster)
            tt, xx = bb.trace(bb.TwoMass.of_law(body.share, self.fn_hz, z, d, body.zeta), x0, x_eq, stroke_mm, after_s, dt)
        rng = np.random.default_rng(0)
        draws = rng.multivariate_normal([z, d], cov, size=DRAWS)
        fns = rng.normal(self.fn_hz, self.fn_sd, size=DRAWS)
        speeds = []
        for (zz, dd), fn in zip(draws, fns):
            _, xd = free_motion(x0, x_eq, max(dd, 0.0), min(max(zz, 0.0), 0.99), max(fn, 0.05), stroke_mm,
                                min(after_s, 1.0 / max(fn, 0.05)), dt)
            speeds.append(rebound_speed(xd, dt))
        s0 = float(seq.swings[0]) if seq.swings.size else float("nan")
        dec, dsd = self.first_decay(clicks, s0) if math.isfinite(s0) else (float("nan"), float("nan"))
        v = rebound_speed(xx[: int(1.0 / self.fn_hz / dt) + 2], dt)
        zsd, dsd_ = math.sqrt(max(cov[0, 0], 0.0)), math.sqrt(max(cov[1, 1], 0.0))
        lo, hi = np.percentile(speeds, [2.5, 97.5])
        head = x_mm[: peak + 1]
        time = np.concatenate((t[: peak + 1], t[peak] + tt[1:]))
        travel = np.concatenate((np.clip(head, 0.0, stroke_mm), xx[1:]))
        return Prediction(self.end, float(clicks), getattr(record, "name", ""), float(source_clicks),
                          Estimate(z, *interval95(z, zsd)), Estimate(d, max(0.0, d - Z95 * dsd_), d + Z95 * dsd_),
                          Estimate(fd, *interval95(fd, fsd)), Estimate(dec, *interval95(dec, dsd)),
                          Estimate(v, float(lo), float(hi)), float(x_eq), float(stroke_mm), float(t[peak]), time, travel,
                          body)


def peak_start(record, seq: bd.Extrema, x_mm, stroke_mm: float) -> tuple[float, int, float]:
    """A record's sample step, its slam's peak sample and the peak's level (mm: the travel averaged over
    10 ms, not one noisy sample, within the stroke)."""
    t = np.asarray(record.time_s, float)
    dt = float(t[1] - t[0])
    peak = int(np.argmin(np.abs(t - seq.slam_s)))
    w = max(1, int(round(0.005 / dt)))
    return dt, peak, float(np.clip(np.mean(np.asarray(x_mm, float)[max(0, peak - w):peak + w + 1]), 0.0, stroke_mm))


def record_timings(seqs, records, ends_mm, scatter: HalfScatter | None = None) -> tuple[list, HalfScatter | None]:
    """Each record's Timing (None: untimed) under the half periods' pooled scatter (``scatter``, or pooled
    over these records); the vertex-only :func:`timing` where there is no pool."""
    halves = [timed_halves(s, np.asarray(r.time_s, float), np.asarray(x, float))
              for s, r, x in zip(seqs, records, ends_mm)]
    sc = scatter if scatter is not None else half_scatter(halves)
    if sc is None:
        return [timing(s, np.asarray(r.time_s, float), np.asarray(x, float))
                for s, r, x in zip(seqs, records, ends_mm)], None
    return [honest_timing(h, sc) for h in halves], sc


def decay_law(end: str, seqs, clicks, records, ends_mm, model: str = "both",
              scatter: HalfScatter | None = None) -> DecayLaw | None:
    """The law of one end across ``clicks`` (``model`` with the friction band common, zeta linear in
    clicks) and its common undamped frequency (the records' timings under the half periods' scatter,
    ``scatter`` or pooled over these records); None when the law has no degree of freedom or fewer
    than two records are timed."""
    fit = bd.fit_common(seqs, clicks, model, law=True)
    if fit is None:
        return None
    per = bd.fit_common(seqs, clicks, model, law=False)
    tms, zs, timed = [], [], []
    all_tm, sc = record_timings(seqs, records, ends_mm, scatter)
    for i, tm in enumerate(all_tm):
        if tm is None:
            continue
        zname = f"zeta[{i}]"
        z = per.value(zname)[0] if per is not None and zname in per.names else (
            fit.theta[0] + fit.theta[1] * clicks[i] if "zeta0" in fit.names else 0.0)
        tms.append(tm)
        zs.append(z)
        timed.append(i)
    if not tms:
        return None
    fn, fsd = common_fn(tms, zs)
    return DecayLaw(end, fit, list(seqs), list(clicks), tms, fn, fsd, zs, timed, sc, list(records),
                    [np.asarray(x, float) for x in ends_mm])


def held_out_decay(law: DecayLaw, seq: bd.Extrema, clicks: float, sc: DecayScatter | None) -> dict:
    """A held-out record's first half cycle's decay: the law's prediction at its first swing (its sd as
    :func:`mtbmj.identify.bounce_decay.law_prediction` gives it, ``decay_sd_total``) against its
    measurement. With the decays' pool ``sc`` the measurement carries the pooled scatter (corrected by
    the direction shift where kept; :func:`measured_decay`) and the miss is in the combined sd, its 95 %
    interval with Student's t at the pool's dof; without a pool the measurement carries its read error."""
    p = bd.law_prediction(law.fit, clicks, float(seq.swings[0]))
    val, msd = measured_decay(seq, sc)
    comb = math.hypot(p["decay_sd_total"], msd)
    t95 = sc.t95 if sc is not None else Z95
    out = {"decay": p["decay"], "decay_sd": p["decay_sd_total"], "decay_measured": val,
           "decay_measured_raw": seq.first_decay(), "decay_measured_sd": msd,
           "decay_measured_read_sd": read_sd(seq), "decay_measured_ci95": [val - t95 * msd, val + t95 * msd],
           "decay_misses_by_sd": abs(val - p["decay"]) / comb,
           "decay_within_ci95": bool(abs(val - p["decay"]) <= t95 * comb)}
    if sc is not None:
        out["decay_scatter"] = sc.summary()
    return out


def held_out(seqs, clicks, records, ends_mm, i: int, model: str = "both") -> dict:
    """Record ``i`` held out: the law fitted on the others predicts its first free half cycle's decay
    (at its own first swing) and its frequency; each compared with the record's own measurement
    (combined sd: the prediction's and the measurement's). Every record's frequency carries the half
    periods' scatter pooled over all the records, and its first decay the decays' scatter about their
    record's law pooled over all the records (:func:`held_out_decay`): properties of the measurement,
    not of the law."""
    keep = [j for j in range(len(seqs)) if j != i]
    all_tm, sc = record_timings(seqs, records, ends_mm)
    law = decay_law("held-out", [seqs[j] for j in keep], [clicks[j] for j in keep], [records[j] for j in keep],
                    [ends_mm[j] for j in keep], model, scatter=sc)
    out = {"clicks": clicks[i], "fitted_on_clicks": [clicks[j] for j in keep]}
    if law is None:
        out["note"] = "no degree of freedom left"
        return out
    s = seqs[i]
    out.update(held_out_decay(law, s, clicks[i], decay_scatter(seqs)))
    fd, fsd = law.frequency(clicks[i])
    tm = all_tm[i]
    out.update({"frequency_hz": fd, "frequency_sd": fsd})
    if sc is not None:
        out["half_period_scatter"] = sc.summary()
    if tm is not None:
        out.update({"frequency_measured": tm.frequency_hz, "frequency_measured_sd": tm.sd,
                    "frequency_measured_vertex_sd": tm.vertex_sd,
                    "frequency_measured_ci95": [tm.frequency_hz - (sc.t95 if sc else Z95) * tm.sd,
                                                tm.frequency_hz + (sc.t95 if sc else Z95) * tm.sd],
                    "frequency_misses_by_sd": abs(tm.frequency_hz - fd) / math.hypot(fsd, tm.sd)})
    return out


__all__ = ["Body", "DECAY_MODEL", "DecayLaw", "DecayScatter", "Estimate", "HalfScatter", "Prediction", "Timing", "common_fn", "decay_law", "decay_scatter", "free_motion",
           "half_decays", "half_scatter", "held_out", "held_out_decay", "honest_timing", "measured_decay", "read_sd", "rebound_speed", "record_timings", "timed_halves", "timing",
           "vertex_time"]

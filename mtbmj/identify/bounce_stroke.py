"""Where a seat slam's ring-down is centred in the stroke, and what the bike's own spring gives there.

A linkage's leverage ratio falls with travel on most bikes, so the rear wheel's rate rises with stroke
even on a linear coil. A ring-down centred deeper in the stroke then rings faster. This module tests
that hypothesis on records at several clicks; it does not assume it.

**The wheel rate along the stroke (derivation).** The rear wheel's travel w and the shock's stroke
s(w) are tied by the leverage ratio LR(w) = dw/ds. The spring's potential energy U(s(w)) gives the
force at the wheel F_w(w) = F_s(s(w)) / LR(w), and its rate

    k_w(w) = dF_w/dw = k_s / LR^2 - F_s LR' / LR^2,

the coil's rate through the leverage squared plus the geometric term of the static force (a falling
LR, LR' < 0, stiffens). It is taken here as the secant of F_w over +-3 mm of wheel travel, as
:mod:`mtbmj.identify.bounce_bike` takes the swingarm's stiffness (the leverage table's rounded
ratios make its slope jump from one millimetre to the next). The spring is the bike file's shock
spring (preload, coil, top-out), nothing fitted.

**The law with the stiffening.** The sprung mass in wheel coordinates is held fixed (the centre moved
by a constant push, e.g. weight on the bars, not by another mass on the saddle), so the undamped
frequency at a centre c is ``f_n(c) = f_n(c_j) sqrt(k_w(c) / k_w(c_j))``. Each record fitted's f_n
(its damped frequency over sqrt(1 - zeta^2)) is carried to the held-out record's centre by that ratio
before the records' mean is taken (:func:`mtbmj.identify.bounce_predict.common_fn`, the same sd); each
record's centre is its x_eq in the law's fit, the held-out record's its x_eq with the law's zeta and
d held (as its prediction starts from it). With one centre for all the records this is the law of
:mod:`mtbmj.identify.bounce_predict`. The decay is left as that law gives it: zeta = c / (2 sqrt(k m))
moves by the inverse of the same frequency ratio (at most 2.6 % on the shared slams).

**What each record's placement is** (:func:`placements`): its centre (x_eq of the per-record fit, with
its sd), its first free swing, its rest before the slam (the sag as the rider sat: the median travel
from 1.5 to 0.6 s before the slam's peak) and its free half periods by direction (compression: from a
trough to a peak; rebound: from a peak to a trough), each the spacing of two vertex times
(:func:`mtbmj.identify.bounce_predict.vertex_time`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from mtbmj.identify import bounce_decay as bd
from mtbmj.identify import bounce_predict as bp

SECANT_M = 3e-3  # the wheel rate: the secant over +-3 mm of wheel travel
REST_BEFORE_S = (1.5, 0.6)  # the rest before the slam: the median travel this long to this long before its peak
MM = 1e-3


@dataclass(frozen=True)
class BikeSpring:
    """The rear end's spring as the wheel feels it: a leverage curve (``mtbmj.measured.leverage.Leverage``)
    and the shock spring's force (N) at a stroke (m)."""

    leverage: object
    spring_force: object

    @classmethod
    def of_bike(cls, bike="sst") -> "BikeSpring":
        """The bike file's leverage and its shock's spring law (a preset, a file or a ``BikeSpec``)."""
        from mtbmj.bike import run as bike_run
        from mtbmj.bike import spec as spec_mod

        spec = bike if isinstance(bike, spec_mod.BikeSpec) else spec_mod.load(str(bike))
        spring = bike_run.setups(spec)[1].fork.spring
        return cls(spec.leverage, lambda s: float(spring.force(s, 0.0)))

    def wheel_force(self, w: float) -> float:
        """F_w (N) at wheel travel ``w`` (m): the spring's force through the leverage."""
        return self.spring_force(self.leverage.stroke(w)) / self.leverage.ratio_at(w)

    def wheel_rate(self, stroke_mm: float) -> float:
        """k_w (N/m) at the shock's ``stroke_mm``: the secant of F_w over +-SECANT_M of wheel travel."""
        w = self.leverage.travel_at_stroke(stroke_mm * MM)
        return (self.wheel_force(w + SECANT_M) - self.wheel_force(w - SECANT_M)) / (2 * SECANT_M)

    def frequency_ratio(self, stroke_mm: float, from_mm: float) -> float:
        """f_n at ``stroke_mm`` over f_n at ``from_mm``, the sprung mass the same: sqrt of the rates' ratio."""
        return math.sqrt(self.wheel_rate(stroke_mm) / self.wheel_rate(from_mm))


@dataclass
class Placement:
    """Where one record's ring-down lies in the stroke and how fast each of its free half cycles went."""

    clicks: float
    centre_mm: float
    centre_sd_mm: float
    first_swing_mm: float
    rest_before_mm: float
    half_periods: list  # (direction, from_mm, to_mm, seconds)

    def summary(self) -> dict:
        return {"clicks": self.clicks, "centre_mm": self.centre_mm, "centre_sd_mm": self.centre_sd_mm,
                "first_swing_mm": self.first_swing_mm, "rest_before_slam_mm": self.rest_before_mm,
                "half_periods_s": [{"direction": d, "from_mm": a, "to_mm": b, "s": s}
                                   for d, a, b, s in self.half_periods]}


def half_periods(seq: bd.Extrema, t: np.ndarray, x: np.ndarray) -> list:
    """The free half cycles of one record: (direction, from_mm, to_mm, seconds between vertex times)."""
    times = seq.times_s[np.isfinite(seq.times_s)]
    if times.size < 2:
        return []
    half0 = float(np.median(np.diff(times)))
    tv = [bp.vertex_time(t, x, ti, half0)[0] for ti in times]
    lv = seq.levels_mm
    return [("compression" if lv[j + 1] > lv[j] else "rebound", float(lv[j]), float(lv[j + 1]), tv[j + 1] - tv[j])
            for j in range(times.size - 1)]


def rest_before(t: np.ndarray, x: np.ndarray, slam_s: float) -> float:
    """The median travel from REST_BEFORE_S[0] to REST_BEFORE_S[1] before the slam's peak (nan: none there)."""
    w = (t > slam_s - REST_BEFORE_S[0]) & (t < slam_s - REST_BEFORE_S[1])
    return float(np.median(x[w])) if w.any() else float("nan")


def placements(seqs, clicks, records, ends_mm, model: str = "both") -> list:
    """Each record's Placement; the centres from the records' common fit with zeta per record."""
    per = bd.fit_common(seqs, clicks, model, law=False)
    out = []
    for i, (s, r, x) in enumerate(zip(seqs, records, ends_mm)):
        t, xx = np.asarray(r.time_s, float), np.asarray(x, float)
        c, csd = per.value(f"x_eq_mm[{i}]") if per is not None else (float("nan"), float("nan"))
        out.append(Placement(float(clicks[i]), float(c), float(csd),
                             float(s.swings[0]) if s.swings.size else float("nan"),
                             rest_before(t, xx, s.slam_s), half_periods(s, t, xx)))
    return out


def stiffened(law: bp.DecayLaw, spring: BikeSpring, centre_mm: float) -> bp.DecayLaw:
    """``law`` with each timed record's f_n carried to ``centre_mm`` by the bike's own wheel rate."""
    scaled = []
    for tm, j in zip(law.timings, law.timed):
        q = spring.frequency_ratio(centre_mm, law.fit.value(f"x_eq_mm[{j}]")[0])
        scaled.append(bp.Timing(tm.frequency_hz * q, tm.sd * q, tm.n_times))
    fn, fsd = bp.common_fn(scaled, law.zetas)
    return dataclasses.replace(law, fn_hz=fn, fn_sd=fsd)


def held_out(seqs, clicks, records, ends_mm, i: int, spring: BikeSpring, model: str = "both") -> dict:
    """Record ``i`` held out as :func:`mtbmj.identify.bounce_predict.held_out` gives it, and beside it the
    frequency with the bike's stiffening carried to its centre (``frequency_stiffened_hz``, its sd and its
    miss in combined sd), the centres (``centre_mm``, ``fitted_centres_mm``) and the stiffening's ratio."""
    out = bp.held_out(seqs, clicks, records, ends_mm, i, model)
    keep = [j for j in range(len(seqs)) if j != i]
    sc = bp.record_timings(seqs, records, ends_mm)[1]
    law = bp.decay_law("held-out", [seqs[j] for j in keep], [clicks[j] for j in keep], [records[j] for j in keep],
                       [ends_mm[j] for j in keep], model, scatter=sc)
    if law is None:
        return out
    centre = law.x_eq_of(seqs[i], clicks[i])
    st = stiffened(law, spring, centre)
    fd, fsd = st.frequency(clicks[i])
    out.update({"centre_mm": centre, "fitted_centres_mm": [law.fit.value(f"x_eq_mm[{j}]")[0] for j in law.timed],
                "stiffening_ratio": st.fn_hz / law.fn_hz, "frequency_stiffened_hz": fd,
                "frequency_stiffened_sd": fsd})
    if "frequency_measured" in out:
        out["frequency_stiffened_misses_by_sd"] = (abs(out["frequency_measured"] - fd)
                                                   / math.hypot(fsd, out["frequency_measured_sd"]))
    return out


__all__ = ["BikeSpring", "Placement", "half_periods", "held_out", "placements", "rest_before", "stiffened"]

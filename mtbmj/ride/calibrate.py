"""The ridden bike calibrated on the ride before advice is given (``mtbmj advise``, issue 52 item 1).

**What is identified.** The effective spring of each end: a scale on the fork's spring (its rate,
or its air pressure) and one on the shock's, relative to what the bike file (and its ``--set``\\ s)
says. A spring the bike file gets wrong (a fork 30 % softer than its label, a pressure gauge that
reads high, a spring worn) is the commonest way the model advised on is not the bike ridden
(issue 52: the simulated fork at 23 % dynamic sag where the rider's sat at 35 %).

**How** (:func:`spring_scales`, closed form from the record, nothing simulated). Over a ride that
starts and ends at about the same speed, the frame's vertical momentum and its pitch come back: the
time mean of each end's suspension force at the wheel equals that end's static load (the sprung
weight it carries at rest: frame, rider, from the bike file's masses and the rider's place, the
statics of ``mtbmj.ride.reconstruct_bike.whole_bike``). The record gives each end's travel x(t)
and speed v(t) (``mtbmj.measured.metrics.velocity``); the end's law, composed from the bike file at
a spring scale s (the fork's vertical force F(x, v) / sin(head angle), the shock's F(stroke(w), v) /
leverage ratio), gives the mean force the ride had at s. The scale is the one whose mean force
(spring, stops and damper together: a two-rate damper's mean force is not 0) equals the static
load: one equation per end, solved by bisection (``brentq``) on the composed law, so a progressive
or air spring is scaled as its own key scales it (the law evaluated along the whole ride at each
scale the bisection tries, through the compiled kernel the engines run where numba is present:
:func:`_along`). A stretch of the ride where the wheel hangs in the air carries no force, and that
is in the mean too (the frame falls meanwhile).

**Its interval** (``Scale.low``/``high``): the statics' own uncertainty, the rider's mean place fore and
aft known to ``RIDER_PLACE_MM`` (assumed; it moves load from one end to the other), and the ride split into the advice's segments
(``mtbmj.ride.advice_rules.SEGMENT_S``); each segment's mean spring and damper forces; the segments
resampled ``BOOTSTRAP`` times (seeded) and the scale of each resample (the balance linearised about
the ride's scale: spring force proportional to the scale); the 2.5-97.5 % range; the two added in quadrature. A 5 s segment does
not start and end at one speed, so its spread is the ride's own: it covers what a ride of this
length cannot pin down.

**What it cannot separate.** The mean force fixes each end's spring *for the rider's weight as the
bike file gives it*: a rider 10 kg heavier than the file reads as both springs about 10 % softer
(the sum of the two balances is the total weight, their ratio the rider's place fore and aft).
The scales are then those of the springs that carry the file's rider as the ridden ones carried
the real one, which is what a change of spring is judged against; the rider's mass itself is not
identified (``--rider-kg`` sets it). The damping is not calibrated here.

**When no calibration describes the ride** (:class:`~mtbmj.ride.advice_rules.RideNotDescribed`): no
scale within ``SCALE_RANGE`` of the file's balances an end's mean force (the end sits on its stop,
or the ride's mean travel is beyond what any spring of that kind gives the file's rider). Whether the
calibrated bike then rides the ride as recorded is the advice's check (``mtbmj.ride.advise``).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from mtbmj.ride.advice_rules import (BOOTSTRAP, MAX_SEGMENTS, MIN_SEGMENTS, SEGMENT_S, Adjuster, RideNotDescribed,
                                     adjusters)

SCALE_RANGE = (0.3, 3.0)  # a spring scale beyond these of the file's is no calibration: the ride is not described
SPRING_LABELS = ("spring rate", "air pressure")  # the adjuster that scales an end's spring
RIDER_PLACE_MM = 30.0  # assumed (95 %): the rider's mean place fore and aft, rider to rider (moves load between ends)


@dataclass(frozen=True)
class Scale:
    """One end's spring scale: ``value`` (the ride's), ``low``-``high`` its 95 % interval; the
    adjuster it scales (the bike file's value and unit) and the value ridden (``value`` times it)."""

    end: str
    value: float
    low: float
    high: float
    adjuster: Adjuster
    load_N: float  # the end's static load at the wheel (the file's masses)
    segments: int

    def to_dict(self) -> dict:
        a = self.adjuster
        st = a.setting(a.value * self.value)
        return {"end": self.end, "scale": self.value, "low": self.low, "high": self.high,
                "key": st["key"], "unit": st["unit"], "file": st["from"], "calibrated": st["to"],
                "calibrated_low": a.setting(a.value * self.low)["to"],
                "calibrated_high": a.setting(a.value * self.high)["to"], "static_load_N": self.load_N,
                "segments": self.segments}

    def line(self) -> str:
        d = self.to_dict()
        return (f"{self.adjuster.label} {d['calibrated']:g} {d['unit']} (95 %: {d['calibrated_low']:g}-"
                f"{d['calibrated_high']:g}; the file's {d['file']:g}, x{self.value:.2f})")


@dataclass
class Calibration:
    """The ridden bike's springs (:class:`Scale` per end with a spring adjuster) and the overrides
    that make the bike file that bike (``overrides``: merged over the recorded ones)."""

    scales: dict
    overrides: dict = field(default_factory=dict)
    method: str = "mean suspension force = static load, per end (closed form; see mtbmj.ride.calibrate)"

    def to_dict(self) -> dict:
        return {"method": self.method, "springs": {e: s.to_dict() for e, s in self.scales.items()},
                "overrides": self.overrides,
                "not_identified": "the rider's mass (a heavier rider reads as softer springs) and the damping"}

    def line(self) -> str:
        return "calibrated on the ride: " + "; ".join(s.line() for s in self.scales.values())

    def apply(self, bike, overrides=None) -> dict:
        """``overrides`` with each calibrated end's spring (as ``bike`` with them sets it) times its
        scale: the ridden bike at that setting (a spring tried is the one labelled so, ridden)."""
        from mtbmj.bike import spec as spec_mod

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            spec = spec_mod.load(bike, overrides or None)
        out = dict(overrides or {})
        for end, sc in self.scales.items():
            a = spring_adjuster(spec, end)
            if a is not None:
                out = merged(out, a.overrides(a.value * sc.value))
        return out

    def adjusters(self, spec) -> list:
        """The bike file's adjusters (``spec`` without the calibration) on the calibrated bike: each
        spring's value and candidates times its end's scale, read in the file's units (``per_unit``
        times the scale: the setting a rider sets, relative to the calibrated spring)."""
        from dataclasses import replace

        out = []
        for a in adjusters(spec):
            sc = self.scales.get(a.end)
            if sc is not None and a.label.partition(" ")[2] in SPRING_LABELS:
                s = sc.value
                a = replace(a, value=a.value * s, down=None if a.down is None else a.down * s,
                            up=None if a.up is None else a.up * s, per_unit=a.per_unit * s)
            out.append(a)
        return out


def spring_adjuster(spec, end: str) -> Adjuster | None:
    """The adjuster that scales ``end``'s spring (its rate or air pressure), or None."""
    return next((a for a in adjusters(spec) if a.end == end and a.label.partition(" ")[2] in SPRING_LABELS), None)


def _laws(bike, overrides):
    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod
    from mtbmj.ride import reconstruct_bike

    with warnings.catch_warnings():  # a scale tried on the way may leave the plausible range
        warnings.simplefilter("ignore")
        spec = spec_mod.load(bike, overrides)
        fork_setup, shock_setup = bike_run.setups(spec)
    return spec, reconstruct_bike.whole_bike(spec, fork_setup, shock_setup)


def _geometry(whole, end: str, x_m):
    """The rear's leverage ratio and shock stroke per sample of its wheel travel ``x_m`` (m), or None
    for the front: geometry, the same at every spring scale, so computed once per ride."""
    if end == "front":
        return None
    return np.array([whole.lev.ratio_at(w) for w in x_m]), whole.lev.strokes(np.asarray(x_m, float))


def _along(law, x, v):
    """``law``'s force (N) at each stroke ``x`` (m) and speed ``v`` (m/s), a stick state at 0 for a law
    with one: through the compiled kernel every engine runs (``kernels.fork_forces``) where numba is
    present and the law has a compiled form (``compiled.fork_forces_along``), else the Python law per
    sample (its specification)."""
    from mtbmj.controllers.compiled import fork_forces_along

    x, v = np.asarray(x, float), np.asarray(v, float)
    out = fork_forces_along(law, x, v, np.zeros(x.size))
    if out is not None:
        return out
    one = (lambda a, b: law.force(a, b, 0.0)) if law.has_state else law.force
    return np.array([one(a, b) for a, b in zip(x, v)])


def _total(whole, end: str, x_m, v_m_per_s, geometry=None):
    """The suspension force at the wheel (spring, stops and damper together), vertical, N, per sample
    of ``end``'s travel (m: the fork's stroke, the rear wheel's travel) and its speed; ``geometry``
    the rear's :func:`_geometry` (computed here where None)."""
    if end == "front":
        return _along(whole.fork, x_m, v_m_per_s) / whole.sin_a
    ratio, strokes = _geometry(whole, end, x_m) if geometry is None else geometry
    return _along(whole.shock, strokes, np.asarray(v_m_per_s, float) / ratio) / ratio


def _forces(whole, end: str, x_m, v_m_per_s, geometry=None):
    """(spring force, damper force) at the wheel, vertical, N, per sample of ``end``'s travel (m:
    the fork's stroke, the rear wheel's travel) and its speed (the spring's at no speed, the damper's
    the rest of :func:`_total`)."""
    still = np.zeros(np.asarray(x_m).size)
    if end == "front":
        spring = _along(whole.fork, x_m, still) / whole.sin_a
    else:
        ratio, strokes = _geometry(whole, end, x_m) if geometry is None else geometry
        geometry = (ratio, strokes)
        spring = _along(whole.shock, strokes, still) / ratio
    total = _total(whole, end, x_m, v_m_per_s, geometry)
    return spring, total - spring


def merged(base: dict, extra: dict) -> dict:
    """``base`` overrides with ``extra``'s over them (a section's keys merged)."""
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in (base or {}).items()}
    for k, v in extra.items():
        out[k] = {**out.get(k, {}), **v} if isinstance(v, dict) else v
    return out


def _segments(t) -> list:
    length = float(t[-1] - t[0])
    n = int(min(max(length // SEGMENT_S, MIN_SEGMENTS), MAX_SEGMENTS))
    edges = np.linspace(t[0], t[-1], n + 1)
    return [(t >= a) & (t <= b) for a, b in zip(edges[:-1], edges[1:])]


def spring_scales(t, front_mm, rear_mm, bike, overrides=None, name: str = "ride") -> Calibration:
    """Each end's spring scale from the ride (see the module doc): ``t`` s, ``front_mm`` the fork's
    travel and ``rear_mm`` the rear wheel's (compression positive) on it; ``bike`` a preset, file or
    ``ResolvedBike``, ``overrides`` its recorded keys. Raises ``RideNotDescribed`` naming the end
    where no scale within ``SCALE_RANGE`` balances it."""
    from scipy.optimize import brentq

    from mtbmj.measured import metrics as m

    t = np.asarray(t, float)
    spec, whole = _laws(bike, overrides)
    series = {"front": np.asarray(front_mm, float), "rear": np.asarray(rear_mm, float)}
    loads = {"front": whole.fF0, "rear": whole.fR0}
    segs = _segments(t)
    rng = np.random.default_rng(0)
    pick = rng.integers(0, len(segs), size=(BOOTSTRAP, len(segs)))
    scales, over = {}, {}
    for end in ("front", "rear"):
        adj = spring_adjuster(spec, end)
        if adj is None:
            continue
        x = np.clip(series[end], 0.0, None) * 1e-3
        v = m.velocity(t, series[end]) * 1e-3
        load = float(loads[end])

        geometry = _geometry(whole, end, x)  # the leverage does not change with the spring

        def mean_force(s):  # the whole force's mean: its spring and damper parts not needed apart here
            _, w = _laws(bike, merged(overrides, adj.overrides(adj.value * s)))
            return float(np.mean(_total(w, end, x, v, geometry)))

        lo, hi = SCALE_RANGE
        f_lo, f_hi = mean_force(lo) - load, mean_force(hi) - load
        if not f_lo < 0.0 < f_hi:
            what = "softer" if f_lo >= 0.0 else "stiffer"
            raise RideNotDescribed(
                f"{name}: no {adj.label} within x{lo:g}-x{hi:g} of the bike file's carries the {end} end's static "
                f"load ({load:.0f} N) over the ride's travel (the ride's mean {series[end].mean():.1f} mm needs a "
                f"spring {what} than that): the model does not describe this ride, so it cannot predict a change")
        s = float(brentq(lambda q: mean_force(q) - load, lo, hi, xtol=1e-4))
        _, w = _laws(bike, merged(overrides, adj.overrides(adj.value * s)))
        spring, damper = _forces(w, end, x, v, geometry)
        sp = np.array([spring[k].mean() for k in segs])
        dm = np.array([damper[k].mean() for k in segs])
        n = np.array([k.sum() for k in segs], float)
        # each resample's scale, the balance linearised about s (spring force proportional to its scale)
        S = (sp[pick] * n[pick]).sum(1) / n[pick].sum(1)
        D = (dm[pick] * n[pick]).sum(1) / n[pick].sum(1)
        boot = s * (load - D) / S
        low, high = np.percentile(boot, [2.5, 97.5])
        # and the statics' own: the rider's mean place fore and aft, RIDER_PLACE_MM (two sigma), moves
        # m g dx / wheelbase of load between the ends; added in quadrature to each side
        place = s * (whole.mr * whole.g * RIDER_PLACE_MM * 1e-3 / (whole.xF - whole.xR)) / (load - float(damper.mean()))
        low, high = s - math.hypot(s - low, place), s + math.hypot(high - s, place)
        scales[end] = Scale(end, s, float(min(low, s)), float(max(high, s)), adj, load, len(segs))
        over = merged(over, adj.overrides(adj.value * s))
    return Calibration(scales, over)


def calibrate(record, bike, overrides=None, duration: float | None = None) -> Calibration:
    """:func:`spring_scales` of a ``TelemetryRecord`` with both ends (its first ``duration`` s), read
    as the reconstruction reads it (at ``mtbmj.ride.reconstruct.RATE_HZ``)."""
    from mtbmj.ride.reconstruct import RATE_HZ

    rec = record.decimated(RATE_HZ)
    t = np.asarray(rec.time_s, float)
    keep = (t - t[0] <= duration) if duration is not None else np.ones(t.size, bool)
    return spring_scales(t[keep], np.asarray(rec.fork_mm, float)[keep], np.asarray(rec.rear_mm, float)[keep], bike,
                         overrides, rec.name)


__all__ = ["Calibration", "Scale", "SCALE_RANGE", "calibrate", "merged", "spring_adjuster", "spring_scales"]

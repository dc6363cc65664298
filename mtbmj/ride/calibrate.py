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

**Nor how the ride's load is split fore and aft** (:class:`Split`, ``Calibration.split``). Each end's
balance takes the end's load as the bike at rest on level ground carries it. A ride that carries load
forward (a descent at a steady speed: the weight's component along the slope acts at the centre of
mass, ``h`` above the ground, and moves ``m g h sin(slope) / wheelbase`` onto the front; braking;
the rider further forward than the file's place) sinks the fork and lifts the rear as a softer fork
and a stiffer shock would: with a linear spring the two are the same motion (the sag, and with it the
frequency, is the load over the rate). So the same two balances are also read the other way: both
springs at one scale, from their sum (the whole weight, which no fore-aft split moves), and what is
left of the front's balance a load carried forward (``shift_N``, as the rider's place or a mean
descent). Measured on rides made in the tests: the file's bike ridden with the rider 150 mm forward
reads per end as the fork x0.81 and the shock x1.22, and the other reading gives both x1.00 with the
load the rider moved (86 N against the 86 N of their weight times 0.15 m over the wheelbase); a fork
30 % softer than its file reads per end right (x0.68), the other reading both x0.84 with 96 N forward.
The shared rides of one setting read per end x0.61/1.23, x0.60/1.16 and x0.79/1.09 (fork/shock), the
other way x0.89, x0.86 and x0.95 with 131, 123 and 59 N forward (descents of 8.9, 8.4 and 4.0 deg):
their common scale agrees better ride to ride than their fork's (10 % against 26 %), but nothing in the
travel decides. The advice therefore judges a change that rests on the static sag (which depends on
the reading; the ride's own metrics do not) on both readings (``mtbmj.ride.advise.Advice.other_reading``,
``mtbmj.ride.advice_verdict``): a change that holds on one only is "inconclusive", and says that the
static sag measured standing on level ground is what tells them apart.

**The static sag measured decides it** (``static_sag_mm``, ``--static-sag-mm FORK,SHOCK``:
:func:`sag_scales`). Each end's spring is the scale whose closed-form static stroke under the file's
rider in the file's place is the one measured (its interval the scales at the sag +- ``SAG_READ_MM``).
The ride's balances then give what the ride carried (:func:`_carried`, ``Calibration.carried``): half
the difference of the ends' excess mean forces a load carried forward (as the rider's place and a mean
descent), their sum a weight the file's rider does not have. The calibrated bike rides with its rider
moved to that place (``Calibration.apply``: the reconstruction and every run carry the load as the
ride did; on the made forward ride the bike loops out at 5.9 s without the move, 21 s on its point-contact ride), and a run's static
sag is taken back to the file's place before the rules read it (``Calibration.level_offsets``,
``mtbmj.ride.advise.Advice.levelled``): the rules judge the sag the rider measured. Measured on the
made rides: the forward ride's springs x0.97/x1.02 with 86 N carried forward (the rider 149 mm, made
150); the soft fork's x0.68 (made 0.7) with none. Or (``carried_as="descent"``, ``--carried-as descent``) the rider stays in
place and the runs ride the terrain laid on the steady descent that carries the load
(``Calibration.descent_deg``, found through the engine: :mod:`mtbmj.ride.calibrate_descent`); the
reconstruction's level-ground statics then carry it with the rider at that place (``apply(statics=True)``).

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
NOT_IDENTIFIED = ("the rider's mass (a heavier rider reads as softer springs), how the ride's load is split fore and aft "
                  "(a fork softer than the file reads as a load carried forward: see \"or\") and the damping")
SAG_READ_MM = 2.0  # assumed: a static sag read at an O-ring, the rider's stance as they ride, to +-2 mm (95 %)
SAG_METHOD = "the static sag measured (--static-sag-mm), per end (closed-form statics; see mtbmj.ride.calibrate)"
CARRIED_AS = ("rider", "descent")  # how the sag path's runs carry the load the ride carried fore-aft
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


def carried_words(load_N: float, place_mm: float, descent_deg: float) -> str:
    """A load carried fore-aft in words, as every line and report says it: "131 N carried forward of rest
    (the rider 234 mm forward, or a 8.9 deg mean descent)"."""
    where = "forward" if load_N >= 0 else "rearward"
    return (f"{abs(load_N):.0f} N carried {where} of rest (the rider {abs(place_mm):.0f} mm {where}, or a "
            f"{abs(descent_deg):.1f} deg mean {'descent' if descent_deg >= 0 else 'climb'})")


@dataclass(frozen=True)
class Split:
    """The same ride read the other way (see the module doc, "What it cannot separate"): both springs
    at one scale ``common`` (from the sum of the ends' balances, the whole weight), and the front's
    mean force over its static load at that scale a load the ride moved forward, ``shift_N`` (N at the
    front wheel, off the rear). ``place_mm``: the rider's mean place forward that moves it; ``slope_deg``:
    the mean descent that moves it at a steady speed (the weight's component along the slope at the
    centre of mass, ``com_height_m`` above the ground). ``static_sag``: per end, the static sag (% of
    travel, closed-form statics) as the per-end scales give it and as the common scale does."""

    common: float
    shift_N: float
    place_mm: float
    slope_deg: float
    com_height_m: float
    static_sag: dict

    def to_dict(self) -> dict:
        return {"common_scale": self.common, "load_forward_N": self.shift_N, "rider_place_forward_mm": self.place_mm,
                "descent_deg": self.slope_deg, "com_height_m": self.com_height_m,
                "static_sag_percent": {e: {"springs_apart": a, "springs_together": b}
                                       for e, (a, b) in self.static_sag.items()}}

    def line(self) -> str:
        return (f"or both springs x{self.common:.2f} with {carried_words(self.shift_N, self.place_mm, self.slope_deg)}: "
                f"the travel alone cannot tell these apart")


@dataclass
class Calibration:
    """The ridden bike's springs (:class:`Scale` per end with a spring adjuster) and the overrides
    that make the bike file that bike (``overrides``: merged over the recorded ones)."""

    scales: dict
    overrides: dict = field(default_factory=dict)
    method: str = "mean suspension force = static load, per end (closed form; see mtbmj.ride.calibrate)"
    split: Split | None = None  # the same balances read as one spring scale and a load carried fore-aft
    carried: dict | None = None  # with the springs from a measured static sag: the load the ride carried (_carried)
    level: dict | None = None  # per end, static sag points from the rider as carried to the rider in place (sag path)
    rides: int = 1  # the rides it was read from (several: calibrate_pooled)
    descent_deg: float = 0.0  # the sag path's load carried as a mean descent: the grade every run rides (deg)

    def to_dict(self) -> dict:
        return {"method": self.method, "rides": self.rides, "springs": {e: s.to_dict() for e, s in self.scales.items()},
                "overrides": self.overrides,
                "not_identified": NOT_IDENTIFIED,
                "or": None if self.split is None else self.split.to_dict(), "carried": self.carried}

    def line(self) -> str:
        if self.carried is not None:
            c = self.carried
            on = "" if self.rides == 1 else f" ({self.rides} rides pooled)"
            out = f"calibrated on the static sag{on}: " + "; ".join(s.line() for s in self.scales.values())
            if "load_forward_N" not in c:
                return out
            ridden = (f"; ridden as a {abs(self.descent_deg):.1f} deg mean {'descent' if self.descent_deg >= 0 else 'climb'} "
                      f"(--carried-as descent)" if c.get("as") == "descent" else "")
            return (f"{out}; on the ride {carried_words(c['load_forward_N'], c['rider_place_forward_mm'], c['descent_deg'])} "
                    f"and {c['weight_beyond_file_kg']:+.1f} kg of weight beyond the file's rider{ridden}")
        on = "the ride" if self.rides == 1 else f"{self.rides} rides pooled"
        out = f"calibrated on {on}: " + "; ".join(s.line() for s in self.scales.values())
        return out if self.split is None else f"{out}; {self.split.line()}"

    def level_offsets(self) -> dict:
        """Per end, the static sag (points of travel) to add to a run's, whose rider rides where the ride
        carried the load (``carried``: the rider moved in ``overrides``), for the sag standing in the
        file's place on level ground, which the rules judge (and the rider measured): 0 without a move."""
        return dict(self.level) if self.level else {"front": 0.0, "rear": 0.0}

    def static_sag_offsets(self) -> dict:
        """Per end, the static sag (points of travel) the other reading (:class:`Split`) gives over this
        calibration's: 0 where there is no split."""
        if self.split is None:
            return {"front": 0.0, "rear": 0.0}
        return {e: b - a for e, (a, b) in self.split.static_sag.items()}

    def apply(self, bike, overrides=None, statics: bool = False) -> dict:
        """``overrides`` with each calibrated end's spring (as ``bike`` with them sets it) times its
        scale: the ridden bike at that setting (a spring tried is the one labelled so, ridden); on the sag
        path (``--static-sag-mm``) the rider moved forward by the place the ride carried its load at
        (carried as a descent: only where ``statics``, the reconstruction's, whose level-ground statics
        then carry the descent's mean load as the ride did, while the runs ride the grade)."""
        from mtbmj.bike import spec as spec_mod

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            spec = spec_mod.load(bike, overrides or None)
        out = dict(overrides or {})
        for end, sc in self.scales.items():
            a = spring_adjuster(spec, end)
            if a is not None:
                out = merged(out, a.overrides(a.value * sc.value))
        place = (self.carried or {}).get("rider_place_forward_mm")
        how = (self.carried or {}).get("as")
        if place is not None and (how == "rider" or (statics and how == "descent")):  # where the load was carried
            out = merged(out, _rider_moved(spec, place))
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
    return whole.lev.ratios(x_m), whole.lev.strokes(np.asarray(x_m, float))


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


class _MeanForce:
    """``end``'s mean suspension force over the ride (N, at the wheel: spring, stops and damper) at a
    scale ``s`` on its spring adjuster ``adj``; ``geometry`` the rear's leverage along the ride, the same
    at every scale (computed once)."""

    def __init__(self, bike, overrides, adj, whole, end, x, v):
        self.bike, self.overrides, self.adj, self.end, self.x, self.v = bike, overrides, adj, end, x, v
        self.geometry = _geometry(whole, end, x)

    def __call__(self, s: float) -> float:
        _, w = _laws(self.bike, _scaled(self.overrides, self.adj, s))
        return float(np.mean(_total(w, self.end, self.x, self.v, self.geometry)))


def static_sags(bike, overrides=None) -> dict:
    """Each end's static sag, % of its travel (the fork's stroke, the rear wheel's), of ``bike`` with
    ``overrides``: the closed-form statics of ``reconstruct_bike.whole_bike`` (the file's rider in its
    place on level ground), not a simulation."""
    _, w = _laws(bike, overrides)
    return {"front": 100.0 * w.wF0 / w.sin_a / w.fork_travel, "rear": 100.0 * w.wR0 / w.lev.full_travel}


def _com_height(spec, whole) -> float:
    """The whole bike's centre of mass above level ground (m): frame body, rider, the wheels at their axles."""
    from mtbmj.bike.model import frame_body

    M, (_, cz), _ = frame_body(spec)
    axle = 0.5 * (spec.front_axle[1] + spec.rear_axle[1])
    parts = ((M, cz), (whole.mr, spec.rider.com[1]), (whole.mF, spec.front_axle[1]), (whole.mR, spec.rear_axle[1]))
    return sum(m * z for m, z in parts) / sum(m for m, _ in parts) - axle + whole.radius


def _scaled(overrides, adj, s: float) -> dict:
    """``overrides`` with the spring adjuster ``adj`` at ``s`` times its value."""
    return merged(overrides, adj.overrides(adj.value * s))


def _springs_at(overrides, scales) -> dict:
    """``overrides`` with each spring adjuster of ``scales`` ((adjuster, scale) pairs) at that scale."""
    out = overrides
    for adj, s in scales:
        out = _scaled(out, adj, s)
    return dict(out or {})


def _load_as(spec, whole, forward_N: float) -> tuple:
    """A load ``forward_N`` carried onto the front (off the rear) read as (the rider's place forward that
    moves it, mm; the mean descent that moves it at a steady speed, deg; the centre of mass's height, m)."""
    wheelbase = whole.xF - whole.xR
    everything = whole.M + whole.mr + whole.mF + whole.mR
    h = _com_height(spec, whole)
    sine = max(-1.0, min(1.0, forward_N * wheelbase / (everything * whole.g * h)))
    return 1e3 * forward_N * wheelbase / (whole.mr * whole.g), math.degrees(math.asin(sine)), h


def _rider_moved(spec, forward_mm: float) -> dict:
    """The override that moves ``spec``'s rider ``forward_mm`` forward of its place (``rider.com_mm``)."""
    x, z = (1e3 * c for c in spec.rider.com)
    return {"rider.com_mm": [x + forward_mm, z]}


def _split(spec, whole, bike, overrides, scales, mean_forces) -> Split:
    """The other reading of the same two balances (:class:`Split`): both springs at one scale, from
    their sum, and what is left of the front's balance a load moved forward."""
    from scipy.optimize import brentq

    total = whole.fF0 + whole.fR0
    lo, hi = SCALE_RANGE

    def excess(q):
        return mean_forces["front"](q) + mean_forces["rear"](q) - total

    if not excess(lo) < 0.0 < excess(hi):  # each end balanced within the range, their sum is too
        return None
    common = float(brentq(excess, lo, hi, xtol=1e-4))
    shift = mean_forces["front"](common) - whole.fF0
    place, slope, h = _load_as(spec, whole, shift)
    apart = static_sags(bike, _springs_at(overrides, [(sc.adjuster, sc.value) for sc in scales.values()]))
    together = static_sags(bike, _springs_at(overrides, [(sc.adjuster, common) for sc in scales.values()]))
    return Split(common, float(shift), place, slope, h, {e: (apart[e], together[e]) for e in ("front", "rear")})


def static_strokes(bike, overrides=None) -> dict:
    """Each end's static stroke, mm (the fork's, the shock's) of ``bike`` with ``overrides``: the
    closed-form statics of ``reconstruct_bike.whole_bike`` (the file's rider in its place, level ground)."""
    _, w = _laws(bike, overrides)
    return {"front": 1e3 * w.wF0 / w.sin_a, "rear": 1e3 * float(w.lev.strokes(np.array([w.wR0]))[0])}


def sag_scales(bike, overrides, static_sag_mm, segments: int = 0) -> dict:
    """Each end's spring scale (:class:`Scale`) whose static stroke (:func:`static_strokes`, the file's
    rider) is the one measured, ``static_sag_mm`` = (fork, shock) mm; its interval the scales at the
    sag +- ``SAG_READ_MM``. Raises ``ConfigError`` naming ``--static-sag-mm`` where no scale within
    ``SCALE_RANGE`` sags so far (or the sag is beyond the stroke)."""
    from scipy.optimize import brentq

    from mtbmj.errors import ConfigError

    spec, whole = _laws(bike, overrides)
    loads = {"front": whole.fF0, "rear": whole.fR0}
    out = {}
    for end, target in zip(("front", "rear"), static_sag_mm):
        adj = spring_adjuster(spec, end)
        if adj is None:
            continue

        def sag(q, adj=adj, end=end):
            return static_strokes(bike, _scaled(overrides, adj, q))[end]

        lo, hi = SCALE_RANGE
        values = []
        for mm in (target, target + SAG_READ_MM, max(target - SAG_READ_MM, 0.0)):
            if not sag(hi) < mm < sag(lo):
                part = "fork's" if end == "front" else "shock's"
                raise ConfigError(
                    f"--static-sag-mm: the {part} {target:g} mm is not a static sag any {adj.label} within x{lo:g}-x{hi:g} "
                    f"of the bike file's gives its rider ({sag(hi):.1f}-{sag(lo):.1f} mm): check the number, the end "
                    f"(fork first, then shock) and --rider-kg")
            values.append(float(brentq(lambda q: sag(q) - mm, lo, hi, xtol=1e-5)))
        s, low, high = values[0], min(values), max(values)
        out[end] = Scale(end, s, low, high, adj, float(loads[end]), segments)
    return out


def _carried(spec, whole, scales, mean_forces) -> dict:
    """The load the ride carried over what rest carries (N, each end's mean force at its scale less its
    static load), read as a load moved forward (half their difference) and a weight the file's rider
    does not have (their sum, kg): the rider's place and the descent that would move it (as :class:`Split`)."""
    extra = {e: mean_forces[e](scales[e].value) - (whole.fF0 if e == "front" else whole.fR0) for e in scales}
    if len(extra) < 2:
        return {f"{e}_N": v for e, v in extra.items()}
    forward = 0.5 * (extra["front"] - extra["rear"])
    place, descent, _ = _load_as(spec, whole, forward)
    return {"front_N": extra["front"], "rear_N": extra["rear"], "load_forward_N": forward,
            "rider_place_forward_mm": place, "descent_deg": descent,
            "weight_beyond_file_kg": (extra["front"] + extra["rear"]) / whole.g}


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


def spring_scales(t, front_mm, rear_mm, bike, overrides=None, name: str = "ride", static_sag_mm=None,
                  velocity=None, carried_as: str = "rider") -> Calibration:
    """Each end's spring scale from the ride (see the module doc): ``t`` s, ``front_mm`` the fork's
    travel and ``rear_mm`` the rear wheel's (compression positive) on it; ``bike`` a preset, file or
    ``ResolvedBike``, ``overrides`` its recorded keys. Raises ``RideNotDescribed`` naming the end
    where no scale within ``SCALE_RANGE`` balances it. ``static_sag_mm`` (the fork's stroke, the shock's
    stroke, mm, measured standing on level ground): the springs from it instead (:func:`sag_scales`),
    the ride's balances then the load it carried (``Calibration.carried``). ``velocity``: each end's
    travel speed (mm/s on ``t``, {"front", "rear"}) where it is not the derivative of the travel on ``t``
    (rides joined end to end: :func:`calibrate_pooled`). ``carried_as`` (with ``static_sag_mm``): how the runs
    carry the load the ride carried fore-aft, "rider" (the rider moved to that place) or "descent" (a mean
    descent at a steady speed: the runs ride the terrain laid on that grade, the rider in the file's place)."""
    from scipy.optimize import brentq

    from mtbmj.measured import metrics as m

    t = np.asarray(t, float)
    spec, whole = _laws(bike, overrides)
    series = {"front": np.asarray(front_mm, float), "rear": np.asarray(rear_mm, float)}
    loads = {"front": whole.fF0, "rear": whole.fR0}
    segs = _segments(t)
    rng = np.random.default_rng(0)
    pick = rng.integers(0, len(segs), size=(BOOTSTRAP, len(segs)))
    scales, over, mean_forces = {}, {}, {}
    for end in ("front", "rear"):
        adj = spring_adjuster(spec, end)
        if adj is None:
            continue
        x = np.clip(series[end], 0.0, None) * 1e-3
        v = (m.velocity(t, series[end]) if velocity is None else np.asarray(velocity[end], float)) * 1e-3
        load = float(loads[end])
        mean_force = _MeanForce(bike, overrides, adj, whole, end, x, v)
        mean_forces[end] = mean_force

        lo, hi = SCALE_RANGE
        f_lo, f_hi = mean_force(lo) - load, mean_force(hi) - load
        if not f_lo < 0.0 < f_hi:
            what = "softer" if f_lo >= 0.0 else "stiffer"
            raise RideNotDescribed(
                f"{name}: {_on_sag_load(bike, overrides, static_sag_mm, end, mean_force, load)}no {adj.label} within "
                f"x{lo:g}-x{hi:g} of the bike file's carries the {end} end's static load ({load:.0f} N) over the ride's "
                f"travel (the ride's mean {series[end].mean():.1f} mm needs a spring {what} than that): the model does "
                f"not describe this ride, so it cannot predict a change")
        if static_sag_mm is not None:  # the springs come from the sag: this end's balance is only needed described
            continue
        s = float(brentq(lambda q: mean_force(q) - load, lo, hi, xtol=1e-4))
        _, w = _laws(bike, _scaled(overrides, adj, s))
        spring, damper = _forces(w, end, x, v, mean_force.geometry)
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
    if static_sag_mm is not None:  # the springs from the sag measured: the ride's balances give the load carried
        return _on_the_sag(spec, whole, bike, overrides, static_sag_mm, len(segs), mean_forces, name, carried_as)
    split = _split(spec, whole, bike, overrides, scales, mean_forces) if len(scales) == 2 else None
    return Calibration(scales, over, split=split)


def _on_sag_load(bike, overrides, static_sag_mm, end: str, mean_force, load: float) -> str:
    """With a measured static sag, what a ride no spring balances says first: the load the ride carried
    on ``end`` at the spring that sag gives, against the ``load`` bike and rider put on it at rest; ""
    without one (or a sag no spring gives: ``sag_scales`` says that)."""
    from mtbmj.errors import ConfigError

    if static_sag_mm is None:
        return ""
    try:
        q = sag_scales(bike, overrides, static_sag_mm)[end].value
    except (ConfigError, KeyError):
        return ""
    carried = float(mean_force(q))
    sag = static_sag_mm[0 if end == "front" else 1]
    less = carried < load
    # a climb moves load rearward, a descent or braking forward, and so does the rider's place
    cause = ("a climb or the rider back" if less == (end == "front") else
             "a descent, braking or the rider forward")
    return (f"at the spring --static-sag-mm gives ({sag:g} mm, x{q:.2f} of the bike file's) the ride carried {carried:.0f} N "
            f"on the {end} end, {100.0 * carried / load:.0f} % of the {load:.0f} N bike and rider weigh on it: the ride "
            f"carries {'less' if less else 'more'} than the bike and rider weigh there ({cause}, or the sag of another "
            f"setting or rider?); ")


def _on_the_sag(spec, whole, bike, overrides, static_sag_mm, segments: int, mean_forces, name: str,
                carried_as: str = "rider") -> Calibration:
    """The calibration on a measured static sag (:func:`sag_scales`), the load the ride carried
    (:func:`_carried`), and that load carried by the runs as ``carried_as`` says: "rider", the rider moved
    to where it was carried and the static sag points that move adds (``Calibration.level``; raises
    ``RideNotDescribed`` where that place is past the bars or behind the pedals); "descent", the rider in
    place and every run on the mean descent that carries it (``Calibration.descent_deg``)."""
    if carried_as not in CARRIED_AS:
        raise ValueError(f"carried_as: one of {', '.join(CARRIED_AS)}, got {carried_as!r}")
    scales = sag_scales(bike, overrides, static_sag_mm, segments)
    over = _springs_at({}, [(sc.adjuster, sc.value) for sc in scales.values()])
    carried = _carried(spec, whole, scales, mean_forces)
    level = {"front": 0.0, "rear": 0.0}
    if "descent_deg" in carried and carried_as == "descent":  # the load a descent's: the terrain laid on its grade
        try:
            found = descent_for(bike, overrides, scales, carried["load_forward_N"], carried["descent_deg"])
        except RideNotDescribed as exc:
            raise RideNotDescribed(f"{name}: with the springs --static-sag-mm gives, {exc}: the model does not "
                                   f"describe this ride with that sag") from None
        carried.update({"as": "descent", "ridden_descent_deg": found["descent_deg"], "descent_runs": found["runs"]})
        return Calibration(scales, over, SAG_METHOD, carried=carried, level=level, descent_deg=found["descent_deg"])
    if "rider_place_forward_mm" in carried:
        carried["as"] = "rider"  # the rider carried where the ride put the load: the model rides it so
        moved = _rider_moved(spec, carried["rider_place_forward_mm"])
        place, _ = moved["rider.com_mm"]
        pedals, bars = 1e3 * spec.rider.leg_x, 1e3 * spec.rider.arm_x
        if not pedals < place < bars:
            where = "past the bars" if place >= bars else "behind the pedals"
            raise RideNotDescribed(
                f"{name}: with the springs --static-sag-mm gives, the ride carried {carried['load_forward_N']:.0f} N "
                f"forward of rest: the rider would ride {place:.0f} mm from the pedals, {where} (pedals {pedals:.0f}, "
                f"bars {bars:.0f} mm), so the model cannot carry the load as the ride did there: a descent of "
                f"{carried['descent_deg']:.1f} deg carries it (--carried-as descent), or the ride does not fit this sag")
        moved = merged(over, moved)
        at_rest, riding = static_sags(bike, merged(overrides, over)), static_sags(bike, merged(overrides, moved))
        level = {e: at_rest[e] - riding[e] for e in level}
        over = moved
    return Calibration(scales, over, SAG_METHOD, carried=carried, level=level)


def _read_on_grade(bike, overrides, scales, whole, ridden, grade_percent: float) -> tuple:
    """(the load forward of rest, N, this module reads from a steady run of ``bike`` with ``ridden`` (the
    overrides ``overrides`` with each end's spring at its scale in ``scales``) at ``grade_percent`` (0:
    level ground); the run): each end's mean force over the run's travels on its steady stretch, as a
    ride's is read (:class:`_MeanForce`, ``whole`` the bike of ``overrides``)."""
    from mtbmj.bike import run as bike_run
    from mtbmj.measured import metrics as m
    from mtbmj.ride import calibrate_descent as cd

    scenario = (f"climb:grade_percent={grade_percent:.6g},length_m={cd.LENGTH_M:g},at_m={cd.AT_M:g}" if grade_percent
                else f"flat:length_m={cd.LENGTH_M + cd.AT_M:g}")
    r = bike_run.run_bike(bike, scenario, cd.SPEED_M_PER_S, overrides=ridden or None,
                          duration=(cd.AT_M + cd.SETTLE_M + cd.READ_M + 2.0) / cd.SPEED_M_PER_S)
    raw = r.raw
    k = (raw["front_axle_x_m"] >= cd.AT_M + cd.SETTLE_M) & (raw["front_axle_x_m"] <= cd.AT_M + cd.SETTLE_M + cd.READ_M)
    excess = {}
    for end, column in (("front", "front_travel_mm"), ("rear", "rear_travel_mm")):
        x_mm, sc = raw[column][k], scales[end]
        mean = _MeanForce(bike, overrides, sc.adjuster, whole, end, np.clip(x_mm, 0.0, None) * 1e-3,
                          m.velocity(raw["time_s"][k], x_mm) * 1e-3)
        excess[end] = mean(sc.value) - (whole.fF0 if end == "front" else whole.fR0)
    return 0.5 * (excess["front"] - excess["rear"]), r


def descent_for(bike, overrides, scales, load_forward_N: float, first_deg: float) -> dict:
    """The steady mean descent (deg) whose run of ``bike`` (``overrides`` the recorded ones, the rider in
    place, each end's spring at its scale in ``scales``) this module reads as ``load_forward_N`` carried
    forward, from ``first_deg``: :func:`mtbmj.ride.calibrate_descent.grade_for` on :func:`_read_on_grade`."""
    from mtbmj.ride.calibrate_descent import grade_for

    _, whole = _laws(bike, overrides)
    ridden = _springs_at(overrides, [(sc.adjuster, sc.value) for sc in scales.values()])
    return grade_for(lambda g: _read_on_grade(bike, overrides, scales, whole, ridden, g), load_forward_N, first_deg)


def calibrate(record, bike, overrides=None, duration: float | None = None, static_sag_mm=None,
              carried_as: str = "rider") -> Calibration:
    """:func:`spring_scales` of a ``TelemetryRecord`` with both ends (its first ``duration`` s), read
    as the reconstruction reads it (at ``mtbmj.ride.reconstruct.RATE_HZ``); ``static_sag_mm`` and
    ``carried_as`` as there."""
    t, front, rear = _as_read(record, duration)
    return spring_scales(t, front, rear, bike, overrides, record.name, static_sag_mm, carried_as=carried_as)


def _as_read(record, duration: float | None):
    """(t s, fork mm, rear wheel mm) of ``record``'s first ``duration`` s, read as the reconstruction reads it
    (at ``mtbmj.ride.reconstruct.RATE_HZ``)."""
    from mtbmj.ride.reconstruct import RATE_HZ

    rec = record.decimated(RATE_HZ)
    t = np.asarray(rec.time_s, float)
    keep = (t - t[0] <= duration) if duration is not None else np.ones(t.size, bool)
    return t[keep], np.asarray(rec.fork_mm, float)[keep], np.asarray(rec.rear_mm, float)[keep]


def calibrate_pooled(records, bike, overrides=None, duration: float | None = None, static_sag_mm=None,
                     carried_as: str = "rider") -> Calibration:
    """:func:`calibrate` of several rides of one setting as one ride (``mtbmj advise RIDE RIDE ...``): each
    ride read as :func:`calibrate` reads it (its first ``duration`` s), its travel speeds taken on its own
    time, and the rides joined end to end, so each end's balance is the mean force over all their samples
    (each ride weighted by its length) and the interval resamples the segments of every ride together."""
    from mtbmj.measured import metrics as m
    from mtbmj.ride.reconstruct import RATE_HZ

    ts, series, speeds, offset = [], {"front": [], "rear": []}, {"front": [], "rear": []}, 0.0
    for record in records:
        t, front, rear = _as_read(record, duration)
        for end, x in (("front", front), ("rear", rear)):
            series[end].append(x)
            speeds[end].append(m.velocity(t, x))
        ts.append(t - t[0] + offset)
        offset = float(ts[-1][-1]) + 1.0 / RATE_HZ
    cal = spring_scales(np.concatenate(ts), np.concatenate(series["front"]), np.concatenate(series["rear"]), bike,
                        overrides, f"{len(ts)} rides", static_sag_mm,
                        {end: np.concatenate(v) for end, v in speeds.items()}, carried_as)
    cal.method = f"{cal.method}; {len(ts)} rides pooled as one (each weighted by its length)"
    cal.rides = len(ts)
    return cal


__all__ = ["CARRIED_AS", "Calibration", "Scale", "descent_for", "SCALE_RANGE", "SAG_READ_MM", "Split", "calibrate", "calibrate_pooled", "merged", "sag_scales",
           "spring_adjuster", "spring_scales", "static_sags", "static_strokes"]

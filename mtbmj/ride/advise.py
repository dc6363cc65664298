"""Setup advice from a ride: candidate settings simulated over the ride's own terrain (``mtbmj advise``).

**What is simulated.** The ride is reconstructed through the bike (``mtbmj.ride.reconstruct``: its
speed from the lag between the ends, the terrain under the front wheel). The whole bike
(``mtbmj.bike.run``: MuJoCo, both ends, the pitch that couples them, the standing rider) then rides
that terrain at the ride's median speed, held by the rider's drive, once with the recorded settings
(the bike file's) and once for each candidate: every adjuster the bike's parts have, one step each
way (:func:`adjusters`), within what the part allows (an adjuster's clicks within its measured
range, a value within what any part has: ``mtbmj.config.PLAUSIBLE``). A candidate its part still
refuses (a volume spacer that would fill the air chamber, two adjusters whose summed effects leave
the measured forces) is skipped, not fatal: :func:`allowed` composes each candidate's fork and
shock before anything is simulated, and the report names every one skipped and why (``skipped``).

**What is scored** (:func:`ride_metrics`, each end in % of its own travel): static sag (standing,
the model's statics); dynamic sag (the mean travel); maximum travel and bottom-outs (within 3 mm
of full travel, as telemetry tools count them); the share of time deeper than 80 %; the time at low
and high speed (100 mm/s) and the 95th percentiles of compression and rebound speed; packing (the
95th percentile of rebound speed over that of compression: a rebound too slow to recover between
hits keeps it low); the balance of the ends (dynamic sag front less rear); the tyre-load variation
(std/mean, grip) and the rider's vertical acceleration (RMS, comfort).

**Rules** (:data:`RULES`, each a penalty that is 0 inside its window; sources as the makers' setup
guides state them (Fox, RockShox, Motion Instruments; read secondhand, not checked against the
guides' current editions), marked *assumed* where no source gives the number):

- static sag: front 20-25 % (Fox: "start at 25 %"; RockShox 10-30 %), rear 27-30 % (common on trail
  bikes); a point outside costs 1/5;
- bottom-outs: occasional is right ("an occasional bottom-out is a good thing", RockShox): more than
  ``BOTTOM_OUTS_PER_MINUTE`` per minute of ride costs (assumed), none with the maximum below 85 % of
  travel costs too (travel left unused: assumed);
- packing: rebound p95 below ``PACKING_RATIO`` of compression p95 (assumed);
- balance: the ends' dynamic sags within ``BALANCE_POINTS`` points ("front and rear should move about
  the same", Motion Instruments; the number assumed);
- grip and comfort: a small weight on the relative change of tyre-load variation and rider
  acceleration (tie-breakers, assumed).

The predicted change of every metric is the candidate's simulated value less the recorded
setting's, and the value expected on the rider's own ride (``expected``; the simulated ``to``
beside it) is the recorded value moved by that change within the metric's bounds (:func:`expected`:
a change towards a bound scaled by the room the ride has on that side, so the model's five
bottom-outs becoming four take a ride's none to none, not to -1; a count or share is never
expected below 0, a share of time never above 100 %). Its uncertainty comes from the ride itself
(``UNCERTAINTY_METHOD``: the ride's segments resampled, the model's error at the recorded setting
and the change's spread over the segments). The verdict (:func:`_judge`): a change is advised only
where it lowers the total penalty by at least ``MIN_GAIN`` and a metric of a rule it improves moves
by more than its uncertainty; "keep" only where every candidate is predicted worse beyond its
uncertainty; otherwise "inconclusive", naming why (never "keep" by default). Every setting is also
given in the rider's words (:meth:`Adjuster.setting`: lb/in at the rates sold for a coil shock,
psi, clicks where a click map exists). Any other setting can be tried on the ride beside the
recorded one (:func:`trial`, :func:`predict`; ``--try``, ``--try-set``).

**When a ride cannot support advice** (:class:`AdviseError`): shorter than ``MIN_SECONDS``, or a
stretch of it shorter than that asked for (``duration``: the minimum holds for what is analysed), its
recorded setting crashing on the reconstructed terrain (a crash the rider did not have: the terrain
or the model is wrong there), or its reconstruction's own check failed (the rear predicted worse than ``MAX_REAR_MISS_PERCENT`` % of the
travel it used, or fewer than ``MIN_CHECKED_PERCENT`` % of the samples checked).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mtbmj.errors import ConfigError, MtbmjError, RunError

SAG_WINDOW = {"front": (20.0, 25.0), "rear": (27.0, 30.0)}  # % of travel, static (sources above)
SAG_POINTS = 5.0  # % points outside the window per unit of penalty
BOTTOM_OUTS_PER_MINUTE = 2.0  # assumed: more than this is too many
UNUSED_BELOW_PERCENT = 85.0  # assumed: no bottom-out and less travel than this leaves travel unused
DEEP_PERCENT = 80.0  # the deep-travel share counts time beyond this % of travel
PACKING_RATIO = 0.6  # assumed: rebound p95 speed below this share of compression p95 is packing
BALANCE_POINTS = 10.0  # assumed: the ends' dynamic sags this close move "about the same"
GRIP_COMFORT_WEIGHT = 1.0  # penalty per relative change of tyre-load variation and rider acceleration
MIN_GAIN = 0.1  # a recommendation lowers the penalty by at least this
MIN_SECONDS = 15.0  # a ride shorter than this cannot support advice (three of the speed's 5 s windows)
MAX_REAR_MISS_PERCENT = 60.0  # the reconstruction's check: rear predicted within this % of the travel used
MIN_CHECKED_PERCENT = 10.0  # ... over at least this share of the ride
LEAD_IN_M = 3.5  # flat ground before the ride's terrain: the bike starts at rest on it
SPEED_SPLIT_MM_PER_S = 100.0  # low/high-speed threshold (as ``mtbmj telemetry``)
SEGMENT_S = 5.0  # the ride is split into segments about this long (3 to 20 of them) for its uncertainty
MIN_SEGMENTS, MAX_SEGMENTS = 3, 20
BOOTSTRAP = 2000  # resamples of the segments (seeded: the same ride gives the same answer)
UNCERTAINTY_METHOD = (
    f"the analysed ride split into equal segments of about {SEGMENT_S:g} s ({MIN_SEGMENTS}-{MAX_SEGMENTS}); every "
    f"metric measured on each segment, recorded and simulated; {BOOTSTRAP} bootstrap resamples of the segments "
    f"(seeded). The model's error on a metric: the 90th percentile of |the mean over a resample of (simulated at "
    f"the recorded setting - recorded)| (its bias and the ride's segment-to-segment spread of it). A change's "
    f"uncertainty: that error and half the 5-95 % bootstrap interval of the mean over segments of (simulated at the "
    f"setting - simulated at the recorded setting), added in quadrature; a count's at least its counting spread "
    f"(the square root of the count, at least 1); static sag (not in a ride) takes dynamic sag's error")
HEADLINE = ("front.dynamic_sag_percent", "rear.dynamic_sag_percent", "front.max_travel_percent",
            "rear.max_travel_percent", "front.bottom_outs_per_minute", "rear.bottom_outs_per_minute")  # printed
RULES = {
    "static_sag": "front 20-25 %, rear 27-30 % of travel (Fox, RockShox; rear common on trail bikes; secondhand)",
    "bottom_outs": f"occasional (RockShox): more than {BOTTOM_OUTS_PER_MINUTE:g} per minute too many, the excess over "
                   f"that rate one unit of penalty per {BOTTOM_OUTS_PER_MINUTE:g} (assumed)",
    "travel_unused": f"no bottom-out and a maximum below {UNUSED_BELOW_PERCENT:g} % of travel: travel left unused, "
                     f"one unit of penalty per 10 points (assumed)",
    "packing": f"rebound p95 speed at least {PACKING_RATIO:g} of compression p95 (assumed)",
    "balance": f"front and rear dynamic sag within {BALANCE_POINTS:g} points (Motion Instruments; number assumed)",
    "grip_comfort": "lower tyre-load variation and rider acceleration, as tie-breakers (assumed weight)",
    "authority": "a change is advised only where a metric of a rule it improves moves by more than its uncertainty "
                 "(from the ride's segments); else the answer is inconclusive: try it and record again",
}


class AdviseError(MtbmjError):
    """A ride that cannot support advice: names the ride and why."""


class RideNotDescribed(AdviseError, RunError):
    """The model cannot describe or ride this ride (its reconstruction fails its check, or the
    recorded setting crashes on it): a run error, so the refusal line carries every plausibility
    warning of the command (an implausible key is a likely cause)."""


@dataclass(frozen=True)
class Adjuster:
    """One setting of one part: ``section`` "fork.set" or "shock.set", its configuration ``key``,
    the recorded ``value`` and the two candidates (``down``, ``up``), each within the part's range."""

    end: str  # "front" / "rear" / "both"
    section: str
    key: str
    value: float
    down: float | None
    up: float | None
    label: str
    rider_key: str = ""  # the key a rider sets, in the unit the part is sold in (shock.spring_rate_lb_per_in)
    unit: str = ""  # that unit: "lb/in", "psi", "clicks", "N s/m", "spacers", "N/mm"
    per_unit: float = 1.0  # the configuration's value per unit of the rider's

    @property
    def name(self) -> str:
        return f"{self.section.split('.')[0]}:{self.key}"

    def setting(self, value) -> dict:
        """The change to ``value`` in the rider's words: the part, the adjuster, the key a rider sets
        (a bike key for the shock as sold, else the part's configuration key under its end's name:
        ``fork:KEY``, ``shock:KEY``; both taken by ``--try-set``), its unit, from and to in it."""
        return {"part": self.label.split(" ")[0], "adjuster": self.label.partition(" ")[2],
                "key": self.rider_key or self.name, "unit": self.unit,
                "from": _round(self.value / self.per_unit), "to": _round(value / self.per_unit)}

    def overrides(self, value) -> dict:
        return {self.section: {self.key: value}}


def _round(x: float) -> float:
    return float(f"{x:.4g}")


SOLD_LB_PER_IN = 25.0  # coil springs are sold in steps of this (lb/in)
UNITS = {"rate_N_per_mm": "N/mm", "rate_lb_per_in": "lb/in", "_psi": "psi", "_N_s_per_m": "N s/m", "_clicks": "clicks",
         "tokens": "spacers"}


def _unit(key: str) -> str:
    return next((u for end, u in UNITS.items() if key.endswith(end)), "")


def _bounded(key: str, value: float, low: float = 0.0, high: float = math.inf):
    from mtbmj.config import PLAUSIBLE

    lo, hi = PLAUSIBLE.get(key, (low, high))
    lo, hi = max(lo, low), min(hi, high)
    return value if lo <= value <= hi else None


def adjusters(spec) -> list[Adjuster]:
    """The adjusters of the bike's fork, shock and tyres (from their configurations in effect),
    each with one step down and up: a spring or pressure 10 %, a damper coefficient 25 %, two clicks,
    a volume token, a tyre 2 psi; a step the part does not allow is None."""
    from mtbmj.config import N_PER_MM_PER_LB_PER_IN, load

    out = []
    for end, section, cfg, over in (("front", "fork.set", spec.fork_config, spec.fork_overrides),
                                    ("rear", "shock.set", spec.shock_config, spec.shock_overrides)):
        v = load(cfg, over).values
        part = "fork" if end == "front" else "shock"

        def add(key, label, down, up, value, rider_key="", unit="", per_unit=1.0):
            out.append(Adjuster(end, section, key, value, _bounded(key, down) if down is not None else None,
                                _bounded(key, up) if up is not None else None, f"{part} {label}",
                                rider_key, unit or _unit(key), per_unit))

        spring = v.get("fork.spring.model")
        lb = N_PER_MM_PER_LB_PER_IN
        for model, key, label in (("linear", "fork.spring.rate_N_per_mm", "spring rate"),
                                  ("progressive", "fork.spring.progressive_rate_N_per_mm", "spring rate"),
                                  ("air", "fork.spring.air_pressure_psi", "air pressure")):
            if spring == model and key in v:
                x = float(v[key])
                if model == "linear" and (part == "shock" or "fork.spring.rate_lb_per_in" in over):
                    # a coil as sold: in lb/in, the candidates the rates sold next to 10 % either way
                    rider = "shock.spring_rate_lb_per_in" if part == "shock" else ""
                    given = x / lb
                    down = round(given * 0.9 / SOLD_LB_PER_IN) * SOLD_LB_PER_IN
                    up = round(given * 1.1 / SOLD_LB_PER_IN) * SOLD_LB_PER_IN
                    add(key, label, down * lb if down > 0 and abs(down - given) > 1e-6 else None,
                        up * lb if abs(up - given) > 1e-6 else None, x,
                        rider or "fork:fork.spring.rate_lb_per_in", "lb/in", lb)
                else:
                    add(key, label, round(x * 0.9, 3), round(x * 1.1, 3), x,
                        "shock.pressure_psi" if part == "shock" and model == "air" else "")
        if spring == "air" and "fork.spring.tokens" in v:
            n = float(v["fork.spring.tokens"])
            add("fork.spring.tokens", "volume spacers", n - 1 if n >= 1 else None, n + 1, n,
                "shock.volume_spacers" if part == "shock" else "")
        damper = v.get("fork.damper.model")
        keys = {"linear": [("fork.damper.coefficient_N_s_per_m", "damping")],
                "bilinear": [("fork.damper.compression_N_s_per_m", "compression damping"),
                             ("fork.damper.rebound_N_s_per_m", "rebound damping")],
                "digressive": [("fork.damper.compression_low_N_s_per_m", "low-speed compression damping"),
                               ("fork.damper.rebound_low_N_s_per_m", "low-speed rebound damping"),
                               ("fork.damper.compression_high_N_s_per_m", "high-speed compression damping"),
                               ("fork.damper.rebound_high_N_s_per_m", "high-speed rebound damping")]}.get(damper, [])
        for key, label in keys:
            x = float(v[key])
            rider = (f"shock.{key.rpartition('.')[2]}" if part == "shock" and damper == "bilinear" else "")
            add(key, label, round(x * 0.8, 3), round(x * 1.25, 3), x, rider)
        for kind in ("compression", "rebound", "low_speed_compression", "high_speed_compression",
                     "low_speed_rebound", "high_speed_rebound"):
            key, measured = f"fork.damper.{kind}_clicks", f"fork.damper.{kind}_clicks_measured"
            if damper == "clicks" and key in v and measured in v:
                # two clicks each way within the measured range (its own ends, not 0)
                n, low, top = float(v[key]), float(min(v[measured])), float(max(v[measured]))
                add(key, f"{kind.replace('_', ' ')} clicks", n - 2 if n - 2 >= low else (low if n > low else None),
                    n + 2 if n + 2 <= top else (top if n < top else None), n)
        if end == "front" and "tire.pressure_psi" in v:
            x = float(v["tire.pressure_psi"])
            out.append(Adjuster("both", "fork.set", "tire.pressure_psi", x, _bounded("tire.pressure_psi", x - 2),
                                _bounded("tire.pressure_psi", x + 2), "tyre pressure", "fork:tire.pressure_psi", "psi"))
    return out


def ride_metrics(t, front_mm, rear_mm, front_top: float, rear_top: float, static=None, loads=None,
                 rider_acc=None) -> dict:
    """The metrics riders read (see the module doc) of one ride, measured or simulated: ``front_mm``
    fork travel, ``rear_mm`` rear wheel travel (compression positive); ``static`` (front, rear)
    static travel mm when known; ``loads`` (front, rear) tyre loads N and ``rider_acc`` m/s2 when
    simulated."""
    from mtbmj.measured import metrics as m

    t = np.asarray(t, float)
    out = {}
    minutes = max(float(t[-1] - t[0]), 1e-9) / 60.0
    for end, x, top, k in (("front", front_mm, front_top, 0), ("rear", rear_mm, rear_top, 1)):
        x = np.asarray(x, float)
        v = m.velocity(t, x)
        comp, reb = v[v > 0], -v[v < 0]
        p95c = float(np.percentile(comp, 95)) if comp.size else 0.0
        p95r = float(np.percentile(reb, 95)) if reb.size else 0.0
        e = {"travel_mm": top, "dynamic_sag_percent": float(x.mean() / top * 100),
             "max_travel_percent": float(x.max() / top * 100),
             "bottom_outs": int(m.bottom_outs(x, top)),
             "bottom_outs_per_minute": float(m.bottom_outs(x, top) / minutes),
             "deep_travel_percent": float(np.mean(x > DEEP_PERCENT / 100 * top) * 100),
             "high_speed_percent": float(np.mean(np.abs(v) > SPEED_SPLIT_MM_PER_S) * 100),
             "p95_compression_mm_per_s": p95c, "p95_rebound_mm_per_s": p95r,
             "rebound_over_compression": p95r / p95c if p95c > 0 else None}
        e["low_speed_percent"] = 100.0 - e["high_speed_percent"]
        if static is not None:
            e["static_sag_percent"] = float(static[k] / top * 100)
        if loads is not None:
            f = np.asarray(loads[k], float)
            e["tyre_load_variation"] = float(f.std() / f.mean()) if f.mean() > 0 else None
        out[end] = e
    out["balance_points"] = out["front"]["dynamic_sag_percent"] - out["rear"]["dynamic_sag_percent"]
    out["duration_s"] = float(t[-1] - t[0])
    if rider_acc is not None:
        out["rider_acceleration_rms_m_per_s2"] = float(np.sqrt(np.mean(np.square(rider_acc))))
    return out


def penalties(mt: dict) -> dict:
    """Each rule's penalty (0 inside its window) of a metrics dict (:func:`ride_metrics`)."""
    p = {}
    for end in ("front", "rear"):
        e = mt[end]
        lo, hi = SAG_WINDOW[end]
        s = e.get("static_sag_percent")
        p[f"{end}_static_sag"] = 0.0 if s is None else max(lo - s, s - hi, 0.0) / SAG_POINTS
        over = e["bottom_outs_per_minute"] - BOTTOM_OUTS_PER_MINUTE
        unused = (UNUSED_BELOW_PERCENT - e["max_travel_percent"]) / 10.0 if e["bottom_outs"] == 0 else 0.0
        p[f"{end}_bottom_outs"] = max(over / BOTTOM_OUTS_PER_MINUTE, 0.0)
        p[f"{end}_travel_unused"] = max(unused, 0.0)
        r = e["rebound_over_compression"]
        p[f"{end}_packing"] = 0.0 if r is None else max(PACKING_RATIO - r, 0.0) / 0.2
    p["balance"] = max(abs(mt["balance_points"]) - BALANCE_POINTS, 0.0) / BALANCE_POINTS
    return p


def _grip_comfort(base: dict, cand: dict) -> float:
    """The relative change of tyre-load variation (both ends) and rider acceleration, weighted."""
    terms = []
    for end in ("front", "rear"):
        a, b = base[end].get("tyre_load_variation"), cand[end].get("tyre_load_variation")
        if a and b is not None:
            terms.append((b - a) / a)
    a, b = base.get("rider_acceleration_rms_m_per_s2"), cand.get("rider_acceleration_rms_m_per_s2")
    if a and b is not None:
        terms.append((b - a) / a)
    return GRIP_COMFORT_WEIGHT * float(np.mean(terms)) if terms else 0.0


SHARES = ("deep_travel_percent", "high_speed_percent", "low_speed_percent")  # shares of time: 0-100 %
SIGNED = ("balance_points",)  # may take either sign; every other metric is a count, share, speed or ratio >= 0


def bounds(metric: str) -> tuple[float, float]:
    """The range a metric (``_flat`` name) can take: a share of time 0-100 %, the balance any
    value, every other (counts, travel, speeds, ratios) 0 and up."""
    leaf = metric.rpartition(".")[2]
    if leaf in SHARES:
        return 0.0, 100.0
    return (-math.inf, math.inf) if leaf in SIGNED else (0.0, math.inf)


def expected(metric: str, recorded: float, sim_from: float, sim_to: float) -> float:
    """The value ``metric`` is expected to take on the rider's ride when the model's takes it from
    ``sim_from`` to ``sim_to`` and the ride recorded ``recorded``: the model's range mapped onto the
    ride's by the straight lines through (bound, bound) and (``sim_from``, ``recorded``) (its
    :func:`bounds`): a change towards a bound scaled by the room left on that side (the model
    halving its bottom-outs halves the ride's; the model losing all loses all), a change with no
    bound on its side added as it is. An expected value stays within the metric's bounds (never a
    negative count or share): what stays outside them (a model value past its own bound) is
    clipped to them."""
    lo, hi = bounds(metric)
    change = sim_to - sim_from
    if change == 0.0:
        value = recorded
    elif change < 0.0 and math.isfinite(lo) and sim_from > lo:
        value = lo + (recorded - lo) * (sim_to - lo) / (sim_from - lo)
    elif change > 0.0 and math.isfinite(hi) and sim_from < hi:
        value = hi - (hi - recorded) * (hi - sim_to) / (hi - sim_from)
    else:
        value = recorded + change
    return float(min(max(value, lo), hi))


def _flat(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        elif isinstance(v, (int, float)) and not isinstance(v, bool) and v is not None:
            out[f"{prefix}{k}"] = float(v)
    return out


@dataclass
class Run:
    """One simulated setting over the ride: its overrides, metrics, penalties and travel series."""

    label: str
    overrides: dict
    metrics: dict
    penalty: dict
    front_mm: np.ndarray = field(repr=False, default=None)
    rear_mm: np.ndarray = field(repr=False, default=None)
    crash: str | None = None
    time_s: np.ndarray = field(repr=False, default=None)  # ride time of the series (0 where the ride starts)

    @property
    def total(self) -> float:
        return float(sum(self.penalty.values()))


def terrain_of(rec):
    """The reconstruction's terrain with a flat lead-in (the bike starts at rest on level ground);
    where the front wheel was off the ground (a jump) the ground is unknown, and its found height
    is the wheel's flight: the straight line from take-off to landing stands in for it."""
    from mtbmj.rolling.terrain import Terrain

    ground = np.array(rec.ground, float)
    for a, b in rec.jumps:
        i, j = int(np.searchsorted(rec.t, a)), int(np.searchsorted(rec.t, b))
        i, j = max(i - 1, 0), min(j, ground.size - 1)
        if j > i + 1:
            ground[i:j + 1] = np.interp(rec.distance[i:j + 1], [rec.distance[i], rec.distance[j]], [ground[i], ground[j]])
    keep = np.concatenate(([True], np.diff(rec.distance) > 1e-9))
    x, z = rec.distance[keep], ground[keep]
    x = np.concatenate(([x[0] - LEAD_IN_M - 50.0, x[0] - 0.01], x, [x[-1] + 50.0]))
    z = np.concatenate(([z[0], z[0]], z, [z[-1]]))
    start = float(rec.distance[0] - 1.0)  # the front axle 1 m before the ride's first metre
    return Terrain(f"{rec.name} (reconstructed)", x, z, start, float(rec.distance[-1] - start), {"ride": rec.name})


def simulate(bike, overrides: dict, terrain, speed: float, duration: float, label: str, lead_s: float) -> Run:
    """The bike with ``overrides`` over ``terrain`` at ``speed``: its metrics from ``lead_s`` on."""
    from mtbmj.bike import run as bike_run

    r = bike_run.run_bike(bike, terrain, speed, duration=duration, drive="rider", overrides=overrides or None)
    raw = r.raw
    s = r.summary
    keep = raw["time_s"] >= lead_s
    if keep.sum() < 10:
        keep[:] = True
    front_top = s["ride_metrics"]["front"]["travel_max_mm"]
    rear_top = s["rear_wheel_travel_mm"]
    mt = ride_metrics(raw["time_s"][keep], raw["front_travel_mm"][keep], raw["rear_travel_mm"][keep], front_top,
                      rear_top, static=(s["static_front_travel_mm"], s["static_rear_travel_mm"]),
                      loads=(raw["front_tire_N"][keep], raw["rear_tire_N"][keep]),
                      rider_acc=raw["rider_acc_z_m_per_s2"][keep])
    crash = s["crash"]["line"] if s.get("crash") else None
    return Run(label, overrides, mt, penalties(mt), raw["front_travel_mm"][keep], raw["rear_travel_mm"][keep], crash,
               raw["time_s"][keep] - lead_s)


@dataclass
class Advice:
    ride: str
    bike: str
    reconstruction: dict
    measured: dict
    base: Run
    candidates: list  # (Adjuster, direction, value, Run)
    recommendation: dict | None
    record_front: np.ndarray = field(repr=False, default=None)
    record_rear: np.ndarray = field(repr=False, default=None)
    wall_s: float = 0.0
    skipped: list = field(default_factory=list)  # candidates the part does not allow: {key, label, ..., why}
    tries: list = field(default_factory=list)  # (Trial, Run): the settings tried on the ride
    record_t: np.ndarray = field(repr=False, default=None)  # ride time of record_front / record_rear (0 at its start)
    verdict: dict = field(default_factory=dict)  # {"answer": "change" / "inconclusive" / "keep", "why": ...}

    def tried(self) -> list:
        """Each tried setting: its label, bike file, settings as asked, penalty (and its change), crash,
        and every metric's predicted change (as a recommendation's ``changes``)."""
        return [{"label": tr.label, "bike": tr.bike, "settings": dict(tr.settings), "penalty": run.total,
                 "penalty_change": run.total - self.base.total, "crash": run.crash,
                 "changes": _changes(self.base, run, self.change_uncertainty(run), self.measured)}
                for tr, run in self.tries]

    def segments(self) -> np.ndarray:
        """The edges (s of ride time) of the segments the uncertainty resamples."""
        length = self.base.metrics["duration_s"]
        n = int(min(max(length // SEGMENT_S, MIN_SEGMENTS), MAX_SEGMENTS))
        return np.linspace(0.0, length, n + 1)

    def _per_segment(self, t, front, rear) -> list:
        ftop, rtop = self.base.metrics["front"]["travel_mm"], self.base.metrics["rear"]["travel_mm"]
        t, front, rear = np.asarray(t, float), np.asarray(front, float), np.asarray(rear, float)
        out = []
        edges = self.segments()
        for a, b in zip(edges[:-1], edges[1:]):
            k = (t >= a) & (t <= b)
            out.append(_flat(ride_metrics(t[k], front[k], rear[k], ftop, rtop)) if k.sum() >= 10 else {})
        return out

    def _segment_diffs(self, run: Run, against) -> dict:
        """Per metric: the array over segments of ``run``'s value less ``against``'s (a list of per-segment
        flat metrics), segments where either has none left out."""
        mine = self._per_segment(run.time_s, run.front_mm, run.rear_mm)
        out = {}
        for k in (mine[0] if mine else {}):
            d = [m[k] - o[k] for m, o in zip(mine, against) if k in m and k in o]
            if len(d) >= MIN_SEGMENTS - 1:
                out[k] = np.asarray(d, float)
        return out

    def _boot(self, n: int) -> np.ndarray:
        return np.random.default_rng(0).integers(0, n, size=(BOOTSTRAP, n))

    def uncertainty(self) -> dict:
        """Per metric: the model's error on this ride from its segments (``UNCERTAINTY_METHOD``); a
        count's at least its counting spread (the square root of the count, at least 1)."""
        if getattr(self, "_model_error", None) is not None:
            return dict(self._model_error)
        out = {}
        if self.record_t is not None and self.base.time_s is not None:
            rec = self._per_segment(self.record_t, self.record_front, self.record_rear)
            for k, d in self._segment_diffs(self.base, rec).items():
                out[k] = float(np.percentile(np.abs(d[self._boot(d.size)].mean(axis=1)), 90))
        else:  # no series to split (an Advice made by hand): the whole ride's one sample
            a, b = _flat(self.base.metrics), _flat(self.measured)
            out = {k: abs(a[k] - b[k]) for k in a if k in b}
        for end in ("front", "rear"):
            if f"{end}.dynamic_sag_percent" in out:
                out[f"{end}.static_sag_percent"] = out[f"{end}.dynamic_sag_percent"]
        self._floor_counts(out, self.base)
        self._model_error = dict(out)
        return out

    def _floor_counts(self, out: dict, run: Run) -> None:
        minutes = self.base.metrics["duration_s"] / 60.0
        for end in ("front", "rear"):
            n = math.sqrt(max(self.base.metrics[end]["bottom_outs"], run.metrics[end]["bottom_outs"], 1))
            out[f"{end}.bottom_outs"] = max(out.get(f"{end}.bottom_outs", 0.0), n)
            out[f"{end}.bottom_outs_per_minute"] = max(out.get(f"{end}.bottom_outs_per_minute", 0.0), n / minutes)

    def change_uncertainty(self, run: Run) -> dict:
        """Per metric: the uncertainty of ``run``'s change from the recorded setting (``UNCERTAINTY_METHOD``)."""
        model = self.uncertainty()
        out = dict(model)
        if run.time_s is not None and self.base.time_s is not None:
            base = self._per_segment(self.base.time_s, self.base.front_mm, self.base.rear_mm)
            for k, d in self._segment_diffs(run, base).items():
                lo, hi = np.percentile(d[self._boot(d.size)].mean(axis=1), [5, 95])
                out[k] = float(math.hypot(model.get(k, 0.0), (hi - lo) / 2))
            for end in ("front", "rear"):
                if f"{end}.dynamic_sag_percent" in out:
                    out[f"{end}.static_sag_percent"] = out[f"{end}.dynamic_sag_percent"]
        self._floor_counts(out, run)
        return out

    def to_dict(self) -> dict:
        cands = []
        for adj, direction, value, run in self.candidates:
            cands.append({"key": adj.name, "label": adj.label, "direction": direction, "from": adj.value, "to": value,
                          "setting": adj.setting(value),
                          "penalty": run.total, "penalty_change": run.total - self.base.total,
                          "grip_comfort": _grip_comfort(self.base.metrics, run.metrics), "crash": run.crash})
        return {"ride": self.ride, "bike": self.bike, "method": __doc__.split("\n\n")[1].replace("\n", " "),
                "rules": RULES, "reconstruction": self.reconstruction,
                "recorded_setting": {"measured": self.measured, "simulated": self.base.metrics,
                                     "penalties": self.base.penalty, "penalty": self.base.total},
                "uncertainty": self.uncertainty(), "uncertainty_method": UNCERTAINTY_METHOD,
                "verdict": self.verdict, "candidates": cands, "skipped": list(self.skipped),
                "recommendation": self.recommendation, "tried": self.tried(), "wall_time_s": self.wall_s}

    def line(self) -> str:
        rec, v = self.recommendation, self.verdict or {}
        if rec is not None and v.get("answer", "change") == "change":
            return f"{self.ride} on {self.bike}: {rec['why']}{self._skipped()}"
        return f"{self.ride} on {self.bike}: {v.get('answer', 'inconclusive')}: {v.get('why', '')}{self._skipped()}"

    def _skipped(self) -> str:
        if not self.skipped:
            return ""
        return "; skipped, not allowed by the part: " + ", ".join(
            f"{c['label']} {c['from']:g} -> {c['to']:g} ({c['why']})" for c in self.skipped)

    def figure(self):
        from matplotlib.figure import Figure

        fig = Figure(figsize=(11, 4.8), layout="constrained")
        axes = fig.subplots(1, 2)
        best = self.recommendation
        shown = best if best is not None else (self.verdict or {}).get("best_candidate")
        run = None
        if shown is not None:
            run = next((r for a, d, v, r in self.candidates if a.name == shown["key"] and d == shown["direction"]), None)
        for ax, end, rec, top in ((axes[0], "front", self.record_front, self.base.metrics["front"]["travel_mm"]),
                                  (axes[1], "rear", self.record_rear, self.base.metrics["rear"]["travel_mm"])):
            edges = np.linspace(0, 100, 21)
            series = [("recorded ride", 100 * np.asarray(rec) / top, "0.5"),
                      ("simulated, recorded setting", 100 * self.base.front_mm / top if end == "front"
                       else 100 * self.base.rear_mm / top, "C0")]
            if run is not None:
                st = shown.get("setting", {"from": shown["from"], "to": shown["to"], "unit": ""})
                series.append((f"simulated, {shown['label']} {st['from']:g} -> {st['to']:g}"
                               f"{' ' + st['unit'] if st['unit'] else ''}{'' if best is not None else ' (not advised)'}",
                               100 * (run.front_mm if end == "front" else run.rear_mm) / top, "C3"))
            for label, x, color in series:
                h, _ = np.histogram(np.clip(x, 0, 100), bins=edges)
                ax.stairs(100 * h / max(h.sum(), 1), edges, label=label, color=color, linewidth=1.6)
            ax.set(xlim=(0, 100), xlabel=f"{'fork' if end == 'front' else 'rear wheel'} travel (% of {top:.0f} mm)",
                   ylabel="time (%)", title=f"{end}: travel histogram")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8, loc="upper right")
        if best is None:
            title = (self.verdict or {}).get("answer", "inconclusive") + ": no change advised"
        else:
            st = best.get("setting", {"from": best["from"], "to": best["to"], "unit": ""})
            title = f"recommended: {best['label']} {st['from']:g} -> {st['to']:g}{' ' + st['unit'] if st['unit'] else ''}"
        fig.suptitle(f"{self.ride} on {self.bike}: " + title)
        return fig

    def png(self) -> bytes:
        from mtbmj.readout import quicklook  # the one figure writer: a "$" in a name drawn as written

        return quicklook.png(self.figure(), dpi=90)

    def headline(self) -> str:
        """The one recommended change first, in the rider's words (or the verdict and why)."""
        v, rec = self.verdict or {}, self.recommendation
        if rec is not None and v.get("answer", "change") == "change":
            st = rec["setting"]
            return (f"Recommended: {'raise' if st['to'] > st['from'] else 'lower'} the {st['part']} {st['adjuster']} "
                    f"from {st['from']:g} to {st['to']:g} {st['unit']} ({st['key']})")
        return f"{v.get('answer', 'inconclusive').capitalize()}: {v.get('why', '')}"

    def html(self, png: bytes) -> str:
        import base64
        import html as esc

        d = self.to_dict()
        rec = d["recommendation"]
        v = d["verdict"] or {}
        shown = rec if rec is not None else v.get("best_candidate")

        def metric_rows(changes, skip_still=True):
            out = []
            for k, c in sorted(changes.items()):
                if skip_still and c["change"] == 0:
                    continue
                out.append(f"<tr><td>{esc.escape(k)}</td><td>{esc.escape(metric_unit(k))}</td><td>{_num(c['recorded'])}"
                           f"</td><td>{c['from']:.3g}</td><td>{c['to']:.3g}</td><td>{c['change']:+.3g}</td>"
                           f"<td>{_num(c['uncertainty'])}</td><td>{c['expected']:.3g}</td></tr>")
            return out

        head = ("<tr><th>metric</th><th>unit</th><th>recorded</th><th>simulated now</th><th>simulated {}</th>"
                "<th>change</th><th>uncertainty (same unit)</th><th>expected on your ride</th></tr>")
        blank = "<td></td>" * 7
        if shown is not None:
            rows = metric_rows(shown["changes"])
            caption = ("the recommended change" if rec is not None else
                       "the best candidate, not advised: what it improves moves less than its uncertainty")
            rows = rows or [f"<tr><td>no metric moves at {esc.escape(shown['label'])} {shown['to']:g}</td>{blank}</tr>"]
        else:
            caption = "no change: " + v.get("answer", "")
            rows = [f"<tr><td>no candidate to show: {esc.escape(v.get('why', 'no candidate'))}</td>{blank}</tr>"]

        def cand_row(c):
            st = c["setting"]
            return (f"<tr><td>{esc.escape(c['label'])} ({esc.escape(st['key'])})</td><td>{esc.escape(st['unit'])}</td>"
                    f"<td>{st['from']:g}</td><td>{st['to']:g}</td><td>{c['penalty_change']:+.2f}</td>"
                    f"<td>{esc.escape(c['crash'] or '')}</td></tr>")

        cand = "".join(cand_row(c) for c in d["candidates"])
        skip = "".join(f"<li>{esc.escape(c['label'])} {c['setting']['from']:g} -&gt; {c['setting']['to']:g} "
                       f"{esc.escape(c['setting']['unit'])}: {esc.escape(c['why'])}</li>" for c in d["skipped"])
        if skip:
            skip = f'<h2>Skipped: not allowed by the part</h2><ul id="skipped">{skip}</ul>'
        tried = ""
        for tr in d["tried"]:
            crash = f" ({esc.escape(tr['crash'])})" if tr["crash"] else ""
            tried += (f"<h2>Tried: {esc.escape(tr['label'])}</h2><p>rule penalty (no unit) "
                      f"{d['recorded_setting']['penalty']:.2f} -&gt; {tr['penalty']:.2f}{crash}</p><table class=\"tried\">"
                      f"{head.format('tried')}{''.join(metric_rows(tr['changes'], False))}</table>")
        sim, meas, u = _flat(self.base.metrics), _flat(self.measured), d["uncertainty"]
        match = "".join(f"<tr><td>{esc.escape(k)}</td><td>{esc.escape(metric_unit(k))}</td><td>{meas[k]:.3g}</td>"
                        f"<td>{sim[k]:.3g}</td><td>{sim[k] - meas[k]:+.3g}</td><td>{_num(u.get(k))}</td></tr>"
                        for k in sorted(meas) if k in sim and k not in ("duration_s",) and not k.endswith("travel_mm"))
        rc = d["reconstruction"]["checks"]
        img = base64.b64encode(png).decode()
        return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>mtbmj advice: {esc.escape(self.ride)}</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}table{{border-collapse:collapse}}
td,th{{border:1px solid #bbb;padding:2px 6px;text-align:right}}td:first-child{{text-align:left}}</style></head>
<body><h1>Setup advice: {esc.escape(self.ride)} on {esc.escape(self.bike)}</h1>
<p id="recommended"><b>{esc.escape(self.headline())}</b></p>
<p id="line">{esc.escape(self.line())}</p>
<p>Reconstruction check: front reproduced within {rc['front_reproduced_rms_mm']:.2f} mm RMS, rear predicted
{rc['rear_predicted_rms_mm']:.1f} mm RMS ({rc['rear_predicted_rms_percent_of_used']:.0f} % of the travel used),
{rc['samples_checked_percent']:.0f} % of the ride checked; speed {d['reconstruction']['speed_m_per_s']:.2f} m/s.</p>
<img id="histograms" src="data:image/png;base64,{img}" alt="travel histograms before and after">
<h2>Predicted change of every metric: {esc.escape(caption)}</h2>
<table id="changes">{head.format('after')}
{''.join(rows)}</table>
<h2>How well the model matched the ride (recorded setting)</h2>
<p>Uncertainty: {esc.escape(d['uncertainty_method'])}.</p>
<table id="match"><tr><th>metric</th><th>unit</th><th>recorded</th><th>simulated</th><th>simulated - recorded</th>
<th>model's error (same unit)</th></tr>{match}</table>
<h2>Every candidate</h2>
<table id="candidates"><tr><th>setting (key)</th><th>unit</th><th>from</th><th>to</th><th>rule penalty change (no unit)</th>
<th>crash</th></tr>{cand}</table>
{skip}
{tried}
<h2>Rules</h2><ul>{''.join(f'<li>{esc.escape(k)}: {esc.escape(v)}</li>' for k, v in RULES.items())}</ul>
</body></html>
"""

    def write(self, out_dir) -> list:
        import json

        from mtbmj import output

        png = self.png()
        return output.write_atomically(out_dir, {
            "advice.json": (json.dumps(self.to_dict(), indent=2, default=_json) + "\n").encode(),
            "advice.png": png, "advice.html": self.html(png).encode()})


def metric_unit(metric: str) -> str:
    """The unit of a metric (``_flat`` name), as the report's tables show it."""
    leaf = metric.rpartition(".")[2]
    if leaf in SHARES:
        return "% of time"
    for end, unit in (("_percent", "% of travel"), ("_per_minute", "per minute"), ("_mm_per_s", "mm/s"),
                      ("_m_per_s2", "m/s2"), ("_mm", "mm"), ("_s", "s")):
        if leaf.endswith(end):
            return unit
    return {"bottom_outs": "count", "rebound_over_compression": "ratio", "tyre_load_variation": "std/mean",
            "balance_points": "points of travel %"}.get(leaf, "")


def _num(x, spec: str = ".3g") -> str:
    return "" if x is None else format(x, spec)


def _json(o):
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(type(o).__name__)


RULE_METRICS = {"static_sag": "static_sag_percent", "bottom_outs": "bottom_outs_per_minute",
                "travel_unused": "max_travel_percent", "packing": "rebound_over_compression"}


def _rule_metric(rule: str) -> str:
    """The metric (``_flat`` name) a penalty ``rule`` (``front_static_sag``, ``balance``) reads."""
    if rule == "balance":
        return "balance_points"
    end, _, name = rule.partition("_")
    return f"{end}.{RULE_METRICS[name]}"


def _beyond(rules, a: dict, b: dict, u: dict) -> list:
    """The metrics of ``rules`` (penalty names) that move from ``a`` to ``b`` by more than their
    uncertainty ``u`` (a metric without one never does)."""
    return [m for m in dict.fromkeys(_rule_metric(k) for k in rules)
            if m in a and m in b and abs(b[m] - a[m]) > u.get(m, math.inf)]


def _judge(advice) -> tuple[dict | None, dict]:
    """(the recommendation or None, the verdict ``{"answer", "why"}``): a change is advised only where
    it lowers the penalty by ``MIN_GAIN`` or more and a metric of a rule it improves moves by more
    than that change's uncertainty (the best such candidate, grip and comfort breaking ties);
    "keep" only where every candidate is predicted worse beyond its uncertainty (a crash is worse);
    otherwise "inconclusive", naming why."""
    base, measured = advice.base, advice.measured
    a = _flat(base.metrics)
    good, worse, near = [], 0, None
    for adj, direction, value, run in advice.candidates:
        if run.crash:
            worse += 1
            continue
        u = advice.change_uncertainty(run)
        b = _flat(run.metrics)
        gain = base.total - run.total
        improved = [k for k in base.penalty if run.penalty[k] < base.penalty[k] - 1e-9]
        worsened = [k for k in base.penalty if run.penalty[k] > base.penalty[k] + 1e-9]
        score = gain - _grip_comfort(base.metrics, run.metrics)
        if gain >= MIN_GAIN and _beyond(improved, a, b, u):
            good.append((score, adj, direction, value, run, improved, u))
        elif gain <= -MIN_GAIN and _beyond(worsened, a, b, u):
            worse += 1
        elif gain >= MIN_GAIN and (near is None or score > near[0]):
            near = (score, adj, direction, value, run, improved, u)
    n = len(advice.candidates)
    if good:
        _, adj, direction, value, run, improved, u = max(good, key=lambda g: g[0])
        moved = _beyond(improved, a, _flat(run.metrics), u)
        st = adj.setting(value)
        why = (f"{'raise' if direction == 'up' else 'lower'} the {adj.label} from {st['from']:g} to {st['to']:g} "
               f"{st['unit']} ({st['key']}): the penalty falls {base.total:.2f} -> {run.total:.2f} "
               f"({', '.join(k.replace('_', ' ') for k in improved)}; "
               + ", ".join(f"{m} {a[m]:.3g} -> {_flat(run.metrics)[m]:.3g} +- {u[m]:.2g}" for m in moved) + ")")
        rec = {"setting": adj.setting(value), "key": adj.name, "section": adj.section, "config_key": adj.key,
               "label": adj.label,
               "direction": direction, "from": adj.value, "to": value, "penalty_from": base.total,
               "penalty_to": run.total, "improves": improved, "confident": True, "why": why,
               "changes": _changes(base, run, u, measured)}
        return rec, {"answer": "change", "why": why}
    if n and worse == n:
        return None, {"answer": "keep", "why": f"every one of the {n} candidates is predicted worse beyond its "
                                               f"uncertainty (or crashes)"}
    if not n:
        return None, {"answer": "inconclusive", "why": "no candidate was simulated"}
    if near is not None:
        _, adj, direction, value, run, improved, u = near
        b = _flat(run.metrics)
        ms = list(dict.fromkeys(_rule_metric(k) for k in improved))
        return None, {"answer": "inconclusive",
                      "why": f"the best candidate, the {adj.label} {adj.setting(value)['from']:g} -> "
                             f"{adj.setting(value)['to']:g} {adj.unit}, lowers the penalty "
                             f"{base.total:.2f} -> {run.total:.2f}, but what it improves moves less than its "
                             f"uncertainty ("
                             + ", ".join(f"{m} {a[m]:.3g} -> {b[m]:.3g} +- {u.get(m, math.inf):.2g}" for m in ms if m in b)
                             + "): try it and record again",
                      "best_candidate": {"setting": adj.setting(value), "key": adj.name, "section": adj.section,
                                         "config_key": adj.key, "label": adj.label, "direction": direction,
                                         "from": adj.value, "to": value, "changes": _changes(base, run, u, measured)}}
    return None, {"answer": "inconclusive",
                  "why": f"no candidate of {n} lowers the penalty by {MIN_GAIN:g} or more beyond its uncertainty, "
                         f"and {n - worse} of them are not predicted worse beyond it either: the ride cannot tell "
                         f"these settings apart"}


def _changes(base: Run, run: Run, uncertainty: dict, measured: dict) -> dict:
    """Per metric (``_flat`` name): the simulated value at the recorded setting (``from``) and at
    ``run``'s (``to``), the change, its uncertainty, the recorded value and the one expected on the
    rider's ride (:func:`expected`)."""
    a, b, rode = _flat(base.metrics), _flat(run.metrics), _flat(measured)
    return {k: {"from": v0, "to": b[k], "change": b[k] - v0, "uncertainty": uncertainty.get(k),
                "recorded": rode.get(k), "expected": expected(k, rode[k], v0, b[k]) if k in rode else b[k]}
            for k, v0 in a.items() if k in b}


def _skip(adj: Adjuster, direction: str, value, exc) -> dict:
    return {"key": adj.name, "label": adj.label, "direction": direction, "from": adj.value, "to": value,
            "setting": adj.setting(value), "why": str(exc)}


@dataclass(frozen=True)
class Trial:
    """A setting tried on the ride (``mtbmj advise --try FILE --try-set KEY=VALUE``): the bike file
    ``bike`` with ``overrides`` (the keys of :func:`mtbmj.bike.spec.load`), its ``label`` and the
    ``settings`` as asked (``KEY: value``)."""

    label: str
    bike: str
    overrides: dict
    settings: dict


def _compose(bike, overrides) -> list[str]:
    """Load and compose ``bike`` with ``overrides`` as a run would; the plausibility warnings it gives."""
    import warnings

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod
    from mtbmj.errors import ConfigWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bike_run.setups(spec_mod.load(str(bike), overrides or None))
    return [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)]


def trial(bike, overrides=None, other=None, sets=()) -> Trial:
    """A setting to try on the ride, checked before any work: ``other`` (a bike file or preset: the
    bike as that file sets it, the recorded ``overrides`` not carried) or else the recorded
    ``bike`` with its ``overrides``, and over it ``sets``, ``(KEY, value)`` pairs: ``fork:KEY`` /
    ``shock:KEY`` a key of the fork's / shock's configuration in effect (``fork:fork.spring.rate_N_per_mm``,
    ``shock:fork.damper.rebound_clicks``: the names of :attr:`Adjuster.name`), or a bike key
    ``SECTION.KEY`` (``rider.mass_kg``, ``shock.spring_rate_lb_per_in``, ``shock.pressure_psi``).
    Refused (``ConfigError``, naming ``--try``/``--try-set`` and the key): a file that does not
    load, a key the bike's part has not, a value the part refuses, or a value far outside what any
    part has (a plausibility warning the recorded bike does not already give: the advice's
    candidates stay within that range, and so does what it predicts)."""
    from pathlib import Path

    from mtbmj.bike import spec as spec_mod
    from mtbmj.config import ALTERNATIVES, load

    if other is not None:
        ref, over, what = str(other), {}, f"--try {other}"
        if not Path(ref).exists() and ref not in spec_mod.preset_names():
            raise ConfigError(f"--try {other}: no such bike file (nor a preset: {', '.join(spec_mod.preset_names())})")
    else:
        ref, over, what = str(bike), dict(overrides or {}), "--try-set"
    try:
        spec = spec_mod.load(ref, over or None)
    except ConfigError as exc:
        raise ConfigError(f"{what}: {exc}") from None
    settings = {}
    over = {k: (dict(v) if isinstance(v, dict) else v) for k, v in over.items()}
    for key, value in sets:
        key = str(key)
        settings[key] = value
        part, colon, name = key.partition(":")
        named = next((a for a in adjusters(spec) if a.rider_key == key), None)
        if named is not None and not colon:  # a key the advice names: set as its candidates are (a coil's
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ConfigError(f"--try-set {key}: must be a number, got {value!r}")
            over.setdefault(named.section, {})[named.key] = value * named.per_unit  # rate, its preload kept)
        elif colon:
            if part not in ("fork", "shock") or not name:
                raise ConfigError(f"--try-set {key}: a part's key is fork:KEY or shock:KEY (e.g. "
                                  f"fork:fork.spring.rate_N_per_mm), a bike key SECTION.KEY (e.g. rider.mass_kg)")
            cfg, cover = ((spec.fork_config, spec.fork_overrides) if part == "fork"
                          else (spec.shock_config, spec.shock_overrides))
            have = load(cfg, cover).values
            canonical = ALTERNATIVES.get(name, (name, 1.0))[0]
            if canonical not in have:
                raise ConfigError(f"--try-set {key}: the bike's {part} has no {name} (its adjusters: "
                                  f"{', '.join(a.name for a in adjusters(spec) if a.section == part + '.set') or 'none'})")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ConfigError(f"--try-set {key}: must be a number, got {value!r}")
            over.setdefault(f"{part}.set", {})[name] = value
        else:
            over[key] = value
    if not sets and other is None:
        raise ConfigError("--try-set: nothing to try (give --try FILE or --try-set KEY=VALUE)")
    try:
        base_notes = set(_compose(ref, {k: v for k, v in (overrides or {}).items()} if other is None else None))
    except ConfigError as exc:
        raise ConfigError(f"{what}: {exc}") from None
    try:
        notes = _compose(ref, over)
    except ConfigError as exc:
        raise ConfigError(f"{what}{' ' + ', '.join(f'{k}={v}' for k, v in settings.items()) if settings else ''}: "
                          f"{exc}") from None
    new = [n for n in notes if n not in base_notes]
    if new and settings:
        raise ConfigError(f"--try-set {', '.join(f'{k}={v}' for k, v in settings.items())}: {new[0]} (advise "
                          f"predicts only within what parts have)")
    label = (Path(ref).name if other is not None else "recorded setting") + (
        (" with " if other is not None else ": ") + ", ".join(f"{k} = {v}" for k, v in settings.items())
        if settings else "")
    return Trial(label, ref, over, settings)


def allowed(bike, candidates, merged) -> tuple[list, list]:
    """(the candidates ``(adjuster, direction, value)`` the part allows, the others as dicts naming
    why): each candidate's bike (``merged(adjuster.overrides(value))``, the recorded overrides with
    the candidate's over them) loaded and its fork and shock composed, as its run would; one the
    part refuses (a click outside the measured range, a volume spacer that fills the air chamber,
    two adjusters whose summed effects leave the measured forces) is skipped, not fatal. Nothing is
    simulated here."""
    import warnings

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod

    ok, skipped = [], []
    for a, d, v in candidates:
        try:
            with warnings.catch_warnings():  # the recorded setting's warnings were issued once already
                warnings.simplefilter("ignore")
                bike_run.setups(spec_mod.load(str(bike), merged(a.overrides(v))))
        except ConfigError as exc:
            skipped.append(_skip(a, d, v, exc))
        else:
            ok.append((a, d, v))
    return ok, skipped


def advise(record, bike, overrides=None, duration: float | None = None, progress=None, workers: int = 2,
           tries=(), candidates: bool = True) -> Advice:
    """Advice for ``record`` (a two-ended ``TelemetryRecord``) on ``bike`` (preset or file, its keys
    ``overrides``); ``duration`` limits the simulated ride to its first seconds; the runs spread
    over ``workers`` processes. ``tries``: settings to try (:class:`Trial`, from :func:`trial`),
    simulated over the same terrain beside the recorded setting and predicted as the candidates are
    (``Advice.tries``); ``candidates`` False simulates the tried settings only (:func:`predict`)."""
    import time

    from mtbmj.bike import spec as spec_mod
    from mtbmj.ride import reconstruct as rc

    start = time.perf_counter()
    length = float(record.time_s[-1] - record.time_s[0])
    if length < MIN_SECONDS:
        raise AdviseError(f"{record.name}: {length:.1f} s of ride cannot support advice (at least {MIN_SECONDS:g} s)")
    # the minimum holds for the stretch analysed, not only for the file it is cut from
    if duration is not None:
        duration = float(duration)
        if not (math.isfinite(duration) and duration > 0.0):
            raise AdviseError(f"--duration: must be a positive number of seconds, got {duration:g}")
        if duration < MIN_SECONDS:
            raise AdviseError(f"--duration: {duration:g} s of {record.name} cannot support advice (at least "
                              f"{MIN_SECONDS:g} s; the ride is {length:.1f} s)")
    rec = rc.reconstruct(record, bike, overrides)
    checks = rec.checks()
    if (checks["samples_checked_percent"] < MIN_CHECKED_PERCENT
            or not checks["rear_predicted_rms_percent_of_used"] <= MAX_REAR_MISS_PERCENT):
        raise RideNotDescribed(f"{record.name}: its reconstruction fails its own check (rear predicted within "
                               f"{checks['rear_predicted_rms_percent_of_used']:.0f} % of the travel used, "
                               f"{checks['samples_checked_percent']:.0f} % of the ride checked; advice needs within "
                               f"{MAX_REAR_MISS_PERCENT:g} % over {MIN_CHECKED_PERCENT:g} %): the model does not "
                               f"describe this ride well enough to predict a change")
    if not checks.get("passes", True):  # the rear predicted no better than a naive baseline (issue 51)
        raise RideNotDescribed(f"{record.name}: its reconstruction fails its own check: {checks['verdict']}; advice "
                               f"needs a model that beats both naive baselines, so it cannot predict a change")
    spec = spec_mod.load(str(bike), overrides)
    speed = float(rec.speed["speed_m_per_s"])
    ride_s = length if duration is None else min(length, float(duration))
    lead_s = 1.0 / speed  # the front axle reaches the ride's first metre
    sim_s = ride_s + lead_s
    terrain = terrain_of(rec)
    adj = adjusters(spec)
    base_over = dict(overrides or {})

    def merged(extra):
        out = dict(base_over)
        for k, v in extra.items():
            out[k] = {**out.get(k, {}), **v}
        return out

    tries = list(tries or ())
    todo, skipped = allowed(bike, [(a, d, v) for a in adj for d, v in (("down", a.down), ("up", a.up))
                                   if v is not None and v != a.value] if candidates else [], merged)
    n = len(todo) + len(tries) + 1
    done = [0]

    def step():
        done[0] += 1
        if progress is not None:
            progress(done[0] / n)

    jobs = [(str(bike), base_over, terrain, speed, sim_s, "recorded setting", lead_s)]
    jobs += [(str(bike), merged(a.overrides(v)), terrain, speed, sim_s, f"{a.label} {v:g}", lead_s) for a, d, v in todo]
    jobs += [(tr.bike, tr.overrides, terrain, speed, sim_s, tr.label, lead_s) for tr in tries]
    runs = [None] * len(jobs)
    if workers > 1 and len(jobs) > 1:
        from concurrent.futures import as_completed

        from mtbmj.workers import process_pool

        with process_pool(min(workers, len(jobs))) as pool:
            futures = {pool.submit(simulate, *job): i for i, job in enumerate(jobs)}
            for future in as_completed(futures):
                i = futures[future]
                try:
                    runs[i] = future.result()
                except ConfigError as exc:  # a candidate its part refuses only when run: skipped (the recorded
                    if i == 0 or i > len(todo):  # setting's own refusal and a tried one's stay the user's error)
                        raise
                    runs[i] = exc
                step()
    else:
        for i, job in enumerate(jobs):
            try:
                runs[i] = simulate(*job)
            except ConfigError as exc:
                if i == 0 or i > len(todo):
                    raise
                runs[i] = exc
            step()
    base = runs[0]
    if base.crash:
        raise RideNotDescribed(f"{record.name}: the recorded setting {base.crash} on the ride's reconstructed terrain: "
                               f"the model cannot ride this ride as reconstructed, so it cannot predict a change")
    cands = []
    for (a, d, v), run in zip(todo, runs[1:1 + len(todo)]):
        if isinstance(run, ConfigError):
            skipped.append(_skip(a, d, v, run))
        else:
            cands.append((a, d, v, run))
    t = rec.t
    keep = t - t[0] <= ride_s
    measured = ride_metrics(t[keep], rec.front[keep], rec.rear[keep], base.metrics["front"]["travel_mm"],
                            base.metrics["rear"]["travel_mm"])
    advice = Advice(rec.name, spec.name, rec.summary(), measured, base, cands, None, rec.front[keep], rec.rear[keep],
                    skipped=skipped, tries=list(zip(tries, runs[1 + len(todo):])), record_t=t[keep] - t[0])
    advice.recommendation, advice.verdict = _judge(advice)
    advice.wall_s = time.perf_counter() - start
    return advice


def predict(record, bike, tries, overrides=None, duration: float | None = None, progress=None,
            workers: int = 2) -> Advice:
    """The ride's metrics at each tried setting (:func:`trial`) beside the recorded setting's, with
    the advice's reconstruction and uncertainty, no candidate simulated: ``Advice.tried()``."""
    return advise(record, bike, overrides, duration, progress, workers, tries=tries, candidates=False)


__all__ = ["Adjuster", "Advice", "AdviseError", "RideNotDescribed", "RULES", "Trial", "adjusters", "advise", "allowed",
           "bounds", "expected", "penalties", "predict", "ride_metrics", "simulate", "terrain_of", "trial"]

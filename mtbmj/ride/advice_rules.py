"""What advice measures and judges a ride by, and what it may change: the rider metrics of a ride
or a run (:func:`ride_metrics`), the rules' windows and their penalties (:data:`RULES`,
:func:`penalties`; sources in ``mtbmj.ride.advise``'s module text) and what they are scored on (the
ride expected at a setting: :func:`on_the_ride`), each metric's bounds and the
value expected on the ride at another setting (:func:`bounds`, :func:`expected`), and the bike's
adjusters in the rider's words (:class:`Adjuster`, :func:`adjusters`) and a setting tried on a ride
(:func:`trial`). The search, the verdict and
the report are ``mtbmj.ride.advise``'s."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mtbmj.errors import ConfigError, MtbmjError, RunError

SAG_WINDOW = {"front": (20.0, 25.0), "rear": (27.0, 30.0)}  # % of travel, static (sources above)
SAG_POINTS = 5.0  # % points outside the window per unit of penalty
BOTTOM_OUTS_PER_MINUTE = 2.0  # assumed: more than this is too many
UNUSED_BELOW_PERCENT = 85.0  # assumed: no bottom-out and less travel than this leaves travel unused ...
UNUSED_SHARE = 0.8  # assumed: ... where it is also less than this share of the other end's maximum on the ride
DEEP_PERCENT = 80.0  # the deep-travel share counts time beyond this % of travel
PACKING_SHARE = 0.8  # assumed: an end whose rebound-over-compression is below this share of the other end's packs
PACKING_FLOOR = 0.4  # assumed: rebound p95 below this share of compression p95 packs whatever the other end does
POGO_SHARE = 1.0 / PACKING_SHARE  # an end whose rebound-over-compression is above this multiple of the other end's pogoes
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
    "travel_unused": f"no bottom-out and a maximum below {UNUSED_BELOW_PERCENT:g} % of travel and below "
                     f"{UNUSED_SHARE:g} of the other end's maximum on the ride as recorded (the same terrain: a trail "
                     f"whose hits take neither end deep asks for no more travel; assumed): travel left unused, one "
                     f"unit of penalty per 10 points short of the lower (assumed)",
    "packing": f"each end's rebound p95 speed over its compression p95 at least {PACKING_SHARE:g} of the other end's, "
               f"on the ride as recorded, the same terrain (front and rear rebound about the same: Motion Instruments' balance, read "
               f"secondhand; number assumed), and at least {PACKING_FLOOR:g} whatever the other end does (assumed); "
               f"one unit of penalty per 0.2 short of the stricter",
    "pogo": f"a change leaves each end's rebound p95 speed over its compression p95 at most {POGO_SHARE:g} of the other "
            f"end's on the ride as recorded, or the end's own there where that is more (the packing rule's other side: "
            f"rebound 'about the same' at both ends, between pogo and packing, ShockWiz's 'Goldilocks Rebound', read "
            f"secondhand; the number the packing rule's inverse, assumed; the ride's own imbalance is packing's, which "
            f"blames the slower end); one unit of penalty per 0.2 over",
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
                "from": round_setting(self.value / self.per_unit), "to": round_setting(value / self.per_unit)}

    def overrides(self, value) -> dict:
        return {self.section: {self.key: value}}


def round_setting(x: float) -> float:
    return float(f"{x:.4g}")


SOLD_LB_PER_IN = 25.0  # coil springs are sold in steps of this (lb/in)
UNITS = {"rate_N_per_mm": "N/mm", "rate_lb_per_in": "lb/in", "_psi": "psi", "_N_s_per_m": "N s/m", "_clicks": "clicks",
         "tokens": "spacers"}


def unit_of(key: str) -> str:
    return next((u for end, u in UNITS.items() if key.endswith(end)), "")


def bounded_value(key: str, value: float, low: float = 0.0, high: float = math.inf):
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
            out.append(Adjuster(end, section, key, value, bounded_value(key, down) if down is not None else None,
                                bounded_value(key, up) if up is not None else None, f"{part} {label}",
                                rider_key, unit or unit_of(key), per_unit))

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
            out.append(Adjuster("both", "fork.set", "tire.pressure_psi", x, bounded_value("tire.pressure_psi", x - 2),
                                bounded_value("tire.pressure_psi", x + 2), "tyre pressure", "fork:tire.pressure_psi", "psi"))
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


def penalties(mt: dict, terrain: dict | None = None) -> dict:
    """Each rule's penalty (0 inside its window) of a metrics dict (:func:`ride_metrics`). ``terrain``:
    the metrics of the ride as recorded, whose ends read the terrain for the packing, pogo and the
    travel-unused rules (each end's rebound-over-compression against the other end's there, and its
    maximum travel against the other end's: a setting tried does not change the terrain, so slowing
    or stiffening the other end mends neither); default ``mt`` itself. The travel one end is asked to
    use is ``UNUSED_BELOW_PERCENT`` of its travel, or ``UNUSED_SHARE`` of the other end's maximum
    where that is less: a smooth trail whose hits take the other end to 73 % asks for 58 %, not 85. Pogo
    bounds a change (an end sped past ``POGO_SHARE`` of the other end's ratio there, and past its own):
    the ride's own imbalance is packing's, read at the slower end."""
    terrain = mt if terrain is None else terrain
    p = {}
    for end in ("front", "rear"):
        e = mt[end]
        lo, hi = SAG_WINDOW[end]
        s = e.get("static_sag_percent")
        p[f"{end}_static_sag"] = 0.0 if s is None else max(lo - s, s - hi, 0.0) / SAG_POINTS
        over = e["bottom_outs_per_minute"] - BOTTOM_OUTS_PER_MINUTE
        other = terrain["rear" if end == "front" else "front"]  # the same terrain's hits, through the other end
        asked = min(UNUSED_BELOW_PERCENT, UNUSED_SHARE * other["max_travel_percent"])
        unused = (asked - e["max_travel_percent"]) / 10.0 if e["bottom_outs"] == 0 else 0.0
        p[f"{end}_bottom_outs"] = max(over / BOTTOM_OUTS_PER_MINUTE, 0.0)
        p[f"{end}_travel_unused"] = max(unused, 0.0)
        r, o = e["rebound_over_compression"], terrain["rear" if end == "front" else "front"]["rebound_over_compression"]
        short = 0.0 if r is None else max(PACKING_FLOOR - r, PACKING_SHARE - r / o if o else 0.0, 0.0)
        p[f"{end}_packing"] = short / 0.2  # the terrain sets compression speeds: the other end reads it too
        # too fast, it kicks: above POGO_SHARE of the other end's, and above its own on the ride as recorded (the
        # bound of a change: packing reads the ride's own imbalance and blames the slower end, not both ends)
        own = terrain[end]["rebound_over_compression"]
        p[f"{end}_pogo"] = 0.0 if r is None or not o else max(r / o - max(POGO_SHARE, (own or 0.0) / o), 0.0) / 0.2
    p["balance"] = max(abs(mt["balance_points"]) - BALANCE_POINTS, 0.0) / BALANCE_POINTS
    return p


RULE_METRICS = {"static_sag": "static_sag_percent", "bottom_outs": "bottom_outs_per_minute",
                "travel_unused": "max_travel_percent", "packing": "rebound_over_compression",
                "pogo": "rebound_over_compression"}


def rule_metric(rule: str) -> str:
    """The metric (``flat_metrics`` name) a penalty ``rule`` (``front_static_sag``, ``balance``) reads."""
    if rule == "balance":
        return "balance_points"
    end, _, name = rule.partition("_")
    return f"{end}.{RULE_METRICS[name]}"


def beyond(rules, a: dict, b: dict, u: dict) -> list:
    """The metrics of ``rules`` (penalty names) that move from ``a`` to ``b`` by more than their
    uncertainty ``u`` (a metric without one never does)."""
    return [m for m in dict.fromkeys(rule_metric(k) for k in rules)
            if m in a and m in b and abs(b[m] - a[m]) > u.get(m, math.inf)]


def grip_comfort(base: dict, cand: dict) -> float:
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
    """The range a metric (``flat_metrics`` name) can take: a share of time 0-100 %, the balance any
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


def on_the_ride(recorded: dict, sim_from: dict, sim_to: dict) -> dict:
    """The metrics (:func:`ride_metrics`' shape) the rider's own ride is expected to show at a setting
    the model rides as ``sim_to`` where it rides the recorded setting as ``sim_from`` and the ride
    recorded ``recorded``: every metric the ride records its :func:`expected` value (the recorded
    value moved by the model's predicted change, within its bounds; at the recorded setting the
    recorded value itself), every other (static sag, tyre loads, the rider's acceleration: no ride
    records them) the model's. The rules are scored on these (``mtbmj.ride.advise.Advice.score``): they
    judge the bike as ridden and the change the model predicts, not the model's own bias (its
    bottom-outs where the ride had none)."""
    out = {}
    for key, value in sim_to.items():
        if isinstance(value, dict):
            rec, frm = recorded.get(key) or {}, sim_from.get(key) or {}
            out[key] = {k: (expected(f"{key}.{k}", rec[k], frm[k], v)
                            if k != "travel_mm" and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                        for x in (rec.get(k), frm.get(k), v)) else v)
                        for k, v in value.items()}
        elif key == "balance_points" and all(isinstance(x, (int, float)) for x in
                                             (recorded.get(key), sim_from.get(key), value)):
            out[key] = expected(key, recorded[key], sim_from[key], value)
        else:
            out[key] = value
    return out


def flat_metrics(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(flat_metrics(v, f"{prefix}{k}."))
        elif isinstance(v, (int, float)) and not isinstance(v, bool) and v is not None:
            out[f"{prefix}{k}"] = float(v)
    return out


@dataclass(frozen=True)
class Trial:
    """A setting tried on the ride (``mtbmj advise --try FILE --try-set KEY=VALUE``): the bike file
    ``bike`` with ``overrides`` (the keys of :func:`mtbmj.bike.spec.load`), its ``label`` and the
    ``settings`` as asked (``KEY: value``); ``resolved``: that file resolved once
    (:class:`mtbmj.bike.spec.ResolvedBike`), what its run takes."""

    label: str
    bike: str
    overrides: dict
    settings: dict
    resolved: object = field(default=None, repr=False, compare=False)  # the file resolved (mtbmj.bike.spec.ResolvedBike)


def compose_setting(bike, overrides) -> list[str]:
    """Load and compose ``bike`` with ``overrides`` as a run would; the plausibility warnings it gives."""
    import warnings

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod
    from mtbmj.errors import ConfigWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bike_run.setups(spec_mod.load(bike, overrides or None))
    return [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)]


def _read_by_model(key: str, config, overrides: dict, canonical: str) -> None:
    """Refuse ``--try-set key`` when the part's model (``config`` with ``overrides``, the tried value
    among them) does not read ``canonical``: the try would predict the recorded setting again (as
    ``--fork-set`` refuses it, ``mtbmj.compose``). Any other refusal (a value the part refuses) is
    left to the whole bike's composition after, which names the try."""
    import dataclasses

    from mtbmj import compose
    from mtbmj.config import load

    try:
        compose.setup(dataclasses.replace(load(config, overrides), given=frozenset({canonical})))
    except compose.NotRead as exc:
        raise ConfigError(f"--try-set {key}: {exc}") from None
    except ConfigError:
        pass


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
    from mtbmj.config import ALTERNATIVES, load, unit_keys

    if other is not None:
        ref, over, what = str(other), {}, f"--try {other}"
        if not Path(ref).exists() and ref not in spec_mod.preset_names():
            from mtbmj.textfile import other_case

            raise ConfigError(f"--try {other}: no such bike file{other_case(Path(ref))} (nor a preset: "
                              f"{', '.join(spec_mod.preset_names())})")
    else:  # the recorded bike: a ResolvedBike is not read again
        ref, over, what = getattr(bike, "source", None) or str(bike), dict(overrides or {}), "--try-set"
    try:
        file = spec_mod.resolve(ref if other is not None else bike)  # the file as read, each setting over it
        file = file.with_overrides(None) if file.overrides else file
        spec = spec_mod.load(file, over)
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
            # set under the part's own key (lb/in as the shock configuration's N/mm, whose range is not the bike
            # key's): the bike key's range checked here, unless the recorded setting is outside it too
            from mtbmj.bike.keys import warnings as odd

            section, _, bare = key.partition(".")
            lines = odd({section: {bare: value}})
            if lines and not odd({section: {bare: named.value / named.per_unit}}):
                raise ConfigError(f"--try-set {key}={value:g}: {lines[0]} (advise predicts only within what parts have)")
            over.setdefault(named.section, {})[named.key] = value * named.per_unit  # rate, its preload kept)
        elif colon:
            if part not in ("fork", "shock") or not name:
                raise ConfigError(f"--try-set {key}: a part's key is fork:KEY or shock:KEY (e.g. "
                                  f"fork:fork.spring.rate_N_per_mm), a bike key SECTION.KEY (e.g. rider.mass_kg)")
            cfg, cover = ((spec.fork_config, spec.fork_overrides) if part == "fork"
                          else (spec.shock_config, spec.shock_overrides))
            have = load(cfg, cover).values
            canonical = ALTERNATIVES.get(name, (name, 1.0))[0]
            if canonical not in have:  # the keys nearest the one typed, else the adjusters the advice tries
                import difflib

                near = unit_keys(name, sorted(have))  # fork.spring.psi: the keys in psi the part has, else
                near = difflib.get_close_matches(name, sorted(have), n=3) if near is None else near  # the nearest
                raise ConfigError(f"--try-set {key}: the bike's {part} has no {name} (" + (
                    f"did you mean {' or '.join(part + ':' + k for k in near)}?" if near else "the adjusters the advice "
                    f"tries: {', '.join(a.name for a in adjusters(spec) if a.section == part + '.set') or 'none'}; "
                    f"any key of the {part}'s configuration is taken, docs/configuration.md") + ")")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ConfigError(f"--try-set {key}: must be a number, got {value!r}")
            _read_by_model(key, cfg, {**cover, name: value}, canonical)
            over.setdefault(f"{part}.set", {})[name] = value
        else:
            from mtbmj.bike.bikefile import part_key

            meant = part_key(key)
            if meant is not None:  # a part's configuration key typed as a bike key: it takes the part's prefix
                part = key.partition(".")[0]
                raise ConfigError(f"--try-set {key}: not a bike key; a key of the {part}'s own configuration is "
                                  f"tried as {part}:{meant} (--try-set {part}:{meant}={value})")
            over[key] = value
    if not sets and other is None:
        raise ConfigError("--try-set: nothing to try (give --try FILE or --try-set KEY=VALUE)")
    try:
        base_notes = set(compose_setting(file, {k: v for k, v in (overrides or {}).items()} if other is None else {}))
    except ConfigError as exc:
        raise ConfigError(f"{what}: {exc}") from None
    try:
        notes = compose_setting(file, over)
    except ConfigError as exc:
        said = str(exc).removeprefix("--set ")  # the bike file's own refusal names --set: the key was tried here
        raise ConfigError(f"{what}{' ' + ', '.join(f'{k}={v}' for k, v in settings.items()) if settings else ''}: "
                          f"{said}") from None
    if other is not None:  # the try file's own word (a key its part's model does not read: the try changes
        from mtbmj.config import warn  # nothing there), said before any work where the recorded bike does not say it

        try:
            recorded = set(compose_setting(bike, overrides))
        except ConfigError:
            recorded = set()
        warn([f"--try {other}: {n}" for n in dict.fromkeys(notes) if n not in recorded])
    new = [n for n in notes if n not in base_notes]
    if new and settings:
        raise ConfigError(f"--try-set {', '.join(f'{k}={v}' for k, v in settings.items())}: {new[0]} (advise "
                          f"predicts only within what parts have)")
    label = (Path(ref).name if other is not None else "recorded setting") + (
        (" with " if other is not None else ": ") + ", ".join(f"{k} = {v}" for k, v in settings.items())
        if settings else "")
    return Trial(label, ref, over, settings, file)


def skipped_entry(adj: Adjuster, direction: str, value, exc) -> dict:
    return {"key": adj.name, "label": adj.label, "direction": direction, "from": adj.value, "to": value,
            "setting": adj.setting(value), "why": str(exc)}


def allowed(bike, candidates, merged) -> tuple[list, list]:
    """(the candidates ``(adjuster, direction, value)`` the part allows, the others as dicts naming
    why): each candidate's bike (``merged(adjuster.overrides(value))``, the recorded overrides with
    the candidate's over them; ``bike`` a file, a preset or a ``ResolvedBike``, which is not read
    again) derived and its fork and shock composed, as its run would; one the
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
                bike_run.setups(spec_mod.load(bike, merged(a.overrides(v))))  # a ResolvedBike: not read again
        except ConfigError as exc:
            skipped.append(skipped_entry(a, d, v, exc))
        else:
            ok.append((a, d, v))
    return ok, skipped


def counter(progress, n: int):
    """The step each finished run takes: ``progress(fraction, "run i/n")`` (``mtbmj.cli.common.Progress``
    draws it on a terminal only)."""
    done = [0]

    def step():
        done[0] += 1
        if progress is not None:
            progress(done[0] / n, f"run {done[0]}/{n}")
    return step


def checked_duration(duration):
    """``duration`` (s, or None) checked before any ride is read: positive, finite, at least ``MIN_SECONDS``."""
    if duration is None:
        return None
    duration = float(duration)
    if not (math.isfinite(duration) and duration > 0.0):
        raise AdviseError(f"--duration: must be a positive number of seconds, got {duration:g}")
    return duration

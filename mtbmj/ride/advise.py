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

**Calibrated first, on request** (``calibrated``, ``--calibrate``; :mod:`mtbmj.ride.calibrate`): each end's spring
scaled so that its mean force over the ride is the static load it carries (the record alone, before
the reconstruction finds anything through the springs); every run rides that bike, and each
candidate is read in the bike file's units relative to it (``Adjuster.per_unit`` times the scale).
No scale that carries an end is a refusal (:class:`RideNotDescribed`). Not the default: on a ride
made in the tests with the bike file's own springs and the fork's rebound four times too slow, the
calibration reads the fork at x0.97 (the model's rider sits 6.5 cm further back than the test's),
and that 3 % turned the right answer (rebound lowered 2800 -> 734 N s/m, the true 700) into
"inconclusive"; the front then reproduced at 7.8 mm RMS against 4.6 with the file's spring (measured
before the made ride's wheelbase shortened and every candidate was searched; not measured since).

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

from mtbmj.errors import ConfigError
from mtbmj.ride.advice_rules import (  # noqa: F401 (advise's names for them)
    MAX_SEGMENTS, MIN_SEGMENTS, Adjuster, AdviseError, BALANCE_POINTS, BOOTSTRAP, BOTTOM_OUTS_PER_MINUTE, DEEP_PERCENT,
    GRIP_COMFORT_WEIGHT, HEADLINE, LEAD_IN_M, MAX_REAR_MISS_PERCENT, MIN_CHECKED_PERCENT, MIN_GAIN,
    MIN_SECONDS, PACKING_RATIO, RULES, RideNotDescribed, SAG_POINTS, SAG_WINDOW,
    SEGMENT_S, SHARES, SIGNED, SOLD_LB_PER_IN, SPEED_SPLIT_MM_PER_S, UNCERTAINTY_METHOD,
    UNITS, UNUSED_BELOW_PERCENT, adjusters, bounded_value, bounds, expected,
    flat_metrics, grip_comfort, penalties, ride_metrics, round_setting, unit_of, Trial, compose_setting, trial)


from mtbmj.ride.advice_report import metric_unit  # noqa: E402,F401 (advise's name for it)

LEGEND_ROOM = 1.45  # the histograms' height over their tallest bar: the legend sits above the bars


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
    searched: tuple = None  # (Adjuster, direction, value, Run): the recommendation searched further
    judged: list = field(default_factory=list)  # the candidates as judged: each searched one where it ended
    calibration: object = None  # mtbmj.ride.calibrate.Calibration: the springs ridden (None: the file's as they are)

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
            out.append(flat_metrics(ride_metrics(t[k], front[k], rear[k], ftop, rtop)) if k.sum() >= 10 else {})
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
            a, b = flat_metrics(self.base.metrics), flat_metrics(self.measured)
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
                          "grip_comfort": grip_comfort(self.base.metrics, run.metrics), "crash": run.crash})
        return {"ride": self.ride, "bike": self.bike, "method": __doc__.split("\n\n")[1].replace("\n", " "),
                "rules": RULES, "reconstruction": self.reconstruction,
                "recorded_setting": {"measured": self.measured, "simulated": self.base.metrics,
                                     "penalties": self.base.penalty, "penalty": self.base.total},
                "uncertainty": self.uncertainty(), "uncertainty_method": UNCERTAINTY_METHOD,
                "verdict": self.verdict, "candidates": cands, "skipped": list(self.skipped),
                "recommendation": self.recommendation, "tried": self.tried(), "wall_time_s": self.wall_s,
                "calibration": None if self.calibration is None else self.calibration.to_dict()}

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
            run = next((r for a, d, v, r in ([self.searched] if self.searched else []) + list(self.judged)
                        + list(self.candidates)
                        if a.name == shown["key"] and d == shown["direction"] and v == shown["to"]), None)
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
            tallest = 0.0
            for label, x, color in series:
                h, _ = np.histogram(np.clip(x, 0, 100), bins=edges)
                share = 100 * h / max(h.sum(), 1)
                tallest = max(tallest, float(share.max()))
                ax.stairs(share, edges, label=label, color=color, linewidth=1.6)
            # room above the tallest bar for the legend, so no bar is hidden behind it
            ax.set_ylim(0.0, LEGEND_ROOM * max(tallest, 1.0))
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
        from mtbmj.ride import advice_report

        return advice_report.html(self, png)

    def write(self, out_dir) -> list:
        import json

        from mtbmj import output

        png = self.png()
        return output.write_atomically(out_dir, {
            "advice.json": (json.dumps(self.to_dict(), indent=2, default=_json) + "\n").encode(),
            "advice.png": png, "advice.html": self.html(png).encode()})


def _json(o):
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(type(o).__name__)


RULE_METRICS = {"static_sag": "static_sag_percent", "bottom_outs": "bottom_outs_per_minute",
                "travel_unused": "max_travel_percent", "packing": "rebound_over_compression"}


def _rule_metric(rule: str) -> str:
    """The metric (``flat_metrics`` name) a penalty ``rule`` (``front_static_sag``, ``balance``) reads."""
    if rule == "balance":
        return "balance_points"
    end, _, name = rule.partition("_")
    return f"{end}.{RULE_METRICS[name]}"


def _beyond(rules, a: dict, b: dict, u: dict) -> list:
    """The metrics of ``rules`` (penalty names) that move from ``a`` to ``b`` by more than their
    uncertainty ``u`` (a metric without one never does)."""
    return [m for m in dict.fromkeys(_rule_metric(k) for k in rules)
            if m in a and m in b and abs(b[m] - a[m]) > u.get(m, math.inf)]


def _judge(advice, candidates=None) -> tuple[dict | None, dict]:
    """(the recommendation or None, the verdict ``{"answer", "why"}``): a change is advised only where
    it lowers the penalty by ``MIN_GAIN`` or more and a metric of a rule it improves moves by more
    than that change's uncertainty (the best such candidate, grip and comfort breaking ties);
    "keep" only where every candidate is predicted worse beyond its uncertainty (a crash is worse);
    otherwise "inconclusive", naming why. ``candidates``: those judged (default the one-step ones;
    :func:`advise` passes each searched candidate where its search ended)."""
    base, measured = advice.base, advice.measured
    candidates = advice.candidates if candidates is None else candidates
    a = flat_metrics(base.metrics)
    good, worse, near = [], 0, None
    for adj, direction, value, run in candidates:
        if run.crash:
            worse += 1
            continue
        u = advice.change_uncertainty(run)
        b = flat_metrics(run.metrics)
        gain = base.total - run.total
        improved = [k for k in base.penalty if run.penalty[k] < base.penalty[k] - 1e-9]
        worsened = [k for k in base.penalty if run.penalty[k] > base.penalty[k] + 1e-9]
        score = gain - grip_comfort(base.metrics, run.metrics)
        if gain >= MIN_GAIN and _beyond(improved, a, b, u):
            good.append((score, adj, direction, value, run, improved, u))
        elif gain <= -MIN_GAIN and _beyond(worsened, a, b, u):
            worse += 1
        elif gain >= MIN_GAIN and (near is None or score > near[0]):
            near = (score, adj, direction, value, run, improved, u)
    n = len(candidates)
    if good:
        _, adj, direction, value, run, improved, u = max(good, key=lambda g: g[0])
        moved = _beyond(improved, a, flat_metrics(run.metrics), u)
        st = adj.setting(value)
        why = (f"{'raise' if direction == 'up' else 'lower'} the {adj.label} from {st['from']:g} to {st['to']:g} "
               f"{st['unit']} ({st['key']}): the penalty falls {base.total:.2f} -> {run.total:.2f} "
               f"({', '.join(k.replace('_', ' ') for k in improved)}; "
               + ", ".join(f"{m} {a[m]:.3g} -> {flat_metrics(run.metrics)[m]:.3g} +- {u[m]:.2g}" for m in moved) + ")")
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
        b = flat_metrics(run.metrics)
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
    """Per metric (``flat_metrics`` name): the simulated value at the recorded setting (``from``) and at
    ``run``'s (``to``), the change, its uncertainty, the recorded value and the one expected on the
    rider's ride (:func:`expected`)."""
    a, b, rode = flat_metrics(base.metrics), flat_metrics(run.metrics), flat_metrics(measured)
    return {k: {"from": v0, "to": b[k], "change": b[k] - v0, "uncertainty": uncertainty.get(k),
                "recorded": rode.get(k), "expected": expected(k, rode[k], v0, b[k]) if k in rode else b[k]}
            for k, v0 in a.items() if k in b}


def _skip(adj: Adjuster, direction: str, value, exc) -> dict:
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
            skipped.append(_skip(a, d, v, exc))
        else:
            ok.append((a, d, v))
    return ok, skipped


def advise(record, bike, overrides=None, duration: float | None = None, progress=None, workers: int = 2,
           tries=(), candidates: bool = True, calibrated: bool = False, search: bool = True) -> Advice:
    """Advice for ``record`` (a two-ended ``TelemetryRecord``) on ``bike`` (preset, file or
    ``mtbmj.bike.spec.ResolvedBike``: read once, here or before), its keys ``overrides``;
    ``duration`` limits the simulated ride to its first seconds; the runs spread
    over ``workers`` processes. ``tries``: settings to try (:class:`Trial`, from :func:`trial`),
    simulated over the same terrain beside the recorded setting and predicted as the candidates are
    (``Advice.tries``); ``candidates`` False simulates the tried settings only (:func:`predict`).
    ``calibrated`` (``--calibrate``): the bike's springs calibrated on the ride first
    (:mod:`mtbmj.ride.calibrate`), every run (the recorded setting, each candidate, each try) on the
    calibrated bike, the candidates read in the file's units relative to it; False (the default): the
    bike file as it is. ``search``: every candidate that lowers the penalty searched further along its
    adjuster before the verdict (:mod:`mtbmj.ride.advice_search`)."""
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
    bike = spec_mod.resolve(bike)  # the bike file read once: every run below derives its setting from it
    bike = bike.with_overrides(None) if bike.overrides else bike
    file_spec = spec_mod.load(bike, overrides)
    cal = None
    if calibrated:  # the ridden bike's springs from the ride itself, before anything is found through them
        from mtbmj.ride import calibrate as cal_mod

        cal = cal_mod.calibrate(record, bike, overrides, duration)
        overrides = cal.apply(bike, overrides)
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
    spec = spec_mod.load(bike, overrides)
    speed = float(rec.speed["speed_m_per_s"])
    ride_s = length if duration is None else min(length, float(duration))
    lead_s = 1.0 / speed  # the front axle reaches the ride's first metre
    sim_s = ride_s + lead_s
    terrain = terrain_of(rec)
    adj = adjusters(spec) if cal is None else cal.adjusters(file_spec)
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

    jobs = [(bike, base_over, terrain, speed, sim_s, "recorded setting", lead_s)]
    jobs += [(bike, merged(a.overrides(v)), terrain, speed, sim_s, f"{a.label} {v:g}", lead_s) for a, d, v in todo]
    jobs += [(tr.bike if tr.resolved is None else tr.resolved,
              tr.overrides if cal is None else cal.apply(tr.bike if tr.resolved is None else tr.resolved, tr.overrides),
              terrain, speed, sim_s, tr.label, lead_s) for tr in tries]
    from contextlib import ExitStack

    with ExitStack() as stack:
        pool = None
        if workers > 1 and len(jobs) > 1:
            from mtbmj.workers import process_pool

            pool = stack.enter_context(process_pool(min(workers, len(jobs))))
        # a candidate its part refuses only when run is skipped (the recorded setting's own refusal and a
        # tried one's stay the user's error)
        runs = _run_jobs(jobs, pool, lambda i: 0 < i <= len(todo), step)
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
                        skipped=skipped, tries=list(zip(tries, runs[1 + len(todo):])), record_t=t[keep] - t[0],
                        calibration=cal)
        searched = _search(advice, bike, merged, terrain, speed, sim_s, lead_s, pool) if search else {}
        advice.judged = _searched_candidates(advice, searched)
        advice.recommendation, advice.verdict = _judge(advice, advice.judged)
        if advice.recommendation is not None and search:
            _annotate(advice, searched)
    advice.wall_s = time.perf_counter() - start
    return advice


def _run_jobs(jobs, pool, refusable, step) -> list:
    """Each job's :func:`simulate` (in ``pool`` where given): a ``ConfigError`` of a job ``refusable(i)``
    kept as its result, any other raised."""
    runs = [None] * len(jobs)
    if pool is not None:
        from concurrent.futures import as_completed

        futures = {pool.submit(simulate, *job): i for i, job in enumerate(jobs)}
        done = as_completed(futures)
    else:
        done = range(len(jobs))
    for item in done:
        i = futures[item] if pool is not None else item
        try:
            runs[i] = item.result() if pool is not None else simulate(*jobs[i])
        except ConfigError as exc:
            if not refusable(i):
                raise
            runs[i] = exc
        step()
    return runs


def _search(advice, bike, merged, terrain, speed, sim_s, lead_s, pool) -> dict:
    """Every candidate that lowers the penalty by ``MIN_GAIN`` or more, searched further along its
    adjuster (:func:`mtbmj.ride.advice_search.search_many`, all in one pool): ``{(adjuster name,
    direction): [(value, run), ...]}``, the steps each search kept."""
    from mtbmj.ride import advice_search

    base = advice.base
    starts = [(a, d, v, r) for a, d, v, r in advice.candidates
              if not r.crash and base.total - r.total >= MIN_GAIN]
    if not starts:
        return {}

    def run_values(asks):
        jobs = [(bike, merged(starts[i][0].overrides(v)), terrain, speed, sim_s, f"{starts[i][0].label} {v:g}", lead_s)
                for i, v in asks]
        return _run_jobs(jobs, pool, lambda i: True, lambda: None)

    def allowed_value(i, v):
        a, d = starts[i][0], starts[i][1]
        return bool(allowed(bike, [(a, d, v)], merged)[0])

    kept = advice_search.search_many([(a, v, r) for a, d, v, r in starts], run_values, allowed_value)
    return {(a.name, d): k for (a, d, _, _), k in zip(starts, kept)}


def _searched_candidates(advice, searched: dict) -> list:
    """The candidates as the verdict judges them: each searched one where its search ended."""
    out = []
    for a, d, v, r in advice.candidates:
        kept = searched.get((a.name, d))
        out.append((a, d, *kept[-1]) if kept else (a, d, v, r))
    return out


def _annotate(advice, searched: dict) -> None:
    """The recommendation's search (``search``: each step kept, ``driven_by``: the rule whose penalty
    fell most) and, where it went past the one-step candidate, that said in its why."""
    from mtbmj.ride import advice_search

    rec = advice.recommendation
    kept = searched.get((rec["key"], rec["direction"]), [])
    adj = next(a for a, d, v, r in advice.candidates if a.name == rec["key"] and d == rec["direction"])
    rec["search"] = [{"to": v, "setting": adj.setting(v), "penalty": r.total} for v, r in kept]
    run = kept[-1][1] if kept else next(r for a, d, v, r in advice.candidates
                                        if a.name == rec["key"] and d == rec["direction"])
    if kept:
        advice.searched = (adj, rec["direction"], kept[-1][0], run)
    rec["driven_by"] = advice_search.driving_rule(advice.base.penalty, run.penalty)
    if kept:
        rec["why"] += (f"; found by searching on from the one-step candidate ({len(kept)} step(s) further), "
                       f"driven by the {rec['driven_by'].replace('_', ' ')} rule")
        advice.verdict = {**advice.verdict, "why": rec["why"]}


def predict(record, bike, tries, overrides=None, duration: float | None = None, progress=None,
            workers: int = 2) -> Advice:
    """The ride's metrics at each tried setting (:func:`trial`) beside the recorded setting's, with
    the advice's reconstruction and uncertainty, no candidate simulated: ``Advice.tried()``."""
    return advise(record, bike, overrides, duration, progress, workers, tries=tries, candidates=False)


__all__ = ["Adjuster", "Advice", "AdviseError", "RideNotDescribed", "RULES", "Trial", "adjusters", "advise", "allowed",
           "bounds", "expected", "penalties", "predict", "ride_metrics", "simulate", "terrain_of", "trial"]

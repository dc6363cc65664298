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

**Calibrated first** (``calibrated``, the default; ``--no-calibrate`` turns it off; :mod:`mtbmj.ride.calibrate`): each end's spring
scaled so that its mean force over the ride is the static load it carries (the record alone, before
the reconstruction finds anything through the springs); every run rides that bike, and each
candidate is read in the bike file's units relative to it (``Adjuster.per_unit`` times the scale).
No scale that carries an end is a refusal (:class:`RideNotDescribed`). On the tests' made rides calibrated
advice lowers a rebound four times too slow, 2800 -> 1147 N s/m, and raises a soft fork 5 -> 11.79 N/mm
(why it was opt-in before, and the numbers on each kind of made ride: docs/rolling.md).

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
  travel and below ``UNUSED_SHARE`` of the other end's maximum on the ride as recorded costs too
  (travel left unused, read against what the terrain asked of the other end: a smooth trail asks for
  less; assumed);
- packing: an end's rebound p95 over its compression p95 below ``PACKING_SHARE`` of the other end's
  on the ride as recorded (the terrain sets the compression speeds, and the other end rides the same
  terrain: "front and rear rebound about the same", Motion Instruments' balance; the number assumed),
  or below ``PACKING_FLOOR`` whatever the other end does (assumed; docs/rolling.md says why); pogo, its other
  side: a change that speeds an end past ``POGO_SHARE`` of the other end's (and past its own) costs too;
- balance: the ends' dynamic sags within ``BALANCE_POINTS`` points ("front and rear should move about
  the same", Motion Instruments; the number assumed);
- grip and comfort: a small weight on the relative change of tyre-load variation and rider
  acceleration (tie-breakers, assumed).

**Scored on the ride, not on the model** (:meth:`Advice.score`, :func:`on_the_ride`): the rules
judge what the rider's own ride is expected to show at each setting, the recorded metrics moved by
the model's predicted change (below), static sag the model's (no ride records it). At the recorded
setting that is the ride as recorded. So the rules judge the bike that was ridden and a candidate
by the change the model predicts, not the model's own bias: on the tests' well-set bike the model's
fork bottoms 4 times where the ride had none, and curing those had been the advice.

The predicted change of every metric is the candidate's simulated value less the recorded
setting's, and the value expected on the rider's own ride (``expected``; the simulated ``to``
beside it) is the recorded value moved by that change within the metric's bounds (:func:`expected`:
a change towards a bound scaled by the room the ride has on that side, so the model's five
bottom-outs becoming four take a ride's none to none, not to -1; a count or share is never
expected below 0, a share of time never above 100 %). Its uncertainty comes from the ride itself
(``UNCERTAINTY_METHOD``: the ride's segments resampled, the model's error at the recorded setting
and the change's spread over the segments). The verdict (:func:`judge`): a change is advised only
where it lowers the total penalty by at least ``MIN_GAIN`` and a metric of a rule it improves moves
by more than its uncertainty; "keep" only where every candidate is predicted worse beyond its
uncertainty; otherwise "inconclusive", naming why (never "keep" by default). Where several
candidates are advised, one is recommended first, the balance of the ends before the rest (one that
moves the balance beyond its uncertainty, if any; among changes the ride cannot tell apart, the spring
before rebound before compression: ``advice_verdict.ties``), the others after it (``recommendation["then"]``,
:meth:`Advice.then`; searched again from it, :mod:`mtbmj.ride.advice_combined`). Several rides of one setting are
pooled by :mod:`mtbmj.ride.advice_pool` (``mtbmj advise RIDE RIDE ...``). Every setting is also
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
    MIN_SECONDS, PACKING_FLOOR, PACKING_SHARE, RULES, RideNotDescribed, SAG_POINTS, SAG_WINDOW,
    SEGMENT_S, SHARES, SIGNED, SOLD_LB_PER_IN, SPEED_SPLIT_MM_PER_S, UNCERTAINTY_METHOD,
    UNITS, UNUSED_BELOW_PERCENT, UNUSED_SHARE, skipped_entry, adjusters, allowed, checked_duration, counter, bounded_value, bounds, expected,
    beyond, flat_metrics, grip_comfort, on_the_ride, rule_metric, penalties, ride_metrics, round_setting, unit_of,
    Trial, compose_setting, trial)


from mtbmj.ride.advice_report import LEGEND_ROOM, metric_unit  # noqa: E402,F401 (advise's names for them)
from mtbmj.ride.advice_verdict import changes, judge  # noqa: E402,F401 (advise's names for them)

DESCENT_LEAD_M = 10.0  # --carried-as descent: the level start this much further before the ride (the grade entered)


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
    parts: list = field(repr=False, default=None)  # a pooled run: each ride's own (mtbmj.ride.advice_pool)
    levelled: bool = field(repr=False, default=False)  # its static sags moved to the file's place (Advice.levelled)

    @property
    def total(self) -> float:
        return float(sum(self.penalty.values()))


def terrain_of(rec, descent_deg: float = 0.0):
    """The reconstruction's terrain with a flat lead-in (the bike starts at rest on level ground);
    where the front wheel was off the ground (a jump) the ground is unknown, and its found height
    is the wheel's flight: the straight line from take-off to landing stands in for it. ``descent_deg``
    (``--carried-as descent``): laid on that mean descent, entered over 5 m from 2 m after the start,
    the start ``DESCENT_LEAD_M`` further back so the ride's first metre is on the steady grade."""
    from mtbmj.rolling.terrain import Terrain, on_grade

    ground = np.array(rec.ridden_ground, float)  # a fall its landing cannot give cut (reconstruct_landing)
    for a, b in rec.jumps:
        i, j = int(np.searchsorted(rec.t, a)), int(np.searchsorted(rec.t, b))
        i, j = max(i - 1, 0), min(j, ground.size - 1)
        if j > i + 1:
            ground[i:j + 1] = np.interp(rec.distance[i:j + 1], [rec.distance[i], rec.distance[j]], [ground[i], ground[j]])
    keep = np.concatenate(([True], np.diff(rec.distance) > 1e-9))
    x, z = rec.distance[keep], ground[keep]
    x = np.concatenate(([x[0] - LEAD_IN_M - 50.0, x[0] - 0.01], x, [x[-1] + 50.0]))
    z = np.concatenate(([z[0], z[0]], z, [z[-1]]))
    start = float(rec.distance[0] - 1.0 - (DESCENT_LEAD_M if descent_deg else 0.0))  # the axle 1 m before the ride
    ter = Terrain(f"{rec.name} (reconstructed)", x, z, start, float(rec.distance[-1] - start), {"ride": rec.name})
    return on_grade(ter, -100.0 * math.tan(math.radians(descent_deg)), start + 2.0, 5.0) if descent_deg else ter


def simulate(bike, overrides: dict, terrain, speed: float, duration: float, label: str, lead_s: float,
             profile=None) -> Run:
    """The bike with ``overrides`` over ``terrain`` from ``speed`` (held, or along ``profile``: (x m, v m/s),
    the ride's, ``Reconstruction.speed_along``): its metrics from ``lead_s`` on."""
    from mtbmj.bike import run as bike_run

    r = bike_run.run_bike(bike, terrain, speed, duration=duration, drive="rider", overrides=overrides or None,
                          speed_profile=profile)
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


def sags_moved(metrics: dict, offsets: dict) -> dict:
    """``metrics`` (:func:`ride_metrics`' shape) with each end's static sag moved by ``offsets`` (points of
    travel per end), a new dict; an end without a static sag, or a 0 offset, as it was."""
    out = dict(metrics)
    for end, off in offsets.items():
        if off and out[end].get("static_sag_percent") is not None:
            out[end] = {**out[end], "static_sag_percent": out[end]["static_sag_percent"] + off}
    return out


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

    def score(self, run: Run) -> Run:
        """``run`` (any setting's) with its penalties scored on the ride (the module doc): the rules on
        :func:`on_the_ride` of it, the packing rule's terrain the ride as recorded. Returns ``run``."""
        self.levelled(run)
        run.penalty = penalties(on_the_ride(self.measured, self.base.metrics, run.metrics), self.measured)
        return run

    def levelled(self, run: Run) -> Run:
        """``run`` with its static sags as standing in the file's place on level ground, once: where the
        calibration moved the rider to where the ride carried the load (``Calibration.level_offsets``,
        the sag path of ``--static-sag-mm``), the points that move takes off. Returns ``run``."""
        cal = self.calibration
        if cal is None or not hasattr(cal, "level_offsets") or getattr(run, "levelled", False):
            return run
        run.metrics = sags_moved(run.metrics, cal.level_offsets())
        run.levelled = True
        return run

    def other_offsets(self) -> dict | None:
        """Per end, the static sag points the calibration's other reading adds (``Calibration.split``), or
        None where it has none."""
        cal = self.calibration
        return None if cal is None or getattr(cal, "split", None) is None else cal.static_sag_offsets()

    def other_reading(self, run: Run) -> dict | None:
        """``run``'s penalties scored on the ride as :meth:`score` does, but with each end's static sag
        as the calibration's other reading of the ride gives it (``Calibration.split``: both springs at
        one scale and a load carried fore-aft; its static sags less the per-end reading's added to the
        model's); None where the calibration has no other reading (or there is no calibration)."""
        offsets = self.other_offsets()
        if offsets is None:
            return None
        return penalties(sags_moved(on_the_ride(self.measured, self.base.metrics, run.metrics), offsets), self.measured)

    def tried(self) -> list:
        """Each tried setting: its label, bike file, settings as asked, penalty (and its change), crash,
        and every metric's predicted change (as a recommendation's ``changes``)."""
        for _, run in self.tries:
            self.levelled(run)
        return [{"label": tr.label, "bike": tr.bike, "settings": dict(tr.settings), "penalty": run.total,
                 "penalty_change": run.total - self.base.total, "crash": run.crash,
                 "changes": changes(self.base, run, self.change_uncertainty(run), self.measured)}
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

    def _run_segments(self, run: Run) -> list:
        """``run``'s per-segment flat metrics (a pooled advice: every ride's segments, ride after ride)."""
        return self._per_segment(run.time_s, run.front_mm, run.rear_mm)

    def _record_segments(self) -> list:
        return self._per_segment(self.record_t, self.record_front, self.record_rear)

    def pooled_run(self, runs: list) -> Run:
        """One run of each ride as the advice's run (one ride: its run)."""
        return runs[0]

    def _segment_diffs(self, run: Run, against) -> dict:
        """Per metric: the array over segments of ``run``'s value less ``against``'s (a list of per-segment
        flat metrics), segments where either has none left out."""
        mine = self._run_segments(run)
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
            rec = self._record_segments()
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

    def spread(self, run: Run, start: Run | None = None) -> dict:
        """Per metric: half the 5-95 % bootstrap interval of the mean over segments of ``run``'s change
        from the recorded setting, or from ``start`` (the change's own part of its uncertainty)."""
        out = {}
        if start is None and getattr(self, "_base_segments", None) is None:  # the recorded setting's, once
            self._base_segments = self._run_segments(self.base)
        segments = self._base_segments if start is None else self._run_segments(start)
        for k, d in self._segment_diffs(run, segments).items():
            lo, hi = np.percentile(d[self._boot(d.size)].mean(axis=1), [5, 95])
            out[k] = float(hi - lo) / 2
        return out

    def change_uncertainty(self, run: Run, start: Run | None = None) -> dict:
        """Per metric: the uncertainty of ``run``'s change from the recorded setting, or from ``start`` (a run
        of another setting on the same ride) (``UNCERTAINTY_METHOD``)."""
        model = self.uncertainty()
        out = dict(model)
        if run.time_s is not None and (self.base if start is None else start).time_s is not None:
            for k, half in self.spread(run, start).items():
                out[k] = float(math.hypot(model.get(k, 0.0), half))
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
        from mtbmj.ride import advice_report

        return advice_report.figure(self)

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

    def then(self) -> str:
        """The other changes advised, one line, after the recommended one: the values found after it
        (:func:`mtbmj.ride.advice_combined.then_line`), or from the recorded setting where not searched."""
        from mtbmj.ride.advice_combined import then_line

        return then_line(self)

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


def advise(record, bike, overrides=None, duration: float | None = None, progress=None, workers: int = 2,
           tries=(), candidates: bool = True, calibrated: bool = True, search: bool = True,
           static_sag_mm=None, carried_as: str = "rider", speed=None) -> Advice:
    """Advice for ``record`` (a two-ended ``TelemetryRecord``) on ``bike`` (preset, file or
    ``mtbmj.bike.spec.ResolvedBike``: read once, here or before), its keys ``overrides``;
    ``duration`` limits the simulated ride to its first seconds; the runs spread
    over ``workers`` processes, ``progress(fraction, note)`` called as each ends. ``tries``: settings to try (:class:`Trial`, from :func:`trial`),
    simulated over the same terrain beside the recorded setting and predicted as the candidates are
    (``Advice.tries``); ``candidates`` False simulates the tried settings only (:func:`predict`).
    ``calibrated`` (the default; ``--no-calibrate`` is False): the bike's springs calibrated on the ride
    first (:mod:`mtbmj.ride.calibrate`), every run (the recorded setting, each candidate, each try) on
    the calibrated bike, the candidates read in the file's units relative to it; False: the bike file
    as it is. ``search``: every candidate that lowers the penalty searched further along its
    adjuster before the verdict (:mod:`mtbmj.ride.advice_search`). ``static_sag_mm`` (fork, shock stroke
    mm, standing on level ground; ``--static-sag-mm``): the springs calibrated on it instead of the ride's
    balances (:func:`mtbmj.ride.calibrate.sag_scales`), the load the ride carried fore-aft carried by every run
    as ``carried_as`` says ("rider" or "descent": ``mtbmj.ride.calibrate.spring_scales``). Several rides of one setting:
    :func:`mtbmj.ride.advice_pool.pooled`. ``speed``: the ride's speed given (``reconstruct``'s ``speed=``)."""
    import time

    from mtbmj.bike import spec as spec_mod

    start = time.perf_counter()
    duration = checked_duration(duration)
    bike = spec_mod.resolve(bike)  # the bike file read once: every run below derives its setting from it
    bike = bike.with_overrides(None) if bike.overrides else bike
    ride = prepare(record, bike, overrides, duration, calibrated, candidates, tries, static_sag_mm, carried_as, speed)
    jobs = ride.jobs()
    from contextlib import ExitStack

    with ExitStack() as stack:
        pool = None
        if workers > 1 and len(jobs) > 1:
            from mtbmj.workers import process_pool

            pool = stack.enter_context(process_pool(min(workers, len(jobs))))
        # a candidate its part refuses only when run is skipped (the recorded setting's own refusal and a
        # tried one's stay the user's error)
        runs = run_jobs(jobs, pool, ride.refusable, counter(progress, len(jobs)))
        advice = ride.assemble(runs)
        decide(advice, [ride], pool, search)
        if search:  # the others searched again after the recommended change (mtbmj.ride.advice_combined)
            from mtbmj.ride.advice_combined import combine

            combine(advice, ride, pool, run_jobs, search_on, allowed)
    advice.wall_s = time.perf_counter() - start
    return advice


@dataclass
class Prepared:
    """One ride made ready for advice (:func:`prepare`): its reconstruction, terrain, speed, the
    calibrated overrides, the adjusters and the candidates its parts allow; nothing simulated yet."""

    record: object
    bike: object
    rec: object
    spec: object
    cal: object
    terrain: object
    speed: float
    ride_s: float
    lead_s: float
    adj: list
    base_over: dict
    todo: list
    skipped: list
    tries: list
    profile: tuple | None = None  # (x m, v m/s): the speed along the terrain every run holds (the ride's)

    @property
    def sim_s(self) -> float:
        return self.ride_s + self.lead_s

    def merged(self, extra: dict) -> dict:
        out = dict(self.base_over)
        for k, v in extra.items():
            out[k] = {**out.get(k, {}), **v}
        return out

    def job(self, overrides: dict, label: str) -> tuple:
        return (self.bike, overrides, self.terrain, self.speed, self.sim_s, label, self.lead_s, self.profile)

    def jobs(self) -> list:
        """The recorded setting, each candidate, each try: :func:`simulate`'s arguments."""
        out = [self.job(self.base_over, "recorded setting")]
        out += [self.job(self.merged(a.overrides(v)), f"{a.label} {v:g}") for a, d, v in self.todo]
        for tr in self.tries:
            b = tr.bike if tr.resolved is None else tr.resolved
            out.append((b, tr.overrides if self.cal is None else self.cal.apply(b, tr.overrides), self.terrain,
                        self.speed, self.sim_s, tr.label, self.lead_s, self.profile))
        return out

    def refusable(self, i: int) -> bool:
        return 0 < i <= len(self.todo)

    def assemble(self, runs) -> Advice:
        """The ride's :class:`Advice` (not judged) from its runs (in :meth:`jobs`' order); a recorded
        setting that crashes is a refusal (:class:`RideNotDescribed`)."""
        base = runs[0]
        if base.crash:
            raise RideNotDescribed(f"{self.record.name}: the recorded setting {base.crash} on the ride's reconstructed "
                                   f"terrain: the model cannot ride this ride as reconstructed, so it cannot predict a "
                                   f"change")
        skipped, cands = list(self.skipped), []
        for (a, d, v), run in zip(self.todo, runs[1:1 + len(self.todo)]):
            if isinstance(run, ConfigError):
                skipped.append(skipped_entry(a, d, v, run))
            else:
                cands.append((a, d, v, run))
        t = self.rec.t
        keep = t - t[0] <= self.ride_s
        rec = self.rec
        measured = ride_metrics(t[keep], rec.front[keep], rec.rear[keep], base.metrics["front"]["travel_mm"],
                                base.metrics["rear"]["travel_mm"])
        return Advice(rec.name, self.spec.name, rec.summary(), measured, base, cands, None, rec.front[keep],
                      rec.rear[keep], skipped=skipped, tries=list(zip(self.tries, runs[1 + len(self.todo):])),
                      record_t=t[keep] - t[0], calibration=self.cal)


def prepare(record, bike, overrides=None, duration: float | None = None, calibrated: bool = True,
            candidates: bool = True, tries=(), static_sag_mm=None, carried_as: str = "rider", speed=None) -> Prepared:
    """``record`` made ready for advice on ``bike`` (a ``ResolvedBike`` without overrides): its length
    checked, calibrated where asked, reconstructed and checked, its terrain, the adjusters and the
    candidates the parts allow (:func:`allowed`). Refused (:class:`AdviseError`) as :func:`advise` says."""
    from mtbmj.bike import spec as spec_mod
    from mtbmj.ride import reconstruct as rc

    rc.require_both_ends(record)  # before the calibration, which reads both ends too
    # a bike that stood unweighted mid-ride: its longest part ridden (the reconstruction cuts it too, and
    # says so in its summary), so the calibration and the length read what is reconstructed
    ridden = rc.ridden_part(record)[0]
    length = float(ridden.time_s[-1] - ridden.time_s[0])
    if length < MIN_SECONDS:
        raise AdviseError(f"{record.name}: {length:.1f} s of ride cannot support advice (at least {MIN_SECONDS:g} s)")
    # the minimum holds for the stretch analysed, not only for the file it is cut from
    if duration is not None and duration < MIN_SECONDS:
        raise AdviseError(f"--duration: {duration:g} s of {record.name} cannot support advice (at least "
                          f"{MIN_SECONDS:g} s; the ride is {length:.1f} s)")
    file_spec = spec_mod.load(bike, overrides)
    cal = None
    if calibrated:  # the ridden bike's springs from the ride itself, before anything is found through them
        from mtbmj.ride import calibrate as cal_mod

        cal = cal_mod.calibrate(ridden, bike, overrides, duration, static_sag_mm, carried_as)
        overrides, statics = cal.apply(bike, overrides), cal.apply(bike, overrides, statics=True)
    else:
        statics = overrides
    # all of the ground a wheelbase later, as the bike's runs over it meet it (the spectral share met at once,
    # the check's since issue 51, is not carried by the runs: docs/rolling.md (5))
    rec = rc.reconstruct(record, bike, statics, spectral=False, speed=speed)
    checks = rec.checks()
    if (checks["samples_checked_percent"] < MIN_CHECKED_PERCENT
            or not checks["rear_predicted_rms_percent_of_used"] <= MAX_REAR_MISS_PERCENT):
        raise RideNotDescribed(f"{record.name}: its reconstruction fails its own check (rear predicted within "
                               f"{checks['rear_predicted_rms_percent_of_used']:.0f} % of the travel used, "
                               f"{checks['samples_checked_percent']:.0f} % of the ride checked; advice needs within "
                               f"{MAX_REAR_MISS_PERCENT:g} % over {MIN_CHECKED_PERCENT:g} %): the model does not "
                               f"describe this ride well enough to predict a change")
    if not checks.get("passes", True):  # the rear predicted no better than a naive baseline (issue 51)
        raise RideNotDescribed(f"{record.name}: its reconstruction fails its own check (the rear meeting all of the ground "
                               f"a wheelbase later, as the runs do): {checks['verdict']}; advice needs a model that beats "
                               f"both naive baselines, so it cannot predict a change")
    spec = spec_mod.load(bike, overrides)
    profile = rec.speed_along()  # every run holds the ride's speed where the ride had it
    speed = float(profile[1][0])  # and the first metre's up to it
    adj = adjusters(spec) if cal is None else cal.adjusters(file_spec)
    terrain = terrain_of(rec, 0.0 if cal is None else cal.descent_deg)
    ride = Prepared(record, bike, rec, spec, cal, terrain, speed,  # metrics from the axle at the ride's first metre
                    length if duration is None else min(length, duration), (rec.distance[0] - terrain.start_x) / speed,
                    adj, dict(overrides or {}), [], [], list(tries or ()), profile)
    ride.todo, ride.skipped = allowed(bike, [(a, d, v) for a in adj for d, v in (("down", a.down), ("up", a.up))
                                             if v is not None and v != a.value] if candidates else [], ride.merged)
    return ride


def run_jobs(jobs, pool, refusable, step) -> list:
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


def search_on(advice, rides, pool) -> dict:
    """Every candidate that lowers the penalty by ``MIN_GAIN`` or more, searched further along its
    adjuster (:func:`mtbmj.ride.advice_search.search_flow`, all in one pool, each as its runs end) on every ride of
    ``rides`` (:class:`Prepared`; a pooled advice's runs pooled by ``advice.pooled_run``):
    ``{(adjuster name, direction): [(value, run), ...]}``, the steps each search kept."""
    from concurrent import futures
    from concurrent.futures import Future

    from mtbmj.ride import advice_search

    base = advice.base
    starts = [(a, d, v, r) for a, d, v, r in advice.candidates if not r.crash and base.total - r.total >= MIN_GAIN]
    if not starts:
        return {}
    own = [[next(x for x in ride.adj if x.name == a.name) for ride in rides] for a, *_ in starts]  # each ride's

    def on(a, x, v):  # the value v of adjuster a as a ride's own x has it (the same where no calibration differs)
        return v if x.per_unit == a.per_unit else v / a.per_unit * x.per_unit

    def submit(i, v):  # search i's value v on every ride: a future each (run here where there is no pool)
        jobs = [ride.job(ride.merged(x.overrides(on(starts[i][0], x, v))), f"{starts[i][0].label} {v:g}")
                for ride, x in zip(rides, own[i])]
        if pool is not None:
            return tuple(pool.submit(simulate, *job) for job in jobs)
        done = []
        for job in jobs:
            done.append(Future())
            try:
                done[-1].set_result(simulate(*job))
            except Exception as exc:  # noqa: BLE001 - raised again where it is read, as the pool's would be
                done[-1].set_exception(exc)
        return tuple(done)

    def wait(handles):  # the handles whose every ride's run has ended, each as one (pooled) scored run
        futures.wait([f for h in handles for f in h], return_when=futures.FIRST_COMPLETED)
        out = []
        for h in handles:
            if all(f.done() for f in h):
                parts = [f.exception() or f.result() for f in h]
                bad = next((r for r in parts if isinstance(r, Exception)), None)
                if bad is not None and not isinstance(bad, ConfigError):
                    raise bad
                out.append((h, bad or advice.score(advice.pooled_run(parts))))
        return out

    def allowed_value(i, v):
        a, d = starts[i][0], starts[i][1]
        return all(allowed(ride.bike, [(x, d, on(a, x, v))], ride.merged)[0] for ride, x in zip(rides, own[i]))

    slots = max(1, (1 if pool is None else pool.workers) // len(rides))  # values the pool runs at once
    kept = advice_search.search_flow([(a, v, r) for a, d, v, r in starts], submit, wait, allowed_value, slots)
    return {(a.name, d): k for (a, d, _, _), k in zip(starts, kept)}


def decide(advice, rides, pool, search: bool = True, judging=None) -> None:
    """The verdict of ``advice`` (``judging(advice, candidates)``, default :func:`judge`): each
    candidate that lowers the penalty searched on first (:func:`search_on`), the verdict judging each
    where its search ended (``Advice.judged``), the recommendation's search annotated."""
    for run in [advice.base] + [r for *_, r in advice.candidates] + [r for _, r in advice.tries]:
        advice.score(run)  # the recorded setting first: every other is scored against it
    searched = search_on(advice, rides, pool) if search else {}
    advice.judged = [(a, d, *searched[(a.name, d)][-1]) if searched.get((a.name, d)) else (a, d, v, r)
                     for a, d, v, r in advice.candidates]
    advice.recommendation, advice.verdict = (judging or judge)(advice, advice.judged)
    if advice.recommendation is not None and search:
        from mtbmj.ride.advice_search import annotate

        annotate(advice, searched)


def predict(record, bike, tries, overrides=None, duration: float | None = None, progress=None,
            workers: int = 2) -> Advice:
    """The ride's metrics at each tried setting (:func:`trial`) beside the recorded setting's, with
    the advice's reconstruction and uncertainty, no candidate simulated: ``Advice.tried()``."""
    return advise(record, bike, overrides, duration, progress, workers, tries=tries, candidates=False)


_judge = judge  # its former name

__all__ = ["Adjuster", "Advice", "AdviseError", "RideNotDescribed", "RULES", "Trial", "adjusters", "advise", "allowed",
           "bounds", "expected", "penalties", "predict", "ride_metrics", "simulate", "terrain_of", "trial"]

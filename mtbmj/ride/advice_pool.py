"""Several rides of one bike and one setting pooled into one advice (``mtbmj advise RIDE RIDE ...``,
issue 52 item 4).

**What is pooled.** Each ride is made ready on its own (:func:`mtbmj.ride.advise.prepare`: its
length, its calibration where asked, its reconstruction and that reconstruction's check) and the
whole bike rides each ride's own terrain at its own speed, with the recorded setting and with every
candidate (all rides' runs in one process pool). A candidate is pooled where every ride has it (the
same adjuster, the same direction). The pooled metrics of a setting (:func:`pool_metrics`) are those
of all its rides together: counts summed (bottom-outs, and per minute over the rides' minutes), the
maximum travel the largest, every other metric (sags, shares of time, p95 speeds, tyre-load
variation) the mean weighted by each ride's length, packing the ratio of the pooled p95 speeds, the
balance the pooled sags' difference, the rider's acceleration the RMS over all. The uncertainty is
the single ride's method over the segments of every ride together (``UNCERTAINTY_METHOD``: each
ride's segments, resampled across rides), so more rides narrow it. One verdict, by the single ride's
rules (``mtbmj.ride.advise.judge``), every candidate that lowers the penalty searched on first on every ride
(``mtbmj.ride.advise.search_on``).

**One calibration for the pool** (``advice.json`` ``calibration``, the line, ``advice.html``): the
springs from every kept ride's balances together (``mtbmj.ride.calibrate.calibrate_pooled``: the rides
joined end to end, each weighted by its length), and so its other reading, which the verdict's words
quote; each ride still rides at its own calibration (its own descents and loads), and its own scales
are in ``rides`` (``spring_scales``).

**Each ride's own verdict** (``PooledAdvice.rides``, one step, not searched) is kept beside the
pooled one (``advice.json`` ``rides``, a table in ``advice.html``, a line each on the terminal).
Where the rides contradict each other or the pooled answer (:func:`judge`: one raises an adjuster
another lowers, counting each ride's recommended change and the changes after it; or a ride advises
a change where the pooled answer keeps), the pooled answer is **inconclusive**, naming the adjuster
and the rides each way: one setting should give one answer. Rides that advise different adjusters
without contradicting each other are not a disagreement: the pooled answer, on all their segments,
chooses. **The uncertainty narrows** with more rides in its spread part (the change's mean over more
segments: ``Advice.spread``); the model's error is the pooled mean difference from the records, so a
bias that differs from ride to ride averages rather than narrows.

**A ride refused** (too short, its reconstruction failing its check, the recorded setting crashing
on its terrain) is left out of the pool and named with its reason (``PooledAdvice.refused``, the
line, ``advice.json`` ``refused``, ``advice.html``); where none remain the advice is refused naming
each ride's reason. A ride of another bike or another setting cannot be told from its file in
general: that the rides share one setting is the rider's word.
"""
from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass, field

import numpy as np

from mtbmj.ride.advice_rules import AdviseError, checked_duration, counter, penalties
from mtbmj.ride.advise import Advice, Run, decide, prepare, run_jobs
from mtbmj.ride.advise import judge as judge_one


def pool_metrics(ms: list) -> dict:
    """The metrics (:func:`mtbmj.ride.advice_rules.ride_metrics`) of several rides taken together
    (see the module doc)."""
    w = np.array([m["duration_s"] for m in ms], float)
    total = float(w.sum())
    out = {}
    for end in ("front", "rear"):
        es = [m[end] for m in ms]
        e = {}
        for k in es[0]:
            vals = [x.get(k) for x in es]
            if any(v is None for v in vals):
                e[k] = None
            elif k == "travel_mm":
                e[k] = vals[0]
            elif k == "max_travel_percent":
                e[k] = float(max(vals))
            elif k == "bottom_outs":
                e[k] = int(sum(vals))
            else:
                e[k] = float(np.dot(w, vals) / total)
        e["bottom_outs_per_minute"] = e["bottom_outs"] / max(total, 1e-9) * 60.0
        c, r = e["p95_compression_mm_per_s"], e["p95_rebound_mm_per_s"]
        e["rebound_over_compression"] = r / c if c > 0 else None
        out[end] = e
    out["balance_points"] = out["front"]["dynamic_sag_percent"] - out["rear"]["dynamic_sag_percent"]
    out["duration_s"] = total
    acc = [m.get("rider_acceleration_rms_m_per_s2") for m in ms]
    if all(a is not None for a in acc):
        out["rider_acceleration_rms_m_per_s2"] = float(math.sqrt(np.dot(w, np.square(acc)) / total))
    return out


def pool_runs(runs: list, label: str | None = None) -> Run:
    """One run of each ride as one run: its metrics pooled, its series one after the other (each
    ride's time shifted past the last's), the first crash; ``parts`` the rides' own runs."""
    shift, times = 0.0, []
    for r in runs:
        times.append(r.time_s + shift)
        shift = float(times[-1][-1]) + 1.0
    m = pool_metrics([r.metrics for r in runs])
    run = Run(label or runs[0].label, runs[0].overrides, m, penalties(m),
              np.concatenate([r.front_mm for r in runs]), np.concatenate([r.rear_mm for r in runs]),
              next((f"{r.label} on ride {i + 1}: {r.crash}" for i, r in enumerate(runs) if r.crash), None),
              np.concatenate(times), list(runs))
    return run


@dataclass
class PooledAdvice(Advice):
    """The advice of several rides of one setting (:func:`pooled`): an :class:`Advice` whose runs are
    pooled (:func:`pool_runs`), ``rides`` each ride's own (one-step) advice, ``refused`` the rides left
    out ({"ride", "why"})."""

    rides: list = field(default_factory=list)
    refused: list = field(default_factory=list)

    def _run_segments(self, run: Run) -> list:
        return [s for ride, part in zip(self.rides, run.parts) for s in ride._run_segments(part)]

    def _record_segments(self) -> list:
        return [s for ride in self.rides for s in ride._record_segments()]

    def pooled_run(self, runs: list) -> Run:
        return pool_runs(runs)

    def levelled(self, run: Run) -> Run:
        """``run``'s static sags levelled (``Advice.levelled``) ride by ride, each part by its own ride's
        calibration (each ride's rider moved by its own carried load), then pooled again."""
        if getattr(run, "levelled", False) or not run.parts or len(run.parts) != len(self.rides):
            return super().levelled(run)
        for ride, part in zip(self.rides, run.parts):
            ride.levelled(part)
        w = np.array([part.metrics["duration_s"] for part in run.parts], float)
        for end in ("front", "rear"):  # pooled again as pool_metrics pools it: weighted by the rides' lengths
            sags = [part.metrics[end].get("static_sag_percent") for part in run.parts]
            if all(v is not None for v in sags):
                run.metrics[end] = {**run.metrics[end], "static_sag_percent": float(np.dot(w, sags) / w.sum())}
        run.levelled = True
        return run

    def other_offsets(self) -> dict | None:
        """As ``Advice.other_offsets``, the rides' own, weighted by their lengths as the pooled metrics are
        (None where a ride has no other reading)."""
        cals = [ride.calibration for ride in self.rides]
        if not cals or any(c is None or getattr(c, "split", None) is None for c in cals):
            return None
        w = np.array([ride.base.metrics["duration_s"] for ride in self.rides], float)
        return {e: float(np.dot(w, [c.static_sag_offsets()[e] for c in cals]) / w.sum()) for e in ("front", "rear")}

    def each(self) -> list:
        """Each ride's own verdict: {"ride", "seconds", "answer", "change"} (the change in the rider's
        words, or None)."""
        out = []
        for r in self.rides:
            rec = r.recommendation if (r.verdict or {}).get("answer") == "change" else None
            out.append({"ride": r.ride, "seconds": r.base.metrics["duration_s"], "answer": r.verdict.get("answer"),
                        "why": r.verdict.get("why"), "change": None if rec is None else
                        {"key": rec["key"], "direction": rec["direction"], "setting": rec["setting"]},
                        "spring_scales": None if r.calibration is None else
                        {e: s.value for e, s in r.calibration.scales.items()}})
        return out

    def to_dict(self) -> dict:
        return {**super().to_dict(), "rides": self.each(), "refused": list(self.refused)}

    def line(self) -> str:
        out = super().line()
        if self.refused:
            out += "; left out of the pool: " + "; ".join(f"{r['ride']} ({r['why']})" for r in self.refused)
        return out


def _said(rec: dict | None) -> dict:
    """{adjuster key: direction} of a recommendation and the changes after it."""
    if rec is None:
        return {}
    return {**{t["key"]: t["direction"] for t in rec.get("then") or []}, rec["key"]: rec["direction"]}


def judge(advice: PooledAdvice) -> None:
    """:func:`judging` on the pooled advice's candidates as judged (each searched one where its search
    ended, else the one-step ones), its recommendation and verdict set."""
    advice.recommendation, advice.verdict = judging(advice, advice.judged or None)


def judging(advice: PooledAdvice, candidates=None) -> tuple:
    """The pooled verdict (``mtbmj.ride.advise.judge`` on the pooled runs), made inconclusive where
    the rides contradict each other or it: one ride's change (its recommendation or a change after it)
    the other way on the same adjuster than another's or the pooled one's, or a ride's change where
    the pooled answer is "keep"."""
    recommendation, verdict = judge_one(advice, candidates)
    rec = recommendation if verdict.get("answer") == "change" else None
    each = [(r.ride, r.recommendation if r.verdict.get("answer") == "change" else None) for r in advice.rides]
    ways: dict = {}
    for name, said in [(name, _said(r)) for name, r in each] + [("pooled", _said(rec))]:
        for key, direction in said.items():
            ways.setdefault(key, {}).setdefault(direction, []).append(name)
    crossed = {k: w for k, w in ways.items() if len(w) > 1}
    keep_crossed = verdict.get("answer") == "keep" and any(r is not None for _, r in each)
    if not crossed and not keep_crossed:
        return recommendation, verdict
    label = {a.name: a.label for a, *_ in advice.candidates}
    why = "; ".join(f"{label.get(k, k)}: " + ", ".join(f"{'raised' if d == 'up' else 'lowered'} by {' and '.join(n)}"
                                                        for d, n in w.items()) for k, w in crossed.items())
    if keep_crossed:
        why = (why + "; " if why else "") + "the pooled answer keeps, but " + ", ".join(
            f"{name} advises {r['label']} {'up' if r['direction'] == 'up' else 'down'}" for name, r in each if r)
    verdict = {"answer": "inconclusive", "why": f"the rides disagree ({why}): one setting should give one answer; "
                                                f"check that the rides share it, or record again"}
    if recommendation is not None:
        verdict["best_candidate"] = {k: recommendation[k] for k in ("setting", "key", "section", "config_key", "label",
                                                                     "direction", "from", "to", "changes")}
    return None, verdict


def repeated(records) -> str | None:
    """The line refusing a pool that holds one ride twice (the same travels on the same clock, under its own
    name or another's: a file given twice, or copied), else None. Pooled with itself a ride's segments count
    twice, and the spread its resampling reads narrows though nothing new was ridden."""
    seen = {}
    for record in records:
        series = (record.time_s, record.fork_mm, record.shock_mm, record.rear_mm)
        key = hashlib.sha256(b"|".join(b"-" if a is None else np.ascontiguousarray(a, float).tobytes()
                                       for a in series)).hexdigest()
        if key in seen:
            first, again = seen[key].name, record.name
            if first == again and seen[key].path != record.path:  # "example" and the shipped file, a copy elsewhere
                first, again = seen[key].path, record.path
            return (f"{again}: the same ride as {first} (the same travels on the same clock): a ride pooled with "
                    f"itself counts twice and narrows the spread without anything new ridden; give each ride once")
        seen[key] = record
    return None


def pooled(records, bike, overrides=None, duration: float | None = None, progress=None, workers: int = 2,
           tries=(), calibrated: bool = True, search: bool = True, static_sag_mm=None,
           carried_as: str = "rider", speeds=None) -> PooledAdvice:
    """One advice from ``records``, several rides of ``bike`` at one setting (``overrides``), as
    :func:`mtbmj.ride.advise.advise` gives for one (the module doc says how they are pooled). A ride
    refused is left out and named; none left: :class:`AdviseError` naming each ride's reason. ``speeds``: each
    ride's speed given (``reconstruct``'s ``speed=``, None where not), in the order of ``records``."""
    from contextlib import ExitStack

    from mtbmj.bike import spec as spec_mod
    from mtbmj.ride.reconstruct_speed import ReconstructError

    start = time.perf_counter()
    duration = checked_duration(duration)
    twice = repeated(records)
    if twice:
        raise AdviseError(twice)
    bike = spec_mod.resolve(bike)
    bike = bike.with_overrides(None) if bike.overrides else bike
    ready, refused = [], []
    for record, speed in zip(records, speeds or [None] * len(records)):
        try:
            ready.append(prepare(record, bike, overrides, duration, calibrated, True, tries, static_sag_mm, carried_as,
                                 speed))
        except (AdviseError, ReconstructError) as exc:
            refused.append({"ride": record.name, "why": str(exc)})
    jobs = [ride.jobs() for ride in ready]
    flat = [j for js in jobs for j in js]
    offsets = np.cumsum([0] + [len(js) for js in jobs])

    def refusable(i):
        k = int(np.searchsorted(offsets, i, side="right") - 1)
        return ready[k].refusable(i - int(offsets[k]))

    with ExitStack() as stack:
        pool = None
        if workers > 1 and len(flat) > 1:
            from mtbmj.workers import process_pool

            pool = stack.enter_context(process_pool(min(workers, len(flat))))
        runs = run_jobs(flat, pool, refusable, counter(progress, len(flat)))
        each, kept = [], []
        for k, ride in enumerate(ready):
            try:
                a = ride.assemble(runs[offsets[k]:offsets[k + 1]])
            except AdviseError as exc:
                refused.append({"ride": ride.record.name, "why": str(exc)})
                continue
            a.recommendation, a.verdict = judge_one(a)
            if any(e.ride == a.ride for e in each):  # two files of one name told apart
                a.ride = f"{a.ride} (ride {k + 1})"
            each.append(a)
            kept.append(ride)
        if not each:
            raise AdviseError(f"none of the {len(records)} rides can be advised on: "
                              + "; ".join(r["why"] for r in refused))
        advice = combine(each, refused)
        if calibrated and len(kept) > 1:  # one bike for the pool: its springs from every kept ride's balances
            from mtbmj.ride import calibrate as cal_mod
            from mtbmj.ride import reconstruct as rc

            advice.calibration = cal_mod.calibrate_pooled([rc.ridden_part(r.record)[0] for r in kept], bike,
                                                          overrides, duration, static_sag_mm, carried_as)
        decide(advice, kept, pool, search, judging)
    advice.wall_s = time.perf_counter() - start
    return advice


def combine(each: list, refused: list) -> PooledAdvice:
    """The rides' advices (each assembled) as one :class:`PooledAdvice`, not judged."""
    first = each[0]
    keys = [{(a.name, d): (a, d, v, r) for a, d, v, r in e.candidates} for e in each]
    cands = []
    for key, (a, d, v, _) in keys[0].items():
        if all(key in k for k in keys):
            cands.append((a, d, v, pool_runs([k[key][3] for k in keys], f"{a.label} {v:g}")))
    skipped = [dict(s, why=f"{e.ride}: {s['why']}") for e in each for s in e.skipped]
    tries = [(tr, pool_runs([e.tries[i][1] for e in each])) for i, (tr, _) in enumerate(first.tries)]
    shift, times = 0.0, []
    for e in each:
        times.append(e.record_t + shift)
        shift = float(times[-1][-1]) + 1.0
    n = len(each)
    recon = {"rides": {e.ride: e.reconstruction for e in each},
             "speed_m_per_s": float(np.mean([e.reconstruction["speed_m_per_s"] for e in each])),
             # the check as the worst ride's: every number the largest miss (the least checked)
             "checks": {k: (min if k == "samples_checked_percent" else max)(e.reconstruction["checks"][k] for e in each)
                        for k, v in first.reconstruction["checks"].items()
                        if isinstance(v, (int, float)) and not isinstance(v, bool)}}
    return PooledAdvice(f"{n} rides ({', '.join(e.ride for e in each)})", first.bike, recon,
                        pool_metrics([e.measured for e in each]), pool_runs([e.base for e in each]), cands, None,
                        np.concatenate([e.record_front for e in each]), np.concatenate([e.record_rear for e in each]),
                        skipped=skipped, tries=tries, record_t=np.concatenate(times), calibration=first.calibration,
                        rides=each, refused=refused)


__all__ = ["PooledAdvice", "combine", "judge", "judging", "pool_metrics", "pool_runs", "pooled"]

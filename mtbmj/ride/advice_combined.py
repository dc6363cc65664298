"""The combined step after the recommended change (issue 52 item 2: "for each adjuster a line search
within what the part allows ..., then a combined step; it stops when the stated rules are met and
says which rule drove the change").

The verdict (:mod:`mtbmj.ride.advice_verdict`) recommends one change and lists the other advised
changes after it (``recommendation["then"]``), each found from the recorded setting. Here, after the
recommended change is chosen (and kept as it is), every one of those other adjusters is searched
again **from the recommended setting**: its one-step candidate in the advised direction ridden on
the bike with the recommended change, and, where that lowers the penalty by ``MIN_GAIN`` or more
below the recommended change's, the same line search as before
(``mtbmj.ride.advise.search_on``, its runs in the same pool, each search going on as its runs
end). An adjuster **joins** the combined step where its search's end lowers the penalty by
``MIN_GAIN`` or more below the recommended change's and a metric of a rule it improves moves beyond
the uncertainty of that change (the ride's segments, as every change's: ``Advice.change_uncertainty`` from it).
The recommended change and those that join are then ridden as one candidate (one run more where two
or more join; one alone is its own search's end) and judged like any other: its penalty against the
recorded setting's, a metric of a rule it improves moving beyond its uncertainty, and against the
recommended change's again (a combination the ends' coupling spoils is not advised; the best one
joined alone is then). **The stop** (``STOP_RULE``): an adjuster that does not lower the penalty by
``MIN_GAIN`` beyond its uncertainty from the recommended setting is left where it is; one round
(the adjusters searched once from the recommended setting, not again from the combination). Each
change says the rule that drove it (the rule whose penalty fell most from the recommended setting
to its search's end). One ride only (a pooled advice keeps its "then" from the recorded setting).

The rider still rides the recommended change first and records again: the combined step is the
model's prediction of where the rest goes after it, not a setting to ride untested."""
from __future__ import annotations

import dataclasses
from concurrent.futures import Future
from types import SimpleNamespace

from mtbmj.errors import ConfigError
from mtbmj.ride.advice_rules import MIN_GAIN, beyond, flat_metrics
from mtbmj.ride.advice_search import driving_rule
from mtbmj.ride.advice_verdict import changes

STOP_RULE = (f"an adjuster joins the recommended change where, searched from the recommended setting, it lowers "
             f"the penalty by {MIN_GAIN:g} or more below the recommended change's and a metric of a rule it improves "
             f"moves beyond that change's uncertainty; the search stops where no other adjuster does")


class _Counted:
    """The pool (or, where there is none, runs here at once) counting the runs started."""

    def __init__(self, pool):
        self.pool, self.runs = pool, 0
        self.workers = 1 if pool is None else pool.workers

    def submit(self, fn, *args):
        self.runs += 1
        if self.pool is not None:
            return self.pool.submit(fn, *args)
        done = Future()
        try:
            done.set_result(fn(*args))
        except Exception as exc:  # noqa: BLE001 - raised again where it is read, as the pool's would be
            done.set_exception(exc)
        return done


def lowers(advice, run, start) -> tuple[bool, list]:
    """(whether ``run`` lowers the penalty by ``MIN_GAIN`` or more below ``start``'s with a metric of a rule
    it improves moving beyond its uncertainty, those rules); a crash or a refusal never does."""
    if isinstance(run, Exception) or run.crash:
        return False, []
    improved = [k for k in start.penalty if run.penalty[k] < start.penalty[k] - 1e-9]
    ok = (start.total - run.total >= MIN_GAIN
          and bool(beyond(improved, flat_metrics(start.metrics), flat_metrics(run.metrics),
                          advice.change_uncertainty(run, start))))
    return ok, improved


def combine(advice, ride, pool, run_jobs, search_on, allowed) -> dict | None:
    """The combined step of ``advice`` (its recommendation chosen, ``ride`` its one
    ``mtbmj.ride.advise.Prepared``; ``run_jobs``, ``search_on`` and ``allowed`` advise's, given so that
    this module does not import it back): each adjuster of ``recommendation["then"]`` searched from the
    recommended setting, those that join and the recommended change ridden as one (the module doc).
    Writes ``recommendation["combined"]`` and each "then" entry's ``after_recommended``; returns the
    combined dict (None where nothing follows the recommended change)."""
    rec = advice.recommendation
    if rec is None or not rec.get("then"):
        return None
    counted = _Counted(pool)
    r_adj, _, r_val, r_run = next(c for c in advice.judged if c[0].name == rec["key"] and c[1] == rec["direction"])
    moved = dataclasses.replace(ride, base_over=ride.merged(r_adj.overrides(r_val)))  # the recommended setting
    firsts, refused = [], []
    for t in rec["then"]:
        adj, d, v, _ = next(c for c in advice.candidates if c[0].name == t["key"] and c[1] == t["direction"])
        (firsts if allowed(moved.bike, [(adj, d, v)], moved.merged)[0] else refused).append((adj, d, v))
    jobs = [moved.job(moved.merged(a.overrides(v)), f"{a.label} {v:g} after the recommended change")
            for a, d, v in firsts]
    runs = run_jobs(jobs, counted, lambda i: True, lambda: None)
    for run in runs:
        if not isinstance(run, Exception):
            advice.score(run)
    proxy = SimpleNamespace(base=r_run, score=advice.score, pooled_run=advice.pooled_run,  # scored on the ride as
                            candidates=[(a, d, v, r) for (a, d, v), r in zip(firsts, runs)  # every run, the search
                                        if not isinstance(r, Exception)])  # from the recommended change's
    searched = search_on(proxy, [moved], counted)
    steps, joined = [], []
    for (a, d, v), first in zip(firsts, runs):
        kept = searched.get((a.name, d)) or []
        value, end = kept[-1] if kept else (v, first)
        ok, improved = lowers(advice, end, r_run)
        crash = end.crash if not isinstance(end, Exception) else str(end)
        step = {"key": a.name, "label": a.label, "direction": d, "config_key": a.key, "setting": a.setting(value),
                "to": value, "search": [{"to": x, "setting": a.setting(x), "penalty": r.total} for x, r in kept],
                "penalty_from": r_run.total, "penalty_to": None if isinstance(end, Exception) else end.total,
                "crash": crash, "improves": improved, "joins": ok,
                "driven_by": driving_rule(r_run.penalty, end.penalty) if ok else None}
        steps.append(step)
        if ok:
            joined.append((a, value, end, step))
    for a, d, v in refused:
        steps.append({"key": a.name, "label": a.label, "direction": d, "config_key": a.key, "setting": a.setting(v),
                      "to": v, "search": [], "penalty_from": r_run.total, "penalty_to": None, "crash": None,
                      "improves": [], "joins": False, "driven_by": None,
                      "refused": "the part does not allow it with the recommended change"})
    for t in rec["then"]:
        s = next(s for s in steps if s["key"] == t["key"])
        t["after_recommended"] = {"setting": s["setting"], "penalty_to": s["penalty_to"], "joins": s["joins"],
                                  "driven_by": s["driven_by"]}
    combo, note = _ridden(advice, moved, counted, joined, r_run, run_jobs)
    base = advice.base
    out = {"rule": STOP_RULE, "recommended": rec["setting"], "changes": steps,
           "joined": [s["key"] for _, _, _, s in joined], "penalty_from": base.total, "penalty_recommended": r_run.total,
           "runs": counted.runs, "note": note}
    if combo is not None:
        u = advice.change_uncertainty(combo)
        improved = [k for k in base.penalty if combo.penalty[k] < base.penalty[k] - 1e-9]
        out.update({"setting": [rec["setting"]] + [s["setting"] for *_, s in joined],
                    "penalty_to": combo.total, "driven_by": driving_rule(base.penalty, combo.penalty),
                    "advised": not combo.crash and base.total - combo.total >= MIN_GAIN
                    and bool(beyond(improved, flat_metrics(base.metrics), flat_metrics(combo.metrics), u)),
                    "predicted": changes(base, combo, u, advice.measured),
                    "overrides": combo.overrides})
    rec["combined"] = out
    return out


def _ridden(advice, moved, counted, joined, r_run, run_jobs):
    """(the combined step's run, a note): none where nothing joined; one joined, its search's end; two or
    more, the recommended change and all of them ridden as one, kept where it lowers the penalty by
    ``MIN_GAIN`` beyond its uncertainty below the recommended change's, else the best one joined alone."""
    if not joined:
        return None, "no other adjuster lowers the penalty beyond its uncertainty after the recommended change"
    if len(joined) == 1:
        return joined[0][2], "one adjuster joins: its search's end is the combined step"
    over = {}
    for a, value, _, _ in joined:
        for k, v in a.overrides(value).items():
            over[k] = {**over.get(k, {}), **v}
    try:
        run = run_jobs([moved.job(moved.merged(over), "the combined step")], counted, lambda i: True, lambda: None)[0]
    except ConfigError as exc:  # pragma: no cover - run_jobs keeps a refusal as its result
        run = exc
    if not isinstance(run, Exception):
        advice.score(run)
    if lowers(advice, run, r_run)[0] and all(run.total <= j[2].total for j in joined):
        return run, f"{len(joined)} adjusters joined and ridden as one"
    best = min(joined, key=lambda j: j[2].total)
    for j in joined:
        if j is not best:  # joined, but not with the rest: the coupling of the ends spoils it
            j[3]["joins"], j[3]["spoils_the_combination"] = False, True
    del joined[:]
    joined.append(best)
    return best[2], ("the adjusters joined ridden as one do no better than the best alone "
                     f"({'a refusal' if isinstance(run, Exception) else f'{run.total:.2f}'}): the best alone is the step")


def then_line(advice) -> str:
    """The terminal's and report's line after the recommended change: the values found after it where
    the combined step was searched, else the other changes found from the recorded setting."""
    rec = advice.recommendation or {}
    rest = rec.get("then") or []
    if not rest or (advice.verdict or {}).get("answer", "change") != "change":
        return ""
    comb = rec.get("combined")

    def said(st):
        return (f"{'raise' if st['to'] > st['from'] else 'lower'} the {st['part']} {st['adjuster']} from "
                f"{st['from']:g} to {st['to']:g} {st['unit']}")
    if comb is None:
        return "Then, one at a time, recording again after each (each predicted from the recorded setting): " + "; ".join(
            f"{'raise' if t['setting']['to'] > t['setting']['from'] else 'lower'} the {t['label']} from "
            f"{t['setting']['from']:g} to {t['setting']['to']:g} {t['setting']['unit']}" for t in rest)
    left = [s for s in comb["changes"] if not s["joins"]]
    tail = ("" if not left else "; " + ", ".join(s["label"] for s in left) + " left as recorded (no gain of "
            f"{MIN_GAIN:g} beyond its uncertainty after the recommended change)")
    if not comb["joined"]:
        return ("Then nothing more: searched again from the recommended setting, " + ", ".join(s["label"] for s in left)
                + f" no longer lower the penalty by {MIN_GAIN:g} beyond their uncertainty; record again after it")
    steps = [s for s in comb["changes"] if s["key"] in comb["joined"]]
    return ("Then, after riding the recommended change and recording again (found from the recommended setting; "
            f"together predicted {comb['penalty_recommended']:.2f} -> {comb['penalty_to']:.2f}): "
            + "; ".join(f"{said(s['setting'])} (driven by the {s['driven_by'].replace('_', ' ')} rule)" for s in steps)
            + tail)


__all__ = ["STOP_RULE", "combine", "lowers", "then_line"]

"""The advice's verdict (``mtbmj advise``; the rules and why in ``mtbmj.ride.advise``'s module text):
:func:`judge` reads the candidates, each scored on the ride, against their uncertainty and gives the
recommendation (the balance of the ends first) or "keep" or "inconclusive" with the reason;
:func:`changes` is every metric's predicted change from the recorded setting, its uncertainty and
the value expected on the rider's ride. Split from ``mtbmj.ride.advise`` by role."""
from __future__ import annotations

import math

from mtbmj.ride.advice_rules import MIN_GAIN, beyond, expected, flat_metrics, grip_comfort, rule_metric


def judge(advice, candidates=None) -> tuple[dict | None, dict]:
    """(the recommendation or None, the verdict ``{"answer", "why"}``): a change is advised only where
    it lowers the penalty by ``MIN_GAIN`` or more and a metric of a rule it improves moves by more
    than that change's uncertainty (the best such candidate, grip and comfort breaking ties);
    "keep" only where every candidate is predicted worse beyond its uncertainty (a crash is worse);
    otherwise "inconclusive", naming why. ``candidates``: those judged (default the one-step ones;
    :func:`advise` passes each searched candidate where its search ended)."""
    base, measured = advice.score(advice.base), advice.measured
    candidates = advice.candidates if candidates is None else candidates
    for *_, run in candidates:  # each scored on the ride (Advice.score; the same scores again where they were)
        advice.score(run)
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
        if gain >= MIN_GAIN and beyond(improved, a, b, u):
            good.append((score, adj, direction, value, run, improved, u))
        elif gain <= -MIN_GAIN and beyond(worsened, a, b, u):
            worse += 1
        elif gain >= MIN_GAIN and (near is None or score > near[0]):
            near = (score, adj, direction, value, run, improved, u)
    n = len(candidates)
    if good:  # the balance of the ends first: a change that mends it before any other
        pick = max([g for g in good if "balance" in g[5] and beyond(["balance"], a, flat_metrics(g[4].metrics), g[6])]
                   or good, key=lambda g: g[0])
        _, adj, direction, value, run, improved, u = pick
        then = [{"setting": g[1].setting(g[3]), "key": g[1].name, "label": g[1].label, "direction": g[2],
                 "penalty_to": g[4].total, "improves": g[5]}
                for g in sorted(good, key=lambda g: -g[0]) if g[1].name != adj.name]
        moved = beyond(improved, a, flat_metrics(run.metrics), u)
        st = adj.setting(value)
        why = (f"{'raise' if direction == 'up' else 'lower'} the {adj.label} from {st['from']:g} to {st['to']:g} "
               f"{st['unit']} ({st['key']}): the penalty falls {base.total:.2f} -> {run.total:.2f} "
               f"({', '.join(k.replace('_', ' ') for k in improved)}; "
               + ", ".join(f"{m} {a[m]:.3g} -> {flat_metrics(run.metrics)[m]:.3g} +- {u[m]:.2g}" for m in moved) + ")")
        rec = {"setting": adj.setting(value), "key": adj.name, "section": adj.section, "config_key": adj.key,
               "label": adj.label,
               "direction": direction, "from": adj.value, "to": value, "penalty_from": base.total,
               "penalty_to": run.total, "improves": improved, "confident": True, "why": why,
               "changes": changes(base, run, u, measured),
               "then": [t for i, t in enumerate(then) if t["key"] not in {o["key"] for o in then[:i]}]}  # best first
        return rec, {"answer": "change", "why": why}
    if n and worse == n:
        return None, {"answer": "keep", "why": f"every one of the {n} candidates is predicted worse beyond its "
                                               f"uncertainty (or crashes)"}
    if not n:
        return None, {"answer": "inconclusive", "why": "no candidate was simulated"}
    if near is not None:
        _, adj, direction, value, run, improved, u = near
        b = flat_metrics(run.metrics)
        ms = list(dict.fromkeys(rule_metric(k) for k in improved))
        return None, {"answer": "inconclusive",
                      "why": f"the best candidate, the {adj.label} {adj.setting(value)['from']:g} -> "
                             f"{adj.setting(value)['to']:g} {adj.unit}, lowers the penalty "
                             f"{base.total:.2f} -> {run.total:.2f}, but what it improves moves less than its "
                             f"uncertainty ("
                             + ", ".join(f"{m} {a[m]:.3g} -> {b[m]:.3g} +- {u.get(m, math.inf):.2g}" for m in ms if m in b)
                             + "): try it and record again",
                      "best_candidate": {"setting": adj.setting(value), "key": adj.name, "section": adj.section,
                                         "config_key": adj.key, "label": adj.label, "direction": direction,
                                         "from": adj.value, "to": value, "changes": changes(base, run, u, measured)}}
    return None, {"answer": "inconclusive",
                  "why": f"no candidate of {n} lowers the penalty by {MIN_GAIN:g} or more beyond its uncertainty, "
                         f"and {n - worse} of them are not predicted worse beyond it either: the ride cannot tell "
                         f"these settings apart"}


def changes(base, run, uncertainty: dict, measured: dict) -> dict:
    """Per metric (``flat_metrics`` name): the simulated value at the recorded setting (``from``) and at
    ``run``'s (``to``), the change, its uncertainty, the recorded value and the one expected on the
    rider's ride (:func:`expected`)."""
    a, b, rode = flat_metrics(base.metrics), flat_metrics(run.metrics), flat_metrics(measured)
    return {k: {"from": v0, "to": b[k], "change": b[k] - v0, "uncertainty": uncertainty.get(k),
                "recorded": rode.get(k), "expected": expected(k, rode[k], v0, b[k]) if k in rode else b[k]}
            for k, v0 in a.items() if k in b}


__all__ = ["changes", "judge"]

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
    good, worse, near, split = [], 0, None, None
    other_base = advice.other_reading(base) if hasattr(advice, "other_reading") else None
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
            other = _other_gain(advice, other_base, run, a, b, u)
            if other is None or other[1]:
                good.append((score, adj, direction, value, run, improved, u))
            elif split is None or score > split[0][0]:  # not a change on the calibration's other reading
                split = ((score, adj, direction, value, run, improved, u), other[0])
        elif gain <= -MIN_GAIN and beyond(worsened, a, b, u):
            worse += 1
        elif gain >= MIN_GAIN and (near is None or score > near[0]):
            near = (score, adj, direction, value, run, improved, u)
    n = len(candidates)
    if good:  # the balance of the ends first: a change that mends it before any other
        pool = [g for g in good if "balance" in g[5] and beyond(["balance"], a, flat_metrics(g[4].metrics), g[6])] or good
        best = max(pool, key=lambda g: g[0])
        tied = ties(best, pool)
        pick = min([best] + tied, key=lambda g: (setup_rank(g[1].key), -g[0]))
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
        if tied:  # the candidates the ride cannot tell apart from the best: the setup guides' order decides
            others = [g for g in [best] + tied if g is not pick]
            why += ("; " + ", ".join(f"the {g[1].label} {g[1].setting(g[3])['from']:g} -> {g[1].setting(g[3])['to']:g} "
                                     f"{g[1].setting(g[3])['unit']}" for g in others)
                    + f" would do as well within the uncertainty, and {SETUP_ORDER_WHY}")
        rec = {"setting": adj.setting(value), "key": adj.name, "section": adj.section, "config_key": adj.key,
               "label": adj.label,
               "direction": direction, "from": adj.value, "to": value, "penalty_from": base.total,
               "penalty_to": run.total, "improves": improved, "confident": True, "why": why,
               "changes": changes(base, run, u, measured),
               "then": [t for i, t in enumerate(then) if t["key"] not in {o["key"] for o in then[:i]}],  # best first
               "tied_with": [{"setting": g[1].setting(g[3]), "key": g[1].name, "label": g[1].label,
                              "penalty_to": g[4].total} for g in [best] + tied if g is not pick]}
        return rec, {"answer": "change", "why": why}
    if n and worse == n:
        return None, {"answer": "keep", "why": f"every one of the {n} candidates is predicted worse beyond its "
                                               f"uncertainty (or crashes)"}
    if not n:
        return None, {"answer": "inconclusive", "why": "no candidate was simulated"}
    if split is not None:
        from mtbmj.ride.calibrate import carried_words

        (_, adj, direction, value, run, improved, u), other_total = split
        st, cal = adj.setting(value), advice.calibration
        return None, {"answer": "inconclusive",
                      "why": f"the best candidate, the {adj.label} {st['from']:g} -> {st['to']:g} {st['unit']}, lowers "
                             f"the penalty {base.total:.2f} -> {run.total:.2f} with the springs as calibrated ("
                             + ", ".join(f"{sc.adjuster.label} x{sc.value:.2f}" for sc in cal.scales.values())
                             + f"), but not on the calibration's other reading of the same ride, both springs "
                             f"x{cal.split.common:.2f} with {carried_words(cal.split.shift_N, cal.split.place_mm, cal.split.slope_deg)} "
                             f"({sum(other_base.values()):.2f} -> "
                             f"{other_total:.2f}, its static sags "
                             + ", ".join(f"{e} {b_:.0f} %" for e, (_, b_) in cal.split.static_sag.items())
                             + "): the travel cannot tell a spring off from a load carried fore-aft (a descent, "
                             "braking, the rider's stance); measure the static sag standing on level ground",
                      "best_candidate": {"setting": st, "key": adj.name, "section": adj.section,
                                         "config_key": adj.key, "label": adj.label, "direction": direction,
                                         "from": adj.value, "to": value, "changes": changes(base, run, u, measured)}}
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


def _other_gain(advice, other_base, run, a, b, u):
    """(the penalty's total, whether it is a change) of ``run`` on the calibration's other reading of the
    ride (``Advice.other_reading``: the static sags as one spring scale and a load carried fore-aft give
    them): a change there too lowers the penalty by ``MIN_GAIN`` or more, a metric of a rule it improves
    moving beyond its uncertainty. None where there is no other reading."""
    if other_base is None:
        return None
    other = advice.other_reading(run)
    improved = [k for k in other_base if other[k] < other_base[k] - 1e-9]
    total = sum(other.values())
    return total, sum(other_base.values()) - total >= MIN_GAIN and beyond(improved, a, b, u)


# Where the ride cannot tell two changes apart, the spring (or air pressure, or volume spacers) first, then
# rebound, then compression: the order the setup guides give (sag, set by the spring, "long before you touch
# any of your hydraulic adjustments": "Refresher course: mountain bike suspension tuning for dummies",
# Mountain Bike Action, mbaction.com; sag, then rebound, then compression in the usual step-by-step guides)
SETUP_ORDER_WHY = ("the spring comes before the dampers where the ride cannot choose (sag first, then rebound, "
                   "then compression, as setup guides order them)")


def setup_rank(key: str) -> int:
    """0 for a spring, air pressure or volume spacers, 1 rebound, 2 compression, 3 anything else (a
    tyre's pressure): the setup guides' order (``SETUP_ORDER_WHY``)."""
    k = key.lower()
    if "spring" in k or "pressure_psi" in k and not k.startswith("tire") or "tokens" in k:
        return 0
    return 1 if "rebound" in k else 2 if "compression" in k else 3


def ties(best, pool) -> list:
    """The candidates of ``pool`` (judge's tuples) on another adjuster than ``best`` that the ride cannot
    tell apart from it: no metric of the rules either improves moves between the two by more than the
    larger of their uncertainties. A near-tie in the penalty alone (13.74 against 13.96 on a soft fork's
    ride) let whichever search went furthest decide the answer, and a crash at one step could end it."""
    a = flat_metrics(best[4].metrics)
    out = []
    for g in pool:
        if g is best or g[1].name == best[1].name:
            continue
        u = {m: max(best[6].get(m, math.inf), g[6].get(m, math.inf)) for m in set(best[6]) | set(g[6])}
        if not beyond(set(best[5]) | set(g[5]), a, flat_metrics(g[4].metrics), u):
            out.append(g)
    return out


def changes(base, run, uncertainty: dict, measured: dict) -> dict:
    """Per metric (``flat_metrics`` name): the simulated value at the recorded setting (``from``) and at
    ``run``'s (``to``), the change, its uncertainty, the recorded value and the one expected on the
    rider's ride (:func:`expected`)."""
    a, b, rode = flat_metrics(base.metrics), flat_metrics(run.metrics), flat_metrics(measured)
    return {k: {"from": v0, "to": b[k], "change": b[k] - v0, "uncertainty": uncertainty.get(k),
                "recorded": rode.get(k), "expected": expected(k, rode[k], v0, b[k]) if k in rode else b[k]}
            for k, v0 in a.items() if k in b}


__all__ = ["changes", "judge", "ties", "setup_rank", "SETUP_ORDER_WHY"]

"""The advice's line search (issue 52 item 2): from the best one-step candidate the verdict picks,
further along the same adjuster, within what the part allows, until the penalty stops improving.

**Steps** (:func:`next_value`): clicks and volume spacers by the candidate's own step (two clicks,
one spacer), tyre pressure by its 2 psi; a spring, an air pressure or a damper coefficient by the
candidate's ratio again (x1.1, x0.8 ...), a coil spring rounded to the rates sold
(``SOLD_LB_PER_IN`` in the bike file's lb/in). A value outside what any part has
(``mtbmj.config.PLAUSIBLE``) or one the part refuses (``mtbmj.ride.advise.allowed``: a click outside
the measured range) ends the search there.

**Stop** (:func:`search`): two steps are simulated at a time (in parallel); the farther one is kept
only where it lowers the penalty by ``MIN_GAIN`` (the verdict's own threshold) or more below the
best so far without a crash, and the search goes on from it; at most ``MAX_STEPS`` steps. The rule
that drove the change is the one whose penalty fell most from the recorded setting to the answer.
"""
from __future__ import annotations

from mtbmj.ride.advice_rules import MIN_GAIN, SOLD_LB_PER_IN, Adjuster, bounded_value

MAX_STEPS = 8  # steps beyond the one-step candidate, at most
ADDITIVE_UNITS = ("clicks", "spacers")


def next_value(adj: Adjuster, value: float, first: float) -> float | None:
    """The next value of ``adj`` past ``value`` along the direction of its first candidate ``first``
    (from ``adj.value``), or None where the part has none (outside ``PLAUSIBLE``)."""
    if first == adj.value:
        return None
    if adj.unit in ADDITIVE_UNITS or adj.key == "tire.pressure_psi":
        nxt = value + (first - adj.value)
        if nxt < 0:  # click 0 and no spacer are positions; below them none
            return None
    else:
        nxt = value * (first / adj.value)
        if adj.unit == "lb/in":  # a coil: the rates sold, in the file's lb/in (per_unit carries the calibration)
            sold = round(nxt / adj.per_unit / SOLD_LB_PER_IN) * SOLD_LB_PER_IN
            nxt = sold * adj.per_unit
            if (nxt - value) * (first - adj.value) <= 0:
                nxt = (sold + SOLD_LB_PER_IN * (1 if first > adj.value else -1)) * adj.per_unit
        nxt = float(f"{nxt:.6g}")
        if nxt <= 0:
            return None
    return bounded_value(adj.key, nxt)


def search(adj: Adjuster, first: float, best_run, base_total: float, run_values, allowed_value) -> list:
    """The line search from ``first`` (the one-step candidate, its run ``best_run``): ``run_values``
    simulates a list of values (runs in order; a refused one a ``ConfigError``), ``allowed_value``
    tells whether the part allows a value. Returns the steps ``[(value, run)]`` kept, the last the
    answer (empty where none improved on the candidate)."""
    kept = []
    value, best = first, best_run
    steps = 0
    while steps < MAX_STEPS:
        batch = []
        v = value
        for _ in range(2):
            v = next_value(adj, v, first)
            if v is None or not allowed_value(v):
                break
            batch.append(v)
        if not batch:
            break
        runs = run_values(batch)
        steps += len(batch)
        moved = False
        for v, run in zip(batch, runs):
            if isinstance(run, Exception) or run.crash or not run.total <= best.total - MIN_GAIN:
                break
            value, best, moved = v, run, True
            kept.append((v, run))
        if not moved or len(kept) and kept[-1][0] != batch[-1]:
            break
    return kept


def driving_rule(base_penalty: dict, penalty: dict) -> str:
    """The rule whose penalty fell most from ``base_penalty`` to ``penalty``."""
    return max(base_penalty, key=lambda k: base_penalty[k] - penalty.get(k, 0.0))


__all__ = ["MAX_STEPS", "driving_rule", "next_value", "search"]

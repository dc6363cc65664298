"""The advice's line search (issue 52 item 2): from every one-step candidate that lowers the penalty
by ``MIN_GAIN`` or more, further along the same adjuster, within what the part allows, until the
penalty stops improving; the verdict then judges each searched candidate where it ended (a rebound
four times too slow is not reached by one x0.8 step, and a spring's one step can look better than
it until both are searched).

**Steps** (:func:`next_value`): clicks and volume spacers by the candidate's own step (two clicks,
one spacer), tyre pressure by its 2 psi; a spring, an air pressure or a damper coefficient by the
candidate's ratio again (x1.1, x0.8 ...), a coil spring rounded to the rates sold
(``SOLD_LB_PER_IN`` in the bike file's lb/in). A value outside what any part has
(``mtbmj.config.PLAUSIBLE``) or one the part refuses (``mtbmj.ride.advise.allowed``: a click outside
the measured range) ends the search there.

**Stop** (:func:`search`, :func:`search_many` for all of them at once): each step is kept only where
it lowers the penalty by ``MIN_GAIN`` (the verdict's own threshold) or more below the best so far
without a crash, and the search goes on from it; at most ``MAX_STEPS`` steps. A step where the model
crashed is passed over once (``CRASH_PATIENCE``): a crash on the reconstructed terrain can hang on a
hair (the made soft-fork ride loops out at 28.5 s of 30 at 5.87 N/mm and rides home at 5.0, 6.5, 8
and 11), so the search asks the step after it, keeps going if that one rides home and is better than
the best before the crash, and stops otherwise; a crash passed over on the way to the answer is
listed with it (``passed``), and the answer itself never crashed. ``mtbmj advise`` runs
every search at once as its runs end (:func:`search_flow`): each search asks for its next step as soon
as its own last one is judged, the pool's processes kept busy with the steps every search needs (the
search fewest steps along first), and a process that would stand idle takes the step after one that
starts with it (at most ``LOOKAHEAD`` of one search in flight: a step past one that fails is a run
thrown away, in a slot that would have done nothing and ending about when that step does; one
started after a step long running would hold its process past the search's end). :func:`search_many` runs them one round at a time (a
round waits for its slowest run). The steps kept are the same either way and however the runs end
(each is judged against the one before it, in order). The rule
that drove the change is the one whose penalty fell most from the recorded setting to the answer.
"""
from __future__ import annotations

from mtbmj.ride.advice_rules import MIN_GAIN, SOLD_LB_PER_IN, Adjuster, bounded_value

MAX_STEPS = 8  # steps beyond the one-step candidate, at most
LOOKAHEAD = 2  # steps of one search asked in one round, at most
CRASH_PATIENCE = 1  # a step where the model crashes is passed over (once in a row) if the next one is better
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


def search_many(starts, run_values, allowed_value, per_round: int = LOOKAHEAD) -> list:
    """Line searches along several adjusters at once, each as :func:`search` does it: ``starts`` a list
    of ``(adjuster, first, run)`` (a one-step candidate and its run); each round asks every search
    still going for its next value, and for up to ``LOOKAHEAD`` where ``per_round`` (the values the
    pool runs at once) leaves room for them all, and ``run_values([(i, value), ...])`` simulates them
    all together (runs in order; a refused one a ``ConfigError``); ``allowed_value(i, value)`` tells
    whether search ``i``'s part allows a value. Returns each search's kept steps ``[(value, run)]``."""
    state = [_state(first, run) | {"steps": 0} for _, first, run in starts]
    while True:
        asks = []
        for s in state:
            s["done"] = s["done"] or s["steps"] >= MAX_STEPS
        going = sum(not s["done"] for s in state)
        ahead = max(1, min(LOOKAHEAD, per_round // max(going, 1)))
        for i, (adj, first, _) in enumerate(starts):
            s = state[i]
            if s["done"]:
                continue
            batch, v = [], s["at"]
            for _ in range(min(ahead, MAX_STEPS - s["steps"])):
                v = next_value(adj, v, first)
                if v is None or not allowed_value(i, v):
                    break
                batch.append(v)
            if not batch:
                s["done"] = True
                continue
            asks.append((i, batch))
        if not asks:
            break
        runs = run_values([(i, v) for i, batch in asks for v in batch])
        k = 0
        for i, batch in asks:
            s, got = state[i], runs[k:k + len(batch)]
            k += len(batch)
            s["steps"] += len(batch)
            for v, run in zip(batch, got):
                if not _judge(s, v, run):
                    s["done"] = True
                    break
    return _finish(state, starts)


def _state(first, run) -> dict:
    """A search's state: where it stands (``at``: the last value judged, from the one-step candidate
    ``first``), its best run so far, its steps kept, the crashes passed over (``over`` of them in a
    row), whether it is done."""
    return {"at": first, "best": run, "kept": [], "done": False, "over": 0, "passed": []}


def _judge(s: dict, v: float, run) -> bool:
    """Search ``s`` takes the step ``v`` and its run: passed over where the model crashed there (at most
    ``CRASH_PATIENCE`` in a row), kept where it lowers the best by ``MIN_GAIN`` or more without a crash;
    False where the search ends there (a refused run, a crash past the patience, no gain)."""
    if not isinstance(run, Exception) and run.crash and s["over"] < CRASH_PATIENCE:
        s["at"], s["over"] = v, s["over"] + 1  # passed over: the search goes on past it, keeping none
        s["passed"].append((v, run.crash))
        return True
    if isinstance(run, Exception) or run.crash or not run.total <= s["best"].total - MIN_GAIN:
        return False
    s["at"], s["best"], s["over"] = v, run, 0
    s["kept"].append((v, run))
    return True


def _finish(state, starts) -> list:
    """Each search's kept steps as a ``_Kept``, a crash passed over on the way to the answer said
    with it (one past the answer was a stop, not passed over)."""
    out = []
    for s, (adj, _, _) in zip(state, starts):
        kept = {v for v, _ in s["kept"]}
        last = s["kept"][-1][0] if s["kept"] else None
        out.append(_Kept(s["kept"], [(v, why) for v, why in s["passed"] if last is not None and v not in kept
                                     and (v - adj.value) * (last - v) > 0]))
    return out


def search_flow(starts, submit, wait, allowed_value, slots: int) -> list:
    """The searches of :func:`search_many` (the same values asked, each step judged as there, the same
    steps kept), each going on as soon as its own last step is judged, not a round at a time: a pool
    of ``slots`` processes is kept busy with the next step of every search still going (the steps
    every search needs first), and only where a process would otherwise stand idle with the step
    after one starting now (up to ``LOOKAHEAD`` of one search in flight: a step past one that fails
    is a run thrown away, but in a slot that would have done nothing; only beside a step that starts
    with it, so that it ends about when that step does). ``submit(i, value)`` starts
    search ``i``'s run of ``value`` and returns a handle; ``wait(handles)`` blocks until at least
    one of them has finished and returns ``[(handle, run), ...]`` for those finished (a refused run
    a ``ConfigError``); ``allowed_value(i, value)`` as in :func:`search_many`. Returns each search's
    kept steps ``[(value, run)]``."""
    state = [_state(first, run) | {"asked": [], "got": {}} for _, first, run in starts]
    flying = {}  # handle -> (search, value)

    def ask(i, s):  # the value after the last one asked (or judged), where the part has one
        v = s["asked"][-1] if s["asked"] else s["at"]
        if len(s["kept"]) + len(s["passed"]) + len(s["asked"]) >= MAX_STEPS:
            return False
        v = next_value(starts[i][0], v, starts[i][1])
        if v is None or not allowed_value(i, v):
            if not s["asked"]:
                s["done"] = True
            return False
        s["asked"].append(v)
        flying[submit(i, v)] = (i, v)
        return True

    def fill():
        fresh = []  # the searches whose next step starts now
        for i in sorted(range(len(state)), key=lambda i: len(state[i]["kept"])):  # every search's next step:
            s = state[i]  # needed (the search fewest steps along first, as the rounds have it)
            if len(flying) < slots and not s["done"] and not s["asked"] and ask(i, s):
                fresh.append(i)
        while len(flying) < slots:  # a process otherwise idle: the step after one starting with it (a step
            going = [(len(state[i]["asked"]), i) for i in fresh  # after one long running would hold its
                     if not state[i]["done"] and len(state[i]["asked"]) < LOOKAHEAD]  # process past its end)
            if not going or not ask(min(going)[1], state[min(going)[1]]):
                break

    fill()
    while flying:
        for handle, run in wait(list(flying)):
            i, v = flying.pop(handle)
            s = state[i]
            if s["done"] or v not in s["asked"]:
                continue  # a step past one that failed: thrown away
            s["got"][v] = run
            while s["asked"] and s["asked"][0] in s["got"]:  # judged in order, each against the one before
                v0 = s["asked"].pop(0)
                if not _judge(s, v0, s["got"].pop(v0)):
                    s["done"], s["asked"], s["got"] = True, [], {}
                    break
            if not s["done"] and not s["asked"] and len(s["kept"]) + len(s["passed"]) >= MAX_STEPS:
                s["done"] = True
        fill()
    return _finish(state, starts)


class _Kept(list):
    """A search's kept steps ``[(value, run)]``, and in ``passed`` the values passed over on the way to
    the last of them because the model crashed there ``[(value, the crash's line)]``."""

    def __init__(self, steps=(), passed=()):
        super().__init__(steps)
        self.passed = list(passed)


def search(adj: Adjuster, first: float, best_run, base_total: float, run_values, allowed_value,
           per_round: int = LOOKAHEAD) -> list:
    """The line search from ``first`` (the one-step candidate, its run ``best_run``): ``run_values``
    simulates a list of values (runs in order; a refused one a ``ConfigError``), ``allowed_value``
    tells whether the part allows a value. Returns the steps ``[(value, run)]`` kept, the last the
    answer (empty where none improved on the candidate)."""
    return search_many([(adj, first, best_run)], lambda asks: run_values([v for _, v in asks]),
                       lambda _, v: allowed_value(v), per_round)[0]


def driving_rule(base_penalty: dict, penalty: dict) -> str:
    """The rule whose penalty fell most from ``base_penalty`` to ``penalty``."""
    return max(base_penalty, key=lambda k: base_penalty[k] - penalty.get(k, 0.0))


def annotate(advice, searched: dict) -> None:
    """The recommendation's search (``search``: each step kept, ``driven_by``: the rule whose penalty
    fell most) and, where it went past the one-step candidate, that said in its why."""
    rec = advice.recommendation
    kept = searched.get((rec["key"], rec["direction"]), [])
    adj = next(a for a, d, v, r in advice.candidates if a.name == rec["key"] and d == rec["direction"])
    rec["search"] = [{"to": v, "setting": adj.setting(v), "penalty": r.total} for v, r in kept]
    run = kept[-1][1] if kept else next(r for a, d, v, r in advice.candidates
                                        if a.name == rec["key"] and d == rec["direction"])
    if kept:
        advice.searched = (adj, rec["direction"], kept[-1][0], run)
    rec["driven_by"] = driving_rule(advice.base.penalty, run.penalty)
    passed = getattr(kept, "passed", [])
    rec["search_passed_crashes"] = [{"to": v, "setting": adj.setting(v), "crash": why} for v, why in passed]
    if kept:
        values = ", ".join(f"{adj.setting(v)['to']:g}" for v, _ in passed)
        over = ("" if not passed else f", passing over {len(passed)} setting(s) where the model crashed on the "
                f"ride's terrain ({values} {adj.unit})")
        rec["why"] += (f"; found by searching on from the one-step candidate ({len(kept)} step(s) further{over}), "
                       f"driven by the {rec['driven_by'].replace('_', ' ')} rule")
        advice.verdict = {**advice.verdict, "why": rec["why"]}


__all__ = ["LOOKAHEAD", "MAX_STEPS", "annotate", "driving_rule", "next_value", "search", "search_flow",
           "search_many"]

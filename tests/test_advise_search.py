"""The advice's line search (issue 52 item 2; mtbmj/ride/advice_search.py): its steps within what the
part allows and its stop, on closed forms (a penalty made here as a function of the value)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from mtbmj.ride import advice_search
from mtbmj.ride.advice_rules import MIN_GAIN, Adjuster


def _adj(key="fork.spring.rate_N_per_mm", value=5.0, unit="N/mm", per_unit=1.0):
    return Adjuster("front", "fork.set", key, value, None, None, "fork spring rate", "", unit, per_unit)


def test_steps_repeat_the_candidate_s_ratio_or_step_within_the_part():
    a = _adj()
    assert advice_search.next_value(a, 5.5, 5.5) == pytest.approx(6.05)
    clicks = _adj("fork.damper.rebound_clicks", 8.0, "clicks")
    assert advice_search.next_value(clicks, 6.0, 6.0) == 4.0 and advice_search.next_value(clicks, 2.0, 6.0) == 0.0
    assert advice_search.next_value(clicks, 0.0, 6.0) is None  # below zero: no such click
    air = _adj("fork.spring.air_pressure_psi", 300.0, "psi")
    assert advice_search.next_value(air, 363.0, 330.0) == pytest.approx(399.3)
    assert advice_search.next_value(air, 364.0, 330.0) is None  # 400.4: past the 400 psi forks hold (PLAUSIBLE)
    # a coil sold in 25 lb/in steps: the next rate sold, in the file's lb/in (per_unit: N/mm per lb/in)
    coil = _adj("fork.spring.rate_N_per_mm", 450 * 0.1751, "lb/in", 0.1751)
    nxt = advice_search.next_value(coil, 500 * 0.1751, 500 * 0.1751)
    assert nxt / 0.1751 == pytest.approx(550.0)


def test_the_search_goes_on_while_the_penalty_falls_and_stops_at_its_floor():
    """A penalty (v - 8)^2 made here: from 5.5 by x1.1 steps the search passes 6.05, 6.66, 7.32, 8.05
    and stops where the next step does not lower it by MIN_GAIN."""
    a = _adj()
    run = lambda v: SimpleNamespace(total=(v - 8.0) ** 2, crash=None)  # noqa: E731
    asked = []

    def run_values(values):
        asked.append(list(values))
        return [run(v) for v in values]

    kept = advice_search.search(a, 5.5, run(5.5), run(5.0).total, run_values, lambda v: True)
    values = [v for v, _ in kept]
    assert values == pytest.approx([6.05, 6.655, 7.3205, 8.05255])
    assert all(len(b) <= 2 for b in asked)  # two at a time
    last = values[-1]
    assert (advice_search.next_value(a, last, 5.5) - 8.0) ** 2 > (last - 8.0) ** 2 - MIN_GAIN


def test_the_search_stops_at_what_the_part_refuses_or_a_crash():
    a = _adj()
    run = lambda v: SimpleNamespace(total=-v, crash=None)  # noqa: E731
    kept = advice_search.search(a, 5.5, run(5.5), 0.0, lambda vs: [run(v) for v in vs], lambda v: v < 7.0)
    assert [round(v, 3) for v, _ in kept] == [6.05, 6.655]
    crash = lambda v: SimpleNamespace(total=-v, crash="crashed" if v > 6.1 else None)  # noqa: E731
    kept = advice_search.search(a, 5.5, crash(5.5), 0.0, lambda vs: [crash(v) for v in vs], lambda v: True)
    assert [round(v, 3) for v, _ in kept] == [6.05]
    assert advice_search.driving_rule({"a": 1.0, "b": 3.0}, {"a": 0.5, "b": 0.2}) == "b"


def test_a_lone_crash_is_passed_over_and_said_two_in_a_row_stop_the_search():
    """A penalty -v made here with the model crashing at one value only (6.655, as the made soft-fork
    ride looped out at 5.87 N/mm and rode home at 6.5 and 8): the search passes over it, goes on to
    the part's limit, and names it in ``passed``; two crashes in a row end it before them; a crash
    after which the penalty does not fall below the best before it ends it there too; one past the
    answer is not listed."""
    a = _adj()
    lone = lambda v: SimpleNamespace(total=-v, crash="looped out" if abs(v - 6.655) < 1e-3 else None)  # noqa: E731
    kept = advice_search.search(a, 5.5, lone(5.5), 0.0, lambda vs: [lone(v) for v in vs], lambda v: v < 9.0)
    assert [round(v, 3) for v, _ in kept] == [6.05, 7.321, 8.053, 8.858]
    assert [(round(v, 3), why) for v, why in kept.passed] == [(6.655, "looped out")]
    assert not any(r.crash for _, r in kept)
    two = lambda v: SimpleNamespace(total=-v, crash="looped out" if 6.6 < v < 7.4 else None)  # noqa: E731
    kept = advice_search.search(a, 5.5, two(5.5), 0.0, lambda vs: [two(v) for v in vs], lambda v: v < 9.0)
    assert [round(v, 3) for v, _ in kept] == [6.05] and kept.passed == []
    worse = lambda v: SimpleNamespace(total=-v if v < 6.6 else 0.0, crash="x" if abs(v - 6.655) < 1e-3 else None)  # noqa: E731
    kept = advice_search.search(a, 5.5, worse(5.5), 0.0, lambda vs: [worse(v) for v in vs], lambda v: v < 9.0)
    assert [round(v, 3) for v, _ in kept] == [6.05] and kept.passed == []


def test_several_searches_at_once_end_where_each_alone_ends():
    """Two adjusters searched together (search_many): a spring whose penalty (v - 8)^2 falls from 5.5
    and a rebound damper whose penalty falls as it is lowered to a floor at 400 (from 2240 by x0.8,
    the one-step candidate of 2800). Each ends where its search alone ends, the runs of one round are
    asked for together (up to two per search), and a search that stops leaves the other going."""
    spring = _adj()
    rebound = _adj("fork.damper.rebound_N_s_per_m", 2800.0, "N s/m")
    pen = [lambda v: (v - 8.0) ** 2, lambda v: abs(v - 400.0) / 100.0]
    run = lambda i, v: SimpleNamespace(total=pen[i](v), crash=None)  # noqa: E731
    rounds = []

    def run_values(asks):
        rounds.append(list(asks))
        return [run(i, v) for i, v in asks]

    kept = advice_search.search_many([(spring, 5.5, run(0, 5.5)), (rebound, 2240.0, run(1, 2240.0))], run_values,
                                     lambda i, v: True)
    alone = [advice_search.search(spring, 5.5, run(0, 5.5), 0.0, lambda vs: [run(0, v) for v in vs], lambda v: True),
             advice_search.search(rebound, 2240.0, run(1, 2240.0), 0.0, lambda vs: [run(1, v) for v in vs],
                                  lambda v: True)]
    assert [[v for v, _ in k] for k in kept] == [[v for v, _ in k] for k in alone]
    assert kept[1][-1][0] == pytest.approx(2240.0 * 0.8 ** 8, rel=1e-3)  # 376: MAX_STEPS (8) past the candidate
    assert len(kept[1]) == advice_search.MAX_STEPS and kept[0][-1][0] == pytest.approx(8.05255)
    assert {i for i, _ in rounds[0]} == {0, 1} and all(sum(1 for i, _ in r if i == j) <= 2 for r in rounds for j in (0, 1))
    assert any({i for i, _ in r} == {1} for r in rounds)  # the spring's search stopped first, the rebound's went on


def test_a_step_past_the_next_is_asked_only_where_the_pool_has_room():
    """Three searches made here (a spring whose penalty (v - 8)^2 falls from 5.5, a rebound damper
    falling to a floor at 400 from 2240, a compression damper whose penalty rises at once): with a
    pool of two (``per_round`` 2), a round with two or three searches going asks one step of each,
    one going asks two; served serially (1), one step of each search a round. The steps kept are those of a pool with
    room for two of each (6) and of each search alone, with fewer runs: no step asked past the first
    that fails while the other searches fill the pool."""
    spring = _adj()
    rebound = _adj("fork.damper.rebound_N_s_per_m", 2800.0, "N s/m")
    compression = _adj("fork.damper.compression_N_s_per_m", 500.0, "N s/m")
    pen = [lambda v: (v - 8.0) ** 2, lambda v: abs(v - 400.0) / 100.0, lambda v: v / 100.0]
    run = lambda i, v: SimpleNamespace(total=pen[i](v), crash=None)  # noqa: E731
    starts = [(spring, 5.5, run(0, 5.5)), (rebound, 2240.0, run(1, 2240.0)), (compression, 625.0, run(2, 625.0))]

    def searched(per_round):
        rounds = []

        def run_values(asks):
            rounds.append(list(asks))
            return [run(i, v) for i, v in asks]

        kept = advice_search.search_many(starts, run_values, lambda i, v: True, per_round)
        return [[v for v, _ in k] for k in kept], rounds

    roomy, roomy_rounds = searched(6)
    two, two_rounds = searched(2)
    one, one_rounds = searched(1)
    alone = [[v for v, _ in advice_search.search(a, f, r, 0.0, lambda vs, i=i: [run(i, v) for v in vs], lambda v: True)]
             for i, (a, f, r) in enumerate(starts)]
    assert two == roomy == one == alone
    assert len(alone[1]) == advice_search.MAX_STEPS and alone[2] == []  # the test is not idle: one long, one none
    assert all(len(r) <= 3 for r in two_rounds) and all(len(r) == len({i for i, _ in r}) for r in one_rounds)
    for r in two_rounds:  # two steps of one search only where it alone is going
        going = {i for i, _ in r}
        assert len(r) == (len(going) if len(going) > 1 else len(r)) and len(r) <= 2 * len(going)
    asked = lambda rounds: sum(len(r) for r in rounds)  # noqa: E731
    assert asked(two_rounds) < asked(roomy_rounds)
    assert asked(one_rounds) <= asked(two_rounds)


def test_the_pool_says_how_many_it_runs_at_once():
    """What the search sizes its rounds by (``mtbmj.ride.advise.search_on``)."""
    from mtbmj.workers import process_pool

    with process_pool(3) as pool:
        assert pool.workers == 3


class Clock:
    """A pool of ``slots`` processes made here on a virtual clock: each run takes ``seconds(i, value)``
    and ends at its start plus that; ``wait`` moves the clock to the first end among those waited
    for and returns every one ended by then. Counts the runs and the most ever running at once."""

    def __init__(self, run, seconds):
        self.run, self.seconds, self.now, self.ends, self.asked, self.most = run, seconds, 0.0, {}, [], 0
        self.started = {}

    def submit(self, i, v):
        handle = len(self.asked)
        self.asked.append((i, v))
        self.started[(i, v)] = self.now
        self.ends[handle] = (self.now + self.seconds(i, v), self.run(i, v))
        self.most = max(self.most, sum(1 for e, _ in self.ends.values() if e > self.now))
        return handle

    def wait(self, handles):
        self.now = max(self.now, min(self.ends[h][0] for h in handles))
        return [(h, self.ends[h][1]) for h in handles if self.ends[h][0] <= self.now]


def _three():
    spring = _adj()
    rebound = _adj("fork.damper.rebound_N_s_per_m", 2800.0, "N s/m")
    compression = _adj("fork.damper.compression_N_s_per_m", 500.0, "N s/m")
    pen = [lambda v: (v - 8.0) ** 2, lambda v: abs(v - 400.0) / 100.0, lambda v: v / 100.0]
    run = lambda i, v: SimpleNamespace(total=pen[i](v), crash="crashed" if i == 1 and v < 700 else None)  # noqa: E731
    return [(spring, 5.5, run(0, 5.5)), (rebound, 2240.0, run(1, 2240.0)), (compression, 625.0, run(2, 625.0))], run


def test_the_flowing_search_keeps_the_steps_of_the_rounds_however_its_runs_end():
    """Three searches made here (a spring whose penalty (v - 8)^2 falls from 5.5, a rebound damper
    falling towards 400 from 2240 that crashes below 700, a compression damper whose penalty rises at
    once), searched with each run ending as it does (``search_flow``) on 1 to 6 processes, the runs'
    lengths drawn at random (they end out of order): the steps kept are those of the rounds
    (``search_many``) and of each search alone, and no more runs go at once than the pool has."""
    import random

    starts, run = _three()
    rounds = [[v for v, _ in k] for k in advice_search.search_many(
        starts, lambda asks: [run(i, v) for i, v in asks], lambda i, v: True, 2)]
    alone = [[v for v, _ in advice_search.search(a, f, r, 0.0, lambda vs, i=i: [run(i, v) for v in vs], lambda v: True)]
             for i, (a, f, r) in enumerate(starts)]
    assert rounds == alone and len(alone[0]) == 4 and 0 < len(alone[1]) < advice_search.MAX_STEPS and alone[2] == []
    for slots in (1, 2, 3, 6):
        for seed in range(5):
            rng = random.Random(seed)
            clock = Clock(run, lambda i, v: rng.uniform(0.5, 2.0))
            kept = advice_search.search_flow(starts, clock.submit, clock.wait, lambda i, v: True, slots)
            assert [[v for v, _ in k] for k in kept] == rounds, (slots, seed)
            assert clock.most <= slots
    refused = advice_search.search_flow(starts, clock.submit, clock.wait, lambda i, v: not (i == 0 and v > 7.0), 2)
    assert [v for v, _ in refused[0]] == pytest.approx([6.05, 6.655])  # the part refuses 7.32: the search ends


def test_the_flowing_search_passes_over_a_lone_crash_as_the_rounds_do():
    """A spring search whose model crashes at one value only (6.655) beside a rebound search falling
    towards 400, with each run ending as it does (``search_flow``) on 1, 2 and 3 processes and runs of
    random length: the crash is passed over and named, and the steps kept and passed are those of the
    rounds (``search_many``)."""
    import random

    spring, rebound = _adj(), _adj("fork.damper.rebound_N_s_per_m", 2800.0, "N s/m")

    def run(i, v):
        if i == 0:
            return SimpleNamespace(total=-v, crash="looped out" if abs(v - 6.655) < 1e-3 else None)
        return SimpleNamespace(total=abs(v - 400.0) / 100.0, crash=None)

    starts = [(spring, 5.5, run(0, 5.5)), (rebound, 2240.0, run(1, 2240.0))]
    allowed = lambda i, v: v < 9.0 if i == 0 else True  # noqa: E731
    rounds = advice_search.search_many(starts, lambda asks: [run(i, v) for i, v in asks], allowed, 2)
    assert [round(v, 3) for v, _ in rounds[0]] == [6.05, 7.321, 8.053, 8.858]
    assert [round(v, 3) for v, _ in rounds[0].passed] == [6.655]
    for slots in (1, 2, 3):
        for seed in range(4):
            rng = random.Random(seed)
            clock = Clock(run, lambda i, v: rng.uniform(0.5, 2.0))
            kept = advice_search.search_flow(starts, clock.submit, clock.wait, allowed, slots)
            assert [[v for v, _ in k] for k in kept] == [[v for v, _ in k] for k in rounds], (slots, seed)
            assert [k.passed for k in kept] == [k.passed for k in rounds], (slots, seed)


@pytest.mark.parametrize("patience", [0, 1])
def test_the_flowing_search_keeps_two_processes_busy_where_the_rounds_wait(patience, monkeypatch):
    """The same three searches on two processes, every run 1 s long (the virtual clock): in rounds, a
    round waits for its slowest search and a process stands idle where a round has an odd number of
    runs; flowing, each search goes on as its own last step is judged, an idle process takes the step
    after one still running. With a crash ending its search at once (``CRASH_PATIENCE`` 0) the flow
    ends sooner (6 s against 7), in no more than the runs it needs (each kept step and the one that
    ends each search) on two processes would take, plus one. With the crash passed over once (the
    default) the rebound's search runs one step further and both take 7 s: the flow is no slower."""
    monkeypatch.setattr(advice_search, "CRASH_PATIENCE", patience)
    starts, run = _three()
    rounds = []

    def run_values(asks):
        rounds.append(len(asks))
        return [run(i, v) for i, v in asks]

    kept = advice_search.search_many(starts, run_values, lambda i, v: True, 2)
    in_rounds = sum(-(-n // 2) for n in rounds)  # seconds: each round's runs on two processes
    clock = Clock(run, lambda i, v: 1.0)
    flowing = advice_search.search_flow(starts, clock.submit, clock.wait, lambda i, v: True, 2)
    assert [[v for v, _ in k] for k in flowing] == [[v for v, _ in k] for k in kept]
    needed = sum(len(k) + 1 + patience * (i == 1) for i, k in enumerate(kept))  # every kept step and what ended
    assert (clock.now < in_rounds) if patience == 0 else (clock.now <= in_rounds), (clock.now, in_rounds, rounds)
    assert clock.now <= -(-needed // 2) + 1, (clock.now, needed)
    # a step asked past the one that ended its search started with that step, not after it: it did not
    # hold the search past its end
    for i, (adj, first, _) in enumerate(starts):
        ending = advice_search.next_value(adj, kept[i][-1][0] if kept[i] else first, first)
        if patience and run(i, ending).crash:  # passed over: the search ended at the step after it
            ending = advice_search.next_value(adj, ending, first)
        past = advice_search.next_value(adj, ending, first)
        if (i, past) in clock.started:
            assert clock.started[(i, past)] == clock.started[(i, ending)], (i, clock.started)
    assert clock.now == max(clock.started[(i, v)] + 1.0 for i, v in clock.asked)


def test_a_step_past_the_next_is_not_started_late_to_hold_the_search_past_its_end():
    """A spring search (penalty (v - 6.2)^2 from 5.5: 6.05 kept, 6.655 ends it) beside a compression
    damper whose penalty rises at once, its run 1.5 s where the spring's take 1 s (the virtual clock):
    when the damper's run ends at 1.5 s, the spring's 6.655 is half way; the step after it, started
    then, would run to 2.5 s though the search ends at 2 s with 6.655. It is not asked: the flow ends
    at 2 s."""
    spring = _adj()
    compression = _adj("fork.damper.compression_N_s_per_m", 500.0, "N s/m")
    pen = [lambda v: (v - 6.2) ** 2, lambda v: v / 100.0]
    run = lambda i, v: SimpleNamespace(total=pen[i](v), crash=None)  # noqa: E731
    starts = [(spring, 5.5, run(0, 5.5)), (compression, 625.0, run(1, 625.0))]
    clock = Clock(run, lambda i, v: 1.5 if i == 1 else 1.0)
    kept = advice_search.search_flow(starts, clock.submit, clock.wait, lambda i, v: True, 2)
    assert [v for v, _ in kept[0]] == pytest.approx([6.05]) and kept[1] == []
    assert clock.started[(0, 6.655)] == 1.0 and clock.now == 2.0, clock.started
    assert (0, advice_search.next_value(spring, 6.655, 5.5)) not in clock.started

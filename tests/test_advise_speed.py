"""``mtbmj advise``'s pool started before the ride is prepared, each process warmed by a short run of the
bike (mtbmj/ride/advice_workers.py, issue 52 item 7): a run in a warmed process is the run made in a
process never warmed, to the last bit. No timing is asserted (benchmarks/advise_speed.py measures it)."""
from __future__ import annotations

import os
from contextlib import ExitStack

import numpy as np

from mtbmj.bike import spec
from mtbmj.ride import advice_workers
from mtbmj.ride.advice_rules import adjusters
from mtbmj.ride.advise import simulate
from mtbmj.rolling.terrain import Terrain


def course() -> Terrain:
    """A flat start, then 12 m of bumps drawn here (a made course, not a reconstruction)."""
    rng = np.random.default_rng(52)
    x = np.concatenate(([-60.0, 0.0], np.linspace(0.5, 12.5, 241), [70.0]))
    bumps = np.cumsum(rng.normal(0.0, 0.004, 241))
    z = np.concatenate(([0.0, 0.0], bumps - bumps[0], [bumps[-1] - bumps[0]]))
    return Terrain("made bumps", x, z, -3.0, 20.0)


def job(overrides=None) -> tuple:
    """:func:`mtbmj.ride.advise.simulate`'s arguments: the sst preset over :func:`course` for 2.5 s."""
    return ("sst", overrides or {}, course(), 5.0, 2.5, "made", 0.2, None)


def warmed_here() -> tuple:
    """(this process's id, the bikes :func:`advice_workers.warm` ran here)."""
    return os.getpid(), list(advice_workers.WARMED)


def in_pool(warm: bool, fn, *args):
    """``fn(*args)`` in a fresh one-process pool, warmed for the sst preset first or not."""
    from mtbmj.workers import process_pool

    with ExitStack() as stack:
        pool = advice_workers.started(stack, 1, "sst") if warm else stack.enter_context(process_pool(1))
        return pool.submit(warmed_here).result(), pool.submit(fn, *args).result()


def test_a_run_in_a_warmed_process_is_the_run_in_a_cold_one():
    (pid_w, warmed), hot = in_pool(True, simulate, *job())
    (pid_c, cold_warmed), cold = in_pool(False, simulate, *job())
    assert pid_w != os.getpid() and pid_c != os.getpid()
    assert warmed == ["sst"] and cold_warmed == []  # the warm-up ran in the one pool and not in the other
    assert hot.crash is None and cold.crash is None
    assert len(hot.front_mm) > 4000  # 2.3 s at 0.5 ms
    for a, b in ((hot.front_mm, cold.front_mm), (hot.rear_mm, cold.rear_mm), (hot.time_s, cold.time_s)):
        assert np.array_equal(a, b)
    assert hot.metrics == cold.metrics and hot.penalty == cold.penalty
    # the comparison sees a change: a fork spring 2 % stiffer (the advice's own adjuster) moves the series
    fork = adjusters(spec.load("sst"))[0]
    assert fork.label == "fork spring rate"
    stiffer = simulate(*job(fork.overrides(fork.value * 1.02)))
    assert not np.array_equal(stiffer.front_mm, hot.front_mm)
    assert np.max(np.abs(stiffer.front_mm - hot.front_mm)) > 0.01


def test_a_warm_up_that_fails_leaves_the_pool_working():
    """A bike the warm-up cannot run (no such file): the process starts all the same and runs what it is
    given; the real runs meet the bike's error where it is reported."""
    with ExitStack() as stack:
        pool = advice_workers.started(stack, 1, "no_such_bike.toml")
        assert pool.submit(warmed_here).result()[1] == []
        assert pool.submit(sum, [1, 2]).result() == 3

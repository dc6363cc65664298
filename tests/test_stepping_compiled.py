"""The step rule's compiled ``stop_index`` (``mtbmj.drop.stepping_compiled``) answers as its numpy
definition (``stepping.stop_index_numpy``) and as a row-by-row reading of the rule written here,
on chunks of random states with every zone in play, the edges exactly on a zone's boundary,
NaN and infinity; and a MuJoCo drop steps the same with either."""
import math

import numpy as np
import pytest

from mtbmj.controllers import native
from mtbmj.drop import stepping

MARGIN = stepping.STOP_MARGIN_M
COLUMNS = (0, 1, 5, 6)  # sled, fork position; sled, fork velocity (other columns hold noise)


def lesser(a, b):
    """numpy's minimum of two floats: NaN if either is."""
    return math.nan if math.isnan(a) or math.isnan(b) else min(a, b)


def greater(a, b):
    return math.nan if math.isnan(a) or math.isnan(b) else max(a, b)


def reference(previous, states, columns, zones, step, stops_only):
    """The rule, one step (row pair) at a time, in Python floats."""
    sled, fork, sled_v, fork_v = columns
    compress, extend, rim, band, fast = zones
    rows = [previous] + list(states)
    for i in range(1, len(rows)):
        a, b = rows[i - 1], rows[i]
        xa, xb, va, vb = float(a[fork]), float(b[fork]), float(a[fork_v]), float(b[fork_v])
        da, db = float(a[sled]) - xa, float(b[sled]) - xb
        wa, wb = float(a[sled_v]) - va, float(b[sled_v]) - vb
        m = step * (abs(va) + abs(vb) + abs(vb - va)) + MARGIN
        n = step * (abs(wa) + abs(wb) + abs(wb - wa)) + MARGIN
        near = greater(xa, xb) + m > compress or lesser(xa, xb) - m < extend or greater(da, db) + n > rim
        if not stops_only:
            near = near or (lesser(da, db) - n < 0.0 < greater(da, db) + n)
            if band > 0.0:
                slowest = 0.0 if va * vb <= 0.0 else lesser(abs(va), abs(vb)) - abs(vb - va)
                near = near or slowest < band
            if fast < math.inf:
                near = near or greater(abs(va), abs(vb)) + abs(vb - va) > fast
        if near:
            return i - 1
    return None


def chunks(seed, count):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n = int(rng.choice([1, 2, 10, 10, 37, 400]))
        rows = rng.normal(0.0, 1.0, (n + 1, 8))
        rows[:, 1] = np.cumsum(rng.normal(0.0, 2e-3, n + 1)) + rng.uniform(-0.02, 0.14)  # fork, m
        rows[:, 0] = rows[:, 1] + np.cumsum(rng.normal(0.0, 1e-3, n + 1)) + rng.uniform(-0.01, 0.02)  # sled
        rows[:, 6] = rng.normal(0.0, rng.choice([0.01, 0.5, 3.0]), n + 1)
        rows[:, 5] = rows[:, 6] + rng.normal(0.0, 0.5, n + 1)
        if rng.random() < 0.1:  # a velocity changing sign, a fork at rest
            rows[:, 6] = 0.0
        if rng.random() < 0.05:
            rows[rng.integers(n + 1), rng.integers(8)] = rng.choice([math.nan, math.inf, -math.inf])
        zones = (float(rng.uniform(0.09, 0.13)), float(rng.uniform(-0.03, 0.0)), float(rng.uniform(0.01, 0.04)),
                 float(rng.choice([0.0, 0.0, rng.uniform(0.0, 0.2)])), float(rng.choice([math.inf, rng.uniform(0.5, 4)])))
        step = float(rng.choice([1e-3, 5e-4, 1e-4]))
        if rng.random() < 0.2:  # a zone's edge exactly where a step reaches
            i = int(rng.integers(1, n + 1))
            a, b = rows[i - 1], rows[i]
            m = step * (abs(a[6]) + abs(b[6]) + abs(b[6] - a[6])) + MARGIN
            zones = (float(max(a[1], b[1]) + m),) + zones[1:]
            slowest = min(abs(a[6]), abs(b[6])) - abs(b[6] - a[6])
            if a[6] * b[6] > 0.0 and slowest > 0.0:  # and the band around rest exactly at that step's slowest
                zones = zones[:3] + (float(slowest),) + zones[4:]
        yield np.ascontiguousarray(rows[0]), np.ascontiguousarray(rows[1:]), zones, step


@pytest.fixture(scope="module")
def compiled():
    native.expect_many()
    found = stepping._compiled()
    if found is None:
        pytest.skip("numba not installed")
    return found


@pytest.mark.parametrize("seed", range(4))
def test_compiled_stop_index_is_the_numpy_rule_and_the_rule_read_row_by_row(compiled, seed):
    found = {False: 0, True: 0}
    for previous, states, zones, step in chunks(seed, 1500):
        for stops_only in (False, True):
            want = reference(previous, states, COLUMNS, zones, step, stops_only)
            with np.errstate(invalid="ignore", over="ignore"):  # inf - inf and inf * 0 in numpy's rule
                assert stepping.stop_index_numpy(previous, states, COLUMNS, zones, step, stops_only) == want
            got = compiled(previous, states, *COLUMNS, *zones, step, MARGIN, stops_only)
            assert (None if got < 0 else got) == want, (states, zones, step, stops_only)
            assert stepping.stop_index(previous, states, COLUMNS, zones, step, stops_only) == want
            found[want is not None] += 1
    assert found[True] > 300 and found[False] > 300, found  # both answers, many times


def test_a_drop_steps_the_same_on_either_rule(compiled, monkeypatch):
    """S12 and a hard landing on its stops, through MuJoCo: the same trace, bit for bit, with the
    compiled rule and with numpy's."""
    import mtbmj

    cases = [("S12", {}), ("S12", {"sled.drop_height_mm": 400, "fork.spring.preload_N": 60})]
    with_compiled = [mtbmj.run_drop(c, overrides=o, duration=0.6).csv_bytes() for c, o in cases]
    monkeypatch.setattr(stepping, "_compiled", lambda: None)
    with_numpy = [mtbmj.run_drop(c, overrides=o, duration=0.6).csv_bytes() for c, o in cases]
    assert with_compiled == with_numpy

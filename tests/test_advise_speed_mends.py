"""The cheap mends of ``mtbmj advise``'s speed (issue 52 item 7): the bottom-out count without a Python
loop over the samples (mtbmj/measured/metrics.py) and a profile's straight stretches built once per
process for every run over it (mtbmj/rolling/tire.py ``stretches_of``). Each against a reference
written here. No timing is asserted."""
from __future__ import annotations

import numpy as np

from mtbmj.measured import metrics
from mtbmj.rolling import tire
from mtbmj.rolling.terrain import Terrain


def starts_by_loop(x, top, margin=3.0, release=5.0):
    """The bottom-out rule as stated (``metrics.bottom_outs``), sample by sample: an event starts on
    reaching within ``margin`` of ``top`` from outside; outside again only below top - margin - release."""
    out, inside = [], False
    for i, v in enumerate(x):
        if not inside and v >= top - margin:
            out.append(i)
            inside = True
        elif inside and v < top - margin - release:
            inside = False
    return out


def test_bottom_out_starts_match_the_rule_sample_by_sample():
    rng = np.random.default_rng(4)
    cases = [np.cumsum(rng.normal(0.0, 3.0, 5000)) % 140.0 for _ in range(20)]  # many crossings, jumps too
    cases += [np.full(50, 130.0), np.full(50, 10.0), np.array([128.0, 121.0, 128.0, 125.0, 128.0]),
              np.array([127.0]), 126.0 + 4.0 * np.sin(np.linspace(0, 40, 3000))]
    for x in cases:
        for margin, release in ((3.0, 5.0), (0.0, 0.0), (10.0, 1.0)):
            got = metrics.bottom_out_indices(x, 130.0, margin, release)
            assert got.tolist() == starts_by_loop(x, 130.0, margin, release), (x[:8], margin, release)
    assert metrics.bottom_out_indices(np.array([128.0, 121.0, 128.0, 125.0, 128.0]), 130.0).tolist() == [0, 2]
    # in once (up to 130), never out again (down to 122, not below 122): one event, not 20
    assert metrics.bottom_outs(126.0 + 4.0 * np.sin(np.linspace(0, 40, 3000)), 130.0) == 1


def profile(seed, n=3000):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.uniform(0.01, 0.05, n))
    z = np.round(np.cumsum(rng.normal(0.0, 0.01, n)), 2)
    z[100:300] = 0.5  # a long flat: collinear points merged into one stretch
    return Terrain("made", x, z, float(x[0]), float(x[-1] - x[0]), {})


def test_straight_stretches_are_built_once_per_profile_and_reach():
    """Two terrains of the same points (separate objects, as each run's unpickled copy): one
    stretches object, equal to one built afresh; another reach or another profile: its own; the
    oldest dropped past ``STRETCHES_KEPT``."""
    a, b = profile(1), profile(1)
    first = tire.stretches_of(a, 0.4)
    assert tire.stretches_of(b, 0.4) is first
    fresh = tire.StraightStretches(b, 0.4)
    assert (fresh.x, fresh.z, fresh.reach) == (first.x, first.z, first.reach)
    assert len(first.x) < len(a.x)  # the flat's collinear points merged
    assert tire.stretches_of(a, 0.41) is not first and tire.stretches_of(profile(2), 0.4) is not first
    for seed in range(3, 3 + tire.STRETCHES_KEPT):
        tire.stretches_of(profile(seed, 200), 0.4)
    again = tire.stretches_of(a, 0.4)
    assert again is not first and again.x == first.x

"""Three rides of one well-set bike on different trails, advised alone and pooled (issue 52: "three
rides of one setting on different trails -> the same recommendation"; mtbmj/ride/advice_pool.py).

The rides are made by the independent whole bike of tests/helpers.py (``whole_bike_ride``: scipy's
solve_ivp on its own equations, written as SST v3 counts) at the bike file's own setting (fork 12
N/mm, its rebound 700 N s/m, the shock's 3500) for 30 s at 6.5 +- 0.5 m/s: two over the advice's
hard course on the roughness of seeds 21 and 5, the third over a different mix made here
(``TRAIL_MIX``: G-outs and a smaller drop where the course has its 0.5-0.6 m drops) on seed 8's.

Measured (2026-12-04): alone (one step each, ``PooledAdvice.rides``) seeds 21 and 5 lower the fork's
rebound 700 -> 560 N s/m, seed 8 is inconclusive (every rule inside its window at the recorded
setting); pooled (every candidate searched), inconclusive (the best candidate, the fork's
compression 500 -> 625, improves only the front bottom-outs, 4.7 -> 2 a minute against +- 7.6).
So the rides do not contradict each other and nothing leaves the well-set ranges, but they do not
give one answer. The rules read the trail as much as the setting: the rides' own fork rebounds at
0.52, 0.56 and 0.59 of its compression speed (the packing rule's assumed 0.6) and reaches 90 %, 75 %
and 72 % of its travel without a bottom-out (the rule asks 85 %); and the model sees them through its
own bias (its fork bottoms 4 times on seed 21's drops where the ride had none, 101 % of travel
against 90 %; on seed 8 every rule of the model's ride is inside its window). docs/rolling.md has it.
``test_the_three_give_one_answer`` holds the issue's demand as a strict xfail: it fails today for
that reason and will say so when it no longer does."""
from __future__ import annotations

import shutil
from argparse import Namespace

import pytest

from mtbmj.ride import advice_pool

from helpers import (ADVISE_FEATURES, ADVISE_PROFILE, outside_well_set_ranges, reconstruction_passing,
                     whole_bike_ride)

# a different trail's mix: rock gardens, two G-outs, a tabletop, drops of 0.4 and 0.5 m (kind, where m, size m)
TRAIL_MIX = (("rocks", 10.0, 0.08), ("g_out", 30.0, 0.3), ("rocks", 45.0, 0.1), ("drop", 65.0, 0.4),
             ("rocks", 80.0, 0.1), ("jump", 100.0, 0.3), ("g_out", 125.0, 0.25), ("rocks", 140.0, 0.1),
             ("drop", 165.0, 0.5))
TRAILS = ((21, ADVISE_FEATURES), (5, ADVISE_FEATURES), (8, TRAIL_MIX))


@pytest.fixture(scope="module")
def pooled(tmp_path_factory):
    """The three rides made and pooled (every candidate searched on every ride)."""
    from mtbmj.cli.telemetry import ride_record

    folder = tmp_path_factory.mktemp("trails")
    records = []
    for seed, features in TRAILS:
        made = whole_bike_ride(folder / f"s{seed}", seconds=30.0, profile=ADVISE_PROFILE, features=features, seed=seed)
        sst = shutil.copy(made["sst"], folder / f"seed{seed}.SST")
        records.append(ride_record(sst, Namespace(bike=str(made["bike"]), fork_max_mm=None, shock_max_mm=None)))
    with reconstruction_passing():
        return advice_pool.pooled(records, str(made["bike"]), workers=2)


@pytest.mark.slow  # 3 x 13 whole-bike runs of 31 s and the pooled searches: 6-14 min on two busy cores
def test_the_three_do_not_contradict_and_stay_within_the_well_set_ranges(pooled):
    """No ride is left out; each ride's calibration holds 1 at both ends; no two rides (nor the
    pooled answer) move one adjuster opposite ways; every change advised, alone or pooled, is within
    the well-set ranges (fork spring +-20 %, rebound +-30 %)."""
    assert pooled.refused == [] and len(pooled.rides) == 3
    for ride in pooled.rides:
        for end, sc in ride.calibration.scales.items():
            assert sc.low <= 1.0 <= sc.high, (ride.ride, end, sc)
    assert "the rides disagree" not in pooled.verdict.get("why", ""), pooled.verdict
    for ride in pooled.rides:
        if ride.verdict["answer"] == "change":
            assert outside_well_set_ranges(ride.recommendation) == [], (ride.ride, ride.recommendation)
    if pooled.verdict["answer"] == "change":
        assert outside_well_set_ranges(pooled.recommendation) == [], pooled.recommendation


@pytest.mark.slow
def test_the_pooled_uncertainty_is_narrower_than_each_ride_s(pooled):
    """For every candidate, the uncertainty of its change (the model's error on the ride beside the
    change's spread over the segments) pooled over the three rides is narrower than on any one of
    them for the front's dynamic sag and both ends' packing. (The spread part alone is not: pooled
    it is the spread of a mean over rides whose changes differ, measured wider than the calmest
    ride's; the bottom-outs' is a count's, at least its square root, and grows with the rides' sum.)"""
    keys = ("front.dynamic_sag_percent", "front.rebound_over_compression", "rear.rebound_over_compression")
    for adj, direction, value, run in pooled.candidates:
        whole = pooled.change_uncertainty(run)
        each = [ride.change_uncertainty(part) for ride, part in zip(pooled.rides, run.parts)]
        for k in keys:
            assert whole[k] < min(e[k] for e in each), (adj.label, direction, k, whole[k], [e[k] for e in each])


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="two trails lower the fork's rebound one step, the third and the pool are "
                                       "inconclusive: the rules read the trail (packing, unused travel) and the "
                                       "model's own bottom-outs (see the module doc)")
def test_the_three_give_one_answer(pooled):
    """The issue's demand: every ride alone and the pool give the same recommendation, or all are
    inconclusive."""
    def said(advice):
        rec = advice.recommendation if advice.verdict["answer"] == "change" else None
        return None if rec is None else (rec["key"], rec["direction"])

    answers = {said(ride) for ride in pooled.rides} | {said(pooled)}
    assert len(answers) == 1, answers

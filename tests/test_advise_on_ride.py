"""The advice's rules scored on the ride, not on the model (issue 52: "one answer on three trails";
mtbmj/ride/advice_rules.py ``on_the_ride``, mtbmj/ride/advise.py ``Advice.score``).

Advices made here by hand (no simulation): a ride of 20 s (four 5 s segments) whose fork never
bottoms, a model of it that bottoms four times at the recorded setting (its own bias) and once at a
candidate; and the same model on a ride that bottomed as the model does. The rules must judge the
bike as ridden: the model's own bottom-outs are no reason to change anything, the ride's are."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.ride import advise
from mtbmj.ride.advice_rules import on_the_ride

TOP_F, TOP_R = 130.0, 125.0
T = np.linspace(0.0, 20.0, 4001)


def fork(hits):
    """A fork's travel (mm): a 40 % sag wave, and a hit to within 1 mm of full travel at each of ``hits`` (s)."""
    x = 52.0 + 15.0 * np.sin(2 * np.pi * 1.3 * T)
    for at in hits:
        x = np.maximum(x, (TOP_F - 1.0) * np.exp(-0.5 * ((T - at) / 0.03) ** 2))
    return x


REAR = 0.9 * (50.0 + 15.0 * np.sin(2 * np.pi * 1.1 * T + 0.7))
EVERY_SEGMENT = (2.5, 7.5, 12.5, 17.5)  # one hit in each 5 s segment


def run(label, front, static_f_percent=22.0):
    m = advise.ride_metrics(T, front, REAR, TOP_F, TOP_R,
                            static=(static_f_percent / 100 * TOP_F, 0.28 * TOP_R))
    return advise.Run(label, {}, m, advise.penalties(m), front, REAR, None, T.copy())


def judged(record_front):
    """The model (four bottom-outs at the recorded setting, one at a stiffer fork) advised on a ride
    whose fork travelled ``record_front``."""
    base, stiffer = run("recorded setting", fork(EVERY_SEGMENT)), run("stiffer", fork(EVERY_SEGMENT[:1]))
    measured = advise.ride_metrics(T, record_front, REAR, TOP_F, TOP_R)
    adj = advise.Adjuster("front", "fork.set", "fork.spring.rate_N_per_mm", 10.0, 9.0, 11.0, "fork spring rate")
    a = advise.Advice("ride", "bike", {}, measured, base, [(adj, "up", 11.0, stiffer)], None, record_front, REAR,
                      record_t=T.copy())
    a.recommendation, a.verdict = advise.judge(a)
    return a, stiffer


def test_the_model_s_own_bottom_outs_are_not_advised_on():
    """The ride never bottomed; the model bottoms 12 times a minute (penalty 5 on the model's own
    numbers) and 3 at the stiffer fork: scored on the ride, the recorded setting and the candidate
    both have no bottom-out penalty, and nothing is advised."""
    a, stiffer = judged(fork(()))
    assert a.base.metrics["front"]["bottom_outs"] == 4 and a.measured["front"]["bottom_outs"] == 0
    assert advise.penalties(a.base.metrics)["front_bottom_outs"] == pytest.approx(5.0)  # the model's own: 5
    assert a.base.penalty["front_bottom_outs"] == 0.0
    assert stiffer.penalty["front_bottom_outs"] == 0.0
    assert a.verdict["answer"] == "inconclusive" and a.recommendation is None, a.verdict


def test_the_ride_s_own_bottom_outs_are():
    """The ride bottomed as the model does (12 a minute): the recorded setting's penalty is the
    ride's (5), the stiffer fork's the ride's expected 3 a minute (12 scaled by the model's 3/12:
    0.5), and the stiffer fork lowers the penalty by 4.5."""
    a, stiffer = judged(fork(EVERY_SEGMENT))
    assert a.base.penalty["front_bottom_outs"] == pytest.approx(5.0)
    assert stiffer.penalty["front_bottom_outs"] == pytest.approx(0.5)
    assert a.base.total - stiffer.total == pytest.approx(4.5)


def test_on_the_ride_at_the_recorded_setting_is_the_ride_and_the_statics_are_the_model_s():
    """At the recorded setting (the model's from = to) every metric the ride recorded is the
    recorded value, the static sag (no ride records it) the model's; at another setting a share
    moves by the model's change within its bounds."""
    rec = advise.ride_metrics(T, fork(()), REAR, TOP_F, TOP_R)
    sim = advise.ride_metrics(T, fork(EVERY_SEGMENT) + 10.0, REAR, TOP_F, TOP_R, static=(30.0, 35.0))
    same = on_the_ride(rec, sim, sim)
    for end in ("front", "rear"):
        for k, v in rec[end].items():
            assert same[end][k] == pytest.approx(v), (end, k)
    assert same["front"]["static_sag_percent"] == pytest.approx(30.0 / TOP_F * 100)
    assert same["balance_points"] == pytest.approx(rec["balance_points"])
    deeper = advise.ride_metrics(T, fork(EVERY_SEGMENT) + 20.0, REAR, TOP_F, TOP_R, static=(30.0, 35.0))
    moved = on_the_ride(rec, sim, deeper)
    assert moved["front"]["dynamic_sag_percent"] == pytest.approx(
        rec["front"]["dynamic_sag_percent"] + deeper["front"]["dynamic_sag_percent"] - sim["front"]["dynamic_sag_percent"])
    assert 0.0 <= moved["front"]["deep_travel_percent"] <= 100.0


def ends(front_ratio, rear_ratio, compression=(900.0, 700.0)):
    """Metrics of a ride (both ends in their windows but for packing): each end's rebound p95 this
    share of its compression p95 (mm/s)."""
    out = {"balance_points": 0.0, "duration_s": 60.0}
    for end, r, c in (("front", front_ratio, compression[0]), ("rear", rear_ratio, compression[1])):
        out[end] = {"static_sag_percent": 24.0 if end == "front" else 28.0, "bottom_outs": 1,
                    "bottom_outs_per_minute": 1.0, "max_travel_percent": 97.0, "p95_compression_mm_per_s": c,
                    "p95_rebound_mm_per_s": r * c, "rebound_over_compression": r}
    return out


def test_packing_is_read_against_the_other_end_on_the_same_terrain():
    """A trail with harder hits lowers both ends' rebound-over-compression (its compression speeds
    rise): 0.52 and 0.63 (the well-set bike's on the tests' hard course) is no packing, nor 0.59 and
    0.67; a fork four times too slow, 0.26 against the rear's 0.60, packs (its share of the rear's
    0.43, 0.8 asked: penalty 1.83 at the front, none at the rear); both ends at 0.3 pack by the floor
    (0.4: penalty 0.5 each)."""
    for f, r in ((0.52, 0.63), (0.59, 0.67), (0.56, 0.58)):
        p = advise.penalties(ends(f, r))
        assert p["front_packing"] == 0.0 and p["rear_packing"] == 0.0, (f, r, p)
    p = advise.penalties(ends(0.26, 0.60))
    assert p["front_packing"] == pytest.approx((0.8 - 0.26 / 0.60) / 0.2) and p["rear_packing"] == 0.0
    p = advise.penalties(ends(0.3, 0.3))
    assert p["front_packing"] == pytest.approx(0.5) and p["rear_packing"] == pytest.approx(0.5)


def test_a_change_that_speeds_an_end_far_past_the_other_pogoes():
    """The packing rule's other side (issue 52: a soft fork's advice lowered its rebound 700 -> 117 N s/m, the
    fork then rebounding at 1.34 of its compression speed where the rear rebounds at 0.70, and no rule
    said so): a setting whose end rebounds above 1.25 of the other end's ratio on the ride as recorded
    (and above its own there) costs one unit per 0.2 over. Read against the ride (0.56 fork, 0.70 rear):
    the fork at 0.80 (1.14 of the rear's) pays nothing, at 1.34 it pays (1.34 / 0.70 - 1.25) / 0.2; a
    rear sped to 0.80 (1.43 of the fork's 0.56) pays too; a setting that speeds the rear to 1.2 leaves the
    fork's bound at 1.25 x 0.70. The ride's own imbalance is packing's: a ride whose fork packs (0.46
    against 0.70) does not also make its rear pogo, and the well-set bike's rides (fork over rear 0.83,
    0.97, 0.88) and a fork four times too slow pay no pogo."""
    ride = ends(0.56, 0.70)
    assert advise.penalties(ends(0.80, 0.70), ride)["front_pogo"] == 0.0
    p = advise.penalties(ends(1.34, 0.70), ride)
    assert p["front_pogo"] == pytest.approx((1.34 / 0.70 - 1.25) / 0.2) and p["rear_pogo"] == 0.0
    assert advise.penalties(ends(0.56, 0.80), ride)["rear_pogo"] == pytest.approx((0.80 / 0.56 - 1.25) / 0.2)
    assert advise.penalties(ends(0.9, 1.2), ride)["front_pogo"] == pytest.approx((0.9 / 0.70 - 1.25) / 0.2)
    for f, r in ((0.46, 0.70), (0.52, 0.63), (0.59, 0.67), (0.56, 0.58), (0.26, 0.60)):
        p = advise.penalties(ends(f, r))
        assert p["front_pogo"] == 0.0 and p["rear_pogo"] == 0.0, (f, r, p)
    p = advise.penalties(ends(0.46, 0.70))
    assert p["front_packing"] > 0.0 and p["rear_pogo"] == 0.0  # the slower end blamed, not both
    assert advise.rule_metric("front_pogo") == "front.rebound_over_compression"


def test_slowing_the_other_end_does_not_mend_one_that_packs():
    """The fork packs on the ride (0.26 against the rear's 0.60); a setting that slows the rear to
    0.30 leaves the fork's target where the recorded ride set it (0.8 x 0.60), so the fork still
    packs as much, and the rear now packs by the floor."""
    ride = ends(0.26, 0.60)
    p = advise.penalties(ends(0.26, 0.30), ride)
    assert p["front_packing"] == pytest.approx((0.8 - 0.26 / 0.60) / 0.2)
    assert p["rear_packing"] == pytest.approx((0.4 - 0.30) / 0.2)
    # read against the setting's own rear, the fork would seem mended but for the floor: 0.7, not 1.83
    assert advise.penalties(ends(0.26, 0.30))["front_packing"] == pytest.approx((0.4 - 0.26) / 0.2)

"""The travel-unused rule read against the terrain (issue 52: "use the travel" read the trail: a
smooth trail reaches 72-75 % of travel whatever the setting, and was told to soften): an end is asked
to use 85 % of its travel, or 0.8 of what the other end reached on the ride as recorded where that is
less (``advice_rules.UNUSED_SHARE``: the other end rode the same terrain, its maximum is what the
terrain's biggest hits asked of it). Closed forms here: each end's travel made in the test as a
train of hits whose peaks are set in % of travel; the made rides are in the slow tests below."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.ride import advice_rules
from mtbmj.ride.advice_rules import UNUSED_BELOW_PERCENT, UNUSED_SHARE, penalties, ride_metrics

FRONT_MM, REAR_MM = 130.0, 125.0
T = np.arange(0.0, 30.0, 0.001)


def hits(top_mm, peak_percent, sag_percent=30.0, every_s=3.0):
    """Travel (mm) at ``sag_percent`` of ``top_mm`` with a half-sine hit of 0.2 s every ``every_s``,
    the largest reaching ``peak_percent`` (the others two thirds of the way)."""
    x = np.full(T.size, sag_percent / 100.0 * top_mm)
    for k, at in enumerate(np.arange(1.0, T[-1] - 1.0, every_s)):
        rise = (peak_percent - sag_percent) / 100.0 * top_mm * (1.0 if k == 3 else 2.0 / 3.0)
        on = (T >= at) & (T < at + 0.2)
        x[on] += rise * np.sin(np.pi * (T[on] - at) / 0.2)
    return x


def metrics(front_peak, rear_peak):
    return ride_metrics(T, hits(FRONT_MM, front_peak), hits(REAR_MM, rear_peak), FRONT_MM, REAR_MM)


def test_a_smooth_trail_asks_for_no_more_travel_than_it_gave():
    """Both ends reach 73-75 % (no bottom-out): the rule before asked for 85 % (a penalty of 1.0-1.2 at
    each end: soften); read against the other end's maximum it asks for 0.8 of it, 58-60 %: none."""
    m = metrics(73.0, 75.0)
    assert m["front"]["bottom_outs"] == 0 and m["front"]["max_travel_percent"] == pytest.approx(73.0, abs=0.1)
    p = penalties(m)
    assert p["front_travel_unused"] == 0.0 and p["rear_travel_unused"] == 0.0
    # what the fixed 85 % gave on the same ride
    assert (UNUSED_BELOW_PERCENT - m["front"]["max_travel_percent"]) / 10.0 == pytest.approx(1.2, abs=0.01)


def test_an_end_left_short_where_the_other_bottoms_is_asked_for_its_travel():
    """The rear bottoms on the biggest hit (100 %) where the fork reaches 60 %: the fork is asked for
    the lower of 85 % and 0.8 x 100 %, 80 %: 2 units of penalty; the rear none (it bottomed once: an
    occasional bottom-out is right)."""
    m = metrics(60.0, 100.0)
    assert m["rear"]["bottom_outs"] == 1
    p = penalties(m)
    asked = min(UNUSED_BELOW_PERCENT, UNUSED_SHARE * m["rear"]["max_travel_percent"])
    assert asked == pytest.approx(80.0, abs=0.1)
    assert p["front_travel_unused"] == pytest.approx((asked - m["front"]["max_travel_percent"]) / 10.0)
    assert p["front_travel_unused"] == pytest.approx(2.0, abs=0.02) and p["rear_travel_unused"] == 0.0
    # on a trail that takes the rear only to 70 %, the same fork at 60 % is within the rule (asked 56 %)
    assert penalties(metrics(60.0, 70.0))["front_travel_unused"] == 0.0


def test_the_travel_asked_is_the_ride_s_not_the_setting_s():
    """Scored on the ride (``terrain``: the metrics of the ride as recorded), what one end is asked for
    comes from the other end's maximum as recorded: a setting that stiffens the rear (its maximum
    70 % where the ride had 100 %) does not let the fork off; one that softens the fork to 78 % takes
    0.2 units, as the recorded ride asks 80 %."""
    recorded = metrics(60.0, 100.0)
    stiffer_rear = metrics(60.0, 70.0)
    softer_fork = metrics(78.0, 100.0)
    assert penalties(stiffer_rear, recorded)["front_travel_unused"] == pytest.approx(
        penalties(recorded)["front_travel_unused"])
    assert penalties(softer_fork, recorded)["front_travel_unused"] == pytest.approx(0.2, abs=0.02)
    assert "other end" in advice_rules.RULES["travel_unused"]


def _advised(folder, **settings):
    """A 30 s ride made by the independent whole bike of tests/helpers.py (``whole_bike_ride``: its
    own equations, written as SST v3) at ``settings`` over the roughness of seed 21 (``features``: the
    trail's hits), advised through the command (calibrated, every candidate searched; the
    reconstruction's verdict set to pass, as the advice's other made-ride tests): advice.json and
    the made ride's truth."""
    from mtbmj.cli import main

    from helpers import ADVISE_CARRIED, ADVISE_PROFILE, ADVISE_ROUND_TYRE, reconstruction_passing, whole_bike_ride

    made = whole_bike_ride(folder, seconds=30.0, profile=ADVISE_PROFILE, seed=21, carried=ADVISE_CARRIED,
                           round_tyre=ADVISE_ROUND_TYRE, **settings)
    out = folder / "advice"
    with reconstruction_passing():
        assert main(["advise", str(made["sst"]), "--bike", str(made["bike"]), "--out", str(out)]) == 0
    import json

    return json.loads((out / "advice.json").read_text()), made


def _use_more_travel(change: dict) -> bool:
    return any(k.endswith("travel_unused") for k in change.get("improves", []))


@pytest.mark.slow  # a whole-bike ride made (2-7 min on two busy cores) and one advice on it (2-4 min)
def test_a_well_set_bike_on_a_smooth_trail_is_not_told_to_use_more_travel(tmp_path):
    """The bike as its file says on a smooth trail (seed 21's roughness, no rocks, drops or G-outs): its
    ends reach about 30 % of their travel (the old rule's 85 % asked for 5-6 units of penalty at each
    end: soften). Now neither end's travel-unused penalty counts at the recorded setting, and no change
    advised (first or after) is one made for the travel unused."""
    advice, made = _advised(tmp_path / "smooth", features=())
    rode = advice["recorded_setting"]["measured"]
    assert rode["front"]["max_travel_percent"] < 50.0 and rode["rear"]["max_travel_percent"] < 50.0  # smooth
    pen = advice["recorded_setting"]["penalties"]
    assert pen["front_travel_unused"] == 0.0 and pen["rear_travel_unused"] == 0.0, pen
    rec = advice["recommendation"]
    if advice["verdict"]["answer"] == "change":
        assert not _use_more_travel(rec) and not any(_use_more_travel(t) for t in rec.get("then") or []), rec


@pytest.mark.slow  # a whole-bike ride made (2-7 min on two busy cores) and one advice on it (2-4 min)
def test_a_fork_far_too_stiff_on_a_trail_with_big_hits_is_softened(tmp_path):
    """The fork at 20 N/mm (the bike's own 12) on the advice's hard course (rock gardens, drops of 0.5
    and 0.6 m, a G-out, a tabletop): the rear uses its travel on the big hits (about 92 %), the fork
    about 70 %, short of 0.8 of the rear's: the travel-unused rule counts at the front, and the
    advice lowers the fork's spring."""
    from helpers import ADVISE_FEATURES

    advice, made = _advised(tmp_path / "stiff", features=ADVISE_FEATURES, fork_rate=20.0)
    rode = advice["recorded_setting"]["measured"]
    assert rode["rear"]["max_travel_percent"] > 85.0 > rode["front"]["max_travel_percent"], rode
    assert advice["recorded_setting"]["penalties"]["front_travel_unused"] > 0.0
    rec = advice["recommendation"]
    assert advice["verdict"]["answer"] == "change", advice["verdict"]
    assert rec["key"] == "fork:fork.spring.rate_N_per_mm" and rec["setting"]["to"] < rec["setting"]["from"], rec

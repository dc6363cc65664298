"""MuJoCo's bike against the bike's own ODE reference (``mtbmj.bike.reference``: the closed-form
planar equations integrated by scipy, the terrain's contact patches found afresh at every
evaluation) on every fixed terrain of the library at 4 and 6 m/s, the feature 0.4 m ahead of the
front axle, each run long enough for both wheels to cross it (the ledge drop: for the rear to land
too): travel at both ends and the shock's stroke within 0.1 mm, the tire-load peaks within 1 %.
The root is a 181-point polygon (a corner every 0.9 mm), the square edge has vertical walls, the
drop is the paper's load case (a 300 mm ledge taken at speed; at 4 m/s the fork reaches its bumper,
and those stretches are stepped at the fine step). The reference runs at rtol 1e-6 here (1e-8 in
``mtbmj crosscheck``): the front travel moves by 0.0003 mm on the washboard, a third of the time."""
from __future__ import annotations

import pytest

from mtbmj.bike import spec as spec_mod
from mtbmj.bike.crosscheck import FORCE_TOLERANCE, TOLERANCE_MM, crosscheck
from mtbmj.rolling.terrain import LIBRARY

TERRAINS = {"flat": "flat", "step_up": "step_up:at_m=0.4", "step_down": "step_down:at_m=0.4",
            "square_edge": "square_edge:at_m=0.4", "root": "root:at_m=0.4", "rock": "rock:at_m=0.4",
            "drop": "drop:at_m=0.4", "washboard": "washboard:at_m=0.4,length_m=1.5",
            "iso8608": "iso8608:at_m=0.4,class=D,length_m=10", "climb": "climb:at_m=0.4,grade_percent=15,length_m=3",
            "rock_garden": "rock_garden:at_m=0.4"}
ACROSS_M = {"rock_garden": 2.75}  # a feature longer than 0.35 m: the rear crosses all of it
STATIC_N = {"front": 425.0, "rear": 567.0}  # the SST bike's static tire loads (tests/test_bike.py's closed form)


def test_every_fixed_terrain_of_the_library_is_covered():
    assert set(TERRAINS) == {name for name in LIBRARY if name != "drum"}  # the drum rig holds a single wheel


@pytest.mark.parametrize("speed", [4.0, 6.0])
@pytest.mark.parametrize("name", list(TERRAINS))
def test_mujoco_matches_the_bike_reference(name, speed):
    bike = spec_mod.load("sst")
    wheelbase = bike.front_axle[0] - bike.rear_axle[0]
    reach = (0.4 + wheelbase) / speed  # the rear axle over the feature's start
    duration = reach + 0.35 if name == "drop" else reach + ACROSS_M.get(name, 0.35) / speed
    check = crosscheck(bike, TERRAINS[name], speed, duration=duration, reference_rtol=1e-6)
    assert check["front_travel"].max_abs <= TOLERANCE_MM
    assert check["rear_travel"].max_abs <= TOLERANCE_MM
    assert check["shock_stroke"].max_abs <= TOLERANCE_MM
    for tire in ("front_tire_load", "rear_tire_load"):  # the peak and the series, relative to the reference's peak
        assert check[tire].peak_difference <= FORCE_TOLERANCE and check[tire].series_difference <= FORCE_TOLERANCE
    assert check.passed, check.line()
    front, rear = check["front_tire_load"].engine_peak, check["rear_tire_load"].engine_peak
    if name == "flat":  # nothing to meet: each tire holds its static load
        assert front == pytest.approx(STATIC_N["front"], rel=0.01) and rear == pytest.approx(STATIC_N["rear"], rel=0.01)
    elif name == "iso8608":  # class D at 4-6 m/s: a rough road, not a hit
        assert front > 1.1 * STATIC_N["front"] and rear > 1.04 * STATIC_N["rear"]
    elif name == "climb":  # the grade's concave entry (0.05 1/m) at v: v^2 / 20 m/s^2 more on each wheel
        assert front > (1.0 + 0.8 * speed**2 * 0.05 / 9.81) * STATIC_N["front"] and rear > 1.1 * STATIC_N["rear"]
    elif name in ("drop", "step_down"):  # the rear follows down: it may land softer than it stood
        assert front > 1.5 * STATIC_N["front"] and rear > STATIC_N["rear"]
    else:  # the feature met at both ends: each tire's load rose well above its static value
        assert front > 1.5 * STATIC_N["front"] and rear > 1.5 * STATIC_N["rear"]
    if name == "drop" and speed == 4.0:  # the fork into its bumper: the fine step was used and checked
        assert check.context["refined_fraction"] > 0.0

"""MuJoCo's bike against the bike's own ODE reference (``mtbmj.bike.reference``: the closed-form
planar equations integrated by scipy, the terrain's contact patches found afresh at every
evaluation) on terrains of the library, 0.5 s each at 5 m/s (the drop at 6 m/s) with the feature
0.4 m ahead of the front axle, so both wheels cross it (the rear lands from the ledge within the
0.5 s): travel at both ends within 0.1 mm, the tire-load peaks within
1 %. The root is a 181-point polygon (a corner every 0.9 mm), the square edge has vertical walls,
the drop is the paper's load case (a ledge, here 150 mm, taken at speed)."""
from __future__ import annotations

import pytest

from mtbmj.bike.crosscheck import FORCE_TOLERANCE, TOLERANCE_MM, crosscheck


@pytest.mark.parametrize("scenario,speed", [("root:at_m=0.4", 5.0), ("square_edge:at_m=0.4,height_mm=40", 5.0),
                                            ("drop:at_m=0.4,height_mm=150", 6.0)])
def test_mujoco_matches_the_bike_reference(scenario, speed):
    check = crosscheck("sst", scenario, speed, duration=0.5)
    d, p = check.differences, check.peaks
    assert d["front_travel_mm"]["max_abs_mm"] <= TOLERANCE_MM
    assert d["rear_travel_mm"]["max_abs_mm"] <= TOLERANCE_MM
    assert d["stroke_mm"]["max_abs_mm"] <= TOLERANCE_MM
    assert p["front_tire"]["relative"] <= FORCE_TOLERANCE and p["rear_tire"]["relative"] <= FORCE_TOLERANCE
    # the run did meet the feature at both ends: each tire's load rose well above its static value
    assert p["front_tire"]["engine_N"] > 1.5 * 425.0 and p["rear_tire"]["engine_N"] > 1.2 * 567.0
    assert check.passed

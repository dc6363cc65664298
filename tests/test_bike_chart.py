"""A bike from a geometry chart (issue 40 item 1): [geometry] with head angle, wheelbase, chainstay,
BB drop and offset gives the frame's axles; reach, stack, head tube and axle-to-crown find the
front axle a second way and must agree. The chart's numbers are checked here on the built bike
through MuJoCo's own kinematics (test_bike_geometry's level-axle head angle) and the summary."""
from __future__ import annotations

import math

import pytest

import mtbmj
from mtbmj.bike import run as bike_run
from mtbmj.config import ConfigError
from tests.test_bike_geometry import _level_head_angle

CHART = {"head_angle_deg": 64.5, "wheelbase_mm": 1240.0, "chainstay_mm": 440.0, "bb_drop_mm": 30.0,
         "fork_offset_mm": 44.0}


def _reach_stack(head_tube=110.0, crown=560.0):
    """Reach and stack that agree with CHART: the head tube's top, up the steering axis from the
    front axle CHART gives (its offset back, then head tube and axle-to-crown up the axis)."""
    a = math.radians(CHART["head_angle_deg"])
    front = (CHART["wheelbase_mm"] - math.sqrt(CHART["chainstay_mm"] ** 2 - CHART["bb_drop_mm"] ** 2),
             CHART["bb_drop_mm"])
    along, off = head_tube + crown, CHART["fork_offset_mm"]
    return (front[0] - along * math.cos(a) - off * math.sin(a), front[1] + along * math.sin(a) - off * math.cos(a))


def _file(tmp_path, chart: dict, extra: str = "") -> str:
    lines = ['base = "trail"', extra, "[geometry]"] + [f"{k} = {v!r}" for k, v in chart.items()]
    path = tmp_path / "chart.toml"
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_a_chart_builds_the_bike_it_describes(tmp_path):
    path = _file(tmp_path, CHART)
    p = bike_run.prepare(path, "flat", 4.0)
    assert _level_head_angle(p) == pytest.approx(64.5, abs=1e-9)
    (fx, fz), (rx, rz) = p.spec.front_axle, p.spec.rear_axle
    assert math.hypot(fx - rx, fz - rz) * 1e3 == pytest.approx(1240.0, abs=1e-9)
    assert math.hypot(rx, rz) * 1e3 == pytest.approx(440.0, abs=1e-9) and rz * 1e3 == pytest.approx(30.0)
    g = mtbmj.run_bike(path, "flat", speed_m_per_s=4.0, duration=0.05).summary["geometry"]["chart"]
    assert g["wheelbase_mm"] == pytest.approx(1240.0) and g["head_angle_deg"] == pytest.approx(64.5)
    assert g["bb_height_mm"] == pytest.approx(p.front_tire.radius * 1e3 - 30.0)


def test_reach_and_stack_that_agree_are_taken_and_ones_that_do_not_are_refused(tmp_path):
    reach, stack = _reach_stack()
    full = {**CHART, "reach_mm": round(reach, 1), "stack_mm": round(stack, 1), "head_tube_mm": 110.0,
            "fork_length_mm": 560.0}
    mtbmj.bike.spec.load(_file(tmp_path, full))  # within 5 mm (the rounding: 0.1 mm)
    with pytest.raises(ConfigError, match=r"geometry: reach 472\.9, stack 635\.8, .* 20 mm from where wheelbase 1240"):
        mtbmj.bike.spec.load(_file(tmp_path, {**full, "stack_mm": round(stack, 1) + 20.0}))
    with pytest.raises(ConfigError, match="geometry.stack_mm: needed with"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "reach_mm": 470.0}))


def test_a_chart_and_axles_in_one_file_are_refused(tmp_path):
    with pytest.raises(ConfigError, match="two ways"):
        mtbmj.bike.spec.load(_file(tmp_path, CHART, "[bike]\nfront_axle_mm = [800.0, 10.0]"))

"""A Horst link's rear brake on the link that carries its caliper (issue 40 item 2): the bike runs the
axle on an arm about the circle that fits the axle path, but the brake's couple turns the caliper's
link (the seatstay, or the chainstay), whose turn per the arm's differs; the arm's hinge gets the
couple times that ratio. Checked against the mechanism solved in tests/test_linkage.py (its coupler's
and input link's turns by a root finder), Python = compiled, MuJoCo = the reference, and the
braking rear's travel ordered as the construction's anti-rise says."""
from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from helpers import HORST, MM, FourBar, find, independent, slope_profile


def bike_file(tmp_path, brake_on):
    points = "\n".join(f"{k}_mm = [{v[0] / MM:.6f}, {v[1] / MM:.6f}]" for k, v in HORST.items())
    path = tmp_path / f"horst_{brake_on}.toml"
    path.write_text(f'base = "trail"\n[shock]\nstroke_mm = 50.0\n[linkage]\nkind = "horst_link"\n'
                    f'brake_on = "{brake_on}"\n{points}\n')
    return str(path)


def independent_ratio(pivot, brake_on, travel):
    """d(caliper link's turn) / d(the arm's turn about ``pivot``) at ``travel`` (m), from the four-bar
    solved here: the seatstay is its coupler, the chainstay its input link."""
    w, _, axle = independent("horst_link", HORST)
    fb = FourBar(HORST, "main_pivot", "horst_pivot", "seatstay_rocker", "rocker_pivot")

    def turns(t):
        a = axle(t)
        link = fb.solve(t)[1 if brake_on == "seatstay" else 0]
        return link, math.atan2(a[1] - pivot[1], a[0] - pivot[0])

    t = find(w, travel, -1.0)
    h = 1e-5
    (l1, a1), (l0, a0) = turns(t + h), turns(t - h)
    return (l1 - l0) / (a1 - a0)


@pytest.mark.parametrize("brake_on", ["seatstay", "chainstay"])
def test_the_arm_gets_the_brake_couple_times_the_caliper_link_s_turn(tmp_path, brake_on):
    from mtbmj.bike.run import prepare
    from mtbmj.controllers import installed

    p = prepare(bike_file(tmp_path, brake_on), "flat", 4.0, callback="python")
    m, d, cb = p.bike.model, p.data, p.callback
    d.qvel[p.bike.dof_index("bike_x")] = 6.0  # faster than the set 4 m/s: the rider brakes
    with installed(cb):
        mujoco.mj_forward(m, d)
    tau = d.ctrl[m.actuator("rear_couple").id]
    assert tau > 10.0  # a braking couple on the rear
    axis = d.xaxis[m.joint("swingarm").id][1]
    engine = 1.0 + d.qfrc_applied[p.bike.dof_index("swingarm")] / (tau * axis)
    w = cb.shock_state(d)[0]
    expected = independent_ratio(np.asarray(p.spec.pivot), brake_on, w)
    assert engine == pytest.approx(expected, rel=2e-3)
    if brake_on == "seatstay":  # the floating seatstay turns far less than the arm
        assert engine < 0.6


@pytest.fixture(scope="module")
def descents(tmp_path_factory):
    from mtbmj.bike.run import run_bike

    folder = tmp_path_factory.mktemp("caliper")
    slope = slope_profile(folder, -0.4, "descent")
    return {brake: {"compiled": run_bike(bike_file(folder, brake), slope, 4.0, duration=4.0)}
            for brake in ("seatstay", "chainstay")}


def test_compiled_is_python_braking(tmp_path):
    from mtbmj.bike.run import run_bike

    slope = slope_profile(tmp_path, -0.4, "descent")
    a, b = (run_bike(bike_file(tmp_path, "seatstay"), slope, 4.0, duration=1.5, callback=cb).raw
            for cb in ("compiled", "python"))
    assert np.min(a["drive_force_N"]) < -100.0  # braked
    for key in ("rear_travel_mm", "front_travel_mm", "pitch_deg"):
        assert np.max(np.abs(a[key] - b[key])) < 1e-9, key


def test_the_caliper_s_link_sets_how_the_rear_sits_braking(descents, tmp_path):
    """Braking down 40 %, the seatstay caliper (anti-rise 55-69 % by the construction, mtbmj linkage)
    lets the rear extend more than the chainstay caliper on the main pivot (higher anti-rise)."""
    from mtbmj.bike import rear_end

    rise = {b: rear_end.for_bike(bike_file(tmp_path, b)).summary()["at_30_percent_travel"]["anti_rise_percent"]
            for b in ("seatstay", "chainstay")}
    assert rise["seatstay"] < rise["chainstay"]
    end = {b: float(np.mean(r["compiled"].raw["rear_travel_mm"][-400:])) for b, r in descents.items()}
    assert end["seatstay"] < end["chainstay"] - 1.0, end


@pytest.mark.slow
def test_braking_horst_against_the_reference(tmp_path):
    from mtbmj.bike.crosscheck import crosscheck

    check = crosscheck(bike_file(tmp_path, "seatstay"), slope_profile(tmp_path, -0.4, "descent"), 4.0, duration=1.5)
    assert check.passed, check.line()

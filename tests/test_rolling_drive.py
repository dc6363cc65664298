"""A drive a rider could give (issue 25): the rolling front end is kept moving by a speed
controller within a rider's push, power and braking, so a rock can slow it and nothing relaunches
it faster than it came; the ideal servo stays available by name. The law is checked in closed
form, the runs against the limits and against the work integral taken here from the raw signals."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj import cli
from mtbmj.controllers.drive import RIDER_BRAKE_N, RIDER_POWER_W, RIDER_PUSH_N, Drive, drive_force
from mtbmj.rolling.frontend import run_roll
from helpers import one_line

ROCK = "rock:height_mm=250"  # a rock big enough to strike the rim and stop the wheel at 3 m/s


def test_the_law_in_closed_form():
    kv = 5000.0
    assert drive_force(3.0, 2.99, kv, 400.0, 600.0, 300.0) == pytest.approx(50.0)  # inside the limits: kv dv
    assert drive_force(3.0, 0.5, kv, 400.0, 600.0, 300.0) == 400.0  # the push limit (600 W / 0.5 m/s > 400 N)
    assert drive_force(3.0, 2.0, kv, 400.0, 600.0, 300.0) == pytest.approx(300.0)  # the power limit: 600 W / 2 m/s
    assert drive_force(3.0, 3.5, kv, 400.0, 600.0, 300.0) == -300.0  # the brake limit
    assert drive_force(3.0, 0.0, kv, 400.0, 600.0, 300.0) == 400.0  # at rest the power limit does not divide by 0
    assert Drive("coast", kv).force(3.0, 1.0) == 0.0
    assert (RIDER_PUSH_N, RIDER_POWER_W, RIDER_BRAKE_N) == (418, 580, 328)


@pytest.fixture(scope="module")
def runs():
    return {mode: run_roll(ROCK, 3.0, drive=mode) for mode in ("rider", "servo", "coast")}


def test_the_rider_never_pushes_past_the_limits_and_never_relaunches(runs):
    r = runs["rider"]
    force, speed = r.raw["drive_force_N"], r.raw["speed_m_per_s"]
    push = np.minimum(RIDER_PUSH_N, RIDER_POWER_W / np.maximum(speed, 1e-9))
    assert np.all(force <= push + 1e-6) and np.all(force >= -RIDER_BRAKE_N - 1e-6)
    d = r.summary["drive"]
    assert d["min_speed_m_per_s"] < 2.0  # the rock slows the front end: the drive cannot hold it
    assert d["max_speed_m_per_s"] <= 3.0 * 1.02  # and nothing launches it faster than it came
    assert d["limit_bound_s"] > 0.1
    # the work reported is the integral of force x speed over the raw signals, each row held until the
    # next (the rows are the fine step apart in a fine stretch, the coarse step elsewhere)
    t = r.raw["time_s"]
    assert np.ptp(np.diff(t)) > 0.5 * r.info["timestep_s"]  # both spacings are there
    power = force * speed
    assert d["work_J"] == pytest.approx(float(np.sum(power[:-1] * np.diff(t)) + power[-1] * r.info["timestep_s"]),
                                        rel=1e-6)


def test_the_ideal_servo_pushes_with_whatever_force_it_takes(runs):
    servo = runs["servo"].summary["drive"]
    assert servo["max_push_N"] > 10 * RIDER_PUSH_N  # the force no rider has (the 37.7 kN kind)
    assert servo["max_speed_m_per_s"] > 3.0 * 1.05  # and it relaunches the front end past its speed
    assert servo["work_J"] > runs["rider"].summary["drive"]["work_J"]


def test_coasting_puts_nothing_in(runs):
    d = runs["coast"].summary["drive"]
    assert d["work_J"] == 0.0 and d["max_push_N"] == 0.0 and d["max_brake_N"] == 0.0
    assert d["max_speed_m_per_s"] <= 3.0 + 1e-9


@pytest.mark.parametrize("mode", ["rider", "coast"])
def test_both_callbacks_drive_alike(mode):
    pytest.importorskip("numba")
    a = run_roll("square_edge", 4.0, drive=mode, callback="compiled", duration=0.6)
    b = run_roll("square_edge", 4.0, drive=mode, callback="python", duration=0.6)
    for column in ("x_m", "fork_mm", "drive_force_N"):
        assert np.array_equal(a.raw[column], b.raw[column]), column


def test_the_command_line_names_the_drive_and_refuses_bad_limits(tmp_path, capsys):
    assert cli.main(["roll", "square_edge", "--speed", "4", "--duration", "0.6", "--quiet", "--no-figure",
                     "--drive-push-N", "200", "--out", str(tmp_path / "r")]) == 0
    assert "drive rider:" in capsys.readouterr().out
    one_line(capsys, ["roll", "rock", "--speed", "3", "--drive", "coast", "--drive-power-W", "100",
                      "--out", tmp_path / "x"], "--drive-power-W", "--drive rider")
    one_line(capsys, ["roll", "rock", "--speed", "3", "--drive-brake-N", "-5", "--out", tmp_path / "x"],
             "--drive-brake-N", "at least 0")
    one_line(capsys, ["roll", "rock", "--speed", "3", "--drive", "jet", "--out", tmp_path / "x"], "--drive")
    assert not (tmp_path / "x").exists()

"""The active rider along a speed profile (``run_bike(..., rider="active", speed_profile=)``, ``mtbmj bike
--rider active --speed-profile``): its callback (``RiderCallback.set_speed``) passes the set speed to the drive it
wraps and to its controller's look-ahead, between the run's chunks (``mtbmj.bike.schedule``).

The check is the passive rider's (tests/test_bike_schedule.py) on a profile written here, 4 m/s to 20 m, then
6 m/s from 30 m, on flat terrain: the run's speed where the front axle is within the same 8 % of the profile's
on both holds, and the time to ride 10-45 m within the same 3 % of the profile's integral of 1/v (the closed
form: a metre takes 1 / v), against a run of the same rider at one speed (4 m/s), which must miss both."""
from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from mtbmj.bike.run import run_bike

X = np.array([-100.0, 20.0, 30.0, 300.0])
V = np.array([4.0, 4.0, 6.0, 6.0])
TERRAIN = "flat:length_m=80"
# on the holds: within the ramp 20-30 m the set speed is updated a chunk late (0.512 s under the refinement
# plan, mtbmj.bike.schedule), 8.1 % slow at 25 m and 8.9 % at 30 m, the passive rider 8.1 % and 8.8 % (measured)
PLACES = (5.0, 15.0, 40.0, 45.0)
STRETCH = (10.0, 45.0)


def _time_over(raw, a: float, b: float) -> float:
    x, t = raw["front_axle_x_m"], raw["time_s"]
    return float(np.interp(b, x, t) - np.interp(a, x, t))


def _profile_time(a: float, b: float) -> float:
    xs = np.linspace(a, b, 2001)
    return float(np.trapezoid(1.0 / np.interp(xs, X, V), xs))


@pytest.fixture(scope="module")
def ridden():
    return run_bike("sst", TERRAIN, 4.0, duration=10.0, rider="active", speed_profile=(X, V))


def test_the_rider_callback_passes_the_set_speed_to_its_drive_and_its_look_ahead():
    """``set_speed`` reaches the drive the callback wraps and ``Controller.speed`` (the lead before an edge)."""
    from mtbmj.bike.rider_control import RiderCallback

    got = []
    fake = SimpleNamespace(inner=SimpleNamespace(set_speed=got.append), controller=SimpleNamespace(speed=4.0))
    RiderCallback.set_speed(fake, 6.5)
    assert got == [6.5] and fake.controller.speed == 6.5


@pytest.mark.slow
def test_the_active_rider_holds_the_profile_s_speed_where_the_front_axle_is(ridden):
    raw = ridden.raw
    assert ridden.summary["crash"] is None and ridden.summary["rider"]["kind"] == "active"
    assert ridden.summary["speed_profile_m_per_s"] == [4.0, 6.0]
    x, v = raw["front_axle_x_m"], raw["speed_m_per_s"]
    assert x[-1] > STRETCH[1] + 1.0, x[-1]
    for at in PLACES:
        i = int(np.searchsorted(x, at))
        assert v[i] == pytest.approx(np.interp(at, X, V), rel=0.08), (at, v[i])
    want = _profile_time(*STRETCH)
    assert _time_over(raw, *STRETCH) == pytest.approx(want, rel=0.03), (_time_over(raw, *STRETCH), want)
    # the check can fail: the same rider at one speed (the start's) misses the places on the fast hold and the time
    held = run_bike("sst", TERRAIN, 4.0, duration=12.5, rider="active")
    hx, hv = held.raw["front_axle_x_m"], held.raw["speed_m_per_s"]
    assert hx[-1] > STRETCH[1], hx[-1]
    assert any(abs(hv[int(np.searchsorted(hx, at))] - np.interp(at, X, V)) > 0.08 * np.interp(at, X, V)
               for at in PLACES)
    assert abs(_time_over(held.raw, *STRETCH) - want) > 0.1 * want


@pytest.mark.slow
def test_the_command_rides_a_speed_profile_with_the_active_rider(tmp_path):
    """``mtbmj bike ... --speed-profile CSV --rider active``: exit 0, the summary's set range the profile's, the
    rider the active one, and the run at the profile's speeds (4 then 6 m/s)."""
    from mtbmj.cli import main

    prof = tmp_path / "speed.csv"
    prof.write_text("distance_m,speed_m_per_s\n0,4\n20,4\n30,6\n200,6\n")
    out = tmp_path / "out"
    assert main(["bike", "sst", TERRAIN, "--speed-profile", str(prof), "--rider", "active", "--duration", "8",
                 "--no-figure", "--quiet", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["speed_m_per_s"] == 4.0 and s["speed_profile_m_per_s"] == [4.0, 6.0] and s["rider"]["kind"] == "active"
    assert s["min_speed_m_per_s"] == pytest.approx(4.0, abs=0.1)
    assert s["max_speed_m_per_s"] == pytest.approx(6.0, abs=0.3)

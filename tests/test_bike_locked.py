"""The bike with its rear locked and a 90 degree head angle reproduces the rolling front end's rig.

What makes the two the same mechanical system. The rig (``mtbmj roll``) is a chassis sliding in x
and z with no pitch, a fork sliding along the steering axis below it, and one wheel with the radial
tire. The bike becomes that when:

* ``pitch`` is held (the rig's chassis cannot pitch; with pitch free the front tire's load would
  rotate the bike instead of only lifting it);
* ``rear`` is held (the swingarm: the shock locked out) and ``rider`` is held (the rider rigid on
  the frame): frame, swingarm, rear wheel and rider then move as one body in x and z, the rig's
  chassis;
* the rear tire is off (``rear_tire=False``): the rig stands on its front wheel alone, so the
  bike's rear wheel must carry nothing (no tire force, no rim strike, no drive through it);
* the head angle is 90 degrees (the issue's case; the fork offset is then a constant horizontal
  shift of the axle and drops out of a motion with no pitch);
* both coast (the bike's drive acts through the rear tire, which is off);
* the masses match: the rig's chassis (``sled.body_mass_kg``) = everything above the fork (frame,
  swingarm, rear wheel, rider and the rider's on-bike segments: the bike's total less the fork
  lower and the front wheel), the rig's unsprung mass (``sled.wheel_mass_kg``, split between its
  fork lower and wheel; only the sum enters) = the bike's fork lower + front wheel. The wheels' spin
  inertia does not enter (free spin, forces at the axle);
* the same fork configuration (fork law, tire rate and damping, rim, gravity, integrator) and the
  same start: the front axle over the terrain's start in the front wheel's static equilibrium.

A held joint is MuJoCo's own: an armature of 1e12 on its degree of freedom (``run.LOCK_ARMATURE``),
no constraint, no compliance. At the same step (0.1 ms) the two MJCF models then agree to round-off:
fork travel within 1e-8 mm and the tire load within 3e-7 N on the root (measured), so the test
holds them to 1e-6 mm and 1e-4 N (the armature leaves a coupling of order 1e-8 of the motion).
``run_roll`` as a user runs it steps at its own step rule's 0.01 ms for this fork (the bike at
0.1 ms, no stop refinement); there the difference is the integrators' step error: 0.0080 mm of fork
travel and 2.5 N of 1650 N on the root at 4 m/s (0.0106 mm, 4.4 N on the square edge at 5 m/s),
within the 0.02 mm the front end's own ODE cross-check allows (tests/test_rolling_reference.py).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from mtbmj.bike import spec as spec_mod
from mtbmj.bike.run import run_bike
from mtbmj.errors import ConfigError
from mtbmj.rolling import frontend

SCENARIO, SPEED, DURATION = "root:at_m=0.4", 4.0, 0.5
LOCKED = ("rear", "pitch", "rider")


def _bike_and_rig():
    bike = dataclasses.replace(spec_mod.load("sst"), head_angle=math.radians(90.0))
    unsprung = bike.fork_lower_mass + bike.front_wheel_mass
    overrides = dict(bike.fork_overrides)
    overrides["sled.body_mass_kg"] = bike.total_mass - unsprung
    overrides["sled.wheel_mass_kg"] = unsprung
    return bike, overrides


@pytest.fixture(scope="module")
def locked():
    bike, overrides = _bike_and_rig()
    return run_bike(bike, SCENARIO, SPEED, DURATION, drive="coast", lock=LOCKED, rear_tire=False), bike, overrides


def test_locked_bike_is_the_front_end_rig_at_the_same_step(locked):
    result, bike, overrides = locked
    a = result.raw
    step = result.info["timestep_s"]
    p = frontend.prepare(SCENARIO, SPEED, bike.fork_config, 90.0, overrides, drive="coast")
    p.setup = dataclasses.replace(p.setup, timestep=step, substeps=1)  # the bike's step
    p.front.model.opt.timestep = step
    states, sensors = frontend.simulate(p, DURATION)
    b = frontend._signals(p, states, sensors)
    assert a["time_s"].size == b["time_s"].size
    assert np.max(np.abs(a["time_s"] - b["time_s"])) < 1e-12
    # the held joints held: no pitch, no rear travel
    assert np.max(np.abs(a["pitch_deg"])) < 1e-6
    assert np.ptp(a["rear_travel_mm"]) < 1e-6
    assert np.max(a["rear_tire_N"]) == 0.0
    # the root is met: the fork works through ~40 mm past its sag
    assert a["front_travel_mm"].max() - a["front_travel_mm"][0] > 30.0
    assert np.max(np.abs(a["front_travel_mm"] - b["fork_mm"])) < 1e-6
    assert np.max(np.abs(a["front_tire_N"] - b["tire_force_N"])) < 1e-4
    assert np.max(np.abs(a["speed_m_per_s"] - b["speed_m_per_s"])) < 1e-9


def test_locked_bike_against_run_roll_as_run(locked):
    result, bike, overrides = locked
    a = result.raw
    rig = frontend.run_roll(SCENARIO, SPEED, bike.fork_config, 90.0, DURATION, overrides=overrides, drive="coast")
    b = {k: v[rig.grid_rows] for k, v in rig.raw.items()}  # the front end's coarse grid (it keeps finer rows too)
    every = int(round(result.info["timestep_s"] / rig.info["timestep_s"]))
    assert every >= 1
    fork, load, t = (b[k][::every][:a["time_s"].size] for k in ("fork_mm", "tire_force_N", "time_s"))
    assert np.max(np.abs(t - a["time_s"])) < 1e-9
    assert a["front_travel_mm"][0] == pytest.approx(b["fork_mm"][0], abs=1e-9)  # the same static sag
    assert np.max(np.abs(a["front_travel_mm"] - fork)) < 0.02  # the two steps' error (docstring)
    assert np.max(np.abs(a["front_tire_N"] - load)) < 0.01 * np.max(load)


def test_rear_tire_off_needs_pitch_locked():
    with pytest.raises(ConfigError, match="pitch"):
        run_bike("sst", "flat", 4.0, 0.01, lock=("rear",), rear_tire=False)
    with pytest.raises(ConfigError, match="lock"):
        run_bike("sst", "flat", 4.0, 0.01, lock=("fork",))


def test_rear_locked_holds_its_sag():
    free = run_bike("sst", "root:at_m=0.4", 4.0, 0.05)
    held = run_bike("sst", "root:at_m=0.4", 4.0, 0.05, lock="rear")
    assert held.raw["rear_travel_mm"][0] == pytest.approx(free.raw["rear_travel_mm"][0], abs=1e-9)
    assert np.ptp(held.raw["rear_travel_mm"]) < 1e-6
    assert held.info["locked"] == ["rear"]

"""The rider's legs and arms: the callback's spring-dampers on the rider's joints against MuJoCo's own
spatial tendons with the same stiffness, damping and rest length (MuJoCo computes the tendon's
length, its Jacobian and its passive force itself), at random poses and speeds of the whole bike, on
the Python and the compiled callback. (The whole runs are checked against the bike's ODE reference,
whose limbs are its own closed form, in tests/test_bike_reference.py.)"""
from __future__ import annotations

import numpy as np
import pytest

import mujoco

from mtbmj.bike.run import prepare

JOINTS = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_z", "rider_pitch")


def _with_tendons(p):
    """The bike's drawn model (its tendons between the same sites) with the limbs' springs set on
    the tendons, MuJoCo's passive forces."""
    m = p.visual_model()
    for limb in p.bike.limbs:
        t = m.tendon(limb.name).id
        for field, value in ((m.tendon_stiffness, limb.stiffness), (m.tendon_damping, limb.damping)):
            if field.ndim == 2:
                field[t] = 0.0
                field[t, 0] = value
            else:
                field[t] = value
        m.tendon_lengthspring[t] = [limb.rest, limb.rest]
    return m


def _random_state(p, m, d, rng):
    b = p.bike
    mujoco.mj_resetData(m, d)
    d.qpos[:] = p.initial_qpos
    spread = {"bike_x": 0.5, "bike_z": 0.05, "pitch": 0.3, "fork": 0.05, "swingarm": 0.2, "rider_z": 0.08,
              "rider_pitch": 0.3}
    for name, s in spread.items():
        d.qpos[b.qpos_index(name)] += rng.uniform(-s, s)
        d.qvel[b.dof_index(name)] = rng.uniform(-2.0, 2.0)
    # half a metre up: the tires in the air whatever the pitch (the limbs do not depend on where
    # the frame is; a wheel sunk into the ground would make MuJoCo warn of a huge tire force)
    d.qpos[b.qpos_index("bike_z")] += 0.5


@pytest.mark.parametrize("callback", ["python", "compiled"])
def test_limb_forces_equal_mujocos_tendons(callback):
    if callback == "compiled":
        pytest.importorskip("numba")
    from mtbmj.controllers import installed

    p = prepare("sst", "flat", 4.0, callback=callback)
    b = p.bike
    tendons = _with_tendons(p)
    dt = mujoco.MjData(tendons)
    d = mujoco.MjData(b.model)
    rng = np.random.default_rng(11)
    rider = [b.dof_index("rider_z"), b.dof_index("rider_pitch")]
    others = [b.dof_index(n) for n in JOINTS[:5]]
    biggest = 0.0
    for _ in range(50):
        _random_state(p, tendons, dt, rng)
        mujoco.mj_forward(tendons, dt)  # no callback: MuJoCo's tendons alone push
        d.qpos[:], d.qvel[:], d.act[:] = dt.qpos, dt.qvel, p.initial_act
        with installed(p.callback):
            mujoco.mj_forward(b.model, d)
        expected = dt.qfrc_passive
        # the tendons act on the rider's joints only (the frame's cancel between the two sites)
        assert np.max(np.abs(expected[others])) < 1e-9
        np.testing.assert_allclose(d.qfrc_applied[rider], expected[rider], rtol=1e-10, atol=1e-9)
        biggest = max(biggest, float(np.max(np.abs(expected[rider]))))
    assert biggest > 100.0  # the poses stretched the limbs (N, N m)


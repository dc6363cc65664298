"""Energy balance of the bike on a rock garden: the change of MuJoCo's own kinetic and potential
energy (gravity, ``mjENBL_ENERGY``) and of the legs' and arms' springs (worked out here from the
distance between their sites) equals the work of every force the callback applies (the fork's force
and the shock's torque times their joints' speeds, the tire and drive forces applied at the axles
times the axles' velocities) and of the legs' and arms' dampers (their rate of extension from the
sites' velocities), within 1 % of the energy turned over. The rock garden is a profile written
in tests/helpers.py (a CSV of seven rocks, 50-110 mm high), read through the terrain library's CSV path."""
from __future__ import annotations

import mujoco
import numpy as np

from helpers import rock_garden


def test_energy_balance_on_a_rock_garden(tmp_path):
    from mtbmj.bike.run import prepare, simulate

    # the hub drive: its couple on the swingarm is recorded (rear_couple) and its work counted here;
    # the chain's pull (the presets' drive) is checked by virtual work in tests/test_bike_chain.py
    p = prepare("sst", str(rock_garden(tmp_path / "rocks.csv")), 5.0, overrides={"drive.chain": False})
    states, sensors = simulate(p, 0.5)
    m = p.bike.model
    m.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    d = mujoco.MjData(m)
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    n = sensors.shape[0]
    energy = np.empty(n + 1)
    power = np.empty(n)
    turnover = np.empty(n)
    adr = lambda name: m.sensor_adr[m.sensor(name).id]
    # the fork's force and the shock's torque: motors on their joints (force times joint speed)
    joint_motors = [(m.actuator(name).id, adr(name)) for name in ("fork_force", "shock_torque")]
    # the tire and drive forces: applied at the axles (world x and z, recorded by the probes),
    # their power the force times the axle's velocity
    axles = [(m.site("front_axle").id, ("front_tire", "front_ground")), (m.site("rear_axle").id, ("rear_tire", "drive"))]
    # the couples of the ground's tangential forces about the axles (they act at the contact patches),
    # on the fork lower and the swingarm: their power is the couple times the body's angular velocity
    # about world y (virtual work: what the couple does, not what the code meant it to do)
    couples = [(m.body("fork_lower").id, adr("front_couple")), (m.body("swingarm").id, adr("rear_couple"))]
    spin = np.zeros(6)
    velocity = np.zeros(6)
    r = p.spec.rider
    # the legs and arms: (frame site, rider site, stiffness, damping, rest length)
    limbs = [(m.site("pedals").id, m.site("hips").id, r.leg_stiffness, r.leg_damping, p.bike.legs_rest),
             (m.site("bars").id, m.site("shoulders").id, r.arm_stiffness, r.arm_damping, p.bike.arms_rest)]
    v_frame, v_rider = np.zeros(6), np.zeros(6)
    for i in range(n + 1):
        mujoco.mj_setState(m, d, states[i], kind)
        mujoco.mj_forward(m, d)
        energy[i] = d.energy[0] + d.energy[1]
        rates = []
        for fs, rs, k, c, rest in limbs:
            line = d.site_xpos[rs] - d.site_xpos[fs]
            length = np.linalg.norm(line)
            energy[i] += 0.5 * k * (length - rest) ** 2
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, fs, v_frame, 0)
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, rs, v_rider, 0)
            rates.append((c, line @ (v_rider[3:] - v_frame[3:]) / length))
        if i == n:
            break
        parts = [sensors[i, column] * d.actuator_velocity[a] for a, column in joint_motors]
        for site, forces in axles:
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, site, velocity, 0)
            for name in forces:
                parts.append(sensors[i, adr(f"{name}_x")] * velocity[3] + sensors[i, adr(f"{name}_z")] * velocity[5])
        for body, column in couples:
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, body, spin, 0)
            parts.append(sensors[i, column] * spin[1])
        parts += [-c * rate ** 2 for c, rate in rates]
        power[i] = sum(parts)
        turnover[i] = sum(abs(x) for x in parts)
    dt = p.timestep
    # the work over each step by the trapezoid rule (the last step's end power: one more evaluation)
    work = dt * (0.5 * power[0] + np.sum(power[1:]))
    work_end = dt * 0.5 * power[-1]
    total_work = work + work_end
    scale = np.sum(turnover) * dt
    change = energy[-1] - energy[0]
    assert scale > 200.0  # the rocks were met: hundreds of joules went through the tires and dampers
    print(f"energy change {change:.3f} J, work {total_work:.3f} J, turned over {scale:.1f} J")
    assert abs(change - total_work) <= 0.01 * scale, (change, total_work, scale)

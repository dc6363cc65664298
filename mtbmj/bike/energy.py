"""The energy balance of a bike run with the active rider (``mtbmj bike --rider active``): the change
of the whole system's mechanical energy against the work of every force that acts on it, term by
term, the muscles' work among them.

Stored (J, at each recorded state): MuJoCo's kinetic and gravitational energy of the model
(``mj_energyVel``, ``mj_energyPos`` with ``mjENBL_ENERGY``); the springs the rider's callback
applies (``mtbmj.bike.rider_control``): the feet's and hands' pins (1/2 k d^2 over their stretch in
the pitch plane) and the joints' end stops past the range of motion (1/2 k a^2 over the angle
past it); the fork's and the shock's springs (each law's own ``elastic_energy``: main spring,
bumper, end stops; the shock at its stroke, ``leverage.stroke`` of the rear wheel's travel) and
their friction states (1/2 k z^2, the drop's energy balance's convention).

Work (J, the power at each recorded state integrated by the trapezoid rule over the run's output
step):

* ``muscles``: each joint's muscle torque times the joint's anatomical speed, its positive and its
  negative work apart (``muscle_positive``, ``muscle_negative``, summed over the joints per state),
  pedalling the driving leg's joints among them (``pedal_leg_J``, ``pedal_leg_positive_J`` apart;
  ``crank_J``, not a term, the foot's work on its pedal: the crank's);
* ``tissue``: the joints' passive damping; ``stops_damping``: the end stops' damping;
* ``pins_damping``: the pins' dampers; ``saddle``: the saddle's one-sided push (its spring and damper
  are cut off together where the sum would pull, so they are not split: its work as one);
* ``fork_damping_friction``, ``shock_damping_friction``: the laws' forces on their joints (the fork's
  force, the shock's torque) times the joints' speeds, less their springs' and friction states'
  stored change: the damping, the friction and the stops' damping;
* ``tires``: each tyre's radial force at its axle times the axle's velocity: its spring and its
  damping as one (not split: a contact shared between patches, ``rolling.tire.share_depths``, has no
  one stored energy to write), so the tyres' springs appear as work;
* ``drive``: every other applied wrench (``xfrc_applied``): the drive's and the brakes' forces at
  the axles and their couples, a pedalling foot's push on the pedal and its reaction on the trunk
  (and the legs' swing on the trunk, ``PedalLeg.swing``), less the driving leg's muscles' power (``mtbmj.bike.pedal_leg``: the muscles' terms hold it), so
  pedalling leaves here the chain's and the ground's work less the crank's (the crank's angle is the
  bike's x rolled through the gear, the ground's push the chain's at the loaded radius);
* ``mujoco_passive``, ``mujoco_constraint``: MuJoCo's own joint springs, damping and constraint
  forces (limits, contacts). The bike's model has none (no joint damping, no armature outside the
  settling, no limits, no contacts: the tyres are the callback's forces): both are 0, and are
  computed so a model that had them would show it.

The residual is what is left: the stepping's error (RK4 at the run's step) and the trapezoid rule's
over the output samples, not told apart here. ``unsplit_W`` is the largest difference, over the states, between
``qfrc_applied + qfrc_actuator`` . qvel and the named terms' power (the rider's, with its springs',
and the laws'): 0 when every applied generalised force was named. ``work_done_J``, the scale the
residual is judged against, is the sum over the states of each force's absolute power (the laws'
and the tyres' whole forces) times the step.
"""
from __future__ import annotations

import math

import mujoco
import numpy as np

from mtbmj.bike import rider_body as rb
from mtbmj.bike import rider_control as rc
from mtbmj.controllers import installed

STORED = ("kinetic_gravity", "pins_spring", "stops_spring", "fork_spring", "shock_spring", "fork_friction_state",
          "shock_friction_state")
WORKS = ("muscle_positive", "muscle_negative", "tissue", "stops_damping", "pins_damping", "saddle", "fork", "shock",
         "tires", "drive", "mujoco_passive", "mujoco_constraint")
# each law's work is reported less its spring's and its friction state's stored change (its damping and friction)
ELASTIC = {"fork": ("fork_spring", "fork_friction_state"), "shock": ("shock_spring", "shock_friction_state")}


def rider_terms(cb: rc.RiderCallback) -> dict:
    """The rider's powers (W) and springs' stored energies (J) at the callback's last evaluation."""
    last = cb.last
    speed, taus, stops = last["speed"], last["taus"], last["stops"]
    out = dict.fromkeys(("muscle_positive", "muscle_negative", "tissue", "stops_damping", "pins_damping", "saddle",
                         "pins_spring", "stops_spring", "pedal_leg", "crank"), 0.0)
    leg = last.get("leg")
    out["crank"] = 0.0 if leg is None else leg["crank_power"]
    for pw in ([] if leg is None else [leg["taus"][k] * leg["rates"][k] for k in leg["taus"]]):
        out["muscle_positive" if pw > 0.0 else "muscle_negative"] += pw  # the driving leg's (pedal_leg)
        out["pedal_leg"] += pw
    for k in rc.JOINTS:
        w = speed[k]
        pw = taus[k] * w
        out["muscle_positive" if pw > 0.0 else "muscle_negative"] += pw
        out["tissue"] -= rc.TISSUE_DAMPING * w * w
        past = rb.stop_penetration(last["now"][k], *cb.ranges[k])
        if past != 0.0:
            out["stops_damping"] -= rb.stop_damping(past) * w * w
            out["stops_spring"] += rb.stop_spring(past)[1]
    for f, rel, gap in last["pins"]:
        out["pins_damping"] -= rc.PIN_N_S_PER_M * (rel[0] * rel[0] + rel[2] * rel[2])
        out["pins_spring"] += 0.5 * rc.PIN_N_PER_M * (gap[0] * gap[0] + gap[2] * gap[2])
    push, closing = last["saddle"]
    out["saddle"] = -push * closing
    return out


def balance(p, states: np.ndarray) -> dict:
    """The energy balance of the prepared active-rider run ``p`` over its recorded ``states``
    (``mtbmj.bike.run.simulate``'s, one row per output step): each state evaluated again with the
    run's callback (its peaks and counts are the run's no longer: call after reporting them).
    Returns the stored energies' changes and each force's work (J), the muscles' positive and
    negative work, the work done (the sum over the states and terms of each term's absolute
    power, times the step), the balance's residual and its share of the work done (%)."""
    m, cb = p.bike.model, p.callback
    if not isinstance(cb, rc.RiderCallback):
        raise TypeError("energy.balance: the run has no active rider")
    d = mujoco.MjData(m)
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    n = states.shape[0]
    times = states[:, 0]
    stored = {k: np.zeros(n) for k in STORED}
    power = {k: np.zeros(n) for k in WORKS}
    unsplit = 0.0
    leg = np.zeros(n)  # the driving leg's muscles' power (W; pedalling, mtbmj.bike.pedal_leg)
    crank = np.zeros(n)  # the foot's power on its pedal (W), the crank's
    a = lambda name: int(m.actuator(name).id)
    a_fork, a_shock = a("fork_force"), a("shock_torque")
    tires = [(int(m.site("front_axle").id), a("front_tire_x"), a("front_tire_z")),
             (int(m.site("rear_axle").id), a("rear_tire_x"), a("rear_tire_z"))]
    vel = np.zeros(6)
    qfrc = np.zeros(m.nv)
    b = p.bike
    fork_q = b.qpos_index("fork")
    lev, rear_z0, frame, rear_site = b.spec.leverage, b.spec.rear_axle[1], int(m.body("frame").id), tires[1][0]
    laws = (("fork_friction_state", p.fork_law, int(m.actuator_actadr[a("fork_friction_state")])),
            ("shock_friction_state", p.shock_law, int(m.actuator_actadr[a("shock_friction_state")])))
    flags = m.opt.enableflags
    m.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    cb.reset()
    try:
        with installed(cb):
            for i in range(n):
                mujoco.mj_setState(m, d, states[i], kind)
                mujoco.mj_forward(m, d)
                v = d.qvel
                stored["kinetic_gravity"][i] = d.energy[0] + d.energy[1]
                terms = rider_terms(cb)
                for k in ("pins_spring", "stops_spring"):
                    stored[k][i] = terms[k]
                for k in ("muscle_positive", "muscle_negative", "tissue", "stops_damping", "pins_damping", "saddle"):
                    power[k][i] = terms[k]
                leg[i], crank[i] = terms["pedal_leg"], terms["crank"]
                # the laws' springs (their own elastic energy: main spring, bumper, stops) and friction states
                rot = d.xmat[frame].reshape(3, 3)
                w = float((rot.T @ (d.site_xpos[rear_site] - d.xpos[frame]))[2]) - rear_z0  # the rear's travel
                stored["fork_spring"][i] = p.fork_law.elastic_energy(float(d.qpos[fork_q]))
                stored["shock_spring"][i] = p.shock_law.elastic_energy(lev.stroke(w))
                for key, law, adr in laws:
                    if law.friction.has_state:
                        stored[key][i] = 0.5 * law.friction.stiffness * float(d.act[adr]) ** 2
                power["fork"][i] = d.actuator_force[a_fork] * d.actuator_velocity[a_fork]
                power["shock"][i] = d.actuator_force[a_shock] * d.actuator_velocity[a_shock]
                tyre = 0.0
                for site, ax, az in tires:
                    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, site, vel, 0)
                    tyre += d.ctrl[ax] * vel[3] + d.ctrl[az] * vel[5]
                power["tires"][i] = tyre
                qfrc[:] = 0.0
                for body in range(1, m.nbody):  # every applied wrench, at its body's centre of mass
                    w = d.xfrc_applied[body]
                    if w.any():
                        mujoco.mj_applyFT(m, d, w[:3], w[3:], d.xipos[body], body, qfrc)
                # less the driving leg's muscles' power: the foot's push on the pedal and its reaction on
                # the trunk, with the crank's and chain's forces, are the work the leg's muscles do
                power["drive"][i] = float(qfrc @ v) - tyre - leg[i]
                power["mujoco_passive"][i] = float(d.qfrc_passive @ v)
                power["mujoco_constraint"][i] = float(d.qfrc_constraint @ v)
                applied = float(d.qfrc_applied @ v) + float(d.qfrc_actuator @ v)
                named = sum(power[k][i] for k in ("muscle_positive", "muscle_negative", "tissue", "stops_damping",
                                                  "pins_damping", "saddle", "fork", "shock"))
                unsplit = max(unsplit, abs(applied - (named - leg[i]) - rider_spring_power(cb)))
    finally:
        m.opt.enableflags = flags
    dt = np.diff(times)
    trap = lambda x: float(np.sum(0.5 * (x[1:] + x[:-1]) * dt))
    work = {k: trap(power[k]) for k in WORKS}
    change = {k: float(stored[k][-1] - stored[k][0]) for k in STORED}
    # the laws' work less their springs' (and friction states') change: their damping and friction
    for law, springs in ELASTIC.items():
        work[f"{law}_damping_friction"] = work.pop(law) + sum(change[k] for k in springs)
    done = float(np.sum(0.5 * dt * sum(np.abs(power[k][1:]) + np.abs(power[k][:-1]) for k in WORKS)))
    total_work = sum(work.values())
    total_change = sum(change.values())
    residual = total_change - total_work
    return {"stored_change_J": {k: round(v, 3) for k, v in change.items()},
            "work_J": {k: round(v, 3) for k, v in work.items()},
            "muscle_work_J": round(work["muscle_positive"] + work["muscle_negative"], 3),
            "muscle_positive_J": round(work["muscle_positive"], 3), "muscle_negative_J": round(work["muscle_negative"], 3),
            "energy_change_J": round(total_change, 3), "work_total_J": round(total_work, 3),
            "work_done_J": round(done, 3), "residual_J": round(residual, 4),
            "error_pct": round(100.0 * abs(residual) / done, 4) if done > 0 else math.nan,
            "unsplit_W": round(unsplit, 6), "duration_s": round(float(times[-1] - times[0]), 6),
            "pedal_leg_J": round(trap(leg), 3), "pedal_leg_positive_J": round(trap(np.maximum(leg, 0.0)), 3),
            "crank_J": round(trap(crank), 3)}


def rider_spring_power(cb: rc.RiderCallback) -> float:
    """The power (W) of the pins' and the stops' springs at the callback's last evaluation (the
    rider's applied forces are these and the terms of ``rider_terms``)."""
    last = cb.last
    pins = sum(-rc.PIN_N_PER_M * (gap[0] * rel[0] + gap[2] * rel[2]) for _, rel, gap in last["pins"])
    stops = sum(last["stops"][k] * last["speed"][k]
                + rb.stop_damping(rb.stop_penetration(last["now"][k], *cb.ranges[k])) * last["speed"][k] ** 2
                for k in rc.JOINTS)
    return pins + stops


__all__ = ["balance", "rider_terms", "STORED", "WORKS"]

"""The bike's control callback in Python (``BikeCallback``): the specification of what the
compiled callback (``mtbmj.bike.callback_compiled.CompiledBikeCallback``) computes, and the fallback
where numba is missing or a law, tire or terrain has no compiled form. See ``mtbmj.bike.run`` for
what it applies and the conventions.
"""
from __future__ import annotations

import bisect
import math

import mujoco
import numpy as np

from mtbmj.bike.model import Bike
from mtbmj.bike.spec import leverage_ratio
from mtbmj.controllers.drive import LIFT_EASE_DEG, Drive, chain_pull, eased, pedal_drive, wheel_forces
from mtbmj.rolling.tire import REFRESH_DISTANCE_M, PatchSearch, RadialTire


def rot_apply(xmat, x: float, z: float) -> np.ndarray:
    """The frame-coordinate point (x, 0, z) turned into world axes by the body's ``xmat`` (9,)."""
    return np.array([xmat[0] * x + xmat[2] * z, xmat[3] * x + xmat[5] * z, xmat[6] * x + xmat[8] * z])


class BikeCallback:
    """Fork, shock (through the leverage curve), both tires and the drive, written into ``ctrl``
    (the tire and drive forces also into ``xfrc_applied``); the rider's legs and arms into
    ``qfrc_applied`` (``limb_forces``)."""

    def __init__(self, bike: Bike, fork_law, shock_law, front: RadialTire, rear: RadialTire, drive: Drive,
                 speed: float, traction: float, refresh: float):
        m = bike.model
        self._model = m
        self._address = m._address
        self.bike, self.fork, self.shock = bike, fork_law, shock_law
        self.tires = (front, rear)
        self.drive, self.speed, self.traction, self.refresh = drive, float(speed), float(traction), float(refresh)
        # pedalling: the power the stroke asks at this evaluation (the drive's; the active rider's leg
        # cuts it where its strength or power would be passed: mtbmj.bike.pedal_leg, ``set_pedal_power``)
        self.pedal_power = drive.power
        self.lev = bike.spec.leverage
        # a four-bar's rear caliper on a link that turns otherwise than the arm (spec.caliper_ratio)
        self.caliper = bike.spec.caliper_ratio
        self.arm_joint = int(m.joint("swingarm").id)
        self.fq, self.fv = bike.qpos_index("fork"), bike.dof_index("fork")
        self.sv = bike.dof_index("swingarm")
        self.xv = bike.dof_index("bike_x")
        a = lambda name: int(m.actuator(name).id)
        self.a_fork, self.a_shock = a("fork_force"), a("shock_torque")
        self.a_fs, self.a_ss = a("fork_friction_state"), a("shock_friction_state")
        self.act_f, self.act_s = int(m.actuator_actadr[self.a_fs]), int(m.actuator_actadr[self.a_ss])
        self.a_tire = ((a("front_tire_x"), a("front_tire_z")), (a("rear_tire_x"), a("rear_tire_z")))
        self.a_drive = (a("drive_x"), a("drive_z"))
        self.a_ground = (a("front_ground_x"), a("front_ground_z"), a("front_couple"), a("rear_couple"))
        self.a_probe = (a("front_deflection_probe"), a("rear_deflection_probe"))
        self.a_shock_probe = a("shock_force_probe")
        self.sites = (int(m.site("front_axle").id), int(m.site("rear_axle").id))
        self.frame = int(m.body("frame").id)
        # the drive through the chain (chainring, cog pitch radii, m), or a hub drive (None)
        self.chain = bike.spec.drive.get("chain_m")
        # pedalling (drive mode "pedal"): the crank turns with the distance rolled, through the chain
        self.xq = bike.qpos_index("bike_x")
        self.pitchq = bike.qpos_index("pitch")
        self.rider = int(m.body("rider").id)
        # the legs and arms: (frame site, rider site, k, c, rest), on the rider's two joints
        self.limbs = tuple((int(m.site(lb.frame_site).id), int(m.site(lb.rider_site).id), lb.stiffness, lb.damping,
                            lb.rest) for lb in bike.limbs)
        self.rider_joints = (int(m.joint("rider_z").id), int(m.joint("rider_pitch").id))
        self.rider_dofs = (bike.dof_index("rider_z"), bike.dof_index("rider_pitch"))
        # the tire and drive forces act at the wheels' centres (the axles): xfrc_applied on these bodies
        self.wheels = (int(m.body("front_wheel").id), int(m.body("rear_wheel").id))
        # the parts that react each tyre's ground-force couple: the front caliper's fork lower, the
        # hub drive's and the rear caliper's swingarm (controllers.drive.wheel_forces)
        self.reacting = (int(m.body("fork_lower").id), int(m.body("swingarm").id))
        # the centre of mass's horizontal speed is the X row of M qvel over the whole mass (the
        # horizontal momentum), computed at every evaluation: RK4's inner stages skip the sensors,
        # so the com_velocity sensor would hold the step's start there
        self._momentum = np.zeros(m.nv)
        self.total_mass = float(m.body_subtreemass[self.frame])
        self.pivot_x = bike.spec.pivot[0]
        self.rear_z0 = bike.spec.rear_axle[1]
        # each wheel's patches: the front end's search (kept while the axle stays over a straight stretch)
        self.search = (PatchSearch(front), PatchSearch(rear))
        self.next_refresh = [-math.inf, -math.inf]
        self.last_x = [math.inf, math.inf]
        self.calls = 0
        self.refreshes = 0
        self._vel = np.zeros(6)

    @property
    def patches(self) -> list:
        """Each wheel's (front, rear) contact patches of its last refresh."""
        return [search.patches for search in self.search]

    def set_speed(self, v: float) -> None:
        """The drive's set speed (m/s) from now on (a run on a speed profile: ``mtbmj.bike.schedule``)."""
        self.speed = float(v)

    def reset(self) -> None:
        for search in self.search:
            search.reset()
        self.next_refresh, self.last_x = [-math.inf, -math.inf], [math.inf, math.inf]

    def rear_axle(self, d):
        """The rear axle in the frame's coordinates (x, y, z; origin the bottom bracket)."""
        rot = d.xmat[self.frame].reshape(3, 3)
        return rot.T @ (d.site_xpos[self.sites[1]] - d.xpos[self.frame])

    def shock_state(self, d):
        """(w, dw/dphi) from MuJoCo's kinematics: the rear axle in the frame's coordinates."""
        local = self.rear_axle(d)
        return local[2] - self.rear_z0, -(local[0] - self.pivot_x)

    def limb_forces(self, d) -> tuple[float, float]:
        """The legs' and arms' generalized forces on rider_z and rider_pitch (N, N m): for each, the
        length L between its sites, dL/dq of the slide (the unit vector along the limb on the
        slide's axis) and of the hinge (on the axis crossed with the rider site's arm from the
        hinge), dL/dt from those and the joints' speeds, f = -k (L - rest) - c dL/dt."""
        jz, jp = self.rider_joints
        ax, az = d.xaxis[jz], d.xaxis[jp]
        anchor = d.xanchor[jp]
        vz, vp = d.qvel[self.rider_dofs[0]], d.qvel[self.rider_dofs[1]]
        qz = qp = 0.0
        for fs, rs, k, c, rest in self.limbs:
            p, q = d.site_xpos[rs], d.site_xpos[fs]
            dx, dy, dz = p[0] - q[0], p[1] - q[1], p[2] - q[2]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            ux, uy, uz = dx / length, dy / length, dz / length
            rx, ry, rz = p[0] - anchor[0], p[1] - anchor[1], p[2] - anchor[2]
            d_slide = ux * ax[0] + uy * ax[1] + uz * ax[2]
            d_hinge = (ux * (az[1] * rz - az[2] * ry) + uy * (az[2] * rx - az[0] * rz)
                       + uz * (az[0] * ry - az[1] * rx))
            f = -k * (length - rest) - c * (d_slide * vz + d_hinge * vp)
            qz += f * d_slide
            qp += f * d_hinge
        return qz, qp

    def __call__(self, m, d):
        if m is not self._model and m._address != self._address:
            return
        self.calls += 1
        qz, qp = self.limb_forces(d)
        d.qfrc_applied[self.rider_dofs[0]] = qz
        d.qfrc_applied[self.rider_dofs[1]] = qp
        qpos, qvel, act, ctrl = d.qpos, d.qvel, d.act, d.ctrl
        t = d.time
        x, v = qpos[self.fq], qvel[self.fv]
        if self.fork.has_state:
            z = act[self.act_f]
            ctrl[self.a_fork] = -self.fork.force(x, v, z)
            ctrl[self.a_fs] = self.fork.state_rate(v, z)
        else:
            ctrl[self.a_fork] = -self.fork.force(x, v)
        w, dw = self.shock_state(d)
        ds = dw / self.lev.ratio_at(w)
        s, sd = self.lev.stroke(w), ds * qvel[self.sv]
        if self.shock.has_state:
            z = act[self.act_s]
            fs = self.shock.force(s, sd, z)
            ctrl[self.a_ss] = self.shock.state_rate(sd, z)
        else:
            fs = self.shock.force(s, sd)
        ctrl[self.a_shock] = -fs * ds
        ctrl[self.a_shock_probe] = fs
        radial = [(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
        for k in (0, 1):
            tire = self.tires[k]
            site = self.sites[k]
            cx, cz = d.site_xpos[site][0], d.site_xpos[site][2]
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, site, self._vel, 0)
            vx, vz = self._vel[3], self._vel[5]
            search = self.search[k]
            if t >= self.next_refresh[k] or abs(cx - self.last_x[k]) > REFRESH_DISTANCE_M:
                if search.refresh(cx, cz, t):  # False: kept, the axle still over its straight stretch
                    self.refreshes += 1
                self.next_refresh[k] = t + self.refresh - 1e-12
                self.last_x[k] = cx
            fx, fz, deflection, _, _ = tire.force(cx, cz, vx, vz, search.patches)
            ctrl[self.a_tire[k][0]] = fx
            ctrl[self.a_tire[k][1]] = fz
            ctrl[self.a_probe[k]] = deflection
            radial[k] = (fx, fz, deflection)
        # the drive and the brakes: the ground's forces at the contact patches, each a force at its
        # axle and a couple on the part that reacts it (controllers.drive.wheel_forces)
        (fxf, fzf, df), (fxr, fzr, dr) = radial
        ground = (0.0,) * 6
        foot = (0.0, 0.0, 0.0, 0.0)
        if self.drive.mode == "pedal":  # the crank's torque makes the chain's tension (controllers.drive.pedal_drive)
            mujoco.mj_mulM(m, d, self._momentum, qvel)
            ring, cog = self.chain
            out = pedal_drive(qpos[self.xq], self._momentum[self.xv] / self.total_mass, self.pedal_power, ring, cog,
                              self.tires[1].radius, fxf, fzf, df, fxr, fzr, dr, self.traction)
            ground, foot = out[:6], out[6:]
        elif self.drive.mode != "coast" and math.hypot(fxf, fzf) + math.hypot(fxr, fzr) > 0.0:
            mujoco.mj_mulM(m, d, self._momentum, qvel)
            f = self.drive.force(self.speed, self._momentum[self.xv] / self.total_mass)
            # the rider eases off as the front lifts (controllers.drive.eased)
            f = eased(f, qpos[self.pitchq], math.hypot(fxf, fzf) > 0.0, *LIFT_EASE_DEG)
            ground = wheel_forces(f, fxf, fzf, df, fxr, fzr, dr, self.traction, self.tires[1].radius)
        ctrl[self.a_drive[0]] = ground[3]  # the rear tyre's ground force (drive or brake), at its axle
        ctrl[self.a_drive[1]] = ground[4]
        ctrl[self.a_ground[0]] = ground[0]  # the front tyre's (its brake)
        ctrl[self.a_ground[1]] = ground[1]
        ctrl[self.a_ground[2]] = ground[2]  # the couples the fork lower and the swingarm react
        ctrl[self.a_ground[3]] = ground[5]
        xfrc = d.xfrc_applied
        pull = (0.0, 0.0)
        if self.chain is not None:  # the chain makes the rear couple: its pull on the axle, its reaction on the frame
            local = self.rear_axle(d)
            cx, cz, px, pz = chain_pull(ground[5], local[0], local[2], self.chain[0], self.chain[1])
            if cx != 0.0 or cz != 0.0:
                rot = d.xmat[self.frame].reshape(3, 3)
                pull = (rot[0, 0] * cx + rot[0, 2] * cz, rot[2, 0] * cx + rot[2, 2] * cz)
                ground = ground[:5] + (0.0,)
                ctrl[self.a_ground[3]] = 0.0
            # on the frame at the chainring's tangent point: -pull, and its moment about the frame's centre of mass
            at = d.xpos[self.frame] + rot_apply(d.xmat[self.frame], px, pz) - d.xipos[self.frame]
            frame = xfrc[self.frame]
            frame[0], frame[1], frame[2] = -pull[0], 0.0, -pull[1]
            frame[3], frame[4], frame[5] = 0.0, at[2] * -pull[0] - at[0] * -pull[1], 0.0
            if self.drive.mode == "pedal":  # the foot on its pedal (the frame's, through the crank), its
                # reaction on the rider at the same point (the rider's body braced on the leg)
                rot = d.xmat[self.frame].reshape(3, 3)
                fx, fz = rot[0, 0] * foot[0] + rot[0, 2] * foot[1], rot[2, 0] * foot[0] + rot[2, 2] * foot[1]
                at = d.xpos[self.frame] + rot_apply(d.xmat[self.frame], foot[2], foot[3])
                arm = at - d.xipos[self.frame]
                frame[0] += fx
                frame[2] += fz
                frame[4] += arm[2] * fx - arm[0] * fz
                arm = at - d.xipos[self.rider]
                body = xfrc[self.rider]
                body[0], body[1], body[2] = -fx, 0.0, -fz
                body[3], body[4], body[5] = 0.0, -(arm[2] * fx - arm[0] * fz), 0.0
        for k, (fx, fz, _) in enumerate(radial):
            wheel = xfrc[self.wheels[k]]
            wheel[0], wheel[1], wheel[2] = fx + ground[3 * k], 0.0, fz + ground[3 * k + 1]
            if k == 1:
                wheel[0] += pull[0]
                wheel[2] += pull[1]
            part = xfrc[self.reacting[k]]
            part[3], part[4], part[5] = 0.0, ground[3 * k + 2], 0.0
        if self.caliper is not None:  # the brake's couple turns the caliper's link, not the arm: the
            # arm's hinge gets couple x (d link turn / d arm turn) in all, the xfrc gave it couple x 1
            tau = ground[5] if ground[5] > 0.0 else 0.0
            w_tab, _, _ = self.lev.table
            ratio = leverage_ratio(w_tab, self.caliper, bisect.bisect_right(w_tab, w) - 1, w)
            d.qfrc_applied[self.sv] = (ratio - 1.0) * tau * d.xaxis[self.arm_joint][1]


__all__ = ["BikeCallback"]

"""The planar bike's own ODE reference: the same equations as the MuJoCo model, written out in
closed form and integrated by scipy without MuJoCo (``mtbmj crosscheck --bike PRESET --roll
SCENARIO --speed V``).

Coordinates q = (X, Z, theta, qf, phi, zr, thr): the frame origin's (bottom bracket's)
horizontal and vertical displacement, the frame's pitch (nose up positive), the fork's compression
along the steering axis, the swingarm's rotation on the main pivot (rear wheel up positive), the
rider's slide along the frame's z and the rider's pitch relative to the frame. The wheels' spin
joints are free (no torque acts on them), so their spin inertia drops out of the planar motion: the
wheels are point masses at their axles here (``mass_matrix``; a test compares it with the Schur
complement of MuJoCo's full matrix over the spin joints).

Every body is a point mass at a frame-coordinate position r(q_internal) carried by the frame,
p = O + R(theta) r, plus a pitch inertia about its own centre. With J the 90-degree rotation,
dp/dt = (X', Z') + theta' R J r + R r', and the velocity-product part of its acceleration is
-theta'^2 R r + 2 theta' R J r' + R r''_q (the swingarm's points add -phi'^2 R(-phi) rho). Lagrange's
equations then read M(q) q'' = Q - sum m J^T (bias), with M = sum m J^T J + I w w^T.

Generalised forces: gravity; the fork law F on qf (-F); the shock law F_s in shock coordinates on
phi (-F_s ds/dphi, ds/dphi = (dw/dphi) / LR(w), w the rear wheel's vertical travel in the frame);
the legs' and arms' spring-dampers along their lines; each tire's radial force at its axle (the
terrain's contact patches found afresh at every evaluation from the exact closest points); the
drive's force at the rear axle along the tangent of the rear tire's contact, within its traction.
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from mtbmj.bike.model import LOWER_INERTIA, frame_body
from mtbmj.errors import RunError

NQ = 7


def _rot(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


_J = np.array([[0.0, -1.0], [1.0, 0.0]])


class PlanarBike:
    """The closed-form planar equations of a ``BikeSpec`` (geometry, masses, rider springs)."""

    def __init__(self, spec, legs_rest: float, arms_rest: float, gravity: float):
        self.spec = spec
        self.g = gravity
        a = spec.head_angle
        self.u = np.array([-math.cos(a), math.sin(a)])  # fork compression direction (frame)
        self.front0 = np.array(spec.front_axle)
        self.rear0 = np.array(spec.rear_axle)
        self.pivot = np.array(spec.pivot)
        m_f, c_f, i_f = frame_body(spec)
        self.m_frame, self.c_frame, self.i_frame = m_f, np.array(c_f), i_f
        self.m_front = spec.fork_lower_mass + spec.front_wheel_mass
        self.i_lower = LOWER_INERTIA
        self.m_arm, self.i_arm = spec.swingarm_mass, spec.swingarm_inertia
        self.arm_rho = (self.rear0 - self.pivot) / 2.0  # swingarm centre of mass from the pivot
        self.rear_rho = self.rear0 - self.pivot
        self.m_rear = spec.rear_wheel_mass
        r = spec.rider
        self.m_rider, self.i_rider = r.mass, r.pitch_inertia
        self.c_rider = np.array(r.com)
        self.legs = (np.array([r.leg_x, r.leg_z]), np.array([r.leg_x - r.com[0], r.leg_z + r.leg_length - r.com[1]]),
                     r.leg_stiffness, r.leg_damping, legs_rest)
        self.arms = (np.array([r.arm_x, r.arm_z]), np.array([r.arm_x - r.com[0], r.arm_z + r.arm_length - r.com[1]]),
                     r.arm_stiffness, r.arm_damping, arms_rest)

    # -- points: (mass, r (frame coords), dr/dq (2 x 7, internal columns only), r''_q bias) ------
    def points(self, q, qd):
        th, qf, phi, zr, thr = q[2], q[3], q[4], q[5], q[6]
        out = []
        z = np.zeros((2, NQ))
        out.append((self.m_frame, self.c_frame, z.copy(), np.zeros(2)))
        d = z.copy()
        d[:, 3] = self.u
        out.append((self.m_front, self.front0 + qf * self.u, d, np.zeros(2)))
        rp = _rot(-phi)
        for m, rho in ((self.m_arm, self.arm_rho), (self.m_rear, self.rear_rho)):
            d = z.copy()
            turned = rp @ rho
            d[:, 4] = -(_J @ turned)
            out.append((m, self.pivot + turned, d, -qd[4] ** 2 * turned))
        d = z.copy()
        d[:, 5] = (0.0, 1.0)
        out.append((self.m_rider, self.c_rider + np.array([0.0, zr]), d, np.zeros(2)))
        return out

    def jacobian(self, q, r, dr):
        """World-velocity Jacobian (2 x 7) of a frame-carried point at r with internal dr/dq."""
        R = _rot(q[2])
        jac = R @ dr
        jac[:, 0] += (1.0, 0.0)
        jac[:, 1] += (0.0, 1.0)
        jac[:, 2] += R @ (_J @ r)
        return jac

    def rotations(self):
        """(inertia, angular-velocity weights over q) of each body with pitch inertia."""
        w = lambda **k: np.array([0.0, 0.0, k.get("th", 0.0), 0.0, k.get("phi", 0.0), 0.0, k.get("thr", 0.0)])
        return [(self.i_frame, w(th=1.0)), (self.i_lower, w(th=1.0)), (self.i_arm, w(th=1.0, phi=-1.0)),
                (self.i_rider, w(th=1.0, thr=1.0))]

    def mass_matrix(self, q) -> np.ndarray:
        M = np.zeros((NQ, NQ))
        for m, r, dr, _ in self.points(q, np.zeros(NQ)):
            jac = self.jacobian(q, r, dr)
            M += m * jac.T @ jac
        for inertia, w in self.rotations():
            w = w.astype(float)
            M += inertia * np.outer(w, w)
        return M

    def front_axle(self, q, qd):
        r = self.front0 + q[3] * self.u
        dr = np.zeros((2, NQ))
        dr[:, 3] = self.u
        jac = self.jacobian(q, r, dr)
        return _rot(q[2]) @ r, jac

    def rear_axle(self, q, qd):
        turned = _rot(-q[4]) @ self.rear_rho
        r = self.pivot + turned
        dr = np.zeros((2, NQ))
        dr[:, 4] = -(_J @ turned)
        return _rot(q[2]) @ r, self.jacobian(q, r, dr)

    def wheel_travel(self, phi) -> tuple[float, float]:
        """(w m, dw/dphi m/rad): the rear axle's rise in frame coordinates and its rate."""
        turned = _rot(-phi) @ self.rear_rho
        return float(self.pivot[1] + turned[1] - self.rear0[1]), float(-(_J @ turned)[1])

    def tendon(self, q, qd, which):
        f, h, k, c, rest = which
        zr, thr = q[5], q[6]
        Rr = _rot(thr)
        v = self.c_rider + np.array([0.0, zr]) + Rr @ h - f
        length = float(np.hypot(v[0], v[1]))
        dz = v[1] / length
        dth = float(v @ (Rr @ (_J @ h))) / length
        rate = dz * qd[5] + dth * qd[6]
        force = -(k * (length - rest) + c * rate)  # along the length (positive lengthens)
        return length, rate, force, dz, dth


class Reference:
    """The ODE of a prepared bike run (``mtbmj.bike.run.prepare``), from its state at t = 0."""

    def __init__(self, prepared):
        p = prepared
        self.p = p
        b = p.bike
        self.planar = PlanarBike(b.spec, b.legs_rest, b.arms_rest, p.gravity)
        self.fork, self.shock = p.fork_law, p.shock_law
        self.front_tire, self.rear_tire = p.front_tire, p.rear_tire
        self.drive, self.speed, self.traction = p.drive, p.speed, p.traction
        self.lev = b.spec.leverage
        self.x0, self.z0 = b.x0, b.z0
        from mtbmj.bike.contact import StraightStretches

        self.straight = StraightStretches(p.terrain, self.front_tire.radius + self.front_tire.margin)
        self.nf = 1 if self.fork.has_state else 0
        self.ns = 1 if self.shock.has_state else 0

    def origin(self, q):
        return np.array([self.x0 + q[0], self.z0 + q[1]])

    def forces(self, t, y):
        """Generalised forces Q (7,) and a dict of the applied forces."""
        pl = self.planar
        q, qd = y[:NQ], y[NQ:2 * NQ]
        zf = y[2 * NQ] if self.nf else 0.0
        zs = y[2 * NQ + self.nf] if self.ns else 0.0
        Q = np.zeros(NQ)
        out = {}
        # gravity
        for m, r, dr, _ in pl.points(q, qd):
            Q += pl.jacobian(q, r, dr).T @ np.array([0.0, -m * pl.g])
        # fork
        f = self.fork.force(q[3], qd[3], zf) if self.nf else self.fork.force(q[3], qd[3])
        Q[3] -= f
        out["fork_force"] = f
        out["fork_rate"] = self.fork.state_rate(qd[3], zf) if self.nf else 0.0
        # shock through the leverage curve
        w, dw = pl.wheel_travel(q[4])
        lr = self.lev.ratio_at(w)
        ds = dw / lr
        s, sd = self.lev.stroke(w), ds * qd[4]
        fs = self.shock.force(s, sd, zs) if self.ns else self.shock.force(s, sd)
        Q[4] -= fs * ds
        out.update(shock_force=fs, shock_rate=self.shock.state_rate(sd, zs) if self.ns else 0.0, stroke=s,
                   stroke_velocity=sd, wheel_travel=w)
        # legs and arms
        for name, which in (("legs", pl.legs), ("arms", pl.arms)):
            length, rate, force, dz, dth = pl.tendon(q, qd, which)
            Q[5] += force * dz
            Q[6] += force * dth
            out[name] = (length, rate, force)
        # tires
        o = self.origin(q)
        for name, tire, axle in (("front", self.front_tire, pl.front_axle), ("rear", self.rear_tire, pl.rear_axle)):
            pos, jac = axle(q, qd)
            cx, cz = o + pos
            vx, vz = jac @ qd
            patches = self.straight.patch(cx, cz, tire.radius, tire.margin)
            if patches is None:  # not on a straight stretch: the exact closest points, searched afresh
                patches = tire.patches(cx, cz, t)
            fx, fz, deepest, _, _ = tire.force(cx, cz, vx, vz, patches)
            Q += jac.T @ np.array([fx, fz])
            out[name] = (fx, fz, deepest)
            out[name + "_jac"] = jac
        fx, fz, _ = out["rear"]
        n = math.hypot(fx, fz)
        dx = dz = 0.0
        if n > 0.0 and self.drive.mode != "coast":
            f = self.drive.force(self.speed, qd[0])
            limit = self.traction * n
            f = min(max(f, -limit), limit)
            dx, dz = f * fz / n, -f * fx / n
            Q += out["rear_jac"].T @ np.array([dx, dz])
        out["drive"] = (dx, dz)
        return Q, out

    def bias(self, q, qd):
        pl = self.planar
        b = np.zeros(NQ)
        R = _rot(q[2])
        for m, r, dr, rqq in pl.points(q, qd):
            rd = dr @ qd
            acc = -qd[2] ** 2 * (R @ r) + 2.0 * qd[2] * (R @ (_J @ rd)) + R @ rqq
            b += m * pl.jacobian(q, r, dr).T @ acc
        return b

    def accelerations(self, t, y):
        q, qd = y[:NQ], y[NQ:2 * NQ]
        Q, out = self.forces(t, y)
        qdd = np.linalg.solve(self.planar.mass_matrix(q), Q - self.bias(q, qd))
        return qdd, out

    def rhs(self, t, y):
        qdd, out = self.accelerations(t, y)
        rates = [out["fork_rate"]] * self.nf + [out["shock_rate"]] * self.ns
        return np.concatenate((y[NQ:2 * NQ], qdd, rates))

    def y0(self, qpos, qvel, act) -> np.ndarray:
        """The state vector from MuJoCo's qpos, qvel and act (the friction states)."""
        b = self.p.bike
        names = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_z", "rider_pitch")
        q = [qpos[b.qpos_index(n)] for n in names]
        v = [qvel[b.dof_index(n)] for n in names]
        states = []
        if self.nf:
            states.append(act[0])
        if self.ns:
            states.append(act[1])
        return np.array(q + v + states, float)

    def run(self, y0, times, max_step: float, rtol: float = 1e-10, atol: float = 1e-12) -> dict:
        start = time.perf_counter()
        sol = solve_ivp(self.rhs, (0.0, float(times[-1])), y0, method="DOP853", t_eval=times, rtol=rtol, atol=atol,
                        max_step=max_step)
        if not sol.success:
            raise RunError(f"bike reference: {sol.message}")
        y = sol.y
        n = times.size
        sig = {k: np.empty(n) for k in ("front_tire_N", "rear_tire_N", "front_tire_mm", "rear_tire_mm", "stroke_mm",
                                         "rear_travel_mm")}
        for i in range(n):
            _, out = self.forces(times[i], y[:, i])
            sig["front_tire_N"][i] = math.hypot(*out["front"][:2])
            sig["rear_tire_N"][i] = math.hypot(*out["rear"][:2])
            sig["front_tire_mm"][i] = out["front"][2] * 1e3
            sig["rear_tire_mm"][i] = out["rear"][2] * 1e3
            sig["stroke_mm"][i] = out["stroke"] * 1e3
            sig["rear_travel_mm"][i] = out["wheel_travel"] * 1e3
        sig.update(time_s=times, front_travel_mm=y[3] * 1e3, pitch_deg=np.degrees(y[2]), frame_z_mm=y[1] * 1e3,
                   wall_time_s=time.perf_counter() - start, nfev=int(sol.nfev))
        return sig


def static_equilibrium(reference: Reference, guess=None) -> np.ndarray:
    """q (7,) of the bike rolling steadily on the start at the set speed (the drive's force 0, the
    wheels' spin free): every generalised force but the horizontal one balanced (X = 0), solved by
    Newton's method on the closed-form forces (finite-difference Jacobian)."""
    from scipy.optimize import fsolve

    moving = np.zeros(NQ)
    moving[0] = reference.speed  # rolling at the set speed: the drive's force is 0 there

    def residual(u):
        q = np.concatenate(([0.0], u))
        y = np.concatenate((q, moving, np.zeros(reference.nf + reference.ns)))
        return reference.forces(0.0, y)[0][1:]

    u0 = np.array([-0.06, 0.0, 0.03, 0.2, -0.01, 0.0]) if guess is None else np.asarray(guess, float)
    u, info, ok, msg = fsolve(residual, u0, full_output=True, xtol=1e-13)
    if ok != 1 or np.max(np.abs(residual(u))) > 1e-6:
        raise RunError(f"bike: no static equilibrium found on the start ({msg.strip()})")
    return np.concatenate(([0.0], u))


__all__ = ["PlanarBike", "Reference", "static_equilibrium", "NQ"]

"""The planar bike's own ODE reference: the same equations as the MuJoCo model, written out in
closed form and integrated by scipy without MuJoCo (``mtbmj crosscheck PRESET --bike --roll
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
drive's and the brakes' forces at the contact patches (``controllers.drive.wheel_forces``): each a
force at its axle and its couple about the axle on the fork lower (the pitch) or the swingarm (the
pitch and phi); with a chain (``drive.chainring_teeth``, ``drive.cog_teeth``) the drive's couple is
the chain's instead: its pull on the rear axle along the upper run and its reaction on the frame at
the chainring (``controllers.drive.chain_pull``). This shares the callback's choice of where the
forces act; the moment balance of tests/test_bike_drive_moment.py and the virtual work of
tests/test_bike_chain.py check that choice against physics.
"""
from __future__ import annotations

import bisect
import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from mtbmj.bike.model import JOINTS, LOCKS, LOWER_INERTIA, frame_body
from mtbmj.bike.spec import leverage_ratio
from mtbmj.controllers.drive import LIFT_EASE_DEG, chain_pull, eased, pedal_drive, wheel_forces
from mtbmj.errors import RunError

NQ = 7
# the reference's solver is stalled when it has evaluated the equations STALL_CALLS times in a row
# within STALL_SPAN_S: a force that jumps where the state comes to rest (a sliding mode)
# holds an explicit solver there for ever (the muscles' power limit did, at 1.0402 s off the 1 m drop:
# 425 000 evaluations within 20 ns). The most a run met legitimately: 132 within 1 us, at a stop.
STALL_SPAN_S, STALL_CALLS = 1e-6, 5000


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

    def mass_matrix(self, q) -> np.ndarray:
        return self.dynamics(np.asarray(q, float), np.zeros(NQ))[0]

    def dynamics(self, q, qd):
        """(M (7 x 7), h (7,), axles): the mass matrix, the generalised gravity forces less the
        velocity-product terms, and for each axle (front, rear) its frame-coordinate point r, the
        column index k of its internal coordinate and dr/dq_k, written out per point mass
        (M gets m J^T J with J = [e_x, e_z, R J r, R dr/dq_k]; see the module doc)."""
        th, thd = q[2], qd[2]
        c, s = math.cos(th), math.sin(th)
        g = self.g
        M = np.zeros((NQ, NQ))
        h = np.zeros(NQ)
        phi = q[4]
        cp, sp = math.cos(phi), math.sin(phi)
        axles = [None, None]
        pts = [(self.m_frame, self.c_frame[0], self.c_frame[1], -1, 0.0, 0.0, 0.0, 0.0)]
        fr = self.front0 + q[3] * self.u
        pts.append((self.m_front, fr[0], fr[1], 3, self.u[0], self.u[1], 0.0, 0.0))
        axles[0] = (fr[0], fr[1], 3, self.u[0], self.u[1])
        for m, rho, which in ((self.m_arm, self.arm_rho, None), (self.m_rear, self.rear_rho, 1)):
            tx, tz = cp * rho[0] + sp * rho[1], -sp * rho[0] + cp * rho[1]  # R(-phi) rho
            dx, dz = tz, -tx  # -J R(-phi) rho
            w2 = qd[4] * qd[4]
            pts.append((m, self.pivot[0] + tx, self.pivot[1] + tz, 4, dx, dz, -w2 * tx, -w2 * tz))
            if which:
                axles[1] = (self.pivot[0] + tx, self.pivot[1] + tz, 4, dx, dz)
        pts.append((self.m_rider, self.c_rider[0], self.c_rider[1] + q[5], 5, 0.0, 1.0, 0.0, 0.0))
        gl_x, gl_z = -g * s, -g * c  # gravity per unit mass in frame coordinates: R^T (0, -g)
        for m, rx, rz, k, dx, dz, qqx, qqz in pts:
            jrx, jrz = -rz, rx  # J r
            ax, az = c * jrx - s * jrz, s * jrx + c * jrz  # R J r
            M[0, 0] += m
            M[1, 1] += m
            M[0, 2] += m * ax
            M[1, 2] += m * az
            M[2, 2] += m * (rx * rx + rz * rz)
            # velocity-product acceleration in frame coordinates: -thd^2 r + 2 thd J r' + r''_q
            vk = qd[k] if k >= 0 else 0.0
            lx = -thd * thd * rx + 2.0 * thd * (-dz * vk) + qqx
            lz = -thd * thd * rz + 2.0 * thd * (dx * vk) + qqz
            wx, wz = c * lx - s * lz, s * lx + c * lz
            h[0] -= m * wx
            h[1] -= m * (wz + g)
            h[2] += m * (jrx * (gl_x - lx) + jrz * (gl_z - lz))
            if k >= 0:
                bx, bz = c * dx - s * dz, s * dx + c * dz
                M[0, k] += m * bx
                M[1, k] += m * bz
                M[2, k] += m * (jrx * dx + jrz * dz)
                M[k, k] += m * (dx * dx + dz * dz)
                h[k] += m * (dx * (gl_x - lx) + dz * (gl_z - lz))
        M[2, 2] += self.i_frame + self.i_lower + self.i_arm + self.i_rider
        M[2, 4] -= self.i_arm
        M[4, 4] += self.i_arm
        M[2, 6] += self.i_rider
        M[6, 6] += self.i_rider
        iu = np.triu_indices(NQ, 1)
        M[(iu[1], iu[0])] = M[iu]
        return M, h, axles

    def axle_state(self, q, qd, axle):
        """World position (relative to the frame origin) and velocity of an axle from ``dynamics``."""
        rx, rz, k, dx, dz = axle
        c, s = math.cos(q[2]), math.sin(q[2])
        px, pz = c * rx - s * rz, s * rx + c * rz
        jx, jz = -pz, px  # R J r = J R r
        vk = qd[k]
        return (px, pz, qd[0] + qd[2] * jx + (c * dx - s * dz) * vk, qd[1] + qd[2] * jz + (s * dx + c * dz) * vk)

    @staticmethod
    def apply(Q, q, axle, fx, fz):
        """Add a world force (fx, fz) at an axle to the generalised forces Q."""
        rx, rz, k, dx, dz = axle
        c, s = math.cos(q[2]), math.sin(q[2])
        lx, lz = c * fx + s * fz, -s * fx + c * fz  # R^T F
        Q[0] += fx
        Q[1] += fz
        Q[2] += -rz * lx + rx * lz
        Q[k] += dx * lx + dz * lz

    def apply_rider(self, Q, q, px, pz, fx, fz):
        """Add a world force (fx, fz) on the rider's body at the frame-coordinate point (px, pz) (the
        body's point there now) to Q: the frame's three coordinates, the rider's slide and its pitch
        about its centre of mass."""
        c, s = math.cos(q[2]), math.sin(q[2])
        lx, lz = c * fx + s * fz, -s * fx + c * fz  # R^T F
        hx, hz = px - self.c_rider[0], pz - (self.c_rider[1] + q[5])  # from the rider's centre of mass
        Q[0] += fx
        Q[1] += fz
        Q[2] += -pz * lx + px * lz
        Q[5] += lz
        Q[6] += -hz * lx + hx * lz

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
    """The ODE of a prepared bike run (``mtbmj.bike.run.prepare``), from its state at t = 0. Its
    state: the ``COORDINATES`` (MuJoCo's joints of those names), their speeds, then the friction
    states of the fork and the shock where their laws have them."""

    COORDINATES = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_z", "rider_pitch")  # NQ of them

    def __init__(self, prepared):
        p = prepared
        self.p = p
        b = p.bike
        self.planar = PlanarBike(b.spec, b.legs_rest, b.arms_rest, p.gravity)
        self.fork, self.shock = p.fork_law, p.shock_law
        self.front_tire, self.rear_tire = p.front_tire, p.rear_tire
        self.drive, self.speed, self.traction = p.drive, p.speed, p.traction
        self.pedal_power = p.drive.power  # pedalling: the stroke's asked power (BikeCallback.pedal_power)
        self.lev = b.spec.leverage
        self.caliper = b.spec.caliper_ratio  # a four-bar's rear caliper: its link's turn per the arm's
        self.x0, self.z0 = b.x0, b.z0
        from mtbmj.rolling.tire import stretches_of

        self.straight = stretches_of(p.terrain, self.front_tire.radius + self.front_tire.margin)
        self.chain = b.spec.drive.get("chain_m")  # (chainring, cog) pitch radii, m; None: a hub drive
        # the held coordinates (the run's ``lock``: ``mtbmj.bike.model.LOCKS``' joints) and the free ones
        self.held = sorted({JOINTS.index(j) for key in p.lock for j in LOCKS[key]})
        self.free = [i for i in range(NQ) if i not in self.held]
        self.nf = 1 if self.fork.has_state else 0
        self.ns = 1 if self.shock.has_state else 0

    def origin(self, q):
        return np.array([self.x0 + q[0], self.z0 + q[1]])

    def com_speed(self, M, qd) -> float:
        """The centre of mass's horizontal speed: the X row of M qd (the horizontal momentum) over
        the whole mass (``mtbmj.bike.reference_rider`` counts the articulated rider's in it)."""
        return float(M[0] @ qd) / M[0, 0]

    def forces(self, t, y, dynamics=None):
        """Generalised forces Q (7,) of the suspension, the rider's springs, the tires and the drive
        (gravity and the velocity terms are in ``dynamics``' h), and a dict of the applied forces."""
        pl = self.planar
        q, qd = y[:NQ], y[NQ:2 * NQ]
        zf = y[2 * NQ] if self.nf else 0.0
        zs = y[2 * NQ + self.nf] if self.ns else 0.0
        M, h, axles = pl.dynamics(q, qd) if dynamics is None else dynamics
        Q = np.zeros(NQ)
        out = {}
        f = self.fork.force(q[3], qd[3], zf) if self.nf else self.fork.force(q[3], qd[3])
        Q[3] -= f
        out["fork_force"] = f
        out["fork_rate"] = self.fork.state_rate(qd[3], zf) if self.nf else 0.0
        # the shock through the leverage curve
        w, dw = pl.wheel_travel(q[4])
        ds = dw / self.lev.ratio_at(w)
        s, sd = self.lev.stroke(w), ds * qd[4]
        fs = self.shock.force(s, sd, zs) if self.ns else self.shock.force(s, sd)
        Q[4] -= fs * ds
        out.update(shock_force=fs, shock_rate=self.shock.state_rate(sd, zs) if self.ns else 0.0, stroke=s,
                   stroke_velocity=sd, wheel_travel=w)
        for name, which in (("legs", pl.legs), ("arms", pl.arms)):
            length, rate, force, dz, dth = pl.tendon(q, qd, which)
            Q[5] += force * dz
            Q[6] += force * dth
            out[name] = (length, rate, force)
        ox, oz = self.x0 + q[0], self.z0 + q[1]
        for name, tire, axle in (("front", self.front_tire, axles[0]), ("rear", self.rear_tire, axles[1])):
            px, pz, vx, vz = pl.axle_state(q, qd, axle)
            cx, cz = ox + px, oz + pz
            patches = self.straight.patch(cx, cz, tire.radius, tire.margin)
            if patches is None:  # not on a straight stretch: the exact closest points, searched afresh
                patches = tire.patches(cx, cz, t)
            fx, fz, deepest, _, _ = tire.force(cx, cz, vx, vz, patches)
            pl.apply(Q, q, axle, fx, fz)
            out[name] = (fx, fz, deepest)
        # the drive and the brakes: the ground's forces at the contact patches (wheel_forces), each a
        # force at its axle and a couple (world y) on the part reacting it: the fork lower turns with
        # the frame (pitch, axis -y), the swingarm with the frame and on its hinge (axis +y)
        (fxf, fzf, df), (fxr, fzr, dr) = out["front"], out["rear"]
        ground = (0.0,) * 6
        foot = None
        if self.drive.mode == "pedal":  # the crank's torque pulls the chain (controllers.drive.pedal_drive)
            out_p = pedal_drive(q[0], self.com_speed(M, qd), self.pedal_power, *self.chain,
                                self.rear_tire.radius, fxf, fzf, df, fxr, fzr, dr, self.traction)
            ground, foot = out_p[:6], out_p[6:]
        elif self.drive.mode != "coast" and math.hypot(fxf, fzf) + math.hypot(fxr, fzr) > 0.0:
            f = self.drive.force(self.speed, self.com_speed(M, qd))  # the centre of mass's speed
            f = eased(f, q[2], math.hypot(fxf, fzf) > 0.0, *LIFT_EASE_DEG)  # eased as the front lifts
            ground = wheel_forces(f, fxf, fzf, df, fxr, fzr, dr, self.traction, self.rear_tire.radius)
        if any(ground):
            pl.apply(Q, q, axles[0], ground[0], ground[1])
            pl.apply(Q, q, axles[1], ground[3], ground[4])
            couple = ground[5]
            if self.chain is not None:  # the chain makes the rear couple (controllers.drive.chain_pull)
                cx, cz, px, pz = chain_pull(couple, axles[1][0], axles[1][1], self.chain[0], self.chain[1])
                if cx != 0.0 or cz != 0.0:
                    c, sn = math.cos(q[2]), math.sin(q[2])
                    wx, wz = c * cx - sn * cz, sn * cx + c * cz
                    pl.apply(Q, q, axles[1], wx, wz)  # the pull on the rear axle
                    pl.apply(Q, q, (px, pz, 0, 0.0, 0.0), -wx, -wz)  # its reaction on the frame at the chainring
                    couple = 0.0
            Q[2] -= ground[2] + couple
            Q[4] += couple
            if self.caliper is not None and couple > 0.0:  # a brake on a four-bar link that turns otherwise
                i = bisect.bisect_right(self.lev.table[0], w) - 1
                Q[4] += couple * (leverage_ratio(self.lev.table[0], self.caliper, i, w) - 1.0)
        if foot is not None:  # the foot on its pedal (the frame's) and on the rider at the same point
            c, sn = math.cos(q[2]), math.sin(q[2])
            wx, wz = c * foot[0] - sn * foot[1], sn * foot[0] + c * foot[1]
            pl.apply(Q, q, (foot[2], foot[3], 0, 0.0, 0.0), wx, wz)
            pl.apply_rider(Q, q, foot[2], foot[3], -wx, -wz)
        out["drive"] = (ground[0] + ground[3], ground[1] + ground[4])
        out["foot"] = foot  # pedalling: the foot's force on its pedal and the pedal's place (frame), or None
        out["static"] = h  # gravity less the velocity terms
        return Q, out

    def accelerations(self, t, y):
        """q'' of the free coordinates from M q'' = Q + h over them; a held coordinate (the run's
        ``lock``, a seated rider's two) rigidly at rest (MuJoCo's run holds it by a huge armature)."""
        q, qd = y[:NQ], y[NQ:2 * NQ]
        dyn = self.planar.dynamics(q, qd)
        Q, out = self.forces(t, y, dyn)
        if not self.held:
            return np.linalg.solve(dyn[0], Q + dyn[1]), out
        free = self.free
        qdd = np.zeros(NQ)
        qdd[free] = np.linalg.solve(dyn[0][np.ix_(free, free)], (Q + dyn[1])[free])
        return qdd, out

    def rhs(self, t, y):
        n = len(self.COORDINATES)
        qdd, out = self.accelerations(t, y)
        rates = [out["fork_rate"]] * self.nf + [out["shock_rate"]] * self.ns
        return np.concatenate((y[n:2 * n], qdd, rates))

    def y0(self, qpos, qvel, act) -> np.ndarray:
        """The state vector from MuJoCo's qpos, qvel and act (the friction states)."""
        b = self.p.bike
        q = [qpos[b.qpos_index(n)] for n in self.COORDINATES]
        v = [qvel[b.dof_index(n)] for n in self.COORDINATES]
        states = ([act[0]] if self.nf else []) + ([act[1]] if self.ns else [])
        return np.array(q + v + states, float)

    def run(self, y0, times, max_step: float, rtol: float = 1e-8, atol: float = 1e-10, method: str = "RK45") -> dict:
        """The reference's signals at ``times``. RK45 at rtol 1e-8: on the 50 mm root at 5 m/s (0.5 s)
        its front travel is within 1.1e-5 mm of DOP853's at rtol 1e-9 and 1e-10, with a quarter of
        their evaluations (the profile's polygon corners cut the high-order method's steps). A
        solver that stalls is stopped (``Stall``): ``RunError`` saying where."""
        start = time.perf_counter()
        sol = solve_ivp(Stall(self.rhs, self.COORDINATES), (0.0, float(times[-1])), y0, method=method, t_eval=times,
                        rtol=rtol, atol=atol, max_step=max_step)
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


class Stall:
    """The equations' right-hand side ``rhs`` watched for a stalled solver: ``STALL_CALLS``
    evaluations in a row within ``STALL_SPAN_S`` of the first of them end the run with a ``RunError``
    naming the time and the coordinate whose acceleration jumps most between those evaluations
    (``names``: the state's coordinates, the accelerations following their speeds), instead of a
    reference that crawls on for hours. A sliding mode (a force that jumps where the state comes to
    rest) does this; a stiff stop does not (its steps are short, but they advance)."""

    def __init__(self, rhs, names):
        self.rhs, self.names = rhs, tuple(names)
        self.anchor, self.count, self.first = -math.inf, 0, math.inf
        self.low = self.high = None

    def __call__(self, t, y):
        out = self.rhs(t, y)
        if abs(t - self.anchor) > STALL_SPAN_S:  # a new stretch: the evaluations counted only while they stay near
            self.anchor, self.count, self.first = t, 0, t
            self.low, self.high = out.copy(), out.copy()
            return out
        self.count += 1
        self.first = min(self.first, t)
        np.minimum(self.low, out, out=self.low)
        np.maximum(self.high, out, out=self.high)
        if self.count >= STALL_CALLS:
            n = len(self.names)
            spread = (self.high - self.low)[n:2 * n]
            k = int(np.argmax(spread))
            raise RunError(f"bike reference: the solver stalled at t = {self.first:.6f} s ({self.count} evaluations "
                           f"within {STALL_SPAN_S * 1e6:g} us; the {self.names[k]} acceleration jumping between "
                           f"{self.low[n + k]:.4g} and {self.high[n + k]:.4g}): a force that jumps with the state")
        return out


def static_equilibrium(reference: Reference, guess=None, acceptable=None, held=()) -> np.ndarray:
    """q (7,) of the bike rolling steadily on the start at the set speed (the drive's force 0, the
    wheels' spin free): every generalised force but the horizontal one balanced (X = 0), solved by
    Newton's method on the closed-form forces (finite-difference Jacobian).

    ``acceptable(q)`` (default: any root) tells a bike's equilibrium from a spurious root (a wheel off
    the ground, the frame on end). Where Newton's method from the usual start fails or lands on a
    spurious root, the equilibrium is followed by continuation from a lighter load (gravity scaled
    from a quarter of its value up to all of it, each solution the next start), then tried from
    starts spread over the travel; only when none finds it is the bike refused, saying why.
    ``held``: coordinates (indices into q) held at 0 and left out of the balance (a seated rider's
    two, held rigid on the frame)."""
    from scipy.optimize import fsolve

    free = np.array([i for i in range(1, NQ) if i not in held])

    moving = np.zeros(NQ)
    moving[0] = reference.speed  # rolling at the set speed: the drive's force is 0 there
    planar = reference.planar
    g = planar.g
    acceptable = (lambda q: True) if acceptable is None else acceptable

    def full(v):
        u = np.zeros(NQ - 1)
        u[free - 1] = v
        return u

    def residual(v):
        q = np.concatenate(([0.0], full(v)))
        y = np.concatenate((q, moving, np.zeros(reference.nf + reference.ns)))
        Q, out = reference.forces(0.0, y)
        return (Q + out["static"])[free]

    def solve(u0):  # u0 and the answer over q[1:], the held coordinates 0
        v, _, ok, msg = fsolve(residual, np.asarray(u0, float)[free - 1], full_output=True, xtol=1e-13)
        # a root is judged by its balance: fsolve reports "not making good progress" (ok 5) at a root
        # it has reached to round-off, where xtol 1e-13 asks for more than the forces' digits give
        good = bool(np.all(np.isfinite(v))) and np.max(np.abs(residual(v))) <= 1e-6
        return (full(v) if good else None), " ".join(str(msg).split())

    u0 = np.array([-0.06, 0.0, 0.03, 0.2, -0.01, 0.0]) if guess is None else np.asarray(guess, float)
    u, why = solve(u0)
    if u is not None and acceptable(np.concatenate(([0.0], u))):
        return np.concatenate(([0.0], u))
    found = None
    try:  # continuation in the load: a light bike sits near full extension, where the usual start is
        start = np.array([-0.06, 0.0, 0.03, 0.05, -0.005, 0.0])
        for scale in np.linspace(0.25, 1.0, 16):
            planar.g = g * scale
            start, why = solve(start)
            if start is None:
                break
        else:
            found = start
    finally:
        planar.g = g
    if found is not None and acceptable(np.concatenate(([0.0], found))):
        return np.concatenate(([0.0], found))
    # starts spread over the swingarm's angle (rad) and the rider's height on the bike (m); u is q[1:]:
    # the frame's height and pitch, the fork, the swingarm, the rider's height and pitch
    for arm in np.linspace(0.0, 0.15, 7):
        for rider in (-0.005, 0.0, 0.05, 0.15):
            u, msg = solve(np.array([-0.06, 0.0, 0.03, arm, rider, 0.0]))
            if u is not None and acceptable(np.concatenate(([0.0], u))):
                return np.concatenate(([0.0], u))
            why = msg if u is None else why
    raise RunError("bike: no static equilibrium with both wheels on the ground found on the start from 31 starts "
                   f"and a continuation in the load (the springs may not carry the bike and rider: check the fork's "
                   f"and the shock's rates and preloads; last solver message: {why})")


__all__ = ["PlanarBike", "Reference", "Stall", "static_equilibrium", "NQ"]

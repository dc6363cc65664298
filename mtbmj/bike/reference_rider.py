"""The bike's ODE reference with the articulated rider (``--rider active``): the planar bike of
``mtbmj.bike.reference`` and the rider's chain, written out in closed form and integrated by scipy
without MuJoCo (``mtbmj.bike.crosscheck.crosscheck(..., rider="active")``).

Coordinates q = (X, Z, theta, qf, phi, rx, rz, rp, hip, knee, shoulder, elbow): the bike's five
(``mtbmj.bike.reference``), the hips' fore-aft and vertical place on the frame (slides along the
frame's x and z), the trunk's pitch about the hips relative to the frame, and the hip, knee,
shoulder and elbow hinges (each a turn of the distal segment relative to its parent, nose-up
positive, 0 in the stance pose ``rider_body.pose``, as ``rider_body.attach`` builds them).

Each of the rider's segments (trunk with the head, thigh, shank, upper arm, forearm with the hand;
de Leva's masses, centres and pitch inertias, ``rider_body.body``) is a point mass and a pitch
inertia; a point of the chain sits, in frame coordinates, at r = hip0 + (rx, rz) + sum_l R(a_l) d_l,
each link l a fixed offset d_l (the pose's) turned by a sum a_l of the hinges above it. So
dr/dq_j = sum_{l: j in a_l} J R(a_l) d_l, and the velocity-product part of r'' is
-sum_l a_l'^2 R(a_l) d_l. In the world p = O + R(theta) r; the Jacobian's columns are e_x, e_z,
R J r and R dr/dq_j, and the velocity-product acceleration is R(-theta'^2 r + 2 theta' J r' + r''_q).
Lagrange's equations read M q'' = Q + h with M = sum m Jv^T Jv + I w w^T (w: the segment's angle,
theta plus its hinges, as a row of ones) and h = sum m Jv^T (g - a_velocity). The bike's own parts
are ``reference.PlanarBike``'s with its rigid rider taken out and the frame carrying the feet (as
``rider_body.attach`` puts them on the frame body).

How the loops are closed: the MJCF does not close them (no equality constraint); the rider's
callback (``rider_control.RiderCallback``) pins the shank's lower end to the ankle's point on the
frame and the forearm's end to the grip by stiff spring-dampers (``PIN_N_PER_M``, ``PIN_N_S_PER_M``,
a force in the pitch plane, no moment). The reference closes them the same way: a constraint with
multipliers would be another model than the engine's, and the 0.1 mm cross-check compares models,
not closures. The pins' force acts on the chain's point and its reaction on the frame's point, each
through its Jacobian.

The muscles: the same controller object as the engine's run (``Controller.targets``, called with
the reference's front axle place, pitch and pitch rate), the same targets' inverse kinematics and
limits (``rider_control.aimed``), the same torque law, strength and power limit
(``rider_control.muscle_torques``) and end stops (``rider_body.end_stops``) and tissue damping.
What the reference computes itself: the anatomical angles and speeds from its coordinates (each a
fixed combination of the hinges, ``GRADIENTS``) and the torques' generalised forces by virtual
work (Q = tau d angle / dq). Shared with the engine, then, and not checked by the cross-check: the
controller's law, the gains, the limits, the pose's geometry and the segments' parameters.

Pedalling (``--pedal RPM``, standing): the driving leg's push on its pedal (``mtbmj.bike.pedal_leg``:
the stroke's force and its push along the crank, the same code as the engine's) has its reaction on
the trunk at the pedal's point (``ReferenceRider.pedal_leg``); the stroke is cut by the leg's strength
and power as the engine's is (``PedalLeg.limit``, with the same muscles' torques, before the drive).

Not covered: a seated rider's saddle (refused: ``RunError``).
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.bike import rider_body as rb
from mtbmj.bike import rider_control as rc
from mtbmj.bike.reference import NQ, Reference
from mtbmj.errors import RunError

NAMES = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_x", "rider_z", "rider_pitch", "hip", "knee",
         "shoulder", "elbow")
NQR = len(NAMES)
IRX, IRZ, IRP, IHIP, IKNEE, ISH, IEL = range(5, 12)
_J = np.array([[0.0, -1.0], [1.0, 0.0]])


def _gradient(**weights) -> np.ndarray:
    g = np.zeros(NQR)
    for name, w in weights.items():
        g[NAMES.index(name)] = w
    return g


# each anatomical angle as its stance value plus a fixed combination of the hinges (flexion,
# dorsiflexion positive): the hip flexes as the thigh turns nose-up on the trunk, the knee as the
# shank turns back on the thigh, the ankle dorsiflexes as the shank's turn on the frame (trunk,
# hip and knee together) tips it back, the shoulder and the elbow as their distal segments turn up
GRADIENTS = {"hip": _gradient(hip=1.0), "knee": _gradient(knee=-1.0),
             "ankle": _gradient(rider_pitch=-1.0, hip=-1.0, knee=-1.0), "shoulder": _gradient(shoulder=1.0),
             "elbow": _gradient(elbow=1.0)}


def _rot(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


class RiderChain:
    """The articulated rider's segments and points as links from the hips (module doc)."""

    def __init__(self, body: rb.Body, pose: rb.Pose):
        hip, knee, ankle = (np.array(v, float) for v in (pose.hip, pose.knee, pose.ankle))
        sh, el, grip = (np.array(v, float) for v in (pose.shoulder, pose.elbow, pose.grip))

        def com_on(a, c, seg):
            v = c - a
            return seg.com / float(np.hypot(v[0], v[1])) * v

        trunk, thigh, shank = (IRP,), (IRP, IHIP), (IRP, IHIP, IKNEE)
        upper, fore = (IRP, ISH), (IRP, ISH, IEL)
        self.hip0 = hip
        # (mass, pitch inertia about the centre, the segment's hinges, links to its centre of mass)
        self.segments = [
            (body.trunk.mass, body.trunk.inertia, trunk, [(trunk, com_on(hip, sh, body.trunk))]),
            (body.thigh.mass, body.thigh.inertia, thigh, [(thigh, com_on(hip, knee, body.thigh))]),
            (body.shank.mass, body.shank.inertia, shank, [(thigh, knee - hip), (shank, com_on(knee, ankle, body.shank))]),
            (body.upper_arm.mass, body.upper_arm.inertia, upper, [(trunk, sh - hip), (upper, com_on(sh, el, body.upper_arm))]),
            (body.forearm.mass, body.forearm.inertia, fore,
             [(trunk, sh - hip), (upper, el - sh), (fore, com_on(el, grip, body.forearm))])]
        # the pins: (the chain's end, the frame's point it is pinned to)
        self.pins = [([(thigh, knee - hip), (shank, ankle - knee)], ankle),
                     ([(trunk, sh - hip), (upper, el - sh), (fore, grip - el)], grip)]

    def point(self, q, qd, links):
        """(r (2,), dr/dq (2, NQR), velocity-product r'' (2,)) of a chain point in frame coordinates."""
        r = self.hip0 + np.array([q[IRX], q[IRZ]])
        dr = np.zeros((2, NQR))
        dr[0, IRX] = dr[1, IRZ] = 1.0
        bias = np.zeros(2)
        for hinges, d in links:
            a = sum(q[j] for j in hinges)
            ad = sum(qd[j] for j in hinges)
            c, s = math.cos(a), math.sin(a)
            v = np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
            r += v
            jv = np.array([-v[1], v[0]])
            for j in hinges:
                dr[:, j] += jv
            bias -= ad * ad * v
        return r, dr, bias


def world_jacobian(R, r, dr=None) -> np.ndarray:
    """The (2, NQR) Jacobian of the world point O + R r (r in frame coordinates, dr its derivative
    over the rider's coordinates; None: a point fixed on the frame)."""
    jv = np.zeros((2, NQR))
    jv[0, 0] = jv[1, 1] = 1.0
    jv[:, 2] = R @ (_J @ r)
    if dr is not None:
        jv[:, 5:] = R @ dr[:, 5:]
    return jv


class ReferenceRider(Reference):
    """The ODE of a prepared bike run with the active rider (``mtbmj.bike.run.prepare(rider="active")``):
    the state of :class:`Reference` over the ``NAMES`` coordinates."""

    COORDINATES = NAMES

    def __init__(self, prepared):
        p = prepared
        if p.articulated is None:
            raise RunError("bike reference: the run has no active rider (use mtbmj.bike.reference.Reference)")
        super().__init__(p)
        ctl = p.callback.controller
        if ctl.seated:
            raise RunError("bike reference: the seated active rider's saddle is not in the reference")
        body, pose = p.articulated
        self.body, self.pose0, self.controller = body, pose, ctl
        self.chain_r = RiderChain(body, pose)
        self.leg = p.callback.leg  # pedalling: the driving leg (mtbmj.bike.pedal_leg; its law the engine's)
        self.trunk0 = math.atan2(pose.shoulder[1] - pose.hip[1], pose.shoulder[0] - pose.hip[0])
        pl = self.planar
        spec = p.spec
        r = spec.rider
        # the frame carries the feet (rider_body.attach); the rigid rider is taken out
        feet = (r.leg_x + body.feet_from_pedal[0], r.leg_z + body.feet_from_pedal[1])
        parts = [(spec.frame_mass, spec.frame_com, spec.frame_inertia), (body.feet_mass, feet, 0.0)]
        m = sum(q[0] for q in parts)
        c = np.array([sum(q[0] * q[1][i] for q in parts) / m for i in (0, 1)])
        pl.m_frame, pl.c_frame = m, c
        pl.i_frame = sum(q[2] + q[0] * ((q[1][0] - c[0]) ** 2 + (q[1][1] - c[1]) ** 2) for q in parts)
        pl.m_rider = pl.i_rider = 0.0
        self.a0 = dict(pose.angles)
        self.gains, self.strength = dict(p.callback.gains), dict(p.callback.strength)
        self.ranges = {k: tuple(math.radians(v) for v in rb.RANGES_DEG[k]) for k in rc.JOINTS}
        margin = math.radians(rc.AIM_INSIDE_DEG)
        self.aim = {k: (lo + margin, hi - margin) for k, (lo, hi) in self.ranges.items()}
        self.free = list(range(NQR))
        self._vx = 0.0

    def com_speed(self, M, qd) -> float:
        return self._vx  # the whole system's, set by ``forces`` from the full mass matrix

    def dynamics(self, q, qd):
        """(M (12 x 12), h (12,), axles): the bike's parts (``PlanarBike``, its rigid rider out) and
        the rider's segments (module doc)."""
        q7 = np.concatenate((q[:5], [0.0, 0.0]))
        qd7 = np.concatenate((qd[:5], [0.0, 0.0]))
        M7, h7, axles = self.planar.dynamics(q7, qd7)
        M = np.zeros((NQR, NQR))
        h = np.zeros(NQR)
        M[:5, :5] = M7[:5, :5]
        h[:5] = h7[:5]
        R = _rot(q[2])
        thd = qd[2]
        g = np.array([0.0, -self.planar.g])
        for m, inertia, hinges, links in self.chain_r.segments:
            r, dr, bias = self.chain_r.point(q, qd, links)
            jv = world_jacobian(R, r, dr)
            a = R @ (-thd * thd * r + 2.0 * thd * (_J @ (dr @ qd)) + bias)
            M += m * (jv.T @ jv)
            h += m * (jv.T @ (g - a))
            w = np.zeros(NQR)
            w[2] = 1.0
            w[list(hinges)] = 1.0
            M += inertia * np.outer(w, w)
        return M, h, axles

    def mass_matrix(self, q) -> np.ndarray:
        return self.dynamics(np.asarray(q, float), np.zeros(NQR))[0]

    def angles(self, q, qd) -> tuple[dict, dict]:
        """The anatomical angles (rad) and their speeds (rad/s) from the coordinates."""
        return ({k: self.a0[k] + float(GRADIENTS[k] @ q) for k in rc.JOINTS},
                {k: float(GRADIENTS[k] @ qd) for k in rc.JOINTS})

    def forces(self, t, y, dynamics=None):
        """Generalised forces Q (12,) of the bike's parts (``Reference.forces``), the pins and the
        muscles, end stops and tissue; and the dict of the applied forces (``Reference.forces``'),
        with the muscles' torques (``muscles``) and the pins' forces (``pins``)."""
        q, qd = y[:NQR], y[NQR:2 * NQR]
        M, h, axles = self.dynamics(q, qd) if dynamics is None else dynamics
        self._vx = float(M[0] @ qd) / M[0, 0]
        y7 = np.concatenate((q[:5], [0.0, 0.0], qd[:5], [0.0, 0.0], y[2 * NQR:]))
        # the muscles first: pedalling, the stroke is cut with them (pedal_leg.PedalLeg.limit, as the engine's hold)
        px = self.planar.axle_state(y7[:NQ], y7[NQ:2 * NQ], axles[0])[0]
        x_front = self.x0 + q[0] + px  # the front axle's world x, where the controller reads it
        want = rc.aimed(self.controller, self.aim, x_front, q[2], qd[2])
        now, speed = self.angles(q, qd)
        taus, _, power = rc.muscle_torques(want, now, speed, rc.gains_at(self.controller, self.gains, x_front),
                                           self.strength)
        if self.leg is not None:
            g = self.leg.geometry(*self.leg_inputs(q, qd))
            cut = self.leg.limit(g, q[0], self._vx, self.drive.power, taus, self.leg.power_limit - power)
            self.pedal_power = self.drive.power * cut["share"]
        Q7, out = super().forces(t, y7, (M, h, axles))
        Q = np.zeros(NQR)
        Q[:5] = Q7[:5]
        out["static"] = h
        R = _rot(q[2])
        pins = []
        for links, anchor in self.chain_r.pins:
            r, dr, _ = self.chain_r.point(q, qd, links)
            jd = world_jacobian(R, r, dr) - world_jacobian(R, anchor)
            gap = R @ (r - anchor)
            f = -rc.PIN_N_PER_M * gap - rc.PIN_N_S_PER_M * (jd @ qd)
            Q += jd.T @ f
            pins.append(f)
        stops = rb.end_stops(now, speed, self.ranges)
        for k in rc.JOINTS:
            Q += (taus[k] + stops[k] - rc.TISSUE_DAMPING * speed[k]) * GRADIENTS[k]
        out["muscles"], out["pins"] = taus, pins
        if self.leg is not None and out["foot"] is not None:
            self.pedal_leg(Q, q, qd, R, out)
        return Q, out

    def pedal_leg(self, Q, q, qd, R, out) -> None:
        """Pedalling: the driving leg (``mtbmj.bike.pedal_leg``) pushes the pedal with the stroke's
        force and its own push along the crank, and their reaction acts on the trunk at the pedal's
        point. ``Reference.forces`` put the stroke's force on the frame there and its reaction on the
        rigid rider, whose coordinates are out: on the bike's three the pair cancels, as the push along
        the crank's on the frame and the trunk does. What is added is the reaction on the rider's
        coordinates: the trunk's point at the pedal moves with the hips' slides and the trunk's turn."""
        fx, fz, px, pz = out["foot"]
        hip = self.chain_r.hip0 + np.array([q[IRX], q[IRZ]])
        leg = self.leg.state(*self.leg_inputs(q, qd), (fx, fz))
        arm = np.array([px, pz]) - hip
        dr = np.zeros((2, NQR))
        dr[0, IRX] = dr[1, IRZ] = 1.0
        dr[:, IRP] = _J @ arm
        Q[5:] += (R @ dr[:, 5:]).T @ (R @ -leg["force"])
        # the legs' swing (PedalLeg.swing): its force at the hips and its moment on the trunk
        force, moment = self.leg.swing(q[0], qd[0], tuple(R.T @ np.array([0.0, -self.planar.g])))
        dr[:, IRP] = 0.0
        Q += world_jacobian(R, hip, dr).T @ (R @ force)
        Q[2] += moment
        Q[IRP] += moment
        out["leg"] = leg

    def leg_inputs(self, q, qd) -> tuple:
        """The driving leg's ``PedalLeg.geometry`` arguments (the engine's ``PedalLeg.inputs``): the hips
        and their speed on the frame, the trunk's angle and turn rate, the bike's x and its rate."""
        hip = self.chain_r.hip0 + np.array([q[IRX], q[IRZ]])
        return tuple(hip), (qd[IRX], qd[IRZ]), self.trunk0 + q[IRP], qd[IRP], q[0], qd[0]

    def accelerations(self, t, y):
        q, qd = y[:NQR], y[NQR:2 * NQR]
        dyn = self.dynamics(q, qd)
        Q, out = self.forces(t, y, dyn)
        return np.linalg.solve(dyn[0], Q + dyn[1]), out


__all__ = ["ReferenceRider", "RiderChain", "GRADIENTS", "NAMES", "NQR"]

"""The driving leg of a pedalling active rider (``--pedal RPM --rider active``): the joint torques
that push the pedal along the stroke, and their power.

The articulated rider's leg (``mtbmj.bike.rider_body``) is both legs lumped into one, its ankle
pinned to the mean of the two ankles: the bottom bracket's point plus the foot's offset, fixed on
the frame (the pedals half a turn apart, their mean place is the bottom bracket). That common leg
carries the body's weight and posture. What pedalling adds is the two legs' difference: one foot
goes round with its pedal, and on its downstroke pushes it. This module is that driving leg, as a
*massless* chain from the hips (the trunk's hip point, wherever the body is) to the driving pedal
(``controllers.drive.pedal_forces``' place at the crank's angle), the ankle ``rider_body``'s offset
from the pedal (the foot keeps its attitude on the frame, translating with the pedal, but tips
heel-up about the spindle where the hips are further than the leg reaches with the knee
``KNEE_LEAST_DEG`` bent: ``foot_tip``), the knee ahead of the line from the ankle to the hip
(``rider_body.pose``). Being massless it is in statics: the foot's force F on the pedal is made by
the joint torques tau_j = (P - j) x F (P the pedal's spindle, j the hip, the knee or the ankle; x
the pitch-plane cross product, nose-up positive), J^T F, and the leg passes -F to the hips along
the same line of action. F is the stroke's (along the crank circle's tangent, the wrench the bike's
callback puts on the ``rider`` body, the trunk) and a push along the crank that makes the joints'
torques least against their strength (``PedalLeg.radial``; no crank torque, no work on the crank;
``PedalLeg.apply`` puts it on the frame at the pedal and its reaction on the trunk). Its joints'
speeds follow from the pedal's and the hips' motion on the frame (``leg_rates``), and the muscles'
power is sum tau w = F . (v_P - v_trunk(P)): the crank's power F . v_P less what the reaction does
on the body. So the pedalling's work is the muscles' (``mtbmj.bike.energy``) and the body moves
with the reaction. Standing, the pedalling rider's hips are lowered so that the driving leg reaches
the stroke's bottom (``pedalling_hip``, used by ``rider_control.stance``).

The stroke cut by the leg's strength and power (``PedalLeg.limit``, set by ``hold`` before the bike's
callback as the power its stroke asks, ``pedal_power``; the ODE reference the same from its own
state): the stroke's force and the push along the crank make joint torques proportional to the
stroke's peak crank torque, so the largest peak that keeps every joint within one side's strength
(flexion, extension) with half the common leg's muscle torque added, and the leg's power within what
the rider's muscles' ``POWER_W`` leaves the common leg's (``rider_control.muscle_torques``' positive
power), has a closed form; where the asked stroke is past it, the stroke is scaled to it (the crank
gets less torque; the radial push, proportional to the stroke, with it). The summary
(``PedalLeg.report``) gives the crank work the stroke asked and the work delivered, and for each
limit the share of the stroke's time it set the cut.

The legs' swing (``PedalLeg.swung``, ``swing``; off by default, ``run_bike(..., legs_swing=True)``:
on, the standing bob twice a turn all but cancels, docs/bike.md): the lumped leg keeps both legs' mass on the mean
posture, where the two legs go round with their pedals. Their thigh and shank (half the lumped
masses each) posed on their own pedals at the stance's hips, against the lumped leg on the pedals'
mean, give the first moment S(theta) of the difference about the hips and K(theta) = sum m h x h';
at a steady cadence w the legs' d'Alembert force is -S'' w^2, its moment about the hips -K' w^2, and
their weight's moment moved from the lumped leg's place S x g. The stroke's force on the pedal is the
drive's, so what moves the legs comes through the hips: the wrench acts on the trunk there (in the
engine and the reference alike). *Assumed*: the cadence's change (theta'') and the hips' and the
frame's own motion left out of the legs' accelerations, and the swing kept at the stance's hips
(tabulated once, ``SWING_HARMONICS`` of the crank's turn); the joint torques that swing the legs
are not added to the driving leg's (nor cut). Its work is an applied wrench's (the energy balance's
``drive`` term). Not modelled: a foot that rocks on the pedal other than the tip at the bottom.
"""
from __future__ import annotations

import math

import mujoco
import numpy as np

from mtbmj.bike import rider_body as rb
from mtbmj.controllers.drive import CRANK_LENGTH_M, pedal_forces, pedal_peak

LEG_JOINTS = ("hip", "knee", "ankle")
# standing and pedalling, the hips as low as puts the driving leg's knee this far bent at the stroke's
# bottom (assumed: bike fitters set 25-35 deg there, seated; the attack position's hips, its knees 45 deg
# bent over the pedals' mean, are out of the leg's reach at the bottom with 170 mm cranks)
BOTTOM_KNEE_DEG = 25.0
# the driving leg's knee is kept this far bent at least: where the hips are further from the pedal the
# foot tips heel-up about the spindle (plantar flexion), as riders' do at the stroke's bottom (assumed)
KNEE_LEAST_DEG = 15.0
# the legs' swing (``PedalLeg.swung``): tabulated at this many crank angles over a turn, kept to this many
# harmonics of the crank's turn (the swing's own is the second: the legs half a turn apart)
SWING_SAMPLES, SWING_HARMONICS = 256, 16


def pedalling_hip(body: rb.Body, hip, pedal) -> tuple:
    """The standing pedalling rider's hips (m, frame coordinates): ``hip`` (the attack position's),
    lowered at its fore-aft place until the driving leg reaches the stroke's bottom (the pedal
    ``CRANK_LENGTH_M`` below the pedals' mean ``pedal``) with the knee ``BOTTOM_KNEE_DEG`` bent;
    ``hip`` itself where it is already that low."""
    l1, l2 = body.thigh.length, body.shank.length
    reach = math.sqrt(l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * math.cos(math.radians(BOTTOM_KNEE_DEG)))
    ankle = (pedal[0] + body.ankle_from_pedal[0], pedal[1] - CRANK_LENGTH_M + body.ankle_from_pedal[1])
    dx = hip[0] - ankle[0]
    z = ankle[1] + math.sqrt(max(reach * reach - dx * dx, 0.0))
    return (hip[0], min(hip[1], z))


def cross(r, f) -> float:
    """The pitch-plane moment (nose-up positive, x forward and z up) of force ``f`` at arm ``r``."""
    return float(r[0] * f[1] - r[1] * f[0])


def leg_torques(hip, knee, ankle, pedal, force) -> dict:
    """The anatomical torques (N m: hip and knee flexion, ankle dorsiflexion positive) with which a
    massless leg (joints at ``hip``, ``knee``, ``ankle``, the foot on ``pedal``; frame coordinates,
    m) pushes its pedal with ``force`` (N, frame coordinates): each joint's torque on its distal part
    balances the pedal's push back at the spindle, tau_j = (P - j) x F; knee flexion turns the shank
    back on the thigh (its torque the shank's nose-down), the others their distal part nose-up."""
    p = np.asarray(pedal, float)
    f = np.asarray(force, float)
    return {"hip": cross(p - np.asarray(hip, float), f), "knee": -cross(p - np.asarray(knee, float), f),
            "ankle": cross(p - np.asarray(ankle, float), f)}


def leg_rates(hip, knee, ankle, v_hip, v_ankle, w_trunk: float, w_foot: float = 0.0) -> dict:
    """The anatomical speeds (rad/s) of the leg hip-knee-ankle whose hips move at ``v_hip`` and
    ankle at ``v_ankle`` (m/s), the trunk turns at ``w_trunk`` and the foot at ``w_foot`` (rad/s,
    nose-up), all relative to the frame. The thigh's and the shank's turn rates solve
    v_ankle - v_hip = w_t J (knee - hip) + w_s J (ankle - knee), J the quarter turn nose-up."""
    h, k, a = (np.asarray(v, float) for v in (hip, knee, ankle))
    u, s = k - h, a - k
    m = np.array([[-u[1], -s[1]], [u[0], s[0]]])
    w_t, w_s = np.linalg.solve(m, np.asarray(v_ankle, float) - np.asarray(v_hip, float))
    return {"hip": float(w_t - w_trunk), "knee": float(w_t - w_s), "ankle": float(w_foot - w_s)}


def _rot(a: float, v) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def foot_tip(hip, v_hip, pedal, v_pedal, offset, longest: float) -> tuple[float, float, bool]:
    """(turn rad, its rate rad/s, reached) of the foot about the pedal's spindle (nose-up positive;
    heel up is nose-down) that keeps the ankle (``offset`` from the spindle, turned with the foot)
    within ``longest`` of the hips: 0 where it already is; else the smaller turn that puts it at
    ``longest`` (its rate from d/dt |hip - ankle|^2 = 0); where no turn does, the ankle on the line to
    the hips (reached False). Frame coordinates, speeds relative to the frame."""
    d = np.asarray(hip, float) - np.asarray(pedal, float)
    o = np.asarray(offset, float)
    if float(np.hypot(*(d - o))) <= longest:
        return 0.0, 0.0, True
    nd, no = float(np.hypot(*d)), float(np.hypot(*o))
    c = (nd * nd + no * no - longest * longest) / (2.0 * nd * no)  # cos of the angle from d to the ankle's offset
    v_d = np.asarray(v_hip, float) - np.asarray(v_pedal, float)
    base = math.atan2(d[1], d[0]) - math.atan2(o[1], o[0])
    if c >= 1.0:  # past any turn's reach: pointed at the hips
        return math.remainder(base, 2.0 * math.pi), cross(d, v_d) / (nd * nd), False
    g = math.acos(max(c, -1.0))
    phi = min((math.remainder(base + sg * g, 2.0 * math.pi) for sg in (1.0, -1.0)), key=abs)
    a = _rot(phi, o)
    r = d - a  # the ankle to the hips
    return phi, float(r @ v_d) / float(r @ np.array([-a[1], a[0]])), True


def _derivative(values: np.ndarray, order: int) -> np.ndarray:
    """The ``order``-th derivative over the turn of samples ``values`` evenly spaced over one turn
    (spectral: the Fourier series differentiated)."""
    c = np.fft.rfft(values)
    k = np.arange(c.size)
    return np.fft.irfft(c * (1j * k) ** order, n=values.size)


def _series(values: np.ndarray) -> np.ndarray:
    """The Fourier coefficients (``SWING_HARMONICS`` + 1, complex) of samples ``values`` evenly spaced
    over one turn: f(theta) = Re sum_k c_k e^(i k theta) (``_at``)."""
    c = np.fft.rfft(values)[:SWING_HARMONICS + 1] * (2.0 / values.size)
    c[0] *= 0.5
    return c


def _at(c: np.ndarray, theta: float) -> float:
    return float(np.real(np.sum(c * np.exp(1j * theta * np.arange(c.size)))))


class PedalLeg:
    """The driving leg's statics and power at each evaluation of a pedalling active rider's run
    (module doc). ``gear``: crank radians per metre of the bike's x rolled (cog / (ring radius), as
    ``controllers.drive.pedal_drive``'s)."""

    def __init__(self, body: rb.Body, grip, gear: float, strength_one_side: dict, power_limit: float = math.inf):
        self.body, self.grip, self.gear = body, tuple(grip), float(gear)
        self.strength = {k: strength_one_side[k] for k in LEG_JOINTS}  # (flexion, extension) N m
        self.power_limit = float(power_limit)  # W, all the rider's muscles' positive power together
        l1, l2 = body.thigh.length, body.shank.length  # the hips at most this far from the ankle (KNEE_LEAST_DEG)
        self.longest = math.sqrt(l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * math.cos(math.radians(KNEE_LEAST_DEG)))
        self.now = {"share": 1.0, "by": None, "asked_W": 0.0}  # the engine's cut at its last evaluation
        self.series = None  # the legs' swing (``swung``); None: no swing
        self.clear_peaks()

    def clear_peaks(self) -> None:
        self.peak = dict.fromkeys(LEG_JOINTS, 0.0)  # the largest |torque| (N m) of the driving leg alone
        self.peak_side = dict.fromkeys(LEG_JOINTS, 0.0)  # with half the common leg's: its side's, of the limit
        self.peak_power = 0.0
        self.out_of_reach_s = 0.0  # s with the driving pedal past the leg's reach from the hips
        self.asked_J = self.delivered_J = 0.0  # the stroke's crank work asked and let through by the cut
        self.pushing_s = 0.0  # s with the stroke asking work of the crank
        self.cut_s = dict.fromkeys(LEG_JOINTS + ("power",), 0.0)  # s with the cut set by each limit
        self._t_seen = -math.inf

    def bind(self, model) -> "PedalLeg":
        """Read the engine's state from ``model`` (the articulated bike's: ``rider_body.attach``)."""
        self.frame, self.rider = int(model.body("frame").id), int(model.body("rider").id)
        self.hips, self.shoulders = int(model.site("hips").id), int(model.site("shoulders").id)
        dof = lambda name: int(model.joint(name).dofadr[0])
        self.v_idx = (dof("rider_x"), dof("rider_z"), dof("rider_pitch"), dof("bike_x"))
        self.x_idx = int(model.joint("bike_x").qposadr[0])
        self._momentum = np.zeros(model.nv)
        self.gravity = np.array(model.opt.gravity, float)
        self.total_mass = float(model.body_subtreemass[self.frame])  # as the bike's callback reads the speed
        return self

    def inputs(self, d) -> tuple:
        """(hips m, their speed m/s, trunk rad, its turn rate rad/s, the bike's x m and its rate m/s),
        ``geometry``'s arguments, from the engine's data ``d``: the hips slide on the frame along its x
        and z and the trunk turns on it (``rider_body.attach``)."""
        rot = d.xmat[self.frame].reshape(3, 3)
        o = d.xpos[self.frame]
        hip = rot.T @ (d.site_xpos[self.hips] - o)
        sh = rot.T @ (d.site_xpos[self.shoulders] - o)
        vx, vz, wp, vb = (float(d.qvel[i]) for i in self.v_idx)
        return ((hip[0], hip[2]), (vx, vz), math.atan2(sh[2] - hip[2], sh[0] - hip[0]), wp,
                float(d.qpos[self.x_idx]), vb)

    def engine(self, d) -> dict:
        """``state`` from the engine's data ``d`` after the bike's callback: the foot's force is the
        reaction the callback put on the ``rider`` body (the trunk), turned into the frame's axes."""
        f = d.xmat[self.frame].reshape(3, 3).T @ -d.xfrc_applied[self.rider][:3]
        return self.state(*self.inputs(d), (f[0], f[2]))

    def hold(self, m, d, inner, common: dict, common_power: float) -> None:
        """Before the bike's callback ``inner`` (``BikeCallback`` or its compiled twin): the stroke's
        cut at this evaluation (``limit``, with the muscles' torques ``common`` and their positive
        power ``common_power``, both legs' lumped), set as the power the stroke asks of ``inner``
        (``pedal_power``: the stroke's force is proportional to it). The centre of mass's speed, the
        cadence's, is the bike's callback's: the bike's x row of M qvel over the whole mass."""
        mujoco.mj_mulM(m, d, self._momentum, d.qvel)
        inputs = self.inputs(d)
        asked = inner.drive.power
        self.now = self.limit(self.geometry(*inputs), inputs[4], self._momentum[self.v_idx[3]] / self.total_mass,
                              asked, common, self.power_limit - common_power)
        inner.pedal_power = asked * self.now["share"]

    def pedal(self, x: float, x_rate: float) -> tuple[np.ndarray, np.ndarray]:
        """(place m, speed m/s) of the driving pedal on the frame, the bike's x at ``x`` moving at ``x_rate``."""
        _, _, _, px, pz = pedal_forces(x * self.gear, 1.0, CRANK_LENGTH_M)
        w = x_rate * self.gear
        # d/dtheta of the place (crank sin, crank cos), on whichever crank drives (pedal_forces' sign)
        return np.array([px, pz]), w * np.array([pz, -px])

    def radial(self, hip, knee, ankle, pedal, force) -> np.ndarray:
        """The force (N, frame coordinates) along the crank with which the foot pushes besides the
        stroke's ``force`` (along the crank circle's tangent: ``controllers.drive.pedal_forces``): the
        one that makes the joints' torques least against their strength, sum (tau_j / S_j)^2 least
        (S_j one side's strength in the direction the stroke's force alone turns joint j). It makes no
        crank torque and does no work on the crank; the bottom bracket takes it (a common assumption
        of pedalling models: the leg pushes as its joints are strongest, *assumed*)."""
        f = np.asarray(force, float)
        if not f.any():
            return np.zeros(2)
        p = np.asarray(pedal, float)
        n = p / float(np.hypot(*p))  # along the crank, outward
        a = leg_torques(hip, knee, ankle, p, f)
        b = leg_torques(hip, knee, ankle, p, n)
        w = {k: 1.0 / self.strength[k][0 if a[k] > 0.0 else 1] ** 2 for k in LEG_JOINTS}
        lam = -sum(w[k] * a[k] * b[k] for k in LEG_JOINTS) / sum(w[k] * b[k] * b[k] for k in LEG_JOINTS)
        return lam * n

    def geometry(self, hip, v_hip, trunk: float, w_trunk: float, x: float, x_rate: float) -> dict:
        """The driving leg's places and speeds: the hips at ``hip`` moving at ``v_hip`` (m, m/s), the
        trunk at ``trunk`` rad turning at ``w_trunk``, the bike's x and its rate, all in frame
        coordinates. Returns the pedal's place and speed, the foot's turn (``foot_tip``), the pose
        (``rider_body.pose``: hip, knee, ankle) and the joints' anatomical speeds (rad/s)."""
        p, v_p = self.pedal(x, x_rate)
        b = self.body
        phi, w_foot, reached = foot_tip(hip, v_hip, p, v_p, b.ankle_from_pedal, self.longest)
        a = _rot(phi, b.ankle_from_pedal)
        v_a = v_p + w_foot * np.array([-a[1], a[0]])
        # rider_body.pose puts the ankle at the pedal plus the offset: given the spindle less it, the tipped ankle
        pose = rb.pose(b, tuple(p + a - np.asarray(b.ankle_from_pedal)), self.grip, tuple(hip), trunk)
        return {"pedal": p, "pedal_speed": v_p, "foot_turn": phi, "reached": reached, "pose": pose,
                "rates": leg_rates(pose.hip, pose.knee, pose.ankle, v_hip, v_a, w_trunk, w_foot)}

    def push(self, g: dict, force) -> tuple[np.ndarray, np.ndarray, dict]:
        """(the foot's whole force, its push along the crank ``radial``, the joints' torques) with
        which the leg at ``geometry`` ``g`` makes the stroke's ``force`` (N, frame coordinates)."""
        pose = g["pose"]
        radial = self.radial(pose.hip, pose.knee, pose.ankle, g["pedal"], force)
        whole = np.asarray(force, float) + radial
        return whole, radial, leg_torques(pose.hip, pose.knee, pose.ankle, g["pedal"], whole)

    def limit(self, g: dict, x: float, speed: float, power: float, common: dict, spare: float) -> dict:
        """The cut of the stroke by the leg's strength and power, at ``geometry`` ``g`` with the bike's
        x at ``x`` (the crank's angle through the gear) and the centre of mass at ``speed`` m/s (the
        cadence's), the stroke asking ``power`` W (``controllers.drive.pedal_forces`` with
        ``pedal_peak``'s torque). The stroke's force and its push along the crank (``radial``:
        proportional to it) make joint torques proportional to the stroke's peak torque k, tau_j =
        k a_j; with half the common leg's muscle torque ``common`` (both legs') added, each joint
        must stay within one side's strength, -ext_j <= k a_j + common_j / 2 <= flex_j, and the
        leg's power k sum a_j w_j within ``spare`` W (what the rider's ``power_limit`` leaves the
        common leg's muscles). Returns ``share`` (0-1: the largest k within all of them over the
        asked one, 1 within), ``by`` (the joint, or "power", that sets a share below 1; None) and
        ``asked_W`` (the crank's power the uncut stroke asks here, the traction's cap not counted)."""
        theta = x * self.gear
        peak = pedal_peak(power, speed * self.gear)
        _, fx, fz, _, _ = pedal_forces(theta, 1.0, CRANK_LENGTH_M)
        unit = np.array([fx, fz])  # the stroke's force per N m of its peak torque
        asked = peak * float(unit @ g["pedal_speed"])
        if peak <= 0.0 or not unit.any():
            return {"share": 1.0, "by": None, "asked_W": asked}
        _, _, a = self.push(g, unit)
        best, by = math.inf, None
        for k in LEG_JOINTS:
            flex, ext = self.strength[k]
            half = 0.5 * common[k]
            room = (flex - half) / a[k] if a[k] > 0.0 else ((ext + half) / -a[k] if a[k] < 0.0 else math.inf)
            if room < best:
                best, by = max(room, 0.0), k
        work = sum(a[k] * g["rates"][k] for k in LEG_JOINTS)
        if work > 0.0 and max(spare, 0.0) / work < best:
            best, by = max(spare, 0.0) / work, "power"
        share = min(best / peak, 1.0)
        return {"share": share, "by": by if share < 1.0 else None, "asked_W": asked}

    def state(self, hip, v_hip, trunk: float, w_trunk: float, x: float, x_rate: float, force) -> dict:
        """The driving leg at one evaluation: ``geometry``'s arguments and the foot's force on its
        pedal ``force`` (N, frame coordinates; the stroke's, as cut). Returns the joints' places, the
        pedal's, the anatomical angles, torques (N m), speeds (rad/s) and the power (W)."""
        g = self.geometry(hip, v_hip, trunk, w_trunk, x, x_rate)
        pose, p, rates = g["pose"], g["pedal"], g["rates"]
        force, radial, taus = self.push(g, force)
        power = sum(taus[k] * rates[k] for k in LEG_JOINTS)
        angles = {k: pose.angles[k] for k in LEG_JOINTS}
        angles["ankle"] += g["foot_turn"]  # the foot's own turn: dorsiflexion nose-up
        return {"pedal": p, "pedal_speed": g["pedal_speed"], "knee": pose.knee, "ankle": pose.ankle,
                "foot_turn": g["foot_turn"], "force": force, "radial": radial,
                "crank_power": float(force @ g["pedal_speed"]), "angles": angles, "taus": taus, "rates": rates,
                "power": power, "reached": g["reached"]}

    def swung(self, hip, trunk: float) -> "PedalLeg":
        """Tabulate the two legs' swing about the lumped leg at the stance (the hips at ``hip``, m, the
        trunk at ``trunk`` rad, frame coordinates): over a crank turn, each leg (half the lumped thigh's
        and shank's mass) posed on its own pedal (half a turn apart about the bottom bracket, the frame's
        origin; the foot tipped as ``geometry``'s), against the lumped leg posed on the pedals' mean.
        Kept as Fourier series (``SWING_HARMONICS``) of S, the first moment about the hips of the legs'
        mass less the lumped leg's (kg m), of S'' and of K' (K = sum m h x dh/dtheta, h a centre from
        the hips), for ``swing``."""
        b, offset = self.body, np.asarray(self.body.ankle_from_pedal, float)
        segs = ((b.thigh, lambda p: (p.hip, p.knee)), (b.shank, lambda p: (p.knee, p.ankle)))
        h0 = np.asarray(hip, float)

        def centres(pedal):  # each segment's centre less the hips (m)
            phi = foot_tip(hip, (0.0, 0.0), pedal, (0.0, 0.0), offset, self.longest)[0]
            pose = rb.pose(b, tuple(pedal + _rot(phi, offset) - offset), self.grip, tuple(hip), trunk)
            out = []
            for seg, ends in segs:
                a, e = (np.asarray(v, float) for v in ends(pose))
                out.append(a + seg.com / float(np.hypot(*(e - a))) * (e - a) - h0)
            return out

        n = SWING_SAMPLES
        th = 2.0 * math.pi * np.arange(n) / n
        first, spin = np.zeros((n, 2)), np.zeros(n)
        for sign in (1.0, -1.0):
            h = np.array([centres(sign * CRANK_LENGTH_M * np.array([math.sin(t), math.cos(t)])) for t in th])
            for j, (seg, _) in enumerate(segs):  # h[:, j]: (n, 2)
                dh = np.stack([_derivative(h[:, j, i], 1) for i in (0, 1)], axis=1)
                first += 0.5 * seg.mass * h[:, j]
                spin += 0.5 * seg.mass * (h[:, j, 0] * dh[:, 1] - h[:, j, 1] * dh[:, 0])
        for (seg, _), c in zip(segs, centres(np.zeros(2))):
            first -= seg.mass * c
        self.series = {"S": [_series(first[:, i]) for i in (0, 1)],
                       "S2": [_series(_derivative(first[:, i], 2)) for i in (0, 1)],
                       "K1": _series(_derivative(spin, 1))}
        return self

    def swing(self, x: float, x_rate: float, gravity) -> tuple[np.ndarray, float]:
        """(force N, moment N m about the hips, nose-up) on the trunk, frame coordinates, of the two
        legs' swing (``swung``) with the bike's x at ``x`` moving at ``x_rate`` (the crank's angle
        and speed through the gear) and ``gravity`` (m/s2, frame coordinates): the d'Alembert force
        of the legs' motion about the hips, -S'' w^2, and its moment, -K' w^2, with the moment of
        their weight moved from the lumped leg's place, S x g. The stroke's force on the pedal is the
        drive's, so what moves the legs' mass comes through the hips (zeros without ``swung``)."""
        if self.series is None:
            return np.zeros(2), 0.0
        theta, w2 = x * self.gear, (x_rate * self.gear) ** 2
        sr = self.series
        first = np.array([_at(c, theta) for c in sr["S"]])
        force = -w2 * np.array([_at(c, theta) for c in sr["S2"]])
        return force, cross(first, gravity) - w2 * _at(sr["K1"], theta)

    def apply(self, d, state: dict) -> None:
        """Put the foot's push along the crank (``radial``) into the engine's ``xfrc_applied``: on the
        frame at the pedal (the crank takes it to the bottom bracket) and its reaction on the trunk
        at the same point (the leg carries it to the hips), as the bike's callback puts the stroke's."""
        rot = d.xmat[self.frame].reshape(3, 3)
        g = rot.T @ self.gravity
        force, moment = self.swing(float(d.qpos[self.x_idx]), float(d.qvel[self.v_idx[3]]), (g[0], g[2]))
        if force.any() or moment:  # the legs' swing on the trunk: its force at the hips and its moment
            fw = rot @ np.array([force[0], 0.0, force[1]])
            w = d.xfrc_applied[self.rider]
            w[:3] += fw
            w[3:] += np.cross(d.site_xpos[self.hips] - d.xipos[self.rider], fw) + rot @ np.array([0.0, -moment, 0.0])
        f = state["radial"]
        if not f.any():
            return
        fw = rot @ np.array([f[0], 0.0, f[1]])
        at = d.xpos[self.frame] + rot @ np.array([state["pedal"][0], 0.0, state["pedal"][1]])
        for body, sign in ((self.frame, 1.0), (self.rider, -1.0)):
            w = d.xfrc_applied[body]
            w[:3] += sign * fw
            w[3:] += np.cross(at - d.xipos[body], sign * fw)

    def note(self, state: dict, common: dict, strength_one_side: dict, t: float) -> None:
        """Keep the peaks: the driving leg's torques alone and with half the common leg's muscle
        torque (``common``, both legs') against one side's strength (flexion, extension); and, each
        stretch of time (``t`` s) counted once, the time with the pedal out of the leg's reach, the
        stroke's crank work asked and let through by the cut (``now``, ``hold``'s) and the time the
        cut was set by each limit."""
        if t > self._t_seen:
            if self._t_seen > -math.inf:
                dt = t - self._t_seen
                if not state["reached"]:
                    self.out_of_reach_s += dt
                asked, share = max(self.now["asked_W"], 0.0), self.now["share"]
                self.asked_J += dt * asked
                self.delivered_J += dt * share * asked
                self.pushing_s += dt if asked > 0.0 else 0.0
                if self.now["by"] is not None:
                    self.cut_s[self.now["by"]] += dt
            self._t_seen = t
        for k in LEG_JOINTS:
            tau = state["taus"][k]
            self.peak[k] = max(self.peak[k], abs(tau))
            side = tau + 0.5 * common[k]
            flex, ext = strength_one_side[k]
            self.peak_side[k] = max(self.peak_side[k], side / flex if side > 0 else -side / ext)
        self.peak_power = max(self.peak_power, state["power"])

    def report(self) -> dict:
        """The driving leg's peaks (``note``) and the stroke's cut: the share of the crank work the
        stroke asked that the leg's limits let through, and of the time the stroke pushed, the share
        the cut was set by each limit (a joint's strength or the power)."""
        push = self.pushing_s
        return {"peak_N_m": {k: round(v, 2) for k, v in self.peak.items()},
                "side_peak_of_limit": {k: round(v, 4) for k, v in self.peak_side.items()},
                "within_limits": all(v <= 1.0 + 1e-9 for v in self.peak_side.values()),
                "peak_power_W": round(self.peak_power, 1), "out_of_reach_s": round(self.out_of_reach_s, 4),
                "asked_crank_J": round(self.asked_J, 3), "delivered_crank_J": round(self.delivered_J, 3),
                "delivered_of_asked": round(self.delivered_J / self.asked_J, 4) if self.asked_J > 0.0 else 1.0,
                "cut_of_stroke_time": {k: round(v / push, 4) if push > 0.0 else 0.0 for k, v in self.cut_s.items()},
                "legs_swing": self.series is not None}


__all__ = ["PedalLeg", "leg_torques", "leg_rates", "foot_tip", "cross", "pedalling_hip", "LEG_JOINTS", "BOTTOM_KNEE_DEG"]

"""The rider's body, articulated in the pitch plane: segments from de Leva's table, joint ranges,
a pose from where the hips and the trunk are, and the MJCF bodies that carry it.

The body (``Body``) is both legs lumped into one planar leg and both arms into one arm (twice a
side's mass, inertia and strength): feet on the pedals (their mass on the frame, as a platform the
sole stands on), each leg a shank from the ankle to the knee and a thigh from the knee to the hip,
the trunk (pelvis, abdomen, thorax, neck and head) hinged at the hips, each arm an upper arm from
the shoulder to the elbow and a forearm with its hand from the elbow to the grip on the bars. In
the model (``attach``) the trunk is the ``rider`` body of the bike's scene, on three joints
relative to the frame (``rider_x``, ``rider_z`` and ``rider_pitch`` at the hips: where the trunk
is, which no muscle acts on directly); the thigh and shank hang from it at the hip and the knee,
the upper arm and forearm at the shoulder and the elbow. The shank's lower end is pinned to the
ankle's point on the frame and the forearm's to the grip (``mtbmj.bike.rider_control`` closes both
loops with stiff springs), so the body keeps three degrees of freedom on the bike: the hips' fore-
aft and height and the trunk's pitch, which the joints' torques move.
Past a joint's range of motion an end stop pushes it back (``end_stops``: a spring, stiffer further
out, and a damper ramped in; ``mtbmj.bike.rider_control`` adds them to the muscles' torques).

Sources:

* Segment masses, centres of mass and radii of gyration: P. de Leva, "Adjustments to
  Zatsiorsky-Seluyanov's segment inertia parameters", J. Biomech. 29(9):1223-1230 (1996), Table 4,
  male (stature 1741 mm): mass % of the body, the centre of mass % of the segment's length from
  its proximal end, and the radius of gyration % of the length for a turn in the sagittal plane.
  The segment lengths are that table's, scaled by ``height / 1.741`` (de Leva's lengths are the
  mean of his sample: a taller rider has each segment longer in the same proportion, *assumed*).
* Joint ranges of motion: American Academy of Orthopaedic Surgeons, "Joint Motion: Method of
  Measuring and Recording" (1965), the usual reference values (hip flexion 0-120 deg, extension
  30 deg; knee flexion 0-135 deg; ankle dorsiflexion 20 deg, plantar flexion 50 deg; shoulder
  flexion 0-180 deg, extension 60 deg; elbow flexion 0-150 deg), which J. M. Soucie et al.,
  "Range of motion measurements: reference values and a database for comparison studies",
  Haemophilia 17(3):500-507 (2011), measured again within a few degrees in healthy men.
* *Assumed* (no table gives them): the shoulder joint's centre on the trunk's line 60 mm (at
  1741 mm stature) below the seventh cervical vertebra; the ankle 130 mm behind and 90 mm above the
  pedal's spindle (the ball of the foot on the spindle, sole and pedal between); the grip at the
  hand's centre of mass; the feet's mass 70 mm behind and 50 mm above the spindle.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from mtbmj.controllers.stops import DAMPING_RAMP
from mtbmj.errors import ConfigError
from mtbmj.limits import RIDER_HEIGHT_M

STATURE_M = 1.741  # de Leva's male sample: the lengths below are its
# name: (mass % of the body, length mm at 1741 mm stature, centre of mass % of length from the
# proximal end, sagittal radius of gyration % of length); de Leva 1996, Table 4, male
DE_LEVA = {
    "head": (6.94, 242.9, 59.76, 36.2),  # vertex to C7 (CERV); centre of mass from the vertex
    "trunk": (43.46, 603.3, 44.86, 37.2),  # C7 (CERV) to the hip joints' midpoint (MIDH)
    "upper_arm": (2.71, 281.7, 57.72, 28.5),  # shoulder to elbow joint centre
    "forearm": (1.62, 268.9, 45.74, 27.6),  # elbow to wrist joint centre
    "hand": (0.61, 86.2, 79.00, 62.8),  # wrist to the third metacarpale
    "thigh": (14.16, 422.2, 40.95, 32.9),  # hip to knee joint centre
    "shank": (4.33, 434.0, 44.59, 25.5),  # knee joint centre to the lateral malleolus
    "foot": (1.37, 258.1, 44.15, 25.7),  # heel to the tip of the longest toe
}
SIDES = {"upper_arm", "forearm", "hand", "thigh", "shank", "foot"}  # a pair: both sides lumped
SHOULDER_BELOW_C7_MM = 60.0  # assumed, at 1741 mm stature
ANKLE_FROM_PEDAL_MM = (-130.0, 90.0)  # assumed, at 1741 mm stature
FEET_FROM_PEDAL_MM = (-70.0, 50.0)  # assumed
# anatomical ranges (deg): (least, most) of hip flexion, knee flexion, ankle dorsiflexion,
# shoulder flexion, elbow flexion (AAOS 1965; Soucie et al. 2011); negative: extension, plantar flexion
RANGES_DEG = {"hip": (-30.0, 120.0), "knee": (0.0, 135.0), "ankle": (-50.0, 20.0), "shoulder": (-60.0, 180.0),
              "elbow": (0.0, 150.0)}
HEIGHT_RANGE_M = RIDER_HEIGHT_M  # refused outside (mtbmj.limits; the plausible range is mtbmj.bike.keys.KEYS')
# each joint's end stop past its range of motion (``end_stops``; the muscles' are ``mtbmj.bike.rider_control``'s)
STOP_N_M_PER_RAD, STOP_N_M_S_PER_RAD = 600.0, 20.0  # past the range of motion (assumed)
# and, further than STOP_HARD_FROM_DEG past it, this stiffness (assumed: a joint's passive moment rises
# steeply at the end of its range). At 600 N m/rad throughout the ankle was pushed 26 deg past its 20 deg
# of dorsiflexion on landings with the arms softened, the body folded onto the bars and stayed there
# (knee, ankle and shoulder at their limits 0.7-0.9 s to the run's end)
STOP_HARD_N_M_PER_RAD, STOP_HARD_FROM_DEG = 3000.0, 5.0
# the end stop's damping sets in over this much past the range, c tanh(DAMPING_RAMP p / p0) (the
# suspension's stops' and the rim's ramp, ``controllers.stops``): at full strength from the range's
# end it jumped by c times the joint's speed (69 N m at the elbow leaving its stop off the 1 m drop),
# which a fixed step meets inside a step (assumed: 99.5 % of c at 2 deg past the range)
STOP_RAMP_RAD = math.radians(2.0)


@dataclass(frozen=True)
class Segment:
    mass: float  # kg (both sides for a pair)
    length: float  # m, proximal joint to distal joint (or grip)
    com: float  # m from the proximal joint along the segment
    inertia: float  # kg m^2 about its centre of mass, a turn in the pitch plane


@dataclass(frozen=True)
class Body:
    """A rider of ``mass`` (kg, the whole rider) and ``height`` (m) as the model's segments."""

    mass: float
    height: float
    thigh: Segment
    shank: Segment
    upper_arm: Segment
    forearm: Segment  # forearm and hand, elbow to grip
    trunk: Segment  # trunk, neck and head, hip to shoulder (com along that line)
    feet_mass: float  # kg, on the frame at the pedals
    ankle_from_pedal: tuple[float, float]  # m, frame coordinates
    feet_from_pedal: tuple[float, float]  # m

    @property
    def segment_masses(self) -> dict:
        return {"feet": self.feet_mass, "shanks": self.shank.mass, "thighs": self.thigh.mass,
                "trunk_head": self.trunk.mass, "upper_arms": self.upper_arm.mass, "forearms_hands": self.forearm.mass}


def _row(name: str, mass: float, scale: float) -> tuple[float, float, float, float]:
    """(mass kg, length m, com m from the proximal end, inertia kg m^2) of one segment of de Leva's
    table (both sides for a pair)."""
    pct, length_mm, com_pct, r_pct = DE_LEVA[name]
    n = 2.0 if name in SIDES else 1.0
    m = n * pct / 100.0 * mass
    length = length_mm / 1000.0 * scale
    return m, length, com_pct / 100.0 * length, m * (r_pct / 100.0 * length) ** 2


def _combine(parts) -> tuple[float, float, float]:
    """(mass, com, inertia about the com) of point-line parts (mass, com along a line, own inertia)."""
    m = sum(p[0] for p in parts)
    c = sum(p[0] * p[1] for p in parts) / m
    return m, c, sum(p[2] + p[0] * (p[1] - c) ** 2 for p in parts)


def body(mass_kg: float, height_m: float) -> Body:
    """The segments of a rider of ``mass_kg`` (the whole rider) and ``height_m``: de Leva's table
    scaled (masses by the body's, lengths by the stature's ratio to his sample's)."""
    if not (isinstance(height_m, (int, float)) and HEIGHT_RANGE_M[0] <= height_m <= HEIGHT_RANGE_M[1]):
        raise ConfigError(f"rider.height_m: must be within {HEIGHT_RANGE_M[0]:g}-{HEIGHT_RANGE_M[1]:g} m, got "
                          f"{height_m!r}")
    s = height_m / STATURE_M
    seg = {name: _row(name, mass_kg, s) for name in DE_LEVA}

    def plain(name):
        m, length, c, i = seg[name]
        return Segment(m, length, c, i)

    # the forearm and the hand as one, elbow to grip (the grip at the hand's centre of mass)
    fm, fl, fc, fi = seg["forearm"]
    hm, hl, hc, hi = seg["hand"]
    grip = fl + hc
    m, c, i = _combine([(fm, fc, fi), (hm, fl + hc, hi)])
    forearm = Segment(m, grip, c, i)
    # the trunk with the head on its line above C7, hip to shoulder
    tm, tl, tc, ti = seg["trunk"]  # tc from C7 (its proximal end)
    em, el, ec, ei = seg["head"]  # ec from the vertex
    shoulder = tl - SHOULDER_BELOW_C7_MM / 1000.0 * s
    m, c, i = _combine([(tm, tl - tc, ti), (em, tl + (el - ec), ei)])  # along the line from the hips
    trunk = Segment(m, shoulder, c, i)
    return Body(float(mass_kg), float(height_m), plain("thigh"), plain("shank"), plain("upper_arm"), forearm, trunk,
                seg["foot"][0], tuple(v / 1000.0 * s for v in ANKLE_FROM_PEDAL_MM),
                tuple(v / 1000.0 * s for v in FEET_FROM_PEDAL_MM))


def _two_link(a, b, l1: float, l2: float, pick) -> tuple[float, float]:
    """The middle joint of a two-link chain from ``a`` (link ``l1``) to ``b`` (link ``l2``): of the
    two solutions the one ``pick`` prefers (a function of the point: larger is preferred). A
    distance past the chain's reach is held at 0.999 of it (the pose is then the nearest reachable)."""
    dx, dz = b[0] - a[0], b[1] - a[1]
    d = math.hypot(dx, dz)
    d_max = 0.999 * (l1 + l2)
    d_min = 1.001 * abs(l1 - l2)
    dd = min(max(d, d_min), d_max)
    cos_a = (l1 * l1 + dd * dd - l2 * l2) / (2.0 * l1 * dd)
    alpha = math.acos(max(-1.0, min(1.0, cos_a)))
    base = math.atan2(dz, dx)
    options = [(a[0] + l1 * math.cos(base + sgn * alpha), a[1] + l1 * math.sin(base + sgn * alpha)) for sgn in (1, -1)]
    return max(options, key=pick)


@dataclass(frozen=True)
class Pose:
    """Where the body's joints are (m, frame coordinates) and its anatomical angles (rad: hip,
    knee and shoulder and elbow flexion, ankle dorsiflexion)."""

    hip: tuple[float, float]
    knee: tuple[float, float]
    ankle: tuple[float, float]
    shoulder: tuple[float, float]
    elbow: tuple[float, float]
    grip: tuple[float, float]
    angles: dict


def _angle(p, q) -> float:
    return math.atan2(q[1] - p[1], q[0] - p[0])


def pose(b: Body, pedal, grip, hip, trunk_angle: float) -> Pose:
    """The pose with the hips at ``hip`` and the trunk at ``trunk_angle`` (rad from the frame's x,
    nose up positive), the feet on ``pedal`` and the hands on ``grip`` (frame coordinates, m): the
    knee ahead of the line from the ankle to the hip, the elbow below the line from the shoulder to
    the grip."""
    ankle = (pedal[0] + b.ankle_from_pedal[0], pedal[1] + b.ankle_from_pedal[1])
    knee = _two_link(ankle, hip, b.shank.length, b.thigh.length, lambda p: p[0])
    shoulder = (hip[0] + b.trunk.length * math.cos(trunk_angle), hip[1] + b.trunk.length * math.sin(trunk_angle))
    elbow = _two_link(shoulder, grip, b.upper_arm.length, b.forearm.length, lambda p: -p[1])
    t_thigh, t_shank = _angle(hip, knee), _angle(knee, ankle)
    t_ua, t_fa = _angle(shoulder, elbow), _angle(elbow, grip)
    raw = {"hip": math.pi - trunk_angle + t_thigh, "knee": t_thigh - t_shank, "ankle": math.pi / 2.0 - (t_shank + math.pi),
           "shoulder": t_ua - trunk_angle - math.pi, "elbow": t_fa - t_ua}
    return Pose(hip, knee, ankle, shoulder, elbow, tuple(grip), {k: wrap_joint(k, a) for k, a in raw.items()})


def wrap_joint(name: str, a: float) -> float:
    """Angle ``a`` (rad) of joint ``name`` as the one turn centred on the middle of its range of
    motion (``RANGES_DEG``): the cut half a turn from any angle the joint reaches. (Centred on
    0, the cut at +-180 deg fell inside the shoulder's range, whose 180 deg of flexion is the arm
    straight along the trunk's line: a target there flipped between +180 and -180 deg from one
    evaluation to the next, and the muscle's torque with it, a 100 Hz chatter.)"""
    lo, hi = RANGES_DEG[name]
    mid = math.radians(0.5 * (lo + hi))
    return mid + (a - mid + math.pi) % (2.0 * math.pi) - math.pi


def trunk_for_reach(b: Body, hip, grip, reach: float) -> float:
    """The trunk angle (rad) that puts the shoulder ``reach`` (m) from the grip, leaning forward:
    of the two, the smaller angle above the horizontal (the lower trunk); the nearest when none."""
    dx, dz = grip[0] - hip[0], grip[1] - hip[1]
    d = math.hypot(dx, dz)
    lt = b.trunk.length
    cos_a = (lt * lt + d * d - reach * reach) / (2.0 * lt * d)
    alpha = math.acos(max(-1.0, min(1.0, cos_a)))
    base = math.atan2(dz, dx)
    return base + alpha  # above the line from the hips to the grip


def centre_of_mass(b: Body, p: Pose, pedal) -> tuple[float, float]:
    """The whole rider's centre of mass (m, frame coordinates) in pose ``p``."""
    def along(a, c, seg):
        d = math.hypot(c[0] - a[0], c[1] - a[1])
        f = seg.com / d if d > 0 else 0.0
        return (a[0] + f * (c[0] - a[0]), a[1] + f * (c[1] - a[1]))

    parts = [(b.feet_mass, (pedal[0] + b.feet_from_pedal[0], pedal[1] + b.feet_from_pedal[1])),
             (b.shank.mass, along(p.knee, p.ankle, b.shank)), (b.thigh.mass, along(p.hip, p.knee, b.thigh)),
             (b.trunk.mass, along(p.hip, p.shoulder, b.trunk)), (b.upper_arm.mass, along(p.shoulder, p.elbow, b.upper_arm)),
             (b.forearm.mass, along(p.elbow, p.grip, b.forearm))]
    m = sum(q[0] for q in parts)
    return (sum(q[0] * q[1][0] for q in parts) / m, sum(q[0] * q[1][1] for q in parts) / m)


def attach(ms, spec, b: Body, p: Pose, pedal, visual: bool = True) -> None:
    """Turn the bike scene's rigid rider (``ms``, an ``mujoco.MjSpec`` of ``mjcf/bike_scene.xml``
    already set for ``spec``) into the articulated body ``b`` in pose ``p``: the frame body
    carries the frame and the feet; the ``rider`` body is the trunk at the hips on ``rider_x``,
    ``rider_z`` and ``rider_pitch``; thigh, shank, upper arm and forearm hang from it on the
    ``hip``, ``knee``, ``shoulder`` and ``elbow`` hinges (nose-up positive, as the frame's pitch).
    Every joint at 0 is the pose ``p``. Sites: ``ankle_anchor`` (frame) and ``ankle_end`` (shank),
    ``bars`` (frame) and ``grip_end`` (forearm), ``hips``, ``shoulders`` and ``rider_com`` (the
    trunk's centre of mass) on the trunk. The legs' and arms' drawn tendons are removed."""
    import mujoco

    y_axis = [0.0, -1.0, 0.0]
    frame = ms.body("frame")
    feet = (pedal[0] + b.feet_from_pedal[0], pedal[1] + b.feet_from_pedal[1])
    parts = [(spec.frame_mass, spec.frame_com, spec.frame_inertia), (b.feet_mass, feet, 0.0)]
    m = sum(q[0] for q in parts)
    cx = sum(q[0] * q[1][0] for q in parts) / m
    cz = sum(q[0] * q[1][1] for q in parts) / m
    inertia = sum(q[2] + q[0] * ((q[1][0] - cx) ** 2 + (q[1][1] - cz) ** 2) for q in parts)
    frame.mass, frame.ipos, frame.inertia = m, [cx, 0.0, cz], [inertia] * 3
    frame.add_site(name="ankle_anchor", pos=[p.ankle[0], 0.0, p.ankle[1]], size=[0.01, 0, 0])
    rider = ms.body("rider")
    for joint in list(rider.joints):
        ms.delete(joint)
    rider.add_joint(name="rider_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1.0, 0.0, 0.0])
    rider.add_joint(name="rider_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, 0.0, 1.0])
    rider.add_joint(name="rider_pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=y_axis)
    hip = p.hip
    rider.pos = [hip[0], 0.0, hip[1]]

    def rel(q, o):
        return [q[0] - o[0], 0.0, q[1] - o[1]]

    def com_on(a, c, seg):
        d = math.hypot(c[0] - a[0], c[1] - a[1])
        return [seg.com / d * (c[0] - a[0]), 0.0, seg.com / d * (c[1] - a[1])]

    rider.mass, rider.ipos, rider.inertia = b.trunk.mass, com_on(hip, p.shoulder, b.trunk), [b.trunk.inertia] * 3
    ms.site("hips").pos = [0.0, 0.0, 0.0]
    ms.site("shoulders").pos = rel(p.shoulder, hip)
    ms.site("rider_com").pos = com_on(hip, p.shoulder, b.trunk)
    ms.geom("torso").fromto = [0.0, 0.0, 0.0] + rel(p.shoulder, hip)
    chain = [("thigh", rider, hip, p.knee, b.thigh, "hip", None),
             ("shank", None, p.knee, p.ankle, b.shank, "knee", "ankle_end"),
             ("upper_arm", rider, p.shoulder, p.elbow, b.upper_arm, "shoulder", None),
             ("forearm", None, p.elbow, p.grip, b.forearm, "elbow", "grip_end")]
    parent_at = {"thigh": hip, "upper_arm": hip}
    last = None
    for name, parent, a, c, seg, joint, end in chain:
        parent = parent if parent is not None else last
        origin = parent_at.get(name, None)
        body_ = parent.add_body(name=name, pos=rel(a, origin if origin is not None else last_a))
        body_.mass, body_.ipos, body_.inertia = seg.mass, com_on(a, c, seg), [seg.inertia] * 3
        body_.add_joint(name=joint, type=mujoco.mjtJoint.mjJNT_HINGE, axis=y_axis)
        if end:
            body_.add_site(name=end, pos=rel(c, a), size=[0.01, 0, 0])
        if visual:
            body_.add_geom(name=f"{name}_drawn", type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0.0, 0.0, 0.0] + rel(c, a),
                           size=[0.045 if name in ("thigh", "shank") else 0.03, 0, 0], contype=0, conaffinity=0,
                           group=1, density=0.0, rgba=[0.8, 0.55, 0.4, 1.0])
        last, last_a = body_, a
    for tendon in list(ms.tendons):
        ms.delete(tendon)


def stop_penetration(a: float, lo: float, hi: float) -> float:
    """How far (rad) the anatomical angle ``a`` is past its range (lo, hi): positive above ``hi``,
    negative below ``lo``, 0 within."""
    return a - hi if a > hi else (a - lo if a < lo else 0.0)


def stop_damping(past: float) -> float:
    """The end stop's damping (N m s/rad) at ``past`` rad beyond the range: ``STOP_N_M_S_PER_RAD``
    ramped in over ``STOP_RAMP_RAD``, so the stop's torque is continuous where the joint enters or
    leaves it."""
    return STOP_N_M_S_PER_RAD * math.tanh(DAMPING_RAMP * abs(past) / STOP_RAMP_RAD)


def stop_spring(past: float) -> tuple[float, float]:
    """(torque N m, stored energy J) of the end stop's spring ``past`` rad beyond the range:
    ``STOP_N_M_PER_RAD`` and, past ``STOP_HARD_FROM_DEG``, ``STOP_HARD_N_M_PER_RAD`` (continuous)."""
    deep = max(abs(past) - math.radians(STOP_HARD_FROM_DEG), 0.0)
    extra = STOP_HARD_N_M_PER_RAD - STOP_N_M_PER_RAD
    torque = -STOP_N_M_PER_RAD * past - math.copysign(extra * deep, past)
    return torque, 0.5 * STOP_N_M_PER_RAD * past * past + 0.5 * extra * deep * deep


def end_stops(now: dict, speed: dict, ranges: dict) -> dict:
    """Each joint's end-stop torque (N m, anatomical): a spring-damper past its range of motion
    (``ranges``: (least, most) rad), its damping ramped in (``stop_damping``), 0 within it."""
    out = {}
    for k in RANGES_DEG:  # the joints (``rider_control.JOINTS``)
        past = stop_penetration(now[k], *ranges[k])
        out[k] = stop_spring(past)[0] - stop_damping(past) * speed[k] if past != 0.0 else 0.0
    return out


__all__ = ["Body", "Segment", "Pose", "body", "pose", "attach", "centre_of_mass", "trunk_for_reach", "DE_LEVA",
           "RANGES_DEG", "STATURE_M", "HEIGHT_RANGE_M", "wrap_joint", "end_stops", "stop_penetration",
           "stop_damping", "stop_spring"]

"""The articulated rider's muscles and its riding controller (``--rider active``).

The body is ``mtbmj.bike.rider_body``'s. ``RiderCallback`` wraps the bike's control callback (the
compiled one or its Python specification, unchanged: the rigid rider's legs and arms are given no
stiffness, so they put nothing on the trunk) and adds, every evaluation, into ``qfrc_applied``:

* the two loops closed: the shank's lower end pinned to the ankle's point on the frame and the
  forearm's end to the grip, each by a stiff spring-damper (``PIN_N_PER_M``, ``PIN_N_S_PER_M``:
  the shoe on its pedal, the hand round the grip; a pin, no moment);
* the muscles: a torque at each of hip, knee, ankle, shoulder and elbow that drives the joint's
  anatomical angle to its target (stiffness and damping ``GAINS``), limited by the joint's
  isometric strength in each direction (``STRENGTH_N_M``, both sides together) and, all joints
  together, by the power a rider's muscles give (``POWER_W``): where the joints' positive work
  would exceed it, the torques doing positive work are cut to it, each the more the more work it
  does (``power_factors``; continuous in the joints' speeds, so a joint at rest keeps its torque);
* the passive tissue: a little damping at each joint and, past the joint's range of motion
  (``mtbmj.bike.rider_body.RANGES_DEG``), a stiff end stop (not a muscle: not in the limits);
* seated: the saddle, a one-sided spring-damper under the ischial point (``SADDLE_*``);
* pedalling: the driving leg (``mtbmj.bike.pedal_leg``), whose push on the pedal the bike's
  callback puts on the trunk; its push along the crank added on the frame and the trunk; the
  stroke cut where it would pass the leg's strength or the power left (``PedalLeg.hold``).

The controller (``Controller.targets``) sets where the hips are and how the trunk leans, in the
frame's coordinates, and the joints' targets follow by the pose's inverse kinematics
(``rider_body.pose``). Standing, the default is the attack position: the hips over the pedals
where the bike file puts the rider's (``rider.pedals_mm``, ``rider.leg_length_mm``), knees and
elbows bent. Ahead of a drop or a lip, known from the terrain's profile (the ground ahead falling
by more than ``EDGE_M`` within ``EDGE_RUN_M``), the hips go back and down over ``LEAD_S`` of
riding before the edge (``HIPS_BACK_M``, ``HIPS_DOWN_M``), the arms extending with them, and the
hips' fore-aft place follows the frame's pitch (``PITCH_GAIN_M_PER_RAD``, ``RATE_GAIN_M_S``)
until the bike has landed: what riders are taught and do off a drop (weight back, arms
extending, the legs and arms taking the landing; e.g. L. Brink and B. Lopes, "Mastering Mountain
Bike Skills", 3rd ed., 2017, ch. on drops; *the gains are assumed*, tuned on the shipped bikes).
On landing the legs and arms take the energy within their torque limits. The controller reads the
state only (no memory of its own), so a stretch stepped again at the fine step (``mtbmj.runpath``)
is stepped again alike.

Strength (one side, isometric, N m; checked at the sources for issue 54 where a number was found):

* knee 250 extension / 130 flexion: within a meta-analysis's pooled 95 % intervals for adult men
  at mid-range knee angles, 2.92-3.45 N m/kg extension and 1.15-1.62 N m/kg flexion (a
  meta-analysis of isometric knee strength, 411 studies and 13 893 participants, PubMed Central
  PMC8554160; authors and journal not recorded here): 248-293 and 98-138 N m at 85 kg;
* shoulder 80 flexion: men's static flexion 89.9 N m with the arm at the side and 68.6 N m at
  45 deg of flexion (26 men and 25 women, KIN-COM; "Dynamic shoulder flexion strength for use in
  occupational risk analysis and clinical assessment", its abstract; journal not recorded here);
  95 extension: checked by ratio, extension stronger than flexion by 5:4 in 31 volunteers ("Isokinetic
  testing of shoulder strength: normal values", Arch. Phys. Med. Rehabil. 66(6):384-386 (1985),
  PubMed 4004537, its abstract; authors not recorded here): 100 N m from the 80 of flexion;
* elbow 75 flexion / 60 extension: concentric peak torques of 199 young men, 0.78 and 0.67 N m
  per kg of body mass (L. Lategan and P. E. Kruger, Afr. J. Phys. Health Educ. Recreat. Dance,
  2003 special edition:165-172): 66 and 57 N m at 85 kg concentric, the isometric a little more;
* ankle 150 plantar flexion: checked (issue 54 item 5): nine physically active young men's
  isometric plantar flexion 154.4 +- 37.8 N m with the knee extended and 93.1 +- 22.3 N m with it
  flexed (PubMed 39577118, its abstract; authors and journal not recorded here): the attack
  position's knee, 45 deg bent, lies between, so 150 is at the top of what a rider has (*kept*: the
  landings were tuned with it); 45 dorsiflexion: 47.9-49.4 N m mean peak torque of 200 adults (L. F.
  da Fonseca et al., World J. Orthop. 16(10):108858 (2025), its Table 1; the mode of contraction and
  the sexes' mix not read);
* hip 160 flexion / 250 extension: D. E. Anderson, M. L. Madigan and M. A. Nussbaum, "Maximum
  voluntary joint torque as a function of joint angle and angular velocity: model development and
  application to the lower limb", J. Biomech. 40(14):3105-3113 (2007), Table 3, as transcribed in
  RBDL's muscle addon (github.com/rbdl/rbdl, addons/muscle/Millard2016TorqueMuscle.cc, whose peak
  isometric torque is c1 x body mass x g x height): young men (18-25) c1 0.161 hip extension, 0.113
  flexion, 239 and 168 N m at 85 kg and 1.78 m (the transcription checked, not the paper's own table,
  its posture or its dynamometer); the same rows give the knee 242 / 129 and the ankle 141 / 49 N m,
  beside the 250 / 130 and 150 / 45 above. T. Harbo, J. Brincks and H. Andersen, Eur. J. Appl.
  Physiol. 112:267-275 (2012) (regressions on age, height and mass): *not read*.

The module's first version named the 2007 paper's authors wrongly (F. C. Anderson, D. C.
Madigan); it is Dennis E. Anderson, Michael L. Madigan and Maury A. Nussbaum. Power: a sprint
cyclist's peak, 1300-1700 W (J. C. Martin et al., Eur. J. Appl. Physiol. 75:283 (1997); S. Dorel
et al., Int. J. Sports Med. 26:739 (2005)): 1500 W, *assumed*.

The controller's mends (issue 54): joint angles are read on a turn centred on each range
(``rider_body.wrap_joint``: the shoulder's 180 deg target had flipped to -180 deg, a 100 Hz
chatter); the hips' target is kept within the leg's reach (``Controller.reachable``) and every
joint's target ``AIM_INSIDE_DEG`` inside its range (targets outside had every muscle at its limit
and the knee locked straight); a run started within a drop's ramp starts in its pose instead of
squeezing the ramp into the run-up (the hop that landed the rear in its bumper on the ledge); the
frame's pitch steers the hips only past the edge; the drop's pose is let go over ``RELEASE_M``
once the rear wheel has left the edge (held 1.5 m longer, the hips far back looped the bike out
after landing), and after it a nose-up pitch is still met, a nose-down one not (``Controller.targets``:
the SST bike off 0.8 m at 4 m/s looped out without). As the pose is let go the arms' gains fall to
``ARM_LANDING_SHARE`` for the landing (``Controller.arm_share``, ``gains_at``, the ODE reference's too):
stiff, the arms took the landing at their whole strength; the end stops' stiffening past
``STOP_HARD_FROM_DEG`` (``rider_body.stop_spring``) keeps a landing from folding the body onto the bars. The summary reports, per joint, the torque asked of it (``asked_peak_of_limit``,
above 1 where the limit cut it) and the time spent at the limit (``at_limit_s``).
"""
from __future__ import annotations

import dataclasses
import functools
import math

import mujoco
import numpy as np

from mtbmj.bike import rider_body as rb
from mtbmj.bike.pedal_leg import PedalLeg, pedalling_hip
from mtbmj.errors import ConfigError, RunError, diverging

JOINTS = ("hip", "knee", "ankle", "shoulder", "elbow")
# one side's isometric strength (N m): (flexion, extension); the ankle's (dorsiflexion, plantar flexion)
STRENGTH_ONE_SIDE_N_M = {"hip": (160.0, 250.0), "knee": (130.0, 250.0), "ankle": (45.0, 150.0),
                         "shoulder": (80.0, 95.0), "elbow": (75.0, 60.0)}
STRENGTH_N_M = {k: (2.0 * a, 2.0 * b) for k, (a, b) in STRENGTH_ONE_SIDE_N_M.items()}  # both sides
POWER_W = 1500.0
# the muscles' stiffness (N m/rad) and damping (N m s/rad) about the target, both sides (assumed:
# the legs' vertical stiffness about 25 N/mm at the attack position, the arms' a quarter of it)
GAINS = {"hip": (1500.0, 60.0), "knee": (1500.0, 60.0), "ankle": (800.0, 30.0), "shoulder": (400.0, 16.0),
         "elbow": (300.0, 12.0)}
TISSUE_DAMPING = 2.0  # N m s/rad at every joint (assumed)
PIN_N_PER_M, PIN_N_S_PER_M = 4e5, 1500.0  # the feet and hands pinned (assumed: shoe, pedal, grip)
SADDLE_N_PER_M, SADDLE_N_S_PER_M = 6e4, 1200.0  # assumed: the seated body's 4-6 Hz vertical resonance
ISCHIAL_BELOW_HIP_M = 0.08  # assumed: the sitting bones this far below the hip joints
SIT_DEPTH_M = 0.03  # seated: the hips aimed this far into the saddle (the body sits down on it; assumed)
SEATED_FROM_SADDLE_M = (0.0618, 0.1974)  # the SST chart's seated centre of mass from the saddle
ATTACK_ANKLE_DEG, ATTACK_KNEE_DEG = 15.0, 45.0  # the attack position's ankle dorsiflexion, knee flexion (assumed)
ARM_REACH = 0.88  # the attack position: shoulder to grip this share of the arm's length
EDGE_M, EDGE_RUN_M = 0.15, 0.3  # a drop: the ground falling this much within this run
LEAD_S = 0.8  # s of riding before the edge over which the hips go back
HIPS_BACK_M, HIPS_DOWN_M = 0.3, 0.0
PITCH_GAIN_M_PER_RAD, RATE_GAIN_M_S = -1.0, -0.2  # nose down: the hips further back
TRUNK_GAIN, TRUNK_RATE_S = 1.0, 0.2  # the trunk's lean (rad) per rad of the frame's pitch, per rad/s
KNEE_BENT_DEG = (25.0, 110.0)  # the hips' targets within the leg's reach at these knee flexions (assumed)
COM_BEHIND_PEDAL_M = 0.05  # on the ledge the body's centre of mass at most this far behind the pedals (assumed)
FOLLOW_RAMP_M = 0.2  # the pitch's following comes in over this much past the edge
HOLD_AFTER_M = 0.0  # the drop's pose is held this far past where the rear wheel leaves the edge
RELEASE_M = 1.0  # and let go over this much riding after it
BACK_RANGE_M = (-0.15, 0.6)  # the hips' place behind the attack position's, least and most
LEAN_MAX_RAD = 0.35  # the trunk's lean that follows the pitch, at most
AIM_INSIDE_DEG = 10.0  # every joint's target kept this far inside its range of motion
LOADED_N = 50.0
# once the drop's pose is let go, a nose-up pitch past WHEELIE_FROM_DEG (fully over the next
# WHEELIE_OVER_DEG) is met by the pose's own following, forward only (assumed)
WHEELIE_FROM_DEG, WHEELIE_OVER_DEG = 0.0, 10.0
WHEELIE_FORWARD_M = 0.3  # and the hips go forward of the attack position by at most this (assumed)
# the landing: as the drop's pose is let go the arms' stiffness and damping fall to this share of
# GAINS', stay there LANDING_M of riding past the release and come back over RELEASE_M (assumed): the
# legs take the landing, the arms give with the bars (``Controller.arm_share``)
ARM_LANDING_SHARE, LANDING_M = 0.25, 1.0
ARMS = ("shoulder", "elbow")


def edges(terrain, step: float = 0.01) -> list[float]:
    """Where the ground falls away (m along the terrain): each x where the height ``EDGE_RUN_M``
    ahead is more than ``EDGE_M`` below it, the first of each run of such x."""
    x = np.arange(float(terrain.x[0]), float(terrain.x[-1]) - EDGE_RUN_M, step)
    if x.size == 0:
        return []
    fall = terrain.height(x) - terrain.height(x + EDGE_RUN_M) > EDGE_M
    starts = np.flatnonzero(fall & ~np.concatenate(([False], fall[:-1])))
    # the edge itself: the last x of the run still at the upper height
    out = []
    for i in starts:
        j = i
        while j + 1 < x.size and fall[j + 1]:
            j += 1
        out.append(float(x[j]) + EDGE_RUN_M)
    return out


def _smooth(u: float) -> float:
    u = min(max(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


@dataclasses.dataclass
class Controller:
    """The targets of the hips (m, frame coordinates) and the trunk (rad) from the state."""

    body: rb.Body
    pedal: tuple
    grip: tuple
    hip: tuple  # the attack position's hips
    trunk: float
    edges: list
    speed: float
    wheelbase: float
    seated: bool = False
    saddle: tuple | None = None
    x_start: float = -math.inf  # the front axle's start (m)
    hold_x: float | None = None  # the targets as at this front axle's place, wherever it is (the settling)

    def released_at(self, edge: float) -> float:
        """Where (the front axle's x, m) the drop's pose starts to be let go off the edge at ``edge``:
        once the rear wheel has left it and ``HOLD_AFTER_M`` more (``drop_share`` and ``arm_share``)."""
        return edge + self.wheelbase + HOLD_AFTER_M

    def drop_share(self, x_front: float) -> float:
        """How far into a drop's pose (0-1) the rider is with the front axle at ``x_front``. The
        ramp is the same however far before the edge the run starts: a run started within it
        starts (settles) in the pose the ramp has there (``hold_x``), where it used to squeeze
        the whole ramp into the run-up left (1.8 m, 0.36 s at 5 m/s to the 1 m drop): the body
        thrown back that fast hopped the bike off the ledge and landed it into the rear bumper
        before the take-off."""
        if self.hold_x is not None:
            x_front = self.hold_x
        lead = max(self.speed * LEAD_S, 0.5)
        share = 0.0
        for e in self.edges:
            begin = e - lead
            up = _smooth((x_front - begin) / max(e - 0.4 * lead - begin, 0.05))
            down = 1.0 - _smooth((x_front - self.released_at(e)) / RELEASE_M)
            share = max(share, min(up, down))
        return share

    def arm_share(self, x_front: float) -> float:
        """The share (``ARM_LANDING_SHARE``-1) of the arms' gains with the front axle at ``x_front``
        (``hold_x`` as ``drop_share``'s): falling as the drop's pose is let go (the same ramp),
        held ``LANDING_M`` past it, back over ``RELEASE_M``. Stiff arms took the landing: the
        bars coming up as the rear wheel lands bent the elbows and pushed the shoulders into
        extension against the muscles' whole strength (0.34-0.44 s off 1.5 m)."""
        if self.hold_x is not None:
            x_front = self.hold_x
        soft = 0.0
        for e in self.edges:
            a = self.released_at(e)
            back = _smooth((x_front - a - RELEASE_M - LANDING_M) / RELEASE_M)
            soft = max(soft, _smooth((x_front - a) / RELEASE_M) * (1.0 - back))
        return 1.0 - (1.0 - ARM_LANDING_SHARE) * soft

    def targets(self, x_front: float, pitch: float, rate: float) -> tuple[tuple, float]:
        """(hips m, trunk rad) asked with the front axle at ``x_front`` and the frame's ``pitch``
        and pitch ``rate``: the drop's pose (``drop_share``) with the hips following the pitch
        past the edge; once the pose is let go, a nose-up pitch past ``WHEELIE_FROM_DEG`` is still
        met by the same following, forward only (the hips up to ``WHEELIE_FORWARD_M`` ahead of the
        attack position, the trunk leaning as the pose's does), a nose-down one no longer: the SST
        bike off 0.8 m at 4 m/s came down on its front wheel 43 deg nose-down, was thrown nose-up
        by the rim strike and, the pose let go in the air, landed on its rear wheel pitching up at
        190 deg/s and looped out."""
        if self.seated:
            return self.hip, self.trunk
        s = self.drop_share(x_front)
        past = self.past_edge(x_front)
        follow = PITCH_GAIN_M_PER_RAD * pitch + RATE_GAIN_M_S * rate  # nose down: the hips further back
        full = min(max(HIPS_BACK_M + follow, BACK_RANGE_M[0]), BACK_RANGE_M[1])
        ledge = min(HIPS_BACK_M, self.ledge_back)
        back = s * (ledge + past * (full - ledge))
        wheelie = (1.0 - s) * past * _smooth((math.degrees(pitch) - WHEELIE_FROM_DEG) / WHEELIE_OVER_DEG)
        back += wheelie * max(min(follow, 0.0), -WHEELIE_FORWARD_M)  # let go: a nose-up pitch only
        hip = self.reachable((self.hip[0] - back, self.hip[1] - s * HIPS_DOWN_M))
        reach = ARM_REACH * (self.body.upper_arm.length + self.body.forearm.length)
        lean = min(max(TRUNK_GAIN * pitch + TRUNK_RATE_S * rate, -LEAN_MAX_RAD), LEAN_MAX_RAD)
        lean = s * past * lean + wheelie * max(lean, 0.0)
        return hip, rb.trunk_for_reach(self.body, hip, self.grip, reach) + lean

    @functools.cached_property
    def _leg_reach(self) -> tuple:
        """(the ankle's point, the hips' farthest and nearest distance from it) for ``reachable``."""
        b = self.body
        ankle = (self.pedal[0] + b.ankle_from_pedal[0], self.pedal[1] + b.ankle_from_pedal[1])
        l1, l2 = b.thigh.length, b.shank.length
        far, near = (math.sqrt(l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * math.cos(math.radians(k))) for k in KNEE_BENT_DEG)
        return ankle, far, near

    @functools.cached_property
    def ledge_back(self) -> float:
        """How far back (m) the hips go on the ledge: at most as far as keeps the body's centre of
        mass ``COM_BEHIND_PEDAL_M`` behind the pedals (bisection on the static pose). Further back
        the body hangs on the bars, which its muscles did not hold: settled in a pose 0.3 m back
        the body sagged backwards and pulled the front wheel up 12 deg before the run began."""
        reach = ARM_REACH * (self.body.upper_arm.length + self.body.forearm.length)

        def com_x(back):
            hip = self.reachable((self.hip[0] - back, self.hip[1] - HIPS_DOWN_M))
            trunk = rb.trunk_for_reach(self.body, hip, self.grip, reach)
            return rb.centre_of_mass(self.body, rb.pose(self.body, self.pedal, self.grip, hip, trunk), self.pedal)[0]

        want = self.pedal[0] - COM_BEHIND_PEDAL_M
        lo, hi = 0.0, max(HIPS_BACK_M, 0.0)
        if com_x(hi) >= want:
            return hi
        if com_x(lo) < want:
            return lo
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if com_x(mid) >= want else (lo, mid)
        return lo

    def past_edge(self, x_front: float) -> float:
        """0 on the ledge, rising to 1 over ``FOLLOW_RAMP_M`` once the front axle is past an edge
        (``hold_x`` as ``drop_share``'s). On the ledge the pose is held, not steered by the frame's
        pitch: the body's own motion pitches the frame, and a pitch fed back on the ground is a
        loop that threw the settling body about (both wheels off the flat before the edge)."""
        if self.hold_x is not None:
            x_front = self.hold_x
        return max((_smooth((x_front - e) / FOLLOW_RAMP_M) for e in self.edges), default=0.0)

    def reachable(self, hip) -> tuple:
        """``hip`` (m, frame coordinates) held where the leg reaches it with the knee bent between
        ``KNEE_BENT_DEG``: past the far bound the hips go down (at the same fore-aft place) onto
        it, short of the near bound up. A target out of the leg's reach asked the knee to lock
        straight and every muscle for its whole strength (module doc)."""
        ankle, far, near = self._leg_reach
        dx, dz = hip[0] - ankle[0], hip[1] - ankle[1]
        d = math.hypot(dx, dz)
        if near <= d <= far:
            return tuple(hip)
        r = far if d > far else near
        if abs(dx) < r:
            return (hip[0], ankle[1] + math.sqrt(r * r - dx * dx))
        return (ankle[0] + r * dx / d, ankle[1] + r * dz / d)


def aimed(ctl: Controller, aim: dict, x_front: float, pitch: float, rate: float) -> dict:
    """Each joint's target angle (rad, anatomical) from the controller's targets for the hips and the
    trunk (``Controller.targets`` with the front axle at ``x_front`` m, the frame's pitch and pitch
    rate), by the pose's inverse kinematics, held within ``aim`` (name: (least, most) rad)."""
    hip, trunk = ctl.targets(x_front, pitch, rate)
    return {k: min(max(a, aim[k][0]), aim[k][1])  # a target the joint reaches
            for k, a in rb.pose(ctl.body, ctl.pedal, ctl.grip, hip, trunk).angles.items()}


def gains_at(ctl: Controller, gains: dict, x_front: float) -> dict:
    """The muscles' gains with the front axle at ``x_front``: ``gains`` with the arms' scaled by
    ``Controller.arm_share`` (the engine's callback and the ODE reference alike)."""
    share = ctl.arm_share(x_front)
    return {k: ((kp * share, kd * share) if k in ARMS else (kp, kd)) for k, (kp, kd) in gains.items()}


def power_factors(powers: dict, limit: float) -> dict:
    """Each joint's factor (0-1] on its torque that keeps the joints' positive power together within
    ``limit`` W, from each joint's power ``powers`` (W, torque times speed, before the limit): 1 where
    the sum of the positive ones is within it; past it, a joint's positive power p is cut to
    p / (1 + c p), c > 0 the root of sum p / (1 + c p) = limit (Newton's method from c = 0, which
    this sum, convex and falling in c, approaches from below). The joint doing the most work gives up
    the most, and one doing none (at rest, or absorbing) keeps its whole torque: each factor is
    continuous in every joint's speed. One shared scale on every torque doing positive work jumped
    where a joint's speed changed sign: the shoulder's torque between -140 and -93 N m at rest, a
    sliding mode that the ODE reference's RK45 could not step past (at 1.0402 s off the 1 m drop,
    425 000 evaluations within 20 ns) and that the engine's fixed step chattered through."""
    out = dict.fromkeys(powers, 1.0)
    pos = [p for p in powers.values() if p > 0.0]
    if sum(pos) <= limit:
        return out
    c = 0.0
    for _ in range(100):
        f = sum(p / (1.0 + c * p) for p in pos) - limit
        slope = sum((p / (1.0 + c * p)) ** 2 for p in pos)
        step = f / slope
        c += step
        if step <= 4.0 * math.ulp(c):  # converged to the last bit (from below: step >= 0 but for rounding)
            break
    for k, p in powers.items():
        if p > 0.0:
            out[k] = 1.0 / (1.0 + c * p)
    return out


def muscle_torques(want: dict, now: dict, speed: dict, gains: dict, strength: dict) -> tuple[dict, dict, float]:
    """(torques N m, demands, positive power W) of the muscles: each joint's torque toward its target
    (``gains``' stiffness and damping on the anatomical angle ``now`` and speed ``speed``) limited by
    its strength in each direction (``strength``: (flexion, extension)), then the torques doing
    positive work cut to ``POWER_W`` together where they would exceed it (``power_factors``: each
    the more the more work it does, continuous in the joints' speeds). A demand is the torque asked
    over the limit in its direction (1 and above: held at the limit)."""
    taus, demands = {}, {}
    for k in JOINTS:
        kp, kd = gains[k]
        flex, ext = strength[k]
        ask = kp * (want[k] - now[k]) - kd * speed[k]
        taus[k] = min(max(ask, -ext), flex)
        demands[k] = ask / flex if ask > 0 else -ask / ext
    factors = power_factors({k: taus[k] * speed[k] for k in JOINTS}, POWER_W)
    for k in JOINTS:
        taus[k] *= factors[k]
    power = sum(max(taus[k] * speed[k], 0.0) for k in JOINTS)
    return taus, demands, power


class RiderCallback:
    """The bike's callback (``inner``) and the articulated rider's forces (module doc)."""

    def __init__(self, model, inner, body: rb.Body, pose0: rb.Pose, controller: Controller):
        self.inner, self.body, self.pose0, self.controller = inner, body, pose0, controller
        self._model = model
        j = lambda name: int(model.joint(name).dofadr[0])
        qa = lambda name: int(model.joint(name).qposadr[0])
        self.dof = {k: j(k) for k in ("hip", "knee", "shoulder", "elbow", "rider_pitch", "pitch")}
        self.qadr = {k: qa(k) for k in ("hip", "knee", "shoulder", "elbow", "rider_pitch", "pitch")}
        self.a0 = dict(pose0.angles)
        self.b_shank, self.b_forearm = int(model.body("shank").id), int(model.body("forearm").id)
        self.b_frame, self.b_rider = int(model.body("frame").id), int(model.body("rider").id)
        self.s_pins = ((int(model.site("ankle_end").id), int(model.site("ankle_anchor").id), self.b_shank),
                       (int(model.site("grip_end").id), int(model.site("bars").id), self.b_forearm))
        self.s_front = int(model.site("front_axle").id)
        self.s_hips = int(model.site("hips").id)
        self.a_tz = (int(model.actuator("front_tire_z").id), int(model.actuator("rear_tire_z").id))
        nv = model.nv
        self._j1, self._j2 = np.zeros((3, nv)), np.zeros((3, nv))
        self._q = np.zeros(nv)
        self.ranges = {k: tuple(math.radians(v) for v in rb.RANGES_DEG[k]) for k in JOINTS}
        margin = math.radians(AIM_INSIDE_DEG)
        self.aim = {k: (lo + margin, hi - margin) for k, (lo, hi) in self.ranges.items()}
        self.saddle_peak = 0.0
        self.last = {}
        self.leg = None  # pedalling: the driving leg (mtbmj.bike.pedal_leg.PedalLeg, set by ``activate``)
        self.gains = dict(GAINS)
        self.strength = dict(STRENGTH_N_M)
        self.clear_peaks()

    def clear_peaks(self) -> None:
        """Forget the peaks and the time at the limits (the run starts: the settling is not counted)."""
        self.peak_torque = dict.fromkeys(JOINTS, 0.0)
        self.peak_ratio = dict.fromkeys(JOINTS, 0.0)
        self.peak_demand = dict.fromkeys(JOINTS, 0.0)  # the unlimited torque asked, of the limit
        self.at_limit_s = dict.fromkeys(JOINTS, 0.0)  # s with the torque held at the limit
        self.peak_power = self.saddle_peak = 0.0
        self._t_seen = -math.inf
        if getattr(self, "leg", None) is not None:
            self.leg.clear_peaks()

    # the bike callback's face (mtbmj.bike.run reads these)
    @property
    def calls(self) -> int:
        return self.inner.calls

    @property
    def refreshes(self) -> int:
        return self.inner.refreshes

    @property
    def overflowed(self) -> bool:
        return False  # the rider's run is not redone on the Python path (mtbmj.bike.run.simulate)

    def reset(self) -> None:
        self.inner.reset()

    def set_speed(self, v: float) -> None:
        """The set speed (m/s) from now on (a run on a speed profile, ``mtbmj.bike.schedule``): the drive's
        (``inner``) and the controller's look-ahead before an edge (``Controller.drop_share``'s lead)."""
        self.inner.set_speed(v)
        self.controller.speed = float(v)

    def angles(self, q) -> dict:
        """The anatomical angles (rad) at qpos ``q``: the pose's plus each joint's turn (``attach``'s
        signs: hip, shoulder and elbow flexion turn with their joints, knee flexion against it, the
        ankle's dorsiflexion against the shank's turn on the frame)."""
        a, qa = self.a0, self.qadr
        return {"hip": a["hip"] + q[qa["hip"]], "knee": a["knee"] - q[qa["knee"]],
                "ankle": a["ankle"] - (q[qa["rider_pitch"]] + q[qa["hip"]] + q[qa["knee"]]),
                "shoulder": a["shoulder"] + q[qa["shoulder"]], "elbow": a["elbow"] + q[qa["elbow"]]}

    def rates(self, v) -> dict:
        d = self.dof
        return {"hip": v[d["hip"]], "knee": -v[d["knee"]], "ankle": -(v[d["rider_pitch"]] + v[d["hip"]] + v[d["knee"]]),
                "shoulder": v[d["shoulder"]], "elbow": v[d["elbow"]]}

    def add_torque(self, Q, name: str, tau: float) -> None:
        """An anatomical torque (positive: flexion, dorsiflexion) on the joints' coordinates."""
        d = self.dof
        if name == "knee":
            Q[d["knee"]] -= tau
        elif name == "ankle":
            Q[d["rider_pitch"]] -= tau
            Q[d["hip"]] -= tau
            Q[d["knee"]] -= tau
        else:
            Q[d[name]] += tau

    def __call__(self, m, d):
        if m is not self._model and m._address != self._model._address:
            return
        d.qfrc_applied[:] = 0.0
        ctl = self.controller  # the muscles first: the driving leg's stroke is cut with them (pedal_leg.hold)
        want = aimed(ctl, self.aim, d.site_xpos[self.s_front][0], d.qpos[self.qadr["pitch"]], d.qvel[self.dof["pitch"]])
        now, speed = self.angles(d.qpos), self.rates(d.qvel)
        taus, demands, power = muscle_torques(want, now, speed, gains_at(ctl, self.gains, d.site_xpos[self.s_front][0]),
                                              self.strength)
        if self.leg is not None:
            self.leg.hold(m, d, self.inner, taus, power)
        self.inner(m, d)
        Q = self._q
        Q[:] = 0.0
        qvel = d.qvel
        pins = []
        # the pins: feet at the ankle's point, hands at the grip
        for end, anchor, body in self.s_pins:
            pe, pa = d.site_xpos[end], d.site_xpos[anchor]
            mujoco.mj_jac(m, d, self._j1, None, pe, body)
            mujoco.mj_jac(m, d, self._j2, None, pa, self.b_frame)
            rel = self._j1 @ qvel - self._j2 @ qvel
            f = -PIN_N_PER_M * (pe - pa) - PIN_N_S_PER_M * rel
            f[1] = 0.0
            Q += self._j1.T @ f - self._j2.T @ f
            pins.append((f, rel, pe - pa))
        # the muscles' torques (above), the end stops, the tissue
        stops = rb.end_stops(now, speed, self.ranges)
        clamped = {k: demands[k] >= 1.0 for k in JOINTS}
        applied = {}
        for k in JOINTS:
            tau = taus[k]
            flex, ext = self.strength[k]
            self.peak_demand[k] = max(self.peak_demand[k], float(demands[k]))
            ratio = tau / flex if tau > 0 else -tau / ext
            if abs(tau) > self.peak_torque[k]:
                self.peak_torque[k] = abs(tau)
            if ratio > self.peak_ratio[k]:
                self.peak_ratio[k] = ratio
            applied[k] = tau + stops[k] - TISSUE_DAMPING * speed[k]
            self.add_torque(Q, k, applied[k])
        if power > self.peak_power:
            self.peak_power = power
        if d.time > self._t_seen:  # each stretch of time counted once (a stretch stepped again is not)
            if self._t_seen > -math.inf:
                for k in JOINTS:
                    if clamped[k]:
                        self.at_limit_s[k] += d.time - self._t_seen
            self._t_seen = d.time
        saddle = (0.0, 0.0)
        if ctl.seated and ctl.saddle is not None:
            saddle = self._saddle(m, d, Q)
        d.qfrc_applied[:] += Q
        # pedalling: the driving leg's torques that push the pedal (its reaction is on the trunk, where
        # the bike's callback puts it: mtbmj.bike.pedal_leg)
        leg = None if self.leg is None else self.leg.engine(d)
        if leg is not None:
            self.leg.apply(d, leg)
            self.leg.note(leg, taus, STRENGTH_ONE_SIDE_N_M, d.time)
        # what the energy balance (mtbmj.bike.energy) reads: each force's parts at this evaluation
        self.last = {"taus": taus, "want": want, "now": now, "applied": applied, "speed": speed, "stops": stops,
                     "pins": pins, "saddle": saddle, "leg": leg}

    def _saddle(self, m, d, Q) -> tuple[float, float]:
        """The saddle's push on the sitting bones (one-sided), and its reaction on the frame:
        (push N, closing speed m/s), (0, 0) off the saddle."""
        rot = d.xmat[self.b_frame].reshape(3, 3)
        hips = d.site_xpos[self.s_hips]
        seat = d.xpos[self.b_frame] + rot @ np.array([self.controller.saddle[0], 0.0, self.controller.saddle[1]])
        bone = hips - ISCHIAL_BELOW_HIP_M * rot[:, 2]
        depth = float((seat - bone) @ rot[:, 2])  # how far the sitting bones are below the saddle's top
        if depth <= 0.0:
            return 0.0, 0.0
        mujoco.mj_jac(m, d, self._j1, None, bone, self.b_rider)
        mujoco.mj_jac(m, d, self._j2, None, bone, self.b_frame)
        closing = float(rot[:, 2] @ (self._j2 @ d.qvel - self._j1 @ d.qvel))
        push = max(SADDLE_N_PER_M * depth + SADDLE_N_S_PER_M * closing, 0.0)
        f = push * rot[:, 2]
        Q += self._j1.T @ f - self._j2.T @ f
        self.saddle_peak = max(self.saddle_peak, push)
        return push, closing

    def report(self) -> dict:
        """What the summary says of the rider: each joint's largest muscle torque against its limit."""
        joints = {k: {"peak_N_m": round(self.peak_torque[k], 3), "limit_flexion_N_m": round(self.strength[k][0], 3),
                      "limit_extension_N_m": round(self.strength[k][1], 3), "peak_of_limit": round(self.peak_ratio[k], 4),
                      "asked_peak_of_limit": round(self.peak_demand[k], 3), "at_limit_s": round(self.at_limit_s[k], 4)}
                  for k in JOINTS}
        return {"kind": "active", "height_m": self.body.height, "joints": joints,
                "within_limits": all(v["peak_of_limit"] <= 1.0 + 1e-9 for v in joints.values()),
                "peak_power_W": round(self.peak_power, 1), "power_limit_W": POWER_W,
                "drops_seen_m": [round(e, 3) for e in self.controller.edges],
                **({} if self.leg is None else {"pedal_leg": self.leg.report()})}


def saddle_point(spec) -> tuple[float, float] | None:
    """The saddle's top (m, frame coordinates): the seated centre of mass less the chart's offset
    from the saddle (``SEATED_FROM_SADDLE_M``), or None when the bike gives no seated rider."""
    c = spec.rider.seated_com
    return None if c is None else (c[0] - SEATED_FROM_SADDLE_M[0], c[1] - SEATED_FROM_SADDLE_M[1])


def stance(spec, body: rb.Body, seated: bool = False, pedalling: bool = False) -> tuple[tuple, float]:
    """(hips m, trunk rad) of the standing attack position (ankles ``ATTACK_ANKLE_DEG`` dorsiflexed,
    knees ``ATTACK_KNEE_DEG`` bent: the hips behind the pedals) or seated (the sitting bones on the saddle), the shoulder
    ``ARM_REACH`` of the arm's length from the grip. Standing and ``pedalling``, the hips as low as
    the driving leg needs to reach the stroke's bottom (``pedal_leg.pedalling_hip``)."""
    r = spec.rider
    grip = (r.arm_x, r.arm_z)
    if seated:
        s = saddle_point(spec)
        hip = (s[0], s[1] + ISCHIAL_BELOW_HIP_M - SIT_DEPTH_M)  # sat down into the saddle
    else:  # from the feet up: the shank leaning ATTACK_ANKLE_DEG forward, the knee bent ATTACK_KNEE_DEG
        ankle = (r.leg_x + body.ankle_from_pedal[0], r.leg_z + body.ankle_from_pedal[1])
        lean, bend = math.radians(ATTACK_ANKLE_DEG), math.radians(ATTACK_KNEE_DEG)
        knee = (ankle[0] + body.shank.length * math.sin(lean), ankle[1] + body.shank.length * math.cos(lean))
        thigh = -math.pi / 2.0 - lean + bend  # the thigh's direction, hip to knee
        hip = (knee[0] - body.thigh.length * math.cos(thigh), knee[1] - body.thigh.length * math.sin(thigh))
        if pedalling:
            hip = pedalling_hip(body, hip, (r.leg_x, r.leg_z))
    reach = ARM_REACH * (body.upper_arm.length + body.forearm.length)
    return hip, rb.trunk_for_reach(body, hip, grip, reach)


def activate(p, make_inner, integrator, hold: float, seated: bool = False, settle_s: float = 1.0):
    """The prepared run ``p`` (``mtbmj.bike.run.prepare``, the rigid rider) with the articulated
    rider instead: the same bike, terrain, tires, laws and drive; the bike's joints where the rigid
    rider's static equilibrium put them, the body in its stance, then ``settle_s`` of settling in
    place (the bike held fore and aft by an armature ``hold``, coasting) before it is set rolling at
    the run's speed. ``make_inner(bike)``: the bike's callback of the run's kind for the new model
    (``mtbmj.bike.run.make_callback``); ``integrator``: the model's (``mjtIntegrator``)."""
    from mtbmj.bike import crash
    from mtbmj.bike.callback import BikeCallback
    from mtbmj.bike.model import build_bike
    from mtbmj.controllers import installed
    from mtbmj.controllers.drive import Drive
    from mtbmj.runpath import guard

    if p.lock or not p.rear_tire_on:
        raise ConfigError("rider: the active rider rides the whole bike (no --lock, no --lift-rear)")
    spec = p.spec
    if seated and saddle_point(spec) is None:
        raise ConfigError(f"rider.seated_com_mm: {spec.name} gives no seated rider (the saddle the active rider sits on)")
    r = spec.rider
    body = rb.body(r.mass + r.on_bike_mass, r.height)
    pedal, grip = (r.leg_x, r.leg_z), (r.arm_x, r.arm_z)
    pedalling = getattr(getattr(p.callback, "drive", None), "mode", None) == "pedal"
    hip, trunk = stance(spec, body, seated, pedalling)
    pose0 = rb.pose(body, pedal, grip, hip, trunk)
    limp = dataclasses.replace(spec, rider=dataclasses.replace(r, leg_stiffness=0.0, leg_damping=0.0,
                                                                arm_stiffness=0.0, arm_damping=0.0))
    old, s = p.bike, p.fork_setup
    b = build_bike(spec, old.tire_radius, p.terrain, p.timestep, integrator, p.gravity,
                   old.x0 + spec.front_axle[0], s.fork_length, visual=False, articulated=(body, pose0))
    b = dataclasses.replace(b, spec=limp)  # the rigid rider's legs and arms: nothing on the trunk
    rear = p.rear_tire
    wheelbase = spec.front_axle[0] - spec.rear_axle[0]
    ctl = Controller(body, pedal, grip, hip, trunk, edges(p.terrain), p.speed, wheelbase, seated,
                     saddle_point(spec), old.x0 + spec.front_axle[0])
    inner = make_inner(b)
    rc = RiderCallback(b.model, inner, body, pose0, ctl)
    if pedalling:
        ring, cog = spec.drive["chain_m"]
        rc.leg = PedalLeg(body, grip, cog / (ring * rear.radius), STRENGTH_ONE_SIDE_N_M, POWER_W).bind(b.model)
    data = mujoco.MjData(b.model)
    for name in ("bike_x", "bike_z", "pitch", "fork", "swingarm"):
        data.qpos[b.qpos_index(name)] = p.initial_qpos[old.qpos_index(name)]
    data.act[:] = p.initial_act
    # settle in place: held fore and aft, coasting, the Python callback (a second is 2000 steps)
    coast = BikeCallback(b, p.fork_law, p.shock_law, p.front_tire, rear, Drive("coast", 0.0), p.speed, p.traction,
                         p.callback.refresh)
    # the pose the controller asks for at the start (the stance, or a drop's pose begun before it)
    settle = RiderCallback(b.model, coast, body, pose0, dataclasses.replace(ctl, hold_x=ctl.x_start))
    xdof = b.dof_index("bike_x")
    keep, b.model.dof_armature[xdof] = float(b.model.dof_armature[xdof]), hold
    with installed(settle), guard.collected_warnings(messages := []), diverging("bike (the rider settling)"):
        for _ in range(int(round(settle_s / p.timestep))):
            mujoco.mj_step(b.model, data)
    if (cause := guard.warned_cause(data, messages, b.model)) is not None:  # MuJoCo reset a blown-up state
        raise RunError(f"rider: the active rider did not settle on the bike in place ({cause})")
    b.model.dof_armature[xdof] = keep
    data.time = 0.0
    data.qvel[:] = 0.0
    data.qvel[xdof] = p.speed
    data.qvel[b.dof_index("front_spin")] = p.speed / old.tire_radius
    data.qvel[b.dof_index("rear_spin")] = p.speed / old.tire_radius
    inner.reset()
    with installed(rc):
        mujoco.mj_forward(b.model, data)
    rc.clear_peaks()
    p.bike, p.callback, p.data = b, rc, data
    p.initial_qpos, p.initial_qvel, p.initial_act = data.qpos.copy(), data.qvel.copy(), data.act.copy()
    p.watch = crash.Watch(b.model, p.terrain, b.qpos_index("pitch"))
    p.articulated = (body, pose0)
    return p


__all__ = ["RiderCallback", "Controller", "activate", "aimed", "gains_at", "muscle_torques", "power_factors", "edges", "stance", "saddle_point", "STRENGTH_N_M",
           "STRENGTH_ONE_SIDE_N_M", "POWER_W", "GAINS", "JOINTS"]

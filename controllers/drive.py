"""The rolling front end's drive: how it is kept moving along the terrain.

Three modes (``mtbmj roll --drive``):

* ``rider`` (the default): a speed controller whose force is what a rider and the rest of the
  bike can put through the frame onto the front end, F = clip(kv (v_ref - v), -brake, push(v)),
  push(v) = min(force, power / v). It pushes at most ``force`` (N), or ``power`` (W) at speed v,
  and holds back at most ``brake`` (N). When a rock stops the wheel, the limit binds: the front
  end loses speed, and afterwards comes back to the set speed no faster than the limits allow; it
  never catches up the distance it lost (no position term), so it is never launched.
* ``servo``: the ideal position servo of earlier versions, a PD on x tracking x0 + v t with
  whatever force that takes (the scene's ``drive_position`` and ``drive_velocity`` actuators, 10 Hz
  critically damped). Kept for comparisons with a model driven at an exact speed.
* ``coast``: no drive force at all.

The rider limits are the front end's share of a whole bike's (the front end carries 55.5 kg of
an 85 kg rider and an 11 kg bike, 58 %): ``RIDER_PUSH_N`` = 0.58 x 720 N, a 170 N m peak crank
torque through a 32 x 50 low gear onto a 0.37 m wheel radius; ``RIDER_POWER_W`` = 0.58 x 1000 W, a
trained rider's peak power over a few seconds; ``RIDER_BRAKE_N`` = 0.58 x 565 N, a 0.6 g stop of
the 96 kg. All assumed (round values of the ranges riding and cycling texts give), not measured on
this bike. The force enters MuJoCo through the same two actuators as the servo: the callback sets
the velocity actuator's reference so that its force is F and the position actuator's so that its
force is 0. ``drive_force`` is written once: the Python callback calls it and the compiled
rolling callback compiles its source.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from mtbmj.limits import PEDAL_POWER_W, PEDAL_RPM

MODES = ("rider", "servo", "coast")
SERVO, RIDER, COAST = 0, 1, 2  # codes the compiled callback reads
# Pedalling (the whole bike's ``pedal`` mode, ``pedal_forces``): the crank's length and what a
# rider's legs can do. 170 mm is the commonest crank on trail bikes (assumed); cadence and power
# (``PEDAL_RPM``, ``PEDAL_POWER_W``) are the numeric gate's, ``mtbmj.limits``: one range for the
# command's arguments, the Python check and this law.
CRANK_LENGTH_M = 0.170
FRONT_SHARE = 0.58
RIDER_PUSH_N = round(FRONT_SHARE * 720.0)  # 418 N
RIDER_POWER_W = round(FRONT_SHARE * 1000.0)  # 580 W
RIDER_BRAKE_N = round(FRONT_SHARE * 565.0)  # 328 N


def drive_force(v_ref: float, v: float, kv: float, push: float, power: float, brake: float) -> float:
    """The rider's drive force (N, forward positive) at speed v (m/s) for the set speed v_ref:
    kv (v_ref - v), at most ``push`` and ``power`` / v forward, at most ``brake`` back."""
    f = kv * (v_ref - v)
    limit = push
    if v > 0.0 and power < limit * v:
        limit = power / v
    if f > limit:
        f = limit
    if f < -brake:
        f = -brake
    return f


# The whole bike's rider eases off the push as the front lifts (``eased``): with the front tyre off the
# ground, the push is cut linearly from all of it at a frame pitch of LIFT_EASE_DEG[0] nose up to none at
# LIFT_EASE_DEG[1] (what a rider does when the front comes up unasked: he stops pedalling, as a wheelie is
# held down by easing the drive and raised by pedalling, as a motorcycle's wheelie control cuts the engine's
# torque; the angles assumed, below the balance point over the rear tyre's contact, about 26 deg on the
# tests' bike: its masses' centre 0.55 m ahead of the rear axle and 1.09 m above the ground).
LIFT_EASE_DEG = (10.0, 20.0)


def eased(f: float, pitch: float, front_loaded: bool, lo_deg: float, hi_deg: float) -> float:
    """The drive force ``f`` (N, forward positive) as a rider gives it with the frame at ``pitch`` (rad,
    nose up positive): unchanged while the front tyre carries load (``front_loaded``) or when it holds
    back (f <= 0); with the front off the ground, cut from all of it at ``lo_deg`` to none at ``hi_deg``."""
    if front_loaded or f <= 0.0:
        return f
    u = (pitch * 57.29577951308232 - lo_deg) / (hi_deg - lo_deg)
    if u <= 0.0:
        return f
    if u >= 1.0:
        return 0.0
    return f * (1.0 - u)


def at_patch(f: float, fx: float, fz: float, deflection: float, radius: float):
    """(dx, dz, torque): a tangential ground force ``f`` (forward positive) on a tyre whose radial
    force is (fx, fz), as a force at the axle, along the tyre's contact tangent, and the couple
    about the axle (world y, right-handed) of that force acting at the contact patch, which lies
    radius - deflection from the axle against the radial force."""
    n = (fx * fx + fz * fz) ** 0.5
    if n <= 0.0 or f == 0.0:
        return 0.0, 0.0, 0.0
    dx = f * fz / n
    dz = -f * fx / n
    rho = radius - (deflection if deflection > 0.0 else 0.0)
    rx = -rho * fx / n
    rz = -rho * fz / n
    return dx, dz, rz * dx - rx * dz


def wheel_forces(f: float, fxf: float, fzf: float, df: float, fxr: float, fzr: float, dr: float,
                 traction: float, radius: float):
    """The whole bike's drive ``f`` (N, forward positive; ``drive_force``) as the ground's forces
    on the two tyres: (dxf, dzf, torque_f, dxr, dzr, torque_r). Each tyre's ground force acts at
    its contact patch: returned as a force at its axle and the couple (world y) the part that makes
    the force reacts (the hub drive's and the rear caliper's swingarm, the front caliper's fork
    lower). A push drives the rear tyre alone, at most ``traction`` times its radial load; a brake
    is shared as a rider brakes, in proportion to the tyres' loads, each at most ``traction`` times
    its load, what one tyre cannot hold going to the other within its grip. (fx, fz) is each tyre's
    radial force, ``d`` its deflection, ``radius`` the tyres' radius."""
    nf = (fxf * fxf + fzf * fzf) ** 0.5
    nr = (fxr * fxr + fzr * fzr) ** 0.5
    front = 0.0
    rear = 0.0
    if f > 0.0:
        rear = f if f < traction * nr else traction * nr
    elif f < 0.0 and nf + nr > 0.0:
        brake = -f
        capf = traction * nf
        capr = traction * nr
        bf = brake * nf / (nf + nr)
        br = brake - bf
        if bf > capf:
            br += bf - capf
            bf = capf
        if br > capr:
            bf += br - capr
            br = capr
        if bf > capf:
            bf = capf
        front = -bf
        rear = -br
    dxf, dzf, tf = at_patch(front, fxf, fzf, df, radius)
    dxr, dzr, tr = at_patch(rear, fxr, fzr, dr, radius)
    return dxf, dzf, tf, dxr, dzr, tr


def chain_pull(torque: float, ax: float, az: float, ring: float, cog: float):
    """(fx, fz, px, pz) in the frame's coordinates (origin the bottom bracket): the chain's pull
    (fx, fz) on the rear axle at (ax, az), and the point (px, pz) on the chainring where its
    reaction -(fx, fz) acts on the frame, when the rear tyre's ground couple about its axle
    ``torque`` (world y; negative when the ground pushes the bike forward: a drive) is made through
    the chain. The chain's upper run is the outer tangent of the cog (radius ``cog`` about the
    axle) and the chainring (radius ``ring`` about the bottom bracket) above their centres; its
    tension T = -torque / cog balances the ground's couple on the wheel, so the swingarm gets the
    pull at the axle and no couple; the chainring's torque is reacted by the frame (the crank held
    by the rider's legs on it). Zero for a braking couple (torque >= 0: the caliper reacts it) or
    without a chain (cog <= 0)."""
    if torque >= 0.0 or cog <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    dx = -ax  # from the cog's centre to the chainring's
    dz = -az
    length = (dx * dx + dz * dz) ** 0.5
    ux = dx / length
    uz = dz / length
    c = (cog - ring) / length  # the tangent points' normal n: n . d = cog - ring, n above the centres
    sq = (1.0 - c * c) ** 0.5
    px = -uz
    pz = ux
    if pz < 0.0:
        px = -px
        pz = -pz
    nx = c * ux + sq * px
    nz = c * uz + sq * pz
    tx = dx + (ring - cog) * nx  # the run from the cog's tangent point to the chainring's
    tz = dz + (ring - cog) * nz
    tl = (tx * tx + tz * tz) ** 0.5
    tension = -torque / cog
    return tension * tx / tl, tension * tz / tl, ring * nx, ring * nz


def pedal_forces(theta: float, peak: float, crank: float):
    """(torque, fx, fz, px, pz) of a pedalling rider at crank angle ``theta`` (rad: the right
    crank's angle from top dead centre, turning forward): the crank torque (N m, forward positive),
    the driving foot's force (fx, fz) on its pedal and that pedal's place (px, pz) from the bottom
    bracket, in the frame's coordinates (x forward, z up). Each leg drives on its downstroke with
    ``peak`` sin(phi), phi its own crank's angle from the top (0 to pi), and pushes its pedal along
    the crank circle's tangent (the effective force: the radial part, which makes no torque, is left
    out); the legs are half a turn apart, so one drives at a time and the torque is
    ``peak`` |sin theta|, its mean over a turn 2 ``peak`` / pi, twice a turn from zero at the dead
    centres to ``peak`` with the crank level (the common idealisation of a pedal stroke; assumed)."""
    s = math.sin(theta)
    c = math.cos(theta)
    if s < 0.0:  # the left crank drives: it is half a turn on
        s = -s
        c = -c
    torque = peak * s
    f = torque / crank
    return torque, f * c, -f * s, crank * s, crank * c


def pedal_peak(power: float, cadence: float) -> float:
    """The peak crank torque (N m) of ``pedal_forces`` whose mean over a turn at ``cadence``
    (rad/s) is ``power`` (W): pi P / (2 omega). A rider holds the power as the crank speeds up or
    slows (so a climb settles at the speed where the power lifts the bike); below the slowest
    cadence (``PEDAL_RPM``) the torque is that cadence's: legs push no harder."""
    slowest = PEDAL_RPM[0] * math.pi / 30.0
    return math.pi * power / (2.0 * (cadence if cadence > slowest else slowest))


def pedal_drive(x: float, speed: float, power: float, ring: float, cog: float, radius: float, fxf: float,
                fzf: float, df: float, fxr: float, fzr: float, dr: float, traction: float):
    """A pedalling rider's forces on the whole bike: (dxf, dzf, tf, dxr, dzr, tr) of
    ``wheel_forces`` and (foot_x, foot_z, pedal_x, pedal_z), the driving foot's force on its pedal
    and the pedal's place (frame coordinates). The crank's angle is the distance ``x`` (m) rolled
    through the gear (theta = x cog / (ring radius)); its torque (``pedal_forces``) holds ``power``
    at ``speed`` (the centre of mass's, m/s) through the gear (``pedal_peak``); the ground's push
    at the rear contact is the one whose couple there is the chain's (torque / ring x cog, over
    the loaded radius); the foot's force is scaled down as the rear tyre's ``traction`` caps that
    push, and nothing acts with the rear tyre unloaded. ``ring``, ``cog``: the sprockets' pitch
    radii (m); (fx, fz) each tyre's radial force, d its deflection. Written once: the bike's Python
    callback and its ODE reference call it, the compiled callback compiles it."""
    gear = cog / (ring * radius)  # crank radians per metre rolled
    torque, fx, fz, px, pz = pedal_forces(x * gear, pedal_peak(power, speed * gear), CRANK_LENGTH_M)
    rho = radius - (dr if dr > 0.0 else 0.0)
    want = torque * cog / (ring * rho)
    if want <= 0.0 or math.hypot(fxr, fzr) <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    dxf, dzf, tf, dxr, dzr, tr = wheel_forces(want, fxf, fzf, df, fxr, fzr, dr, traction, radius)
    share = math.hypot(dxr, dzr) / want
    return dxf, dzf, tf, dxr, dzr, tr, share * fx, share * fz, px, pz


@dataclass(frozen=True)
class Drive:
    """A drive mode and its limits (see the module doc); ``kv`` (N s/m) is the velocity
    actuator's gain, the rider's speed loop through it."""

    mode: str = "rider"
    kv: float = 0.0
    push: float = RIDER_PUSH_N
    power: float = RIDER_POWER_W
    brake: float = RIDER_BRAKE_N
    cadence: float = 0.0  # pedal: the crank's speed at the start (rad/s); the torque follows the crank's speed

    @property
    def code(self) -> int:
        return {"servo": SERVO, "rider": RIDER, "coast": COAST}[self.mode]  # the front end's modes (pedal is the bike's)

    def force(self, v_ref: float, v: float) -> float:
        """The force of the rider or coasting modes (the servo's comes from its actuators)."""
        if self.mode in ("coast", "pedal"):  # pedal: the crank's torque, through the chain (pedal_forces)
            return 0.0
        return drive_force(v_ref, v, self.kv, self.push, self.power, self.brake)


__all__ = ["Drive", "chain_pull", "drive_force", "eased", "LIFT_EASE_DEG", "pedal_drive", "pedal_forces", "pedal_peak", "CRANK_LENGTH_M", "wheel_forces", "MODES", "RIDER_PUSH_N", "RIDER_POWER_W", "RIDER_BRAKE_N"]

"""The planar bike in MuJoCo: ``mjcf/bike_scene.xml`` rewritten for a bike description.

``build_bike(spec, tire_radius, terrain, setup)`` loads the scene with ``mujoco.MjSpec`` (as the
rolling front end does), sets every position, mass, inertia and axis from the ``BikeSpec``, adds
the terrain as a visual heightfield and compiles. The rider's legs and arms (``Limb``) are the
control callback's forces; the scene draws them as tendons. The bike is placed with its
front axle over ``start_x`` and its front tire just touching the ground at qpos = 0 (both ends at
full extension, frame level); ``mtbmj.bike.run`` then settles it to its static equilibrium.

Mass bookkeeping (``frame_body``): the frame body carries the frame and the rider's segments that
move with the bike (feet and shanks at the pedals, hands and forearms at the bars, in de Leva's
proportions 5.70 : 2.23); the fork lower carries the fork's unsprung mass at the front axle; each
wheel its own mass at its axle (its spin joint is free, so its spin inertia does not enter the
planar motion); the swingarm its mass midway between the main pivot and the rear axle.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from mtbmj import mjcf
from mtbmj.errors import ConfigError
from mtbmj.runpath import loop

SCENE = "bike_scene.xml"
LOWER_INERTIA = 0.02  # kg m^2, the fork lower's pitch inertia about the axle (assumed)
PEDAL_SHARE = 5.70 / (5.70 + 2.23)  # de Leva 1996, male: (foot + shank) / (foot + shank + hand + forearm)
JOINTS = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_z", "rider_pitch")
# what a run can hold at its static values (``mtbmj.bike.run.prepare(lock=...)``): key -> joints
LOCKS = {"rear": ("swingarm",), "pitch": ("pitch",), "rider": ("rider_z", "rider_pitch")}
# what ``build_bike(visual=False)`` leaves out of the scene (``MjSpec`` lists): what only a picture uses
NOT_STEPPED = ("geoms", "tendons", "cameras", "lights")


def frame_body(spec) -> tuple[float, tuple[float, float], float]:
    """(mass kg, centre of mass m in frame coordinates, pitch inertia kg m^2 about it) of the frame
    body: the frame with the rider's on-bike segments at the pedals and the bars."""
    r = spec.rider
    parts = [(spec.frame_mass, spec.frame_com, spec.frame_inertia),
             (r.on_bike_mass * PEDAL_SHARE, (r.leg_x, r.leg_z), 0.0),
             (r.on_bike_mass * (1.0 - PEDAL_SHARE), (r.arm_x, r.arm_z), 0.0)]
    m = sum(p[0] for p in parts)
    cx = sum(p[0] * p[1][0] for p in parts) / m
    cz = sum(p[0] * p[1][1] for p in parts) / m
    inertia = sum(p[2] + p[0] * ((p[1][0] - cx) ** 2 + (p[1][1] - cz) ** 2) for p in parts)
    return m, (cx, cz), inertia


def centre_of_mass(spec) -> tuple[float, tuple[float, float]]:
    """(mass kg, centre of mass m in frame coordinates) of the bike and rider at full extension:
    the frame body (:func:`frame_body`), the rider at its stance, the fork lower and front wheel at
    the front axle, the rear wheel at the rear axle, the swingarm midway between pivot and axle."""
    m_frame, c_frame, _ = frame_body(spec)
    swingarm = tuple(0.5 * (p + a) for p, a in zip(spec.pivot, spec.rear_axle))
    bodies = [(m_frame, c_frame), (spec.rider.mass, spec.rider.com),
              (spec.fork_lower_mass + spec.front_wheel_mass, spec.front_axle),
              (spec.rear_wheel_mass, spec.rear_axle), (spec.swingarm_mass, swingarm)]
    total = sum(m for m, _ in bodies)
    return total, tuple(sum(m * float(p[i]) for m, p in bodies) / total for i in (0, 1))


def rider_rest_lengths(spec, gravity: float) -> tuple[float, float]:
    """Spring lengths (m) of the legs and arms that hold the rider at rest at its stance on a level
    frame: each carries its share of the rider's weight by the lever rule about the centre of mass,
    legs W (x_bars - x_com) / (x_bars - x_pedals), arms the rest."""
    r = spec.rider
    w = r.mass * gravity
    span = r.arm_x - r.leg_x
    legs = w * (r.arm_x - r.com[0]) / span
    arms = w * (r.com[0] - r.leg_x) / span
    return r.leg_length + legs / r.leg_stiffness, r.arm_length + arms / r.arm_stiffness


@dataclass(frozen=True)
class Bike:
    """A compiled bike and the numbers its callback needs (SI)."""

    model: mujoco.MjModel
    spec: object  # BikeSpec
    x0: float  # world position of the frame origin (bottom bracket) at qpos = 0
    z0: float
    tire_radius: float
    legs_rest: float
    arms_rest: float

    def qpos_index(self, name: str) -> int:
        return int(self.model.joint(name).qposadr[0])

    def dof_index(self, name: str) -> int:
        return int(self.model.joint(name).dofadr[0])

    @property
    def limbs(self) -> tuple[Limb, Limb]:
        """The legs and the arms (``Limb``): the rider's springs, which the control callback applies."""
        r = self.spec.rider
        return (Limb("legs", "pedals", "hips", r.leg_stiffness, r.leg_damping, self.legs_rest),
                Limb("arms", "bars", "shoulders", r.arm_stiffness, r.arm_damping, self.arms_rest))


@dataclass(frozen=True)
class Limb:
    """The rider's legs or arms: a linear spring-damper along the straight line from a site on the
    frame to a site on the rider (SI). Both sites are fixed in their bodies and the rider hangs on
    the frame by its own two joints (``rider_z``, ``rider_pitch``), so the length depends on those
    joints alone, and the force acts on them alone: Q_j = f dL/dq_j with f = -k (L - rest) - c dL/dt
    (what a MuJoCo spatial tendon with this stiffness and damping gives, ``tests/test_bike_limbs.py``).
    The callback applies it as ``qfrc_applied``: a tendon's own computation took 15 % of a step."""

    name: str
    frame_site: str
    rider_site: str
    stiffness: float
    damping: float
    rest: float


def crown(spec, fork_length: float) -> tuple[float, float]:
    """The fork crown (frame coordinates): from the front axle at full extension back by the fork's
    offset (perpendicular to the steering axis) and up the axis by the fork's length."""
    a = spec.head_angle
    c, s = math.cos(a), math.sin(a)
    fx, fz = spec.front_axle
    return fx - spec.fork_offset * s - fork_length * c, fz - spec.fork_offset * c + fork_length * s


START_BEFORE_M = 100.0  # how far before a terrain's beginning a run may start (its level lead-in ridden first)


def _check_start(spec, terrain, start: float, radius: float) -> None:
    """Refuse a front axle's start from which neither wheel meets the terrain's feature (or, on a
    profile without one, past its end): such a run went on over the level ground beyond, its
    feature window over nothing (--start-m 30 past a rock: "0 % tire-load variation over the feature");
    and one more than ``START_BEFORE_M`` before the terrain begins (--start-m -5000 rode 5 km of level ground
    first, silently)."""
    from mtbmj.bike.summary import feature_span

    span = feature_span(terrain)
    rear = start - (spec.front_axle[0] - spec.rear_axle[0])
    end = terrain.start_x + terrain.length
    if start < terrain.start_x - START_BEFORE_M:  # a sign slip or mm for m: that much level ground ridden first
        raise ConfigError(f"start: the front axle's start (--start-m) {start:g} m is {terrain.start_x - start:g} m "
                          f"before the terrain {terrain.name} begins ({terrain.start_x:g} to {end:g} m): start within "
                          f"{START_BEFORE_M:g} m of its beginning")
    if span is None and start >= end:
        raise ConfigError(f"start: the front axle's start (--start-m) {start:g} m is past the end of the terrain "
                          f"{terrain.name} ({terrain.start_x:g} to {end:g} m): nothing ahead to ride over")
    if span is not None and rear >= span[1] + radius:
        raise ConfigError(f"start: from the front axle's start (--start-m) {start:g} m both wheels start past the "
                          f"feature of {terrain.name} ({span[0]:g} to {span[1]:g} m; the rear axle at {rear:.2f} m): "
                          f"nothing ahead to ride over")


def build_bike(spec, tire_radius: float, terrain, timestep: float, integrator, gravity: float,
               start_x: float | None = None, fork_length: float = 0.58, visual: bool = True,
               articulated=None) -> Bike:
    """Compile the bike scene for ``spec`` on ``terrain``; the front axle starts over ``start_x``
    (default the terrain's start); ``fork_length`` (axle to crown, m) places the drawn stanchions.
    ``visual=False`` leaves out every geom (the drawn bike and the terrain), the drawn legs and
    arms (tendons), the camera and the light (``NOT_STEPPED``): nothing in the physics depends on
    them (the inertias are given, nothing collides, the callback applies the limbs' forces), and
    MuJoCo then places no geoms, cameras or lights and computes no tendon at each evaluation (~4 %,
    ~0.5 % and ~15 % of a step); the joints, bodies and their numbering are the same (MuJoCo's passive
    stage is skipped while a run steps where the model has nothing for it: ``mtbmj.runpath.loop.
    passive_skipped``). ``articulated``: (``rider_body.Body``, ``rider_body.Pose``), the articulated
    rider in place of the rigid one (``rider_body.attach``; ``--rider active``)."""
    ms = mujoco.MjSpec.from_file(str(mjcf.path(SCENE)))
    ms.option.timestep = timestep
    ms.option.integrator = integrator
    ms.option.gravity = [0.0, 0.0, -gravity]
    # no MuJoCo contacts or constraints: the tires, the suspension's stops and the drive are the
    # callback's forces; skipping the empty collision and constraint stages saves ~10 % of a step
    ms.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    a = spec.head_angle
    c, s = math.cos(a), math.sin(a)
    fx, fz = spec.front_axle
    rx, rz = spec.rear_axle
    px, pz = spec.pivot
    start = terrain.start_x if start_x is None else float(start_x)
    _check_start(spec, terrain, start, tire_radius)
    h0 = float(terrain.height(start))
    x0 = start - fx
    z0 = h0 + tire_radius - fz  # the front tread touches the ground at qpos = 0
    frame = ms.body("frame")
    frame.pos = [x0, 0.0, z0]
    m, com, inertia = frame_body(spec)
    frame.mass = m
    frame.ipos = [com[0], 0.0, com[1]]
    frame.inertia = [inertia, inertia, inertia]
    r = spec.rider
    ms.site("pedals").pos = [r.leg_x, 0.0, r.leg_z]
    ms.site("bb").pos = [0.0, 0.0, 0.0]
    ms.site("bars").pos = [r.arm_x, 0.0, r.arm_z]
    ms.site("main_pivot").pos = [px, 0.0, pz]
    lower = ms.body("fork_lower")
    lower.pos = [fx, 0.0, fz]
    lower.mass = spec.fork_lower_mass
    lower.inertia = [LOWER_INERTIA] * 3
    ms.joint("fork").axis = [-c, 0.0, s]
    ms.geom("lower_leg").fromto = [0.0, 0.0, 0.0, -0.3 * c, 0.0, 0.3 * s]
    cx_, cz_ = crown(spec, fork_length)
    ms.geom("stanchion").fromto = [cx_, 0.0, cz_, cx_ + 0.55 * fork_length * c, 0.0, cz_ - 0.55 * fork_length * s]
    for name, mass in (("front_wheel", spec.front_wheel_mass), ("rear_wheel", spec.rear_wheel_mass)):
        body = ms.body(name)
        body.mass = mass
        i = spec.wheel_inertia
        body.inertia = [i / 2, i, i / 2]
    for name in ("front_tire", "rear_tire"):
        ms.geom(name).size = [tire_radius, 0.03, 0.0]
    for name in ("front_marker", "rear_marker"):
        ms.geom(name).size = [max(tire_radius - 0.07, 0.04), 0.005, 0.01]
    arm = ms.body("swingarm")
    arm.pos = [px, 0.0, pz]
    arm.mass = spec.swingarm_mass
    arm.ipos = [(rx - px) / 2, 0.0, (rz - pz) / 2]
    arm.inertia = [spec.swingarm_inertia] * 3
    ms.geom("chainstay").fromto = [0.0, 0.0, 0.0, rx - px, 0.0, rz - pz]
    ms.body("rear_wheel").pos = [rx - px, 0.0, rz - pz]
    rider = ms.body("rider")
    rider.pos = [r.com[0], 0.0, r.com[1]]
    rider.mass = r.mass
    rider.inertia = [r.pitch_inertia] * 3
    hips = (r.leg_x - r.com[0], r.leg_z + r.leg_length - r.com[1])
    shoulders = (r.arm_x - r.com[0], r.arm_z + r.arm_length - r.com[1])
    ms.site("hips").pos = [hips[0], 0.0, hips[1]]
    ms.site("shoulders").pos = [shoulders[0], 0.0, shoulders[1]]
    ms.geom("torso").fromto = [hips[0], 0.0, hips[1], shoulders[0], 0.0, shoulders[1]]
    legs_rest, arms_rest = rider_rest_lengths(spec, gravity)
    if articulated is not None:
        from mtbmj.bike import rider_body

        rider_body.attach(ms, spec, *articulated, (r.leg_x, r.leg_z), visual)
    if visual:
        _terrain_visual(ms, terrain)
    else:
        for item in [item for kind in NOT_STEPPED for item in getattr(ms, kind)]:
            ms.delete(item)
    model = ms.compile()
    loop.skip_collision(model)
    return Bike(model, spec, x0, z0, float(tire_radius), legs_rest, arms_rest)


def _terrain_visual(ms, terrain) -> None:
    x_lo, x_hi = float(terrain.x[0]) - 2.0, float(terrain.x[-1])
    n = int(min(20000, max(64, (x_hi - x_lo) / 0.005)))
    xs = np.linspace(x_lo, x_hi, n)
    zs = terrain.height(xs)
    lo, hi = float(zs.min()), float(zs.max())
    span = max(hi - lo, 1e-3)
    ms.add_hfield(name="terrain", size=[(x_hi - x_lo) / 2, 0.3, span, 0.05], nrow=2, ncol=n,
                  userdata=list(np.tile((zs - lo) / span, 2)))
    ms.worldbody.add_geom(name="terrain", type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="terrain",
                          pos=[(x_lo + x_hi) / 2, 0.0, lo], contype=0, conaffinity=0, group=1, material="terrain")


__all__ = ["Bike", "Limb", "build_bike", "crown", "frame_body", "rider_rest_lengths", "JOINTS", "LOCKS", "LOWER_INERTIA", "NOT_STEPPED", "PEDAL_SHARE"]

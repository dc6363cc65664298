"""A whole bike on the trail: ``run_bike(bike, scenario, speed_m_per_s)``.

The bike (``mtbmj.bike.spec``) is built in MuJoCo (``mtbmj.bike.model``), settled to its static
equilibrium on the start of the terrain (the closed-form forces of ``mtbmj.bike.reference``) and
rolled at the set speed. One control callback applies, each evaluation (``BikeCallback`` in
``mtbmj.bike.callback`` is its specification in Python; runs use its compiled twin
``mtbmj.bike.callback_compiled.CompiledBikeCallback`` where numba is installed, ``callback="python"``
forces the Python one):

* the fork law (``compose``'s law of the bike's fork configuration) along the fork slide;
* the shock law (the same law library, the bike's shock configuration) in shock coordinates:
  the rear wheel's travel w and dw/dphi are read from MuJoCo's own kinematics (the rear axle site
  in the frame's coordinates), the stroke is s(w) = integral of dw / LR, the stroke speed
  (dw/dphi) phi' / LR(w), and the shock's force F_s enters as the torque -F_s (dw/dphi) / LR(w) on
  the swingarm (at the wheel: F_s / LR);
* the radial tire (``mtbmj.rolling.tire.RadialTire``, with the rim) at each axle, each on the same
  terrain profile (the rear meets what the front met a wheelbase later);
* the drive: ``controllers.drive.Drive``'s speed controller (rider limits of the whole bike) on the
  horizontal speed of the whole centre of mass (bike and rider), as a force along the rear tire's
  contact tangent, at most ``traction`` times the rear tire's load, none in the air; or coasting.

Conventions: travel and stroke compression positive, zero at full extension; pitch nose up
positive; speed the horizontal speed of the centre of mass of bike and rider; tire loads are each tire's total radial force (N); the rider's vertical acceleration is
the rider body's (gravity excluded, up positive).
"""
from __future__ import annotations

import dataclasses

import math
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable

import mujoco
import numpy as np

from mtbmj import compose, output
from mtbmj.bike import crash
from mtbmj.bike import spec as spec_mod
from mtbmj.bike.model import LOCKS, Bike, build_bike
from mtbmj.bike.parts import setups
from mtbmj.controllers import installed
from mtbmj.controllers.drive import Drive
from mtbmj.errors import ConfigError
from mtbmj.limits import check_duration, check_run, crossing, given, speed as ridden_speed, switch
from mtbmj.result import RunOutput
from mtbmj.rolling import terrain as terrain_mod
from mtbmj.rolling.tire import REFRESH_DISTANCE_M, REFRESH_S, RadialTire
from mtbmj.bike.callback import BikeCallback
from mtbmj.bike.summary import default_duration, gear_speed, signals, summary
from mtbmj.bike.stepping import Stepping, stepping
from mtbmj.runpath import callbacks, guard, loop

CHUNK = 10000
CALLBACKS = ("auto", "compiled", "python")
RIDERS = ("passive", "active")
HEIGHT_UNUSED = ("{}rider.height_m = {:g} m is read by the active rider only (--rider active): the passive rider is its "
                 "mass at rider.com_mm on legs and arms of rider.leg_length_mm and arm_length_mm, whatever its height")
VIDEO_SAMPLE_HZ = 240.0  # the bike's pose kept for a video (qpos rows per second)
# Held degrees of freedom (``lock``): each held joint gets this armature (kg or kg m^2 added to its
# own diagonal of the mass matrix, nothing else), so it keeps its start value and zero speed: under
# the ~1e3 N (m) the tires, springs and dampers put on it, it moves ~1e-9 m (rad) in a second, and the
# other joints move as if it were a rigid constraint (the coupling it leaves is of order M_fc^2 /
# armature ~ 1e-8 of theirs). Unlike MuJoCo's equality constraints (soft, solref) it adds no
# compliance and keeps the model's constraint stage off.
LOCK_ARMATURE = 1e12
DRIVE_HZ = 10.0  # the speed loop's gain: kv = 2 M (2 pi 10 Hz), as the front end's servo
INTEGRATORS = {"rk4": mujoco.mjtIntegrator.mjINT_RK4, "euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST, "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT}
COLUMNS = ("time_s", "x_m", "speed_m_per_s", "front_travel_mm", "rear_travel_mm", "stroke_mm", "pitch_deg",
           "front_tire_N", "rear_tire_N", "front_tire_mm", "rear_tire_mm", "rider_acc_z_m_per_s2", "fork_force_N",
           "shock_force_N", "drive_force_N", "terrain_front_mm", "terrain_rear_mm", "bb_height_mm")
# A pedalling run whose speed falls below this has stalled (walking pace: the power does not hold the grade)
STALL_M_PER_S = 0.5


@dataclass
class Prepared:
    bike: Bike
    spec: object
    fork_setup: compose.Setup
    shock_setup: compose.Setup
    fork_law: object
    shock_law: object
    terrain: object
    front_tire: RadialTire
    rear_tire: RadialTire
    drive: Drive
    traction: float
    speed: float
    gravity: float
    timestep: float  # the output step: the coarse step of ``stepping``
    callback: BikeCallback  # or its compiled twin (mtbmj.bike.callback_compiled.CompiledBikeCallback)
    data: mujoco.MjData
    initial_qpos: np.ndarray
    initial_qvel: np.ndarray
    initial_act: np.ndarray
    stepping: Stepping | None = None
    lock: tuple = ()  # the held degrees of freedom (LOCKS' keys), as checked
    rear_tire_on: bool = True  # False: the rear tire taken off (``prepare(rear_tire=False)``)
    refined_steps: int = 0  # coarse steps stepped again at the fine step (a stop or the rim within reach)
    stepped: int = 0  # coarse steps made
    watch: crash.Watch | None = None  # the run's crash check (``mtbmj.bike.crash``)
    speed_profile: object = None  # mtbmj.bike.schedule.SpeedProfile: the set speed along the terrain, or None
    articulated: tuple | None = None  # the active rider's (body, pose) (``mtbmj.bike.rider_control``), None: rigid

    def visual_model(self) -> mujoco.MjModel:
        """The same bike with its drawn geoms and the terrain (``bike.model`` has none: see
        ``build_bike(visual=...)``): the model a video draws, with the same joints."""
        b, s = self.bike, self.fork_setup
        return build_bike(self.spec, b.tire_radius, self.terrain, self.timestep, INTEGRATORS[s.integrator],
                          self.gravity, b.x0 + self.spec.front_axle[0], s.fork_length,
                          articulated=self.articulated).model


def _check(speed, duration, pedal=None, warn=True):
    """The speed (None with ``pedal``: the gear's speed at its cadence) and the duration, each one
    ConfigError line when it is not a positive number."""
    if speed is None and pedal is not None:
        speed = 1.0
    ridden_speed(speed, warn=warn)
    check_duration("duration", duration)


def _passive(s: dict) -> str:
    """What a pitch crash of the passive rider's run adds: that rider does not shift its weight."""
    if (s.get("rider") or {}).get("kind") == "active" or s["crash"]["kind"] not in ("over the bars", "looped out"):
        return ""
    return (" with the passive rider, a rigid body on spring-damper limbs that does not shift its weight "
            "(--rider active does)")


def prepare(bike="sst", scenario="flat", speed_m_per_s: float | None = 4.0, drive: str = "rider",
            start_x: float | None = None, callback: str = "auto", lock=(), rear_tire: bool = True,
            overrides=None, seated: bool = False, pedal=None, rider: str = "passive",
            legs_swing: bool = False, speed_profile=None) -> Prepared:
    """Everything a run needs, with the data at t = 0: the bike at rest on its static equilibrium
    over the start, moving at the set speed. ``callback``: "auto" (the compiled callback where numba
    is installed, else the Python one with a ``FallbackWarning``), "compiled" or "python".

    ``lock``: degrees of freedom held at their static values (``LOCKS``): "rear" (the swingarm: the
    shock locked out at its sag), "pitch" (the frame level at its static pitch), "rider" (the rider
    rigid on the frame). ``rear_tire=False`` takes the rear tire (and its rim) off: the bike then
    stands on its front wheel alone and needs "pitch" locked; it starts level (pitch 0) in the
    front wheel's own static equilibrium, the swingarm at full extension and the rider at its
    stance (their qpos 0). Locked "pitch", "rear" and "rider" with the rear tire off
    is the rolling front end's rig (``tests/test_bike_locked.py``). ``seated``: the rider sits on
    the saddle, the body's centre of mass at ``rider.seated_com_mm`` held rigid on the frame (its
    two degrees of freedom locked at the seated position: a seated body's vertical resonance, 4-6
    Hz, lies above a bike's sprung modes; ``mtbmj.identify.bounce_bike``).

    ``pedal``: (cadence_rpm, power_W): the rider pedals instead of holding a speed. The crank
    torque (``controllers.drive.pedal_forces``: each leg on its downstroke, mean ``power_W`` at
    ``cadence_rpm``) pulls the chain (the bike needs ``drive.chainring_teeth`` and ``cog_teeth``),
    and the driving foot pushes its pedal, its reaction on the rider (standing: the body on its legs
    and arms moves; seated: held, the pair cancels). The crank turns with the distance rolled
    through the gear; the speed is what the forces make of it, from ``speed_m_per_s`` at the start
    (default: the gear's speed at ``cadence_rpm``).

    ``rider``: "passive" (the rigid body on spring-damper legs and arms) or "active" (the
    articulated rider with its muscles and riding controller, ``mtbmj.bike.rider_control``; seated,
    on the saddle's contact instead of held). ``legs_swing``: the pedalling active rider's two legs'
    swing on the trunk (``mtbmj.bike.pedal_leg.PedalLeg.swung``; off by default: docs/bike.md).
    ``speed_profile`` (x_m, v_m_per_s): the drive's set speed along the terrain at the front axle
    (``mtbmj.bike.schedule``; the passive or active rider holding a speed, not a pedalling or coasting one),
    ``speed_m_per_s`` the start's."""
    from mtbmj.bike.reference import Reference, static_equilibrium

    # "no" is true to Python: seated="no" ran seated
    rear_tire, seated, legs_swing = (switch(k, v) for k, v in (("rear_tire", rear_tire), ("seated", seated),
                                                               ("legs_swing", legs_swing)))
    if rider not in RIDERS:
        raise ConfigError(f"rider: must be one of {', '.join(RIDERS)}, got {rider!r}")
    if rider == "active":
        from mtbmj.bike import rider_control

        if lock or not rear_tire:
            raise ConfigError("rider: the active rider rides the whole bike (no lock, no lifted rear)")
        with warnings.catch_warnings():  # the passive rider's note on rider.height_m: this rider takes it
            warnings.filterwarnings("ignore", message=r".*rider\.height_m = .* is read by the active rider only")
            p = prepare(bike, scenario, speed_m_per_s, drive, start_x, callback, lock, rear_tire, overrides, False,
                        pedal, speed_profile=speed_profile)
        kind = callback_kind(p.callback)
        rear = p.rear_tire
        p = rider_control.activate(
            p, lambda b: make_callback(kind, b, p.fork_law, p.shock_law, p.front_tire, rear, p.drive, p.speed,
                                       p.traction, p.callback.refresh),
            INTEGRATORS[p.fork_setup.integrator], LOCK_ARMATURE, seated)
        if legs_swing:  # at the stance the run starts in (the ODE reference shares the leg)
            if p.callback.leg is None:
                raise ConfigError("legs_swing: the legs swing only for a pedalling active rider (pedal=...)")
            pose = p.articulated[1]
            p.callback.leg.swung(pose.hip, math.atan2(pose.shoulder[1] - pose.hip[1], pose.shoulder[0] - pose.hip[0]))
        return p

    if legs_swing:
        raise ConfigError("legs_swing: the legs swing only for a pedalling active rider (rider='active', pedal=...)")
    if speed_profile is not None and (pedal is not None or drive != "rider"):
        raise ConfigError("speed_profile: the rider's drive holds a set speed along the terrain; a pedalling or "
                          "coasting run has none")
    if speed_profile is not None:  # checked before any work (the CLI's --speed-profile is, with the file named)
        from mtbmj.bike.schedule import SpeedProfile

        speed_profile = SpeedProfile.checked(speed_profile)
    if pedal is not None:
        if drive != "rider":
            raise ConfigError(f"pedal: a pedalling rider is the drive; drive {drive!r} cannot be given with it")
        cadence_rpm, power = _check_pedal(pedal)
        drive = "pedal"
    _check(speed_m_per_s, None, pedal, warn=False)  # warned by run_bike (a replay, a still rig: not)
    if start_x is not None:  # nan was "does not start on level ground"; within --start-m's range, as the command's
        start_x = given("--start-m", "start_x", start_x, " (the front axle's start)")
    if callback not in CALLBACKS:
        raise ConfigError(f"callback: must be one of {', '.join(CALLBACKS)}, got {callback!r}")
    if drive not in ("rider", "coast") and pedal is None:  # a pedalling rider comes with pedal=(rpm, W)
        raise ConfigError(f"drive: {drive!r} is not one of rider, coast (a pedalling rider: pedal=(cadence_rpm, "
                          f"power_W))")
    lock = _check_lock(lock, rear_tire)
    if isinstance(bike, spec_mod.BikeSpec) and overrides:
        raise ConfigError("overrides: give them with a bike name or file, not a ready-made BikeSpec")
    resolved = None if isinstance(bike, spec_mod.BikeSpec) else spec_mod.resolve(bike, overrides)  # read once
    spec = bike if resolved is None else resolved.spec
    if resolved is not None and "height_m" in resolved.table.get("rider", {}):  # said, not refused (a file for both)
        from mtbmj.config import warn

        filed = "height_m" in resolved.read.get("rider", {}) and resolved.source not in spec_mod.preset_names()
        warn([HEIGHT_UNUSED.format(f"{resolved.source}: " if filed else "", spec.rider.height)])
    if seated:
        if spec.rider.seated_com is None:
            raise ConfigError(f"rider.seated_com_mm: {spec.name} gives no seated rider (the rider's centre of mass "
                              f"seated on the saddle, e.g. rider.seated_com_mm = [-90, 920], or the chart's saddle: "
                              f"geometry.seat_tube_angle_deg and saddle_height_mm)")
        if not rear_tire:
            raise ConfigError("seated: a seated rider rides on both wheels (not with the rear tire off)")
        spec = dataclasses.replace(spec, rider=dataclasses.replace(spec.rider, com=spec.rider.seated_com))
        lock = tuple(dict.fromkeys(tuple(lock) + ("rider",)))
    if pedal is not None:
        if spec.drive.get("chain_m") is None:
            raise ConfigError(f"pedal: {spec.name} has no chain to pedal through (a hub drive: drive.chain = false, or "
                              f"no sprockets): give drive.chainring_teeth and drive.cog_teeth (e.g. --set "
                              f"drive.chainring_teeth=32 --set drive.cog_teeth=42)")
        if not rear_tire:
            raise ConfigError("pedal: a pedalling rider drives the rear wheel (not with the rear tire off)")
    ter = terrain_mod.make(scenario)
    if ter.moving:
        raise ConfigError("scenario: the drum rig holds a single wheel; a bike rolls on fixed terrain")
    if speed_profile is not None:  # held flat past its ends, one off the terrain would set one speed, silently
        speed_profile.along(ter.start_x, ter.start_x + ter.length)
    fork_setup, shock_setup = setups(spec)
    radius = fork_setup.tire_radius
    spec_mod.check_geometry(spec, radius)
    if pedal is not None and speed_m_per_s is None:
        speed_m_per_s = gear_speed(spec, cadence_rpm, radius)
    rim = fork_setup.tire.rim
    steps = stepping(spec, fork_setup, shock_setup, (rim, rim if rear_tire else None))
    timestep = steps.coarse
    g = fork_setup.gravity
    b = build_bike(spec, radius, ter, timestep, INTEGRATORS[fork_setup.integrator], g, start_x, fork_setup.fork_length,
                   visual=False)
    values = fork_setup.tire.values(1)  # rolling is sustained contact: the in-contact values of a switching law
    rate, damping = values.rate, values.damping
    front = RadialTire(ter, radius, rate, damping, rim=fork_setup.tire.rim)
    rear = RadialTire(ter, radius, rate, damping, rim=fork_setup.tire.rim)
    # the callback's rear tire: none (no rate, no damping, no rim) when the rear wheel is lifted;
    # the reference below keeps the real one for the two-wheel equilibrium the locks start from
    rear_cb = rear if rear_tire else RadialTire(ter, radius, 0.0, 0.0, rim=None)
    total = spec.total_mass
    kv = 2.0 * total * 2.0 * math.pi * DRIVE_HZ
    limits = {k: spec.drive[v] for k, v in (("push", "push_N"), ("power", "power_W"), ("brake", "brake_N"))
              if v in spec.drive}
    drv = Drive(drive, kv, **limits) if pedal is None else \
        Drive("pedal", kv, power=power, cadence=cadence_rpm * 2.0 * math.pi / 60.0)
    traction = spec.drive.get("traction", 1.0)
    refresh = min(REFRESH_S, REFRESH_DISTANCE_M / float(speed_m_per_s))
    cb = make_callback(callback, b, fork_setup.fork, shock_setup.fork, front, rear_cb, drv, speed_m_per_s, traction,
                       refresh)
    data = mujoco.MjData(b.model)
    p = Prepared(b, spec, fork_setup, shock_setup, fork_setup.fork, shock_setup.fork, ter, front, rear, drv, traction,
                 float(speed_m_per_s), g, timestep, cb, data, None, None, None, steps, lock, bool(rear_tire))
    ref = Reference(p)
    _check_start(p, ref)
    names = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_z", "rider_pitch")
    if rear_tire:
        q = static_equilibrium(ref, acceptable=lambda q: _is_equilibrium(ref, q),  # refuses when none is one
                               held=(5, 6) if seated else ())
        q = dict(zip(names, q))
    else:  # on the front wheel alone: the rear at full extension, the rider at its stance (both held)
        q = dict.fromkeys(names, 0.0)
        q.update(_front_alone(p))
    for name, value in q.items():
        data.qpos[b.qpos_index(name)] = value
    for key in lock:
        for name in LOCKS[key]:
            b.model.dof_armature[b.dof_index(name)] = LOCK_ARMATURE
    data.qvel[b.dof_index("bike_x")] = speed_m_per_s
    data.qvel[b.dof_index("front_spin")] = speed_m_per_s / radius
    data.qvel[b.dof_index("rear_spin")] = speed_m_per_s / radius
    with installed(cb):
        mujoco.mj_forward(b.model, data)
    p.initial_qpos, p.initial_qvel, p.initial_act = data.qpos.copy(), data.qvel.copy(), data.act.copy()
    p.watch = crash.Watch(b.model, ter, b.qpos_index("pitch"), pitch_locked="pitch" in lock)
    p.speed_profile = speed_profile
    return p


def _check_pedal(pedal) -> tuple[float, float]:
    """(cadence_rpm, power_W) of a pedalling rider, each within what riders do
    (``limits.PEDAL_RPM``, ``PEDAL_POWER_W``: ``--pedal``'s and ``--power``'s), else one ConfigError line."""
    from mtbmj.limits import PEDAL_POWER_W, PEDAL_RPM

    try:
        if isinstance(pedal, (str, bytes)):  # "90" unpacked as cadence "9", power "0"
            raise TypeError
        cadence, power = pedal
    except (TypeError, ValueError):
        raise ConfigError(f"pedal: must be (cadence_rpm, power_W), got {pedal!r}") from None
    for name, value, (low, high), unit in (("cadence", cadence, PEDAL_RPM, "rpm"),
                                            ("power", power, PEDAL_POWER_W, "W")):
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) \
                or not low <= value <= high or (name == "power" and value <= 0.0):
            raise ConfigError(f"pedal: {name} {value!r} {unit} is outside what a rider turns ({low:g}-{high:g} {unit})")
    return float(cadence), float(power)


def _check_lock(lock, rear_tire) -> tuple[str, ...]:
    if isinstance(lock, str):
        if not lock.strip():  # '' locked nothing where ``mtbmj bike --lock ''`` is refused (cli.bike.lock_option)
            raise ConfigError(f"lock {lock!r}: names no part; give {', '.join(LOCKS)} (one, or a list of them), or "
                              f"leave lock out to lock none")
        lock = (lock,)
    try:
        lock = tuple(dict.fromkeys(lock))
    except TypeError:
        raise ConfigError(f"lock: must be a list of {', '.join(LOCKS)}, got {lock!r}") from None
    bad = [k for k in lock if k not in LOCKS]
    if bad:
        raise ConfigError(f"lock: {bad[0]!r} is not one of {', '.join(LOCKS)}")
    if not rear_tire and "pitch" not in lock:
        raise ConfigError("rear_tire: the bike cannot stand on its front wheel alone unless its pitch is locked "
                          "(lock 'pitch')")
    return lock


def _front_alone(p: Prepared) -> dict:
    """(bike_z, pitch, fork) of the bike level on its front wheel alone, on flat ground, at rest:
    the front tire carries the whole weight W (its deflection W / k), and the fork's spring the part
    above the fork along the steering axis, (W - (m_lower + m_wheel) g) sin(head angle), as the
    front-end rig's ``static_sag``."""
    from mtbmj.rolling.frontend import spring_compression

    spec, g = p.spec, p.gravity
    unsprung = spec.fork_lower_mass + spec.front_wheel_mass
    a = spec.head_angle
    xf = spring_compression(p.fork_setup, (spec.total_mass - unsprung) * g * math.sin(a))
    deflection = spec.total_mass * g / p.front_tire.rate
    # the front axle (frame level) is at z0 + bike_z + fz + xf sin(a); at qpos = 0 its tread touches
    return {"bike_z": -deflection - xf * math.sin(a), "pitch": 0.0, "fork": xf}


def make_callback(kind: str, *args):
    """The bike's callback of ``kind`` ("python", "compiled" or "auto"), ``args`` as
    ``BikeCallback``'s; "auto": the compiled one when possible, else the Python one with a warning
    (``mtbmj.runpath.callbacks.choose``)."""
    def load():
        from mtbmj.bike import callback_compiled  # numba is imported on the first compiled run only

        return callback_compiled

    return callbacks.choose(kind, lambda: BikeCallback(*args), load,
                            lambda module: module.CompiledBikeCallback(*args), "bike")


def callback_kind(callback) -> str:
    """"python" for ``BikeCallback``, "compiled" for its compiled twin."""
    return "python" if isinstance(callback, BikeCallback) else "compiled"


def _python_twin(cb) -> BikeCallback:
    """A fresh ``BikeCallback`` with the settings of the compiled ``cb`` (a rerun on the Python path)."""
    front, rear = cb.tires
    return BikeCallback(cb.bike, cb.fork, cb.shock, front, rear, cb.drive, cb.speed, cb.traction, cb.refresh)


def _check_start(p: Prepared, ref) -> None:
    """Both wheels must start on level, straight ground (the static equilibrium is the bike's on
    the flat): each tire's whole reach on one horizontal stretch of the profile."""
    b = p.bike
    where = {"front": b.x0 + b.spec.front_axle[0], "rear": b.x0 + b.spec.rear_axle[0]}
    for name, x in where.items():
        seg = ref.straight.segment(x)
        if seg is None or seg[1] != seg[3]:  # a CSV has no at_m: its first rows must be level
            fix = (f"{p.terrain.params['csv']} is not level within {ref.straight.reach * 1e3:.0f} mm of it: begin the "
                   f"profile with a level stretch" if "csv" in p.terrain.params else "put the feature farther ahead (at_m)")
            raise ConfigError(f"start: the {name} wheel (at x = {x:.3f} m) does not start on level ground clear of the "
                              f"terrain's features; {fix} or start elsewhere (--start-m)")


def _is_equilibrium(ref, q) -> bool:
    """Both wheels on the ground and the frame within 30 deg of level: a bike's equilibrium."""
    from mtbmj.bike.reference import NQ

    y = np.concatenate((q, np.zeros(NQ), np.zeros(ref.nf + ref.ns)))
    y[NQ] = ref.speed
    _, out = ref.forces(0.0, y)
    return bool(out["front"][1] > 0.0 and out["rear"][1] > 0.0 and abs(q[2]) < math.radians(30.0))


def simulate(p: Prepared, duration: float, progress=None):
    """(states (n+1, nstate), sensordata (n, nsensor)) of ``duration`` s from the prepared state:
    row i of the sensors describes row i of the states (``mtbmj.runpath.loop``).

    If the compiled callback met more contact patches than it holds (``overflowed``), the run is
    redone on the Python path (``p.callback`` becomes that ``BikeCallback``), with a warning."""
    def to_python():
        p.callback = _python_twin(p.callback)  # its first evaluation searches the patches afresh
        p.refined_steps = p.stepped = 0
        if p.watch is not None:
            p.watch.reset()

    return callbacks.rerun_on_python(p.bike.model, p.data, lambda: _simulate(p, duration, progress),
                                     lambda: getattr(p.callback, "overflowed", False), to_python, "bike")


def _simulate(p: Prepared, duration: float, progress=None):
    """Step ``duration`` s on the shared run path (``mtbmj.runpath.loop.chunked``) with the bike's
    refinement plan: where a chunk came within reach of an end stop or a rim, its steps from the
    sample before the first such to one past the last are stepped again at the fine step."""
    model = p.bike.model
    steps = int(round(duration / p.timestep))
    b = p.bike
    sensors = [int(model.sensor_adr[model.sensor(n).id]) for n in ("front_deflection", "rear_deflection")]
    plan = p.stepping.refinement(1 + b.qpos_index("fork"), 1 + b.qpos_index("swingarm"), sensors,
                                 lambda: p.callback.reset())  # the patches of the chunk's end: searched afresh
    counts = loop.Counts()
    chunk, stop = CHUNK, p.watch
    if p.speed_profile is not None:  # the set speed updated between chunks (mtbmj.bike.schedule)
        from mtbmj.bike import schedule

        chunk = max(1, int(round(schedule.UPDATE_S / p.timestep)))
        stop = schedule.steering(p.speed_profile, p.callback, p.watch, 1 + b.qpos_index("bike_x"),
                                 b.x0 + b.spec.front_axle[0] - float(p.initial_qpos[b.qpos_index("bike_x")]))
    try:
        with installed(p.callback):
            return loop.chunked(model, p.data, steps, p.timestep, "bike", plan if plan.substeps > 1 else None,
                                progress, counts, chunk=chunk, report_every=CHUNK, stop=stop)
    finally:
        p.stepped += counts.stepped
        p.refined_steps += counts.refined


@dataclass
class BikeResult(RunOutput):
    """A bike run: ``raw`` at the engine step (also ``signals``), ``summary``."""

    name: str
    scenario: str
    signals: dict
    raw: dict
    summary: dict
    wall_time_s: float
    prepared: Prepared
    info: dict = field(default_factory=dict)
    motion: tuple = ()  # (times, qpos) at VIDEO_SAMPLE_HZ, for ``video``
    COLUMNS = COLUMNS
    # difference(): travel and stroke in mm, pitch in deg, tyre loads in N
    COMPARED = ("front_travel_mm", "rear_travel_mm", "stroke_mm", "pitch_deg", "front_tire_N", "rear_tire_N")

    def csv_bytes(self, raw: bool = False) -> bytes:
        header = (f"mtbmj bike {self.name} over {self.scenario}, engine rate\n"
                  "travel and stroke compression positive from full extension; pitch nose up positive; tire loads the "
                  "total radial force of each tire; tire deflection at the deepest patch (-10 mm: no ground within 10 "
                  "mm); rider acceleration vertical, gravity excluded, up positive; speed of the centre of mass")
        return output.csv_bytes({k: self.raw[k] for k in COLUMNS}, header)

    def csv_chunks(self, raw: bool = False):
        yield self.csv_bytes(raw)

    def manifest(self) -> dict:
        from mtbmj.result import versions

        return {"name": self.name, "scenario": self.scenario, "engine": "mujoco", "bike_source": self.prepared.spec.source,
                "bike_overrides": self.prepared.spec.overrides,
                "fork_config": self.prepared.fork_setup.config.digest(),
                "shock_config": self.prepared.shock_setup.config.digest(), "versions": versions(),
                "wall_time_s": self.wall_time_s, "engine_info": self.info}

    def files(self, stream: bool = False, figure: bool = True, video: bool = False, extra: dict | None = None) -> dict:
        files = {"timeseries.csv": self.csv_bytes(), "summary.json": output.json_bytes(self.summary),
                 "manifest.json": output.json_bytes(self.manifest()),
                 "fork_config.toml": self.prepared.fork_setup.config.to_toml().encode(),
                 "shock_config.toml": self.prepared.shock_setup.config.to_toml().encode()}
        if figure:
            from mtbmj.bike.figure import png

            files["quicklook.png"] = png(self)
        files.update(extra or {})  # e.g. the files beside a real ride (mtbmj.ride.beside.files)
        if video:
            import tempfile
            from pathlib import Path

            with tempfile.TemporaryDirectory() as tmp:
                path = Path(tmp) / "bike.gif"
                self.video(path)
                files["bike.gif"] = path.read_bytes()
        return files

    def write(self, out_dir, figure: bool = True, video: bool = False, extra: dict | None = None):
        """Write the output folder whole (``figure``: quicklook.png; ``video``: bike.gif; ``extra``:
        more files by name, e.g. ``mtbmj.ride.beside.files(result, "example")``, the run beside a
        real ride)."""
        return output.write_atomically(out_dir, self.files(figure=figure, video=video, extra=extra))

    def video(self, path, fps: float = 30.0, width: int = 640, height: int = 480) -> dict:
        """Write a video (.gif, or .mp4 with the [video] extra) of the run to ``path``, side on, the
        camera following the bike (``mtbmj.rolling.render``, headless EGL or OSMesa)."""
        from mtbmj.rolling import render

        return render.render(self.trajectory(fps), path, fps, width, height)

    def trajectory(self, fps: float = 30.0, duration: float | None = None, label: str | None = None):
        """The run as a ``mtbmj.rolling.render.Trajectory`` (its pose kept at 240 Hz): what
        ``video`` and ``mtbmj render`` of a bike folder draw."""
        from mtbmj.rolling import render

        times, qpos = self.motion
        return render.rolling_frames(self.prepared.visual_model(), times, qpos, fps, duration,
                                     label or f"bike {self.name} over {self.scenario}")

    def headline(self) -> str:
        s = self.summary
        f, r = s["front"], s["rear"]
        strikes = s["rim_strikes"]

        def ends(rep):
            parts = [k.replace("_", " ") for k in ("bumper", "hard_stop") if rep[k]["count"]]
            return f" ({', '.join(parts)})" if parts else ""

        held = self.info.get("locked")
        seated = bool(self.info.get("seated"))
        if seated and held is not None:  # the seated rider's hold is the seat's, said as "seated"
            held = [k for k in held if k != "rider"]
        if held is not None or seated or not self.info.get("rear_tire", True):  # the active rider sits unheld
            parts = (["seated"] if seated else []) + ([f"held: {', '.join(held)}"] if held else [])
            parts += [] if self.info.get("rear_tire", True) else ["rear tire off"]
            held = f" ({'; '.join(parts)})"
        else:
            held = ""
        m = s["mass_kg"]
        crashed = f"{s['crash']['line']}{_passive(s)}: " if s.get("crash") else ""
        prof = s.get("speed_profile_m_per_s")
        at = (f"at {s['speed_m_per_s']:g} m/s set" if prof is None else
              f"along a speed profile ({prof[0]:.3g}-{prof[1]:.3g} m/s set)")
        return (f"{crashed}bike {self.name}{held} (rider {m['rider']:.1f} kg, bike {m['bike']:.1f} kg) over {self.scenario} "
                f"{at} ({s['min_speed_m_per_s']:.2f}-{s['max_speed_m_per_s']:.2f} m/s): "
                f"front travel peak "
                f"{s['max_front_travel_mm']:.1f} of {f['travel_mm']:g} mm{ends(f)}, rear {s['max_rear_travel_mm']:.1f} of "
                f"{s['rear_wheel_travel_mm']:.4g} mm (shock {s['max_stroke_mm']:.1f} of {r['travel_mm']:g} mm){ends(r)}, "
                f"pitch {s['pitch_deg']['min']:.1f} to {s['pitch_deg']['max']:.1f} deg, rim strikes "
                f"{strikes['front']}/{strikes['rear']}, {self._comfort()}{self._rider()}")

    def _rider(self) -> str:
        """The active rider's joint torques against their limits (nothing for the passive rider)."""
        r = self.summary.get("rider") or {}
        if r.get("kind") != "active":
            return ""
        worst = max(r["joints"], key=lambda k: r["joints"][k]["peak_of_limit"])
        # every joint held at its limit, longest first (the first named as before)
        held = sorted((k for k in r["joints"] if r["joints"][k].get("at_limit_s", 0.0) > 0.0),
                      key=lambda k: -r["joints"][k]["at_limit_s"])
        rest = ", ".join(f"the {k}'s {r['joints'][k]['at_limit_s']:.2f} s" for k in held[1:])
        clamp = (f"; held at its limit longest: the {held[0]}'s, {r['joints'][held[0]]['at_limit_s']:.2f} s"
                 + (f" (then {rest})" if rest else "") if held else "; none held at its limit")
        e = self.summary.get("energy")
        work = (f"; muscle work {e['muscle_work_J']:.1f} J ({e['muscle_positive_J']:.1f} positive, "
                f"{e['muscle_negative_J']:.1f} negative), energy balance error {e['error_pct']:.3f} % of "
                f"{e['work_done_J']:.0f} J of work done") if e else ""
        leg = r.get("pedal_leg")
        if leg:  # pedalling: the driving leg (mtbmj.bike.pedal_leg), its side's torques against one side's strength
            top = max(leg["side_peak_of_limit"], key=leg["side_peak_of_limit"].get)
            reach = f", its pedal out of its reach {leg['out_of_reach_s']:.2f} s" if leg["out_of_reach_s"] > 0 else ""
            cut = {k: v for k, v in leg["cut_of_stroke_time"].items() if v > 0.0}
            by = ", ".join(f"the {k}'s {100 * v:.1f} %" for k, v in sorted(cut.items(), key=lambda kv: -kv[1]))
            leg = (f"; the driving leg {'within' if leg['within_limits'] else 'PAST'} one side's strength (largest "
                   f"{100 * leg['side_peak_of_limit'][top]:.0f} % of the {top}'s), peak power "
                   f"{leg['peak_power_W']:.0f} W{reach}, {100 * leg['delivered_of_asked']:.1f} % of the stroke's asked "
                   f"crank work delivered" + (f" (cut by {by} of the stroke's time)" if cut else " (never cut)"))
        return (f"; active rider: joint torques {'within' if r['within_limits'] else 'PAST'} their limits (largest "
                f"{100 * r['joints'][worst]['peak_of_limit']:.0f} % of the {worst}'s{clamp}), peak power "
                f"{r['peak_power_W']:.0f} of {r['power_limit_W']:.0f} W{leg or ''}{work}")

    def _comfort(self) -> str:
        """Comfort and grip over the feature's window (the whole run's where it has none)."""
        s = self.summary
        f = s.get("feature") or {}
        if f.get("window_s"):
            rms, var = f["rider_acceleration_rms_m_per_s2"], f["tire_load_variation"]
            where = f" over the feature ({f['window_s'][0]:.2f}-{f['window_s'][1]:.2f} s" + (
                ")" if f["closed"] else ", the run ended before it settled)")
        else:
            rms = s["rider_acceleration_rms_m_per_s2"]
            var = {end: s["tire_load"][end]["variation"] for end in ("front", "rear")}
            where = " over the run"
        return (f"rider {rms:.2f} m/s2 RMS, tire-load variation {100 * (var['front'] or 0):.0f} % front / "
                f"{100 * (var['rear'] or 0):.0f} % rear{where}")

    def quicklook(self):
        """The quick-look figure (``mtbmj.bike.figure``): terrain, travel, pitch, tyre loads, the
        rider's acceleration and the speed against time."""
        from mtbmj.bike.figure import figure

        return figure(self)

    def plot(self, axes=None, label: str | None = None, **line_kwargs):
        """Front travel, rear wheel travel and pitch against time on three stacked axes (given, or
        a new figure's): several runs drawn on the same axes compare them. Returns the figure."""
        return self.plot_stacked((("front_travel_mm", "front travel [mm]"), ("rear_travel_mm", "rear wheel travel [mm]"),
                                  ("pitch_deg", "pitch, nose up [deg]")), self.raw, axes,
                                 label or f"{self.name} over {self.scenario}", {"loc": "best", "fontsize": 8},
                                 **line_kwargs)


def run_bike(bike="sst", scenario="drop", speed_m_per_s: float | None = 4.0, duration: float | None = None,
             drive: str = "rider", start_x: float | None = None,
             progress: Callable[[float], None] | None = None, callback: str = "auto", lock=(),
             rear_tire: bool = True, overrides=None, seated: bool = False, pedal=None,
             rider: str = "passive", legs_swing: bool = False, speed_profile=None) -> BikeResult:
    """Roll the bike ``bike`` (a preset name, a TOML path, a ``mtbmj.bike.spec.ResolvedBike``, which
    ``overrides`` derive again without reading its file, or a ``BikeSpec``) over ``scenario`` (a
    terrain spec of ``mtbmj roll``) at ``speed_m_per_s``; ``duration`` defaults to the time for both
    wheels to cross the feature and settle; ``drive`` "rider" (a speed controller within a rider's
    limits) or "coast"; ``start_x`` the front axle's start (default the terrain's); ``callback``
    "auto" (compiled where numba is installed, else Python with a warning), "compiled" or "python";
    ``lock`` degrees of freedom held at their static values ("rear": the shock locked out at its
    sag, "pitch", "rider"), ``rear_tire=False`` the rear wheel lifted (needs "pitch" locked), see
    ``prepare``; ``overrides`` change bike keys (``{"rider.mass_kg": 78}``) and the fork's or the
    shock's configuration keys (``{"fork.set": {"fork.spring.air_pressure_psi": 60}}``), see
    ``mtbmj.bike.spec.overridden``; ``seated`` the rider seated, held rigid on the frame (``prepare``);
    ``pedal`` (cadence_rpm, power_W) the rider pedalling through the chain instead of holding a speed
    (``prepare``; ``speed_m_per_s`` None: the gear's speed at the cadence); ``rider`` "passive" (the
    rigid rider on spring-damper limbs) or "active" (the articulated rider with muscles and a
    riding controller, ``mtbmj.bike.rider_control``; the summary's ``rider`` then reports each
    joint's largest torque against its limit); ``legs_swing`` and ``speed_profile`` (``prepare``)."""
    _check(speed_m_per_s, duration, pedal)  # the plausible speed warned here, at the caller's line, not in prepare
    p = guard.prepared("bike", lambda: prepare(bike, scenario, speed_m_per_s, drive, start_x, callback, lock, rear_tire,
                                               overrides, seated, pedal, rider, legs_swing, speed_profile),
                       model_of=lambda p: p.bike.model)
    if duration is None:  # the terrain crossed: a crawl refused before the run
        duration = default_duration(p)
        crossing(p.speed, duration, p.terrain.name)
    check_run(duration, p.timestep, 1.0 / p.timestep)
    start = time.perf_counter()
    states, sensors = simulate(p, duration, progress)
    wall = time.perf_counter() - start
    raw = signals(p, states, sensors)
    summary_ = summary(p, raw)
    plan = p.stepping
    info = {"steps": int(sensors.shape[0]), "timestep_s": p.timestep, "timestep_why": plan.coarse_why,
            "fine_timestep_s": plan.fine, "fine_timestep_why": plan.fine_why,
            "refined_fraction": p.refined_steps / p.stepped if p.stepped else 0.0,
            "integrator": p.fork_setup.integrator,
            "callback": callback_kind(getattr(p.callback, "inner", p.callback)), "callback_calls": p.callback.calls, "geometry_refreshes": p.callback.refreshes,
            "real_time_factor": duration / wall if wall > 0 else None}
    summary_["rider"] = p.callback.report() if p.articulated is not None else {"kind": "passive"}
    if p.articulated is not None:  # the energy balance with the muscles' work (evaluates the run's states again)
        from mtbmj.bike.energy import balance

        summary_["energy"] = balance(p, states)
    if p.articulated is not None:
        info["rider"] = "active"
    if seated:
        info["seated"] = True
    if pedal is not None:
        if summary_["min_speed_m_per_s"] < STALL_M_PER_S:
            from mtbmj.config import warn

            warn([f"pedal: the rider stalled (the speed fell to {summary_['min_speed_m_per_s']:.2f} m/s): "
                  f"{pedal[1]:g} W does not carry the bike up this terrain in this gear"])
    if p.lock or not p.rear_tire_on:
        info["locked"] = list(p.lock)
        info["rear_tire"] = p.rear_tire_on
    past = summary_["max_rear_travel_mm"] - summary_["rear_wheel_travel_mm"]
    if past > 0.05:
        from mtbmj.config import warn

        warn([f"bike: the rear wheel reached {summary_['max_rear_travel_mm']:.1f} mm, {past:.1f} mm past the end of "
              f"the leverage table ({summary_['rear_wheel_travel_mm']:g} mm): its last ratio was carried on there"])
    name = p.spec.name
    result = BikeResult(name, str(scenario), raw, raw, summary_, wall, p, info)
    every = max(1, int(round(1.0 / (VIDEO_SAMPLE_HZ * p.timestep))))
    nq = p.bike.model.nq
    rows = states[:-1:every]  # the rows of the output's samples (the state after the last step is not one)
    result.motion = (rows[:, 0].copy(), rows[:, 1:1 + nq].copy())
    return result


__all__ = ["run_bike", "prepare", "LOCKS", "LOCK_ARMATURE", "simulate", "BikeResult", "BikeCallback", "Prepared", "COLUMNS", "setups",
           "CALLBACKS", "make_callback", "callback_kind"]

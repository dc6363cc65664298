"""The front end rolling over terrain: the drop study's fork and tire laws on a planar front end.

``run_roll(scenario, speed_m_per_s, config="S12", head_angle_deg=65, duration=None)`` builds
``mjcf/rolling_scene.xml`` for the configuration (masses, tire radius, fork length, solver) and a
head angle, puts the wheel at rest (static sag) at the start of the terrain, and rolls it at the
set speed: a PD servo on the chassis' horizontal joint tracks x0 + v t. The fork law (spring,
damper, friction, as ``compose.setup``) and the radial tire (``mtbmj.rolling.tire``, the
configuration's tire values) are applied by one control callback through motors, so MuJoCo's
``actuatorfrc`` sensors record the exact forces of every step. ``RollCallback`` (Python) is that
callback's specification; by default runs use its compiled twin
(``mtbmj.rolling.callback_compiled``: the fork law, the tire and its patch search in numba,
same results), and fall back to ``RollCallback`` with a warning when numba is missing
(``callback="python"`` forces it).

Conventions: fork_mm compression positive, zero at unloaded full extension; tire_mm radial
deflection (compression positive, negative = clearance when airborne); body_z_mm and axle_z_mm
heights relative to the start (up positive); axle forces on the axle from the ground, x forward,
z up; SI inside, units in every external name.

The tire uses the in-contact values of a switching tire law (rolling is sustained contact; the
impact values of the coefficient-of-restitution method belong to the drop's first impact).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, Mapping

import mujoco
import numpy as np

from mtbmj import mjcf
from mtbmj.controllers import installed
from mtbmj.controllers.drive import MODES as DRIVE_MODES, Drive
from mtbmj.controllers.tire import TIRE_DAMPING_DEPTH_M
from mtbmj import compose, limits, output
from mtbmj.drop import measure
from mtbmj.readout.endtravel import end_of_travel
from mtbmj.rolling import terrain as terrain_mod
from mtbmj.rolling.terrain import DEFAULT_HEAD_ANGLE_DEG
from mtbmj.config import Config
from mtbmj.errors import ConfigError
from mtbmj.limits import check_duration, check_run, crossing, plausible, speed as ridden_speed
from mtbmj.result import RunOutput
from mtbmj.rolling.callback import RollCallback
from mtbmj.rolling.tire import REFRESH_DISTANCE_M, REFRESH_S, RadialTire
from mtbmj.runpath import callbacks, guard, loop, steprule

DRIVE_HZ = 10.0  # bandwidth of the speed servo (critically damped)
CHUNK = 10000
CALLBACKS = ("auto", "compiled", "python")
SCENE = "rolling_scene.xml"
COLUMNS = (
    "time_s", "x_m", "speed_m_per_s", "terrain_mm", "body_z_mm", "axle_z_mm", "fork_mm", "tire_mm",
    "body_z_velocity_mm_per_s", "fork_velocity_mm_per_s", "fork_force_N", "axle_force_x_N", "axle_force_z_N",
    "tire_force_N", "drive_force_N",
)


@dataclass(frozen=True)
class FrontEnd:
    """A compiled front end and the numbers the callback needs (all SI)."""

    model: mujoco.MjModel
    head_angle: float  # rad, from the horizontal
    fork_length: float
    chassis_x0: float  # world position of the chassis (crown) at qpos = 0
    chassis_z0: float
    drum_dof: int | None = None

    @property
    def axis(self) -> tuple[float, float]:
        """(cos, sin) of the head angle: the fork compresses along (-cos, +sin) in x-z."""
        return math.cos(self.head_angle), math.sin(self.head_angle)

    def axle_state(self, qpos, qvel, joints):
        """Axle position (x, z) and velocity (vx, vz) in the world from the state, for the joint
        addresses ``joints`` = (chassis x, chassis z, fork) qpos indices + the same dof indices."""
        xq, zq, fq, xv, zv, fv = joints
        c, s = self.axis
        qf = qpos[fq]
        vf = qvel[fv]
        cx = self.chassis_x0 + qpos[xq] + (self.fork_length - qf) * c
        cz = self.chassis_z0 + qpos[zq] - (self.fork_length - qf) * s
        return cx, cz, qvel[xv] - vf * c, qvel[zv] + vf * s

    def axle(self, qx, qz, qf):
        c, s = self.axis
        return self.chassis_x0 + qx + (self.fork_length - qf) * c, self.chassis_z0 + qz - (self.fork_length - qf) * s


def _check_inputs(speed, head_angle_deg, duration, warn=True):
    ridden_speed(speed, warn=warn)
    if not isinstance(head_angle_deg, (int, float)) or not math.isfinite(head_angle_deg) or not 45.0 < head_angle_deg <= 90.0:
        rad = ""
        if isinstance(head_angle_deg, (int, float)) and math.pi / 4 < head_angle_deg <= math.pi / 2:  # 1.13: radians
            rad = f" (radians? {head_angle_deg:g} rad is {math.degrees(head_angle_deg):.1f} deg)"
        raise ConfigError(f"head angle: must be in (45, 90] degrees from the horizontal, got {head_angle_deg!r}{rad}")
    if warn:  # the command line's line (--head-angle 50: outside 55-80 deg), said to a caller from Python too
        plausible("--head-angle", head_angle_deg)
    check_duration("duration", duration)


def _check_start(ter, radius: float) -> None:
    """A terrain CSV's ground must not reach into the tyre where the wheel starts at rest (its first distance, on
    the first row's level): a wall or a steep rise there would be started on top of or inside, never met."""
    if "csv" not in ter.params or isinstance(ter, terrain_mod.DrumTerrain):
        return
    x0 = ter.start_x
    x = np.union1d(np.linspace(x0, x0 + radius, 201), ter.x[(ter.x >= x0) & (ter.x <= x0 + radius)])
    into = ter.height(x) - (ter.z[0] + radius - np.sqrt(np.maximum(radius ** 2 - (x - x0) ** 2, 0.0)))
    if into.max() > START_INTO_M:
        raise ConfigError(f"start: {ter.params['csv']} rises {(ter.height(x).max() - ter.z[0]) * 1e3:.0f} mm within "
                          f"{radius * 1e3:.0f} mm of its first distance ({x0:g} m): the wheel at rest there would start "
                          f"{into.max() * 1e3:.0f} mm into the ground; begin the profile with a level stretch")


START_INTO_M = 0.005  # a terrain CSV's start: the ground this far into the tyre at rest is a feature, not a start


def build_front_end(setup: compose.Setup, terrain, head_angle_deg: float = DEFAULT_HEAD_ANGLE_DEG) -> FrontEnd:
    """Compile the rolling scene for ``setup`` and ``terrain`` at ``head_angle_deg``."""
    from mtbmj.drop.scene import INTEGRATORS

    spec = mujoco.MjSpec.from_file(str(mjcf.path(SCENE)))
    spec.option.timestep = setup.timestep
    spec.option.integrator = INTEGRATORS[setup.integrator]
    spec.option.gravity = [0.0, 0.0, -setup.gravity]
    a = math.radians(head_angle_deg)
    c, s = math.cos(a), math.sin(a)
    L, r = setup.fork_length, setup.tire_radius
    h0 = terrain.start_height()
    x0 = terrain.start_x - L * c
    z0 = h0 + r + L * s  # at qpos = 0 the tread just touches the ground under the start
    chassis = spec.body("chassis")
    chassis.pos = [x0, 0.0, z0]
    chassis.mass = setup.body_mass
    lower = spec.body("fork_lower")
    lower.pos = [L * c, 0.0, -L * s]
    # The unsprung mass m_w is split 0.5 : 1.8 between lower legs and wheel as in the XML; only
    # the sum enters the planar dynamics (the wheel's hinge sits at the lower's origin).
    lower.mass = setup.wheel_mass * 0.5 / 2.3
    wheel = spec.body("wheel")
    wheel.mass = setup.wheel_mass * 1.8 / 2.3
    hoop = wheel.mass * r * r  # thin hoop: rim + tire carry the mass
    wheel.inertia = [hoop / 2, hoop, hoop / 2]
    spec.joint("fork").axis = [-c, 0.0, s]
    spec.geom("stanchion").fromto = [0.0, 0.0, 0.0, 0.6 * L * c, 0.0, -0.6 * L * s]
    spec.geom("lower_leg").fromto = [0.0, 0.0, 0.0, -0.6 * L * c, 0.0, 0.6 * L * s]
    spec.geom("tire").size = [r, 0.03, 0.0]
    spec.geom("rim").size = [max(r - 0.06, 0.05), 0.0125, 0.0]
    spec.geom("spoke_marker").size = [max(r - 0.07, 0.04), 0.005, 0.01]
    total = setup.body_mass + setup.wheel_mass
    kp = total * (2 * math.pi * DRIVE_HZ) ** 2
    kv = 2.0 * math.sqrt(kp * total)
    for act in spec.actuators:
        if act.name == "drive_position":
            act.gainprm[0] = kp
            act.biasprm[1] = -kp
        elif act.name == "drive_velocity":
            act.gainprm[0] = kv
            act.biasprm[2] = -kv
    _add_terrain_visual(spec, terrain)
    with installed(None):
        model = spec.compile()
    loop.skip_collision(model)
    drum_dof = int(model.joint("drum").dofadr[0]) if isinstance(terrain, terrain_mod.DrumTerrain) else None
    return FrontEnd(model, a, L, x0, z0, drum_dof)


def _add_terrain_visual(spec, terrain) -> None:
    world = spec.worldbody
    if isinstance(terrain, terrain_mod.DrumTerrain):
        R = terrain.radius
        body = world.add_body(name="drum", pos=[0.0, 0.0, -R])
        body.add_joint(name="drum", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 1.0, 0.0])
        body.mass = 100.0
        body.inertia = [10.0, 10.0, 10.0]
        body.add_geom(name="drum_shell", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[R, 0.15, 0.0],
                      euler=[math.pi / 2, 0.0, 0.0], contype=0, conaffinity=0, group=1, rgba=[0.5, 0.5, 0.55, 1])
        p = terrain.params
        a0 = math.radians(p["cleat_at_deg"])
        h, w = p["cleat_height_mm"] * 1e-3, p["cleat_width_mm"] * 1e-3
        if h > 0:
            body.add_geom(name="cleat", type=mujoco.mjtGeom.mjGEOM_BOX, size=[w / 2, 0.15, h / 2 + 0.002],
                          pos=[(R + h / 2) * math.sin(a0), 0.0, (R + h / 2) * math.cos(a0)], euler=[0.0, a0, 0.0],
                          contype=0, conaffinity=0, group=1, rgba=[0.8, 0.3, 0.1, 1])
        return
    x_lo, x_hi = float(terrain.x[0]), float(terrain.x[-1])
    n = int(min(20000, max(64, (x_hi - x_lo) / 0.005)))
    xs = np.linspace(x_lo, x_hi, n)
    zs = terrain.height(xs)
    lo, hi = float(zs.min()), float(zs.max())
    span = max(hi - lo, 1e-3)
    base = 0.05
    spec.add_hfield(name="terrain", size=[(x_hi - x_lo) / 2, 0.3, span, base], nrow=2, ncol=n,
                    userdata=list(np.tile((zs - lo) / span, 2)))
    world.add_geom(name="terrain", type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="terrain",
                   pos=[(x_lo + x_hi) / 2, 0.0, lo], contype=0, conaffinity=0, group=1, material="terrain")


def spring_compression(setup: compose.Setup, load_N: float) -> float:
    """The fork compression (m) at which ``setup``'s spring at rest carries ``load_N``: bisected
    from 50 mm past full extension (a top-out spring balances there) to 1.5 times the travel."""
    lo, hi = -0.05, setup.travel * 1.5
    spring = setup.fork.spring
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if spring.force(mid, 0.0) < load_N:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def static_sag(setup: compose.Setup, head_angle: float) -> tuple[float, float]:
    """(fork compression m, tire deflection m) at rest on flat ground: the spring carries the
    body weight's component along the fork, m_b g sin(head angle); the tire all the weight."""
    x = spring_compression(setup, setup.body_mass * setup.gravity * math.sin(head_angle))
    rate = tire_values(setup)[0]
    return x, (setup.body_mass + setup.wheel_mass) * setup.gravity / rate


def tire_values(setup: compose.Setup) -> tuple[float, float]:
    """(rate N/m, damping N s/m) of the rolling tire: in-contact values when the law switches."""
    v = setup.tire.values(1)
    return v.rate, v.damping


@dataclass
class Prepared:
    setup: compose.Setup
    terrain: object
    front: FrontEnd
    tire: RadialTire
    callback: RollCallback
    data: mujoco.MjData
    speed: float
    chassis_speed: float


def prepare(scenario, speed_m_per_s: float, config: Config | str = "S12", head_angle_deg: float = DEFAULT_HEAD_ANGLE_DEG,
            overrides: Mapping | None = None, fork_law=None, settled: bool = True, callback: str = "auto",
            drive: str | Drive = "rider", fine_throughout: bool = False) -> Prepared:
    """Everything a rolling run needs, with the data at t = 0 (at rest on the start, at speed).

    ``drive``: ``"rider"`` (a speed controller within a rider's force, power and braking limits),
    ``"servo"`` (the ideal servo on x0 + v t), ``"coast"``, or a ``controllers.drive.Drive`` with
    other limits (see ``controllers/drive.py``); a drum rig always holds its axle with the servo.

    ``callback``: ``"auto"`` (the compiled callback of ``mtbmj.rolling.callback_compiled`` when numba
    is available, else ``RollCallback`` with a warning), ``"compiled"`` or ``"python"``.

    ``fine_throughout``: the model's step is the drop's fine step (for a caller that steps it
    directly, without the run path's refinement: the dm_control environment)."""
    from mtbmj.drop.chain import resolve

    _check_inputs(speed_m_per_s, head_angle_deg, None, warn=False)  # warned by run_roll (a replay, a rig: not)
    if callback not in CALLBACKS:
        raise ConfigError(f"callback: must be one of {', '.join(CALLBACKS)}, got {callback!r}")
    ter = terrain_mod.make(scenario)
    cfg = resolve(config, overrides)
    setup = compose.setup(cfg)
    _check_start(ter, setup.tire_radius)
    # a coarse step (the bike's) where no stop or rim acts, the drop's fine step where one may
    setup = steprule.at_fine_step(setup) if fine_throughout else steprule.rolling(setup)
    drum = isinstance(ter, terrain_mod.DrumTerrain)
    if drum:
        ter = ter.with_speed(float(speed_m_per_s))
    chassis_speed = 0.0 if drum else float(speed_m_per_s)
    front = build_front_end(setup, ter, head_angle_deg)
    rate, damping = tire_values(setup)
    tire = RadialTire(ter, setup.tire_radius, rate, damping, rim=setup.tire.rim)
    model = front.model
    data = mujoco.MjData(model)
    c, s = front.axis
    xf, dt = static_sag(setup, front.head_angle) if settled else (0.0, 0.0)
    qx = xf * c
    data.qpos[model.joint("fork").qposadr[0]] = xf
    data.qpos[model.joint("chassis_x").qposadr[0]] = qx
    data.qpos[model.joint("chassis_z").qposadr[0]] = -dt - xf * s
    data.qvel[model.joint("chassis_x").dofadr[0]] = chassis_speed
    data.qvel[model.joint("wheel_spin").dofadr[0]] = float(speed_m_per_s) / setup.tire_radius
    if front.drum_dof is not None:
        data.qvel[front.drum_dof] = -float(speed_m_per_s) / ter.radius
    refresh = min(REFRESH_S, REFRESH_DISTANCE_M / max(float(speed_m_per_s), 1e-9))
    kv = float(model.actuator_gainprm[model.actuator("drive_velocity").id, 0])
    if isinstance(drive, str):
        if drive not in DRIVE_MODES:
            raise ConfigError(f"drive: {drive!r} is not one of {', '.join(DRIVE_MODES)}")
        drive = Drive(drive)
    elif not isinstance(drive, Drive):  # None met "'NoneType' object has no attribute 'mode'"
        raise ConfigError(f"drive: must be one of {', '.join(DRIVE_MODES)} or a controllers.drive.Drive, got {drive!r}")
    drive = Drive("servo", kv) if drum else Drive(drive.mode, kv, drive.push, drive.power, drive.brake)
    for name in ("push", "power", "brake"):
        value = getattr(drive, name)
        if not (math.isfinite(value) and value >= 0.0):
            raise ConfigError(f"drive {name}: must be a finite number >= 0, got {value}")
    cb = _make_callback(callback, front, fork_law or setup.fork, tire, chassis_speed, qx, refresh, drive)
    cb.bind(data)
    with installed(cb):
        mujoco.mj_forward(model, data)
    return Prepared(setup, ter, front, tire, cb, data, float(speed_m_per_s), chassis_speed)


def _make_callback(kind: str, front, law, tire, speed, x_ref0, refresh, drive=None):
    """The rolling callback of ``kind`` (``mtbmj.runpath.callbacks.choose``)."""
    def load():
        from mtbmj.rolling import callback_compiled  # numba is imported on the first compiled run only

        return callback_compiled

    return callbacks.choose(kind, lambda: RollCallback(front, law, tire, speed, x_ref0, refresh, drive), load,
                            lambda m: m.CompiledRollCallback(front, law, tire, speed, x_ref0, refresh, drive), "rolling")


def callback_kind(callback) -> str:
    """"python" for ``RollCallback``, "compiled" for the compiled callback."""
    return "python" if isinstance(callback, RollCallback) else "compiled"


def _python_twin(cb) -> RollCallback:
    """A fresh Python ``RollCallback`` with the settings of ``cb`` (for a rerun on the Python path)."""
    twin = RollCallback(cb.front, cb.law, cb.tire, cb.speed, cb.x_ref0, cb.refresh, cb.drive)
    twin.damper_scale = cb.damper_scale
    return twin


def default_duration(p: Prepared) -> float:
    return max(1.0, p.terrain.length / p.speed)


def simulate(p: Prepared, duration: float, progress=None, grid: list | None = None):
    """(states (n+1, nstate) incl. t = 0, sensordata (n, nsensor) of each step's start state), on
    the shared run path (``mtbmj.runpath.loop.chunked``) at the coarse step, stepped again at the
    fine step where :func:`refinement` finds a stop, the rim or the tire's ramp within reach; a fine
    stretch's rows are at the fine step (``grid``, a list, receives the mask of the rows on the
    coarse grid).

    If the compiled callback met more contact patches than it holds (``overflowed``), the run is
    redone on the Python path (``p.callback`` becomes that ``RollCallback``), with a warning."""
    def to_python():
        p.callback = _python_twin(p.callback)
        p.callback.bind(p.data)

    def run():
        if grid is not None:
            grid.clear()  # a rerun on the Python path replaces the first run's mask
        return _simulate(p, duration, progress, grid)

    return callbacks.rerun_on_python(p.front.model, p.data, run,
                                     lambda: getattr(p.callback, "overflowed", False), to_python, "rolling")


def refinement(p: Prepared) -> loop.Refinement:
    """The front end's refinement (``mtbmj.runpath.loop.Refinement``, the bike's kind): a chunk
    stepped coarse is looked at after the fact and its stretch within reach of a fork stop, the rim
    or the tire's touchdown, lift-off and damping ramp (its first ``TIRE_DAMPING_DEPTH_M``, where
    the force's slope changes fastest) at its deepest patch or at its shallowest (``tire_touch``: a
    square edge's corner touching down while the tread is deep on the flat) (``steprule.reach_span``)
    stepped again at the fine step, whose rows are kept (``fine_rows``): on
    a 20 mm washboard at 5 m/s the tire lightens to 0.7 mm, where the coarse step alone leaves the
    fork 0.06 mm from the fine step's travel. Before a fine stretch the callback searches its
    patches afresh (they are the chunk's end's)."""
    s, model = p.setup, p.front.model
    sensor = lambda name: int(model.sensor_adr[model.sensor(name).id])  # noqa: E731
    rim = s.tire.rim.max_deflection if s.tire.rim is not None else math.inf
    margin, ramp = steprule.REACH_MARGIN_M, (0.0, TIRE_DAMPING_DEPTH_M)
    watches = (loop.Watch("state", 1 + int(model.joint("fork").qposadr[0]), steprule.stop_zone(s.fork.spring), margin),
               loop.Watch("sensor", sensor("tire_deflection"), (-math.inf, rim), margin),
               loop.Watch("sensor", sensor("tire_deflection"), ramp, margin, inside=True),
               loop.Watch("sensor", sensor("tire_touch"), ramp, margin, inside=True))
    return loop.Refinement(s.substeps, watches, lambda: p.callback.reset(), fine_rows=True)


def _simulate(p: Prepared, duration: float, progress=None, grid: list | None = None):
    steps = int(round(duration / p.setup.timestep))
    model = p.front.model
    with installed(p.callback):
        return loop.chunked(model, p.data, steps, p.setup.timestep, "rolling", refinement(p), progress,
                            chunk=CHUNK, report_every=loop.REFINE_CHUNK, grid=grid)


def _signals(p: Prepared, states, sensors) -> dict[str, np.ndarray]:
    model = p.front.model
    t0 = 0
    n = sensors.shape[0]
    st = states[:n]
    nq = model.nq
    qpos = st[:, 1:1 + nq]
    qvel = st[:, 1 + nq:1 + nq + model.nv]
    cb = p.callback
    cx, cz, vx, vz = cb.axle_state(qpos.T, qvel.T)
    sens = lambda name: sensors[:, model.sensor_adr[model.sensor(name).id]]
    fx, fz = sens("tire_force_x"), sens("tire_force_z")
    q0 = states[0, 1:1 + nq]
    qz0 = q0[cb.zq]
    cz0 = cb.axle_state(q0, states[0, 1 + nq:1 + nq + model.nv])[1]
    times = st[:, t0]
    defl = _with_clearance(p, sens("tire_deflection"), cx, cz, times)  # deepest patch, as the callback applied it
    ground = p.terrain.height(cx) if not p.terrain.moving else p.terrain.height(np.zeros(n))
    return {
        "time_s": times,
        "x_m": cx,
        "speed_m_per_s": qvel[:, cb.xv] if p.chassis_speed else np.full(n, p.speed),
        "terrain_mm": ground * 1e3,
        "body_z_mm": (qpos[:, cb.zq] - qz0) * 1e3,
        "axle_z_mm": (cz - cz0) * 1e3,
        "fork_mm": qpos[:, cb.fq] * 1e3,
        "tire_mm": defl * 1e3,
        "body_z_velocity_mm_per_s": qvel[:, cb.zv] * 1e3,
        "fork_velocity_mm_per_s": qvel[:, cb.fv] * 1e3,
        "fork_force_N": -sens("fork_force"),
        "axle_force_x_N": fx,
        "axle_force_z_N": fz,
        "tire_force_N": np.hypot(fx, fz),
        "drive_force_N": sens("drive_force_pos") + sens("drive_force_vel"),
    }


def _with_clearance(p: Prepared, deflection: np.ndarray, cx: np.ndarray, cz: np.ndarray,
                    times: np.ndarray) -> np.ndarray:
    """The tire's deflection with the clearance (negative: the gap between tire and ground,
    radially) where the callback saw no patch within its margin and wrote its sentinel, -margin:
    the exact distance from the axle to the terrain there, less the radius."""
    tire = p.tire
    sentinel = deflection <= -tire.margin + 1e-12
    if not np.any(sentinel):
        return deflection
    out = deflection.copy()
    idx = np.flatnonzero(sentinel)
    if p.terrain.moving:  # the drum: its surface moves, ask the tire's own geometry at each time
        for i in idx:
            seeing = type(tire)(tire.terrain, tire.radius, tire.rate, tire.damping, margin=1.0)
            out[i] = tire.radius - seeing.distance(float(cx[i]), float(cz[i]), float(times[i]))
        return out
    # the closest point is no farther than the ground straight below: look that far either side
    reach = np.maximum(cz[idx] - p.terrain.height(cx[idx]), tire.radius) + 1e-3
    px, pz, _, _ = p.terrain.polyline(float(np.min(cx[idx] - reach)), float(np.max(cx[idx] + reach)))
    lo = np.maximum(np.searchsorted(px, cx[idx] - reach, side="left") - 1, 0)
    hi = np.minimum(np.searchsorted(px, cx[idx] + reach, side="right") + 1, px.size)
    width = int(np.max(hi - lo - 1))  # segments per sample, padded to the widest window
    for start in range(0, idx.size, max(1, 2_000_000 // max(width, 1))):  # bounded memory
        part = slice(start, start + max(1, 2_000_000 // max(width, 1)))
        j = lo[part, None] + np.arange(width)[None, :]
        valid = j < (hi[part, None] - 1)
        j = np.minimum(j, px.size - 2)
        ax, az, ex, ez = px[j], pz[j], px[j + 1] - px[j], pz[j + 1] - pz[j]
        x, z = cx[idx[part], None], cz[idx[part], None]
        length2 = np.where(ex * ex + ez * ez > 0.0, ex * ex + ez * ez, 1.0)
        u = np.clip(((x - ax) * ex + (z - az) * ez) / length2, 0.0, 1.0)
        dist = np.where(valid, np.hypot(x - ax - u * ex, z - az - u * ez), np.inf)
        out[idx[part]] = tire.radius - dist.min(axis=1)
    return out


def _drive_line(d: dict) -> str:
    """"; drive rider: 0.55-3.03 m/s, 309 J put in, at its limit 0.60 s" (the servo: its peak push)."""
    text = (f"; drive {d['mode']}: {d['min_speed_m_per_s']:.2f}-{d['max_speed_m_per_s']:.2f} m/s, "
            f"{d['work_J']:.0f} J put in")
    if d["mode"] == "servo":
        return text + f", pushing up to {d['max_push_N']:.0f} N"
    if d["mode"] == "rider" and d["limit_bound_s"] > 0.0:
        return text + f", at its limit {d['limit_bound_s']:.2f} s"
    return text


def row_spans(times: np.ndarray, timestep: float) -> np.ndarray:
    """Each row's span of time (s): to the next row's time, the last row ``timestep`` (a run's rows
    are the coarse step apart, the fine step inside a fine stretch)."""
    return np.append(np.diff(times), timestep) if times.size else np.empty(0)


def _drive_summary(p: Prepared, raw: dict) -> dict:
    """What the drive did: its mode and limits, the speed it kept (set, lowest, highest), the work
    it put in (J, the integral of force x speed) and its peak forces, and the time its limit bound."""
    drive = p.callback.drive
    force, speed = raw["drive_force_N"], raw["speed_m_per_s"]
    dt = row_spans(raw["time_s"], p.setup.timestep)  # each row's span: the fine step in a fine stretch
    out = {"mode": drive.mode, "set_speed_m_per_s": p.speed,
           "min_speed_m_per_s": float(speed.min()), "max_speed_m_per_s": float(speed.max()),
           "work_J": float(np.sum(force * speed * dt)),
           "max_push_N": float(max(0.0, force.max())), "max_brake_N": float(max(0.0, -force.min())) + 0.0}
    if drive.mode == "rider":
        push = np.minimum(drive.push, np.where(speed > 0.0, drive.power / np.maximum(speed, 1e-12), np.inf))
        bound = (force >= push * (1.0 - 1e-9)) | (force <= -drive.brake * (1.0 - 1e-9))
        out.update(push_limit_N=drive.push, power_limit_W=drive.power, brake_limit_N=drive.brake,
                   limit_bound_s=float(np.sum(bound * dt)))
    return out


# A run that ends with the tyre this far or more above the ground, carrying nothing, ends before its
# landing (a drop or a cliff edited into a terrain near its end): its peaks miss the landing's.
IN_AIR_AT_END_MM = 5.0


def in_air_at_end(tire_mm, tire_force_N) -> float | None:
    """The tyre's height above the ground (mm) where the run ends in the air, else None."""
    if tire_force_N[-1] <= 0.0 and -tire_mm[-1] >= IN_AIR_AT_END_MM:
        return float(-tire_mm[-1])
    return None


def _air_line(s: dict) -> str:
    h = s.get("in_air_at_end_mm")
    return "" if h is None else (f"; the run ended with the wheel in the air, {h / 1e3:.2f} m above the ground: its "
                                 f"landing is not in the run (a longer --duration)")


# A wheel rolled forward never moves back over ground it gets over (the library's features at 1.5 and 5 m/s: the
# lowest speed 1.39 m/s, tests/test_fuzz_careless29b.py); a speed below this, backwards, is a wheel that did not.
BACKWARDS_M_PER_S = -0.05


def went_back(time_s, x_m, speed) -> dict | None:
    """Where the wheel first moved backwards (``time_s`` s, ``x_m`` m) and its fastest backwards (m/s), else None."""
    back = np.flatnonzero(np.asarray(speed) < BACKWARDS_M_PER_S)
    if not back.size:
        return None
    return {"time_s": float(time_s[back[0]]), "x_m": float(x_m[back[0]]), "speed_m_per_s": float(np.min(speed))}


def _back_line(s: dict) -> str:
    b = s.get("went_back")
    return "" if b is None else (f"; the wheel went backwards at {b['time_s']:.2f} s ({b['x_m']:.2f} m), up to "
                                 f"{-b['speed_m_per_s']:.2f} m/s: it did not get over the terrain there (a wall, an "
                                 f"edge, or a climb beyond the drive), no ride over it")


def _summary(p: Prepared, logged: dict, raw: dict) -> dict:
    travel_mm = p.setup.travel * 1e3
    fork = raw["fork_mm"]
    out = {
        "scenario": p.terrain.describe(),
        "speed_m_per_s": p.speed,
        "head_angle_deg": math.degrees(p.front.head_angle),
        "duration_s": float(raw["time_s"][-1] + p.setup.timestep),
        "tire_rate_N_per_mm": p.tire.rate / 1e3,
        "tire_damping_N_s_per_m": p.tire.damping,
        "static_fork_mm": float(fork[0]),
        "static_tire_mm": float(raw["tire_mm"][0]),
        "max_fork_mm": float(fork.max()),
        "min_fork_mm": float(fork.min()),
        **end_of_travel(p.setup, fork, raw["fork_velocity_mm_per_s"], raw["tire_mm"], time_s=raw["time_s"]),
        "max_tire_mm": float(raw["tire_mm"].max()),
        "tire_off_ground_s": float(np.sum((raw["tire_force_N"] <= 0.0) * row_spans(raw["time_s"], p.setup.timestep))),
        "max_axle_force_x_N": float(raw["axle_force_x_N"].max()),
        "min_axle_force_x_N": float(raw["axle_force_x_N"].min()),
        "max_axle_force_z_N": float(raw["axle_force_z_N"].max()),
        "max_fork_velocity_mm_per_s": float(raw["fork_velocity_mm_per_s"].max()),
        "min_fork_velocity_mm_per_s": float(raw["fork_velocity_mm_per_s"].min()),
        "drive": _drive_summary(p, raw),
        "in_air_at_end_mm": in_air_at_end(raw["tire_mm"], raw["tire_force_N"]),
        "went_back": went_back(raw["time_s"], raw["x_m"], raw["speed_m_per_s"]),
    }
    try:
        from mtbmj.measured import metrics as ride_metrics
    except ImportError:  # written by a parallel piece of work; the summary stands without it
        out["ride_metrics"] = None
    else:
        out["ride_metrics"] = ride_metrics.summarize(logged["time_s"], logged["fork_mm"], travel_mm,
                                                     velocity_mm_per_s=logged["fork_velocity_mm_per_s"])
        # the telemetry rule, on the 1 kHz record as a logger would see it: for comparing with a
        # recorded ride; the model's own end of travel is the bumper/hard_stop/rim_strikes above
        out["ride_metrics"]["bottom_outs"]["rule"] = ("telemetry: within margin_mm of full travel on the 1 kHz "
                                                     "record, as for a recorded ride")
    return out


@dataclass
class RollResult(RunOutput):
    """A rolling run: ``signals`` at the logger rate (1 kHz after the 400 Hz low-pass, like the
    drop), ``raw`` at the engine step, ``summary`` (peaks, rider metrics)."""

    name: str
    scenario: str
    config: Config
    signals: dict[str, np.ndarray]
    raw: dict[str, np.ndarray]
    summary: dict
    wall_time_s: float
    info: dict = field(default_factory=dict)
    grid_rows: np.ndarray | None = None  # the rows of ``raw`` on the coarse grid (None: all)
    COLUMNS = COLUMNS
    # difference(): the body's and the axle's heights, fork travel and tyre deflection in mm, the tyre's force in N
    COMPARED = ("body_z_mm", "axle_z_mm", "fork_mm", "tire_mm", "tire_force_N")

    def csv_bytes(self, raw: bool = False) -> bytes:
        data = self.raw if raw else self.signals
        rate = "engine rate" if raw else "1 kHz after a 400 Hz anti-aliasing low-pass"
        header = (f"mtbmj roll {self.scenario}, config {self.name}, {rate}\n"
                  "fork compression positive from unloaded full extension; tire radial deflection positive; "
                  "heights from the start, up positive; axle forces from the ground, x forward, z up")
        return output.csv_bytes({k: data[k] for k in COLUMNS}, header)

    def manifest(self) -> dict:
        from mtbmj.result import versions

        return {"name": self.name, "scenario": self.scenario, "engine": "mujoco", "config_sha256": self.config.digest(),
                "config_sources": list(self.config.sources), "versions": versions(),
                "wall_time_s": self.wall_time_s, "engine_info": self.info}

    def headline(self) -> str:
        """The run in one line: peaks, axle forces and any bottom-out or rim strike."""
        from mtbmj.readout.endtravel import line

        s = self.summary
        return (f"roll {self.scenario} at {s['speed_m_per_s']:g} m/s ({self.name}, head angle {s['head_angle_deg']:g} "
                f"deg): fork peak {s['max_fork_mm']:.1f} mm ({s['travel_used_percent']:.0f} % of travel), tire peak "
                f"{s['max_tire_mm']:.1f} mm, axle force peak {s['max_axle_force_z_N']:.0f} N up / "
                f"{max(0.0, -s['min_axle_force_x_N']):.0f} N back{line(s)}{_drive_line(s['drive'])}{_back_line(s)}{_air_line(s)}")

    def quicklook(self):
        """The quick-look figure (``mtbmj.readout.quicklook``): terrain, fork, tire (its clearance in the
        air), axle and fork forces, on the engine-rate signals; titled by the run's headline and,
        for a configuration file, what the file is."""
        from mtbmj.readout import quicklook

        r = self.raw
        return quicklook.figure(r["time_s"], r["fork_mm"], r["tire_mm"],
                                {k: r[k] for k in ("axle_force_z_N", "axle_force_x_N", "fork_force_N")},
                                self.summary, quicklook.run_title(self.config, self.headline()),
                                extra=[("terrain under the axle", r["terrain_mm"], "mm")])

    def plot(self, axes=None, label: str | None = None, **line_kwargs):
        """Terrain under the axle, fork travel, tire deflection and the axle's force up and back
        against time on five stacked axes (given, or a new figure's): several runs drawn on the same
        axes compare them, as every rig's ``plot``. Returns the figure."""
        return self.plot_stacked((("terrain_mm", "terrain [mm]"), ("fork_mm", "fork travel [mm]"),
                                  ("tire_mm", "tire deflection [mm]"), ("axle_force_z_N", "axle force up [N]"),
                                  ("axle_force_x_N", "axle force, forward [N]")), self.signals, axes,
                                 label or f"{self.name} over {self.scenario}", {"loc": "best", "fontsize": 8},
                                 **line_kwargs)


def run_roll(scenario, speed_m_per_s: float, config: Config | str = "S12",
             head_angle_deg: float = DEFAULT_HEAD_ANGLE_DEG, duration: float | None = None,
             overrides: Mapping | None = None, progress: Callable[[float], None] | None = None,
             callback: str = "auto", drive: str | Drive = "rider") -> RollResult:
    """Roll the front end over ``scenario`` (a terrain spec, CSV path or ``Terrain``) at
    ``speed_m_per_s`` with the fork and tire of ``config``; ``duration`` defaults to the time to
    cross the feature and settle (the drum: its revolutions). ``callback``: ``"auto"`` (compiled
    when numba is available), ``"compiled"`` or ``"python"`` (the specification; same results);
    ``drive``: see ``prepare`` (default ``"rider"``: within a rider's force, power and braking)."""
    _check_inputs(speed_m_per_s, head_angle_deg, duration)  # the plausible ranges warned here, not in prepare
    p = guard.prepared("rolling", lambda: prepare(scenario, speed_m_per_s, config, head_angle_deg, overrides,
                                                  callback=callback, drive=drive), model_of=lambda p: p.front.model)
    if duration is None:  # the terrain crossed: a crawl refused before the run
        duration = default_duration(p)
        crossing(p.speed, duration, p.terrain.name)
    check_run(duration, p.setup.timestep, p.setup.sample_rate)
    start = time.perf_counter()
    grid: list = []
    states, sensors = simulate(p, duration, progress, grid)
    wall = time.perf_counter() - start
    raw = _signals(p, states, sensors)
    on_grid = grid[0]
    logged = measure.logged(p.setup, {k: v[on_grid] for k, v in raw.items()})  # the logger reads the coarse grid
    summary = _summary(p, logged, raw)
    info = {"steps": int(on_grid.sum()), "rows": int(sensors.shape[0]), "timestep_s": p.setup.timestep,
            "fine_timestep_s": p.setup.timestep / p.setup.substeps, "integrator": p.setup.integrator,
            "callback": callback_kind(p.callback),
            "callback_calls": p.callback.calls, "geometry_refreshes": p.callback.refreshes,
            "real_time_factor": duration / wall if wall > 0 else None}
    return RollResult(p.setup.config.name, str(scenario), p.setup.config, logged, raw, summary, wall, info,
                      grid_rows=np.flatnonzero(on_grid))


def roll_trajectory(scenario, speed_m_per_s: float, config: Config | str = "S12",
                    head_angle_deg: float = DEFAULT_HEAD_ANGLE_DEG, duration: float | None = None,
                    overrides: Mapping | None = None, fps: float = 60.0, drive: str | Drive = "rider"):
    """(model, times, qpos) of a rolling run sampled at ``fps`` for rendering; the model has the
    terrain as a visual heightfield (group 1) or the drum with its cleat. ``drive`` as ``prepare``."""
    _check_inputs(speed_m_per_s, head_angle_deg, duration, warn=False)  # a saved run's values: warned when it ran
    fps = limits.given("--fps", "fps", fps, warn=False)
    p = guard.prepared("rolling", lambda: prepare(scenario, speed_m_per_s, config, head_angle_deg, overrides, drive=drive),
                       model_of=lambda p: p.front.model)
    duration = default_duration(p) if duration is None else duration
    check_run(duration, p.setup.timestep, p.setup.sample_rate)
    grid: list = []
    states, _ = simulate(p, duration, grid=grid)
    dt = p.setup.timestep
    every = max(1, int(round(1.0 / (fps * dt))))
    # the coarse grid's states: the start state of every row on the grid, and the last state
    rows = states[np.append(np.flatnonzero(grid[0]), grid[0].size)][::every]
    nq = p.front.model.nq
    return p.front.model, rows[:, 0].copy(), rows[:, 1:1 + nq].copy()


__all__ = ["run_roll", "roll_trajectory", "RollResult", "RollCallback", "FrontEnd", "build_front_end", "prepare",
           "simulate", "static_sag", "spring_compression", "tire_values", "callback_kind", "COLUMNS", "CALLBACKS", "DEFAULT_HEAD_ANGLE_DEG"]

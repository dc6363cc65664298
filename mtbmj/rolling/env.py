"""A dm_control task: roll the front end over terrain with a semi-active fork damper.

Action: one number u in [0, 1], the damper command. The fork's hydraulic damper force (the
configuration's law, e.g. S12's table) is scaled by ``SCALE_MIN + u (SCALE_MAX - SCALE_MIN)``:
a valve that can make the damper softer or firmer but never push on its own (the force keeps the
sign of the compression velocity): semi-active. Spring and friction stay passive.

Observations (SI, compression positive; each a float64 array):

- ``body_z_velocity`` (1,): vertical velocity of the body (the chassis the fork hangs from), m/s,
  up positive.
- ``body_z_acceleration`` (1,): its vertical acceleration, m/s^2, up positive (what the reward
  penalises).
- ``fork_compression`` (1,): fork travel used, m, from full extension along the fork axis.
- ``fork_velocity`` (1,): its rate, m/s, compression positive.
- ``tire_deflection`` (1,): radial tire deflection at the deepest contact patch, m (0 in the air).
- ``axle_force`` (2,): force of the terrain on the wheel, N, (x forward, z up).
- ``damper_force_per_scale`` (1,): the passive damper force D(v) at the current fork velocity, N
  (the force at scale 1), so a controller can turn a wanted force into a command.
- ``head_angle_sin`` (1,): sine of the head angle (constant in an episode): the fork acts on the
  body along its axis, so a fork force F lifts the body by F sin(head angle).

Reward: ride comfort in (0, 1], 1 / (1 + (a_z / g)^2) with a_z the body's vertical acceleration.

Headless: dm_control chooses its OpenGL backend when first imported and, left alone, tries GLFW
first (an error message on a machine without a display). Importing this module before dm_control,
with ``MUJOCO_GL`` unset and no display, sets ``MUJOCO_GL`` to ``egl`` (or ``osmesa``, or
``disable`` when neither library is found); a value the user set is never changed.

The fork, tire and speed servo act through ``mtbmj.rolling.frontend.RollCallback``; MuJoCo's control
callback is process-global, so the environment installs it only while it steps and restores the
previous one after (also on errors).
"""
from __future__ import annotations

import collections
import ctypes.util
import os
import sys

import numpy as np


def _default_gl() -> str | None:
    """The OpenGL backend to name for dm_control when the user named none, or None to leave it.

    dm_control picks its backend once, when first imported; left to itself it tries GLFW first,
    which prints a "DISPLAY missing" error on a headless machine. This environment never renders,
    so with no display it names a headless backend: EGL, else OSMesa, else none at all."""
    if os.environ.get("MUJOCO_GL") or "dm_control" in sys.modules:
        return None  # the user's choice, or dm_control has chosen already
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None  # a desktop: dm_control's own order (GLFW first) works there
    for name, library in (("egl", "EGL"), ("osmesa", "OSMesa")):
        if ctypes.util.find_library(library):
            return name
    return "disable"


if (_gl := _default_gl()) is not None:
    os.environ["MUJOCO_GL"] = _gl  # only ever set where it was unset (see _default_gl)

try:
    from dm_control import mujoco as dm_mujoco
    from dm_control.rl import control
    from dm_control.suite import base
    from dm_env import specs
except ImportError as error:
    from mtbmj.extras import missing

    if missing(["dm_control", "dm_env"]):  # not installed; any other import failure speaks for itself
        raise ImportError(f"mtbmj.rolling.env needs dm-control ({error}): pip install 'mtbmj[rl]'") from error
    raise

from mtbmj.controllers import installed
from mtbmj.rolling import frontend as rolling

SCALE_MIN = 0.2
SCALE_MAX = 3.0
CONTROL_TIMESTEP_S = 0.002


def command_to_scale(u) -> float:
    u = float(np.clip(u, 0.0, 1.0))
    return SCALE_MIN + u * (SCALE_MAX - SCALE_MIN)


def scale_to_command(scale) -> float:
    return float(np.clip((scale - SCALE_MIN) / (SCALE_MAX - SCALE_MIN), 0.0, 1.0))


class RollingTask(base.Task):
    """Rolling at a set speed; the action commands the damper scale."""

    def __init__(self, prepared: rolling.Prepared, random=None):
        super().__init__(random=random)
        self.prepared = prepared
        self.callback: rolling.RollCallback | None = None
        self._initial = None

    def attach(self, physics, callback: rolling.RollCallback) -> None:
        self.callback = callback
        d = self.prepared.data
        self._initial = (d.qpos.copy(), d.qvel.copy(), d.act.copy())

    def initialize_episode(self, physics):
        qpos, qvel, act = self._initial
        physics.data.qpos[:] = qpos
        physics.data.qvel[:] = qvel
        physics.data.act[:] = act
        physics.data.time = 0.0
        self.callback.reset()
        self.callback.damper_scale = 1.0

    def action_spec(self, physics):
        return specs.BoundedArray((1,), np.float64, 0.0, 1.0, name="damper_command")

    def before_step(self, action, physics):
        self.callback.damper_scale = command_to_scale(np.asarray(action).reshape(-1)[0])

    def get_observation(self, physics):
        cb = self.callback
        d = physics.data
        qpos, qvel = d.qpos, d.qvel
        cx, cz, vx, vz = cb.axle_state(qpos, qvel)
        fx, fz, deflection, _, _ = cb.tire.force(cx, cz, vx, vz, cb.patches)
        obs = collections.OrderedDict()
        obs["body_z_velocity"] = np.array([qvel[cb.zv]])
        obs["body_z_acceleration"] = np.array([d.qacc[cb.zv]])
        obs["fork_compression"] = np.array([qpos[cb.fq]])
        obs["fork_velocity"] = np.array([qvel[cb.fv]])
        obs["tire_deflection"] = np.array([deflection])
        obs["axle_force"] = np.array([fx, fz])
        obs["damper_force_per_scale"] = np.array([cb.law.damper.force(float(qvel[cb.fv]))])
        obs["head_angle_sin"] = np.array([cb.sin])
        return obs

    def get_reward(self, physics):
        a = float(physics.data.qacc[self.callback.zv]) / self.prepared.setup.gravity
        return 1.0 / (1.0 + a * a)


class RollingEnvironment(control.Environment):
    """``control.Environment`` that installs the rolling callback while it steps."""

    def reset(self):
        with installed(self.task.callback):
            return super().reset()

    def step(self, action):
        with installed(self.task.callback):
            return super().step(action)


def load(scenario="washboard", speed_m_per_s: float = 5.0, config="S12",
         head_angle_deg: float = rolling.DEFAULT_HEAD_ANGLE_DEG, duration: float | None = None,
         control_timestep: float = CONTROL_TIMESTEP_S, overrides=None, random=None) -> RollingEnvironment:
    """A ready environment: terrain spec, speed, configuration, head angle, episode length (s)."""
    p = rolling.prepare(scenario, speed_m_per_s, config, head_angle_deg, overrides, fine_throughout=True)
    physics = dm_mujoco.Physics.from_model(dm_mujoco.wrapper.MjModel(p.front.model))
    # The callback must see the Physics' own model and data (from_model may copy the model). It
    # drives with the ideal servo (RollCallback's default): the task is a rig held at speed.
    cb = rolling.RollCallback(p.front, p.setup.fork, p.tire, p.chassis_speed, p.callback.x_ref0, p.callback.refresh)
    cb._model = physics.model.ptr
    cb._address = physics.model.ptr._address
    cb.bind(physics.data.ptr)
    task = RollingTask(p, random=random)
    task.attach(physics, cb)
    duration = rolling.default_duration(p) if duration is None else duration
    n_sub = max(1, int(round(control_timestep / p.setup.timestep)))
    return RollingEnvironment(physics, task, time_limit=duration, n_sub_steps=n_sub)


__all__ = ["load", "RollingEnvironment", "RollingTask", "command_to_scale", "scale_to_command",
           "SCALE_MIN", "SCALE_MAX"]

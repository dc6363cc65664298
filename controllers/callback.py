"""Injecting the fork force law into MuJoCo through ``mujoco.set_mjcb_control``.

The control callback is process-global, fires for every model stepped while installed (dm_control
included) and, with RK4, four times per step at the stage states. ``ForkCallback`` therefore acts
only on the model it was built for, reads the state it is handed (so RK4 stages are right), and
assigns (never adds to) ``qfrc_applied``, which MuJoCo does not clear. ``installed`` restores the
previous callback however the run ends.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import replace

import mujoco


class ForkCallback:
    """Writes -F_fork into the fork joint's generalized force and, for a friction law with a state
    (LuGre, Sticking), dz/dt into the control of an integrator actuator whose activation is the
    bristle state z; with ``rim``, the rim-strike force on the sled and fork joints; with
    ``floor``, the force that makes MuJoCo's soft tire contact the Kelvin-Voigt law exactly
    (``ContactFloor``; :meth:`set_tire` follows the tire switch)."""

    def __init__(self, model, fork_law, fork_joint: str = "fork", state_actuator: str = "friction_state",
                 rim=None, sled_joint: str = "sled", floor=None):
        self.law = fork_law
        self.rim = rim  # controllers.stops.Rim on the tire deflection sled - fork (the drop scene), or None
        self.floor = floor  # controllers.tire.ContactFloor (the drop scene), or None
        if rim is not None or floor is not None:
            sled = model.joint(sled_joint)
            self.sled_qpos, self.sled_dof = int(sled.qposadr[0]), int(sled.dofadr[0])
        self._model = model
        self._model_address = model._address
        joint = model.joint(fork_joint)
        self.qpos_index = int(joint.qposadr[0])
        self.dof_index = int(joint.dofadr[0])
        self.has_state = fork_law.has_state
        actuator = model.actuator(state_actuator)
        self.ctrl_index = int(actuator.id)
        self.act_index = int(model.actuator_actadr[actuator.id])
        self.calls = 0
        self._data = None
        self._arrays = None

    def bind(self, data) -> None:
        """Keep views of ``data``'s arrays: the binding creates a new view at every attribute
        access, which costs more than the force law itself. Other data are still served."""
        self._data = data
        self._arrays = (data.qpos, data.qvel, data.act, data.ctrl, data.qfrc_applied)

    def __call__(self, m, d):
        if m is not self._model and m._address != self._model_address:
            return
        self.calls += 1
        if d is self._data:
            qpos, qvel, act, ctrl, qfrc = self._arrays
        else:
            qpos, qvel, act, ctrl, qfrc = d.qpos, d.qvel, d.act, d.ctrl, d.qfrc_applied
        x = qpos[self.qpos_index]
        v = qvel[self.dof_index]
        if self.has_state:
            z = act[self.act_index]
            ctrl[self.ctrl_index] = self.law.state_rate(v, z)
            force = -self.law.force(x, v, z)
        else:
            force = -self.law.force(x, v)
        if self.rim is None and self.floor is None:
            qfrc[self.dof_index] = force
            return
        # forces on the wheel from the ground side (the rim, the contact's correction) push it
        # up and not the sled: generalized -F on the sled joint, +F on the fork joint
        deflection, rate = qpos[self.sled_qpos] - x, qvel[self.sled_dof] - v
        sled = 0.0
        if self.rim is not None:
            rim = self.rim.force(deflection, rate)
            sled = -rim
            force += rim
        if self.floor is not None:
            c = self.floor.correction(deflection, rate, force)
            sled -= c
            force += c
        qfrc[self.sled_dof] = sled
        qfrc[self.dof_index] = force

    def set_tire(self, rate: float, damping: float) -> None:
        """The tire law's values changed (the switch): the contact correction follows."""
        if self.floor is not None:
            self.floor = replace(self.floor, rate=rate, damping=damping)


@contextmanager
def installed(callback):
    """Install ``callback`` as MuJoCo's control callback for the duration of a with-block."""
    previous = mujoco.get_mjcb_control()
    mujoco.set_mjcb_control(callback)
    try:
        yield callback
    finally:
        mujoco.set_mjcb_control(previous)


__all__ = ["ForkCallback", "installed"]

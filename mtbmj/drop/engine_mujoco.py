"""The drop on MuJoCo: the scene from ``mtbmj.drop.scene``, the fork law through the control callback,
the tire as calibrated soft contact, the tire-law switch applied between steps."""
from __future__ import annotations

from contextlib import contextmanager

import mujoco
import numpy as np
from mtbmj.controllers import ForkCallback, installed, native
from mtbmj.drop import scene as scene_mod
from mtbmj.compose import Setup
from mtbmj.drop.stepping import Stepping
from mtbmj.runpath import callbacks, loop
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace


def state_layout(model) -> tuple[int, slice, slice, slice]:
    """Offsets of time, qpos, qvel and act in MuJoCo's full-physics state vector."""
    size = lambda spec: mujoco.mj_stateSize(model, spec)
    t = size(mujoco.mjtState.mjSTATE_TIME)
    nq, nv = size(mujoco.mjtState.mjSTATE_QPOS), size(mujoco.mjtState.mjSTATE_QVEL)
    na = size(mujoco.mjtState.mjSTATE_ACT)
    return 0, slice(t, t + nq), slice(t + nq, t + nq + nv), slice(t + nq + nv, t + nq + nv + na)


# MuJoCo gives a contact at exactly zero distance no constraint row: at t = 0 the tread would
# push with neither spring nor damper for one step. Start it touching by a rounding error, as the
# ODE reference's guard takes the touchdown side at a zero distance.
TOUCH_DEPTH_M = 1e-12

# the names ``mtbmj.rolling.frontend`` imports (it is to move to the public ones above)


CALLBACKS = ("auto", "compiled", "python")


def fork_callback(model, law, kind="auto", rim=None, floor=None):
    """The fork callback for ``model``, chosen as every rig's is (``mtbmj.runpath.callbacks.choose``):
    ``"auto"`` (the compiled laws when possible, else the Python laws with a one-time warning;
    ``run`` takes the Python laws for a short run in a process without numba, see
    ``controllers.native``), ``"compiled"``, ``"python"``, or a factory ``f(model, law)``. ``rim``
    (a ``controllers.Rim``) adds the rim strike on the tire deflection, ``floor`` (a
    ``controllers.ContactFloor``) the soft contact's correction."""
    if callable(kind):
        return kind(model, law)
    if kind not in CALLBACKS:
        raise ValueError(f"callback: expected one of {', '.join(CALLBACKS)} or a factory, got {kind!r}")

    def load():
        from mtbmj.controllers import compiled  # numba is imported on the first run only

        return compiled

    return callbacks.choose(kind, lambda: ForkCallback(model, law, rim=rim, floor=floor), load,
                            lambda compiled: compiled.CompiledForkCallback(model, law, rim=rim, floor=floor), "fork")


@contextmanager
def stepping_finer(models, substeps):
    """Each of ``models`` at its step over its ``substeps`` (the steps restored after): the batched
    engine's fine rollouts on the pool's threads."""
    steps = [m.opt.timestep for m in models]
    try:
        for m, h, k in zip(models, steps, substeps):
            m.opt.timestep = h / k
        yield
    finally:
        for m, h in zip(models, steps):
            m.opt.timestep = h


class _Plan(Stepping):
    """The drop's :class:`~mtbmj.drop.stepping.Stepping` as the run path's plan
    (``mtbmj.runpath.loop.Plan``): it counts the output steps thrown away, keeps the tire phase
    each recorded row was stepped in, and makes the tire-law switch on the scene."""

    def __init__(self, setup: Setup, columns, scene, callback):
        super().__init__(setup, columns)
        self.scene, self.callback = scene, callback
        self.discarded = 0  # output steps computed past a tire-law switch or into a zone, and recomputed
        self.row_phase = self.phase

    def size(self, remaining: int) -> int:
        self.row_phase = self.phase
        return super().size(remaining)

    def keep(self, previous, states, fine_states=None, sensors=None, warned=False):
        keep, switch, partial = super().keep(previous, states, fine_states)
        self.discarded += len(states) - keep
        if partial is not None:
            self.computed += partial[1]  # the fine steps that finish the output step under the new law
            self.discarded -= 1  # that output step is made, not thrown away
        return keep, switch, partial

    def switched(self) -> None:
        values = self.setup.tire.values(1)
        self.scene.set_tire(values.rate, values.damping, self.callback)
        self.row_phase = self.phase


def run(setup: Setup, duration: float | None = None, progress=None, callback="auto") -> RawTrace:
    """Integrate the drop from tire touch (t = 0, both bodies at the impact speed).

    Steps run in chunks through ``mujoco.rollout`` (the loop and the recording stay in C++; the
    control callback still supplies the fork force). When the tire law switches, the chunk is cut
    at the step where the tire lifts off or the fork turns (``stepping.switch_index``), the contact is
    re-parameterised and stepping resumes from that state, exactly as if the switch had been made
    between two single steps. Where an end stop or the rim may act (``stepping.stop_index``) the chunk is
    cut before that step and stepping goes on at ``setup.fine_timestep`` (recording every
    ``setup.substeps``-th state, so the output grid stays ``setup.timestep``; at
    ``setup.contact_substeps`` in the zones where no stop or rim can act) until the fork and
    tire are clear of them again.
    ``callback`` chooses the fork callback (see :func:`fork_callback`).
    """
    duration = setup.duration if duration is None else duration
    sc = scene_mod.build(setup)
    model = sc.model
    data = mujoco.MjData(model)
    data.qvel[sc.sled_dof] = setup.impact_speed
    data.qpos[sc.sled_qpos] = TOUCH_DEPTH_M
    mujoco.mj_forward(model, data)
    steps = int(round(duration / setup.timestep))
    # compiled (numba) force laws read and write mjData directly; the Python laws are the fallback,
    # and "auto" takes them for a short run in a process without numba (controllers.native)
    if callback == "auto" and not native.worth(steps):
        callback = "python"
    callback = fork_callback(model, setup.fork, callback, setup.tire.rim, sc.floor())
    callback.bind(data)
    substeps = setup.substeps
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    _, iq, iv, ia = state_layout(model)
    # Only the columns the trace needs are kept (sled, fork, their velocities, the friction
    # state): memory grows with the run by 40 bytes a step, not by the whole physics state.
    columns = [iq.start + sc.sled_qpos, iq.start + sc.fork_qpos, iv.start + sc.sled_dof, iv.start + sc.fork_dof]
    if model.na:
        columns.append(ia.start + callback.act_index)
    record = np.zeros((steps + 1, 5))
    record[0, : len(columns)] = state[columns]
    phase = np.zeros(steps + 1, dtype=np.int8)
    plan = _Plan(setup, columns[:4], sc, callback)

    def sink(first, rows, _sensors):
        record[first + 1: first + 1 + len(rows), : len(columns)] = rows[:, columns]
        phase[first + 1: first + 1 + len(rows)] = plan.row_phase

    with installed(callback):
        loop.stepped(model, data, steps, setup.timestep, "drop", plan, sink, progress,
                     limit=(slice(1, 3), MAX_DISPLACEMENT_M, "a displacement beyond 10 m"))
    discarded = plan.discarded
    return RawTrace(
        engine="mujoco",
        time=np.arange(steps + 1, dtype=float) * setup.timestep,
        sled=record[:, 0],
        fork=record[:, 1],
        sled_velocity=record[:, 2],
        fork_velocity=record[:, 3],
        friction_state=record[:, 4],
        tire_phase=phase,
        info={"steps": steps, "steps_discarded": discarded, "steps_refined": plan.refined, "substeps": substeps,
              "contact_substeps": plan.contact_level,
              "steps_computed": plan.computed, "callback_calls": callback.calls, "integrator": setup.integrator,
              "callback": "python" if isinstance(callback, ForkCallback) else "compiled",
              "timestep_s": setup.timestep, "contact_inverse_inertia_per_kg": sc.inverse_inertia},
    )


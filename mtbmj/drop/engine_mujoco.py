"""The drop on MuJoCo: the scene from ``mtbmj.drop.scene``, the fork law through the control callback,
the tire as calibrated soft contact, the tire-law switch applied between steps."""
from __future__ import annotations

from contextlib import contextmanager

import mujoco
import numpy as np
from mujoco import rollout

from mtbmj.controllers import ForkCallback, installed, native
from mtbmj.drop import scene as scene_mod
from mtbmj.compose import Setup
from mtbmj.drop.stepping import Stepping
from mtbmj.errors import RunError
from mtbmj.runpath import guard
from mtbmj.runpath.guard import collected_warnings, first_warning, steps_clean
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace


# MuJoCo's warnings and the divergence checks are the shared run path's (``mtbmj.runpath.guard``)


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
    """The fork callback for ``model``: ``"auto"`` (the compiled laws when possible, else the Python
    laws with a one-time warning; ``run`` takes the Python laws for a short run in a process
    without numba, see ``controllers.native``), ``"compiled"``, ``"python"``, or a factory ``f(model, law)``.
    ``rim`` (a ``controllers.Rim``) adds the rim strike on the tire deflection, ``floor`` (a
    ``controllers.ContactFloor``) the soft contact's correction."""
    if callable(kind):
        return kind(model, law)
    if kind == "python":
        return ForkCallback(model, law, rim=rim, floor=floor)
    from mtbmj.controllers import compiled  # numba is imported on the first run only

    if kind == "compiled":
        return compiled.CompiledForkCallback(model, law, rim=rim, floor=floor)
    if kind == "auto":
        return compiled.make_callback(model, law, rim=rim, floor=floor)
    raise ValueError(f"callback: expected one of {', '.join(CALLBACKS)} or a factory, got {kind!r}")


@contextmanager
def stepping_finer(models, substeps):
    """Each of ``models`` at its step over its ``substeps`` (the steps restored after)."""
    steps = [m.opt.timestep for m in models]
    try:
        for m, h, k in zip(models, steps, substeps):
            m.opt.timestep = h / k
        yield
    finally:
        for m, h in zip(models, steps):
            m.opt.timestep = h


def fine_rollout(model, data, start, n: int, substeps: int, nstep: int | None = None):
    """``mujoco.rollout`` of ``n`` output steps (or ``nstep`` fine steps) from one state at
    ``model.opt.timestep / substeps`` (the model's step is restored after): (the states of
    every ``substeps``-th step, all the states)."""
    with stepping_finer([model], [substeps]):
        states, _ = rollout.rollout(model, data, start, nstep=n * substeps if nstep is None else nstep)
    return states[0, substeps - 1:: substeps], states[0]


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
    plan = Stepping(setup, columns[:4])
    done = 0
    discarded = 0  # output steps computed past a tire-law switch or into a zone, and recomputed
    messages: list[str] = []
    with installed(callback), collected_warnings(messages):
        while done < steps:
            n = plan.size(steps - done)
            current_phase, fine, level = plan.phase, plan.fine, plan.substeps
            if fine:
                states, fine_states = fine_rollout(model, data, state[None, :], n, level)
            else:
                states, fine_states = rollout.rollout(model, data, state[None, :], nstep=n)[0][0], None
            keep, switch, partial = plan.keep(state, states, fine_states)
            discarded += n - keep
            if keep < n and (messages or first_warning(data) is not None) and steps_clean(state, states[:keep]):
                # the warning came from steps past the cut, which are thrown away
                data.warning.number[:] = 0
                messages.clear()
            if keep:
                record[done + 1: done + 1 + keep, : len(columns)] = states[:keep, columns]
                phase[done + 1: done + 1 + keep] = current_phase
                _check(data, states[:keep], done + keep, setup, messages)
                state = states[keep - 1].copy()
                done += keep
            if switch:
                values = setup.tire.values(1)
                sc.set_tire(values.rate, values.damping, callback)
            if partial is not None:  # the switch fell inside an output step: finish it under the new law
                at, left = partial
                _, rest = fine_rollout(model, data, fine_states[at][None, :], 0, level, nstep=left)
                plan.computed += left
                discarded -= 1  # that output step is made, not thrown away
                record[done + 1, : len(columns)] = rest[-1, columns]
                phase[done + 1] = plan.phase
                _check(data, rest, done + 1, setup, messages)
                state = rest[-1].copy()
                done += 1
            if progress is not None:
                progress(done / steps)
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


def _check(data, states, done: int, setup: Setup, messages=()) -> None:
    """Stop on a MuJoCo warning or a non-finite or runaway state, naming the time (one line)."""
    t = done * setup.timestep
    warning = first_warning(data)
    if warning is not None or messages:
        raise guard.diverged("drop", t, guard.likely_cause(warning, messages[0] if messages else None))
    if not np.all(np.isfinite(states)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(states), axis=1))[0])
        raise RunError(f"drop run diverged at t = {(done - len(states) + bad + 1) * setup.timestep:.4f} s: "
                       f"the state is not finite")
    if np.max(np.abs(states[:, 1:3])) > MAX_DISPLACEMENT_M:
        raise guard.diverged("drop", t, "a displacement beyond 10 m")

"""The drop on MuJoCo: the scene from ``mtbmj.drop.scene``, the fork law through the control callback,
the tire as calibrated soft contact, the tire-law switch applied between steps."""
from __future__ import annotations

import math
from contextlib import contextmanager

import mujoco
import numpy as np
from mujoco import rollout

from mtbmj.controllers import ForkCallback, installed
from mtbmj.drop import scene as scene_mod
from mtbmj import compose
from mtbmj.compose import Setup
from mtbmj.errors import RunError
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace


def _warning(data) -> str | None:
    for i, w in enumerate(data.warning):
        if w.number:
            return mujoco.mjtWarning(i).name.removeprefix("mjWARN_")
    return None


def _steps_clean(start, states) -> bool:
    """True if no step of ``states`` (recorded from ``start``) was reset by MuJoCo after an
    instability: their times (the first column) rise steadily from the start's."""
    times = np.concatenate(([start[0]], states[:, 0]))
    return bool(np.all(np.isfinite(states)) and np.all(np.diff(times) > 0.0))


@contextmanager
def _collected_warnings(messages: list):
    """Route MuJoCo's warning text into ``messages`` for the run (by default MuJoCo prints it
    and appends it to MUJOCO_LOG.TXT in the working directory); restore the handler after."""
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


def _state_layout(model) -> tuple[int, slice, slice, slice]:
    """Offsets of time, qpos, qvel and act in MuJoCo's full-physics state vector."""
    size = lambda spec: mujoco.mj_stateSize(model, spec)
    t = size(mujoco.mjtState.mjSTATE_TIME)
    nq, nv = size(mujoco.mjtState.mjSTATE_QPOS), size(mujoco.mjtState.mjSTATE_QVEL)
    na = size(mujoco.mjtState.mjSTATE_ACT)
    return 0, slice(t, t + nq), slice(t + nq, t + nq + nv), slice(t + nq + nv, t + nq + nv + na)


SWITCH_CHUNK_S = 0.1  # simulated time per rollout while a tire-law switch is pending (the most recomputed)
CHUNK_S = 2.0  # simulated time per rollout otherwise (each call costs setup time; progress per chunk)
# MuJoCo gives a contact at exactly zero distance no constraint row: at t = 0 the tread would
# push with neither spring nor damper for one step. Start it touching by a rounding error, as the
# ODE reference's guard takes the touchdown side at a zero distance.
TOUCH_DEPTH_M = 1e-12


CALLBACKS = ("auto", "compiled", "python")


def fork_callback(model, law, kind="auto", rim=None):
    """The fork callback for ``model``: ``"auto"`` (the compiled laws when possible, else the Python
    laws with a one-time warning), ``"compiled"``, ``"python"``, or a factory ``f(model, law)``.
    ``rim`` (a ``controllers.Rim``) adds the rim strike on the tire deflection."""
    if callable(kind):
        return kind(model, law)
    if kind == "python":
        return ForkCallback(model, law, rim=rim)
    from mtbmj.controllers import compiled  # numba is imported on the first run only

    if kind == "compiled":
        return compiled.CompiledForkCallback(model, law, rim=rim)
    if kind == "auto":
        return compiled.make_callback(model, law, rim=rim)
    raise ValueError(f"callback: expected one of {', '.join(CALLBACKS)} or a factory, got {kind!r}")


def switch_index(previous, states, columns) -> int | None:
    """The tire-law switch (``controllers.tire.SWITCH_RULE``) in a chunk of recorded states: the
    index of the first state at which the tire has left the ground (deflection <= 0 after > 0) or
    the fork has turned from extension back into compression (velocity >= 0 after < 0), or None.
    ``previous`` is the state before the chunk; ``columns`` are the sled and fork position and the
    fork velocity columns of a state row."""
    sled, fork, fork_velocity = columns
    deflection = np.concatenate(([previous[sled] - previous[fork]], states[:, sled] - states[:, fork]))
    v = np.concatenate(([previous[fork_velocity]], states[:, fork_velocity]))
    found = np.flatnonzero(((deflection[:-1] > 0.0) & (deflection[1:] <= 0.0)) | ((v[:-1] < 0.0) & (v[1:] >= 0.0)))
    return int(found[0]) if found.size else None


# A coarse step is refined (``setup.substeps`` finer steps) when, at either end, the fork or the
# tire is within this distance plus what the step can cover of a stop's or the rim's reach.
STOP_MARGIN_M = 0.2e-3
REFINED_CHUNK_S = 0.01  # simulated time per rollout at the fine step
AFTER_REFINED_CHUNK_S = 0.01  # the first coarse rollout after one: doubled while none is cut


def stop_zones(setup: Setup) -> tuple[float, float, float, float]:
    """Where the engine refines: (fork compression at the bumper or the compression stop, fork
    compression at the extension stop, tire deflection at the rim, +-inf where there is none;
    the half-width of the steep velocity band around rest, ``compose.refined_band``)."""
    spring = setup.fork.spring
    compress = getattr(spring, "bumper_start", math.inf)
    extend = -getattr(spring, "extension", math.inf)
    rim = setup.tire.rim.max_deflection if setup.tire.rim is not None else math.inf
    return compress, extend, rim, compose.refined_band(setup)


def stop_index(previous, states, columns, zones, step: float) -> int | None:
    """The index of the first step of a chunk of recorded states that a stop or the rim may have
    acted in, or in which the tire may have touched down or lifted off (see ``STOP_MARGIN_M``),
    or None. ``columns`` are the sled and fork position and
    velocity columns of a state row; ``zones`` as :func:`stop_zones`."""
    sled, fork, sled_v, fork_v = columns
    compress, extend, rim, band = zones
    rows = np.concatenate((previous[None, :], states))
    x, v = rows[:, fork], rows[:, fork_v]
    d, w = rows[:, sled] - x, rows[:, sled_v] - v

    def reach(value, rate):
        a, b = value[:-1], value[1:]
        ra, rb = np.abs(rate[:-1]), np.abs(rate[1:])
        margin = step * (ra + rb + np.abs(rate[1:] - rate[:-1])) + STOP_MARGIN_M
        return np.minimum(a, b) - margin, np.maximum(a, b) + margin

    x_low, x_high = reach(x, v)
    d_low, d_high = reach(d, w)
    # a stop, the rim, or the tire touching down or lifting off (its damping force jumps there)
    near = (x_high > compress) | (x_low < extend) | (d_high > rim) | ((d_low < 0.0) & (d_high > 0.0))
    if band > 0.0:  # the stroke velocity comes within the band of zero (or crosses it)
        a, b = v[:-1], v[1:]
        slowest = np.where(a * b <= 0.0, 0.0, np.minimum(np.abs(a), np.abs(b)) - np.abs(b - a))
        near |= slowest < band
    found = np.flatnonzero(near)
    return int(found[0]) if found.size else None


def run(setup: Setup, duration: float | None = None, progress=None, callback="auto") -> RawTrace:
    """Integrate the drop from tire touch (t = 0, both bodies at the impact speed).

    Steps run in chunks through ``mujoco.rollout`` (the loop and the recording stay in C++; the
    control callback still supplies the fork force). When the tire law switches, the chunk is cut
    at the step where the tire lifts off or the fork turns (``switch_index``), the contact is
    re-parameterised and stepping resumes from that state, exactly as if the switch had been made
    between two single steps. Where an end stop or the rim may act (``stop_index``) the chunk is
    cut before that step and stepping goes on at ``setup.fine_timestep`` (recording every
    ``setup.substeps``-th state, so the output grid stays ``setup.timestep``) until the fork and
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
    # compiled (numba) force laws read and write mjData directly; the Python laws are the fallback
    callback = fork_callback(model, setup.fork, callback, setup.tire.rim)
    callback.bind(data)
    steps = int(round(duration / setup.timestep))
    h, substeps = setup.timestep, setup.substeps
    switch_chunk = max(1, int(round(SWITCH_CHUNK_S / h)))
    chunk = max(1, int(round(CHUNK_S / h)))
    refined_chunk = max(1, int(round(REFINED_CHUNK_S / h)))
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    _, iq, iv, ia = _state_layout(model)
    fork_col = iq.start + sc.fork_qpos
    # Only the columns the trace needs are kept (sled, fork, their velocities, the friction
    # state): memory grows with the run by 40 bytes a step, not by the whole physics state.
    columns = [iq.start + sc.sled_qpos, fork_col, iv.start + sc.sled_dof, iv.start + sc.fork_dof]
    if model.na:
        columns.append(ia.start + callback.act_index)
    record = np.zeros((steps + 1, 5))
    record[0, : len(columns)] = state[columns]
    phase = np.zeros(steps + 1, dtype=np.int8)
    tire = setup.tire
    current_phase = 0
    done = 0
    discarded = 0  # steps computed past a tire-law switch or into a stop, and recomputed
    refined = 0  # output steps made at the fine step
    computed = 0  # MuJoCo steps made (fine ones each counted), discarded ones included
    sled_col = iq.start + sc.sled_qpos
    fork_vcol = iv.start + sc.fork_dof
    stop_columns = tuple(columns[:4])
    zones = stop_zones(setup)
    fine = False
    coarse_chunk = chunk
    messages: list[str] = []
    with installed(callback), _collected_warnings(messages):
        while done < steps:
            pending = tire.switches and current_phase == 0
            if fine:
                n = min(refined_chunk, steps - done)
                model.opt.timestep = h / substeps
                try:
                    states, _ = rollout.rollout(model, data, state[None, :], nstep=n * substeps)
                    computed += n * substeps
                finally:
                    model.opt.timestep = h
                states = states[0, substeps - 1:: substeps]
                refined += n
            else:
                n = min(switch_chunk if pending else coarse_chunk, steps - done)
                states, _ = rollout.rollout(model, data, state[None, :], nstep=n)
                computed += n
                states = states[0]
            keep = n
            switch = False
            if substeps > 1 and not fine:
                k = stop_index(state, states, stop_columns, zones, h)
                if k is not None:
                    keep = k
            if pending and keep:
                k = switch_index(state, states[:keep], (sled_col, fork_col, fork_vcol))
                if k is not None:
                    keep = k + 1
                    switch = True
            discarded += n - keep
            if keep < n and (messages or _warning(data) is not None) and _steps_clean(state, states[:keep]):
                # the warning came from steps past the cut, which are thrown away
                data.warning.number[:] = 0
                messages.clear()
            if keep:
                record[done + 1: done + 1 + keep, : len(columns)] = states[:keep, columns]
                phase[done + 1: done + 1 + keep] = current_phase
                _check(data, states[:keep], done + keep, setup, messages)
                previous = state if keep == 1 else states[keep - 2]
                state = states[keep - 1].copy()
                done += keep
            if fine:  # back to the coarse step once the last step is clear of every stop
                fine = stop_index(previous, state[None, :], stop_columns, zones, h) is not None
                coarse_chunk = max(1, int(round(AFTER_REFINED_CHUNK_S / h)))
            elif keep < n and not switch:
                fine = True
            elif keep == n:
                coarse_chunk = min(chunk, 2 * coarse_chunk)
            if switch:
                current_phase = 1
                values = tire.values(1)
                sc.set_tire(values.rate, values.damping)
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
        info={"steps": steps, "steps_discarded": discarded, "steps_refined": refined, "substeps": substeps,
              "steps_computed": computed, "callback_calls": callback.calls, "integrator": setup.integrator,
              "timestep_s": setup.timestep, "contact_inverse_inertia_per_kg": sc.inverse_inertia},
    )


def _check(data, states, done: int, setup: Setup, messages=()) -> None:
    """Stop on a MuJoCo warning or a non-finite or runaway state, naming the time."""
    t = done * setup.timestep
    warning = _warning(data)
    if warning is not None or messages:
        text = messages[0] if messages else warning
        raise RunError(f"run diverged before t = {t:.4f} s: MuJoCo warning {warning}: {text}")
    if not np.all(np.isfinite(states)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(states), axis=1))[0])
        raise RunError(f"run diverged at t = {(done - len(states) + bad + 1) * setup.timestep:.4f} s: state is not finite")
    if np.max(np.abs(states[:, 1:3])) > MAX_DISPLACEMENT_M:
        raise RunError(f"run diverged before t = {t:.4f} s: displacement beyond 10 m")

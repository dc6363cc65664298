"""The drop on MuJoCo: the scene from ``mtbmj.drop.scene``, the fork law through the control callback,
the tire as calibrated soft contact, the tire-law switch applied between steps."""
from __future__ import annotations

import math
from contextlib import contextmanager

import mujoco
import numpy as np
from mujoco import rollout

from mtbmj.controllers import ForkCallback, installed, native
from mtbmj.drop import scene as scene_mod
from mtbmj import compose
from mtbmj.compose import Setup
from mtbmj.errors import RunError
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace


def _warning(data) -> str | None:
    raised = np.flatnonzero(data.warning.number)  # one array read (iterating the structs costs 0.1 ms)
    return mujoco.mjtWarning(int(raised[0])).name.removeprefix("mjWARN_") if raised.size else None


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


STOP_MARGIN_M = compose.STOP_MARGIN_M  # see stop_index
REFINED_CHUNK_S = 0.01  # simulated time per rollout at the fine step
AFTER_REFINED_CHUNK_S = 0.01  # the first coarse rollout after one: doubled while none is cut


def stop_index(previous, states, columns, zones, step: float, stops_only: bool = False) -> int | None:
    """The index of the first step of a chunk of recorded states that a stop or the rim may have
    acted in, or in which the tire may have touched down or lifted off (see ``STOP_MARGIN_M``),
    or None; with ``stops_only``, of a stop or the rim only. ``columns`` are the sled and fork
    position and velocity columns of a state row; ``zones`` as ``compose.refine_zones``."""
    sled, fork, sled_v, fork_v = columns
    compress, extend, rim, band, fast = zones
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
    near = (x_high > compress) | (x_low < extend) | (d_high > rim)  # a stop or the rim
    if stops_only:
        found = np.flatnonzero(near)
        return int(found[0]) if found.size else None
    near |= (d_low < 0.0) & (d_high > 0.0)  # the tire touching down or lifting off (its damping force jumps)
    if band > 0.0:  # the stroke velocity comes within the band of zero (or crosses it)
        a, b = v[:-1], v[1:]
        slowest = np.where(a * b <= 0.0, 0.0, np.minimum(np.abs(a), np.abs(b)) - np.abs(b - a))
        near |= slowest < band
    if fast < math.inf:  # the stroke speed may pass the friction state's limit within the step
        a, b = np.abs(v[:-1]), np.abs(v[1:])
        near |= np.maximum(a, b) + np.abs(v[1:] - v[:-1]) > fast
    found = np.flatnonzero(near)
    return int(found[0]) if found.size else None


class Stepping:
    """The stepping decisions of one drop run, shared by :func:`run` and the batched sweep:
    how many output steps the next rollout makes and at which step (:meth:`size`, ``fine``),
    and, from what it returned, how many to keep and what comes next (:meth:`keep`).

    ``columns`` are the sled and fork position and velocity columns of a recorded state row.
    Chunks are sized in simulated time; at the coarse step they start short after a refined
    stretch (a cut discards the rest of a chunk) and double while none is cut. ``computed`` and
    ``refined`` count the MuJoCo steps and the refined output steps of the rollouts handed to
    :meth:`keep` (a caller adds the fine steps that finish a switch's output step).
    """

    def __init__(self, setup: Setup, columns):
        h = setup.timestep
        self.setup = setup
        # fine steps per output step: near a stop or the rim, and in the other zones
        self.stop_level = setup.substeps
        self.contact_level = min(setup.contact_substeps or setup.substeps, setup.substeps)
        self.substeps = self.stop_level  # the level of the next fine rollout
        self.stop_columns = tuple(columns)
        sled, fork, _, fork_v = self.stop_columns
        self.switch_columns = (sled, fork, fork_v)
        self.zones = compose.refine_zones(setup)
        self.chunk = max(1, int(round(CHUNK_S / h)))
        self.switch_chunk = max(1, int(round(SWITCH_CHUNK_S / h)))
        self.refined_chunk = max(1, int(round(REFINED_CHUNK_S / h)))
        self.after_refined = min(self.chunk, max(1, int(round(AFTER_REFINED_CHUNK_S / h))))
        self.coarse_chunk = self.after_refined if self.stop_level > 1 else self.chunk
        self.fine = False
        self.phase = 0
        self.computed = 0  # MuJoCo steps made (fine ones each counted), discarded ones included
        self.refined = 0  # output steps made at a fine step

    @property
    def pending(self) -> bool:
        """The tire-law switch is still to come."""
        return self.setup.tire.switches and self.phase == 0

    def size(self, remaining: int) -> int:
        """Output steps for the next rollout (at ``setup.timestep / substeps`` if ``fine``)."""
        if self.fine:
            return min(self.refined_chunk, remaining)
        return min(min(self.switch_chunk, self.coarse_chunk) if self.pending else self.coarse_chunk, remaining)

    def _level(self, before, step) -> int:
        """The fine level for output step ``step`` (a one-row array) from state ``before``: the
        stops' where a stop or the rim may act in it, else the other zones'."""
        near = stop_index(before, step, self.stop_columns, self.zones, self.setup.timestep, stops_only=True)
        return self.stop_level if near is not None else self.contact_level

    def keep(self, previous, states, fine_states=None) -> tuple[int, bool, tuple | None]:
        """(how many of ``states``, recorded from ``previous``, to keep; whether the tire law
        switches after them; ``None``, or (i, m) when it switches inside the next output step:
        after fine state ``fine_states[i]``, with ``m`` fine steps left to finish that output
        step under the new law), and the mode of the next rollout.

        At the fine step ``fine_states`` are all the states the output ``states`` were taken
        from (at ``substeps`` per output step, the level this rollout was made at), and the
        switch is made at the fine step it falls in. At a coarse step that may hold the switch,
        the chunk is cut before that step and stepped finely: the switch lands within a fine
        step, as the reference's event does (1 ms late, it moved a random S12 fork 0.7 mm).
        Stepped finely at the other zones' level, a chunk is cut where a stop or the rim comes
        within reach, and goes on at the stops' level."""
        n = len(states)
        level = self.substeps
        self.computed += n if fine_states is None else len(fine_states)
        self.refined += 0 if fine_states is None else n
        keep, switch, partial = n, False, None
        if self.stop_level > 1 and not self.fine:
            k = stop_index(previous, states, self.stop_columns, self.zones, self.setup.timestep)
            if k is not None:
                keep = k
        elif self.fine and level < self.stop_level:
            k = stop_index(previous, states, self.stop_columns, self.zones, self.setup.timestep, stops_only=True)
            if k is not None:
                keep = k
        if self.pending and keep:
            if fine_states is not None:
                k = switch_index(previous, fine_states[: keep * level], self.switch_columns)
                if k is not None:
                    whole, part = divmod(k + 1, level)
                    keep, switch = whole, True
                    if part:
                        partial = (k, level - part)
            else:
                k = switch_index(previous, states[:keep], self.switch_columns)
                if k is not None and self.stop_level > 1:
                    keep = k  # refine the step that holds it
                elif k is not None:
                    keep, switch = k + 1, True
        if switch and self.fine:
            pass  # stays fine for one more chunk: the exit is judged on whole output steps
        elif self.fine and keep < n:  # a stop came within reach: on at the stops' level
            self.substeps = self.stop_level
        elif self.fine:  # back to the coarse step once the last step is clear of every zone
            before = previous if keep == 1 else states[keep - 2]
            self.fine = stop_index(before, states[keep - 1: keep], self.stop_columns, self.zones,
                                   self.setup.timestep) is not None
            if self.fine:
                self.substeps = self._level(before, states[keep - 1: keep])
            self.coarse_chunk = self.after_refined
        elif keep < n and not switch:
            self.fine = True
            self.substeps = self._level(previous if keep == 0 else states[keep - 1], states[keep: keep + 1])
        elif keep == n:
            self.coarse_chunk = min(self.chunk, 2 * self.coarse_chunk)
        if switch:
            self.phase = 1
        return keep, switch, partial


def fine_rollout(model, data, start, n: int, substeps: int, nstep: int | None = None):
    """``mujoco.rollout`` of ``n`` output steps (or ``nstep`` fine steps) from one state at
    ``model.opt.timestep / substeps`` (the model's step is restored after): (the states of
    every ``substeps``-th step, all the states)."""
    h = model.opt.timestep
    model.opt.timestep = h / substeps
    try:
        states, _ = rollout.rollout(model, data, start, nstep=n * substeps if nstep is None else nstep)
    finally:
        model.opt.timestep = h
    return states[0, substeps - 1:: substeps], states[0]


def run(setup: Setup, duration: float | None = None, progress=None, callback="auto") -> RawTrace:
    """Integrate the drop from tire touch (t = 0, both bodies at the impact speed).

    Steps run in chunks through ``mujoco.rollout`` (the loop and the recording stay in C++; the
    control callback still supplies the fork force). When the tire law switches, the chunk is cut
    at the step where the tire lifts off or the fork turns (``switch_index``), the contact is
    re-parameterised and stepping resumes from that state, exactly as if the switch had been made
    between two single steps. Where an end stop or the rim may act (``stop_index``) the chunk is
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
    _, iq, iv, ia = _state_layout(model)
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
    with installed(callback), _collected_warnings(messages):
        while done < steps:
            n = plan.size(steps - done)
            current_phase, fine, level = plan.phase, plan.fine, plan.substeps
            if fine:
                states, fine_states = fine_rollout(model, data, state[None, :], n, level)
            else:
                states, fine_states = rollout.rollout(model, data, state[None, :], nstep=n)[0][0], None
            keep, switch, partial = plan.keep(state, states, fine_states)
            discarded += n - keep
            if keep < n and (messages or _warning(data) is not None) and _steps_clean(state, states[:keep]):
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

"""The batched MuJoCo drop engine: many drops (one configuration, a set of overrides each)
stepped together through ``mujoco.rollout`` on the compiled force laws, each with the same
numbers as ``run_drop(config, "mujoco", overrides)``. The sweep's default runner
(``mtbmj.sweep.batch``) and the drop fit's Jacobian (``drop_traces``) run on it.

How a batch runs
----------------
* **Prepare** each drop as ``run_drop`` does (``chain.prepare``: overrides, ``compose.setup``
  with its checks; the scene, the initial state at tire touch), one ``mjModel`` per drop:
  ``mujoco.rollout`` takes a list of models, one per initial state, and the compiled dispatcher
  (``controllers.compiled``) serves each model's own fork law by its ``mjModel*``. Scenes are
  compiled once per distinct geometry/mass/solver set and copied (the compiled model depends on
  nothing else; the tire's solref is set per drop).
* **Step** in rounds: every round advances the drops at their coarse step by the same number
  of steps in one rollout call (``threads`` MjData, i.e. threads, per process), and the drops
  at their fine steps (near a stop, the rim, touchdown, fast sliding) in one call of their own
  on those threads (``_fine_together``; on one thread, a call each); the
  decisions are the engine's own (``stepping.Stepping``): where a drop's chunk is cut (a
  zone ahead, the tire-law switch), it keeps its states up to that step, its model gets the new
  tire solref if the law switched, and it goes on from there in the next round (steps past the
  cut are discarded, as the engine does). Chunk boundaries change MuJoCo's results only through
  the contact solver's warm start (about 1e-11 mm), so the batched traces equal the engine's.
* **Finish** each drop with ``chain.finish`` on only what the summary needs (``channels``: the
  tire force along the trace, not the fork force; the logger's filter on the three
  displacements), then the summary itself (the same detector and rest/energy code as
  ``run_drop``).
* **Anything unusual** (a bad parameter, a fork law without a compiled form, a MuJoCo reset after
  a warning in the steps kept, a non-finite or runaway state, a numpy RuntimeWarning in the
  post-processing) leaves the drop unfinished: ``run`` reports it and the caller runs it alone
  (``run_drop``), which raises what it meets; the other drops of the batch go on.
"""
from __future__ import annotations

import copy
import time
import warnings
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout as _rollout

from mtbmj.controllers import installed, native
from mtbmj.drop import chain, engine_mujoco
from mtbmj.drop import scene as scene_mod
from mtbmj.drop.stepping import Stepping
from mtbmj.runpath import guard, loop
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace

CHANNELS = ("sled", "fork", "tire")  # the logged displacements a batched drop returns

MAX_ROUND = 20000  # steps per round otherwise
ROUND_BUFFER_VALUES = 4_000_000  # cap on nbatch * nstep * nstate of one round's state buffer (32 MB)
MAX_BATCH = 64  # drops stepped together (more run in slices)

_SCENES: dict = {}  # per process: compiled scenes by what ``scene.build`` depends on
_SCENE_CACHE_SIZE = 64


def _scene_key(setup) -> tuple:
    return (setup.timestep, setup.integrator, setup.gravity, setup.body_mass, setup.wheel_mass,
            setup.fork_length, setup.tire_radius)


def build_scene(setup) -> scene_mod.DropScene:
    """``scene.build(setup)``, compiled once per distinct geometry/mass/solver set and copied."""
    key = _scene_key(setup)
    proto = _SCENES.get(key)
    if proto is None:
        proto = scene_mod.build(setup)
        if len(_SCENES) >= _SCENE_CACHE_SIZE:
            _SCENES.pop(next(iter(_SCENES)))
        _SCENES[key] = proto
    sc = copy.copy(proto)
    sc.model = copy.deepcopy(proto.model)
    first = setup.tire.values(0)
    sc.set_tire(first.rate, first.damping)
    return sc


@dataclass
class _Run:
    """One drop in flight (``index``: its place in the caller's list)."""

    index: int
    setup: object
    scene: scene_mod.DropScene
    callback: object
    steps: int
    record: np.ndarray  # (steps + 1, nstate)
    phase: np.ndarray
    done: int = 0
    discarded: int = 0
    failed: bool = False
    extra: dict = field(default_factory=dict)
    plan: Stepping | None = None


def prepare(config, overrides, duration, index: int, spec) -> _Run:
    """What ``run_drop`` and ``engine_mujoco.run`` do before stepping (raises as they do)."""
    from mtbmj.controllers.compiled import CompiledForkCallback

    _, setup = chain.prepare(config, overrides, duration)
    duration = setup.duration if duration is None else duration
    sc = build_scene(setup)
    model = sc.model
    data = mujoco.MjData(model)
    data.qvel[sc.sled_dof] = setup.impact_speed
    data.qpos[sc.sled_qpos] = engine_mujoco.TOUCH_DEPTH_M
    mujoco.mj_forward(model, data)
    callback = CompiledForkCallback(model, setup.fork, count_calls=False, rim=setup.tire.rim, floor=sc.floor())  # UnsupportedLaw: single path
    steps = int(round(duration / setup.timestep))
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    record = np.empty((steps + 1, state.size))
    record[0] = state
    _, iq, iv, _ = engine_mujoco.state_layout(model)
    columns = (iq.start + sc.sled_qpos, iq.start + sc.fork_qpos, iv.start + sc.sled_dof, iv.start + sc.fork_dof)
    return _Run(index, setup, sc, callback, steps, record, np.zeros(steps + 1, dtype=np.int8),
                plan=Stepping(setup, columns))


def _signature(run: _Run) -> tuple:
    m = run.scene.model
    return (m.nq, m.nv, m.na, m.nu, run.record.shape[1])


def step_group(runs: list[_Run], datas, pool, spec) -> None:
    """Advance ``runs`` (same model sizes) to their ends in rounds: one rollout call for the runs
    at their coarse step, one for each run at its fine step (``stepping.Stepping`` decides,
    as for a single run)."""
    nstate = runs[0].record.shape[1]
    messages: list[str] = []
    active = [r for r in runs if r.steps > 0]
    size = min(ROUND_BUFFER_VALUES, len(active) * min(MAX_ROUND, max((r.steps for r in active), default=1)) * nstate)
    buffer = np.empty(max(size, nstate))  # one state buffer for all rounds (views of it, C-contiguous)
    with guard.collected_warnings(messages):
        while active:
            made = []
            coarse = [r for r in active if not r.plan.fine]
            if coarse:
                n = min(r.plan.size(r.steps - r.done) for r in coarse)
                n = max(1, min(n, MAX_ROUND, buffer.size // (len(coarse) * nstate)))
                start = np.array([r.record[r.done] for r in coarse])
                out = buffer[: len(coarse) * n * nstate].reshape(len(coarse), n, nstate)
                models = [r.scene.model for r in coarse]
                if pool is None:
                    _rollout.rollout(models, datas[0], start, nstep=n, state=out)
                else:
                    pool.rollout(models, datas, start, nstep=n, state=out)
                made += [(r, states, None) for r, states in zip(coarse, out)]
            fine = [r for r in active if r.plan.fine]
            if pool is not None and len(fine) > 1:
                made += _fine_together(fine, datas, pool)
            else:
                for r in fine:
                    n = r.plan.size(r.steps - r.done)
                    states, _, fine_states = loop.roll(r.scene.model, datas[0], r.record[r.done], n, r.plan.substeps)
                    made.append((r, states, fine_states))
            # A warning is not traced to its drop: a run whose kept steps show no reset (MuJoCo
            # restarts a run that goes unstable) is sound; the others go to the single path.
            warned = bool(messages) or any(d.warning.number.any() for d in datas)
            still = []
            for r, states, fine_states in made:
                start = r.record[r.done]
                phase, level = r.plan.phase, r.plan.substeps
                keep, switch, partial = r.plan.keep(start, states, fine_states)
                kept = states[:keep]
                if (not np.all(np.isfinite(kept)) or (keep and np.max(np.abs(kept[:, 1:3])) > MAX_DISPLACEMENT_M)
                        or (warned and not guard.steps_clean(start, kept))):
                    r.failed = True  # the single path says where and why
                    continue
                r.discarded += len(states) - keep
                r.record[r.done + 1: r.done + 1 + keep] = kept
                r.phase[r.done + 1: r.done + 1 + keep] = phase
                r.done += keep
                if switch:
                    values = r.setup.tire.values(1)
                    r.scene.set_tire(values.rate, values.damping, r.callback)
                if partial is not None:  # as engine_mujoco.run: finish the output step under the new law
                    at, left = partial
                    _, _, rest = loop.roll(r.scene.model, datas[0], fine_states[at], 0, level, nstep=left)
                    r.plan.computed += left
                    if not np.all(np.isfinite(rest)):
                        r.failed = True
                        continue
                    r.discarded -= 1
                    r.record[r.done + 1] = rest[-1]
                    r.phase[r.done + 1] = r.plan.phase
                    r.done += 1
                if r.done < r.steps:
                    still.append(r)
            if warned:
                for d in datas:
                    d.warning.number[:] = 0
                messages.clear()
            active = still


def _fine_together(runs: list[_Run], datas, pool) -> list[tuple]:
    """The runs at their fine steps in one rollout call on the pool's threads: each its own plan's
    output steps (``plan.size``) at its own fine step (its model's step over ``plan.substeps``), as
    ``mtbmj.runpath.loop.roll`` steps it alone; the call makes as many fine steps as the longest
    needs, and a run's steps past its own are dropped (its decisions are its plan's, unchanged).
    (run, output states, fine states) per run."""
    sizes = [(r.plan.size(r.steps - r.done), r.plan.substeps) for r in runs]
    nstep = max(n * k for n, k in sizes)
    models = [r.scene.model for r in runs]
    start = np.array([r.record[r.done] for r in runs])
    with engine_mujoco.stepping_finer(models, [k for _, k in sizes]):
        out = pool.rollout(models, datas, start, nstep=nstep)[0]
    made = []
    for r, states, (n, k) in zip(runs, out, sizes):
        fine_states = states[: n * k]
        made.append((r, fine_states[k - 1:: k], fine_states))
    return made


def trace_of(run: _Run) -> RawTrace:
    """The ``RawTrace`` of a finished run, as ``engine_mujoco.run`` returns it."""
    sc, setup, record = run.scene, run.setup, run.record
    model = sc.model
    _, iq, iv, ia = engine_mujoco.state_layout(model)
    return RawTrace(
        engine="mujoco",
        time=np.arange(run.steps + 1) * setup.timestep,
        sled=record[:, iq.start + sc.sled_qpos],
        fork=record[:, iq.start + sc.fork_qpos],
        sled_velocity=record[:, iv.start + sc.sled_dof],
        fork_velocity=record[:, iv.start + sc.fork_dof],
        friction_state=record[:, ia.start + run.callback.act_index] if model.na else np.zeros(run.steps + 1),
        tire_phase=run.phase,
        info={"steps": run.steps, "steps_discarded": run.discarded, "steps_refined": run.plan.refined,
              "substeps": setup.substeps, "contact_substeps": run.plan.contact_level,
              "steps_computed": run.plan.computed, "integrator": setup.integrator,
              "timestep_s": setup.timestep, "contact_inverse_inertia_per_kg": sc.inverse_inertia},
    )


def finish(run: _Run) -> chain.Finished:
    """The summary and the logged displacements of a finished run, as ``run_drop`` computes them
    (``chain.finish`` on ``CHANNELS``)."""
    return chain.finish(run.setup, trace_of(run), "mujoco", channels=CHANNELS)


def available() -> bool:
    """The batched engine can run: the compiled laws are there."""
    from mtbmj.controllers import compiled

    return compiled.available()


def run(config, overrides: list, duration: float | None = None, threads: int = 1):
    """The drops ``(config, o, duration)`` for each override set ``o`` of ``overrides``, stepped
    together through ``mujoco.rollout`` on ``threads`` threads, in slices of ``MAX_BATCH`` (each
    drop holds a compiled-law registry slot while it runs). Yields, slice by slice, ``(index,
    finished, wall_time_s)``: ``finished`` is the drop's ``chain.Finished`` (summary and logged
    ``CHANNELS``, the numbers of ``run_drop(config, "mujoco", o, duration)``) or None for a drop
    to be run alone (see the module doc); first the finished drops of the slice, then the
    others. ``config`` is a resolved ``Config``; requires the compiled laws (``available``)."""
    for at in range(0, len(overrides), MAX_BATCH):
        yield from _run_slice(config, list(enumerate(overrides))[at: at + MAX_BATCH], duration, threads)


def drop_traces(config, overrides: list[dict], duration: float | None = None, threads: int = 1) -> list:
    """The logged signals of ``run_drop(config, "mujoco", o, duration)`` for each override set
    ``o``, stepped as one batch (``run``): per set, in order, a dict ``{"time_s", "sled_mm",
    "fork_mm", "tire_mm": arrays}`` or, for a run that fails, its reason (a string, as a sweep
    records it: ``chain.failure_reason``). ``config`` is a resolved ``Config``. Without the
    compiled laws every drop runs alone."""
    out: list = [None] * len(overrides)
    batched = run(config, overrides, duration, max(1, int(threads))) if available() else (
        (i, None, 0.0) for i in range(len(overrides)))
    for i, finished, _ in batched:
        out[i] = _traces(finished.logged) if finished is not None else _alone(config, overrides[i], duration)
    return out


def _traces(log: dict) -> dict:
    return {"time_s": np.asarray(log["time_s"], dtype=float),
            **{f"{c}_mm": np.asarray(log[f"{c}_mm"], dtype=float) for c in CHANNELS}}


def _alone(config, overrides: dict, duration) -> dict | str:
    """One drop through ``run_drop`` (numpy warnings as errors): its logged displacements, or the
    reason it failed."""
    from mtbmj.drop.run import run_drop

    native.expect_many()  # many drops repay loading the compiled laws
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)  # as a sweep's single path does
            result = run_drop(config, "mujoco", overrides, duration)
    except Exception as exc:  # noqa: BLE001 - a failed drop is a reason, not an exception
        return chain.failure_reason(exc)
    return _traces(result.signals)


def _run_slice(config, indexed: list, duration, threads: int) -> list[tuple]:
    start = time.perf_counter()
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    threads = max(1, int(threads or 1))
    runs: list[_Run] = []
    alone: list[int] = []
    finished: list[tuple] = []
    try:
        for i, o in indexed:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", RuntimeWarning)
                    runs.append(prepare(config, o, duration, i, spec))
            except Exception:  # noqa: BLE001 - the single path says why
                alone.append(i)

        groups: dict[tuple, list[_Run]] = {}
        for r in runs:
            groups.setdefault(_signature(r), []).append(r)
        pool = _rollout.Rollout(nthread=threads) if threads > 1 and len(runs) > 1 else None
        try:
            for group in groups.values():
                datas = [mujoco.MjData(group[0].scene.model) for _ in range(threads if pool else 1)]
                with installed(group[0].callback):
                    step_group(group, datas, pool, spec)
        finally:
            if pool is not None:
                pool.close()

        for r in runs:
            if r.failed:
                alone.append(r.index)
                continue
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", RuntimeWarning)  # as the single path does
                    finished.append((r.index, finish(r)))
            except Exception:  # noqa: BLE001
                alone.append(r.index)
    finally:
        for r in runs:
            r.callback.close()  # free the registry slots now
    each = (time.perf_counter() - start) / len(finished) if finished else 0.0
    return [(i, done, each) for i, done in finished] + [(i, None, 0.0) for i in alone]


__all__ = ["run", "available", "drop_traces", "build_scene", "prepare", "step_group", "trace_of", "finish",
           "CHANNELS", "MAX_BATCH"]

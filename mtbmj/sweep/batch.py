"""Batched sweep runner: a batch of variants stepped together through ``mujoco.rollout`` on the
compiled force laws, with a vectorised post-processing. A drop-in ``runner`` for
``mtbmj.sweep.runner.run_sweep`` (the default for the MuJoCo engine); records equal those of
:func:`mtbmj.sweep.runner.run_batch` (which calls ``run_drop`` per variant).

How a batch runs
----------------
* **Prepare** each variant as ``run_drop`` does (overrides, ``compose.setup`` with its checks, the
  scene, the initial state at tire touch), one ``mjModel`` per variant: ``mujoco.rollout`` takes a
  list of models, one per initial state, and the compiled dispatcher
  (``controllers.compiled``) serves each model's own fork law by its ``mjModel*``. Scenes are
  compiled once per distinct geometry/mass/solver set and copied (the compiled model depends on
  nothing else; the tire's solref is set per variant).
* **Step** in rounds: every round advances the variants at their coarse step by the same number
  of steps in one rollout call (``threads`` MjData, i.e. threads, per process), and each variant
  at its fine step (near a stop, the rim, touchdown, fast sliding) in a call of its own; the
  decisions are the engine's own (``engine_mujoco.Stepping``): where a variant's chunk is cut (a
  zone ahead, the tire-law switch), it keeps its states up to that step, its model gets the new
  tire solref if the law switched, and it goes on from there in the next round (steps past the
  cut are discarded, as the engine does). Chunk boundaries change MuJoCo's results only through
  the contact solver's warm start (about 1e-11 mm), so the batched traces equal the engine's.
* **Post-process** each variant with only what the summary needs: the tire force along the trace
  vectorised with numpy (the fork force is not part of the summary), the logger's filter and
  decimation on the three displacement signals only, then ``events.summarize`` itself (the same
  detector and rest/energy code as ``run_drop``).
* **Anything unusual** (a bad parameter, a fork law without a compiled form, a MuJoCo reset after
  a warning in the steps kept, a non-finite or runaway state, a numpy RuntimeWarning in the post-processing) sends the variant to
  the single-variant path (``sweep.run_variant``), which records it exactly as the old runner
  does, with its reason; the other variants of the batch go on.
"""
from __future__ import annotations

import copy
import time
import warnings
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout as _rollout

from mtbmj import compose
from mtbmj.drop import engine_mujoco
from mtbmj.drop import events
from mtbmj.drop import measure
from mtbmj.drop.measure import tire_forces
from mtbmj.drop import scene as scene_mod
from mtbmj.controllers import installed
from mtbmj.sweep.variants import SIGNALS, BatchJob, Variant, flatten_summary
from mtbmj.sweep.single import run_batch, run_variant
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace

MAX_ROUND = 20000  # steps per round otherwise
ROUND_BUFFER_VALUES = 4_000_000  # cap on nbatch * nstep * nstate of one round's state buffer (32 MB)
MAX_BATCH = 64  # variants stepped together (a larger job runs in slices)

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
    """One variant in flight."""

    variant: Variant
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
    plan: engine_mujoco.Stepping | None = None


def setup_of(cfg):
    """``compose.setup(cfg)``: laws in SI and the step chosen by the step rule."""
    return compose.setup(cfg)


def _prepare(job: BatchJob, variant: Variant, spec) -> _Run:
    """What ``run_drop`` and ``engine_mujoco.run`` do before stepping (raises as they do)."""
    from mtbmj.controllers.compiled import CompiledForkCallback
    from mtbmj.drop.run import resolve
    from mtbmj.errors import ConfigError

    cfg = resolve(job.config, variant.overrides)
    if job.duration is not None and not job.duration > 0:
        raise ConfigError(f"duration: must be positive, got {job.duration}")
    setup = setup_of(cfg)
    duration = setup.duration if job.duration is None else job.duration
    from mtbmj.limits import check_run

    check_run(duration, setup.timestep, setup.sample_rate)
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
    _, iq, iv, _ = engine_mujoco._state_layout(model)
    columns = (iq.start + sc.sled_qpos, iq.start + sc.fork_qpos, iv.start + sc.sled_dof, iv.start + sc.fork_dof)
    return _Run(variant, setup, sc, callback, steps, record, np.zeros(steps + 1, dtype=np.int8),
                plan=engine_mujoco.Stepping(setup, columns))


def _signature(run: _Run) -> tuple:
    m = run.scene.model
    return (m.nq, m.nv, m.na, m.nu, run.record.shape[1])


def _step_group(runs: list[_Run], datas, pool, spec) -> None:
    """Advance ``runs`` (same model sizes) to their ends in rounds: one rollout call for the runs
    at their coarse step, one for each run at its fine step (``engine_mujoco.Stepping`` decides,
    as for a single run)."""
    nstate = runs[0].record.shape[1]
    messages: list[str] = []
    active = [r for r in runs if r.steps > 0]
    size = min(ROUND_BUFFER_VALUES, len(active) * min(MAX_ROUND, max((r.steps for r in active), default=1)) * nstate)
    buffer = np.empty(max(size, nstate))  # one state buffer for all rounds (views of it, C-contiguous)
    with engine_mujoco._collected_warnings(messages):
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
            for r in active:
                if r.plan.fine:
                    n = r.plan.size(r.steps - r.done)
                    states, fine_states = engine_mujoco.fine_rollout(r.scene.model, datas[0], r.record[r.done][None, :],
                                                                     n, r.plan.substeps)
                    made.append((r, states, fine_states))
            # A warning is not traced to its variant: a run whose kept steps show no reset (MuJoCo
            # restarts a run that goes unstable) is sound; the others go to the single path.
            warned = bool(messages) or any(d.warning.number.any() for d in datas)
            still = []
            for r, states, fine_states in made:
                start = r.record[r.done]
                phase, level = r.plan.phase, r.plan.substeps
                keep, switch, partial = r.plan.keep(start, states, fine_states)
                kept = states[:keep]
                if (not np.all(np.isfinite(kept)) or (keep and np.max(np.abs(kept[:, 1:3])) > MAX_DISPLACEMENT_M)
                        or (warned and not engine_mujoco._steps_clean(start, kept))):
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
                    _, rest = engine_mujoco.fine_rollout(r.scene.model, datas[0], fine_states[at][None, :], 0,
                                                         level, nstep=left)
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


def _trace(run: _Run) -> RawTrace:
    sc, setup, record = run.scene, run.setup, run.record
    model = sc.model
    _, iq, iv, ia = engine_mujoco._state_layout(model)
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


def logged(setup, raw: dict, names) -> dict:
    """``measure.logged`` for the signals ``names`` only."""
    return measure.logged(setup, {"time_s": raw["time_s"], **{name: raw[name] for name in names}})


def summarize(run: _Run) -> tuple[dict, dict]:
    """(summary, logged displacement signals) of a finished run, as ``run_drop`` computes them."""
    trace = _trace(run)
    for name in ("sled", "fork", "sled_velocity", "fork_velocity", "friction_state"):
        if not np.all(np.isfinite(getattr(trace, name))):
            raise FloatingPointError(name)  # the single path reports it
    setup = run.setup
    tire = trace.tire
    raw = {
        "time_s": trace.time,
        "sled_mm": trace.sled * 1e3,
        "fork_mm": trace.fork * 1e3,
        "tire_mm": tire * 1e3,
        "tire_force_N": tire_forces(setup.tire, tire, trace.tire_velocity, trace.tire_phase),
        "fork_velocity_mm_per_s": trace.fork_velocity * 1e3,
        "tire_velocity_mm_per_s": trace.tire_velocity * 1e3,
    }
    log = logged(setup, raw, [f"{s}_mm" for s in SIGNALS])
    return events.summarize(setup, trace, log, raw), log


def run_batch_rollout(job: BatchJob) -> list[dict]:
    """The batched runner: the variants of ``job`` stepped together through ``mujoco.rollout`` on
    ``job.threads`` threads (default 1) with the compiled force laws; same records as
    :func:`mtbmj.sweep.runner.run_batch`. Falls back to ``run_batch`` for another engine, a custom
    ``job.drop`` or when the compiled laws are unavailable. A large batch runs in slices of
    ``MAX_BATCH`` variants (each variant holds a compiled-law registry slot while it runs)."""
    from mtbmj.controllers import compiled

    if job.engine != "mujoco" or job.drop is not None or not compiled.available():
        return run_batch(job)
    records: list[dict] = []
    for at in range(0, len(job.variants), MAX_BATCH):
        records.extend(_run_slice(job, job.variants[at: at + MAX_BATCH]))
    return records


def drop_traces(config, overrides: list[dict], duration: float | None = None, threads: int = 1) -> list:
    """The logged signals of ``run_drop(config, "mujoco", o, duration)`` for each override set
    ``o``, stepped as one batch (``run_batch_rollout`` with traces): per set, in order, a dict
    ``{"time_s", "sled_mm", "fork_mm", "tire_mm": arrays}`` or, for a run that fails, its reason
    (a string). ``config`` is a resolved ``Config``."""
    variants = [Variant(i, str(i), dict(o)) for i, o in enumerate(overrides)]
    job = BatchJob(config, "mujoco", duration, variants, traces=True, threads=max(1, int(threads)))
    by_id = {rec["id"]: rec for rec in run_batch_rollout(job)}
    return [by_id[v.id]["traces"] if by_id[v.id]["status"] == "ok" else by_id[v.id]["reason"] for v in variants]


def _run_slice(job: BatchJob, variants: list[Variant]) -> list[dict]:
    start = time.perf_counter()
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    threads = max(1, int(getattr(job, "threads", 1) or 1))
    runs: list[_Run] = []
    single: list[Variant] = []
    outputs: list[dict] = []
    try:
        for v in variants:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", RuntimeWarning)
                    runs.append(_prepare(job, v, spec))
            except Exception:  # noqa: BLE001 - the single path records it with its reason
                single.append(v)

        groups: dict[tuple, list[_Run]] = {}
        for r in runs:
            groups.setdefault(_signature(r), []).append(r)
        pool = _rollout.Rollout(nthread=threads) if threads > 1 and len(runs) > 1 else None
        try:
            for group in groups.values():
                datas = [mujoco.MjData(group[0].scene.model) for _ in range(threads if pool else 1)]
                with installed(group[0].callback):
                    _step_group(group, datas, pool, spec)
        finally:
            if pool is not None:
                pool.close()

        for r in runs:
            if r.failed:
                single.append(r.variant)
                continue
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", RuntimeWarning)  # as the single path does
                    summary, log = summarize(r)
                rec = {"id": r.variant.id, "status": "ok", "reason": "", "outputs": flatten_summary(summary)}
                rec["traces"] = ({"time_s": np.asarray(log["time_s"], dtype=float),
                                  **{f"{s}_mm": np.asarray(log[f"{s}_mm"], dtype=float) for s in SIGNALS}}
                                 if job.traces else None)
                outputs.append(rec)
            except Exception:  # noqa: BLE001
                single.append(r.variant)
    finally:
        for r in runs:
            r.callback.close()  # free the registry slots now
    if outputs:
        each = (time.perf_counter() - start) / len(outputs)
        for rec in outputs:
            rec["wall_time_s"] = each
    return outputs + [run_variant(job, v) for v in single]


__all__ = ["run_batch_rollout", "drop_traces", "build_scene", "tire_forces", "logged", "summarize"]

"""The sweep's batched runner: a batch of variants through the batched MuJoCo drop engine
(``mtbmj.drop.engine_batch``: the variants stepped together in ``mujoco.rollout`` on the compiled
force laws). A drop-in ``runner`` for ``mtbmj.sweep.runner.run_sweep`` (the default for the MuJoCo
engine); records equal those of :func:`mtbmj.sweep.single.run_batch` (which calls ``run_drop``
per variant). A variant the engine leaves unfinished goes to the single-variant path
(``run_variant``), which records it exactly as the single runner does, with its reason; the other
variants of the batch go on.
"""
from __future__ import annotations

import numpy as np

from mtbmj.drop import engine_batch
from mtbmj.sweep.single import run_batch, run_variant
from mtbmj.sweep.variants import SIGNALS, BatchJob, flatten_summary


def run_batch_rollout(job: BatchJob) -> list[dict]:
    """The batched runner: the variants of ``job`` stepped together on ``job.threads`` threads
    (default 1); same records as :func:`mtbmj.sweep.single.run_batch`. Falls back to
    ``run_batch`` for another engine, a custom ``job.drop`` or when the compiled laws are
    unavailable."""
    if job.engine != "mujoco" or job.drop is not None or not engine_batch.available():
        return run_batch(job)
    threads = max(1, int(getattr(job, "threads", 1) or 1))
    records = []
    for i, finished, wall in engine_batch.run(job.config, [v.overrides for v in job.variants], job.duration, threads):
        variant = job.variants[i]
        if finished is None:
            records.append(run_variant(job, variant))
            continue
        log = finished.logged
        records.append({"id": variant.id, "status": "ok", "reason": "", "outputs": flatten_summary(finished.summary),
                        "traces": ({"time_s": np.asarray(log["time_s"], dtype=float),
                                    **{f"{s}_mm": np.asarray(log[f"{s}_mm"], dtype=float) for s in SIGNALS}}
                                   if job.traces else None),
                        "wall_time_s": wall})
    return records


__all__ = ["run_batch_rollout"]

"""The single-variant runner: each variant of a batch through ``run_drop`` (or a drop-in
replacement), every error recorded with its reason."""
from __future__ import annotations

import threading
import time
import warnings
from typing import Any

import numpy as np

from mtbmj.drop import chain
from mtbmj.sweep.variants import SIGNALS, BatchJob, Variant, flatten_summary

_RUN_LOCK = threading.Lock()  # MuJoCo's control callback is process-global: one drop at a time


def run_variant(job: BatchJob, variant: Variant) -> dict:
    """One variant as a journal record; every error becomes ``status = "failed"`` with its reason."""
    from mtbmj.controllers import native
    from mtbmj.drop.run import run_drop

    native.expect_many()  # a sweep's variants repay loading the compiled laws
    drop = job.drop or run_drop
    start = time.perf_counter()
    record: dict[str, Any] = {"id": variant.id, "status": "ok", "reason": "", "outputs": {}}
    traces = None
    try:
        with _RUN_LOCK, warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)  # as the command line does
            result = drop(job.config, job.engine, variant.overrides, job.duration)
        record["outputs"] = flatten_summary(result.summary)
        if job.traces:
            traces = {"time_s": np.asarray(result.signals["time_s"], dtype=float)}
            traces.update({f"{s}_mm": np.asarray(result.signals[f"{s}_mm"], dtype=float) for s in SIGNALS})
    except Exception as exc:  # a bug must not stop the other variants either: every failure is recorded
        record.update(status="failed", reason=chain.failure_reason(exc))
    record["wall_time_s"] = time.perf_counter() - start
    record["traces"] = traces
    return record


def run_batch(job: BatchJob) -> list[dict]:
    """The default runner: the variants of ``job`` one after the other through ``job.drop``.

    A runner returns one record per variant of the batch (any order): ``{"id": variant id,
    "status": "ok" | "failed", "reason": str, "outputs": flatten_summary(summary),
    "wall_time_s": float, "traces": None | {"time_s", "sled_mm", "fork_mm", "tire_mm": arrays}}``
    and never raises for a bad variant. A batched path (one ``mujoco.rollout`` over the batch's
    models on several threads) is a drop-in replacement with this contract."""
    return [run_variant(job, v) for v in job.variants]



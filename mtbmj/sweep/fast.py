"""The sweep runner of the fast engine: each variant of a batch integrated by
``mtbmj.drop.engine_fast`` and finished with only what the summary needs (``chain.finish`` on the
logged displacements, as the batched MuJoCo engine does), in one process without a MuJoCo scene.
Same records as ``run_batch`` with ``engine="fast"``; a variant that fails goes through
``run_variant``, which words its reason."""
from __future__ import annotations

import time
import warnings

import numpy as np

from mtbmj.sweep.single import run_batch, run_variant
from mtbmj.sweep.variants import SIGNALS, BatchJob, flatten_summary


def run_batch_fast(job: BatchJob) -> list[dict]:
    from mtbmj.controllers import compiled

    if job.engine != "fast" or job.drop is not None or not compiled.available():
        return run_batch(job)
    from mtbmj.drop import chain, engine_fast

    records = []
    for variant in job.variants:
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)  # as the command line does
                _, setup = chain.prepare(job.config, variant.overrides, job.duration)
                trace = engine_fast.run(setup, job.duration)
                _, log, summary = chain.finish(setup, trace, "fast", channels=SIGNALS)
        except Exception:  # noqa: BLE001 - the single path runs it again and records the reason
            records.append(run_variant(job, variant))
            continue
        records.append({
            "id": variant.id, "status": "ok", "reason": "", "outputs": flatten_summary(summary),
            "traces": ({"time_s": np.asarray(log["time_s"], dtype=float),
                        **{f"{s}_mm": np.asarray(log[f"{s}_mm"], dtype=float) for s in SIGNALS}}
                       if job.traces else None),
            "wall_time_s": time.perf_counter() - start,
        })
    return records


__all__ = ["run_batch_fast"]

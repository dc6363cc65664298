"""Shared helpers of the benchmark scripts (not a test module)."""
from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def environment() -> dict:
    import mujoco
    import numpy
    import scipy

    import mtbmj

    return {"mtbmj": mtbmj.__version__, "mujoco": mujoco.__version__, "scipy": scipy.__version__,
            "numpy": numpy.__version__, "python": platform.python_version(), "cpus": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0], "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def commit() -> str | None:
    """Short hash of the checkout's HEAD, or None outside a git checkout (or without git)."""
    try:
        done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).resolve().parent, capture_output=True,
                              text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return (done.stdout.strip() or None) if done.returncode == 0 else None


def write_json(script: str, payload: dict) -> Path:
    """Write ``payload`` to results/<script's stem>.json with the environment, the UTC date of the
    run (``measured_at``) and the commit it ran on (``commit``; read by benchmarks/report.py)."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{Path(script).stem}.json"
    stamp = {"measured_at": datetime.datetime.now(datetime.timezone.utc).date().isoformat(), "commit": commit()}
    path.write_text(json.dumps({**stamp, "environment": environment(), **payload}, indent=2, default=float) + "\n")
    return path


def stats(values) -> dict:
    """Median, smallest, largest and count of ``values`` (one figure's repetitions)."""
    v = np.asarray(values, float)
    return {"median": float(np.median(v)), "min": float(v.min()), "max": float(v.max()), "n": int(v.size)}


def best_of(fn, repeat: int = 3):
    """(best wall time in s, all times, last return value) of ``repeat`` calls of ``fn``."""
    times, value = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - start)
    return min(times), times, value

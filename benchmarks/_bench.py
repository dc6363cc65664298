"""Shared helpers of the benchmark scripts (not a test module).

A benchmark writes its results where its ``--out`` says (``add_out_option``), and with no
``--out`` to a scratch file outside the repository (``scratch_path``: ``<tempdir>/mtbmj-benchmarks/
<name>``), never over a committed file by default. Refreshing a committed result is explicit:
``--out benchmarks/results/<stem>.json``.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"  # the committed results (benchmarks/report.py reads them)
SCRATCH = "mtbmj-benchmarks"  # the folder under the system's temporary directory that takes results by default


def scratch_path(name: str) -> Path:
    """Where a results file called ``name`` goes when no ``--out`` is given: ``<tempdir>/
    mtbmj-benchmarks/<name>``, outside the repository (the temporary directory is looked up at
    each call)."""
    return Path(tempfile.gettempdir()) / SCRATCH / name


def _out_file(text: str) -> Path:
    """``--out``'s type: a file's path (not an existing folder)."""
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a folder: name the results file (e.g. {Path(text) / 'results.json'})")
    return path


def add_out_option(parser: argparse.ArgumentParser, script: str, *, name: str | None = None,
                   what: str = "the results (JSON)", committed: str | None = None, note: str = "") -> None:
    """Add ``--out PATH`` to ``parser``: where ``script`` writes ``what``; by default the scratch file
    ``scratch_path(name)`` (``name``: the script's stem + .json unless given). ``committed`` is the
    repository's copy that ``--out`` refreshes (default ``benchmarks/results/<name>``); ``note`` ends
    the default's words (e.g. another name under an option)."""
    name = name or f"{Path(script).stem}.json"
    committed = committed or f"benchmarks/results/{name}"
    text = (f"write {what} to PATH (default: {scratch_path(name)}, outside the repository{note}; "
            f"--out {committed} refreshes the committed file)")
    parser.add_argument("--out", type=_out_file, default=None, metavar="PATH", help=text.replace("%", "%%"))


def add_ride_options(parser: argparse.ArgumentParser, repeats: int) -> None:
    """``--ride`` (an SST recording or a travel CSV, or 'example': the shipped 00649.SST), ``--bike``
    (the recorded bike: a preset or a file) and ``--repeats``, as every ride benchmark takes them."""
    parser.add_argument("--ride", default="example", help="an SST recording or a travel CSV, or 'example' (00649.SST)")
    parser.add_argument("--bike", default="sst", help="the recorded bike (preset or file)")
    parser.add_argument("--repeats", type=int, default=repeats)


def ride_options_shown(args) -> str:
    """The ``--ride`` and ``--bike`` of ``add_ride_options`` as a results file's command repeats them
    (each left out at its default)."""
    return ((f" --ride {args.ride}" if args.ride != "example" else "")
            + (f" --bike {args.bike}" if args.bike != "sst" else ""))


def read_ride(args, bike=None):
    """The ride ``args.ride`` read as ``mtbmj`` reads it for ``args.bike`` (``bike``: its resolved
    bike where the caller has it)."""
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry

    path = telemetry.ride_path(args.ride)
    how = SimpleNamespace(bike=args.bike, fork_max_mm=None, shock_max_mm=None)
    return telemetry.read_ride(path, **(decoding(how) if bike is None else decoding(how, bike)))


def environment() -> dict:
    import mujoco
    import numpy
    import scipy

    import mtbmj

    return {"mtbmj": mtbmj.__version__, "mujoco": mujoco.__version__, "scipy": scipy.__version__,
            "numpy": numpy.__version__, "python": platform.python_version(), "cpus": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0], "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def load_average() -> str:
    """The 1, 5 and 15 minute load averages (/proc/loadavg), or "n/a"."""
    try:
        return " ".join(open("/proc/loadavg").read().split()[:3])
    except OSError:
        return "n/a"


def pin_one_core() -> None:
    """Run this process on one core (the first it may use), where the system allows it."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})


def commit() -> str | None:
    """Short hash of the checkout's HEAD, or None outside a git checkout (or without git)."""
    try:
        done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).resolve().parent, capture_output=True,
                              text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return (done.stdout.strip() or None) if done.returncode == 0 else None


def write_json(script: str, payload: dict, out: str | os.PathLike | None = None) -> Path:
    """Write ``payload`` to ``out`` (a file's path, its folder made if missing), or with no ``out``
    to the scratch file ``scratch_path(<script's stem>.json)``, outside the repository; with the
    environment, the UTC date of the run (``measured_at``) and the commit it ran on (``commit``;
    read by benchmarks/report.py). Returns the path written: the script prints it."""
    path = Path(out) if out is not None else scratch_path(f"{Path(script).stem}.json")
    path.parent.mkdir(parents=True, exist_ok=True)
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

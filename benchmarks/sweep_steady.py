"""The fast sweep's steady state (issue 27, item 2): variants per second of whole
``mtbmj sweep S12 --engine fast`` commands once start-up is paid, on ``--workers`` processes.

Each round runs the same command twice, with ``--small`` and with ``--variants`` Latin-hypercube
variants (the three ranges of ``speed_scales.py`` part e), and takes the steady rate as the
difference: (variants - small) / (T(variants) - T(small)), so start-up, the pool, numba's cache
and the table libraries cancel. The baseline, timed in this script between the commands of each
round, is the fast engine alone (``engine_fast.run``) on ``--phase-variants`` of the same variants
in this process, with the other phases of a variant (``chain.prepare``: overrides, ``compose.setup``
and its step rule; ``chain.finish``: logged signals and the summary) timed beside it: the figure is
the steady per-variant cost of one worker (workers / rate) over the engine's own. Rounds alternate
the order of the two commands. Where ``perf stat`` counts task-clock, each command runs under it,
and the same difference gives the CPU time a variant costs, every process of the command
together: the target's rate allows at most cores / rate of it (2 ms on 2 cores).

    python benchmarks/sweep_steady.py [--variants 20000] [--small 2000] [--repeat 3] [--workers 2] [--out PATH]

Writes its results (medians, spreads, the load average before and after each round) where ``--out``
says (default ``<tempdir>/mtbmj-benchmarks/sweep_steady.json``, outside the repository; ``--out
benchmarks/results/sweep_steady.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from _bench import add_out_option, stats, write_json

BIN = Path(sys.executable).with_name("mtbmj")
RANGES = ["fork.spring.preload_N=150:300", "tire.impact_rate_N_per_mm=75:95", "sled.drop_height_mm=60:130"]
TARGET_VARIANTS_PER_S = 1000


def command(n: int, workers: int, out: Path) -> list[str]:
    vary = [a for r in RANGES for a in ("--vary", r)]
    return [str(BIN), "sweep", "S12", "--engine", "fast", "--samples", str(n), "--seed", "1", *vary,
            "--workers", str(workers), "--quiet", "--no-figure", "--out", str(out)]


def _perf() -> str | None:
    """``perf`` where it counts a command's CPU time (task-clock, the command and every process it
    starts), else None."""
    perf = shutil.which("perf")
    if perf is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "probe"
        done = subprocess.run([perf, "stat", "-x,", "-e", "task-clock", "-o", str(out), "true"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return perf if done.returncode == 0 and _task_clock_s(out) is not None else None


def _task_clock_s(path: Path) -> float | None:
    for line in path.read_text().splitlines():
        fields = line.split(",")
        if len(fields) > 2 and fields[2].startswith("task-clock"):
            try:
                return float(fields[0]) / 1e3
            except ValueError:
                return None
    return None


def timed_command(n: int, workers: int, tmp: Path, tag: str, perf: str | None = None) -> tuple[float, float | None]:
    """(wall time, CPU time of the command and its workers, or None without ``perf``) in s."""
    out = tmp / tag
    stat = tmp / f"{tag}.perf"
    cmd = command(n, workers, out)
    if perf is not None:
        cmd = [perf, "stat", "-x,", "-e", "task-clock", "-o", str(stat), *cmd]
    start = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - start
    subprocess.run(["rm", "-rf", str(out)], check=True)
    return wall, (_task_clock_s(stat) if perf is not None else None)


def phases(n: int) -> dict:
    """Per-variant wall time (ms) of prepare, the fast engine and finish, in this process, on the
    first ``n`` variants of the command's plan (each phase summed over the variants)."""
    from mtbmj import sweep
    from mtbmj.drop import chain, engine_fast
    from mtbmj.sweep.variants import SIGNALS

    cfg = chain.resolve("S12")
    overrides = sweep.sample([sweep.parse_vary(r, count=False) for r in RANGES], n, "lhs", 1)
    setups, traces = [], []
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for ov in overrides:
            setups.append(chain.prepare(cfg, ov, None)[1])
    t1 = time.perf_counter()
    for s in setups:
        traces.append(engine_fast.run(s))
    t2 = time.perf_counter()
    for s, tr in zip(setups, traces):
        chain.finish(s, tr, "fast", channels=SIGNALS)
    t3 = time.perf_counter()
    return {"prepare_ms": (t1 - t0) * 1e3 / n, "engine_ms": (t2 - t1) * 1e3 / n, "finish_ms": (t3 - t2) * 1e3 / n}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--variants", type=int, default=20000)
    ap.add_argument("--small", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--phase-variants", type=int, default=300)
    add_out_option(ap, __file__)
    args = ap.parse_args()
    from mtbmj.drop import engine_fast

    engine_fast.kernel()
    phases(20)  # warm: numba's cache, scipy's sampler
    with tempfile.TemporaryDirectory(prefix="mtbmj_steady_") as tmp:
        tmp = Path(tmp)
        perf = _perf()
        timed_command(200, args.workers, tmp, "warm")  # the page cache, numba's cache files
        rounds = []
        for k in range(args.repeat):
            load_before = os.getloadavg()[0]
            order = ("small", "large") if k % 2 == 0 else ("large", "small")
            walls, cpus = {}, {}
            for which in order:
                n = args.small if which == "small" else args.variants
                walls[which], cpus[which] = timed_command(n, args.workers, tmp, f"{which}{k}", perf)
                if which == order[0]:
                    p = phases(args.phase_variants)
            rate = (args.variants - args.small) / (walls["large"] - walls["small"])
            per_worker_ms = args.workers / rate * 1e3
            cpu_ms = (None if perf is None else
                      (cpus["large"] - cpus["small"]) / (args.variants - args.small) * 1e3)
            rounds.append({"small_s": walls["small"], "large_s": walls["large"], "steady_variants_per_s": rate,
                           "steady_ms_per_variant_per_worker": per_worker_ms, "phases_ms": p,
                           "cpu_small_s": cpus["small"], "cpu_large_s": cpus["large"],
                           "steady_cpu_ms_per_variant": cpu_ms,
                           "over_engine": per_worker_ms / p["engine_ms"],
                           "load_before": load_before, "load_after": os.getloadavg()[0]})
            print(f"round {k + 1}: {args.small} variants {walls['small']:.1f} s, {args.variants} variants "
                  f"{walls['large']:.1f} s: steady {rate:.0f} variants/s ({per_worker_ms:.2f} ms per variant per "
                  f"worker); in-process prepare {p['prepare_ms']:.2f} ms, engine {p['engine_ms']:.2f} ms, finish "
                  f"{p['finish_ms']:.2f} ms; CPU per variant "
                  f"{'n/a' if cpu_ms is None else format(cpu_ms, '.2f') + ' ms'}; load {load_before:.2f} -> "
                  f"{rounds[-1]['load_after']:.2f}", flush=True)
    payload = {
        "command": f"python benchmarks/sweep_steady.py --variants {args.variants} --small {args.small} "
                   f"--repeat {args.repeat} --workers {args.workers}",
        "variants": args.variants, "small": args.small, "workers": args.workers,
        "phase_variants": args.phase_variants, "ranges": RANGES, "rounds": rounds,
        "steady_variants_per_s": stats([r["steady_variants_per_s"] for r in rounds]),
        "steady_ms_per_variant_per_worker": stats([r["steady_ms_per_variant_per_worker"] for r in rounds]),
        "over_engine": stats([r["over_engine"] for r in rounds]),
        "phases_ms": {k: stats([r["phases_ms"][k] for r in rounds]) for k in ("prepare_ms", "engine_ms", "finish_ms")},
        "load": stats([x for r in rounds for x in (r["load_before"], r["load_after"])]),
        "target_variants_per_s": TARGET_VARIANTS_PER_S,
        # the CPU time a variant may take, all processes together, for the target on this machine's cores
        "cpu_ms_per_variant_at_target": (os.cpu_count() or 1) / TARGET_VARIANTS_PER_S * 1e3,
    }
    if perf is not None:
        payload["steady_cpu_ms_per_variant"] = stats([r["steady_cpu_ms_per_variant"] for r in rounds])
    s = payload["steady_variants_per_s"]
    print(f"steady state {s['median']:.0f} variants/s ({s['min']:.0f}-{s['max']:.0f}) on {args.workers} workers; "
          f"target {TARGET_VARIANTS_PER_S}")
    print(f"wrote {write_json(__file__, payload, args.out)}")


if __name__ == "__main__":
    main()

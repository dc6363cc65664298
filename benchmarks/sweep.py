"""Sweep throughput: an S12 Latin-hypercube sweep end to end (process pool, journal, Parquet
table written) against ``mujoco.rollout`` of the bare scene for the same variants.

The issue's figure is a 10 000-variant S12 sweep (1.5 s drops, default settings) on 2 cores,
compared with the bare-scene rollout (target <= 1.2x). ``--variants`` sets the size:

    python benchmarks/sweep.py --variants 200 [--workers 2] [--duration 1.5]
        [--runner batch|single] [--threads 1] [--repeat 1] [--sweep-dir DIR] [--out PATH]

``--runner batch`` (the default: ``mtbmj.sweep.batch.run_batch_rollout`` on the batched drop engine
``mtbmj.drop.engine_batch``, variants of a batch stepped together through ``mujoco.rollout`` on the
compiled laws) or ``single`` (``run_drop`` per
variant); ``--threads``: rollout threads per worker process. The per-variant costs of the batched
runner's phases (prepare, step, post-process) are measured in-process on ``--phase-variants``
variants against the bare rollout of the same variants on one thread, and against the bare scene
making as many steps as the runner does with the compiled fork callback installed (what stepping
costs without the runner's bookkeeping).

Bare scene: ``mtbmj.drop.scene.build(compose.setup(load_config("S12")))`` with no control callback
(no fork law: MuJoCo's own contact and joints only), one rollout per variant from tire touch at
that variant's impact speed, the same number of steps, ``--workers`` rollout threads, states
recorded (as the sweep does), in chunks to bound memory.

``--repeat N`` (N > 1, batched runner) adds N interleaved rounds (the order alternating) of the
whole sweep (``run_sweep`` in this process), the same sweep in workers warmed before the timing,
the whole ``mtbmj sweep`` command in a process of its own, the bare scene making as many steps
per variant as the runner with built-in elements (the fork as joint stiffness and damping: issue
27's baseline, target >= 0.85x of its throughput) and the same with the compiled fork callback
installed, on ``--workers`` x ``--threads`` threads: ratios of medians, the spread of the
per-round ratios, the load average before and after each round.

``--sweep-dir`` keeps the sweep's own folder (journal, table; default a temporary one).

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/sweep.json``, outside
the repository; ``--out benchmarks/results/sweep_200.json``, for instance, refreshes that committed
file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

import mtbmj
from mtbmj import compose
from mtbmj.drop import scene
from mtbmj import sweep
from mtbmj.controllers import installed
from _bench import add_out_option, write_json

RANGES = ["fork.spring.preload_N=150:300", "fork.spring.progressive_rate_N_per_mm=9:14",
          "tire.impact_rate_N_per_mm=75:95", "sled.drop_height_mm=60:130"]


def variants(n: int, seed: int) -> list[dict]:
    return sweep.sample([sweep.parse_vary(r, count=False) for r in RANGES], n, "lhs", seed)


def run_sweep(vs, workers: int, duration, out: Path, runner: str = "batch", threads: int = 1):
    start = time.perf_counter()
    result = sweep.run_sweep("S12", vs, out, duration=duration, workers=workers, progress=True, runner=runner,
                             threads=threads)
    return time.perf_counter() - start, result


def phase_costs(vs, duration) -> dict:
    """Per-variant wall time (ms) of the batched runner's phases, one process, one thread, against
    the bare-scene rollout of the same variants (best of 3 each, interleaved)."""
    from mtbmj.drop import engine_batch
    from mtbmj.sweep import batch

    cfg = mtbmj.load_config("S12")
    variants = sweep.plan(cfg, vs, duration=duration)
    job = sweep.BatchJob(cfg, "mujoco", duration, variants)
    batch.run_batch_rollout(job)  # warm-up (numba cache load, scene cache)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    best = {}

    def note(name, seconds):
        best[name] = min(best.get(name, float("inf")), seconds * 1e3 / len(vs))

    for _ in range(3):
        t0 = time.perf_counter()
        runs = [engine_batch.prepare(job.config, v.overrides, job.duration, i, spec) for i, v in enumerate(variants)]
        t1 = time.perf_counter()
        datas = [mujoco.MjData(runs[0].scene.model)]
        with installed(runs[0].callback):
            engine_batch.step_group(runs, datas, None, spec)
        t2 = time.perf_counter()
        for r in runs:
            engine_batch.finish(r)
        t3 = time.perf_counter()
        note("prepare_ms", t1 - t0)
        note("step_ms", t2 - t1)
        note("post_process_ms", t3 - t2)
        note("bare_rollout_ms", bare_rollout(vs, 1, duration)[0])
        steps = int(round(np.mean([r.plan.computed for r in runs])))
        note("bare_same_steps_with_callback_ms", bare_rollout(vs, 1, duration, steps=steps, callback=True)[0])
        t4 = time.perf_counter()
        batch.run_batch_rollout(job)
        note("whole_runner_ms", time.perf_counter() - t4)
    best["post_process_share_of_runner"] = best["post_process_ms"] / best["whole_runner_ms"]
    best["runner_over_bare"] = best["whole_runner_ms"] / best["bare_rollout_ms"]
    best["runner_steps_per_variant"] = steps
    best["runner_over_bare_same_steps_with_callback"] = best["whole_runner_ms"] / best["bare_same_steps_with_callback_ms"]
    return best


def bare_rollout(vs, threads: int, duration, chunk: int = 32, builtin: bool = False, steps: int | None = None,
                 callback: bool = False) -> tuple[float, int]:
    """Wall time of the bare-scene rollouts of ``vs`` (scene built once, outside the timing).
    ``builtin``: the fork as MuJoCo joint stiffness/preload/damping (``benchmarks/compiled.py``'s
    built-in-elements scene, dynamics close to the real fork) instead of no fork force at all.
    ``steps``: that many steps per variant (default: the output steps); ``callback``: with S12's
    compiled fork callback installed (the runner's per-step cost, no refinement or chunking)."""
    base = mtbmj.load_config("S12")
    setup = compose.setup(base)
    sc = scene.build(setup)
    model = sc.model
    if builtin:
        from compiled import builtin_model  # benchmarks/compiled.py

        model = builtin_model(sc, setup)
    steps = int(round((duration or setup.duration) / setup.timestep)) if steps is None else steps
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    states = []
    for v in vs:
        speed = math.sqrt(2.0 * setup.gravity * v["sled.drop_height_mm"] * 1e-3)
        data = mujoco.MjData(model)
        data.qvel[sc.sled_dof] = speed
        data.qpos[sc.sled_qpos] = 1e-12
        mujoco.mj_forward(model, data)
        state = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, data, state, spec)
        states.append(state)
    states = np.array(states)
    datas = [mujoco.MjData(model) for _ in range(threads)]
    out = np.empty((min(chunk, len(vs)), steps, states.shape[1]))
    fork = None
    if callback:
        from mtbmj.controllers.compiled import CompiledForkCallback

        fork = CompiledForkCallback(model, setup.fork, count_calls=False, rim=setup.tire.rim, floor=sc.floor())
    with installed(fork):
        rollout.rollout(model, datas, states[:1], nstep=10)  # warm-up
        start = time.perf_counter()
        for i in range(0, len(vs), chunk):
            part = states[i:i + chunk]
            rollout.rollout(model, datas, part, nstep=steps, state=out[: len(part)])
        wall = time.perf_counter() - start
    return wall, steps


def _warm_worker() -> int:
    """A warm-up task: a 50 ms S12 drop on the batched engine (numba, the cached callback, the
    scene), then a pause so that the other worker takes the next task; returns the worker's pid."""
    from mtbmj.drop import engine_batch

    list(engine_batch.run(mtbmj.load_config("S12"), [{}], 0.05, 1))
    time.sleep(0.3)
    return os.getpid()


def warm_sweep(vs, workers: int, duration, out: Path, runner: str = "batch", threads: int = 1) -> float:
    """Wall time of the same sweep in workers started, and their compiled code loaded
    (``start_pool``'s warm-up task), before the timing: the sweep without its fixed start-up cost
    (the pool, numba and the cached callback in each worker), which the built-in scene never pays."""
    from mtbmj.sweep.runner import start_pool

    pool = start_pool(workers, "mujoco")
    try:
        for _ in range(10):  # until every worker has made a short drop of its own
            if len({f.result() for f in [pool.submit(_warm_worker) for _ in range(workers)]}) == workers:
                break
        else:
            raise SystemExit(f"could not warm each of the {workers} workers in 10 tries")
        start = time.perf_counter()
        sweep.run_sweep("S12", vs, out, duration=duration, workers=workers, progress=True, runner=runner,
                        threads=threads, pool=pool)
        return time.perf_counter() - start
    finally:
        pool.shutdown(wait=True)


def command_sweep(vs, args, out: Path) -> float:
    """Wall time of the whole ``mtbmj sweep`` command for the same variants (its own process: Python,
    the imports, the pool and the compiled laws' load in each worker included); checks that the
    command sampled the variants ``vs`` holds."""
    import subprocess
    import sys

    vary = [a for r in RANGES for a in ("--vary", r)]
    cmd = [str(Path(sys.executable).with_name("mtbmj")), "sweep", "S12", "--samples", str(len(vs)), "--seed",
           str(args.seed), *vary, "--workers", str(args.workers), "--threads", str(args.threads), "--runner",
           args.runner, "--quiet", "--no-figure", "--out", str(out)]
    if args.duration:
        cmd += ["--duration", str(args.duration)]
    start = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - start
    table = sweep.read_table(out)
    for key in vs[0]:
        if not np.array_equal(table[key].to_numpy(), np.array([v[key] for v in vs])):
            raise SystemExit(f"the command sampled other variants than this script ({key})")
    return wall


def interleaved(vs, args, steps: int) -> dict:
    """``args.repeat`` rounds of the whole sweep, the same sweep in warmed workers, the whole
    command and the bare scene making ``steps`` steps per variant (built-in elements; compiled
    callback), interleaved, the order alternating."""
    threads = args.workers * args.threads
    runs = {
        "sweep": lambda out: run_sweep(vs, args.workers, args.duration, out, args.runner, args.threads)[0],
        "warm": lambda out: warm_sweep(vs, args.workers, args.duration, out, args.runner, args.threads),
        "command": lambda out: command_sweep(vs, args, out),
        "builtin": lambda out: bare_rollout(vs, threads, args.duration, builtin=True, steps=steps)[0],
        "callback": lambda out: bare_rollout(vs, threads, args.duration, steps=steps, callback=True)[0],
    }
    rounds = []
    for k in range(args.repeat):
        load = os.getloadavg()[0]
        order = list(runs) if k % 2 == 0 else list(reversed(runs))
        walls = {}
        with tempfile.TemporaryDirectory() as tmp:
            for name in order:
                walls[name] = runs[name](Path(tmp) / f"{name}{k}")
        rounds.append({**{f"{n}_s": w for n, w in walls.items()}, "load_before": load,
                       "load_after": os.getloadavg()[0]})
        print(f"round {k + 1}: sweep {walls['sweep']:.2f} s, bare {steps} steps per variant built-in "
              f"{walls['builtin']:.2f} s ({walls['builtin'] / walls['sweep']:.2f}), with the callback "
              f"{walls['callback']:.2f} s ({walls['callback'] / walls['sweep']:.2f}); in warmed workers "
              f"{walls['warm']:.2f} s (built-in {walls['builtin'] / walls['warm']:.2f}); the command "
              f"{walls['command']:.2f} s (built-in {walls['builtin'] / walls['command']:.2f}); load {load:.2f}",
              flush=True)
    out = {"rounds": rounds, "steps_per_variant": steps, "target_builtin": 0.85}
    wall = {name: np.array([r[f"{name}_s"] for r in rounds]) for name in runs}

    def throughput(base: str, timed: str) -> dict:
        """``base``'s wall time over ``timed``'s: the ratio of the medians, the per-round spread."""
        per = wall[base] / wall[timed]
        return {"ratio_of_medians": float(np.median(wall[base]) / np.median(wall[timed])),
                "min": float(per.min()), "max": float(per.max())}

    out["throughput_builtin_over_sweep"] = throughput("builtin", "sweep")
    out["throughput_callback_over_sweep"] = throughput("callback", "sweep")
    out["throughput_builtin_over_warm_sweep"] = throughput("builtin", "warm")
    out["throughput_builtin_over_command"] = throughput("builtin", "command")
    start_up = wall["sweep"] - wall["warm"]  # per round: what the whole sweep pays that the warmed one does not
    out["start_up_s"] = {"median": float(np.median(start_up)), "min": float(start_up.min()),
                         "max": float(start_up.max())}
    out.update({f"{name}_s": float(np.median(w)) for name, w in wall.items()})
    out["load"] = [float(min(r["load_before"] for r in rounds)), float(max(r["load_after"] for r in rounds))]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=10000)
    parser.add_argument("--workers", type=int, default=2, help="sweep processes and rollout threads (default 2)")
    parser.add_argument("--duration", type=float, help="simulated time per drop in s (default S12's 1.5 s)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sweep-dir", type=Path, help="the sweep's output folder (default: a temporary one)")
    parser.add_argument("--skip-rollout", action="store_true")
    parser.add_argument("--runner", choices=sweep.RUNNERS, default="batch")
    parser.add_argument("--threads", type=int, default=1, help="rollout threads per worker process (default 1)")
    parser.add_argument("--phase-variants", type=int, default=32, help="variants for the phase costs (0: skip)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="interleaved rounds of the whole sweep against the bare scene making as many steps")
    add_out_option(parser, __file__)
    args = parser.parse_args()

    vs = variants(args.variants, args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        out = args.sweep_dir or Path(tmp) / "sweep"
        wall, result = run_sweep(vs, args.workers, args.duration, out, args.runner, args.threads)
        table_bytes = (out / sweep.TABLE).stat().st_size
        # each variant's wall time is in timings.csv (variant,variant_id,wall_time_s), not the table
        walls = np.genfromtxt(out / "timings.csv", delimiter=",", skip_header=1, usecols=2)
    drop_s = float(np.nanmedian(walls))
    print(f"S12 sweep ({args.runner} runner, {args.threads} rollout thread(s) per process): {args.variants} variants "
          f"on {args.workers} processes in {wall:.2f} s end to end "
          f"({args.variants / wall:.1f} variants/s; median drop {drop_s:.3f} s in its worker; "
          f"{result.failed} failed; table {table_bytes / 1e3:.0f} kB)")
    payload = {"variants": args.variants, "workers": args.workers, "runner": args.runner,
               "threads_per_process": args.threads, "duration_s": args.duration or 1.5,
               "ranges": RANGES, "sweep_wall_s": wall, "variants_per_s": args.variants / wall,
               "median_drop_wall_s": drop_s, "failed": result.failed, "table_bytes": table_bytes}
    if not args.skip_rollout:
        bare, steps = bare_rollout(vs, args.workers * args.threads, args.duration)
        ratio = wall / bare
        print(f"bare-scene mujoco.rollout of the same {args.variants} variants ({steps} steps each, "
              f"{args.workers * args.threads} threads): {bare:.2f} s ({args.variants * steps / bare / 1e3:.0f} k steps/s, "
              f"{args.variants / bare:.1f} drops/s); sweep / rollout = {ratio:.2f}x (target <= 1.2x), "
              f"throughput ratio {bare / wall:.2f} (target >= 0.9)")
        builtin, _ = bare_rollout(vs, args.workers * args.threads, args.duration, builtin=True)
        print(f"built-in-elements scene rollout (fork as joint stiffness + damping, as benchmarks/compiled.py): "
              f"{builtin:.2f} s; sweep / rollout = {wall / builtin:.2f}x, throughput ratio {builtin / wall:.2f}")
        payload.update({"builtin_rollout_wall_s": builtin, "ratio_sweep_over_builtin_rollout": wall / builtin,
                        "throughput_ratio_sweep_to_builtin_rollout": builtin / wall})
        payload.update({"bare_rollout_wall_s": bare, "steps_per_variant": steps,
                        "bare_rollout_steps_per_s": args.variants * steps / bare,
                        "bare_rollout_drops_per_s": args.variants / bare, "ratio_sweep_over_rollout": ratio,
                        "throughput_ratio_sweep_to_rollout": bare / wall})
    if args.phase_variants and args.runner == "batch":
        phases = phase_costs(vs[: args.phase_variants], args.duration)
        payload["batch_runner_phases_per_variant"] = phases
        print("batched runner, per variant (1 process, 1 thread): " + ", ".join(
            f"{k} {v:.2f}" for k, v in phases.items()))
        if not args.skip_rollout:  # the whole sweep against bare stepping of as many steps, callback installed
            same, _ = bare_rollout(vs, args.workers * args.threads, args.duration,
                                   steps=phases["runner_steps_per_variant"], callback=True)
            payload.update({"bare_same_steps_with_callback_wall_s": same,
                            "throughput_ratio_sweep_to_same_steps_with_callback": same / wall})
            print(f"bare scene, {phases['runner_steps_per_variant']} steps per variant (as many as the runner "
                  f"makes, the phase variants' mean), compiled callback installed: {same:.2f} s; throughput "
                  f"ratio {same / wall:.2f}")
    if args.repeat > 1 and args.phase_variants and args.runner == "batch" and not args.skip_rollout:
        payload["interleaved"] = interleaved(vs, args, phases["runner_steps_per_variant"])
    estimate = 10000 / args.variants * wall
    payload["extrapolated_10000_variant_sweep_s"] = estimate
    print(f"extrapolated 10 000-variant sweep on this path: {estimate / 60:.1f} min")
    path = write_json(__file__, payload, args.out)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

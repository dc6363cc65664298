"""Sweep throughput: an S12 Latin-hypercube sweep end to end (process pool, journal, Parquet
table written) against ``mujoco.rollout`` of the bare scene for the same variants.

The issue's figure is a 10 000-variant S12 sweep (1.5 s drops, default settings) on 2 cores,
compared with the bare-scene rollout (target <= 1.2x). On the Python force-law path that takes
about an hour, so ``--variants`` sets the size:

    /work/venv/bin/python benchmarks/sweep.py --variants 200 [--workers 2] [--duration 1.5]

Bare scene: ``mtbmj.scene.build(compose.setup(load_config("S12")))`` with no control callback
(no fork law: MuJoCo's own contact and joints only), one rollout per variant from tire touch at
that variant's impact speed, the same number of steps, ``--workers`` rollout threads, states
recorded (as the sweep does), in chunks to bound memory.

Writes benchmarks/results/sweep.json. Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

import mtbmj
from mtbmj import compose, scene, sweep
from mtbmj.controllers import installed
from _bench import write_json

RANGES = ["fork.spring.preload_N=150:300", "fork.spring.progressive_rate_N_per_mm=9:14",
          "tire.impact_rate_N_per_mm=75:95", "sled.drop_height_mm=60:130"]


def variants(n: int, seed: int) -> list[dict]:
    return sweep.sample([sweep.parse_vary(r, count=False) for r in RANGES], n, "lhs", seed)


def run_sweep(vs, workers: int, duration, out: Path):
    start = time.perf_counter()
    result = sweep.run_sweep("S12", vs, out, duration=duration, workers=workers, progress=True)
    return time.perf_counter() - start, result


def bare_rollout(vs, threads: int, duration, chunk: int = 32) -> tuple[float, int]:
    """Wall time of the bare-scene rollouts of ``vs`` (scene built once, outside the timing)."""
    base = mtbmj.load_config("S12")
    setup = compose.setup(base)
    sc = scene.build(setup)
    model = sc.model
    steps = int(round((duration or setup.duration) / setup.timestep))
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
    with installed(None):
        rollout.rollout(model, datas, states[:1], nstep=10)  # warm-up
        start = time.perf_counter()
        for i in range(0, len(vs), chunk):
            part = states[i:i + chunk]
            rollout.rollout(model, datas, part, nstep=steps, state=out[: len(part)])
        wall = time.perf_counter() - start
    return wall, steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=10000)
    parser.add_argument("--workers", type=int, default=2, help="sweep processes and rollout threads (default 2)")
    parser.add_argument("--duration", type=float, help="simulated time per drop in s (default S12's 1.5 s)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, help="sweep output directory (default: a temporary one)")
    parser.add_argument("--skip-rollout", action="store_true")
    args = parser.parse_args()

    vs = variants(args.variants, args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp) / "sweep"
        wall, result = run_sweep(vs, args.workers, args.duration, out)
        table_bytes = (out / sweep.TABLE).stat().st_size
    drop_s = float(result.table["wall_time_s"].median())
    print(f"S12 sweep: {args.variants} variants on {args.workers} processes in {wall:.2f} s end to end "
          f"({args.variants / wall:.1f} variants/s; median drop {drop_s:.3f} s in its worker; "
          f"{result.failed} failed; table {table_bytes / 1e3:.0f} kB)")
    payload = {"variants": args.variants, "workers": args.workers, "duration_s": args.duration or 1.5,
               "ranges": RANGES, "sweep_wall_s": wall, "variants_per_s": args.variants / wall,
               "median_drop_wall_s": drop_s, "failed": result.failed, "table_bytes": table_bytes}
    if not args.skip_rollout:
        bare, steps = bare_rollout(vs, args.workers, args.duration)
        ratio = wall / bare
        print(f"bare-scene mujoco.rollout of the same {args.variants} variants ({steps} steps each, "
              f"{args.workers} threads): {bare:.2f} s ({args.variants * steps / bare / 1e3:.0f} k steps/s); "
              f"sweep / rollout = {ratio:.1f}x (issue target <= 1.2x, for the compiled path)")
        payload.update({"bare_rollout_wall_s": bare, "steps_per_variant": steps,
                        "bare_rollout_steps_per_s": args.variants * steps / bare, "ratio_sweep_over_rollout": ratio})
    estimate = 10000 / args.variants * wall
    payload["extrapolated_10000_variant_sweep_s"] = estimate
    print(f"extrapolated 10 000-variant sweep on this path: {estimate / 60:.0f} min")
    path = write_json(__file__, payload)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

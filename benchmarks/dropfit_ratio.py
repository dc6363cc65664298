"""The drop fit's MuJoCo form against its fast-engine form, per engine run (issue 27, item 4:
target within 3x).

The six-parameter S12 fit of ``benchmarks/dropfit.py`` (the same 1.5 s ODE record: six values
changed by 7-15 %, logger noise, the 400 Hz filter, 16-bit quantisation), fitted on the fast
engine (``--fast-workers``, 1 as in dropfit.py's fast row) and on MuJoCo (``--mujoco-workers``
threads for the batched Jacobian, 2 as in its MuJoCo row), alternately in this process, ``--repeat``
rounds (the order alternates; one warm-up fit of each first). Each fit's wall time divided by its
engine runs is its cost per engine run; the figure is the per-round ratio MuJoCo / fast (median,
spread), with the wall times, the runs and the load average before and after each round.

Each round also times the floor of the MuJoCo form: S12's scene stepped by ``mujoco.rollout`` with
its compiled fork callback and nothing else (no step rule, no fit), for as many steps as the
MuJoCo engine makes for one run at the truth, on one thread (``benchmarks/sweep.py``'s
``bare_rollout``), divided by ``--mujoco-workers`` as if the fit used its threads perfectly: no
MuJoCo fit can cost less per run than that; the figure is that floor over the fast fit's cost per
run.

Each fit ends with one run at the optimum that measures the engine's own error (the fast engine
stepped finer, about 0.15 s, for both). The rounds also time both fits without it (``engine_error=False``), the fit loop alone, so the per-run
cost of the engines themselves shows.

    python benchmarks/dropfit_ratio.py [--repeat 5] [--seed 3] [--fast-workers 1] [--mujoco-workers 2]
        [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/dropfit_ratio.json``,
outside the repository; ``--out benchmarks/results/dropfit_ratio.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import os
import time

from mtbmj.drop.chain import resolve
from mtbmj.identify.drop_synthetic import make_drop_record
from mtbmj.identify.dropfit import fit_drop
from _bench import add_out_option, stats, write_json
from dropfit import FACTORS
from sweep import bare_rollout

TARGET = 3.0


def truth_steps(truth) -> int:
    """The MuJoCo steps the engine makes for one 1.5 s run at the truth (its step rule's refined
    steps included)."""
    import mujoco

    from mtbmj.controllers import installed
    from mtbmj.drop import engine_batch

    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    run = engine_batch.prepare(resolve("S12"), truth, 1.5, 0, spec)
    with installed(run.callback):
        engine_batch.step_group([run], [mujoco.MjData(run.scene.model)], None, spec)
    return int(run.plan.computed)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--fast-workers", type=int, default=1)
    ap.add_argument("--mujoco-workers", type=int, default=2)
    add_out_option(ap, __file__)
    args = ap.parse_args()
    cfg = resolve("S12")
    truth = {k: round(cfg[k] * f, 4) for k, f in FACTORS.items()}
    record = make_drop_record("S12", truth, duration=1.5, engine="ode", seed=args.seed)
    workers = {"fast": args.fast_workers, "mujoco": args.mujoco_workers}

    def fit(engine: str, engine_error: bool = True) -> dict:
        start = time.perf_counter()
        result = fit_drop(record, "S12", free=list(truth), engine=engine, workers=workers[engine],
                          engine_error=engine_error)
        wall = time.perf_counter() - start
        runs = result.extra["engine_runs"]
        return {"wall_s": wall, "engine_runs": runs, "per_run_ms": wall / runs * 1e3,
                "max_abs_error_percent": max(abs(result.values[k] / truth[k] - 1.0) * 100 for k in truth)}

    def floor_ms() -> float:
        """The MuJoCo steps of one run at the truth, bare with the compiled callback, one thread
        (best of 3), shared perfectly over the MuJoCo fit's threads."""
        walls = [bare_rollout([{"sled.drop_height_mm": cfg["sled.drop_height_mm"]}], 1, 1.5, steps=steps,
                              callback=True)[0] for _ in range(3)]
        return min(walls) * 1e3 / workers["mujoco"]

    steps = truth_steps(truth)
    fit("fast"), fit("mujoco")  # warm: numba's cache, scenes, scipy
    rounds = []
    for k in range(args.repeat):
        load_before = os.getloadavg()[0]
        order = ("fast", "mujoco") if k % 2 == 0 else ("mujoco", "fast")
        got = {engine: fit(engine) for engine in order}
        loop = {engine: fit(engine, engine_error=False) for engine in order}
        ratio = got["mujoco"]["per_run_ms"] / got["fast"]["per_run_ms"]
        loop_ratio = loop["mujoco"]["per_run_ms"] / loop["fast"]["per_run_ms"]
        floor = floor_ms()
        rounds.append({**got, "mujoco_over_fast_per_run": ratio, "fit_loop": loop,
                       "fit_loop_mujoco_over_fast_per_run": loop_ratio, "mujoco_floor_per_run_ms": floor,
                       "floor_over_fast_per_run": floor / got["fast"]["per_run_ms"], "load_before": load_before,
                       "load_after": os.getloadavg()[0]})
        print(f"round {k + 1}: fast {got['fast']['wall_s']:.2f} s / {got['fast']['engine_runs']} runs "
              f"({got['fast']['per_run_ms']:.1f} ms a run), MuJoCo {got['mujoco']['wall_s']:.2f} s / "
              f"{got['mujoco']['engine_runs']} runs ({got['mujoco']['per_run_ms']:.1f} ms a run): {ratio:.2f}x; "
              f"without the engine-error run fast {loop['fast']['wall_s']:.2f} s ({loop['fast']['per_run_ms']:.1f} ms "
              f"a run), MuJoCo {loop['mujoco']['wall_s']:.2f} s ({loop['mujoco']['per_run_ms']:.1f} ms a run): "
              f"{loop_ratio:.2f}x; MuJoCo's floor {floor:.1f} ms a run "
              f"({floor / got['fast']['per_run_ms']:.2f}x the fast fit's); load {load_before:.2f} -> {rounds[-1]['load_after']:.2f}", flush=True)
    payload = {
        "command": f"python benchmarks/dropfit_ratio.py --repeat {args.repeat} --seed {args.seed} "
                   f"--fast-workers {args.fast_workers} --mujoco-workers {args.mujoco_workers}",
        "workers": workers, "rounds": rounds, "target": TARGET,
        "mujoco_over_fast_per_run": stats([r["mujoco_over_fast_per_run"] for r in rounds]),
        "per_run_ms": {e: stats([r[e]["per_run_ms"] for r in rounds]) for e in ("fast", "mujoco")},
        "wall_s": {e: stats([r[e]["wall_s"] for r in rounds]) for e in ("fast", "mujoco")},
        "engine_runs": {e: stats([r[e]["engine_runs"] for r in rounds]) for e in ("fast", "mujoco")},
        "fit_loop_mujoco_over_fast_per_run": stats([r["fit_loop_mujoco_over_fast_per_run"] for r in rounds]),
        "fit_loop_per_run_ms": {e: stats([r["fit_loop"][e]["per_run_ms"] for r in rounds]) for e in ("fast", "mujoco")},
        "fit_loop_wall_s": {e: stats([r["fit_loop"][e]["wall_s"] for r in rounds]) for e in ("fast", "mujoco")},
        "mujoco_floor_steps": steps,
        "mujoco_floor_per_run_ms": stats([r["mujoco_floor_per_run_ms"] for r in rounds]),
        "floor_over_fast_per_run": stats([r["floor_over_fast_per_run"] for r in rounds]),
        "load": stats([x for r in rounds for x in (r["load_before"], r["load_after"])]),
    }
    s = payload["mujoco_over_fast_per_run"]
    print(f"MuJoCo fit / fast fit, per engine run: {s['median']:.2f}x ({s['min']:.2f}-{s['max']:.2f}); "
          f"target <= {TARGET}x; the fit loop alone {payload['fit_loop_mujoco_over_fast_per_run']['median']:.2f}x; "
          f"MuJoCo's floor ({steps} steps a run, bare with the callback, over {workers['mujoco']} threads) "
          f"{payload['floor_over_fast_per_run']['median']:.2f}x the fast fit's cost per run")
    print(f"wrote {write_json(__file__, payload, args.out)}")


if __name__ == "__main__":
    main()

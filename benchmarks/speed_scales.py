"""Speed at every scale (issue 14): the drop against MuJoCo's own stepping, whole-process start-up
against the ``import numpy, mujoco`` floor, peak memory of a long drop, and the fast engine against
the ODE reference and MuJoCo. Every ratio is between timings taken interleaved in this script.

(a) ``run_drop("S12")`` in-process against a bare ``mujoco.rollout`` of the shipped scene (as
    many steps at the coarse and at the fine step as run_drop makes, same integrator, the
    compiled fork callback installed) and against the
    same rollout without any callback. Target: run_drop <= 1.5x the bare stepping.
(b) Whole processes: ``mtbmj --help``, ``mtbmj drop S12`` (MuJoCo) and ``--engine fast``, against
    ``python -c "import numpy, mujoco"``. Targets: --help <= 2x, drop <= 3.5x.
(c) Peak RSS of whole ``mtbmj drop S12 --duration D`` processes (D = 15 and 150 s). Target: 150 s
    <= 450 MiB.
(d) The fast engine: S12 drops per second in-process (engine only, and whole ``run_drop``), the
    largest difference from the ODE reference on every preset (mm), against MuJoCo and the ODE.
(e) Whole ``mtbmj sweep S12 --engine fast`` commands of 200 Latin-hypercube variants (variants/s
    including start-up), against the same sweep on MuJoCo.

Measured at the step rule's default (RK4 at 1 ms, refined near stops, touchdown and fast sliding).

    python benchmarks/speed_scales.py [--repeat 7] [--skip a,b,c,d,e] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/speed_scales.json``,
outside the repository; ``--out benchmarks/results/speed_scales.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _bench import add_out_option, write_json

BIN = Path(sys.executable).with_name("mtbmj")
RSS = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, check=True); "
       "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")


def stats(values) -> dict:
    v = np.asarray(values, float)
    return {"median": float(np.median(v)), "min": float(v.min()), "max": float(v.max()),
            "iqr": float(np.subtract(*np.percentile(v, [75, 25]))), "n": int(v.size)}


def ratio(a, b) -> dict:
    """Median of a / median of b, and the spread of the pairwise ratios (interleaved pairs)."""
    r = np.asarray(a, float) / np.asarray(b, float)
    return {"ratio_of_medians": float(np.median(a) / np.median(b)), "pairwise_min": float(r.min()),
            "pairwise_max": float(r.max())}


def timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def part_a(repeat: int) -> dict:
    import mujoco
    from mujoco import rollout

    from mtbmj import compose, config
    from mtbmj.controllers import compiled, installed
    from mtbmj.drop import engine_mujoco, scene
    from mtbmj.drop.run import run_drop

    setup = compose.setup(config.load("S12"))
    info = run_drop("S12").trace.info
    # the MuJoCo steps run_drop makes: at the coarse step, and (near stops, touchdown, fast
    # sliding) at the fine step; the bare rollout makes as many of each
    fine_steps = info["steps_refined"] * info["substeps"]
    coarse_steps = info["steps_computed"] - fine_steps
    steps = info["steps_computed"]

    def step_all(model, data, state):
        rollout.rollout(model, data, state[None, :], nstep=coarse_steps)
        model.opt.timestep = setup.fine_timestep
        rollout.rollout(model, data, state[None, :], nstep=fine_steps)
        model.opt.timestep = setup.timestep

    def bare(with_callback: bool):
        sc = scene.build(setup)
        model = sc.model
        data = mujoco.MjData(model)
        data.qvel[sc.sled_dof] = setup.impact_speed
        data.qpos[sc.sled_qpos] = engine_mujoco.TOUCH_DEPTH_M
        mujoco.mj_forward(model, data)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, data, state, spec)
        if with_callback:
            callback = compiled.CompiledForkCallback(model, setup.fork)
            with installed(callback):
                start = time.perf_counter()
                step_all(model, data, state)
                return time.perf_counter() - start
        start = time.perf_counter()
        step_all(model, data, state)
        return time.perf_counter() - start

    run_drop("S12"), bare(True), bare(False)  # warm: numba, scipy, caches
    drop, cb, none = [], [], []
    for _ in range(repeat):
        drop.append(timed(lambda: run_drop("S12")))
        cb.append(bare(True))
        none.append(bare(False))
    out = {"steps": steps, "run_drop_s": stats(drop), "bare_with_compiled_callback_s": stats(cb),
           "bare_no_callback_s": stats(none), "run_drop_over_bare_callback": ratio(drop, cb),
           "run_drop_over_bare_no_callback": ratio(drop, none), "target": 1.5}
    print(f"(a) run_drop S12 {np.median(drop) * 1e3:.1f} ms; bare rollout with the compiled callback "
          f"{np.median(cb) * 1e3:.1f} ms ({out['run_drop_over_bare_callback']['ratio_of_medians']:.2f}x), "
          f"without {np.median(none) * 1e3:.1f} ms ({out['run_drop_over_bare_no_callback']['ratio_of_medians']:.2f}x)")
    return out


def part_b(repeat: int) -> dict:
    out_dir = tempfile.mkdtemp(prefix="mtbmj_bench_")
    commands = {
        "floor": [sys.executable, "-c", "import numpy, mujoco"],
        "help": [str(BIN), "--help"],
        "drop_mujoco": [str(BIN), "drop", "S12", "--quiet", "--out", out_dir],
        "drop_fast": [str(BIN), "drop", "S12", "--engine", "fast", "--quiet", "--out", out_dir],
    }
    for c in commands.values():  # warm: caches and the page cache
        subprocess.run(c, stdout=subprocess.DEVNULL, check=True)
    times = {k: [] for k in commands}
    for _ in range(repeat):
        for k, c in commands.items():
            times[k].append(timed(lambda: subprocess.run(c, stdout=subprocess.DEVNULL, check=True)))
    out = {k: stats(v) for k, v in times.items()}
    for k in ("help", "drop_mujoco", "drop_fast"):
        out[f"{k}_over_floor"] = ratio(times[k], times["floor"])
    out["targets"] = {"help": 2.0, "drop_mujoco": 3.5}
    print("(b) whole process: " + ", ".join(f"{k} {np.median(v):.2f} s" for k, v in times.items()) + "; "
          + ", ".join(f"{k} {out[f'{k}_over_floor']['ratio_of_medians']:.2f}x floor"
                      for k in ("help", "drop_mujoco", "drop_fast")))
    return out


def part_c() -> dict:
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for duration in (15, 150):
            command = [sys.executable, "-c", RSS, str(BIN), "drop", "S12", "--quiet", "--duration", str(duration),
                       "--out", str(Path(tmp) / f"d{duration}")]
            start = time.perf_counter()
            kib = int(subprocess.run(command, capture_output=True, text=True, check=True).stdout.split()[-1])
            out[f"{duration}s"] = {"peak_rss_MiB": kib / 1024, "wall_s": time.perf_counter() - start}
    per_step = (out["150s"]["peak_rss_MiB"] - out["15s"]["peak_rss_MiB"]) * 2**20 / ((150 - 15) / 1e-4)
    out.update({"bytes_per_engine_step": per_step, "target_150s_MiB": 450})
    print(f"(c) peak RSS: 15 s drop {out['15s']['peak_rss_MiB']:.0f} MiB, 150 s drop "
          f"{out['150s']['peak_rss_MiB']:.0f} MiB ({per_step:.0f} bytes per engine step kept)")
    return out


def part_d(repeat: int) -> dict:
    from mtbmj import compose, config
    from mtbmj.drop import engine_fast, engine_mujoco
    from mtbmj.drop.run import run_drop

    setup = compose.setup(config.load("S12"))
    engine_fast.run(setup), engine_mujoco.run(setup)
    fast, fast_whole, mj, ode = [], [], [], []
    for _ in range(repeat):
        fast.append(np.median([timed(lambda: engine_fast.run(setup)) for _ in range(20)]))
        fast_whole.append(timed(lambda: run_drop("S12", "fast")))
        mj.append(timed(lambda: engine_mujoco.run(setup)))
        ode.append(timed(lambda: run_drop("S12", "ode")))
    accuracy = {}
    for name in config.study_presets():
        a, b = run_drop(name, "fast"), run_drop(name, "ode")
        accuracy[name] = max(d["max_abs_mm"] for d in a.difference(b).values())
    out = {"fast_engine_s": stats(fast), "fast_run_drop_s": stats(fast_whole), "mujoco_engine_s": stats(mj),
           "ode_run_drop_s": stats(ode), "fast_drops_per_s_engine": 1.0 / float(np.median(fast)),
           "fast_drops_per_s_run_drop": 1.0 / float(np.median(fast_whole)),
           "mujoco_engine_over_fast_engine": ratio(mj, fast), "ode_over_fast_run_drop": ratio(ode, fast_whole),
           "max_diff_from_ode_mm": accuracy, "worst_mm": max(accuracy.values()), "target_mm": 0.01,
           "target_drops_per_s": 1000}
    print(f"(d) fast engine S12 {np.median(fast) * 1e3:.2f} ms ({out['fast_drops_per_s_engine']:.0f} drops/s engine, "
          f"{out['fast_drops_per_s_run_drop']:.0f}/s whole run_drop); MuJoCo engine "
          f"{out['mujoco_engine_over_fast_engine']['ratio_of_medians']:.1f}x slower; worst difference from the ODE "
          f"on S1-S14 {out['worst_mm']:.1e} mm")
    return out


def part_e(repeat: int) -> dict:
    out = {}
    times = {"fast": [], "mujoco": []}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeat):
            for engine in times:
                command = [str(BIN), "sweep", "S12", "--engine", engine, "--samples", "200", "--seed", "1",
                           "--vary", "fork.spring.preload_N=150:300", "--vary", "tire.impact_rate_N_per_mm=75:95",
                           "--vary", "sled.drop_height_mm=60:130", "--quiet", "--out", str(Path(tmp) / f"{engine}{k}")]
                times[engine].append(timed(lambda: subprocess.run(command, stdout=subprocess.DEVNULL, check=True)))
    for engine, t in times.items():
        out[engine] = {"wall_s": stats(t), "variants_per_s": 200.0 / float(np.median(t))}
    out["mujoco_over_fast"] = ratio(times["mujoco"], times["fast"])
    out["target_fast_variants_per_s"] = 150
    print(f"(e) 200-variant sweep command: fast {out['fast']['variants_per_s']:.0f} variants/s, MuJoCo "
          f"{out['mujoco']['variants_per_s']:.0f} variants/s")
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--skip", default="", help="comma-separated parts to skip, e.g. c,e")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    skip = set(args.skip.split(","))
    payload = {"command": f"python benchmarks/speed_scales.py --repeat {args.repeat}"
               + (f" --skip {args.skip}" if args.skip else ""), "load_before": os.getloadavg()[0]}
    parts = {"a": lambda: part_a(args.repeat), "b": lambda: part_b(args.repeat), "c": part_c,
             "d": lambda: part_d(args.repeat), "e": lambda: part_e(args.repeat)}
    for key, fn in parts.items():
        if key not in skip:
            payload[key] = fn()
    print(f"wrote {write_json(__file__, payload, args.out)}")


if __name__ == "__main__":
    main()

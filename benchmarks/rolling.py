"""Real-time factor of a 10 s rolling run over the washboard at default settings (S12, 5 m/s,
head angle 65 deg, dt 1e-4 s, implicitfast): simulated time / engine wall time, best of N, one core
(one process, rollout single-threaded). Target (issue 5): >= 10x. Not a test: nothing is asserted.

The default path is the compiled rolling callback (``mtbmj.rolling.callback_compiled``: fork law,
radial tire and its patch search in numba); the Python ``RollCallback`` (the specification and the
fallback without numba) is timed in the same run, and the two runs are compared (max |diff| of the
raw fork, tire and axle signals). The compile (or load from numba's cache) happens before the
timed engine loop and is reported separately.

    python benchmarks/rolling.py [--repeat N] [--python-repeat M] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/rolling.json``,
outside the repository; ``--out benchmarks/results/rolling.json`` refreshes the committed file).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from mtbmj.rolling.frontend import run_roll
from _bench import add_out_option, write_json

SIMULATED_S = 10.0
SPEED = 5.0
COMPARED = ("fork_mm", "tire_mm", "fork_force_N", "axle_force_x_N", "axle_force_z_N", "tire_force_N")


def timed(callback: str, repeat: int):
    walls, totals, result = [], [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = run_roll("washboard", SPEED, duration=SIMULATED_S, callback=callback)
        totals.append(time.perf_counter() - start)
        walls.append(result.wall_time_s)
    return walls, totals, result


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=5, help="runs on the default (compiled) path")
    parser.add_argument("--python-repeat", type=int, default=1, help="runs on the Python path (0: skip)")
    add_out_option(parser, __file__)
    args = parser.parse_args()

    start = time.perf_counter()
    from mtbmj.rolling import callback_compiled as compiled_rolling

    load_s = time.perf_counter() - start
    walls, totals, result = timed("auto", args.repeat)
    best = min(walls)
    rtf = SIMULATED_S / best
    kind = result.info["callback"]
    print(f"washboard, {SIMULATED_S:g} s at {SPEED:g} m/s, {kind} callback: engine {best:.3f} s (best of "
          f"{args.repeat}), {rtf:.2f}x real time (target >= 10x: {'met' if rtf >= 10 else 'NOT met'}); "
          f"end to end incl. outputs {min(totals):.2f} s; numba compile/cache load {load_s:.2f} s")
    payload = {
        "scenario": "washboard", "speed_m_per_s": SPEED, "simulated_s": SIMULATED_S, "config": "S12",
        "callback": kind, "compile_or_cache_load_s": load_s,
        "engine_wall_s_best": best, "engine_wall_s_all": walls, "end_to_end_s_all": totals,
        "real_time_factor": rtf, "target_real_time_factor": 10.0, "met": rtf >= 10.0, "engine_info": result.info,
    }
    if args.python_repeat > 0:
        py_walls, py_totals, py_result = timed("python", args.python_repeat)
        py_rtf = SIMULATED_S / min(py_walls)
        diff = {name: float(np.max(np.abs(result.raw[name] - py_result.raw[name]))) for name in COMPARED}
        print(f"  python callback: engine {min(py_walls):.2f} s (best of {args.python_repeat}), {py_rtf:.2f}x real "
              f"time; speed-up {py_rtf and rtf / py_rtf:.1f}x; max |compiled - python|: "
              + ", ".join(f"{k} {v:.1e}" for k, v in diff.items()))
        payload["python"] = {"engine_wall_s_best": min(py_walls), "engine_wall_s_all": py_walls,
                             "end_to_end_s_all": py_totals, "real_time_factor": py_rtf,
                             "engine_info": py_result.info}
        payload["speed_up"] = rtf / py_rtf
        payload["max_abs_difference_compiled_vs_python"] = diff
    path = write_json(__file__, payload, args.out)
    print(f"wrote {path}")
    del compiled_rolling


if __name__ == "__main__":
    main()

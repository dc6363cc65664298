"""Real-time factor of a 10 s rolling run over the washboard at default settings (S12, 5 m/s,
head angle 65 deg, dt 1e-4 s, implicitfast): simulated time / engine wall time, best of N, one core
(one process, rollout single-threaded). Target (issue 5): >= 10x. Not a test: nothing is asserted.

    /work/venv/bin/python benchmarks/rolling.py [--repeat N]

Writes benchmarks/results/rolling.json.
"""
from __future__ import annotations

import argparse
import time

from mtbmj.rolling import run_roll
from _bench import write_json

SIMULATED_S = 10.0
SPEED = 5.0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    walls, totals, info = [], [], None
    for _ in range(args.repeat):
        start = time.perf_counter()
        r = run_roll("washboard", SPEED, duration=SIMULATED_S)
        totals.append(time.perf_counter() - start)
        walls.append(r.wall_time_s)
        info = r.info
    best = min(walls)
    rtf = SIMULATED_S / best
    print(f"washboard, {SIMULATED_S:g} s at {SPEED:g} m/s: engine {best:.2f} s (best of {args.repeat}), "
          f"{rtf:.2f}x real time (target >= 10x: {'met' if rtf >= 10 else 'NOT met'}); "
          f"end to end incl. outputs {min(totals):.2f} s")
    path = write_json(__file__, {
        "scenario": "washboard", "speed_m_per_s": SPEED, "simulated_s": SIMULATED_S, "config": "S12",
        "engine_wall_s_best": best, "engine_wall_s_all": walls, "end_to_end_s_all": totals,
        "real_time_factor": rtf, "target_real_time_factor": 10.0, "met": rtf >= 10.0, "engine_info": info,
    })
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

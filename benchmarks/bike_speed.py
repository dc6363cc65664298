"""Speed of the whole bike (``mtbmj bike``) on a rock garden, on one core, as real-time factors
(simulated seconds per wall second) and as a ratio against the rolling front end (``mtbmj roll``)
on the same profile, interleaved (bike, front end, bike, ...) so both see the same machine load.

    python benchmarks/bike_speed.py [--repeats 5] [--duration 1.0] [--speed 5]

Prints each repetition and the median and spread (min-max) of each real-time factor and of their
ratio. Only the stepping is timed (``simulate``): building the model and the static equilibrium
are not. The rock garden is seven rocks 50-110 mm high over 3 m (the profile of
tests/test_bike_energy.py), written to a temporary CSV.
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time
from pathlib import Path


def rock_garden(path: Path) -> Path:
    rows = [(-1.5, 0.0), (0.45, 0.0)]
    rocks = [(0.45, 0.25, 80), (0.85, 0.30, 110), (1.3, 0.2, 60), (1.65, 0.35, 100), (2.15, 0.25, 70),
             (2.55, 0.3, 90), (3.0, 0.2, 50)]
    for start, length, height in rocks:
        for k in range(1, 40):
            a = math.pi * (1 - k / 40)
            rows.append((start + length / 2 * (1 + math.cos(a)), height * math.sin(a)))
        rows.append((start + length, 0.0))
        rows.append((start + length + 0.1, 0.0))
    rows.append((8.0, 0.0))
    path.write_text("distance_m,height_mm\n" + "\n".join(f"{x:.6f},{z:.4f}" for x, z in rows) + "\n")
    return path


def bike_rtf(profile: str, speed: float, duration: float) -> float:
    from mtbmj.bike.run import prepare, simulate

    p = prepare("sst", profile, speed)
    start = time.perf_counter()
    simulate(p, duration)
    return duration / (time.perf_counter() - start)


def roll_rtf(profile: str, speed: float, duration: float) -> tuple[float, str]:
    from mtbmj.rolling import frontend

    p = frontend.prepare(profile, speed)
    start = time.perf_counter()
    frontend.simulate(p, duration)
    return duration / (time.perf_counter() - start), frontend.callback_kind(p.callback)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run")
    ap.add_argument("--speed", type=float, default=5.0)
    args = ap.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    with tempfile.TemporaryDirectory() as tmp:
        profile = str(rock_garden(Path(tmp) / "rock_garden.csv"))
        roll_rtf(profile, args.speed, 0.05)  # warm-up: imports, numba compilation of the front end's callback
        bike_rtf(profile, args.speed, 0.05)
        bikes, rolls, ratios = [], [], []
        for i in range(args.repeats):
            b = bike_rtf(profile, args.speed, args.duration)
            r, kind = roll_rtf(profile, args.speed, args.duration)
            bikes.append(b)
            rolls.append(r)
            ratios.append(b / r)
            print(f"repeat {i + 1}: bike {b:.3f}x real time, front end ({kind} callback) {r:.2f}x, ratio {b / r:.4f}",
                  flush=True)

    def line(name, values, unit):
        return (f"{name}: median {statistics.median(values):.4g}{unit}, spread {min(values):.4g}-{max(values):.4g}"
                f"{unit} over {len(values)} repeats")

    print(line("bike (sst, rock garden)", bikes, "x real time"))
    print(line("front end (S12, same profile)", rolls, "x real time"))
    print(line("bike / front end", ratios, ""))


if __name__ == "__main__":
    main()

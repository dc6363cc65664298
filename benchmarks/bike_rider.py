"""Step cost of the active rider (``--rider active``) against the passive one on the same ride, on
one core, as real-time factors (simulated seconds per wall second): the SST bike over a rock at
4 m/s (a ride both riders finish), the compiled bike callback under both, and the passive rider on
the Python callback beside them (the active rider's own forces are Python); interleaved (each
repetition runs all three) so they see the same machine load.

    python benchmarks/bike_rider.py [--repeats 5] [--duration 2] [--out PATH]

Prints each repetition, then the median and spread (min-max) of each real-time factor and of the
ratios passive / active (how many times the passive rider's step the active rider's costs), and
writes them where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/bike_rider.json``, outside
the repository; ``--out benchmarks/results/bike_rider.json`` writes a committed file). Only the
stepping is timed (``simulate``): building the model, the static equilibrium and the active
rider's settling are not.
"""
from __future__ import annotations

import argparse
import statistics
import time

RIDE = "rock:at_m=0.4"
SPEED = 4.0


def rtf(duration: float, rider: str, callback: str = "compiled") -> float:
    """Real-time factor of one run of ``rider`` ("passive" or "active") on ``callback``."""
    from mtbmj.bike.run import prepare, simulate

    p = prepare("sst", RIDE, SPEED, callback=callback, rider=rider)
    start = time.perf_counter()
    simulate(p, duration)
    return duration / (time.perf_counter() - start)


def main() -> None:
    from _bench import add_out_option, load_average, pin_one_core, stats, write_json

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--duration", type=float, default=2.0, help="simulated seconds per run")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    pin_one_core()
    before = load_average()
    print(f"load average before: {before}", flush=True)
    for rider in ("passive", "active"):  # warm-up: imports, numba compilation of the compiled callback
        rtf(0.05, rider)
    rows: dict[str, list[float]] = {k: [] for k in ("passive", "active", "passive_python", "passive_over_active",
                                                     "passive_python_over_active")}
    for i in range(args.repeats):
        pa, ac, py = rtf(args.duration, "passive"), rtf(args.duration, "active"), rtf(args.duration, "passive", "python")
        for key, value in (("passive", pa), ("active", ac), ("passive_python", py), ("passive_over_active", pa / ac),
                           ("passive_python_over_active", py / ac)):
            rows[key].append(value)
        print(f"repeat {i + 1}: passive {pa:.2f}x real time, active {ac:.2f}x, passive on the Python callback "
              f"{py:.3f}x; passive / active {pa / ac:.2f}", flush=True)
    after = load_average()
    for key, values in rows.items():
        print(f"{key}: median {statistics.median(values):.4g}, spread {min(values):.4g}-{max(values):.4g}")
    print(f"load average after: {after}")
    path = write_json(__file__, {"settings": {"bike": "sst", "terrain": RIDE, "speed_m_per_s": SPEED,
                                              "duration_s": args.duration, "repeats": args.repeats,
                                              "load_before": before, "load_after": after},
                                 "real_time_factors": {k: stats(v) for k, v in rows.items()}}, args.out)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

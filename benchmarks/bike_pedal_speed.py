"""Speed of a pedalling bike (``mtbmj bike ... --pedal RPM``) against the same bike held at the
same speed by the rider's drive, on one core, as real-time factors (simulated seconds per wall
second): the SST bike in 32x42 up a 14 % climb, standing and seated at 60 rpm and 250 W, the compiled
callback, and the rider's speed controller at the gear's speed at 60 rpm; interleaved (each
repetition runs all three) so they see the same machine load. The Python callback's pedalling run
is timed once per repetition over ``--python-duration`` s.

    python benchmarks/bike_pedal_speed.py [--repeats 5] [--duration 4] [--python-duration 0.5] [--out PATH]

Prints each repetition, then the median and spread (min-max) of each real-time factor and of the
ratios pedalling / rider drive (what the pedalling rider's forces cost over the drive's), and writes
them where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/bike_pedal_speed.json``, outside
the repository; ``--out benchmarks/results/bike_pedal_speed.json`` writes a committed file). Only
the stepping is timed (``simulate``): building the model and the static equilibrium are not.
"""
from __future__ import annotations

import argparse
import statistics
import time

CLIMB = "climb:grade_percent=14,length_m=40,at_m=0.5"
GEAR = {"drive.chainring_teeth": 32, "drive.cog_teeth": 42}
CADENCE_RPM, POWER_W = 60.0, 250.0


def rtf(duration: float, mode: str, callback: str = "compiled") -> float:
    """Real-time factor of one run: ``mode`` "standing", "seated" (pedalling) or "drive" (the rider's
    speed controller at the gear's speed at CADENCE_RPM)."""
    from mtbmj.bike.run import callback_kind, prepare, simulate

    if mode == "drive":
        p = prepare("sst", CLIMB, _gear_speed(), callback=callback, overrides=GEAR)
    else:
        p = prepare("sst", CLIMB, None, callback=callback, overrides=GEAR, pedal=(CADENCE_RPM, POWER_W),
                    seated=mode == "seated")
    assert callback_kind(p.callback) == callback
    start = time.perf_counter()
    simulate(p, duration)
    return duration / (time.perf_counter() - start)


def _gear_speed() -> float:
    from mtbmj.bike import spec as spec_mod
    from mtbmj.bike.run import gear_speed, setups

    spec = spec_mod.load("sst", GEAR)
    return gear_speed(spec, CADENCE_RPM, setups(spec)[0].tire_radius)


def main() -> None:
    from _bench import add_out_option, load_average, pin_one_core, stats, write_json

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--duration", type=float, default=4.0, help="simulated seconds per compiled run")
    ap.add_argument("--python-duration", type=float, default=0.5, help="simulated seconds of the Python run")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    pin_one_core()
    before = load_average()
    print(f"load average before: {before}", flush=True)
    for mode in ("drive", "standing"):  # warm-up: imports, numba compilation of the compiled callback
        rtf(0.05, mode)
    rows: dict[str, list[float]] = {k: [] for k in ("drive", "standing", "seated", "python_standing",
                                                     "standing_over_drive", "seated_over_drive",
                                                     "compiled_over_python")}
    for i in range(args.repeats):
        d, st, se = rtf(args.duration, "drive"), rtf(args.duration, "standing"), rtf(args.duration, "seated")
        py = rtf(args.python_duration, "standing", "python")
        for key, value in (("drive", d), ("standing", st), ("seated", se), ("python_standing", py),
                           ("standing_over_drive", st / d), ("seated_over_drive", se / d),
                           ("compiled_over_python", st / py)):
            rows[key].append(value)
        print(f"repeat {i + 1}: rider drive {d:.2f}x real time, pedalling standing {st:.2f}x, seated {se:.2f}x, "
              f"Python standing {py:.3f}x; standing / drive {st / d:.3f}, seated / drive {se / d:.3f}", flush=True)
    after = load_average()
    for key, values in rows.items():
        print(f"{key}: median {statistics.median(values):.4g}, spread {min(values):.4g}-{max(values):.4g}")
    print(f"load average after: {after}")
    path = write_json(__file__, {"settings": {"terrain": CLIMB, "gear": "32x42", "cadence_rpm": CADENCE_RPM,
                                              "power_W": POWER_W, "duration_s": args.duration,
                                              "python_duration_s": args.python_duration, "repeats": args.repeats,
                                              "load_before": before, "load_after": after},
                                 "real_time_factors": {k: stats(v) for k, v in rows.items()}}, args.out)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

"""The rolling cross-check over the terrain library (issue 25): every fixed terrain of
``mtbmj.rolling.terrain`` at 2 and 5 m/s, MuJoCo (``mtbmj roll``, default settings: the rider's
drive, compiled callback) against the rolling ODE reference (``mtbmj.rolling.reference``). Reported
per run: the largest differences of fork travel, body and axle height and tire deflection (mm) and
of the axle force peaks and series (relative to the reference's peak), whether the fork is within
0.02 mm and the peaks within 1 %, and both wall times: each row is the cross-check's ``to_dict``.
The drum (a moving surface) has no reference.

    python benchmarks/rolling_crosscheck.py [--duration 1.0] [--speeds 2,5] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/rolling_crosscheck.json``,
outside the repository; ``--out benchmarks/results/rolling_crosscheck.json`` refreshes the committed file). Not a test: nothing is asserted (the test suite
checks three of these runs, tests/test_rolling_reference.py).
"""
from __future__ import annotations

import argparse

from _bench import add_out_option, write_json

from mtbmj.rolling.reference import crosscheck

TERRAINS = ("flat", "step_up", "step_down", "square_edge", "root", "rock", "drop", "washboard", "iso8608")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run (the feature comes at 0.4 m)")
    ap.add_argument("--speeds", default="2,5")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    rows = []
    for speed in (float(s) for s in args.speeds.split(",")):
        for terrain in TERRAINS:
            spec = terrain if terrain == "flat" else f"{terrain}:at_m=0.4"  # the feature 0.4 m ahead
            check = crosscheck(spec, speed, duration=args.duration)
            rows.append(check.to_dict())  # the one cross-check result (mtbmj.runpath.crosscheck), wall times included
            print(check.line(), flush=True)
    worst_fork = max(r["signals"]["fork"]["max_abs"] for r in rows)
    worst_peak = max(r["signals"][name]["peak_difference"] for r in rows
                     for name in ("axle_force_up", "axle_force_back"))
    summary = {"runs": len(rows), "passed": sum(r["passed"] for r in rows), "worst_fork_mm": worst_fork,
               "worst_force_peak_relative": worst_peak, "duration_s": args.duration, "speeds": args.speeds}
    print(summary)
    print(f"wrote {write_json(__file__, {'summary': summary, 'rows': rows}, args.out)}")


if __name__ == "__main__":
    main()

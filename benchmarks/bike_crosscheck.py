"""The bike's cross-check over the terrain library (issue 26): every fixed terrain of
``mtbmj.rolling.terrain`` at 4 and 6 m/s, the SST bike on MuJoCo (``mtbmj bike``, default
settings: the rider's drive, compiled callback, the 0.5 ms step with the fine step near a stop or
the rim) against the bike's ODE reference (``mtbmj.bike.reference``, rtol 1e-8 as ``mtbmj
crosscheck``). Reported per run: the largest differences of front and rear wheel travel and shock
stroke (mm) and pitch (deg), the tire loads' peaks and series (relative to the reference's peak),
the fraction of the run stepped at the fine step, whether travel is within 0.1 mm and the tire loads
within 1 %, and both wall times: each row is the cross-check's ``to_dict``. The
feature is 0.4 m ahead of the front axle; the washboard runs 5 m, the ISO 8608 profile is class D
over 10 m. The drum holds a single wheel: no bike rolls on it.

    python benchmarks/bike_crosscheck.py [--duration 0.6] [--speeds 4,6] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/bike_crosscheck.json``,
outside the repository; ``--out benchmarks/results/bike_crosscheck.json`` refreshes the committed file). Not a test: nothing is asserted (the test suite
runs every terrain at both speeds for as long as both wheels need to cross the feature,
tests/test_bike_reference.py).
"""
from __future__ import annotations

import argparse

from _bench import add_out_option, write_json

from mtbmj.bike.crosscheck import crosscheck

TERRAINS = ("flat", "step_up:at_m=0.4", "step_down:at_m=0.4", "square_edge:at_m=0.4", "root:at_m=0.4",
            "rock:at_m=0.4", "drop:at_m=0.4", "washboard:at_m=0.4,length_m=5", "iso8608:at_m=0.4,class=D,length_m=10")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=0.6, help="simulated seconds per run")
    ap.add_argument("--speeds", default="4,6")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    rows = []
    for speed in (float(s) for s in args.speeds.split(",")):
        for terrain in TERRAINS:
            check = crosscheck("sst", terrain, speed, duration=args.duration)
            rows.append(check.to_dict())  # the one cross-check result (mtbmj.runpath.crosscheck), wall times included
            print(check.line(), flush=True)
    travel = ("front_travel", "rear_travel", "shock_stroke")
    tires = ("front_tire_load", "rear_tire_load")
    worst = max(r["signals"][k]["max_abs"] for r in rows for k in travel)
    worst_at = max(rows, key=lambda r: max(r["signals"][k]["max_abs"] for k in travel))
    worst_peak = max(r["signals"][k]["peak_difference"] for r in rows for k in tires)
    worst_series = max(r["signals"][k]["series_difference"] for r in rows for k in tires)
    summary = {"runs": len(rows), "passed": sum(r["passed"] for r in rows), "worst_travel_mm": worst,
               "worst_scenario": worst_at["context"]["scenario"],
               "worst_speed_m_per_s": worst_at["context"]["speed_m_per_s"], "worst_tire_peak_relative": worst_peak,
               "worst_tire_series_relative": worst_series,
               "refined_runs": sum(r["context"]["refined_fraction"] > 0 for r in rows),
               "duration_s": args.duration, "speeds": args.speeds}
    print(summary)
    print(f"wrote {write_json(__file__, {'summary': summary, 'rows': rows}, args.out)}")


if __name__ == "__main__":
    main()

"""The bike's cross-check over the terrain library (issue 26): every fixed terrain of
``mtbmj.rolling.terrain`` at 4 and 6 m/s, the SST bike on MuJoCo (``mtbmj bike``, default
settings: the rider's drive, compiled callback, the 0.5 ms step with the fine step near a stop or
the rim) against the bike's ODE reference (``mtbmj.bike.reference``, rtol 1e-8 as ``mtbmj
crosscheck``). Reported per run: the largest differences of front and rear wheel travel and shock
stroke (mm) and pitch (deg), the tire-load peaks (relative), the fraction of the run stepped at the
fine step, whether travel is within 0.1 mm and the peaks within 1 %, and both wall times. The
feature is 0.4 m ahead of the front axle; the washboard runs 5 m, the ISO 8608 profile is class D
over 10 m. The drum holds a single wheel: no bike rolls on it.

    python benchmarks/bike_crosscheck.py [--duration 0.6] [--speeds 4,6]

Writes benchmarks/results/bike_crosscheck.json. Not a test: nothing is asserted (the test suite
runs every terrain at both speeds for as long as both wheels need to cross the feature,
tests/test_bike_reference.py).
"""
from __future__ import annotations

import argparse

from _bench import write_json

from mtbmj.bike.crosscheck import crosscheck

TERRAINS = ("flat", "step_up:at_m=0.4", "step_down:at_m=0.4", "square_edge:at_m=0.4", "root:at_m=0.4",
            "rock:at_m=0.4", "drop:at_m=0.4", "washboard:at_m=0.4,length_m=5", "iso8608:at_m=0.4,class=D,length_m=10")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=0.6, help="simulated seconds per run")
    ap.add_argument("--speeds", default="4,6")
    args = ap.parse_args()
    rows = []
    for speed in (float(s) for s in args.speeds.split(",")):
        for terrain in TERRAINS:
            check = crosscheck("sst", terrain, speed, duration=args.duration)
            rows.append(check.to_dict() | {"engine_wall_s": check.engine_wall_s,
                                           "reference_wall_s": check.reference_wall_s})
            print(check.line(), flush=True)
    travel = ("front_travel_mm", "rear_travel_mm", "stroke_mm")
    worst = max(r["differences"][k]["max_abs_mm"] for r in rows for k in travel)
    worst_at = max(rows, key=lambda r: max(r["differences"][k]["max_abs_mm"] for k in travel))
    worst_peak = max(p["relative"] for r in rows for p in r["tire_load_peaks"].values())
    summary = {"runs": len(rows), "passed": sum(r["passed"] for r in rows), "worst_travel_mm": worst,
               "worst_scenario": worst_at["scenario"], "worst_speed_m_per_s": worst_at["speed_m_per_s"],
               "worst_tire_peak_relative": worst_peak, "refined_runs": sum(r["refined_fraction"] > 0 for r in rows),
               "duration_s": args.duration, "speeds": args.speeds}
    print(summary)
    print(f"wrote {write_json(__file__, {'summary': summary, 'rows': rows})}")


if __name__ == "__main__":
    main()

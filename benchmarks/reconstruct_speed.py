"""``mtbmj reconstruct`` timed by its stages on one ride (issue 51 item 6: the command's speed).

    python benchmarks/reconstruct_speed.py [--ride example] [--bike sst] [--repeats 2] [--out PATH]

Each repetition reconstructs the ride in this process (``mtbmj.ride.reconstruct.reconstruct``) with
its stages timed by wrappers around them: the two ends' quarter-car inverses
(``reconstruct_inverse.ground_under``), the speed per window (``reconstruct_speed.speed_from_either``),
the whole bike's passes (``reconstruct_bike.ride``: the terrain found, pass by pass, and the free
check), and the rest. Prints each repetition, then the medians of the wall time, its ratio to the
ride's length (the issue's target: 10 s per 100 s of ride, a ratio of 0.1), and each stage's share of
the wall time; the whole bike's cost per pass per second of ride. Writes its results where ``--out``
says (default ``<tempdir>/mtbmj-benchmarks/reconstruct_speed.json``, outside the repository). Not a
test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, add_ride_options, read_ride, ride_options_shown, write_json  # noqa: E402


def _timed(module, name: str, spent: dict):
    """``module.name`` wrapped: its calls and their wall time added to ``spent[name]``."""
    real = getattr(module, name)

    def wrapper(*a, **k):
        t0 = time.perf_counter()
        try:
            return real(*a, **k)
        finally:
            calls, s = spent.get(name, (0, 0.0))
            spent[name] = (calls + 1, s + time.perf_counter() - t0)

    setattr(module, name, wrapper)
    return real


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_ride_options(ap, repeats=2)
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from mtbmj.bike import spec
    from mtbmj.ride import reconstruct, reconstruct_bike

    bike = spec.resolve(args.bike)
    record = read_ride(args, bike)
    seconds = float(record.time_s[-1] - record.time_s[0])
    rows = []
    for i in range(args.repeats):
        spent: dict = {}
        saved = [(reconstruct, "ground_under", _timed(reconstruct, "ground_under", spent)),
                 (reconstruct, "speed_from_either", _timed(reconstruct, "speed_from_either", spent)),
                 (reconstruct_bike, "ride", _timed(reconstruct_bike, "ride", spent))]
        t0 = time.perf_counter()
        try:
            rec = reconstruct.reconstruct(record, bike)
        finally:
            for module, name, real in saved:
                setattr(module, name, real)
        wall = time.perf_counter() - t0
        stages = {"quarter_car_inverses_s": spent.get("ground_under", (0, 0.0))[1],
                  "speed_s": spent.get("speed_from_either", (0, 0.0))[1],
                  "whole_bike_s": spent.get("ride", (0, 0.0))[1]}
        stages["rest_s"] = wall - sum(stages.values())
        passes = spent.get("ride", (0, 0.0))[0]
        row = {"wall_s": wall, "ratio_to_ride": wall / seconds, **stages, "whole_bike_passes": passes,
               "whole_bike_s_per_pass_per_ride_s": stages["whole_bike_s"] / max(passes, 1) / seconds,
               "shares": {k[:-2]: v / wall for k, v in stages.items()}, "passes_check": rec.checks()["passes"]}
        rows.append(row)
        print(f"repeat {i + 1}: {wall:.1f} s on {seconds:.0f} s of ride (ratio {row['ratio_to_ride']:.2f}); "
              + ", ".join(f"{k} {100 * v:.0f} %" for k, v in row["shares"].items())
              + f"; {passes} whole-bike passes", flush=True)

    def median(key, sub=None):
        return statistics.median(r[key] if sub is None else r[key][sub] for r in rows)

    out = {"command": "python benchmarks/reconstruct_speed.py"
                      + ride_options_shown(args)
                      + f" --repeats {args.repeats} --out benchmarks/results/reconstruct_speed.json",
           "ride": record.name, "ride_seconds": seconds, "repeats": rows,
           "wall_s": median("wall_s"), "ratio_to_ride": median("ratio_to_ride"), "target_ratio": 0.1,
           "shares": {k: median("shares", k) for k in rows[0]["shares"]},
           "whole_bike_passes": median("whole_bike_passes"),
           "whole_bike_s_per_pass_per_ride_s": median("whole_bike_s_per_pass_per_ride_s")}
    print(f"reconstruct {out['wall_s']:.1f} s on {seconds:.0f} s of ride: ratio {out['ratio_to_ride']:.2f} (target "
          f"0.1); the whole bike {100 * out['shares']['whole_bike']:.0f} % of it ({out['whole_bike_passes']:.0f} "
          f"passes, {out['whole_bike_s_per_pass_per_ride_s']:.3f} s per pass per second of ride)")
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The tyres' patch search with its shortcuts against the search before them (issue 52 item 7): the
bike over a reconstructed ride, the same run twice per repetition, interleaved, on one core.

    python benchmarks/patch_search.py [--ride example] [--bike sst] [--repeats 3] [--duration S] [--out PATH]

The ride is reconstructed and ridden as ``mtbmj advise`` rides it (``advise.terrain_of``, the ride's
speed along it, the rider's drive, the compiled callback); each repetition runs the bike ``--duration``
s (default: the ride's length) with ``plain_search`` set (``mtbmj.bike.callback_compiled``: each
segment cut into pieces at each search, every run of pieces through ``share_depths``, as the search
was) and unset (the profile cut once, the window found from the last search's, a run along which the
distance falls, then rises, taken at once), in alternating order. Prints and writes, per kind, the
CPU time of the stepping (``time.process_time``: the machine is shared) and its wall time, their
ratios now / before per repetition (median and spread), the searches counted (``refreshes``), the CPU
time saved per search, whether the two runs' states and sensors are equal to the bit, and the load
average before and after. Writes where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/
patch_search.json``, outside the repository). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, add_ride_options, load_average, pin_one_core, read_ride, ride_options_shown  # noqa: E402
from _bench import stats as spread_of, write_json  # noqa: E402


def one_run(bike, terrain, speed, profile, duration, plain):
    from mtbmj.bike.run import callback_kind, prepare, simulate

    p = prepare(bike, terrain, speed, drive="rider", speed_profile=profile, callback="compiled")
    assert callback_kind(p.callback) == "compiled"
    p.callback.plain_search = plain
    cpu, wall = time.process_time(), time.perf_counter()
    states, sensors = simulate(p, duration)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    return {"cpu_s": cpu, "wall_s": wall, "refreshes": int(p.callback.refreshes), "calls": int(p.callback.calls),
            "states": np.asarray(states), "sensors": np.asarray(sensors)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_ride_options(ap, repeats=3)
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds per run (default: the ride's)")
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from mtbmj.ride import advise, reconstruct

    record = read_ride(args)
    rec = reconstruct.reconstruct(record, args.bike)
    terrain = advise.terrain_of(rec)
    profile = rec.speed_along()
    speed = float(profile[1][0])
    seconds = float(record.time_s[-1] - record.time_s[0])
    duration = args.duration if args.duration is not None else seconds + 1.0 / speed
    pin_one_core()
    before = load_average()
    one_run(args.bike, terrain, speed, profile, 0.05, False)  # warm-up: the compiled callback loaded
    rows, identical = [], True
    for i in range(args.repeats):
        got = {}
        for plain in ((True, False) if i % 2 == 0 else (False, True)):
            got[plain] = one_run(args.bike, terrain, speed, profile, duration, plain)
        same = all(np.array_equal(got[True][k], got[False][k]) for k in ("states", "sensors")) \
            and got[True]["refreshes"] == got[False]["refreshes"]
        identical &= same
        b, a = got[True], got[False]
        row = {"before_cpu_s": b["cpu_s"], "now_cpu_s": a["cpu_s"], "before_wall_s": b["wall_s"],
               "now_wall_s": a["wall_s"], "cpu_ratio": a["cpu_s"] / b["cpu_s"], "wall_ratio": a["wall_s"] / b["wall_s"],
               "searches": a["refreshes"], "calls": a["calls"],
               "saved_us_per_search": 1e6 * (b["cpu_s"] - a["cpu_s"]) / max(a["refreshes"], 1),
               "identical": bool(same)}
        rows.append(row)
        print(f"repeat {i + 1}: before {b['cpu_s']:.2f} s CPU ({b['wall_s']:.2f} s wall), now {a['cpu_s']:.2f} s CPU "
              f"({a['wall_s']:.2f} s wall): now / before {row['cpu_ratio']:.3f} CPU, {row['wall_ratio']:.3f} wall; "
              f"{row['searches']} searches in {row['calls']} calls, {row['saved_us_per_search']:.2f} us saved a search; "
              f"states and sensors {'equal to the bit' if same else 'DIFFERENT'}", flush=True)
    after = load_average()

    def stats(key):
        return spread_of([r[key] for r in rows])

    out = {"command": f"python benchmarks/patch_search.py --repeats {args.repeats}" + ride_options_shown(args)
                      + (f" --duration {args.duration:g}" if args.duration is not None else ""),
           "ride": record.name, "duration_s": duration, "terrain_points": int(np.size(terrain.x)),
           "load_before": before, "load_after": after, "repeats": rows, "identical_to_the_bit": bool(identical),
           "cpu_ratio": stats("cpu_ratio"), "wall_ratio": stats("wall_ratio"), "before_cpu_s": stats("before_cpu_s"),
           "now_cpu_s": stats("now_cpu_s"), "saved_us_per_search": stats("saved_us_per_search")}
    print(f"now / before: CPU {out['cpu_ratio']['median']:.3f} ({out['cpu_ratio']['min']:.3f}-"
          f"{out['cpu_ratio']['max']:.3f}), wall {out['wall_ratio']['median']:.3f}; runs equal to the bit: {identical}; "
          f"load average {before} before, {after} after")
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

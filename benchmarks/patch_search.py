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
average before and after. Then one search alone: the axle positions of the searches of the ride's
first ``--log-seconds`` s (the Python callback's, logged), searched by the compiled kernel
(``update_patches`` on the bike's wheel rows) in a loop, both ways interleaved (2 x repeats + 1
times): the CPU time a search and whether every search's patches are equal to the bit. Writes where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/
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


def logged_searches(bike, terrain, speed, profile, seconds):
    """The axle positions of the searches of a bike run of ``seconds`` (the Python callback, its
    ``PatchSearch.refresh`` calls logged): rows (wheel 0 front / 1 rear, x, z, t)."""
    from mtbmj.bike.run import prepare, simulate
    from mtbmj.rolling import tire

    p = prepare(bike, terrain, speed, drive="rider", speed_profile=profile, callback="python")
    wheel = {id(s): k for k, s in enumerate(p.callback.search)}  # (front, rear)
    log = []
    refresh = tire.PatchSearch.refresh

    def logged(search, cx, cz, t=0.0):
        log.append((wheel[id(search)], cx, cz, t))
        return refresh(search, cx, cz, t)

    tire.PatchSearch.refresh = logged
    try:
        simulate(p, seconds)
    finally:
        tire.PatchSearch.refresh = refresh
    return np.array(log, dtype=np.float64)


def search_times(bike, terrain, speed, profile, log, repeats):
    """CPU time a search (``update_patches`` on a compiled bike's wheel rows, over the logged
    positions) with ``plain_search`` set and unset, interleaved; and whether every search's patches
    are equal to the bit."""
    import numba

    from mtbmj.bike import callback_compiled as BC
    from mtbmj.bike.run import prepare
    from mtbmj.rolling import search_compiled as S

    p = prepare(bike, terrain, speed, drive="rider", speed_profile=profile, callback="compiled")
    cb = p.callback
    rows = [(BC._WINTS[cb.slot, k * BC.WI:(k + 1) * BC.WI], BC._WFLOATS[cb.slot, k * BC.WF:(k + 1) * BC.WF])
            for k in (0, 1)]

    @numba.njit
    def run(I0, F0, I1, F1, log, out):
        for i in range(log.shape[0]):
            I, F = (I0, F0) if log[i, 0] == 0.0 else (I1, F1)
            S.update_patches(I, F, log[i, 1], log[i, 2], log[i, 3])
            if out.shape[0] > 0:
                out[i, 0] = I[S.R_NPATCH]
                for k in range(S.PATCH_WIDTH * I[S.R_NPATCH]):
                    out[i, 1 + k] = F[S.F_PATCHES + k]

    def once(plain, out):
        cb.plain_search = plain
        cb.reset()
        cpu = time.process_time()
        run(rows[0][0], rows[0][1], rows[1][0], rows[1][1], log, out)
        return 1e6 * (time.process_time() - cpu) / len(log)

    outs = {plain: np.full((len(log), 1 + S.PATCH_WIDTH * S.MAX_PATCHES), np.nan) for plain in (True, False)}
    for plain in (True, False):
        once(plain, outs[plain])
    identical = bool(np.array_equal(outs[True], outs[False], equal_nan=True))
    none = np.zeros((0, 1 + S.PATCH_WIDTH * S.MAX_PATCHES))
    got = {True: [], False: []}
    for i in range(repeats):
        for plain in ((True, False) if i % 2 == 0 else (False, True)):
            got[plain].append(once(plain, none))
    ratios = [a / b for a, b in zip(got[False], got[True])]
    return {"searches": len(log), "patches": int(np.nansum(outs[False][:, 0])), "identical": identical,
            "before_us": spread_of(got[True]), "now_us": spread_of(got[False]), "ratio": spread_of(ratios)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_ride_options(ap, repeats=3)
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds per run (default: the ride's)")
    ap.add_argument("--log-seconds", type=float, default=3.0,
                    help="seconds of the ride whose searches are logged and timed one by one (0: none)")
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
    searches = None
    if args.log_seconds > 0:
        log = logged_searches(args.bike, terrain, speed, profile, args.log_seconds)
        searches = search_times(args.bike, terrain, speed, profile, log, 2 * args.repeats + 1)
        print(f"{searches['searches']} searches logged over {args.log_seconds:g} s ({searches['patches']} patches), "
              f"CPU a search: before {searches['before_us']['median']:.3f} us, now {searches['now_us']['median']:.3f} "
              f"us, now / before {searches['ratio']['median']:.3f} ({searches['ratio']['min']:.3f}-"
              f"{searches['ratio']['max']:.3f}); patches {'equal to the bit' if searches['identical'] else 'DIFFERENT'}",
              flush=True)
    after = load_average()

    def stats(key):
        return spread_of([r[key] for r in rows])

    out = {"command": f"python benchmarks/patch_search.py --repeats {args.repeats}" + ride_options_shown(args)
                      + (f" --duration {args.duration:g}" if args.duration is not None else "")
                      + (f" --log-seconds {args.log_seconds:g}" if args.log_seconds != 3.0 else ""),
           "ride": record.name, "duration_s": duration, "terrain_points": int(np.size(terrain.x)),
           "load_before": before, "load_after": after, "repeats": rows, "identical_to_the_bit": bool(identical),
           "cpu_ratio": stats("cpu_ratio"), "wall_ratio": stats("wall_ratio"), "before_cpu_s": stats("before_cpu_s"),
           "now_cpu_s": stats("now_cpu_s"), "saved_us_per_search": stats("saved_us_per_search"),
           "one_search": searches}
    print(f"now / before: CPU {out['cpu_ratio']['median']:.3f} ({out['cpu_ratio']['min']:.3f}-"
          f"{out['cpu_ratio']['max']:.3f}), wall {out['wall_ratio']['median']:.3f}; runs equal to the bit: {identical}; "
          f"load average {before} before, {after} after")
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The calibration of ``mtbmj advise`` (``mtbmj.ride.calibrate.calibrate``) on a whole ride, timed
against one plain pass of both ends' laws over the same ride, interleaved.

    python benchmarks/calibrate_speed.py [--ride example] [--bike sst] [--repeats 3] [--out PATH]

Each repetition times, in this process and on its CPU clock (the machine is shared; its wall time is
recorded beside): the baseline, one pass of each end's whole suspension force (its law at the
recorded travel and speed, the rear through the leverage) over every sample of the ride at the bike
file's springs, in a plain per-sample loop written here; then the whole calibration (both ends'
bisections on the spring's scale and their intervals). The ratio calibration / pass says how many
such passes the calibration costs; the calibration's scales are recorded, so runs of two versions
can be told to answer the same. Writes its results where ``--out`` says (default ``<tempdir>/
mtbmj-benchmarks/calibrate_speed.json``, outside the repository). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, add_ride_options, read_ride, ride_options_shown, write_json  # noqa: E402
from _bench import stats as spread_of  # noqa: E402


def one_pass(record, bike) -> None:
    """Both ends' whole force per sample over the ride at the bike file's springs (the baseline)."""
    import numpy as np

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod
    from mtbmj.measured import metrics
    from mtbmj.ride import reconstruct_bike
    from mtbmj.ride.reconstruct import RATE_HZ

    rec = record.decimated(RATE_HZ)
    t = np.asarray(rec.time_s, float)
    spec = spec_mod.load(bike)
    w = reconstruct_bike.whole_bike(spec, *bike_run.setups(spec))
    for end, travel in (("front", rec.fork_mm), ("rear", rec.rear_mm)):
        travel = np.asarray(travel, float)
        x, v = np.clip(travel, 0.0, None) * 1e-3, metrics.velocity(t, travel) * 1e-3
        law = w.fork if end == "front" else w.shock
        force = (lambda a, b: law.force(a, b, 0.0)) if law.has_state else law.force
        if end == "front":
            [force(a, b) / w.sin_a for a, b in zip(x, v)]
        else:
            ratio = np.array([w.lev.ratio_at(a) for a in x])
            [force(s, b / r) / r for s, b, r in zip(w.lev.strokes(x), v, ratio)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_ride_options(ap, repeats=3)
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from mtbmj.ride import calibrate

    record = read_ride(args)
    seconds = float(record.time_s[-1] - record.time_s[0])
    one_pass(record, args.bike)  # the laws loaded once before any timing
    rows = []
    for i in range(args.repeats):
        c0, t0 = time.process_time(), time.perf_counter()
        one_pass(record, args.bike)
        c_pass, w_pass = time.process_time() - c0, time.perf_counter() - t0
        c0, t0 = time.process_time(), time.perf_counter()
        cal = calibrate.calibrate(record, args.bike)
        c_cal, w_cal = time.process_time() - c0, time.perf_counter() - t0
        rows.append({"pass_cpu_s": c_pass, "pass_wall_s": w_pass, "calibrate_cpu_s": c_cal, "calibrate_wall_s": w_cal,
                     "ratio": c_cal / c_pass,
                     "scales": {e: [s.value, s.low, s.high] for e, s in cal.scales.items()}})
        print(f"repeat {i + 1}: one pass {c_pass:.2f} s CPU ({w_pass:.1f} s wall), calibration {c_cal:.2f} s CPU "
              f"({w_cal:.1f} s wall): {c_cal / c_pass:.1f} passes; {cal.line()}", flush=True)

    def stats(key):
        return spread_of([r[key] for r in rows])

    out = {"command": f"python benchmarks/calibrate_speed.py --repeats {args.repeats}"
                      + ride_options_shown(args)
                      + " --out benchmarks/results/calibrate_speed.json",
           "ride": record.name, "ride_seconds": seconds, "repeats": rows, "pass_cpu_s": stats("pass_cpu_s"),
           "calibrate_cpu_s": stats("calibrate_cpu_s"), "calibrate_wall_s": stats("calibrate_wall_s"),
           "ratio": stats("ratio")}
    print(f"calibration {out['calibrate_cpu_s']['median']:.2f} s CPU on {seconds:.0f} s of ride: "
          f"{out['ratio']['median']:.1f} passes of the laws over the ride")
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

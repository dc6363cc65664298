"""Do the drop fit's 95 % intervals mean what they say? Fit N synthetic sled records with
independent noise and count how often the interval holds the truth.

Each record: S12 with two values drawn within +/- 10 % (the truth: tire.impact_rate_N_per_mm and
fork.spring.preload_N), generated on the ODE reference (``engine="ode"``: an independent
integrator of the same laws, not the fitting engine), 0.15 mm white potentiometer noise at the
engine rate BEFORE the 400 Hz anti-aliasing filter (so the record's noise is coloured), 1 kHz
sampling, 0.02 mm white noise and 16-bit quantisation on the samples, a random free fall of 0 to
0.3 s in front of the touch and a random logger clock (time zero found by
``validation.time_zero``). Fitted on MuJoCo from the S12 start values. The issue's logger-clock
case (75 N/mm and 200 N, 50 ms of fall, touch at t = 7.3 s) is timed on its own.

Reported: the coverage of the reported intervals (Newey-West + engine error + touch uncertainty)
and, for comparison, of the white-noise intervals they replace (channel sandwich, normal
quantile); the largest error in %; the wall time per fit (median, spread).

    python benchmarks/interval_coverage.py [--records 20] [--seed 1] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/interval_coverage.json``,
outside the repository; ``--out benchmarks/results/interval_coverage.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import time

from _bench import add_out_option, write_json


import numpy as np  # noqa: E402

from mtbmj.drop.chain import resolve  # noqa: E402
from mtbmj.identify.drop_synthetic import make_drop_record  # noqa: E402
from mtbmj.identify.dropfit import fit_drop  # noqa: E402

KEYS = ("tire.impact_rate_N_per_mm", "fork.spring.preload_N")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--records", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0.6)
    add_out_option(ap, __file__)
    args = ap.parse_args()
    cfg = resolve("S12")
    rng = np.random.default_rng(args.seed)
    rows, walls = [], []
    for i in range(args.records):
        truth = {k: round(cfg[k] * rng.uniform(0.9, 1.1), 3) for k in KEYS}
        fall, offset = float(rng.choice([0.0, rng.uniform(0.003, 0.3)])), float(rng.uniform(0.0, 100.0))
        record = make_drop_record("S12", truth, duration=args.duration, engine="ode", seed=1000 + i, noise_mm=0.02,
                                  sensor_noise_mm=0.15, fall_s=fall, clock_offset_s=offset)
        start = time.perf_counter()
        result = fit_drop(record, "S12", free=list(KEYS), engine="mujoco")
        walls.append(time.perf_counter() - start)
        x = result.extra
        for k in KEYS:
            low, high = x["ci95"][k]
            white = 1.96 * x["stderr_white"][k]
            rows.append({"record": i, "key": k, "true": truth[k], "fitted": result.values[k],
                         "error_percent": 100.0 * (result.values[k] / truth[k] - 1.0),
                         "stderr": result.stderr[k], "ci95": [low, high], "covered": bool(low <= truth[k] <= high),
                         "white_stderr": x["stderr_white"][k],
                         "white_covered": bool(abs(result.values[k] - truth[k]) <= white),
                         "fall_s": fall, "touch_found_error_ms": (x["time_zero"]["touch_in_file_s"] - offset) * 1e3,
                         "time_zero_kind": x["time_zero"]["kind"], "hac_bandwidth_s": x["hac_bandwidth_s"],
                         "engine_runs": x["engine_runs"]})
        print(f"record {i}: " + ", ".join(f"{r['key'].rsplit('.', 1)[-1]} {r['error_percent']:+.3f} % "
                                          f"{'in' if r['covered'] else 'OUT'}" for r in rows[-2:])
              + f" ({walls[-1]:.1f} s)", flush=True)
    coverage = float(np.mean([r["covered"] for r in rows]))
    white = float(np.mean([r["white_covered"] for r in rows]))
    # the logger-clock record, timed
    truth = {"tire.impact_rate_N_per_mm": 75.0, "fork.spring.preload_N": 200.0}
    record = make_drop_record("S12", truth, duration=1.0, engine="ode", seed=7, fall_s=0.05, clock_offset_s=7.3)
    times, logger = [], None
    for _ in range(3):
        start = time.perf_counter()
        logger = fit_drop(record, "S12", free=list(truth), bounds={"tire.impact_rate_N_per_mm": (40.0, 120.0),
                                                                   "fork.spring.preload_N": (120.0, 320.0)})
        times.append(time.perf_counter() - start)
    payload = {
        "records": args.records, "intervals": len(rows), "coverage_95": coverage, "white_noise_coverage_95": white,
        "max_abs_error_percent": float(max(abs(r["error_percent"]) for r in rows)),
        "fit_wall_s": {"median": float(np.median(walls)), "min": float(np.min(walls)), "max": float(np.max(walls))},
        "logger_clock_fit": {
            "truth": truth, "fitted": logger.values, "ci95": logger.extra["ci95"],
            "error_percent": {k: 100.0 * (logger.values[k] / v - 1.0) for k, v in truth.items()},
            "time_zero": logger.extra["time_zero"]["description"],
            "wall_s": {"median": float(np.median(times)), "min": float(np.min(times)), "max": float(np.max(times))},
            "engine_runs": logger.extra["engine_runs"]},
        "rows": rows,
    }
    path = write_json(__file__, payload, args.out)
    print(f"coverage of the 95 % intervals: {coverage * 100:.1f} % of {len(rows)} (white-noise intervals: "
          f"{white * 100:.1f} %); logger-clock fit {np.median(times):.1f} s, errors "
          + ", ".join(f"{k} {v:+.3f} %" for k, v in payload["logger_clock_fit"]["error_percent"].items())
          + f"; wrote {path}")


if __name__ == "__main__":
    main()

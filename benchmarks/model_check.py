"""Does the drop fit's model check say the truth? False alarms on right models, detections on
wrong ones, and the coverage of the 95 % intervals, on records the fitting code did not make.

Every record comes from the test file's own generator (``tests/test_fit_honest.s1_record``: S1's
quarter car in closed form, or with Coulomb friction integrated by LSODA, through an analog 400 Hz
logger, 1 kHz, white noise, 16-bit). Fits free the two rates of S1 (tire impact rate, spring rate)
and run on the ODE engine.

- right model: rates drawn within +/- 15 % of S1's, noise 0.01-0.05 mm; the check should pass
  (target: at most 5 % false alarms) and the 95 % intervals should hold the truth 90-99 % of the
  time;
- wrong drop height: the record falls from 150 mm, the configuration says 95 mm;
- friction left out: 30 N of Coulomb friction in the record's fork, none in S1;
- record cut short: the logger stalls 60-120 ms after touch and repeats its last reading;
  each should be detected (target: at least 95 %).

    python benchmarks/model_check.py [--records 40] [--wrong 20] [--seed 1] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/model_check.json``,
outside the repository; ``--out benchmarks/results/model_check.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from _bench import add_out_option, write_json

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy as np  # noqa: E402

from mtbmj.config import load  # noqa: E402
from mtbmj.identify.dropfit import fit_drop  # noqa: E402
from test_fit_honest import FREE, s1_record  # noqa: E402

KEYS = {"tire.impact_rate_N_per_mm": "tire_N_per_mm", "fork.spring.rate_N_per_mm": "rate_N_per_mm"}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--records", type=int, default=40)
    ap.add_argument("--wrong", type=int, default=20, help="records per wrong-model case")
    ap.add_argument("--seed", type=int, default=1)
    add_out_option(ap, __file__)
    args = ap.parse_args()
    s1 = load("S1")
    rng = np.random.default_rng(args.seed)
    folder = Path(tempfile.mkdtemp(prefix="mtbmj-model-check-"))
    rows, started = [], time.perf_counter()

    def one(case: str, i: int, **kwargs):
        truth = {k: round(s1[k] * rng.uniform(0.85, 1.15), 3) for k in KEYS}
        noise = float(rng.uniform(0.01, 0.05))
        path = s1_record(folder / f"{case}{i}.csv", noise_mm=noise, seed=10_000 + len(rows),
                         clock_s=float(rng.uniform(0, 50)), fall_s=float(rng.uniform(0.03, 0.2)),
                         **{KEYS[k]: v for k, v in truth.items()}, **kwargs)
        result = fit_drop(str(path), "S1", free=FREE, engine="ode")
        x = result.extra
        covered = {k: (x["ci95"][k][0] <= truth[k] <= x["ci95"][k][1]) for k in KEYS}
        rows.append({"case": case, "record": i, "truth": truth, "noise_mm": noise, "fitted": result.values,
                     "passed": x["model_check"]["passed"], "ratio": x["model_check"]["ratio"],
                     "rms_mm": result.rms, "covered": covered, **{k: v for k, v in kwargs.items()}})
        print(f"{case} {i}: check {'passed' if rows[-1]['passed'] else 'FAILED'} ({rows[-1]['ratio']:.1f}x noise), "
              f"covered {sum(covered.values())}/2", flush=True)

    for i in range(args.records):
        one("right", i)
    for i in range(args.wrong):
        one("wrong_drop_height", i, drop_mm=150.0)
    for i in range(args.wrong):
        one("friction_left_out", i, friction_N=30.0)
    for i in range(args.wrong):
        one("cut_short", i, stalled_after_s=float(rng.uniform(0.06, 0.12)))
    right = [r for r in rows if r["case"] == "right"]
    summary = {
        "false_alarm_rate": float(np.mean([not r["passed"] for r in right])),
        "interval_coverage": float(np.mean([c for r in right for c in r["covered"].values()])),
        "detection_rate": {case: float(np.mean([not r["passed"] for r in rows if r["case"] == case]))
                           for case in ("wrong_drop_height", "friction_left_out", "cut_short")},
        "right_model_ratio_median": float(np.median([r["ratio"] for r in right])),
        "wall_time_s": time.perf_counter() - started,
    }
    print(summary)
    print(f"wrote {write_json(__file__, {'summary': summary, 'rows': rows}, args.out)}")


if __name__ == "__main__":
    main()

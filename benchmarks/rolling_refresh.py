"""What the rolling engine's accuracy costs (issue 25): the real-time factor of a rolling run with
the contact patches refreshed every 0.05 ms / 0.25 mm (today's default, chosen by accuracy against
the rolling reference) against the old 1 ms / 5 mm, in one process, interleaved, compiled
callback, one core. Reported: each setting's real-time factor (simulated time / wall time of the
engine) per round, their ratio (median and spread) and each setting's fork difference from the
rolling reference on the 50 mm root at 4 m/s (0.5 s).

    python benchmarks/rolling_refresh.py [--repeat 5] [--seconds 5] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/rolling_refresh.json``,
outside the repository; ``--out benchmarks/results/rolling_refresh.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import mtbmj.rolling.frontend as frontend
import mtbmj.rolling.tire as tire
from _bench import add_out_option, write_json

SETTINGS = {"now": (tire.REFRESH_S, tire.REFRESH_DISTANCE_M), "old": (1e-3, 5e-3)}


def use(name: str) -> None:
    refresh, distance = SETTINGS[name]
    for module in (frontend, tire):  # the Python callback reads the one, the compiled callback the other
        module.REFRESH_S, module.REFRESH_DISTANCE_M = refresh, distance


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=5.0)
    add_out_option(ap, __file__)
    args = ap.parse_args()
    frontend.run_roll("washboard", 5.0, duration=0.2)  # load the compiled callback first
    rounds = []
    for r in range(args.repeat):
        factors = {}
        for name in (("now", "old") if r % 2 == 0 else ("old", "now")):
            use(name)
            start = time.perf_counter()
            run = frontend.run_roll("washboard", 5.0, duration=args.seconds)
            factors[name] = args.seconds / (time.perf_counter() - start)
            assert run.info["callback"] == "compiled"
        rounds.append({"real_time_factor": factors, "now_over_old_wall": factors["old"] / factors["now"]})
        print(f"round {r}: now {factors['now']:.2f}x, old {factors['old']:.2f}x real time", flush=True)
    from mtbmj.rolling.reference import crosscheck

    accuracy = {}
    for name in SETTINGS:
        use(name)
        accuracy[name] = crosscheck("root", 4.0, duration=0.5)["fork"].max_abs
    ratios = [x["now_over_old_wall"] for x in rounds]
    summary = {"seconds": args.seconds, "repeat": args.repeat,
               "real_time_factor_median": {k: float(np.median([x["real_time_factor"][k] for x in rounds]))
                                           for k in SETTINGS},
               "wall_now_over_old": {"median": float(np.median(ratios)), "min": float(min(ratios)),
                                     "max": float(max(ratios))},
               "root_fork_difference_mm": accuracy}
    print(summary)
    print(f"wrote {write_json(__file__, {'summary': summary, 'rounds': rounds}, args.out)}")


if __name__ == "__main__":
    main()

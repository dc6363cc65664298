"""A notebook's loop over ``run_drop``: does it reach the compiled laws on its own? (issue 27)

Each round starts three fresh interpreters, interleaved, each running ``--calls`` default S12
drops in a loop and timing every call:

- ``loop``: the loop as a user writes it (the background load of ``controllers.native`` on);
- ``compiled``: the same loop after ``native.expect_many()`` (the compiled path from the start,
  the baseline of the target);
- ``python``: the loop with ``MTBMJ_BACKGROUND_LOAD=0`` (what a loop got before: the Python laws
  call after call).

Reported per round: the median call time from the third call on, for each; the ratios loop /
compiled (target at most 1.3) and python / compiled; and the time to the end of the whole loop.
Medians and the spread over ``--repeat`` rounds.

    python benchmarks/native_loop.py [--repeat 5] [--calls 12] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/native_loop.json``,
outside the repository; ``--out benchmarks/results/native_loop.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np

from _bench import add_out_option, write_json

LOOP = """
import json, sys, time
t0 = time.perf_counter()
import mtbmj
from mtbmj.controllers import native
if sys.argv[1] == "compiled":
    native.expect_many()
    mtbmj.run_drop("S12")  # the compiled laws' own first call, outside the loop as for a warm kernel
calls = []
for _ in range(int(sys.argv[2])):
    start = time.perf_counter()
    mtbmj.run_drop("S12")
    calls.append(time.perf_counter() - start)
print(json.dumps({"calls": calls, "total": time.perf_counter() - t0}))
"""


def one(kind: str, calls: int) -> dict:
    env = dict(os.environ)
    if kind == "python":
        env["MTBMJ_BACKGROUND_LOAD"] = "0"
    done = subprocess.run([sys.executable, "-c", LOOP, kind, str(calls)], capture_output=True, text=True,
                          env=env, check=True, timeout=600)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--calls", type=int, default=12)
    add_out_option(ap, __file__)
    args = ap.parse_args()
    rounds = []
    for r in range(args.repeat):
        got = {kind: one(kind, args.calls) for kind in (("loop", "compiled", "python") if r % 2 == 0
                                                        else ("python", "compiled", "loop"))}
        from_third = {k: float(np.median(v["calls"][2:])) for k, v in got.items()}
        rounds.append({"from_third_call_s": from_third, "first_two_calls_s": {k: v["calls"][:2] for k, v in got.items()},
                       "total_s": {k: v["total"] for k, v in got.items()},
                       "loop_over_compiled": from_third["loop"] / from_third["compiled"],
                       "python_over_compiled": from_third["python"] / from_third["compiled"]})
        print(f"round {r}: from the third call loop {from_third['loop'] * 1e3:.1f} ms, compiled "
              f"{from_third['compiled'] * 1e3:.1f} ms, python {from_third['python'] * 1e3:.1f} ms; "
              f"loop/compiled {rounds[-1]['loop_over_compiled']:.2f}", flush=True)

    def spread(key):
        values = [x[key] for x in rounds]
        return {"median": float(np.median(values)), "min": float(min(values)), "max": float(max(values))}

    summary = {"calls": args.calls, "repeat": args.repeat, "loop_over_compiled": spread("loop_over_compiled"),
               "python_over_compiled": spread("python_over_compiled"),
               "total_s": {k: float(np.median([x["total_s"][k] for x in rounds])) for k in ("loop", "compiled", "python")}}
    print(json.dumps(summary, indent=1))
    print(f"wrote {write_json(__file__, {'summary': summary, 'rounds': rounds}, args.out)}")


if __name__ == "__main__":
    main()

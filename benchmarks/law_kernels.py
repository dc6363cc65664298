"""One evaluation of the fork law in compiled code: the dispatch inlined into the loop that calls
it (``controllers.kernels.inlined``, what the fast engine and ``kernels.fork_forces`` use) against
the same dispatch called as separately compiled functions (``kernels.fork_force``, what the MuJoCo
callbacks call), on the same law, the same points, in this process, interleaved.

The laws: S12's whole fork (top-out progressive spring in end stops, table damper, sticking
Coulomb friction) and its main spring alone (the step rule's scans of the stroke). Each round
times one pass over ``--points`` points of each variant, alternating their order; the figure is
the called dispatch's time over the inlined one's, per round (median and spread), and the
nanoseconds per evaluation of each.

    python benchmarks/law_kernels.py [--points 200000] [--repeat 9] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/law_kernels.json``,
outside the repository; ``--out benchmarks/results/law_kernels.json`` refreshes the committed file). Not a test: nothing is asserted. Both loops must give
the same forces, bit for bit; the script stops if they do not.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from _bench import add_out_option, stats, write_json


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--repeat", type=int, default=9)
    add_out_option(ap, __file__)
    args = ap.parse_args()

    from mtbmj import compose
    from mtbmj import controllers as law
    from mtbmj.controllers import kernels, lawcodes
    from mtbmj.controllers.jit import numba
    from mtbmj.drop import chain

    if numba is None:
        raise SystemExit("needs numba")

    @numba.njit(nogil=True)
    def called(I, P, x, v, z, out):  # the dispatch as calls (kernels.fork_force is not inlined)
        for i in range(x.size):
            out[i] = kernels.fork_force(I, P, x[i], v[i], z[i])

    setup = compose.setup(chain.resolve("S12"))
    main_spring = setup.fork.spring.main
    laws = {"S12 fork": setup.fork,
            "S12 main spring": law.ForkLaw(main_spring, law.LinearDamper(0.0), law.NoFriction())}
    rng = np.random.default_rng(1)
    n = args.points
    x = rng.uniform(-0.006, 0.125, n)
    v = rng.uniform(-3.0, 3.0, n)
    z = rng.uniform(-1e-3, 1e-3, n)
    results = {}
    for name, fork in laws.items():
        I, P = lawcodes.law_arrays(fork)
        a, b = np.empty(n), np.empty(n)
        called(I, P, x, v, z, a)
        kernels.fork_forces(I, P, x, v, z, b)  # compiled (or loaded) before timing
        if not np.array_equal(a, b):
            raise SystemExit(f"{name}: the inlined and the called dispatch differ")
        times = {"called": [], "inlined": []}
        for k in range(args.repeat):
            order = ("called", "inlined") if k % 2 == 0 else ("inlined", "called")
            for which in order:
                start = time.perf_counter()
                if which == "called":
                    called(I, P, x, v, z, a)
                else:
                    kernels.fork_forces(I, P, x, v, z, b)
                times[which].append((time.perf_counter() - start) / n * 1e9)
        ratios = np.array(times["called"]) / np.array(times["inlined"])
        results[name] = {"called_ns": stats(times["called"]), "inlined_ns": stats(times["inlined"]),
                         "called_over_inlined": stats(ratios)}
        r = results[name]
        print(f"{name}: called {r['called_ns']['median']:.1f} ns, inlined {r['inlined_ns']['median']:.1f} ns per "
              f"evaluation; called / inlined {r['called_over_inlined']['median']:.2f}x "
              f"({r['called_over_inlined']['min']:.2f}-{r['called_over_inlined']['max']:.2f})", flush=True)
    payload = {"command": f"python benchmarks/law_kernels.py --points {n} --repeat {args.repeat}",
               "points": n, "repeat": args.repeat, "laws": results}
    print(f"wrote {write_json(__file__, payload, args.out)}")


if __name__ == "__main__":
    main()

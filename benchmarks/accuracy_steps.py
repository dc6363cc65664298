"""Accuracy against the ODE reference, and what it costs: the step rule's default, per integrator
and step, on the presets, on the random envelope, and the rest position's independence of the
run length.

(a) every preset at default settings (RK4, the step the rule chooses): max |MuJoCo - ODE| of sled,
    fork and tire over the default duration                           target <= 0.05 mm
(b) S12: error and wall time per integrator and step (RK4 and implicitfast at 0.05-1 ms, the
    rule bypassed by calling the engine directly), wall times interleaved, median of --repeat;
    the default's time over implicitfast at 1e-4 s                    target <= 0.5x (see docs/measured.md)
(c) the random envelope of ``mtbmj.drop.envelope`` (seed --seed): worst error, fork and tire
    beyond their limits                                              target <= 0.1 mm, 0 overtravel
(d) S12's rest position at 3 s and 6 s                               target equal within 0.01 mm

    python benchmarks/accuracy_steps.py [--repeat 5] [--envelope 24] [--seed 7] [--out PATH]
    python benchmarks/accuracy_steps.py --envelope-only --envelope 24 --seed 1,2,3,7,20261123 --jobs 2

(c) also gives each fork's conditioning: how far the ODE reference itself moves when the tire's
rates change by 1e-4 (the relative floor of MuJoCo's soft-contact impedance). A fork rattling
between its stops can move by more than 0.1 mm for that; no engine can be compared more finely.

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/accuracy_steps.json``, with
``--envelope-only`` ``accuracy_envelope.json`` there, outside the repository; ``--out
benchmarks/results/accuracy_steps.json`` or ``accuracy_envelope.json`` refreshes the committed file). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace

import numpy as np

import mtbmj
from _bench import add_out_option, write_json
from mtbmj import compose
from mtbmj.drop import engine_mujoco, engine_ode
from mtbmj.drop.envelope import draws
from mtbmj.drop.run import run_drop


def worst(a, b) -> float:
    return max(d["max_abs_mm"] for d in a.difference(b).values())


def presets() -> dict:
    out = {}
    for name in [f"S{i}" for i in range(1, 15)]:
        m, o = run_drop(name, "mujoco"), run_drop(name, "ode")
        out[name] = {"max_abs_mm": worst(m, o), "timestep_s": m.trace.info["timestep_s"]}
        print(f"(a) {name}: {out[name]['max_abs_mm']:.4f} mm at {out[name]['timestep_s']:g} s", flush=True)
    return out


def steps(repeat: int) -> dict:
    base = compose.setup(mtbmj.load_config("S12"))
    duration = base.duration
    ref = engine_ode.run(replace(base, timestep=1e-5), duration)  # dense: every grid below is on it
    cases = {"default": base}
    for integrator in ("rk4", "implicitfast"):
        for dt in (1e-3, 5e-4, 2e-4, 1e-4, 5e-5):  # one step throughout: no refinement
            cases[f"{integrator}_{dt:g}"] = replace(base, integrator=integrator, timestep=dt, substeps=1)
    times = {k: [] for k in cases}
    errors = {}
    for _ in range(repeat):  # interleaved: every case once per round
        for key, setup in cases.items():
            start = time.perf_counter()
            trace = engine_mujoco.run(setup, duration)
            times[key].append(time.perf_counter() - start)
            if key not in errors:
                grid = np.arange(trace.time.size) * setup.timestep
                errors[key] = float(max(np.max(np.abs(np.interp(grid, ref.time, getattr(ref, s)) - getattr(trace, s)))
                                        for s in ("sled", "fork")) * 1e3)
    out = {}
    for key in cases:
        out[key] = {"max_abs_mm": errors[key], "wall_s_median": statistics.median(times[key]),
                    "wall_s_spread": [min(times[key]), max(times[key])]}
        print(f"(b) {key}: {errors[key]:.4f} mm, {out[key]['wall_s_median'] * 1e3:.1f} ms", flush=True)
    ratio = [a / b for a, b in zip(times["default"], times["implicitfast_0.0001"])]
    out["default_over_implicitfast_1e-4"] = {"median": statistics.median(ratio), "spread": [min(ratio), max(ratio)]}
    return out


def envelope(n: int, seed: int) -> dict:
    table = list(mtbmj.load_config("reference").require("fork.damper.force_N"))
    rows = []
    for preset, overrides in draws(n, seed, table):
        cfg = mtbmj.load_config(preset, overrides)
        m, o = run_drop(cfg, "mujoco"), run_drop(cfg, "ode")
        # the configuration's own conditioning: how far the reference moves when the tire's rates
        # change by 1e-4, the relative size of MuJoCo's soft-contact impedance floor (mjMINIMP)
        rates = {k: cfg[k] * (1.0 - 1e-4) for k in cfg.values if k.startswith("tire.") and k.endswith("_N_per_mm")}
        sensitivity = worst(o, run_drop(cfg.with_overrides(rates), "ode"))
        fast = worst(run_drop(cfg, "fast"), o)
        travel, deepest = cfg.require("fork.travel_mm"), cfg.require("tire.max_deflection_mm")
        rows.append({"preset": preset, "max_abs_mm": worst(m, o), "sensitivity_mm": sensitivity, "fast_mm": fast,
                     "timestep_s": m.trace.info["timestep_s"],
                     "fork_past_travel_mm": float(max(np.max(r.raw["fork_mm"]) - travel for r in (m, o))),
                     "tire_past_max_mm": float(max(np.max(r.raw["tire_mm"]) - deepest for r in (m, o))),
                     "hard_stop": m.summary["hard_stop"]["count"], "rim_strikes": m.summary["rim_strikes"]["count"]})
        print(f"(c) {preset}: {rows[-1]['max_abs_mm']:.4f} mm (fast {fast:.4f} mm; reference moves "
              f"{sensitivity:.4f} mm with the tire rates 1e-4 off)", flush=True)
    return {"seed": seed, "cases": rows, "worst_mm": max(r["max_abs_mm"] for r in rows),
            "beyond_0.1_mm": sum(r["max_abs_mm"] > 0.1 for r in rows),
            "beyond_0.1_mm_and_twice_sensitivity": sum(r["max_abs_mm"] > max(0.1, 2 * r["sensitivity_mm"]) for r in rows),
            "fast_worst_mm": max(r["fast_mm"] for r in rows),
            "worst_fork_past_travel_mm": max(r["fork_past_travel_mm"] for r in rows),
            "worst_tire_past_max_mm": max(r["tire_past_max_mm"] for r in rows)}


def rest() -> dict:
    out = {}
    for duration in (3.0, 6.0):
        out[f"{duration:g}s"] = {e: float(run_drop("S12", e, duration=duration).raw["fork_mm"][-1]) for e in ("mujoco", "ode")}
    out["difference_mm"] = abs(out["3s"]["mujoco"] - out["6s"]["mujoco"])
    print(f"(d) {out}", flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--envelope", type=int, default=24)
    ap.add_argument("--seed", default="7", help="envelope seed(s), comma-separated")
    ap.add_argument("--envelope-only", action="store_true",
                    help="only (c), written as accuracy_envelope.json (see --out)")
    ap.add_argument("--jobs", type=int, default=1, help="seeds run in this many processes at once")
    add_out_option(ap, __file__, note=", accuracy_envelope.json there with --envelope-only")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seed.split(",")]
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            envelopes = list(pool.map(envelope, [args.envelope] * len(seeds), seeds))
    else:
        envelopes = [envelope(args.envelope, seed) for seed in seeds]
    cases = [r for e in envelopes for r in e["cases"]]
    totals = {"seeds": seeds, "forks": len(cases), "worst_mm": max(r["max_abs_mm"] for r in cases),
              "beyond_0.1_mm": sum(e["beyond_0.1_mm"] for e in envelopes),
              "beyond_0.1_mm_and_twice_sensitivity": sum(e["beyond_0.1_mm_and_twice_sensitivity"] for e in envelopes),
              "within_0.05_mm": sum(r["max_abs_mm"] <= 0.05 for r in cases),
              "fast_worst_mm": max(r["fast_mm"] for r in cases)}
    print(f"(c) all seeds: {totals}", flush=True)
    if args.envelope_only:
        path = write_json(__file__.replace("accuracy_steps", "accuracy_envelope"), {"envelope": envelopes, "totals": totals},
                          args.out)
        print(f"wrote {path}")
        return
    payload = {"presets": presets(), "steps": steps(args.repeat), "envelope": envelopes[0] if len(seeds) == 1 else envelopes,
               "envelope_totals": totals, "rest": rest()}
    print(f"wrote {write_json(__file__, payload, args.out)}")


if __name__ == "__main__":
    main()

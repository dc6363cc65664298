"""The rolling front end (``mtbmj roll``) against the whole bike (``mtbmj bike``) over the same terrain,
on one core, as real-time factors (simulated seconds per wall second), interleaved: each repetition
runs both (in alternating order), so they see the same machine load. Both use their default (compiled)
callbacks and settings: both with their coarse steps and their refinement (the front end's also
for the tire's damping ramp, which its 0.02 mm agreement with the rolling reference needs). Also timed in each repetition:
each model stepped by MuJoCo alone with no control callback (the floor a callback sits on).

    python benchmarks/rolling_vs_bike.py [--terrain rock_garden] [--speed 5] [--duration 1.0] [--repeats 5]
                                         [--out PATH]

``--terrain``: any scenario both commands take (default ``rock_garden``, the terrain library's: seven
rocks 50-110 mm over 2.75 m; ``root``, ``rock``, a CSV path...).

Prints each repetition, then the median and spread (min-max) of each real-time factor, of the same per
CPU second of this process (``time.process_time``: on a shared machine the wall time also counts time
the core spent elsewhere) and of the ratio front end / bike (per repetition), the number of patch
searches of each, and the load average before and after. Only the stepping is timed (``simulate``;
MuJoCo alone: ``rollout``), not building the models. Writes its results where ``--out`` says (default
``<tempdir>/mtbmj-benchmarks/rolling_vs_bike.json``, outside the repository). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, load_average, pin_one_core, write_json  # noqa: E402


def _timed(fn, duration: float) -> tuple[float, float]:
    cpu, start = time.process_time(), time.perf_counter()
    fn()
    return duration / (time.perf_counter() - start), duration / (time.process_time() - cpu)


def roll(profile: str, speed: float, duration: float) -> dict:
    from mtbmj.rolling import frontend

    p = frontend.prepare(profile, speed)
    rtf, cpu = _timed(lambda: frontend.simulate(p, duration), duration)
    return {"rtf": rtf, "cpu": cpu, "callback": frontend.callback_kind(p.callback), "searches": p.callback.refreshes,
            "calls": p.callback.calls, "timestep_s": p.setup.timestep}


def bike(profile: str, speed: float, duration: float) -> dict:
    from mtbmj.bike import run

    p = run.prepare("sst", profile, speed)
    rtf, cpu = _timed(lambda: run.simulate(p, duration), duration)
    return {"rtf": rtf, "cpu": cpu, "callback": run.callback_kind(p.callback), "searches": p.callback.refreshes,
            "calls": p.callback.calls, "timestep_s": p.timestep}


def alone(model, data, timestep: float, duration: float) -> tuple[float, float]:
    """``model`` stepped by MuJoCo with no control callback from ``data``'s state: real-time factors
    (wall, CPU)."""
    import mujoco
    import numpy as np
    from mujoco import rollout

    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    steps = int(round(duration / timestep))

    def go():
        for done in range(0, steps, 10000):
            rollout.rollout(model, data, state[None, :], nstep=min(10000, steps - done))

    return _timed(go, duration)


def floors(profile: str, speed: float, duration: float) -> tuple[tuple, tuple]:
    from mtbmj.bike import run
    from mtbmj.rolling import frontend

    r = frontend.prepare(profile, speed)
    b = run.prepare("sst", profile, speed)
    return (alone(r.front.model, r.data, r.setup.timestep, duration),
            alone(b.bike.model, b.data, b.timestep, duration))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--terrain", default="rock_garden")
    ap.add_argument("--speed", type=float, default=5.0)
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-floor", action="store_true", help="skip MuJoCo alone (no callback)")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    pin_one_core()
    before = load_average()
    print(f"load average before: {before}", flush=True)
    profile = args.terrain
    roll(profile, args.speed, 0.05)  # warm-up: imports, numba compilation or cache load of both callbacks
    bike(profile, args.speed, 0.05)
    rows: dict = {key: [] for key in ("roll", "bike", "roll_cpu", "bike_cpu", "ratio", "ratio_cpu",
                                      "roll_alone", "bike_alone", "roll_alone_cpu", "bike_alone_cpu")}
    info: dict = {}
    for i in range(args.repeats):
        order = (("roll", roll), ("bike", bike)) if i % 2 == 0 else (("bike", bike), ("roll", roll))
        got = {name: fn(profile, args.speed, args.duration) for name, fn in order}
        r, b = got["roll"], got["bike"]
        rows["roll"].append(r["rtf"])
        rows["bike"].append(b["rtf"])
        rows["roll_cpu"].append(r["cpu"])
        rows["bike_cpu"].append(b["cpu"])
        rows["ratio"].append(r["rtf"] / b["rtf"])
        rows["ratio_cpu"].append(r["cpu"] / b["cpu"])
        info = {name: {k: v for k, v in g.items() if k not in ("rtf", "cpu")} for name, g in got.items()}
        text = ""
        if not args.no_floor:
            (ra, ra_cpu), (ba, ba_cpu) = floors(profile, args.speed, args.duration)
            rows["roll_alone"].append(ra)
            rows["bike_alone"].append(ba)
            rows["roll_alone_cpu"].append(ra_cpu)
            rows["bike_alone_cpu"].append(ba_cpu)
            text = f"; MuJoCo alone: front end {ra:.2f}x ({ra_cpu:.2f}x), bike {ba:.2f}x ({ba_cpu:.2f}x)"
        print(f"repeat {i + 1}: front end ({r['callback']}) {r['rtf']:.2f}x real time ({r['cpu']:.2f}x per CPU "
              f"second), bike ({b['callback']}) {b['rtf']:.2f}x ({b['cpu']:.2f}x); front end / bike "
              f"{r['rtf'] / b['rtf']:.3f}{text}", flush=True)

    def line(name, values, unit=""):
        return (f"{name}: median {statistics.median(values):.4g}{unit}, spread {min(values):.4g}-{max(values):.4g}"
                f"{unit} over {len(values)} repeats")

    label = f"{args.terrain} at {args.speed:g} m/s, {args.duration:g} s"
    print(line(f"front end ({label})", rows["roll"], "x real time"))
    print(line("bike (sst, same)", rows["bike"], "x real time"))
    print(line("front end / bike", rows["ratio"]))
    print(line("front end per CPU second", rows["roll_cpu"], "x"))
    print(line("bike per CPU second", rows["bike_cpu"], "x"))
    print(line("front end / bike per CPU second", rows["ratio_cpu"]))
    if not args.no_floor:
        print(line("front end model, MuJoCo alone", rows["roll_alone"], "x real time"))
        print(line("bike model, MuJoCo alone", rows["bike_alone"], "x real time"))
        print(line("front end model, MuJoCo alone per CPU second", rows["roll_alone_cpu"], "x"))
        print(line("bike model, MuJoCo alone per CPU second", rows["bike_alone_cpu"], "x"))
    for name in ("roll", "bike"):
        i = info[name]
        print(f"{'front end' if name == 'roll' else 'bike'}: step {1e3 * i['timestep_s']:g} ms, {i['calls']} callback "
              f"calls, {i['searches']} patch searches in the last run")
    after = load_average()
    print(f"load average after: {after}")
    summary = {key: {"median": statistics.median(v), "min": min(v), "max": max(v), "runs": v}
               for key, v in rows.items() if v}
    payload = {"command": " ".join(["python", "benchmarks/rolling_vs_bike.py", *sys.argv[1:]]),
               "terrain": args.terrain, "speed_m_per_s": args.speed, "duration_s": args.duration,
               "load_before": before, "load_after": after, "last_run": info, "real_time_factors": summary}
    print(f"wrote {write_json(__file__, payload, args.out)}")


if __name__ == "__main__":
    main()

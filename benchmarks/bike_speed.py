"""Speed of the whole bike (``mtbmj bike``) on a rock garden, on one core, as real-time factors
(simulated seconds per wall second): the bike with its compiled callback and with its Python one,
MuJoCo alone stepping the same bike model with no callback (the floor the callback sits on), and the
rolling front end (``mtbmj roll``, compiled callback) on the same profile; interleaved (each
repetition runs all four) so they see the same machine load.

    python benchmarks/bike_speed.py [--repeats 5] [--duration 1.0] [--python-duration D] [--speed 5] [--coarse-step-ms S]
        [--out PATH]

Prints each repetition, then the median and spread (min-max) of each real-time factor and of the
ratios compiled bike / front end and compiled / Python bike, the compiled bike's and MuJoCo's
simulated seconds per second of this process's CPU time (``time.process_time``: on a machine shared
with other work, the wall time also counts the time the core spent elsewhere), and the load average
(/proc/loadavg) before and after, and writes them where ``--out`` says (default
``<tempdir>/mtbmj-benchmarks/bike_speed.json``, outside the repository; ``--out
benchmarks/results/bike_speed.json`` refreshes the committed file). Only the stepping is timed (``simulate``; MuJoCo alone:
``rollout``): building the model and the static equilibrium are not. The rock garden is the terrain
library's ``rock_garden`` (seven rocks 50-110 mm high over 2.75 m, ``mtbmj.rolling.terrain``). The
Python callback runs ``--python-duration`` s (default the same ``--duration``: a shorter run would
time mostly the flat lead-in, where the patch search is skipped).
"""
from __future__ import annotations

import argparse
import statistics
import time


def bike_rtf(profile: str, speed: float, duration: float, callback: str = "compiled") -> float:
    from mtbmj.bike.run import callback_kind, prepare, simulate

    p = prepare("sst", profile, speed, callback=callback)
    assert callback_kind(p.callback) == callback
    cpu, start = time.process_time(), time.perf_counter()
    simulate(p, duration)
    return duration / (time.perf_counter() - start), duration / (time.process_time() - cpu)


def mujoco_rtf(profile: str, speed: float, duration: float) -> float:
    """The bike's model stepped by MuJoCo with no control callback (the same integrator and step):
    what any callback's cost adds to."""
    import mujoco
    import numpy as np
    from mujoco import rollout

    from mtbmj.bike.run import prepare

    p = prepare("sst", profile, speed, callback="compiled")
    model, data = p.bike.model, p.data
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    steps = int(round(duration / p.timestep))
    cpu, start = time.process_time(), time.perf_counter()
    for done in range(0, steps, 10000):
        rollout.rollout(model, data, state[None, :], nstep=min(10000, steps - done))
    return duration / (time.perf_counter() - start), duration / (time.process_time() - cpu)


def roll_rtf(profile: str, speed: float, duration: float) -> tuple[float, str]:
    from mtbmj.rolling import frontend

    p = frontend.prepare(profile, speed)
    start = time.perf_counter()
    frontend.simulate(p, duration)
    return duration / (time.perf_counter() - start), frontend.callback_kind(p.callback)


def main() -> None:
    from _bench import add_out_option, load_average, pin_one_core, write_json

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run")
    ap.add_argument("--python-duration", type=float, default=None,
                    help="simulated seconds of the Python callback (default --duration)")
    ap.add_argument("--speed", type=float, default=5.0)
    ap.add_argument("--coarse-step-ms", type=float, default=None,
                    help="the bike's largest step (mtbmj.bike.stepping.COARSE_STEP_S, default 0.5 ms); the laws' "
                         "step limits with the bike's masses still bound it")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    if args.coarse_step_ms is not None:
        from mtbmj.bike import stepping

        stepping.COARSE_STEP_S = args.coarse_step_ms * 1e-3
    if args.python_duration is None:
        args.python_duration = args.duration
    pin_one_core()
    before = load_average()
    print(f"load average before: {before}", flush=True)
    profile = "rock_garden"
    roll_rtf(profile, args.speed, 0.05)  # warm-up: imports, numba compilation of both compiled callbacks
    bike_rtf(profile, args.speed, 0.05)
    rows = {"bike": [], "python": [], "mujoco": [], "roll": [], "ratio": [], "speedup": [], "bike_cpu": [],
            "mujoco_cpu": [], "over_mujoco": []}
    for i in range(args.repeats):
        b, b_cpu = bike_rtf(profile, args.speed, args.duration)
        py, _ = bike_rtf(profile, args.speed, args.python_duration, "python")
        mj, mj_cpu = mujoco_rtf(profile, args.speed, args.duration)
        r, kind = roll_rtf(profile, args.speed, args.duration)
        for key, value in (("bike", b), ("python", py), ("mujoco", mj), ("roll", r), ("ratio", b / r),
                           ("speedup", b / py), ("bike_cpu", b_cpu), ("mujoco_cpu", mj_cpu),
                           ("over_mujoco", b / mj)):
            rows[key].append(value)
        print(f"repeat {i + 1}: bike compiled {b:.3f}x real time ({b_cpu:.3f}x per CPU second), Python {py:.4f}x, "
              f"MuJoCo alone {mj:.3f}x ({mj_cpu:.3f}x), "
              f"front end ({kind} callback) {r:.2f}x; bike / front end {b / r:.3f}, compiled / Python {b / py:.1f}",
              flush=True)

    def line(name, values, unit):
        return (f"{name}: median {statistics.median(values):.4g}{unit}, spread {min(values):.4g}-{max(values):.4g}"
                f"{unit} over {len(values)} repeats")

    print(line("bike, compiled callback (sst, rock garden)", rows["bike"], "x real time"))
    print(line("the same per CPU second of this process", rows["bike_cpu"], "x"))
    print(line("MuJoCo alone per CPU second", rows["mujoco_cpu"], "x"))
    print(line("bike, Python callback", rows["python"], "x real time"))
    print(line("bike model, MuJoCo alone (no callback)", rows["mujoco"], "x real time"))
    print(line("front end (S12, same profile)", rows["roll"], "x real time"))
    print(line("bike compiled / front end", rows["ratio"], ""))
    print(line("bike compiled / MuJoCo alone (pairs)", rows["over_mujoco"], ""))
    print(line("bike compiled / Python", rows["speedup"], ""))
    from mtbmj.bike import run

    step = run.prepare("sst", "flat", args.speed).timestep
    after = load_average()
    print(f"bike step: {1e3 * step:g} ms, RK4; load average after: {after}")
    summary = {key: {"median": statistics.median(v), "min": min(v), "max": max(v), "runs": v} for key, v in rows.items()}
    command = f"python benchmarks/bike_speed.py --repeats {args.repeats}"
    if args.python_duration != args.duration:
        command += f" --python-duration {args.python_duration:g}"
    if args.coarse_step_ms is not None:
        command += f" --coarse-step-ms {args.coarse_step_ms:g}"
    path = write_json(__file__, {"command": command, "duration_s": args.duration, "speed_m_per_s": args.speed,
                                 "timestep_s": step, "load_before": before, "load_after": after,
                                 "real_time_factors": summary}, args.out)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

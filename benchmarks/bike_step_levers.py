"""What each lever on MuJoCo's step saves on the bike's run of ``mtbmj advise``, interleaved, and that
each keeps the run's states and sensors to the bit.

    python benchmarks/bike_step_levers.py [--ride example] [--bike sst] [--repeats 9] [--steps 20480] [--out PATH]

The run is the advice's recorded-setting run over the ride's reconstruction, along the ride's speed
(``mtbmj.ride.advise.simulate``'s ``run_bike``), prepared once. Each variant steps the same
stretch (``--steps`` steps of the coarse step from the run's start, in rollouts of
``mtbmj.runpath.loop.REFINE_CHUNK`` steps under the compiled callback, as the run's coarse chunks)
and its CPU time per step is taken (this process, one core). The variants, in turn within every
repetition (each repetition starting at the next variant, so that no variant is always the first after a
change of model): ``none`` (every lever undone: MuJoCo's clock on, the passive stage on, the camera and
light in the model), each lever alone, and ``all`` (the model as ``build_bike`` makes it, stepped
as ``mtbmj.runpath.loop.stepped`` steps it). The levers:

- ``timer``: MuJoCo's timers off (``loop.untimed``: the ``mujoco`` package's ``mjcb_time`` clock);
- ``passive``: the passive stage skipped (``loop.passive_skipped``: the bike has no springs or dampers
  of MuJoCo's);
- ``camera_light``: the scene's camera and light left out (``mtbmj.bike.model.NOT_STEPPED``).

Prints and writes (``--out``) each variant's median and spread (min-max) of CPU us per step, the
median and spread of its per-repetition ratio to ``none``, and whether its states and sensors over
the stretch equal ``none``'s to the bit. Not a test: nothing is asserted (the bit identity is
``tests/test_runpath_levers.py``'s).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, add_ride_options, read_ride, ride_options_shown, stats, write_json  # noqa: E402

VARIANTS = ("none", "timer", "passive", "camera_light", "all")


def prepared(bike, terrain, speed, profile, camera_light: bool):
    """The advice's run prepared; ``camera_light``: the scene's camera and light left out (as built)."""
    from mtbmj.bike import model as model_mod
    from mtbmj.bike import run as bike_run

    kept = model_mod.NOT_STEPPED
    if not camera_light:
        model_mod.NOT_STEPPED = tuple(k for k in kept if k not in ("cameras", "lights"))
    try:
        return bike_run.prepare(bike, terrain, speed, drive="rider", speed_profile=profile)
    finally:
        model_mod.NOT_STEPPED = kept


def stretch(p, steps: int, timer_off: bool, passive_off: bool):
    """(CPU us per step, states, sensors) of ``steps`` steps from ``p``'s start."""
    import contextlib

    import mujoco
    import numpy as np
    from mujoco import rollout

    from mtbmj.controllers import installed
    from mtbmj.runpath import loop

    m, d = p.bike.model, p.data
    flags = m.opt.disableflags
    passive = int(mujoco.mjtDisableBit.mjDSBL_SPRING) | int(mujoco.mjtDisableBit.mjDSBL_DAMPER)
    m.opt.disableflags = (flags | passive) if passive_off else (flags & ~passive)
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(m, kind))
    d.time = 0.0
    d.qpos[:], d.qvel[:], d.act[:] = p.initial_qpos, p.initial_qvel, p.initial_act
    mujoco.mj_getState(m, d, state, kind)
    p.callback.reset()
    states, sensors = [], []
    try:
        with installed(p.callback), (loop.untimed() if timer_off else contextlib.nullcontext()):
            c0 = time.process_time()
            for _ in range(steps // loop.REFINE_CHUNK):
                st, se = rollout.rollout(m, d, state[None, :], nstep=loop.REFINE_CHUNK)
                state = st[0, -1].copy()
                states.append(st[0])
                sensors.append(se[0])
            cpu = time.process_time() - c0
    finally:
        m.opt.disableflags = flags
    n = len(states) * loop.REFINE_CHUNK
    return 1e6 * cpu / n, np.concatenate(states), np.concatenate(sensors)


def main(argv=None) -> int:
    import numpy as np

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_ride_options(ap, repeats=9)
    ap.add_argument("--steps", type=int, default=20480, help="steps of each stretch (a multiple of 1024)")
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from mtbmj.ride import advise, reconstruct
    from mtbmj.runpath import loop

    record = read_ride(args)
    rec = reconstruct.reconstruct(record, args.bike)
    terrain, profile = advise.terrain_of(rec), rec.speed_along()
    speed = float(profile[1][0])
    built = prepared(args.bike, terrain, speed, profile, camera_light=True)
    viewed = prepared(args.bike, terrain, speed, profile, camera_light=False)
    passive_skipped = not loop.has_passive(built.bike.model)
    setups = {"none": (viewed, False, False), "timer": (viewed, True, False), "passive": (viewed, False, True),
              "camera_light": (built, False, False), "all": (built, True, passive_skipped)}
    us = {k: [] for k in VARIANTS}
    same = {k: True for k in VARIANTS}
    for i in range(args.repeats):
        runs = {}
        for k in VARIANTS[i % len(VARIANTS):] + VARIANTS[:i % len(VARIANTS)]:  # each variant first in turn
            cost, states, sensors = stretch(setups[k][0], args.steps, *setups[k][1:])
            us[k].append(cost)
            runs[k] = (states, sensors)
        for k in VARIANTS[1:]:
            same[k] = same[k] and all(np.array_equal(a, b) for a, b in zip(runs[k], runs["none"]))
        print(f"repeat {i + 1}: " + ", ".join(f"{k} {us[k][-1]:.2f}" for k in VARIANTS) + " us/step", flush=True)
    out = {"command": f"python benchmarks/bike_step_levers.py --repeats {args.repeats} --steps {args.steps}"
                      + ride_options_shown(args) + " --out benchmarks/results/bike_step_levers.json",
           "ride": record.name, "steps": args.steps, "timestep_s": built.timestep, "passive_skipped": passive_skipped,
           "us_per_step": {k: stats(us[k]) for k in VARIANTS},
           "over_none": {k: stats(np.array(us[k]) / np.array(us["none"])) for k in VARIANTS if k != "none"},
           "identical_to_none": {k: same[k] for k in VARIANTS if k != "none"}}
    for k in VARIANTS:
        s = out["us_per_step"][k]
        ratio = "" if k == "none" else (f"; / none {out['over_none'][k]['median']:.3f} ({out['over_none'][k]['min']:.3f}-"
                                        f"{out['over_none'][k]['max']:.3f}); states and sensors "
                                        f"{'identical' if same[k] else 'DIFFERENT'}")
        print(f"{k:13s} {s['median']:.2f} us/step ({s['min']:.2f}-{s['max']:.2f}){ratio}")
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

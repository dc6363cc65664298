"""Cost of the compiled force-law layer (issue 6, part 1).

1. Force-law layer: one S12 drop (1.5 s, default step) stepped with the compiled fork laws vs the
   same scene with MuJoCo built-in elements only (joint stiffness, springref and damping on the
   fork; no callback), same number of steps, one thread. Also the whole engine run
   (``engine_mujoco.run`` with chunking, tire switch and checks) with compiled and Python laws.
2. Throughput: ``mujoco.rollout`` of N S12 drops with the full compiled laws vs the built-in-only
   (bare) scene, on 1 and 2 threads: drops per second and 1 -> 2 thread scaling (the Python
   callback is shown for context). Rollouts step a fixed tire law (no switch).

Run: python benchmarks/compiled.py [--drops N] [--repeat 5] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/compiled.json``,
outside the repository; ``--out benchmarks/results/compiled.json`` refreshes the committed file).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, environment, write_json  # noqa: E402

import mtbmj  # noqa: E402
from mtbmj import compose  # noqa: E402
from mtbmj.drop import engine_mujoco, scene  # noqa: E402
from mtbmj.controllers import ForkCallback, installed  # noqa: E402

start_import = time.perf_counter()
from mtbmj.controllers import compiled  # noqa: E402

IMPORT_S = time.perf_counter() - start_import


def builtin_model(sc, setup):
    """The drop scene with the fork as MuJoCo joint stiffness (+ preload via springref) and
    damping only: the same model, the same steps, no callback."""
    model = sc.model  # a fresh build per call; modified in place
    spring = setup.fork.spring
    main = getattr(spring, "main", spring)
    rate = float(getattr(main, "rate", 1.5e4))
    preload = float(getattr(spring, "preload", 0.0))
    model.jnt_stiffness[model.joint("fork").id] = rate
    model.qpos_spring[sc.fork_qpos] = -preload / rate
    model.dof_damping[sc.fork_dof] = 201.3
    return model


def initial_states(sc, setup, n):
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    out = []
    for k in range(n):
        d = mujoco.MjData(sc.model)
        d.qvel[sc.sled_dof] = setup.impact_speed * (0.8 + 0.4 * k / max(n - 1, 1))
        d.qpos[sc.sled_qpos] = 1e-12
        mujoco.mj_forward(sc.model, d)
        s = np.empty(mujoco.mj_stateSize(sc.model, spec))
        mujoco.mj_getState(sc.model, d, s, spec)
        out.append(s)
    return np.array(out)


def rollout_runner(model, states, nstep, nthread, callback):
    """A function stepping ``states`` for ``nstep`` steps on ``nthread`` threads with ``callback``."""
    datas = [mujoco.MjData(model) for _ in range(nthread)]
    out = np.empty((len(states), nstep, states.shape[1]))

    def go():
        with installed(callback):
            rollout.rollout(model, datas if nthread > 1 else datas[0], states, nstep=nstep, state=out)

    go()  # warm-up
    return go


def interleaved_best(runners: dict, repeat: int) -> dict:
    """Best wall time of each runner, the runners taking turns (the machine may be shared: turns
    spread any load over all of them, the best of several is the least disturbed)."""
    best = {name: float("inf") for name in runners}
    for _ in range(repeat):
        for name, go in runners.items():
            start = time.perf_counter()
            go()
            best[name] = min(best[name], time.perf_counter() - start)
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--drops", type=int, default=16, help="drops per rollout batch")
    parser.add_argument("--repeat", type=int, default=5)
    add_out_option(parser, __file__)
    args = parser.parse_args(argv)

    setup = compose.setup(mtbmj.load_config("S12"))
    nstep = int(round(setup.duration / setup.timestep))
    sc = scene.build(setup)
    bare_sc = scene.build(setup)
    bare = builtin_model(bare_sc, setup)
    comp = compiled.CompiledForkCallback(sc.model, setup.fork, count_calls=False)
    python = ForkCallback(sc.model, setup.fork)
    one = initial_states(sc, setup, 1)

    # 1. force-law layer, one drop, one thread
    t = interleaved_best({
        "compiled": rollout_runner(sc.model, one, nstep, 1, comp),
        "builtin": rollout_runner(bare, one, nstep, 1, None),
        "python": rollout_runner(sc.model, one, nstep, 1, python),
        "engine_compiled": lambda: engine_mujoco.run(setup, callback="compiled"),
        "engine_python": lambda: engine_mujoco.run(setup, callback="python"),
    }, args.repeat + 2)
    t_comp, t_bare, t_py, t_engine_c, t_engine_p = (t[k] for k in ("compiled", "builtin", "python", "engine_compiled",
                                                                     "engine_python"))
    layer = {
        "steps": nstep,
        "builtin_only_s": t_bare, "compiled_laws_s": t_comp, "python_laws_s": t_py,
        "ratio_compiled_to_builtin": t_comp / t_bare, "target_ratio": 1.15,
        "ratio_python_to_builtin": t_py / t_bare,
        "engine_run_compiled_s": t_engine_c, "engine_run_python_s": t_engine_p,
        "steps_per_s_compiled": nstep / t_comp, "steps_per_s_builtin": nstep / t_bare,
    }

    # 2. throughput
    states = initial_states(sc, setup, args.drops)
    few = states[: max(2, args.drops // 8)]
    counted_sc = scene.build(setup)
    counted = compiled.CompiledForkCallback(counted_sc.model, setup.fork, count_calls=True)
    rows = {}
    for threads in (1, 2):
        t = interleaved_best({
            "bare": rollout_runner(bare, states, nstep, threads, None),
            "compiled": rollout_runner(sc.model, states, nstep, threads, comp),
            "counting": rollout_runner(counted_sc.model, states, nstep, threads, counted),
        }, args.repeat)
        tp = interleaved_best({"python": rollout_runner(sc.model, few, nstep, threads, python)}, 1)["python"]
        rows[threads] = {
            "bare_drops_per_s": len(states) / t["bare"],
            "compiled_drops_per_s": len(states) / t["compiled"],
            "compiled_counting_calls_drops_per_s": len(states) / t["counting"],
            "python_drops_per_s": len(few) / tp,
            "ratio_compiled_to_bare": t["bare"] / t["compiled"],
        }
    throughput = {
        "drops": args.drops, "steps_per_drop": nstep,
        "threads": {str(k): v for k, v in rows.items()},
        "scaling_1_to_2_threads": {
            "bare": rows[2]["bare_drops_per_s"] / rows[1]["bare_drops_per_s"],
            "compiled": rows[2]["compiled_drops_per_s"] / rows[1]["compiled_drops_per_s"],
            "python": rows[2]["python_drops_per_s"] / rows[1]["python_drops_per_s"],
        },
        "target_ratio": 0.9,
    }
    import numba

    payload = {
        "numba": numba.__version__,
        "compiled_import_s": IMPORT_S,
        "kernel_compile_or_cache_load_s": compiled.COMPILE_SECONDS,
        "load_average_1min_at_end": environment()["load_average_1min"],
        "force_law_layer": layer,
        "throughput": throughput,
    }
    path = write_json(__file__, payload, args.out)
    print(f"force-law layer: compiled {t_comp:.3f} s vs built-in {t_bare:.3f} s = {t_comp / t_bare:.2f}x "
          f"(python {t_py / t_bare:.2f}x); engine run compiled {t_engine_c:.3f} s, python {t_engine_p:.3f} s")
    for k, r in rows.items():
        print(f"{k} thread(s): bare {r['bare_drops_per_s']:.2f} drops/s, compiled {r['compiled_drops_per_s']:.2f} "
              f"(ratio {r['ratio_compiled_to_bare']:.2f}; counting {r['compiled_counting_calls_drops_per_s']:.2f}), "
              f"python {r['python_drops_per_s']:.2f}")
    s = throughput["scaling_1_to_2_threads"]
    print(f"scaling 1->2 threads: bare {s['bare']:.2f}x, compiled {s['compiled']:.2f}x, python {s['python']:.2f}x")
    print(f"kernels compile/cache-load {compiled.COMPILE_SECONDS:.2f} s; wrote {path}")


if __name__ == "__main__":
    main()

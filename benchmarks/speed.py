"""Speed of the MuJoCo engine against the ODE reference, the cost of the Python force-law layer,
and the end-to-end study.

(a) per preset, engine wall time (``DropResult.wall_time_s``) of a 1.5 s drop, best of N:
    MuJoCo at default settings vs the ODE reference at its default rtol 1e-8; target ODE/MuJoCo >= 5x.
(b) S1, same model, same 15000 steps, same stepping call: fork law through our Python control
    callback vs MuJoCo's built-in joint spring (jnt_stiffness) and damper (dof_damping), no callback.
    Both via one ``mujoco.rollout.rollout`` chunk and both via ``mujoco.mj_step(m, d, nstep=N)``;
    the trajectories are compared (mm) to show it is the same physics.
(c) ``mtbmj study --out <tmpdir>`` end to end as a subprocess (target < 20 s on 2 cores), and the
    28 runs alone (``mtbmj.drop.study.run_study()`` in-process: process pool, no figures, no files).

    python benchmarks/speed.py [--repeat N] [--study-repeat N] [--skip-study] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/speed.json``,
outside the repository; ``--out benchmarks/results/speed.json`` refreshes the committed file). Not a test: nothing is asserted. Timings depend on the
machine load, which is recorded (load average) in the JSON.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

import mtbmj
from mtbmj import compose
from mtbmj.drop import scene
from mtbmj.controllers import ForkCallback, installed
from _bench import add_out_option, best_of, write_json

MTBMJ = str(Path(sys.executable).with_name("mtbmj"))


def part_a(repeat: int) -> dict:
    rows = {}
    print(f"(a) engine wall time of a 1.5 s drop, best of {repeat} [s]")
    print(f"{'preset':<6} {'MuJoCo':>8} {'ODE':>8} {'ODE/MuJoCo':>10} {'>=5x':>5}")
    for name in mtbmj.study_presets():
        mj, od = [], []
        for _ in range(repeat):  # interleaved, so a load spike hits both engines alike
            mj.append(mtbmj.run_drop(name, "mujoco").wall_time_s)
            od.append(mtbmj.run_drop(name, "ode").wall_time_s)
        ratio = min(od) / min(mj)
        rows[name] = {"mujoco_s": min(mj), "ode_s": min(od), "ratio_ode_over_mujoco": ratio,
                      "met_5x": ratio >= 5.0, "mujoco_all_s": mj, "ode_all_s": od}
        print(f"{name:<6} {min(mj):>8.3f} {min(od):>8.3f} {ratio:>9.2f}x {'yes' if ratio >= 5 else 'NO':>5}", flush=True)
    total_mj = sum(r["mujoco_s"] for r in rows.values())
    total_od = sum(r["ode_s"] for r in rows.values())
    ratios = [r["ratio_ode_over_mujoco"] for r in rows.values()]
    print(f"{'total':<6} {total_mj:>8.3f} {total_od:>8.3f} {total_od / total_mj:>9.2f}x; "
          f"per-preset ratio min {min(ratios):.2f}x, median {np.median(ratios):.2f}x; "
          f"target >= 5x met for {sum(r['met_5x'] for r in rows.values())}/{len(rows)} presets")
    return {"rows": rows, "total_mujoco_s": total_mj, "total_ode_s": total_od,
            "total_ratio": total_od / total_mj, "min_ratio": min(ratios), "median_ratio": float(np.median(ratios)),
            "all_met_5x": all(r["met_5x"] for r in rows.values())}


def _s1(integrator: str | None = None):
    overrides = {"solver.integrator": integrator} if integrator else None
    setup = compose.setup(mtbmj.load_config("S1", overrides))
    sc = scene.build(setup)
    data = mujoco.MjData(sc.model)
    data.qvel[sc.sled_dof] = setup.impact_speed
    mujoco.mj_forward(sc.model, data)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(sc.model, spec))
    mujoco.mj_getState(sc.model, data, state, spec)
    steps = int(round(setup.duration / setup.timestep))
    return setup, sc, data, state, steps


def _builtin(setup, sc):
    """The same compiled S1 model with the fork law as MuJoCo's joint spring and damper."""
    m = sc.model.__copy__()
    spring, damper = setup.fork.spring, setup.fork.damper
    m.jnt_stiffness[m.joint("fork").id] = spring.rate
    m.dof_damping[sc.fork_dof] = damper.coefficient
    return m


def _positions(states, sc):
    """sled, fork, tire (mm) from rollout states (time is column 0, qpos follows)."""
    sled = states[:, 1 + sc.sled_qpos] * 1e3
    fork = states[:, 1 + sc.fork_qpos] * 1e3
    return sled, fork, sled - fork


def _maxdiff(a, b) -> dict:
    return {k: float(np.max(np.abs(x - y))) for k, x, y in zip(("sled", "fork", "tire"), a, b)}


def part_b(repeat: int) -> dict:
    setup, sc, data, state0, steps = _s1()
    m_cb, m_bi = sc.model, _builtin(setup, sc)
    assert mujoco.get_mjcb_control() is None
    callback = ForkCallback(m_cb, setup.fork)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS

    def roll(m):
        return rollout.rollout(m, data, state0[None, :], nstep=steps)[0][0]

    def step(m):
        mujoco.mj_setState(m, data, state0, spec)
        mujoco.mj_step(m, data, nstep=steps)
        out = np.empty_like(state0)
        mujoco.mj_getState(m, data, out, spec)
        return out

    roll(m_bi), step(m_bi)  # warm-up (rollout's first call sets up its machinery)
    times = {k: [] for k in ("roll_cb", "step_cb", "roll_bi", "step_bi")}
    for _ in range(repeat):  # interleaved, so a load spike hits all four variants alike
        with installed(callback):
            for key, fn in (("roll_cb", roll), ("step_cb", step)):
                start = time.perf_counter()
                out = fn(m_cb)
                times[key].append(time.perf_counter() - start)
                if key == "roll_cb":
                    s_cb = out
                else:
                    f_cb = out
        for key, fn in (("roll_bi", roll), ("step_bi", step)):
            start = time.perf_counter()
            out = fn(m_bi)
            times[key].append(time.perf_counter() - start)
            if key == "roll_bi":
                s_bi = out
            else:
                f_bi = out
    (t_roll_cb, all_roll_cb), (t_step_cb, all_step_cb), (t_roll_bi, all_roll_bi), (t_step_bi, all_step_bi) = (
        (min(times[k]), times[k]) for k in ("roll_cb", "step_cb", "roll_bi", "step_bi"))

    engine = mtbmj.run_drop("S1", "mujoco")
    eng = tuple(engine.raw[c][1:] for c in ("sled_mm", "fork_mm", "tire_mm"))
    match = {
        "callback_vs_builtin_rollout_mm": _maxdiff(_positions(s_cb, sc), _positions(s_bi, sc)),
        "callback_rollout_vs_engine_run_drop_mm": _maxdiff(_positions(s_cb, sc), eng),
        "callback_vs_builtin_final_state_mj_step_mm": _maxdiff(_positions(f_cb[None], sc), _positions(f_bi[None], sc)),
        "rollout_vs_mj_step_final_state_callback_mm": _maxdiff(_positions(s_cb[-1:], sc), _positions(f_cb[None], sc)),
    }
    # implicitfast treats dof_damping implicitly but qfrc_applied explicitly; under rk4 both are
    # explicit, so the two runs must agree to round-off there.
    setup4, sc4, data4, state4, steps4 = _s1("rk4")
    m4_bi = _builtin(setup4, sc4)
    with installed(ForkCallback(sc4.model, setup4.fork)):
        s4_cb = rollout.rollout(sc4.model, data4, state4[None, :], nstep=steps4)[0][0]
    s4_bi = rollout.rollout(m4_bi, data4, state4[None, :], nstep=steps4)[0][0]
    match["callback_vs_builtin_rollout_rk4_mm"] = _maxdiff(_positions(s4_cb, sc4), _positions(s4_bi, sc4))

    res = {
        "steps": steps, "integrator": setup.integrator, "timestep_s": setup.timestep,
        "fork_rate_N_per_m": setup.fork.spring.rate, "fork_damping_N_s_per_m": setup.fork.damper.coefficient,
        "rollout": {"callback_s": t_roll_cb, "builtin_s": t_roll_bi, "ratio_callback_over_builtin": t_roll_cb / t_roll_bi,
                    "callback_all_s": all_roll_cb, "builtin_all_s": all_roll_bi},
        "mj_step_nstep": {"callback_s": t_step_cb, "builtin_s": t_step_bi, "ratio_callback_over_builtin": t_step_cb / t_step_bi,
                          "callback_all_s": all_step_cb, "builtin_all_s": all_step_bi},
        "engine_run_drop_S1_wall_s": engine.wall_time_s,
        "match": match,
    }
    us = lambda t: 1e6 * t / steps
    print(f"\n(b) S1 force-law layer: {steps} steps, {setup.integrator}, dt {setup.timestep:g} s, best of {repeat}")
    print(f"{'stepping':<28} {'callback [s]':>12} {'built-in [s]':>12} {'ratio':>7} {'callback us/step':>16} {'built-in us/step':>16}")
    for label, key in (("rollout, one chunk", "rollout"), ("mj_step(m, d, nstep=N)", "mj_step_nstep")):
        r = res[key]
        print(f"{label:<28} {r['callback_s']:>12.4f} {r['builtin_s']:>12.4f} {r['ratio_callback_over_builtin']:>6.1f}x "
              f"{us(r['callback_s']):>16.2f} {us(r['builtin_s']):>16.2f}")
    print(f"engine run_drop('S1') wall time (chunked rollout + checks): {engine.wall_time_s:.4f} s")
    for k, v in match.items():
        print(f"  max diff {k}: " + ", ".join(f"{c} {x:.2e}" for c, x in v.items()))
    return res


def part_c(repeat: int) -> dict:
    from mtbmj.drop.study import run_study

    print(f"\n(c) study, best of {repeat}")
    e2e = []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            proc = subprocess.run([MTBMJ, "study", "--out", tmp, "--quiet"], capture_output=True, text=True)
            e2e.append(time.perf_counter() - start)
            if proc.returncode:
                print(proc.stdout, proc.stderr, file=sys.stderr)
                raise SystemExit(f"mtbmj study failed with exit code {proc.returncode}")
            files = sorted(p.name for p in Path(tmp).iterdir())
    runs, serial = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        results, _ = run_study()
        runs.append(time.perf_counter() - start)
        if runs[-1] == min(runs):  # the engine time sum of the best run
            serial = sum(r.wall_time_s for per in results.values() for r in per.values())
    res = {"command": f"{MTBMJ} study --out <tmpdir> --quiet", "cpus": os.cpu_count(),
           "end_to_end_s": min(e2e), "end_to_end_all_s": e2e, "target_s": 20.0, "met": min(e2e) < 20.0,
           "runs_alone_s": min(runs), "runs_alone_all_s": runs, "files_written": files,
           "sum_of_engine_wall_times_s": serial, "overhead_beyond_runs_s": min(e2e) - min(runs)}
    print(f"mtbmj study --out <tmp> (subprocess, end to end): {min(e2e):.2f} s (all {', '.join(f'{t:.2f}' for t in e2e)}) "
          f"on {os.cpu_count()} cores; target < 20 s {'MET' if res['met'] else 'MISSED'}")
    print(f"28 runs alone (run_study, process pool):        {min(runs):.2f} s (all {', '.join(f'{t:.2f}' for t in runs)}); "
          f"sum of the 28 engine wall times {serial:.2f} s; import + figures + files {res['overhead_beyond_runs_s']:.2f} s")
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="best of N for (a) and (b) (default 3)")
    ap.add_argument("--study-repeat", type=int, default=3, help="best of N for (c) (default 3)")
    ap.add_argument("--skip-study", action="store_true")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    load = os.getloadavg()[0]
    print(f"{os.cpu_count()} CPUs, load average {load:.2f} at start")
    out = {"command": "python benchmarks/speed.py", "load_average_at_start": load,
           "a_engine_vs_reference": part_a(args.repeat), "b_force_law_layer": part_b(max(args.repeat, 10))}
    if not args.skip_study:
        out["c_study"] = part_c(args.study_repeat)
    out["load_average_at_end"] = os.getloadavg()[0]
    print(f"\nwrote {write_json(__file__, out, args.out)}")


if __name__ == "__main__":
    main()

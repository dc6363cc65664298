"""MuJoCo vs the ODE reference, every preset S1-S14, 1.5 s drop.

(a) default settings (implicitfast, 1e-4 s)   target max |diff| <= 0.1 mm
(b) rk4, 1e-4 s                               target max |diff| <= 0.01 mm

Max |MuJoCo - ODE| of sled, fork and tire displacement on the raw engine grid
(``DropResult.difference``). A diagnosis section then splits the error budget of (b) for the
worst preset: the ODE's own tolerance error, the MuJoCo step-size convergence, and the tire
touchdown at t = 0 (MuJoCo creates the contact at distance 0 but gives it no constraint row, so
the tire damping force B*v_i is missing from the first step / first RK4 stage).

    python benchmarks/accuracy.py [--no-diagnose] [--workers N] [--out PATH]

Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/accuracy.json``,
outside the repository; ``--out benchmarks/results/accuracy.json`` refreshes the committed file).
With ``--no-diagnose`` the last diagnosis is kept (from ``--out``'s file if it exists, else the
committed one). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import os
from concurrent.futures import ProcessPoolExecutor

import mujoco
import numpy as np

import mtbmj
from mtbmj import compose
from mtbmj.drop import engine_mujoco
from mtbmj.drop import scene
from _bench import add_out_option, write_json

DEFAULT = {}
RK4 = {"solver.integrator": "rk4", "solver.timestep_s": 1e-4}
TIGHT_ODE = {"solver.ode_rtol": 1e-11, "solver.ode_atol_mm": 1e-10}
TARGETS = {"default": 0.1, "rk4_1e-4": 0.01}
COLUMNS = ("sled_mm", "fork_mm", "tire_mm")


class _TouchOffset:
    """Stand-in for the ``mujoco`` module inside ``engine_mujoco`` that starts the run with the
    sled ``eps`` m into the ground, so the t = 0 contact has a constraint row. Only for the
    diagnosis; the library is not modified."""

    def __init__(self, eps: float):
        self.eps = eps

    def __getattr__(self, name):
        return getattr(mujoco, name)

    def mj_forward(self, m, d):
        d.qpos[m.joint("sled").qposadr[0]] += self.eps
        mujoco.mj_forward(m, d)


def run_mujoco(name, overrides, touch_eps: float = 0.0):
    if not touch_eps:
        return mtbmj.run_drop(name, "mujoco", overrides=overrides)
    engine_mujoco.mujoco = _TouchOffset(touch_eps)
    try:
        return mtbmj.run_drop(name, "mujoco", overrides=overrides)
    finally:
        engine_mujoco.mujoco = mujoco


def diffs(a, b) -> dict:
    return {c.removesuffix("_mm"): v for c, v in a.difference(b).items()}


def worst(d: dict) -> float:
    return max(v["max_abs_mm"] for v in d.values())


def _pair(job):
    name, label = job
    ov = DEFAULT if label == "default" else RK4
    m = run_mujoco(name, ov)
    o = mtbmj.run_drop(name, "ode", overrides=ov)
    d = diffs(m, o)
    return name, label, {"diff_mm": d, "max_mm": worst(d), "target_mm": TARGETS[label],
                         "met": worst(d) <= TARGETS[label]}


def _diag_job(job):
    kind, name, dt, eps = job
    if kind == "ode_tol":
        o = mtbmj.run_drop(name, "ode", overrides=RK4)
        t = mtbmj.run_drop(name, "ode", overrides={**RK4, **TIGHT_ODE})
        return job, worst(diffs(o, t))
    ov = {"solver.integrator": kind, "solver.timestep_s": dt}
    ref = mtbmj.run_drop(name, "ode", overrides={**ov, **TIGHT_ODE})
    return job, worst(diffs(run_mujoco(name, ov, eps), ref))


def touchdown_facts(name: str) -> dict:
    """What MuJoCo sees at t = 0: the contact exists at distance 0 but has no constraint row."""
    s = compose.setup(mtbmj.load_config(name))
    sc = scene.build(s)
    m, d = sc.model, mujoco.MjData(sc.model)
    d.qvel[sc.sled_dof] = s.impact_speed
    mujoco.mj_forward(m, d)
    at_zero = {"ncon": int(d.ncon), "nefc": int(d.nefc), "dist_m": float(d.contact[0].dist) if d.ncon else None}
    d.qpos[sc.sled_qpos] = 1e-12
    mujoco.mj_forward(m, d)
    missing = s.tire.impact.damping * s.impact_speed
    return {"preset": name, "at_t0": at_zero, "with_1e-12_m_penetration": {"nefc": int(d.nefc),
            "contact_force_N": float(d.efc_force[0]) if d.nefc else 0.0},
            "expected_B_times_vi_N": missing,
            "missing_impulse_first_step_N_s": missing * s.timestep,
            "wheel_velocity_error_first_step_m_per_s": missing * s.timestep / s.wheel_mass}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--no-diagnose", action="store_true")
    add_out_option(ap, __file__)
    args = ap.parse_args()
    names = list(mtbmj.study_presets())
    rows = {n: {} for n in names}
    with ProcessPoolExecutor(args.workers) as pool:
        for name, label, row in pool.map(_pair, [(n, l) for n in names for l in TARGETS]):
            rows[name][label] = row

    print("MuJoCo vs ODE, max |diff| [mm] over 1.5 s (raw 1e-4 s grid)")
    print(f"{'preset':<6} | {'default: sled':>13} {'fork':>8} {'tire':>8} {'<=0.1':>5} | "
          f"{'rk4 1e-4: sled':>14} {'fork':>8} {'tire':>8} {'<=0.01':>6}")
    for n in names:
        a, b = rows[n]["default"], rows[n]["rk4_1e-4"]
        f = lambda r, c: f"{r['diff_mm'][c]['max_abs_mm']:.5f}"
        print(f"{n:<6} | {f(a,'sled'):>13} {f(a,'fork'):>8} {f(a,'tire'):>8} {'yes' if a['met'] else 'NO':>5} | "
              f"{f(b,'sled'):>14} {f(b,'fork'):>8} {f(b,'tire'):>8} {'yes' if b['met'] else 'NO':>6}")
    summary = {}
    for label, target in TARGETS.items():
        w = max(names, key=lambda n: rows[n][label]["max_mm"])
        r = rows[w][label]
        col = max(r["diff_mm"], key=lambda c: r["diff_mm"][c]["max_abs_mm"])
        summary[label] = {"worst_preset": w, "worst_column": col, "worst_mm": r["max_mm"],
                          "at_time_s": r["diff_mm"][col]["at_time_s"], "target_mm": target,
                          "all_met": all(rows[n][label]["met"] for n in names)}
        print(f"{label:>9}: worst {r['max_mm']:.5f} mm ({w} {col} at t = {r['diff_mm'][col]['at_time_s']:.4f} s); "
              f"target <= {target} mm {'MET' if summary[label]['all_met'] else 'MISSED'} for all presets")

    diagnosis = None
    if not args.no_diagnose:
        w = summary["rk4_1e-4"]["worst_preset"]
        probes = sorted({w, "S12", "S13"}, key=names.index)  # worst, the tire-law switch, no tire damping
        jobs = [("ode_tol", n, None, 0.0) for n in probes]
        jobs += [(integ, n, dt, eps) for n in probes for integ in ("rk4", "implicitfast")
                 for dt in (1e-4, 5e-5) for eps in (0.0, 1e-12)]
        with ProcessPoolExecutor(args.workers) as pool:
            out = dict(pool.map(_diag_job, jobs))
        diagnosis = {"touchdown": touchdown_facts(w), "presets": {}}
        print(f"\nDiagnosis (reference: ODE at rtol 1e-11, atol 1e-10 mm). Touchdown at t = 0 on {w}: "
              f"ncon = {diagnosis['touchdown']['at_t0']['ncon']}, nefc = {diagnosis['touchdown']['at_t0']['nefc']}; "
              f"missing tire damping force B*v_i = {diagnosis['touchdown']['expected_B_times_vi_N']:.1f} N "
              f"(with 1e-12 m penetration the row exists: {diagnosis['touchdown']['with_1e-12_m_penetration']['contact_force_N']:.1f} N)")
        print(f"{'preset':<6} {'ODE rtol1e-8 vs 1e-11':>21} | {'integrator':<12} {'dt':>7} {'err as is':>10} "
              f"{'err, t0 contact row':>19}")
        for n in probes:
            p = diagnosis["presets"][n] = {"ode_default_vs_tight_mm": out[("ode_tol", n, None, 0.0)], "mujoco": []}
            for integ in ("rk4", "implicitfast"):
                for dt in (1e-4, 5e-5):
                    e0, e1 = out[(integ, n, dt, 0.0)], out[(integ, n, dt, 1e-12)]
                    p["mujoco"].append({"integrator": integ, "timestep_s": dt, "max_diff_mm": e0,
                                        "max_diff_with_t0_contact_row_mm": e1})
                    print(f"{n:<6} {p['ode_default_vs_tight_mm']:>21.2e} | {integ:<12} {dt:>7.0e} {e0:>10.6f} {e1:>19.6f}")
    if diagnosis is None:  # keep the last diagnosis, marked as such
        import json
        from _bench import RESULTS
        last = args.out if args.out is not None and args.out.is_file() else RESULTS / "accuracy.json"
        try:
            old = json.loads(last.read_text())
            if old.get("diagnosis"):
                diagnosis = {**old["diagnosis"], "from_previous_run": old["environment"]["date"]}
        except (OSError, ValueError, KeyError):
            pass
    path = write_json(__file__, {"command": "python benchmarks/accuracy.py", "targets_mm": TARGETS,
                                 "rows": rows, "summary": summary, "diagnosis": diagnosis}, args.out)
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()

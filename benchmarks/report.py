"""Write docs/measured.md from the benchmark results (benchmarks/results/*.json).

Every figure on the page is read from a results file here; nothing measured is typed in this
script. Each results file has a small function below that turns it into table rows (figure,
target, measured, measured on, command); a file that is missing gives no rows. The targets are the
ones the scripts' docstrings and the issues set, stated with each row (a JSON's own target is used
where it records one).

    python benchmarks/report.py            # rewrite docs/measured.md
    python benchmarks/report.py --check    # exit 1 if docs/measured.md differs from what it would write
    python benchmarks/report.py --out PATH # write the page to PATH instead

This script measures nothing and runs no benchmark: the page it writes follows from the results
files alone, so its default is the page itself. Each row's command is the one that refreshes the
row's results file (``--out benchmarks/results/<file>``: the benchmarks write to a scratch file
outside the repository by default). tests/test_measured_doc.py checks that the page equals what
this script writes.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from dataclasses import dataclass, replace
from pathlib import Path

BENCH = Path(__file__).resolve().parent
RESULTS = BENCH / "results"
REPO = BENCH.parent
PAGE = REPO / "docs" / "measured.md"


@dataclass
class Row:
    figure: str
    target: str
    measured: str
    json_name: str
    command: str


# --- formatting ---------------------------------------------------------------------------------

def num(x: float, digits: int = 2) -> str:
    """``digits`` significant figures, plain notation down to 1e-4, powers of ten below."""
    x = float(x)
    if x == 0:
        return "0"
    if abs(x) < 1e-4:
        mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
        return f"{mantissa}e{int(exponent)}"
    text = f"{x:#.{digits}g}"
    if "e" in text:  # a large number: no exponent, rounded to an integer
        return f"{x:.0f}"
    return text.rstrip(".")


def mm(x: float, digits: int = 2) -> str:
    return f"{num(x, digits)} mm"


def ratio(x: float, digits: int = 3) -> str:
    return f"{num(x, digits)}×"


def spread(lo: float, hi: float, digits: int = 3, unit: str = "") -> str:
    return f"{num(lo, digits)}–{num(hi, digits)}{unit}"


def ms(seconds: float, digits: int = 3) -> str:
    return f"{num(seconds * 1e3, digits)} ms"


def sec(seconds: float, digits: int = 2) -> str:
    return f"{num(seconds, digits)} s"


def pct(fraction: float, digits: int = 3) -> str:
    return f"{num(fraction * 100, digits)} %"


def ratio_cell(d: dict, digits: int = 3) -> str:
    """A ratio block of speed_scales.json: median ratio and the spread of the pairwise ratios."""
    return f"{ratio(d['ratio_of_medians'], digits)} (pairs {spread(d['pairwise_min'], d['pairwise_max'], digits)})"


def tgt(x: float) -> str:
    """A target as the scripts state it (1.15, 2, 0.01)."""
    return f"{float(x):g}"


def plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def py(script: str, *options: str) -> str:
    return " ".join(["python", f"benchmarks/{script}", *options])


def refreshing(command: str, name: str) -> str:
    """``command`` as it refreshes the results file ``name``: any ``--out`` it carries replaced by
    ``--out benchmarks/results/<name>`` (with no ``--out`` a benchmark writes to a scratch file)."""
    kept = re.sub(r"\s--out(?:=|\s+)\S+", "", command)
    return f"{kept} --out benchmarks/results/{name}"


def load(name: str) -> dict | None:
    path = RESULTS / name
    return json.loads(path.read_text()) if path.is_file() else None


def measured_on(name: str) -> str:
    """The run's date and commit as the JSON records them; for a file written before
    ``_bench.write_json`` recorded them, the date in its environment block, and failing that the
    date of the git commit that wrote the file."""
    data = load(name) or {}
    env = data.get("environment", {})
    mujoco = f", MuJoCo {env['mujoco']}" if env.get("mujoco") else ""
    if env.get("load_average_1min") is not None:
        mujoco += f", load {num(env['load_average_1min'])}"
    if data.get("measured_at"):
        commit = f", {data['commit']}" if data.get("commit") else ""
        return f"{data['measured_at']}{commit}{mujoco}"
    if env.get("date"):
        return f"{env['date'][:10]}{mujoco}"
    done = subprocess.run(["git", "log", "-1", "--format=%cs", "--", str(RESULTS / name)], cwd=REPO,
                          capture_output=True, text=True)
    date = done.stdout.strip() or "not committed"
    return f"{date} (date of the commit that wrote it){mujoco}"


# --- one function per results file ---------------------------------------------------------------

def accuracy_steps_rows(d: dict) -> dict[str, list[Row]]:
    name = "accuracy_steps.json"
    env = d["envelope"]
    cmd = py("accuracy_steps.py", "--envelope", str(len(env["cases"])), "--seed", str(env["seed"]))
    presets = d["presets"]
    worst = max(presets, key=lambda p: presets[p]["max_abs_mm"])
    steps = d["steps"]

    def integrator(prefix: str) -> str:
        keys = sorted((k for k in steps if k.startswith(prefix + "_")), key=lambda k: -float(k.split("_")[1]))
        return "; ".join(f"{tgt(float(k.split('_')[1]) * 1e3)} ms: {mm(steps[k]['max_abs_mm'])}, "
                         f"{ms(steps[k]['wall_s_median'])}" for k in keys)

    default = steps["default"]
    over = steps["default_over_implicitfast_1e-4"]
    rest = d["rest"]
    rest_vs_ode = max(abs(rest[t]["mujoco"] - rest[t]["ode"]) for t in ("3s", "6s"))
    past = max(c["fork_past_travel_mm"] for c in env["cases"])
    return {"accuracy": [
        Row(f"MuJoCo vs ODE, max \\|diff\\| of sled, fork and tire, every preset S1–S{len(presets)}, default settings",
            "≤ 0.05 mm", f"{mm(presets[worst]['max_abs_mm'])} ({worst}); S12 {mm(presets['S12']['max_abs_mm'])}",
            name, cmd),
        Row(f"the same on {len(env['cases'])} random plausible forks (`mtbmj.drop.envelope`, seed {env['seed']})",
            "≤ 0.1 mm", f"worst {mm(env['worst_mm'])}, {env['beyond_0.1_mm']} beyond 0.1 mm; fast engine worst "
            f"{mm(env['fast_worst_mm'])}; fork at most {mm(past)} past travel", name, cmd),
        Row("S12 default step rule: error, wall time (median, spread)", "report",
            f"{mm(default['max_abs_mm'])}, {ms(default['wall_s_median'])} "
            f"({spread(default['wall_s_spread'][0] * 1e3, default['wall_s_spread'][1] * 1e3, unit=' ms')})",
            name, cmd),
        Row("S12 RK4 at a fixed step: error, median wall time", "report", integrator("rk4"), name, cmd),
        Row("S12 implicitfast at a fixed step: error, median wall time", "report", integrator("implicitfast"),
            name, cmd),
        Row("S12 wall time, default / implicitfast at 0.1 ms", "≤ 0.5×",
            f"{ratio(over['median'], 2)} (pairs {spread(*over['spread'], 2)})", name, cmd),
        Row("S12 rest position at 3 s and at 6 s", "equal within 0.01 mm",
            f"{num(rest['3s']['mujoco'], 6)} mm, difference {mm(rest['difference_mm'])}; "
            f"MuJoCo vs ODE {mm(rest_vs_ode)}", name, cmd),
    ]}


def accuracy_envelope_rows(d: dict) -> dict[str, list[Row]]:
    t = d["totals"]
    cases = [c for seed in d["envelope"] for c in seed["cases"]]
    seeds = sorted(t["seeds"])
    cmd = py("accuracy_steps.py", "--envelope-only", "--envelope", str(t["forks"] // len(seeds)),
             "--seed", ",".join(map(str, seeds)), "--jobs", "2")
    fast_within = sum(c["fast_mm"] <= 0.01 for c in cases)
    beyond = [c["sensitivity_mm"] for c in cases if c["fast_mm"] > 0.01]
    conditioning = (f"; the reference itself moves by {spread(min(beyond), max(beyond), 2, ' mm')} on those "
                    f"{len(beyond)} when the tire rates change by 0.01 %") if beyond else ""
    return {"accuracy": [
        Row(f"MuJoCo vs ODE on {t['forks']} random forks ({len(seeds)} seeds), max \\|diff\\|", "≤ 0.1 mm",
            f"{t['within_0.05_mm']} of {t['forks']} within 0.05 mm, worst {mm(t['worst_mm'])}; "
            f"fork at most {mm(max(c['fork_past_travel_mm'] for c in cases))} past travel, tire "
            f"{mm(max(c['tire_past_max_mm'] for c in cases))} past its maximum", "accuracy_envelope.json", cmd),
        Row(f"fast engine vs ODE on the same {t['forks']} forks", "≤ 0.01 mm",
            f"{fast_within} of {t['forks']} within 0.01 mm, worst {mm(t['fast_worst_mm'])}{conditioning}",
            "accuracy_envelope.json", cmd),
    ]}


def speed_scales_rows(d: dict) -> dict[str, list[Row]]:
    name, cmd = "speed_scales.json", d["command"]
    rows: dict[str, list[Row]] = {}
    if "a" in d:
        a = d["a"]
        rows.setdefault("drop", []).append(Row(
            "`run_drop(\"S12\")` / bare `mujoco.rollout` making as many steps, compiled callback installed",
            f"≤ {tgt(a['target'])}×",
            f"{ratio_cell(a['run_drop_over_bare_callback'])}: {ms(a['run_drop_s']['median'])} vs "
            f"{ms(a['bare_with_compiled_callback_s']['median'])}; without any callback "
            f"{ratio(a['run_drop_over_bare_no_callback']['ratio_of_medians'])}", name, cmd))
    if "d" in d:
        e = d["d"]
        rows.setdefault("drop", []).append(Row(
            "fast engine, S12 drops per second in-process", f"≥ {e['target_drops_per_s']}",
            f"{e['fast_drops_per_s_engine']:.0f} ({ms(e['fast_engine_s']['median'])}); MuJoCo's engine "
            f"{ratio_cell(e['mujoco_engine_over_fast_engine'])} slower; through `run_drop` "
            f"{e['fast_drops_per_s_run_drop']:.0f} per second", name, cmd))
        worst = max(e["max_diff_from_ode_mm"], key=e["max_diff_from_ode_mm"].get)
        rows.setdefault("accuracy", []).append(Row(
            "fast engine vs ODE, max \\|diff\\| over 2 s, every preset", f"≤ {tgt(e['target_mm'])} mm",
            f"{mm(e['worst_mm'])} ({worst})", name, cmd))
    if "b" in d:
        b = d["b"]
        rows.setdefault("startup", []).extend([
            Row("whole process `mtbmj --help` / `python -c \"import numpy, mujoco\"`",
                f"≤ {tgt(b['targets']['help'])}×", ratio_cell(b["help_over_floor"], 2), name, cmd),
            Row("whole process `mtbmj drop S12` / the same floor", f"≤ {tgt(b['targets']['drop_mujoco'])}×",
                f"{ratio_cell(b['drop_mujoco_over_floor'], 2)}: {sec(b['drop_mujoco']['median'])} vs "
                f"{sec(b['floor']['median'])}", name, cmd),
            Row("whole process `mtbmj drop S12 --engine fast` / the same floor", "report",
                ratio_cell(b["drop_fast_over_floor"], 2), name, cmd)])
    if "c" in d:
        c = d["c"]
        rows.setdefault("startup", []).append(Row(
            "peak RSS, whole `mtbmj drop S12 --duration 150`", f"≤ {c['target_150s_MiB']} MiB",
            f"{c['150s']['peak_rss_MiB']:.0f} MiB (15 s: {c['15s']['peak_rss_MiB']:.0f} MiB; "
            f"{c['bytes_per_engine_step']:.0f} bytes per engine step kept)", name, cmd))
    if "e" in d:
        e = d["e"]
        w = e["fast"]["wall_s"]
        rows.setdefault("sweeps", []).append(Row(
            "whole `mtbmj sweep S12 --engine fast`, 200 variants", f"≥ {e['target_fast_variants_per_s']} variants/s",
            f"{e['fast']['variants_per_s']:.0f} variants/s ({sec(w['median'], 3)}, {spread(w['min'], w['max'], unit=' s')}); "
            f"on MuJoCo {e['mujoco']['variants_per_s']:.0f} variants/s", name, cmd))
    return rows


def speed_rows(d: dict) -> dict[str, list[Row]]:
    name, cmd = "speed.json", d["command"]
    rows: dict[str, list[Row]] = {}
    a = d.get("a_engine_vs_reference")
    if a:
        met = [r for r in a["rows"].values() if r["met_5x"]]
        slowest = min(a["rows"], key=lambda p: a["rows"][p]["ratio_ode_over_mujoco"])
        rows["drop"] = [Row("ODE reference (Radau, rtol 1e-8) time / MuJoCo time, 1.5 s drop, best of 3", "≥ 5×",
                            f"{len(met)} of {len(a['rows'])} presets; median {ratio(a['median_ratio'], 2)}, "
                            f"lowest {slowest} {ratio(a['min_ratio'], 2)}", name, cmd)]
    b = d.get("b_force_law_layer")
    if b:
        rows.setdefault("drop", []).append(Row(
            f"S1 with the Python force-law callback / MuJoCo's built-in joint spring and damping, best of "
            f"{len(b['rollout']['callback_all_s'])}", "report",
            f"{ratio(b['rollout']['ratio_callback_over_builtin'])} (`mujoco.rollout`), "
            f"{ratio(b['mj_step_nstep']['ratio_callback_over_builtin'])} (`mj_step`)", name, cmd))
    c = d.get("c_study")
    if c:
        rows["sweeps"] = [Row(f"`mtbmj study` end to end (28 runs, figures, table), best of {len(c['end_to_end_all_s'])}",
                              f"< {tgt(c['target_s'])} s",
                              f"{sec(c['end_to_end_s'], 3)} (all: {', '.join(sec(t, 3) for t in c['end_to_end_all_s'])}); "
                              f"the runs alone {sec(c['runs_alone_s'], 3)}", name, cmd)]
    return rows


def compiled_rows(d: dict) -> dict[str, list[Row]]:
    name, cmd = "compiled.json", py("compiled.py", "--drops", str(d["throughput"]["drops"]))
    f, t = d["force_law_layer"], d["throughput"]
    one, two = t["threads"]["1"], t["threads"]["2"]
    return {"drop": [
        Row("compiled (numba) force laws: S12 / built-in elements only, one thread, best times interleaved", f"≤ {tgt(f['target_ratio'])}×",
            f"{ratio(f['ratio_compiled_to_builtin'])}; Python laws {ratio(f['ratio_python_to_builtin'])}", name, cmd),
        Row(f"rollout throughput of {t['drops']} drops, compiled S12 laws / bare scene, 1 and 2 threads, best times "
            "interleaved", f"≥ {tgt(t['target_ratio'])}×",
            f"{ratio(one['ratio_compiled_to_bare'])} and {ratio(two['ratio_compiled_to_bare'])} "
            f"({num(one['compiled_drops_per_s'])} and {num(two['compiled_drops_per_s'])} drops/s)", name, cmd),
    ]}


def native_loop_rows(d: dict) -> dict[str, list[Row]]:
    s = d["summary"]
    cmd = py("native_loop.py", "--repeat", str(s["repeat"]), "--calls", str(s["calls"]))
    lo, py_ = s["loop_over_compiled"], s["python_over_compiled"]
    return {"drop": [Row(
        "`run_drop(\"S12\")` in a loop from a fresh process, median call from the third on / the same loop "
        "after `native.expect_many()`", "≤ 1.3×",
        f"{ratio(lo['median'], 2)} (rounds {spread(lo['min'], lo['max'], 2)}); without the background load "
        f"{ratio(py_['median'], 2)} ({spread(py_['min'], py_['max'], 2)})", "native_loop.json", cmd)]}


def sweep_rows(d: dict, name: str) -> dict[str, list[Row]]:
    cmd = py("sweep.py", "--variants", str(d["variants"]), "--workers", str(d["workers"]),
             "--threads", str(d["threads_per_process"]),
             *(["--repeat", str(len(d["interleaved"]["rounds"]))] if "interleaved" in d else []))
    setting = (f"{d['variants']} variants, {plural(d['workers'], 'process')}".replace("processs", "processes")
               + f" of {plural(d['threads_per_process'], 'thread')}, {d['steps_per_variant']} steps per variant")
    rows = [Row(f"S12 sweep (batched runner) / bare-scene rollout of the same variants, one run each; {setting}",
                "≤ 1.2×",
                f"{ratio(d['ratio_sweep_over_rollout'])} ({sec(d['sweep_wall_s'], 3)} vs "
                f"{sec(d['bare_rollout_wall_s'], 3)}; {num(d['variants_per_s'], 3)} variants/s)", name, cmd)]
    if "throughput_ratio_sweep_to_same_steps_with_callback" in d:
        p = d["batch_runner_phases_per_variant"]
        rows.append(Row("the same sweep / the bare scene making as many steps as the runner, compiled callback "
                        "installed (throughput; per variant: best of 3, interleaved)", "≥ 0.9×",
                        f"{ratio(d['throughput_ratio_sweep_to_same_steps_with_callback'], 2)} for the whole "
                        f"sweep (`run_sweep`); in one process {num(p['whole_runner_ms'], 3)} ms per variant vs "
                        f"{num(p['bare_same_steps_with_callback_ms'], 3)} ms of that stepping (runner "
                        f"{ratio(p['runner_over_bare_same_steps_with_callback'])})", name, cmd))
    if "interleaved" in d:
        i = d["interleaved"]
        b, c = i["throughput_builtin_over_sweep"], i["throughput_callback_over_sweep"]
        rows.append(Row(f"the same sweep / the bare scene making as many steps with built-in elements (throughput), "
                        f"{len(i['rounds'])} interleaved rounds", f"≥ {tgt(i['target_builtin'])}×",
                        f"{ratio(b['ratio_of_medians'], 2)} ({spread(b['min'], b['max'], 2)}): {sec(i['sweep_s'], 3)} vs "
                        f"{sec(i['builtin_s'], 3)}; with the compiled callback instead {ratio(c['ratio_of_medians'], 2)} "
                        f"({spread(c['min'], c['max'], 2)})", name, cmd))
        if "throughput_builtin_over_warm_sweep" in i:
            w, u = i["throughput_builtin_over_warm_sweep"], i["start_up_s"]
            rows.append(Row("the same, the sweep in workers started and warmed (a short drop each) before the "
                            "timing", "report",
                            f"{ratio(w['ratio_of_medians'], 2)} ({spread(w['min'], w['max'], 2)}): "
                            f"{sec(i['warm_s'], 3)}; the whole sweep less the warmed one, per round: median "
                            f"{u['median']:+.2f} s ({u['min']:+.2f} to {u['max']:+.2f} s)", name, cmd))
        if "throughput_builtin_over_command" in i:
            m = i["throughput_builtin_over_command"]
            rows.append(Row("the same, the whole `mtbmj sweep` command in a process of its own (imports, pool, "
                            "the compiled laws' load in each worker)", f"≥ {tgt(i['target_builtin'])}×",
                            f"{ratio(m['ratio_of_medians'], 2)} ({spread(m['min'], m['max'], 2)}): "
                            f"{sec(i['command_s'], 3)}", name, cmd))
    return {"sweeps": rows}


def dropfit_rows(d: dict, name: str) -> dict[str, list[Row]]:
    f = d["fit"]
    held = sum(p["ci_holds_truth"] for p in d["parameters"].values())
    engine = "MuJoCo" if f["engine"] == "mujoco" else f"the {f['engine']} engine"
    return {"fits": [Row(
        f"drop fit of {len(f['free'])} S12 parameters on {engine}, {tgt(d['record']['duration_s'])} s "
        f"{d['record']['data_engine'].upper()} record, {plural(f['workers'], 'worker')}, one run", f"< {tgt(f['target_s'])} s",
        f"{sec(f['wall_time_s'])}, {f['engine_runs']} engine runs; largest error "
        f"{num(f['max_abs_error_percent'])} %; 95 % intervals: {held} of {len(d['parameters'])} hold the truth",
        name, d["command"])]}


def sweep_steady_rows(d: dict) -> dict[str, list[Row]]:
    s, w, p = d["steady_variants_per_s"], d["steady_ms_per_variant_per_worker"], d["phases_ms"]
    o = d["over_engine"]
    return {"sweeps": [Row(
        f"`mtbmj sweep S12 --engine fast` steady state: {d['variants']} less {d['small']} variants, "
        f"{plural(d['workers'], 'worker')}, {len(d['rounds'])} interleaved rounds",
        f"≥ {d['target_variants_per_s']} variants/s",
        f"{s['median']:.0f} variants/s ({s['min']:.0f}–{s['max']:.0f}); a variant {num(w['median'])} ms per worker, "
        f"{ratio(o['median'], 2)} the engine's {num(p['engine_ms']['median'])} ms (prepare "
        f"{num(p['prepare_ms']['median'])}, finish {num(p['finish_ms']['median'])} ms)",
        "sweep_steady.json", d["command"])]
        + ([Row("the same, CPU time per variant, every process of the command (perf stat task-clock)",
                f"≤ {num(d['cpu_ms_per_variant_at_target'])} ms (the target's rate on {d['environment']['cpus']} cores)",
                f"{num(d['steady_cpu_ms_per_variant']['median'])} ms ({num(d['steady_cpu_ms_per_variant']['min'])}–"
                f"{num(d['steady_cpu_ms_per_variant']['max'])} ms)", "sweep_steady.json", d["command"])]
           if "steady_cpu_ms_per_variant" in d else [])}


def dropfit_ratio_rows(d: dict) -> dict[str, list[Row]]:
    r, pr = d["mujoco_over_fast_per_run"], d["per_run_ms"]
    lr, lp = d["fit_loop_mujoco_over_fast_per_run"], d["fit_loop_per_run_ms"]
    return {"fits": [Row(
        f"drop fit of 6 S12 parameters, MuJoCo / fast engine, wall time per engine run, {len(d['rounds'])} "
        "interleaved rounds", f"≤ {tgt(d['target'])}×",
        f"{ratio(r['median'], 2)} ({spread(r['min'], r['max'], 2)}): {num(pr['mujoco']['median'])} vs "
        f"{num(pr['fast']['median'])} ms; without the closing engine-error run {ratio(lr['median'], 2)} "
        f"({spread(lr['min'], lr['max'], 2)}): {num(lp['mujoco']['median'])} vs {num(lp['fast']['median'])} ms",
        "dropfit_ratio.json", d["command"])]
        + ([Row(f"floor of any MuJoCo fit (its {d['mujoco_floor_steps']} steps a run, bare with the compiled "
                f"callback, shared perfectly over {d['workers']['mujoco']} threads) / the fast fit's whole cost "
                "per run", "report",
                f"{ratio(d['floor_over_fast_per_run']['median'], 2)} ({spread(d['floor_over_fast_per_run']['min'], d['floor_over_fast_per_run']['max'], 2)}): "
                f"{num(d['mujoco_floor_per_run_ms']['median'])} vs {num(pr['fast']['median'])} ms",
                "dropfit_ratio.json", d["command"])] if "floor_over_fast_per_run" in d else [])}


def interval_coverage_rows(d: dict) -> dict[str, list[Row]]:
    name, cmd = "interval_coverage.json", py("interval_coverage.py", "--records", str(d["records"]))
    lc = d["logger_clock_fit"]
    err = max(abs(v) for v in lc["error_percent"].values())
    touch = max(abs(r["touch_found_error_ms"]) for r in d["rows"])
    return {"fits": [
        Row(f"drop fit on a logger-clock record ({len(lc['truth'])} parameters, ODE data, MuJoCo fit)",
            "within 2 % in ≤ 30 s", f"{num(err)} % in {sec(lc['wall_s']['median'])} "
            f"({spread(lc['wall_s']['min'], lc['wall_s']['max'], 2, ' s')})", name, cmd),
        Row(f"coverage of the drop fit's 95 % intervals, {d['records']} records, {d['intervals']} intervals",
            "≥ 85 %", f"{pct(d['coverage_95'])} (white-noise intervals {pct(d['white_noise_coverage_95'])}); "
            f"errors ≤ {num(d['max_abs_error_percent'])} %; time zero within {num(touch)} ms", name, cmd)]}


def model_check_rows(d: dict) -> dict[str, list[Row]]:
    rows = d["rows"]
    right = sum(r["case"] == "right" for r in rows)
    wrong = [c for c in d["summary"]["detection_rate"]]
    per_wrong = sum(r["case"] == wrong[0] for r in rows)
    cmd = py("model_check.py", "--records", str(right), "--wrong", str(per_wrong))
    s = d["summary"]
    detected = ", ".join(f"{c.replace('_', ' ')} {pct(v)}" for c, v in s["detection_rate"].items())
    return {"fits": [
        Row(f"model check on {right} right models (S1, ODE engine): false alarms", "≤ 5 %",
            f"{pct(s['false_alarm_rate'])}; median residual {num(s['right_model_ratio_median'], 3)} × the noise floor",
            "model_check.json", cmd),
        Row("the same fits: coverage of the 95 % intervals", "90–99 %", pct(s["interval_coverage"]),
            "model_check.json", cmd),
        Row(f"model check on wrong models ({per_wrong} records each): detections", "≥ 95 %", detected,
            "model_check.json", cmd)]}


def rolling_rows(d: dict) -> dict[str, list[Row]]:
    cmd = py("rolling.py", "--repeat", str(len(d["engine_wall_s_all"])),
             "--python-repeat", str(len(d["python"]["engine_wall_s_all"])))
    return {"rolling": [Row(
        f"real-time factor, {tgt(d['simulated_s'])} s over the {d['scenario']} at {tgt(d['speed_m_per_s'])} m/s, "
        f"{d['config']}, one core, best of {len(d['engine_wall_s_all'])}", f"≥ {tgt(d['target_real_time_factor'])}×",
        f"{ratio(d['real_time_factor'])} (compiled callback); Python callback {ratio(d['python']['real_time_factor'])}",
        "rolling.json", cmd)]}


def rolling_refresh_rows(d: dict) -> dict[str, list[Row]]:
    s = d["summary"]
    cmd = py("rolling_refresh.py", "--repeat", str(s["repeat"]), "--seconds", tgt(s["seconds"]))
    w, rtf, root = s["wall_now_over_old"], s["real_time_factor_median"], s["root_fork_difference_mm"]
    return {"rolling": [
        Row("wall time, contact patches refreshed every 0.05 ms / 0.25 mm (default) / every 1 ms / 5 mm, "
            "compiled callback, one core", "report",
            f"{ratio(w['median'], 2)} (rounds {spread(w['min'], w['max'], 2)}); real time "
            f"{ratio(rtf['now'], 2)} against {ratio(rtf['old'], 2)}", "rolling_refresh.json", cmd),
        Row("fork vs the rolling ODE reference on the 50 mm root at 4 m/s, the same two refresh settings",
            "report", f"{mm(root['now'])} against {mm(root['old'])}", "rolling_refresh.json", cmd)]}


def rolling_crosscheck_rows(d: dict) -> dict[str, list[Row]]:
    s = d["summary"]
    if "speeds" in s:  # the summary names them (rows are the cross-check's to_dict)
        speeds = [float(v) for v in s["speeds"].split(",")]
    else:  # results written before: each row had its speed
        speeds = sorted({r["speed_m_per_s"] for r in d["rows"]}) if all("speed_m_per_s" in r for r in d["rows"]) else []
    cmd = py("rolling_crosscheck.py", "--duration", tgt(s["duration_s"]),
             *(["--speeds", ",".join(tgt(v) for v in speeds)] if speeds else []))
    return {"rolling": [Row(
        f"MuJoCo (`mtbmj roll`, default settings) vs the rolling ODE reference, every fixed terrain, "
        f"{tgt(s['duration_s'])} s runs", "fork ≤ 0.02 mm, axle force peaks ≤ 1 %",
        f"{s['passed']} of {s['runs']} runs within; worst fork {mm(s['worst_fork_mm'])}, worst peak "
        f"{pct(s['worst_force_peak_relative'])}", "rolling_crosscheck.json", cmd)]}


def bike_crosscheck_rows(d: dict) -> dict[str, list[Row]]:
    s = d["summary"]
    cmd = py("bike_crosscheck.py", "--duration", tgt(s["duration_s"]), "--speeds", s["speeds"])
    return {"bike": [Row(
        f"the SST bike on MuJoCo (`mtbmj bike`, default settings) vs the bike's ODE reference, every fixed terrain "
        f"at {s['speeds'].replace(',', ' and ')} m/s, {tgt(s['duration_s'])} s runs",
        "travel and stroke ≤ 0.1 mm, tire-load peaks ≤ 1 %",
        f"{s['passed']} of {s['runs']} runs within; worst {mm(s['worst_travel_mm'], 4)} "
        f"({s['worst_scenario']} at {tgt(s['worst_speed_m_per_s'])} m/s), worst peak "
        f"{pct(s['worst_tire_peak_relative'])}"
        + (f", worst series {pct(s['worst_tire_series_relative'])} of the peak" if "worst_tire_series_relative" in s
           else "") + f"; {s['refined_runs']} of them stepped finer near a stop",
        "bike_crosscheck.json", cmd)]}


def bike_speed_rows(d: dict) -> dict[str, list[Row]]:
    r = d["real_time_factors"]

    def cell(key, digits=3):
        return f"{ratio(r[key]['median'], digits)} ({spread(r[key]['min'], r[key]['max'], digits, '×')})"

    return {"bike": [
        Row(f"the SST bike on the rock garden at {tgt(d['speed_m_per_s'])} m/s, one core, compiled callback, "
            f"{ms(d['timestep_s'], 3)} RK4 steps", "≥ 20× real time",
            f"{cell('bike')} real time; MuJoCo alone on the same model {cell('mujoco')}; bike / MuJoCo alone "
            f"{num(r['over_mujoco']['median'], 3)} (pairs {spread(r['over_mujoco']['min'], r['over_mujoco']['max'], 3)})",
            "bike_speed.json", d["command"])]}


def bike_pedal_speed_rows(d: dict) -> dict[str, list[Row]]:
    r, s = d["real_time_factors"], d["settings"]
    cmd = py("bike_pedal_speed.py", "--repeats", str(s["repeats"]), "--duration", tgt(s["duration_s"]),
             "--python-duration", tgt(s["python_duration_s"]))

    def cell(key, digits=3, unit="×"):
        return f"{num(r[key]['median'], digits)}{unit} ({spread(r[key]['min'], r[key]['max'], digits, unit)})"

    return {"bike": [
        Row(f"the SST bike pedalling ({tgt(s['cadence_rpm'])} rpm, {tgt(s['power_W'])} W, {s['gear']}) up a 14 % "
            f"climb, one core, compiled callback, against the rider's drive at the gear's speed", "report",
            f"standing {cell('standing')}, seated {cell('seated')} real time; rider drive {cell('drive')}; "
            f"standing / drive {cell('standing_over_drive', 3, '')}; the Python callback standing "
            f"{cell('python_standing')}", "bike_pedal_speed.json", cmd)]}


def advise_speed_rows(d: dict) -> dict[str, list[Row]]:
    a, r, c, u = d["advise_s"], d["ratio"], d["reconstruct_s"], d["advise_cpu_s"]
    return {"bike": [
        Row(f"`mtbmj advise` on the shipped ride ({num(d['ride_seconds'], 3)} s, {d['repeats'][0]['candidates']} candidates, "
            f"{d['workers']} processes), wall time per 100 s of ride", f"≤ {tgt(d['target_s_per_100_s'])} s",
            f"{num(d['advise_s_per_100_s_of_ride'], 3)} s per 100 s; {sec(a['median'])} ({spread(a['min'], a['max'], 3, ' s')}) "
            f"in all, of which the reconstruction {sec(c['median'])}; advise / one bike run "
            f"{num(r['median'], 3)} ({spread(r['min'], r['max'], 3)}); CPU {sec(u['median'], 3)} (with its workers)"
            + (f", {sec(d['prepare_cpu_s']['median'], 3)} before any run" if "prepare_cpu_s" in d else ""),
            "advise_speed.json", d["command"])]}


def bike_step_levers_rows(d: dict) -> dict[str, list[Row]]:
    u, o, same = d["us_per_step"], d["over_none"], d["identical_to_none"]
    names = {"timer": "timers off", "passive": "passive skipped", "camera_light": "no camera, light", "all": "all"}
    alike = "bit-identical" if all(same.values()) else "NOT identical: " + ", ".join(k for k, v in same.items() if not v)
    return {"bike": [
        Row(f"the bike's step on `mtbmj advise`'s run over the shipped ride ({d['steps']} steps of "
            f"{ms(d['timestep_s'], 3)}, compiled callback, one core), CPU per step, each lever against none", "report",
            ", ".join(f"{names[k]} {num(o[k]['median'], 3)}" for k in ("timer", "passive", "camera_light"))
            + f", all {num(o['all']['median'], 3)} ({spread(o['all']['min'], o['all']['max'], 3)}) of none's "
            f"{num(u['none']['median'], 3)} us; {alike}", "bike_step_levers.json", d["command"])]}


def calibrate_speed_rows(d: dict) -> dict[str, list[Row]]:
    r, c, p = d["ratio"], d["calibrate_cpu_s"], d["pass_cpu_s"]
    return {"bike": [
        Row(f"the calibration of `mtbmj advise` on the shipped ride ({num(d['ride_seconds'], 3)} s), CPU time in "
            f"passes of both ends' laws over the ride", "report",
            f"{num(r['median'], 3)} passes ({spread(r['min'], r['max'], 3)}); {sec(c['median'])} "
            f"({spread(c['min'], c['max'], 3, ' s')}) of CPU, one pass {sec(p['median'])}", "calibrate_speed.json",
            d["command"])]}


def _advise_refusal(why: str) -> str:
    """A refusal of ``mtbmj advise`` in a few words (the results file holds it whole)."""
    why = why.split(": ", 1)[-1]
    if "fails its own check (" in why:
        return "refused: its reconstruction's check (" + why.split("fails its own check (", 1)[1].split(";")[0] + ")"
    if "does not beat a delayed copy" in why:
        return "refused: its reconstruction's rear does not beat a delayed copy of the fork"
    return "refused: " + why[:120]


def advise_rides_rows(d: dict) -> dict[str, list[Row]]:
    rows, name = [], "advise_rides.json"
    target = "intervals overlap; one answer for all"
    for r in d["rides"]:
        figure = f"{r['ride']}" + (f" (v{r['version']}, {num(r['seconds'], 3)} s)" if "version" in r else "")
        if "calibration" in r:
            cal = "; ".join(f"{s['key'].split(':')[0].split('.')[0]} {num(s['calibrated'], 3)} {s['unit']} "
                            f"({spread(s['calibrated_low'], s['calibrated_high'], 3)}; x{num(s['scale'], 3)} of the file's "
                            f"{num(s['file'], 3)})" for s in r["calibration"]["springs"].values())
            other = r["calibration"].get("or")
            if other:
                cal += (f"; or both x{num(other['common_scale'], 3)} with {num(other['load_forward_N'], 3)} N carried "
                        f"forward ({num(other['descent_deg'], 2)} deg of descent)")
        else:
            cal = "calibration " + _advise_refusal(r.get("calibration_refused", r.get("unread", "")))
        if "advice" in r:
            a = r["advice"]
            said = a["answer"] if a["recommendation"] is None else (
                f"{a['recommendation']['setting']['adjuster']} {num(a['recommendation']['setting']['from'], 3)} -> "
                f"{num(a['recommendation']['setting']['to'], 3)}")
        else:
            said = _advise_refusal(r.get("advice_refused", ""))
        rows.append(Row(f"{figure}: the springs calibrated, 95 %", target, cal, name, d["command"]))
        rows.append(Row(f"{figure}: the advice", target, said[:200], name, d["command"]))
    for end, a in d["agreement"].items():
        pairs = ", ".join(f"{k.replace('.SST', '').replace(' ', '/')} {'yes' if v else 'no'}" for k, v in a["pairs"].items())
        common = "none" if a["common"] is None else f"x{num(a['common'][0], 3)}–x{num(a['common'][1], 3)}"
        rows.append(Row(f"the {len(a['rides'])} rides' {end} spring scales: the range every interval holds", target,
                        f"{common}; pairs overlapping: {pairs}", name, d["command"]))
    pc = d.get("pooled_calibration")
    if pc and "springs" in pc:
        cal = "; ".join(f"{s['key'].split(':')[0].split('.')[0]} {num(s['calibrated'], 3)} {s['unit']} "
                        f"({spread(s['calibrated_low'], s['calibrated_high'], 3)}; x{num(s['scale'], 3)})"
                        for s in pc["springs"].values())
        if pc.get("or"):
            cal += f"; or both x{num(pc['or']['common_scale'], 3)} with {num(pc['or']['load_forward_N'], 3)} N forward"
        rows.append(Row(f"the {len(pc['ride_names'])} rides pooled ({', '.join(r.replace('.SST', '') for r in pc['ride_names'])}): "
                        f"one bike's springs calibrated, 95 %", target, cal, name, d["command"]))
    elif pc:
        rows.append(Row("the rides pooled: one bike's springs calibrated", target,
                        "calibration " + _advise_refusal(pc["refused"]), name, d["command"]))
    commons = {r["ride"]: r["calibration"]["or"]["common_scale"] for r in d["rides"]
               if (r.get("calibration") or {}).get("or")}
    if len(commons) > 1:
        lo, hi = min(commons.values()), max(commons.values())
        rows.append(Row(f"the {len(commons)} rides' springs read the other way (one scale for both, the rest a load "
                        f"carried forward)", target, f"x{num(lo, 3)}–x{num(hi, 3)} ({num(100 * (hi / lo - 1), 2)} % apart)",
                        name, d["command"]))
    return {"advise": rows}


def reconstruct_rides_rows(d: dict) -> dict[str, list[Row]]:
    rows = []
    margin = d["beat_margin_percent"]
    for r in d["rides"]:
        name = f"{r['folder']}/{r['ride']}" + (f" (v{r['version']}, {num(r['seconds'], 3)} s)" if "version" in r else "")
        target = f"rear ≥ {num(margin, 2)} % below the better baseline"
        if "refused" in r:
            why = r["refused"].split(": ", 1)[-1]
            short = "no speed: no window gives one" if "do not align at any lag" in why else why[:150]
            rows.append(Row(name, target, f"refused: {short}", "reconstruct_rides.json", d["command"]))
            continue
        p, c = r["speed_profile"], r["checks"]
        sd = r["speed_sd_median_m_per_s"]
        better = "delayed fork" if c["baseline_delayed_fork_rms_mm"] <= c["baseline_rear_mean_rms_mm"] else "mean"
        if c["samples_checked_percent"] > 0:
            checked = (f"; rear {mm(c['rear_predicted_rms_mm'], 3)}"
                       + (f" (corr {num(r['rear_correlation'], 2)})" if r.get("rear_correlation") is not None else "")
                       + f", delayed fork {num(c['baseline_delayed_fork_rms_mm'], 3)}, mean "
                       f"{num(c['baseline_rear_mean_rms_mm'], 3)}; {num(c['samples_checked_percent'], 2)} % checked; ")
        else:  # its whole bike diverged before any sample it could check: no figure to give
            checked = "; no sample checked (nothing before the divergence lies where a window gave a speed); "
        rows.append(Row(name, target, f"{num(p['median_m_per_s'], 3)} m/s ({num(p['min_m_per_s'], 3)}–"
                        f"{num(p['max_m_per_s'], 3)}), {p['windows_accepted']}/{p['windows_accepted'] + p['windows_rejected']} "
                        f"windows" + (f", sd {num(sd, 2)}" if sd is not None else "") + checked
                        + ("**passes**" if c["passes"] else (
                            f"**fails** (the whole bike diverged at {num(r['whole_bike']['diverged_s'], 3)} s)"
                            if (r.get("whole_bike") or {}).get("diverged_s") is not None
                            else f"**fails** (below the {better}, not by the margin)"
                            if c["rear_predicted_rms_mm"] < min(c["baseline_delayed_fork_rms_mm"],
                                                                c["baseline_rear_mean_rms_mm"])
                            else f"**fails** (not below the {better})")),
                        "reconstruct_rides.json", d["command"]))
        bound = c.get("bound_fork_filter_rms_mm")  # None: measured before the bound, or too few samples checked
        if bound is not None:
            rows.append(Row(f"{name}: what the fork's record holds about the rear, not judged", "report",
                            f"a linear filter from the fork, fitted on the rear: {mm(bound, 3)} (mark "
                            f"{mm(c['pass_mark_rms_mm'], 3)})"
                            + ("; the rear moves with the fork at once" if c.get("front_holds_too_little") else ""),
                            "reconstruct_rides.json", d["command"]))
        if r.get("beyond_trail"):  # the ground found past what the bike could climb (reconstruct_envelope)
            rows.append(Row(f"{name}: ground no trail has, not checked", "report", "; ".join(
                f"{num(b['start_s'], 3)}–{num(b['end_s'], 3)} s ({num(b['start_m'], 3)}–{num(b['end_m'], 3)} m): "
                f"{num(b['rise_m'], 2)} m up, at most {num(b['allowed_m'], 2)}" for b in r["beyond_trail"]),
                "reconstruct_rides.json", d["command"]))
        fit = r.get("at_once_fit")
        if fit and fit.get("rear_predicted_rms_mm") is not None and c.get("fork_at_once_rms_mm") is not None:
            rows.append(Row(f"{name}: beside the check, not judged", "report",
                            f"the fork at once {mm(c['fork_at_once_rms_mm'], 3)}; the rear with a share "
                            f"{num(fit['share'], 2)} met at once (fitted on the rear) {mm(fit['rear_predicted_rms_mm'], 3)}",
                            "reconstruct_rides.json", d["command"]))
    return {"reconstruct": rows}


def _there(terrain: dict, record: dict) -> str:
    """The terrain found and the ride's own record at a crash, in a few words."""
    ter = (f"ground {num(terrain['height_m'], 3)} m" + (
        f", steepest {num(terrain['slope_max_deg'], 2)} deg, {num(terrain['step_m'], 2)} m in 0.2 m"
        if terrain.get("slope_max_deg") is not None else ""))
    rec = ("; its record: fork " + (f"{num(record['fork_max_mm'], 3)}" if record.get("fork_max_mm") is not None
                                                 else "none") + ", rear "
           + (f"{num(record['rear_max_mm'], 3)} mm" if record.get("rear_max_mm") is not None else "none")
           + f", {num(record['record_runs_on_s'], 3)} s more")
    return ter + rec


def ride_own_rows(d: dict) -> dict[str, list[Row]]:
    rows, name, target = [], "ride_own.json", "no crash (the rider came home)"
    for r in d["rides"]:
        figure = f"{r['folder']}/{r['ride']}" + (f" ({num(r['seconds'], 3)} s)" if "seconds" in r else "")
        if "refused" in r:
            rows.append(Row(f"{figure}: reconstruct", target, "refused: " + r["refused"].split(": ", 1)[-1][:150],
                            name, d["command"]))
            continue
        there = None
        if "bike_refused" in r:
            said = "refused: " + r["bike_refused"][:150]
        elif r.get("crash"):
            a = r["at"]
            said = (f"**{r['crash']['kind']}** at {num(a['ride_s'], 3)} s, {num(a['ride_m'], 3)} m, "
                    f"{num(a['speed_m_per_s'], 2)} m/s ({a['speed_from']})"
                    + (f"; ground beyond trail within {num(d['near_s'], 1)} s" if a["beyond_trail"] else ""))
            there = Row(f"{figure}: there (the commands)", "report", _there(a["terrain"], a["record"]), name, d["command"])
        else:
            said = "rides it all"
        rows.append(Row(f"{figure}: `mtbmj reconstruct`, then `mtbmj bike`", target, said, name, d["command"]))
        rows += [there] if there else []
        for a in r.get("advise", []):
            how = "calibrated" if a["calibrated"] else "the file's springs"
            note = " (refused by its check; ridden)" if a.get("ridden_anyway") else ""
            if "refused" in a:
                said = "refused: " + a["refused"].split(": ", 1)[-1][:150]
            elif a.get("crash"):
                kind = a["crash"].split(": ", 1)[-1].split(" at ")[0]
                said = (f"**{kind}** at {num(a['ride_s'], 3)} s, {num(a['ride_m'], 3)} m{note}; "
                        + _there(a["terrain"], a["record"]))
            else:
                said = "rides it all" + note
            rows.append(Row(f"{figure}: as advise, {how}", target, said[:200], name, d["command"]))
    return {"ride_own": rows}


def suite_time_rows(d: dict) -> dict[str, list[Row]]:
    rows = []
    for name, what, target in (("suite", "the test suite (`-m \"not slow\"`), two processes", f"≤ {tgt(d['target_suite_minutes'])} min"),
                               ("slow", "the long physics checks (`-m slow`), two processes", "report")):
        r = d["runs"].get(name)
        if r is None:
            continue
        rows.append(Row(f"wall time of {what}", target, f"{num(r['wall_s'] / 60.0, 2)} min, exit {r['exit']}: "
                        f"{r['summary'].replace('|', '/')}", "suite_time.json", d["command"]))
    return {"suite": rows}


SOURCES = [
    ("accuracy_steps.json", accuracy_steps_rows),
    ("accuracy_envelope.json", accuracy_envelope_rows),
    ("speed_scales.json", speed_scales_rows),
    ("speed.json", speed_rows),
    ("compiled.json", compiled_rows),
    ("native_loop.json", native_loop_rows),
    ("sweep_200.json", lambda d: sweep_rows(d, "sweep_200.json")),
    ("sweep_1000_w2.json", lambda d: sweep_rows(d, "sweep_1000_w2.json")),
    ("sweep_200_w1.json", lambda d: sweep_rows(d, "sweep_200_w1.json")),
    ("sweep_200_w1t2.json", lambda d: sweep_rows(d, "sweep_200_w1t2.json")),
    ("sweep_steady.json", sweep_steady_rows),
    ("dropfit.json", lambda d: dropfit_rows(d, "dropfit.json")),
    ("dropfit_fast.json", lambda d: dropfit_rows(d, "dropfit_fast.json")),
    ("dropfit_ratio.json", dropfit_ratio_rows),
    ("interval_coverage.json", interval_coverage_rows),
    ("model_check.json", model_check_rows),
    ("rolling.json", rolling_rows),
    ("rolling_refresh.json", rolling_refresh_rows),
    ("rolling_crosscheck.json", rolling_crosscheck_rows),
    ("bike_crosscheck.json", bike_crosscheck_rows),
    ("bike_speed.json", bike_speed_rows),
    ("bike_pedal_speed.json", bike_pedal_speed_rows),
    ("advise_speed.json", advise_speed_rows),
    ("bike_step_levers.json", bike_step_levers_rows),
    ("calibrate_speed.json", calibrate_speed_rows),
    ("reconstruct_rides.json", reconstruct_rides_rows),
    ("advise_rides.json", advise_rides_rows),
    ("ride_own.json", ride_own_rows),
    ("suite_time.json", suite_time_rows),
]

# --- the page's words ----------------------------------------------------------------------------

INTRO = """\
# Measured figures

<!-- Generated by benchmarks/report.py from benchmarks/results/*.json: edit those, not this page. -->

What the scripts in `benchmarks/` measure: how close the engines come to the ODE reference, how
fast a drop, a sweep, a fit and a rolling run are, and what start-up and memory cost. Each script
writes its numbers where its `--out` says, by default to a scratch file outside the repository
(`mtbmj-benchmarks/` in the system's temporary folder; the script prints the path). This page is
written from the files in `benchmarks/results/` by `python benchmarks/report.py`.

A speed figure is a ratio against a baseline that the same script runs on the same machine: 2
cores, shared with other work. Where the script interleaves the measured runs with the baseline's
(measured, baseline, measured, ...) so that both see the same load, the row gives the ratio of the
medians and, in brackets, the spread (smallest to largest) of the pairwise or per-round ratios; a
row timed as the best of N runs, or as one run, says so. A ratio is only as steady as its spread.
"measured on" is the date of the run (with its commit, for runs that record one), the MuJoCo
version and the machine's 1-minute load average when the script wrote its results (above 2, the
two cores were shared): a row describes the code as it was on that date. Each command runs from
the repository root and, through its `--out`, rewrites the results file the row is read from.
"""

SECTIONS = [
    ("accuracy", "Accuracy against the ODE reference", """\
The difference is the largest absolute difference of sled, fork and tire displacement between the
engine and the ODE reference (scipy Radau, rtol 1e-8) over the whole run. The default settings are
RK4 at 1 ms, with the step refined near the stops, at touchdown and in fast sliding. The random
forks come from `mtbmj.drop.envelope`: plausible forks, some landing hard enough to bottom out or
strike the rim."""),
    ("drop", "Speed of a drop", """\
The engine runs the compiled laws by default (`controllers/compiled.py`; the Python laws give the
same results and stay as the specification and the fallback when numba is missing), with one
exception that changes only the speed: a run shorter than 10 000 steps in a process that has not
loaded numba yet takes the Python laws, because loading numba and the cached laws (about a second)
costs more than that run (`controllers/native.py`). Trajectories and forces are the same bit for
bit; the logged, filtered signals agree within 1e-9 mm. Sweeps, fits and studies load numba up
front. A Python process that calls `run_drop` again and again (a notebook's loop) gets there on
its own: its first drop starts a daemon thread that loads numba and the cached laws while that
drop runs on the Python laws, and from the third drop on every drop runs on the compiled ones (a
drop that finds the load still under way waits for it). A command (`mtbmj drop`) makes one drop
and never starts the thread; `MTBMJ_BACKGROUND_LOAD=0` turns it off. Without numba installed every
command still runs, and says so once on stderr."""),
    ("startup", "Start-up and memory", """\
Whole processes are timed against `python -c "import numpy, mujoco"`, the floor any command pays.
`mtbmj --help` imports no engine; the drop path imports neither `scipy.signal` nor, for a run this
short, numba; `--engine fast` needs numba."""),
    ("sweeps", "Sweeps and the study", """\
The bare-scene rollout is `mujoco.rollout` of the shipped scene with no fork law, from each
variant's tire touch, for the same number of steps: the floor a sweep's stepping cannot beat.
The batched runner steps more than that floor (refined steps at touchdown, lift-off and near the
stops, and the fork callback), which the second ratio separates from its own bookkeeping.

`benchmarks/sweep.py` calls `run_sweep` in its own process after its phase costs have loaded numba
and the compiled callback there, so the workers it forks start with them loaded. A fresh `mtbmj
sweep` pays that load in each worker instead, in parallel: about 0.8 s, most of it numba's import
and its CPU target (which imports `scipy.linalg`), then the cached callback. The warmed row starts
the workers, and has each make a short drop, before the timing; it comes out the same as the whole
sweep within the rounds' spread, so the whole-sweep rows hold no start-up of that kind. The command
row does: a process of its own, its imports, the sampling, the pool and that load, all of which
the built-in scene, stepped in this process on a scene built before the timing, never pays.
Rounds of the same code spread by about 20 % either way on this machine, whose speed changes from
minute to minute: compare medians, and look at the spread before reading a difference."""),
    ("fits", "Fits", """\
Drop fits run on synthetic records made by a different engine or model than the one fitted, with
logger noise, the 400 Hz filter and 16-bit quantisation; the truth is known, so the errors and the
coverage of the 95 % intervals can be counted.

The floor row bounds the fit's MuJoCo form from below: the MuJoCo steps of one run alone, with the
compiled fork callback and no step rule, fit or record around them, shared perfectly over the
fit's threads. No MuJoCo fit can cost less per run than that. While that floor is more than 3
times the fast fit's whole cost per run, the MuJoCo fit cannot come within 3 times the fast fit,
whatever its own code does."""),
    ("rolling", "Rolling", """\
The rolling engine is checked against the rolling ODE reference by the test suite as well:
`tests/test_rolling_reference.py` runs every fixed terrain of the library at 2 or 5 m/s, and
`tests/test_rolling_washboard.py` the 90° washboard against a model written in the test file.
`benchmarks/rolling_crosscheck.py` runs every fixed terrain at both speeds; its results file
`benchmarks/results/rolling_crosscheck.json` gives this table a row when the file is there."""),
    ("bike", "The whole bike", """\
The bike steps at 0.5 ms with RK4 where no end stop or rim is within reach, and stretches that come
within reach are stepped again at the fine step of the stops (`mtbmj/bike/stepping.py`). The test
suite runs every fixed terrain at 4 and 6 m/s against the bike's ODE reference for as long as both
wheels need to cross the feature (`tests/test_bike_reference.py`); `benchmarks/bike_crosscheck.py`
runs the same terrains for a fixed time with the reference at its default tolerance. The speed is
real time on one core (simulated seconds per wall second), interleaved with MuJoCo stepping the
same model with no callback."""),
    ("advise", "Advice on the shared rides (issue 52)", """\
`mtbmj advise RIDE --bike sst` on each shared version-3 ride of the SST bike (`data/sst`), as the command runs
it: the bike's springs calibrated on the ride first (`mtbmj/ride/calibrate.py`: each end's spring scale
that makes its mean force over the ride the static load it carries; its 95 % interval from the ride's
5 s segments resampled and the rider's mean place fore and aft, 30 mm, in quadrature), then the
advice or its refusal. The calibrated values are given in the bike file's units with their interval
and the scale on the file's value; a ride whose advice is refused still has its calibration (it needs
no simulation). The last rows say, per end, which values every ride's interval holds (none: the
rides' calibrations do not agree) and which pairs of rides overlap. Each calibration also reads the
same ride the other way ("or"): both springs at one scale from the sum of the ends' balances, and the
rest of the front's a load carried forward (a descent, braking, the rider's stance), which the travel
alone cannot tell from a fork softer and a shock stiffer than the file (`mtbmj/ride/calibrate.py`); the
last row gives the range of that one scale over the rides. Nothing is set to pass."""),
    ("suite", "The test suite", """\
The suite (`-m "not slow"`) and the long physics checks (`-m slow`), one after the other, from the
repository root, as the README's commands run them (CI runs both in one command, the README's first).
A wall time on two cores shared with other work (the load average is in the results file) is longer
than on a quiet machine."""),
    ("reconstruct", "Rides reconstructed (issue 51)", """\
Per ride: the speed's median and range over the accepted windows, accepted / all windows and the
median of their standard errors (m/s); the rear predicted's RMS error and the two baselines' (mm);
the share of the ride checked; the verdict. "no window gives one": every window rejected by the
rules below (the command's line counts the reasons; the results file holds it whole).
`mtbmj reconstruct RIDE --bike sst` on every shared ride (the shared telemetry beside the clone: `data/sst`, version 3, and
`data/sst_v2`, version 2 at 5 kHz with placeholder amplitudes; 00083-00087 are seat
slams, 00088-00091 pedalling, 00092-00101 trail sections). The speed is found per 5 s window from
the lag between the two ends' grounds (or travels); a window gives none at the search's edge, with
a second peak within 0.9 of the best, a best correlation below 0.3, a peak whose lobe reaches the
search's edge, more than one of its four parts finding its own best lag outside the window's best
peak, a speed uncertain by more than 10 % (the standard error of those parts' lags), or where an end
stands still (each window from the grounds, else from the travels). The rear predicted from the
fork's record through the bike file's whole bike (frame pitch, the rider on his limbs) is compared with
two naive baselines on the same samples: the fork's record delayed by wheelbase / speed(t) with a
least-squares scale and offset (fitted on those very samples), and the rear's mean; it passes only
40 % below the better. A ride whose whole bike diverges fails, its line saying where (past it nothing
is checked). `mtbmj advise` refuses a ride that fails."""),
    ("ride_own", "The bike rides its own reconstruction (issue 51)", """\
Per shared ride that gives a speed (`benchmarks/results/reconstruct_rides.json`): as a user would run it,
`mtbmj reconstruct RIDE --bike sst --out DIR`, then `mtbmj bike sst DIR/terrain.csv --speed-profile DIR/speed.csv`
at the recorded setting (the bike file as it is); and as `mtbmj advise` rides its recorded setting
(`mtbmj.ride.advise.prepare` and `simulate`: the reconstruction without the spectral share met at once), on
the file's springs and calibrated on the ride. Where advise refuses the ride (its reconstruction fails its
own check) the same steps are ridden without the check. At a crash: the ride's time and distance of the front
axle, the speed there and whether a window gave it, the ground found within 2 m before it (height, the steepest
slope, the largest rise or fall over 0.2 m) and the ride's own record within 1 s (both ends' largest travel,
and how long the record runs on past it: every one of these rides came home). Nothing is set to pass."""),
]


def collect() -> dict[str, list[tuple[Row, str]]]:
    tables: dict[str, list[tuple[Row, str]]] = {key: [] for key, _, _ in SECTIONS}
    for name, build in SOURCES:
        data = load(name)
        if data is None:
            continue
        when = measured_on(name)
        for subject, rows in build(data).items():
            tables[subject].extend((replace(row, command=refreshing(row.command, row.json_name)), when)
                                   for row in rows)
    return tables


def render() -> str:
    out = [INTRO]
    tables = collect()
    for key, title, note in SECTIONS:
        rows = tables[key]
        if not rows:
            continue
        out += [f"\n## {title}\n", "| figure | target | measured | measured on | command |", "|---|---|---|---|---|"]
        for row, when in rows:
            out.append(f"| {row.figure} | {row.target} | {row.measured} | {when} | `{row.command}` |")
        out += ["", note]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if the page differs from what it would write")
    ap.add_argument("--out", type=Path, default=PAGE, metavar="PATH",
                    help="the page to write (or, with --check, to compare); default docs/measured.md: the page "
                         "follows from benchmarks/results/*.json alone, nothing is measured")
    args = ap.parse_args(argv)
    text = render()
    page = args.out.resolve()
    shown = page.relative_to(REPO) if page.is_relative_to(REPO) else page
    if args.check:
        same = page.is_file() and page.read_text() == text
        print(f"{shown} is {'up to date' if same else 'out of date: run python benchmarks/report.py'}")
        return 0 if same else 1
    page.parent.mkdir(parents=True, exist_ok=True)
    page.write_text(text)
    print(f"wrote {shown}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

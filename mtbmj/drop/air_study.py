"""The air-fork study: the paper's drop for an air fork set the way riders set it (0-3 volume
spacers, two air pressures, two tire pressures) on both engines, and the spring curves in the
style of the paper's Fig. 3."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Mapping

from mtbmj import compose, output
from mtbmj.config import Config
from mtbmj.drop.chain import resolve
from mtbmj.drop.study import group_figure, png_bytes, run_job, table_markdown
from mtbmj.drop.crosscheck import from_results
from mtbmj.workers import process_pool

SPACERS = (0, 1, 2, 3)
PRESSURES_PSI = (75.0, 95.0)
TIRE_PRESSURES_PSI = (18.0, 24.0)


def variants(base: Config) -> dict[str, tuple[str, dict]]:
    """name -> (group, overrides) of every run of the study."""
    psi = base["fork.spring.air_pressure_psi"]
    out: dict[str, tuple[str, dict]] = {}
    for n in SPACERS:
        out[f"{n} spacer{'' if n == 1 else 's'}"] = ("spacers", {"fork.spring.tokens": float(n)})
    for p in PRESSURES_PSI:
        out[f"{p:g} psi"] = ("pressure", {"fork.spring.air_pressure_psi": p})
    for p in TIRE_PRESSURES_PSI:
        out[f"tire {p:g} psi"] = ("tire", {"tire.pressure_psi": p})
    out[f"{psi:g} psi base"] = ("pressure", {})
    return out


def _titles(base: Config) -> dict[str, str]:
    psi, tokens = base["fork.spring.air_pressure_psi"], base.get("fork.spring.tokens", 0.0)
    return {"spacers": f"Air fork: volume spacers at {psi:g} psi",
            "pressure": f"Air fork: air pressure with {tokens:g} spacer(s)",
            "tire": f"Air fork: tire pressure ({psi:g} psi, {tokens:g} spacer(s))"}


def run_air_study(config: Config | str = "air120", overrides: Mapping | None = None, duration: float | None = None,
                  workers: int | None = None, progress: Callable[[str], None] | None = None):
    """Every variant on MuJoCo and on the ODE reference, in parallel processes. Returns
    ``(base, results, checks)``: ``results[name][engine]`` and one cross-check
    (``CrosscheckResult``) per variant."""
    from mtbmj import limits

    workers = limits.whole("--workers", workers, 1)
    base = resolve(config, overrides)
    if base.get("fork.spring.model") != "air":
        from mtbmj.errors import ConfigError

        raise ConfigError(f"fork.spring.model: the air study needs an air configuration, {base.name} is "
                          f"{base.get('fork.spring.model')!r}")
    configs = []
    for name, (_, change) in variants(base).items():
        c = base.with_overrides(change)
        compose.setup(c)  # every variant is valid before any runs
        configs.append(Config(name, c.values, c.sources))
    jobs = [(c, e, duration) for c in configs for e in ("ode", "mujoco")]
    workers = min(workers or os.cpu_count() or 1, len(jobs))
    results: dict[str, dict] = {c.name: {} for c in configs}
    with process_pool(workers) as pool:
        for done, result in enumerate(pool.map(run_job, jobs), 1):
            results[result.name][result.engine] = result
            if progress is not None:
                progress(f"[{done}/{len(jobs)}] {result.name} {result.engine}: {result.wall_time_s:.2f} s")
    checks = [from_results(results[c.name]["mujoco"], results[c.name]["ode"]) for c in configs]
    return base, results, checks


def static_sag_mm(config: Config) -> float | None:
    """Fork compression (mm) where the spring carries the body's weight; ``None`` when the spring
    cannot carry it anywhere in the travel (the fork would sit on its bumper). The balance of
    ``mtbmj.readout.curves.static_sag``, which the spring-curve figure marks."""
    from mtbmj.readout.curves import static_sag

    setup = compose.setup(config)
    sag = static_sag(setup.fork.spring, setup.body_mass * setup.gravity, setup.travel)
    return None if sag is None else sag * 1e3


def spring_curves_figure(base: Config):
    """Fork spring force vs travel (paper Fig. 3 style) from the top stop to full travel (the
    curves of ``mtbmj.readout.curves``, y range the springs' own): 0-3 spacers at the base pressure, and
    the two study pressures, with the body's weight and each static sag marked."""
    from matplotlib.figure import Figure  # the object API: the caller's backend is left alone

    from mtbmj.readout.curves import draw_spring_totals, spring_curve

    fig = Figure(figsize=(11, 4.4), layout="constrained")
    left, right = fig.subplots(1, 2)
    grid = spring_curve(base).travel_mm
    for ax, group in ((left, "spacers"), (right, "pressure")):
        curves = {name: spring_curve(base.with_overrides(change), travel_mm=grid)
                  for name, (g, change) in variants(base).items() if g == group}
        draw_spring_totals(ax, curves)
    shared = (min(left.get_ylim()[0], right.get_ylim()[0]), max(left.get_ylim()[1], right.get_ylim()[1]))
    for ax in (left, right):
        ax.set_ylim(*shared)  # one force scale for both panels
    left.set_title(f"(a) volume spacers, {base['fork.spring.air_pressure_psi']:g} psi", fontsize=9)
    right.set_title("(b) air pressure; dots: static sag under the sled's weight (dotted)", fontsize=9)
    fig.suptitle(f"{base.name}: air spring curves (top-out spring, negative chamber and bumper included)")
    return fig


def study_rows(results, checks) -> list[dict]:
    rows = []
    for check in checks:
        result = results[check.context["config"]]["mujoco"]
        s = result.summary
        rows.append({"variant": check.context["config"], "static_sag_mm": _rounded(static_sag_mm(result.config), 2),
                     "fork_peak1_mm": _rounded(_event(s, "fork", "peak1"), 2),
                     "tire_peak1_mm": _rounded(_event(s, "tire", "peak1"), 2),
                     "travel_used_percent": round(s["travel_used_percent"], 1),
                     "lift_off_s": None if s["lift_off_s"] is None else round(s["lift_off_s"], 3),
                     "max_mujoco_ode_diff_mm": round(max(c.max_abs for c in check.signals), 4)})
    return rows


def _rounded(value, digits):
    return None if value is None else round(value, digits)


def _event(summary, signal, name):
    """An event's value in mm, ``None`` when the run did not reach it (a run too short for Peak 1)."""
    event = (summary.get("events", {}).get(signal) or {}).get(name)
    return None if not event else event.get("value_mm")


def air_study_files(base: Config, results, checks) -> dict[str, bytes]:
    titles = _titles(base)
    groups: dict[str, list[str]] = {}
    for name, (group, _) in variants(base).items():
        groups.setdefault(group, []).append(name)
    psi = base["fork.spring.air_pressure_psi"]
    groups["tire"] = [f"{psi:g} psi base"] + groups["tire"]
    files = {f"air_{g}.png": png_bytes(group_figure(results, titles[g], names)) for g, names in groups.items()}
    files["air_spring_curves.png"] = png_bytes(spring_curves_figure(base))
    rows = study_rows(results, checks)
    columns = list(rows[0])
    text = ",".join(columns) + "\n" + "\n".join(",".join("" if r[c] is None else str(r[c]) for c in columns)
                                                 for r in rows) + "\n"
    files["air_study.csv"] = text.encode()
    files["engine_vs_reference.md"] = table_markdown(checks).encode()
    files["air_study_summary.json"] = output.json_bytes(
        {name: {engine: r.summary for engine, r in per.items()} for name, per in results.items()})
    return files


def write_air_study(out_dir: str | Path, base: Config, results, checks) -> list[Path]:
    return output.write_atomically(out_dir, air_study_files(base, results, checks))


__all__ = ["run_air_study", "write_air_study", "air_study_files", "spring_curves_figure", "static_sag_mm",
           "study_rows", "variants"]

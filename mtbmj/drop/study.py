"""The S1-S14 study on both engines: the paper's figures and an engine-vs-reference table."""
from __future__ import annotations

import csv as _csv
import io
import os
from pathlib import Path
from typing import Callable, Sequence

from mtbmj.drop.crosscheck import from_results
from mtbmj import compose, limits, output
from mtbmj.controllers import native
from mtbmj.config import Config, study_presets
from mtbmj.drop.chain import resolve
from mtbmj.drop.run import run_drop
from mtbmj.drop.result import DropResult
from mtbmj.errors import ConfigError
from mtbmj.runpath.crosscheck import CrosscheckResult, number
from mtbmj.workers import process_pool

# "{presets}" in a title: the presets drawn (``group_figure``), so a study of S1 and S12 is not
# titled "S1-S7" over one preset
GROUPS = {
    "spring": ("Fork spring study {presets}", [f"S{i}" for i in range(1, 8)]),
    "damper": ("Fork damping study {presets}", ["S8", "S9", "S10"]),
    "tire": ("Tire study {presets}", ["S11", "S12", "S13", "S14"]),
}


def run_job(job: tuple[Config, str, float | None]) -> DropResult:
    """One drop of a study, ``(config, engine, duration)``, in a pool worker."""
    config, engine, duration = job
    native.expect_many()  # a study's runs repay loading the compiled laws
    return run_drop(config, engine, duration=duration)


STUDY_ENGINES = ("mujoco", "ode")


def run_study(presets: Sequence[str] | None = None, overrides=None, duration: float | None = None,
              workers: int | None = None, progress: Callable[[str], None] | None = None,
              engines: Sequence[str] = STUDY_ENGINES):
    """Run every preset on each of ``engines`` (MuJoCo and the ODE reference unless told; add
    "fast" for the native engine), in parallel processes.

    Returns ``(results, crosschecks)``: ``results[name][engine]`` and, when the reference is among
    the engines, one cross-check (``CrosscheckResult``) per preset and engine against it (preset
    order, then engine)."""
    from mtbmj.drop.run import ENGINES

    # "S12" read letter by letter would be refused as the preset "S"; [] of presets ran the whole study, of engines
    # said "workers: must be at least 1, got 0"; workers="2" met "'<' not supported between ..."
    presets = limits.names("presets", presets, "S12")
    engines = list(dict.fromkeys(limits.names("engines", engines, "mujoco", none_ok=False)))
    workers = limits.whole("--workers", workers, 1)
    unknown = [e for e in engines if e not in ENGINES]
    if unknown:
        raise ConfigError(f"engines: {unknown[0]!r} is not one of {', '.join(ENGINES)}")
    configs = [resolve(n, overrides) for n in (presets or study_presets())]
    names = [c.name for c in configs]  # as each run names itself ("s1" is S1, "my/air.toml" is air)
    twice = next((n for i, n in enumerate(names) if n in names[:i]), None)
    if twice is not None:  # one result each: a second would replace the first (a file named as a preset too)
        raise ConfigError(f"--presets: {twice} is named twice (a configuration is run once per study)")
    for c in configs:  # refused here, before any worker starts
        setup = compose.setup(c)
        limits.check_run(setup.duration if duration is None else duration, setup.timestep, setup.sample_rate,
                         f"{c.name}: {'solver.duration_s' if duration is None else limits.named('duration', duration)}",
                         runs=len(engines))
    # the reference first: it is the slowest, so the pool starts on it
    order = sorted(engines, key=lambda e: e != "ode")
    jobs = [(c, e, duration) for c in configs for e in order]
    workers = min(workers or os.cpu_count() or 1, len(jobs))  # never more processes than jobs
    results: dict[str, dict[str, DropResult]] = {n: {} for n in names}
    with process_pool(workers) as pool:
        for done, result in enumerate(pool.map(run_job, jobs), 1):
            results[result.name][result.engine] = result
            if progress is not None:
                progress(f"[{done}/{len(jobs)}] {result.name} {result.engine}: {result.wall_time_s:.2f} s")
    checks = [from_results(results[n][e], results[n]["ode"]) for n in names for e in engines
              if e != "ode" and "ode" in engines]
    return results, checks


STYLES = {"mujoco": ("MuJoCo", 1.4, "-"), "ode": ("ODE", 0.9, "--"), "fast": ("fast", 0.9, ":")}
STYLE_WORDS = {"-": "solid", "--": "dashed", ":": "dotted"}


def span(names: Sequence[str]) -> str:
    """``names`` in short: "S1-S7" for a run of consecutive presets, else "S1, S12"."""
    import re

    numbers = [re.fullmatch(r"S(\d+)", n) for n in names]
    if len(names) > 2 and all(numbers):
        k = [int(m.group(1)) for m in numbers]
        if k == list(range(k[0], k[0] + len(k))):
            return f"{names[0]}-{names[-1]}"
    return ", ".join(names)


def group_title(title: str, names: Sequence[str], drawn: Sequence[str]) -> str:
    """``title`` naming what is drawn: its "{presets}" becomes the presets drawn, with the group's
    others named as not run ("S1 only (of S1-S7)"); a title without it is kept and, when some
    are missing, followed by what is drawn."""
    shown = span(drawn) if drawn else "nothing"
    partial = len(drawn) < len(names)
    if partial:
        shown = f"{shown} only (of {span(names)})"
    if "{presets}" in title:
        return title.replace("{presets}", shown)
    return f"{title}: {shown}" if partial else title


def engines_line(results, names: Sequence[str]) -> str:
    """How the engines are drawn and how far each is from MuJoCo at most: a reference a few
    thousandths of a millimetre away lies under the MuJoCo line, one line to the eye."""
    drawn = [e for e in STYLES if any(e in results[n] for n in names)]
    parts = []
    for engine in drawn:
        label, _, style = STYLES[engine]
        text = f"{label} {STYLE_WORDS[style]}"
        if engine != "mujoco":
            gaps = []
            for n in names:
                if engine in results[n] and "mujoco" in results[n]:
                    try:
                        diff = results[n][engine].difference(results[n]["mujoco"])
                    except ValueError:  # not on the same time grid
                        continue
                    gaps.append(max(d["max_abs_mm"] for d in diff.values()))
            if gaps:
                text += f" (at most {max(gaps):.2g} mm from MuJoCo)"
        parts.append(text)
    return ", ".join(parts)


def group_figure(results, title: str, names: Sequence[str]):
    """Sled, fork and tire histories of one group: MuJoCo solid, ODE reference dashed, the fast
    engine dotted. Titled by the presets drawn (``group_title``) and, under it, the engines'
    line styles and how far each is from MuJoCo."""
    import matplotlib
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 8), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    colours = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    drawn = [n for n in names if n in results]
    for k, name in enumerate(drawn):
        colour = colours[k % len(colours)]
        for engine, (label, width, style) in STYLES.items():
            if engine in results[name]:
                results[name][engine].plot(axes, label=f"{name} {label}", color=colour, lw=width, ls=style)
    if drawn:
        from mtbmj.readout.quicklook import legend_above

        legend_above(axes[0], fontsize=8)  # above the panels: 7 presets x 2 engines inside covered the peaks
    fig.suptitle(f"{group_title(title, names, drawn)}\n{engines_line(results, drawn)}", fontsize=10)
    return fig


def png_bytes(fig) -> bytes:
    from mtbmj.readout.quicklook import png

    return png(fig, dpi=110)


def table_markdown(checks: Sequence[CrosscheckResult]) -> str:
    lines = ["| config | engine | sled max diff [mm] | fork max diff [mm] | tire max diff [mm] | worst at [s] | within tol. | engine [s] | ODE [s] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for c in checks:
        lines.append(f"| {c.case} | {c.engine} | {number(c['sled'].max_abs)} | {number(c['fork'].max_abs)} | "
                     f"{number(c['tire'].max_abs)} | {c.worst.at_time_s:.4f} | {'yes' if c.passed else 'NO'} | "
                     f"{c.engine_wall_s:.3f} | {c.reference_wall_s:.3f} |")
    return "\n".join(lines) + "\n"


def table_row(check: CrosscheckResult) -> dict:
    """A drop cross-check as a row of engine_vs_reference.csv: per signal its largest difference
    (mm) and when, the tolerance, the verdict and both wall times."""
    row = {"config": check.case, "engine": check.engine}
    for s in check.signals:
        row[f"max_diff_{s.name}_{s.unit}"] = s.max_abs
        row[f"at_time_{s.name}_s"] = s.at_time_s
    row.update({"tolerance_mm": check.worst.tolerance, "passed": check.passed, "engine_wall_s": check.engine_wall_s,
                "reference_wall_s": check.reference_wall_s})
    return row


def study_files(results, checks) -> dict[str, bytes]:
    files = {}
    for key, (title, names) in GROUPS.items():
        if any(n in results for n in names):
            files[f"study_{key}.png"] = png_bytes(group_figure(results, title, names))
    rows = [table_row(c) for c in checks]
    if rows:  # none when the reference was not among the engines
        columns = list(rows[0])
        buffer = io.StringIO()
        writer = _csv.writer(buffer, lineterminator="\n")
        writer.writerow(columns)
        writer.writerows([output.spreadsheet_text(str(r[c])) for c in columns] for r in rows)
        files["engine_vs_reference.csv"] = buffer.getvalue().encode()
        files["engine_vs_reference.md"] = table_markdown(checks).encode()
    summary = {name: {engine: r.summary for engine, r in per.items()} for name, per in results.items()}
    files["study_summary.json"] = output.json_bytes(summary)
    return files


def write_study(out_dir: str | Path, results, checks) -> list[Path]:
    return output.write_atomically(out_dir, study_files(results, checks))

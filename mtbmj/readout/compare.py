"""Runs side by side: two or more result folders of ``mtbmj drop`` (or ``mtbmj roll``, or ``mtbmj
bike``) overlaid on shared axes (fork travel, tire deflection, fork force and tire force against
time; a bike's front and rear wheel travel, pitch and tyre loads; one colour per run, the legend
naming each run by its folder) and a difference table, one row per summary figure, one column per
run and one per run's difference from the first. A bike folder is one whose manifest names its
``bike_source``.

A run folder is what ``DropResult.write`` / ``RollResult.write`` (or the commands) wrote:
``manifest.json`` naming mtbmj in its versions, ``summary.json`` and ``timeseries.csv`` with
time_s, fork_mm, tire_mm, fork_force_N and tire_force_N. Its kind is a roll when the manifest names
a scenario, else a drop. Drops and rolls are not compared with each other: a drop's time zero is
the tire's touch and a roll's the start over the terrain, so the same time is not the same moment,
and their summaries share few figures.
"""
from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from mtbmj import output
from mtbmj.errors import MtbmjError
from mtbmj.textfile import number_table, read_text

SIGNALS = (("fork_mm", "fork travel (mm)"), ("tire_mm", "tire deflection (mm)"),
           ("fork_force_N", "fork force (N)"), ("tire_force_N", "tire force (N)"))
# a bike's folder: both ends' travel, the pitch and both tyres' loads
BIKE_SIGNALS = (("front_travel_mm", "front travel (mm)"), ("rear_travel_mm", "rear wheel travel (mm)"),
                ("pitch_deg", "pitch, nose up (deg)"), ("front_tire_N", "front tyre load (N)"),
                ("rear_tire_N", "rear tyre load (N)"))
SIGNALS_OF = {"drop": SIGNALS, "roll": SIGNALS, "bike": BIKE_SIGNALS}
NEEDED = ("time_s",) + tuple(name for name, _ in SIGNALS)


@dataclass
class Run:
    """One result folder: ``label`` names it in the figure and the table."""

    path: Path
    label: str
    kind: str  # "drop", "roll" or "bike"
    manifest: dict
    summary: dict
    signals: dict[str, np.ndarray]
    travel_mm: float | None

    @property
    def description(self) -> str:
        what = self.manifest.get("name", "?")
        if self.kind == "bike":
            speed = self.summary.get("speed_m_per_s")
            changed = self.manifest.get("bike_overrides") or {}
            sets = [f"{k}={v}" for k, v in changed.items() if not isinstance(v, dict)]
            sets += [f"{k.split('.')[0]} {kk}={vv}" for k, v in changed.items() if isinstance(v, dict)
                     for kk, vv in v.items()]
            return f"bike {what} over {self.manifest.get('scenario')}" + (
                f" at {speed:g} m/s" if isinstance(speed, (int, float)) else "") + (
                f", {', '.join(sets)}" if sets else "")
        if self.kind == "roll":
            scenario = self.manifest.get("scenario")
            speed = self.summary.get("speed_m_per_s")
            where = f"{scenario}" + (f" at {speed:g} m/s" if isinstance(speed, (int, float)) else "")
            return f"{what}, roll {where}"
        return f"{what}, {self.manifest.get('engine', '?')}"


def _json(path: Path, run: Path) -> dict:
    label = str(path)
    if not path.is_file():
        raise MtbmjError(f"{run}: not an mtbmj drop, roll or bike result (no {path.name})")
    try:
        data = json.loads(read_text(path, MtbmjError, label, "not a text file"))
    except (ValueError, RecursionError) as exc:
        raise MtbmjError(f"{label}: not valid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise MtbmjError(f"{label}: not an mtbmj {path.stem} (a JSON object is expected)")
    return data


def _timeseries(path: Path, run: Path, needed=NEEDED) -> dict[str, np.ndarray]:
    label = str(path)
    if not path.is_file():
        raise MtbmjError(f"{run}: not an mtbmj drop, roll or bike result (no timeseries.csv)")
    text = read_text(path, MtbmjError, label, "not a text file", "record")
    lines = [line for line in text.splitlines() if line.strip() and not line.startswith("#")]
    if not lines:
        raise MtbmjError(f"{label}: empty")
    names = [n.strip() for n in lines[0].split(",")]
    missing = [n for n in needed if n not in names]
    if missing:
        raise MtbmjError(f"{label}: no {missing[0]} column: not a timeseries of mtbmj drop, roll or bike")
    names, table = number_table(text, label, MtbmjError)
    if table.shape[0] < 2:
        raise MtbmjError(f"{label}: fewer than two rows")
    columns = dict(zip(names, table.T))
    if not np.all(np.isfinite(columns["time_s"])) or np.any(np.diff(columns["time_s"]) <= 0):
        raise MtbmjError(f"{label}: time_s must be finite and increasing")
    return {name: columns[name] for name in needed}


def _travel(run: Path) -> float | None:
    """fork.travel_mm of the run's config.toml, when it holds one."""
    import tomllib

    path = run / "config.toml"
    if not path.is_file():
        return None
    try:
        fork = tomllib.loads(read_text(path, MtbmjError, str(path), "not a text file")).get("fork")
    except (tomllib.TOMLDecodeError, RecursionError, MtbmjError):
        return None
    value = fork.get("travel_mm") if isinstance(fork, dict) else None
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0 else None


def load_run(path: str | Path, label: str | None = None) -> Run:
    """The result folder ``path``, refused (one line naming it) when it is not an mtbmj drop, roll or
    bike result."""
    run = Path(path)
    if not run.is_dir():
        raise MtbmjError(f"{run}: not a folder (give the --out folder of mtbmj drop, mtbmj roll or mtbmj bike)")
    manifest = _json(run / "manifest.json", run)
    versions = manifest.get("versions")
    if not isinstance(versions, dict) or "mtbmj" not in versions:
        raise MtbmjError(f"{run / 'manifest.json'}: not the manifest of an mtbmj run (its versions name no mtbmj)")
    if "engine" not in manifest and "scenario" not in manifest:
        raise MtbmjError(f"{run}: not an mtbmj drop, roll or bike result (its manifest names neither an engine nor a "
                         "scenario)")
    summary = _json(run / "summary.json", run)
    kind = "bike" if "bike_source" in manifest else "roll" if "scenario" in manifest else "drop"
    signals = _timeseries(run / "timeseries.csv", run, ("time_s",) + tuple(n for n, _ in SIGNALS_OF[kind]))
    travel = _travel(run) if kind != "bike" else None
    if kind == "bike" and isinstance(summary.get("front"), dict):
        value = summary["front"].get("travel_mm")
        travel = float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None
    return Run(run, label or run.name or str(run), kind, manifest, summary, signals, travel)


def _labels(paths: Sequence[Path]) -> list[str]:
    """Each run's folder name; the path as given where two share a name."""
    names = [p.name or str(p) for p in paths]
    return [str(p) if names.count(n) > 1 else n for p, n in zip(paths, names)]


def refuse_repeated(paths, named: str = "") -> None:
    """Refuse (one line) a run folder given twice, by the same name or another (``../s1`` beside ``s1``):
    drawn and counted twice. ``named``: the option that gave them, put before the path in the line."""
    seen = {}
    for p in paths:
        key = Path(p).resolve()
        if key in seen:
            raise MtbmjError(f"{named}{p}: given twice (as {seen[key]}); give each run once")
        seen[key] = p


def load_runs(paths: Sequence[str | Path]) -> list[Run]:
    """The runs to compare: at least two, each once, all drops or all rolls."""
    paths = [Path(p) for p in paths]
    if len(paths) < 2:
        raise MtbmjError(f"compare: give at least two run folders (got {len(paths)})")
    refuse_repeated(paths)
    runs = [load_run(p, label) for p, label in zip(paths, _labels(paths))]
    kinds = {r.kind for r in runs}
    if len(kinds) > 1:
        first = runs[0]
        other = next(r for r in runs if r.kind != first.kind)
        raise MtbmjError(f"{other.path}: is a {other.kind} and {first.path} a {first.kind}: they are not compared "
                         "(a drop's time zero is the tire's touch, a roll's and a bike's the start over the terrain, "
                         "and their signals and summaries differ); compare runs of one kind")
    return runs


# --- the difference table ---------------------------------------------------------------------------

def figures(summary: dict, prefix: str = "") -> dict[str, object]:
    """The summary's single figures by dotted key: numbers, flags, text and nulls (a missing event);
    lists (histograms, event times) are left out."""
    out: dict[str, object] = {}
    for key, value in summary.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            if not value:
                continue
            out.update(figures(value, name + "."))
        elif isinstance(value, (bool, int, float, str)) or value is None:
            out[name] = value
    return out


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return f"{value:.9g}"
    return str(output.spreadsheet_text(value))


def _number(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return float(value)


def difference_rows(runs: Sequence[Run]) -> tuple[list[str], list[list[str]]]:
    """(header, rows): ``figure``, one column per run, then ``<run> - <first run>`` per later run;
    a difference only where both are numbers. Rows: every summary figure any run has, in the
    order they first appear, after the run's configuration and engine (from its manifest)."""
    tables = [{"manifest.name": r.manifest.get("name"),
               ("manifest.scenario" if r.kind == "roll" else "manifest.engine"):
                   r.manifest.get("scenario" if r.kind == "roll" else "engine"),
               **figures(r.summary)} for r in runs]
    keys = list(dict.fromkeys(k for t in tables for k in t))
    first = runs[0].label
    header = ["figure"] + [r.label for r in runs] + [f"{r.label} - {first}" for r in runs[1:]]
    rows = []
    for key in keys:
        values = [t.get(key) for t in tables]
        diffs = []
        for value in values[1:]:
            a, b = _number(values[0]), _number(value)
            diffs.append("" if a is None or b is None else f"{b - a:.9g}")
        rows.append([key] + [_cell(v) for v in values] + diffs)
    return header, rows


def difference_csv(runs: Sequence[Run]) -> bytes:
    header, rows = difference_rows(runs)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([output.spreadsheet_text(h) for h in header])
    writer.writerows(rows)
    return buffer.getvalue().encode()


# --- the figure -------------------------------------------------------------------------------------

def _colours(n: int):
    from matplotlib import colormaps

    if n <= 10:
        return [colormaps["tab10"](i) for i in range(n)]
    return [colormaps["turbo"](x) for x in np.linspace(0.05, 0.95, n)]


def figure(runs: Sequence[Run]):
    """Fork travel, tire deflection, fork force and tire force against time, one colour per run;
    the full travel dotted where the runs' configurations give it."""
    from matplotlib.figure import Figure

    signals = SIGNALS_OF[runs[0].kind]
    fig = Figure(figsize=(9, 2.5 * len(signals)), layout="constrained")
    axes = fig.subplots(len(signals), 1, sharex=True)
    styles = ("-", "--", "-.", ":")  # runs that coincide stay visible under one another
    for i, (run, colour) in enumerate(zip(runs, _colours(len(runs)))):
        t = run.signals["time_s"]
        for ax, (name, _) in zip(axes, signals):
            ax.plot(t, run.signals[name], color=colour, lw=1.3, ls=styles[i % len(styles)],
                    label=f"{run.label} ({run.description})")
    for travel in sorted({r.travel_mm for r in runs if r.travel_mm is not None}):
        axes[0].axhline(travel, color="0.4", ls=":", lw=1.0)
        axes[0].annotate(f"full travel {travel:g} mm", xy=(0.005, travel), xycoords=("axes fraction", "data"),
                         ha="left", va="top", fontsize=7, color="0.4")
    for ax, (_, label) in zip(axes, signals):
        ax.set_ylabel(label)
        ax.axhline(0.0, color="0.75", lw=0.6)
        ax.grid(alpha=0.3)
    start = min(float(r.signals["time_s"][0]) for r in runs)
    end = max(float(r.signals["time_s"][-1]) for r in runs)
    axes[0].set_xlim(start, end)
    zero = "tire touch" if runs[0].kind == "drop" else "start of the run"
    axes[-1].set_xlabel(f"time (s) from the {zero}")
    fig.suptitle(f"{len(runs)} {runs[0].kind} runs compared")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(runs), 3), fontsize=8)
    return fig


# --- output -----------------------------------------------------------------------------------------

@dataclass
class Comparison:
    runs: list[Run]

    def files(self) -> dict[str, bytes]:
        from mtbmj.readout.quicklook import png

        listing = [{"label": r.label, "folder": str(r.path), "kind": r.kind, "name": r.manifest.get("name"),
                    "engine": r.manifest.get("engine"), "scenario": r.manifest.get("scenario"),
                    "config_sha256": r.manifest.get("config_sha256")} for r in self.runs]
        return {"compare.png": png(figure(self.runs), dpi=110), "differences.csv": difference_csv(self.runs),
                "compare.json": output.json_bytes({"kind": self.runs[0].kind, "runs": listing})}

    def write(self, out_dir: str | Path) -> list[Path]:
        return output.write_atomically(out_dir, self.files())

    def line(self) -> str:
        name, what = SIGNALS_OF[self.runs[0].kind][0]
        peaks = " / ".join(f"{float(np.max(r.signals[name])):.1f}" for r in self.runs)
        return (f"compared {len(self.runs)} {self.runs[0].kind} runs ({', '.join(r.label for r in self.runs)}): "
                f"{what.split(' (')[0].replace('fork travel', 'fork')} peak {peaks} mm")


def compare_runs(paths: Sequence[str | Path]) -> Comparison:
    """Read the run folders ``paths`` (refused in one line as ``load_runs`` says)."""
    return Comparison(load_runs(paths))


__all__ = ["Run", "Comparison", "compare_runs", "load_run", "load_runs", "refuse_repeated", "figures", "difference_rows",
           "difference_csv", "figure"]

"""A real ride's metrics beside simulated runs' (``mtbmj telemetry FILE.SST --compare RUN_DIR``):
each run directory read (a drop or rolling run's fork, a bike run's fork and rear wheel), the
ride's and the runs' travel and velocity histograms with shared bins, and the figure that puts
them on the same axes: one :class:`RideComparison` that the command and the Python API read alike."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mtbmj import output
from mtbmj.errors import MtbmjError
from mtbmj.measured import metrics as ride_metrics
from mtbmj.measured import telemetry
from mtbmj.textfile import number_table, read_text

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

SPLIT_LABELS = {"high_speed_compression": "HSC", "low_speed_compression": "LSC",
                "low_speed_rebound": "LSR", "high_speed_rebound": "HSR"}
ABBREVIATIONS = {
    "HSC": "high-speed compression: share of time with velocity > +threshold",
    "LSC": "low-speed compression: 0 <= velocity <= +threshold",
    "LSR": "low-speed rebound: -threshold <= velocity < 0",
    "HSR": "high-speed rebound: velocity < -threshold",
}

@dataclass
class RideComparison:
    """The ride's metrics beside the runs': ``summary`` (telemetry.json's content: ``measured``,
    ``simulated``, the conventions and abbreviations) and how many ``runs`` were compared."""

    summary: dict
    runs: int = 0

    def figure(self):
        return figure(self.summary)

    def files(self) -> dict[str, bytes]:
        """telemetry.json and telemetry.png, as bytes."""
        return {"telemetry.json": output.json_bytes(self.summary), "telemetry.png": figure_png(self.summary)}

    def write(self, out_dir) -> list[Path]:
        """The files written atomically to ``out_dir``."""
        return output.write_atomically(out_dir, self.files())

    def line(self) -> str:
        """What the command prints: the ride, each end's deepest travel, bottom-outs, dynamic sag and
        high-speed share, the airtime, and how many runs it was compared with."""
        m = self.summary["measured"]
        parts = []
        for end in ("fork", "rear"):
            if end in m:
                e = m[end]
                # what a rider tunes by: the deepest travel, the bottom-outs and the dynamic sag (the mean
                # travel while on the ground); the histogram's mode stays in the figure and the JSON
                parts.append(f"{end} max {e['travel']['max_percent']:.0f} % ({e['travel']['max_mm']:.1f} of "
                             f"{e['travel_max_mm']:.0f} mm), {e['bottom_outs']['count']} bottom-outs, dynamic sag "
                             f"{e['travel']['mean_percent']:.0f} %, {e['velocity']['high_speed_percent']:.1f} % "
                             f"high-speed")
        air = m.get("fork", m.get("rear"))["airtime"]
        return (f"{m['file']}: {m['duration_s']:.1f} s at {m['sample_rate_Hz']:g} Hz; {'; '.join(parts)}; "
                f"airtime {air['count']} ({air['total_s']:.2f} s); compared {self.runs} run(s)")


def read_columns(run_dir: Path, error=MtbmjError) -> dict:
    """The columns (name -> values) of ``run_dir``'s timeseries.csv."""
    run_dir = Path(run_dir)
    csv_path = run_dir / "timeseries.csv"
    if not run_dir.is_dir():
        if run_dir.is_file():  # the run's CSV (or another file) given for its folder
            raise error(f"--compare {run_dir}: a file, not a run directory" + (
                f" (give the folder that holds it: --compare {run_dir.parent})" if run_dir.name == csv_path.name
                and (run_dir.parent / "summary.json").is_file() else ""))
        raise error(f"--compare {run_dir}: not a run directory")
    if not csv_path.is_file():
        other = _written_by(run_dir)
        if other:  # another command's folder (a telemetry, a reconstruction, a fit): not a run to compare
            raise error(f"--compare {run_dir}: a folder of mtbmj {other}, not a run: --compare takes the folder of a "
                        f"drop, roll or bike run (mtbmj drop, roll or bike ... --out DIR)")
        raise error(f"--compare {run_dir}: no timeseries.csv (write one with mtbmj drop, roll or bike ... --out {run_dir})")
    text = read_text(csv_path, error, str(csv_path), "not a text file", "record")
    names, table = number_table(text, str(csv_path), error)
    return dict(zip(names, table.T))


def _written_by(folder: Path) -> str | None:
    """The command that wrote ``folder`` (its ``mtbmj.output`` record), else None."""
    from mtbmj.output import RECORD

    try:
        record = json.loads((folder / RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    command = record.get("command") if isinstance(record, dict) else None
    return command if isinstance(command, str) and command else None


def _run_name(run_dir: Path, name: str) -> str:
    manifest_path = run_dir / "manifest.json"
    if manifest_path.is_file():
        try:
            manifest = json.loads(read_text(manifest_path, MtbmjError, str(manifest_path), "not a text file"))
            if isinstance(manifest, dict):
                kind = "bike" if "bike_source" in manifest else manifest.get("engine", manifest.get("kind", "sim"))
                name = f"{manifest.get('name', name)} ({kind})"
        except (MtbmjError, ValueError, RecursionError):
            pass
    return name


def _positive(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and 0 < value < 1e6


def _load_bike(run_dir: Path, columns: dict) -> dict:
    """Both ends of a bike run (``mtbmj bike --out``): front (fork) travel and rear wheel travel,
    each end's full travel from summary.json."""
    summary_path = run_dir / "summary.json"
    try:
        summary = json.loads(read_text(summary_path, MtbmjError, str(summary_path), "not a text file"))
        front_max = summary["front"]["travel_mm"]
        rear_max = summary["rear_wheel_travel_mm"]
    except (MtbmjError, ValueError, RecursionError, KeyError, TypeError):
        raise MtbmjError(f"--compare {run_dir}: a bike run without a readable summary.json (front.travel_mm, "
                         "rear_wheel_travel_mm)") from None
    if not (_positive(front_max) and _positive(rear_max)):
        raise MtbmjError(f"--compare {run_dir}: summary.json gives no positive front.travel_mm and rear_wheel_travel_mm")
    return {"name": _run_name(run_dir, run_dir.name), "dir": str(run_dir), "time_s": columns["time_s"],
            "fork_mm": columns["front_travel_mm"], "velocity_mm_per_s": None, "travel_max_mm": float(front_max),
            "rear_mm": columns["rear_travel_mm"], "rear_travel_max_mm": float(rear_max)}


def load_run(run_dir: Path) -> dict:
    """Fork travel of a run directory: name, time_s, fork_mm, fork velocity (or None), travel max;
    a bike run (``mtbmj bike --out``) also gives rear_mm (rear wheel travel) and rear_travel_max_mm."""
    run_dir = Path(run_dir)
    columns = read_columns(run_dir)
    csv_path = run_dir / "timeseries.csv"
    if "time_s" not in columns:
        raise MtbmjError(f"{csv_path}: no time_s column")
    if "fork_mm" not in columns:
        if "front_travel_mm" in columns and "rear_travel_mm" in columns:
            return _load_bike(run_dir, columns)
        raise MtbmjError(f"--compare {run_dir}: neither a drop or roll run (no fork_mm column) nor a bike run "
                         "(no front_travel_mm and rear_travel_mm columns) in timeseries.csv")
    travel_max = None
    config_path = run_dir / "config.toml"
    if config_path.is_file():
        text = read_text(config_path, MtbmjError, str(config_path), "not a text file")
        try:
            fork = tomllib.loads(text).get("fork")
        except (tomllib.TOMLDecodeError, RecursionError) as exc:
            raise MtbmjError(f"{config_path}: not valid TOML ({exc})") from None
        travel_max = fork.get("travel_mm") if isinstance(fork, dict) else None
    if not _positive(travel_max):
        raise MtbmjError(f"--compare {run_dir}: config.toml gives no fork.travel_mm")
    return {"name": _run_name(run_dir, run_dir.name), "dir": str(run_dir), "time_s": columns["time_s"],
            "fork_mm": columns["fork_mm"], "velocity_mm_per_s": columns.get("fork_velocity_mm_per_s"),
            "travel_max_mm": float(travel_max)}


def compare(record: telemetry.TelemetryRecord, runs: list[dict], threshold_mm_per_s: float = 100,
            bin_percent: float = 5) -> RideComparison:
    """Metrics of the ride and of each run's fork (and a bike run's rear wheel), with shared velocity
    bins (``runs``: :func:`load_run`'s); the summary JSON-ready."""
    signals = [v for v in (record.fork_mm, record.rear_mm) if v is not None]
    try:
        velocities = [ride_metrics.velocity(record.time_s, v) for v in signals]
    except ride_metrics.MetricsError as exc:
        raise MtbmjError(f"{Path(record.path).name}: {exc}") from None
    run_ends = []  # (run, end, travel, travel max, velocity) of every simulated end
    for run in runs:
        try:
            run_ends.append((run, "fork", run["fork_mm"], run["travel_max_mm"],
                             run["velocity_mm_per_s"] if run["velocity_mm_per_s"] is not None
                             else ride_metrics.velocity(run["time_s"], run["fork_mm"])))
            if run.get("rear_mm") is not None:  # a bike run: its rear wheel too
                run_ends.append((run, "rear", run["rear_mm"], run["rear_travel_max_mm"],
                                 ride_metrics.velocity(run["time_s"], run["rear_mm"])))
        except ride_metrics.MetricsError as exc:
            raise MtbmjError(f"--compare {run['dir']}: {exc}") from None
    velocities += [e[4] for e in run_ends]
    edges = ride_metrics.velocity_bins(velocities)
    measured = record.metrics(threshold_mm_per_s, bin_percent, velocity_edges=edges, balance=False)
    simulated, entries = [], {}
    for run, end, travel, top, v in run_ends:
        try:
            metrics = ride_metrics.summarize(run["time_s"], travel, top, velocity_mm_per_s=v,
                                             threshold_mm_per_s=threshold_mm_per_s, bin_percent=bin_percent,
                                             velocity_edges=edges)
        except ride_metrics.MetricsError as exc:
            raise MtbmjError(f"--compare {run['dir']}: {exc}") from None
        if id(run) not in entries:
            entries[id(run)] = {"name": run["name"], "dir": run["dir"]}
            simulated.append(entries[id(run)])
        entries[id(run)][end] = metrics
    return RideComparison({"measured": measured, "simulated": simulated,
            "conventions": "travel mm from full extension and % of each run's own travel (the ride's fork "
                           "travel for the ride, fork.travel_mm for a simulated run; a bike run's front in its "
                           "fork travel, its rear in its rear wheel travel); velocity mm/s, "
                           "compression positive; histograms in % of time",
            "abbreviations": {k: v.replace("threshold", f"{threshold_mm_per_s:g} mm/s")
                              for k, v in ABBREVIATIONS.items()}}, len(runs))


def _split_label(metrics: dict) -> str:
    split = metrics["velocity"]["split_percent"]
    return " ".join(f"{SPLIT_LABELS[k]} {split[k]:.0f}%" for k in ride_metrics.SPLIT_NAMES)


def figure_png(summary: dict) -> bytes:
    """``figure`` as PNG bytes."""
    from mtbmj.readout.quicklook import png

    return png(figure(summary), dpi=100)


VELOCITY_SHOWN = 99.9  # % of each run's time the velocity axis shows, with VELOCITY_MARGIN
VELOCITY_MARGIN = 1.2


def velocity_span(histogram: dict, percent: float = VELOCITY_SHOWN) -> float:
    """The smallest bin edge L (mm/s) with ``percent`` of the histogram's time within +-L."""
    edges = np.asarray(histogram["bin_edges_mm_per_s"], float)
    time = np.asarray(histogram["time_percent"], float)
    total = float(time.sum())
    if total <= 0.0:
        return 0.0
    for limit in np.unique(np.abs(edges)):
        inside = float(time[(edges[:-1] >= -limit) & (edges[1:] <= limit)].sum())
        if inside >= percent / 100.0 * total * (1.0 - 1e-12):
            return float(limit)
    return float(np.max(np.abs(edges)))


def beyond(histogram: dict, limit: float) -> float:
    """% of time in the bins outside +-``limit``."""
    edges = np.asarray(histogram["bin_edges_mm_per_s"], float)
    time = np.asarray(histogram["time_percent"], float)
    return float(time[(edges[1:] > limit) | (edges[:-1] < -limit)].sum())


def _legend_below(ax, title: str | None = None) -> None:
    """The legend under the axis label, off the bars (inside, it covered the velocity peak)."""
    from matplotlib.transforms import ScaledTranslation

    below = ax.transAxes + ScaledTranslation(0.0, -0.5, ax.figure.dpi_scale_trans)  # under the tick labels and label
    handles, labels = ax.get_legend_handles_labels()
    order = sorted(range(len(labels)), key=lambda k: labels[k].startswith("beyond"))  # the note last
    ax.legend([handles[k] for k in order], [labels[k] for k in order], fontsize="x-small", title_fontsize="x-small",
              loc="upper left", bbox_to_anchor=(0.0, 0.0), bbox_transform=below, title=title, alignment="left",
              frameon=False, borderaxespad=0.0)


def figure(summary: dict):
    """Travel and velocity histograms, measured bars and simulated steps on the same axes (each
    run's travel in % of its own travel). The velocity axis shows ``VELOCITY_SHOWN`` % of every
    run's time with a margin, and names the time beyond it and the fastest strokes; legends sit
    under the axes, off the bars."""
    from matplotlib.figure import Figure

    measured = summary["measured"]
    ends = [e for e in ("fork", "rear") if e in measured]
    fig = Figure(figsize=(12, 4.8 * len(ends)), constrained_layout=True)
    axes = fig.subplots(len(ends), 2, squeeze=False)
    colors = ["tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink"]
    for row, end in zip(axes, ends):
        m = measured[end]
        ax_t, ax_v = row
        th, vh = m["travel_histogram"], m["velocity"]
        edges_t, edges_v = np.array(th["bin_edges_percent"]), np.array(vh["bin_edges_mm_per_s"])
        label = f"measured {end} ({measured['file']}, % of {m['travel_max_mm']:.0f} mm)"
        ax_t.bar(edges_t[:-1], th["time_percent"], width=np.diff(edges_t), align="edge", color="tab:blue",
                 alpha=0.55, edgecolor="white", label=f"{label}, max {m['travel']['max_percent']:.0f}%")
        ax_v.bar(edges_v[:-1], vh["time_percent"], width=np.diff(edges_v), align="edge", color="tab:blue",
                 alpha=0.55, edgecolor="white", label=f"{label}: {_split_label(m)}")
        for color, run in zip(colors * 4, summary["simulated"]):
            if end in run:  # every run's fork; a bike run's rear wheel too
                s = run[end]
                st, sv = s["travel_histogram"], s["velocity"]
                ax_t.stairs(st["time_percent"], st["bin_edges_percent"], color=color, linewidth=2,
                            label=f"simulated {run['name']} (% of {s['travel_max_mm']:.0f} mm), "
                                  f"max {s['travel']['max_percent']:.0f}%")
                ax_v.stairs(sv["time_percent"], sv["bin_edges_mm_per_s"], color=color, linewidth=2,
                            label=f"simulated {run['name']}: {_split_label(s)}")
        thr = vh["threshold_mm_per_s"]
        for x in (-thr, thr):
            ax_v.axvline(x, color="k", linestyle="--", linewidth=1)
        ax_v.axvspan(edges_v[0], -thr, color="0.94", zorder=0)
        ax_v.axvspan(thr, edges_v[-1], color="0.94", zorder=0)
        ax_t.set_xlim(0, 100)
        ax_t.set_xlabel(f"{end} travel [% of each run's own travel]")
        top = float(m["travel_max_mm"])  # the same axis in mm of the ride's own travel, on top
        mm = ax_t.secondary_xaxis("top", functions=(lambda p, top=top: p * top / 100.0,
                                                    lambda x, top=top: x * 100.0 / top))
        mm.set_xlabel(f"{end} travel [mm] of the ride's {top:.0f} mm", fontsize="small")
        ax_v.set_xlabel(f"{end} velocity [mm/s], compression positive")
        shown = [("measured", vh)] + [(f"simulated {r['name']}", r[end]["velocity"])
                                      for r in summary["simulated"] if end in r]
        # VELOCITY_SHOWN % of every run's time with a margin (a few strokes at 2-3 m/s spread
        # the bulk within +-500 mm/s over a few pixels), at least 3 x the threshold, at most the bins
        span = max(velocity_span(h) for _, h in shown)
        limit = min(max(3 * thr, VELOCITY_MARGIN * span), float(np.max(np.abs(edges_v))))
        ax_v.set_xlim(-limit, limit)
        cut = [f"{name} {beyond(h, limit):.2g} % (fastest {h['compression']['max_mm_per_s']:+.0f} / "
               f"{h['rebound']['max_mm_per_s']:+.0f} mm/s)" for name, h in shown if beyond(h, limit) > 0.0]
        if cut:
            ax_v.plot([], [], ls="none", label=f"beyond ±{limit:.0f} mm/s, not drawn: " + "; ".join(cut))
        split_title = (f"high speed: |v| > {thr:g} mm/s (shaded); HSC/LSC high/low-speed compression, "
                       "LSR/HSR low/high-speed rebound")
        for ax, title in ((ax_t, None), (ax_v, split_title)):
            ax.set_ylabel("time [%]")
            ax.grid(True, alpha=0.3)
            _legend_below(ax, title)
    bottoms = measured.get("fork", measured.get("rear"))
    fig.suptitle(f"{measured['file']}: {measured['duration_s']:.1f} s, airtime {bottoms['airtime']['count']} "
                 f"({bottoms['airtime']['total_s']:.2f} s), bottom-outs fork {measured.get('fork', {}).get('bottom_outs', {}).get('count', '-')}"
                 f" rear {measured.get('rear', {}).get('bottom_outs', {}).get('count', '-')}; histograms exclude airtime")
    return fig


__all__ = ["RideComparison", "compare", "figure", "figure_png", "load_run", "read_columns", "velocity_span"]

"""Validation of configurations against a sled record (or against the ODE reference): the paper's
Fig. 10 amplitude-error bars, overlays of measured and simulated histories, a CSV of all metrics,
a JSON summary and one self-contained HTML report (figures embedded as data URIs, no network).

>>> v = run_validation("sled.csv", ["S11", "S12"])          # the record is the measurement
>>> v = run_validation(None, ["S12"], reference_engine="ode")  # MuJoCo against the ODE reference
>>> v.write("out/validate")                                   # all files or none
"""
from __future__ import annotations

import base64
import contextlib
import csv
import html
import io
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from mtbmj import output
from mtbmj.controllers import native
from mtbmj.config import Config
from mtbmj.drop.chain import resolve
from mtbmj.drop.run import ENGINES, run_drop
from mtbmj.errors import ConfigError
from mtbmj.drop.result import DropResult
from mtbmj.workers import process_pool

from mtbmj.measured import sled as sled_data
from mtbmj.drop.events import EVENTS, LABELS, SIGNALS, Events, detect
from mtbmj.validation.drop_errors import PHASES, Metrics, compare

# The paper's three studies and their colours (Fig. 10): spring blue, damper red, tire green.
GROUPS = {
    "spring": ("Fork spring S1-S7", [f"S{i}" for i in range(1, 8)], "Blues"),
    "damper": ("Fork damping S8-S10", ["S8", "S9", "S10"], "Reds"),
    "tire": ("Tire S11-S14", ["S11", "S12", "S13", "S14"], "Greens"),
    "other": ("Other configurations", [], "Greys"),
}
CSV_COLUMNS = ("config", "group", "engine", "measurement", "signal", "kind", "name", "measured_time_s",
               "measured_mm", "simulated_time_s", "simulated_mm", "amplitude_error_mm", "timing_error_s",
               "rms_error_mm", "phase_start_s", "phase_end_s", "status")


def group_of(name: str) -> str:
    for key, (_, names, _) in GROUPS.items():
        if name in names:
            return key
    return "other"


def _run(job: tuple[Config, str, float | None]) -> DropResult:
    config, engine, duration = job
    native.expect_many()  # a study's runs repay loading the compiled laws
    return run_drop(config, engine, duration=duration)


def _run_all(jobs, workers, progress):
    if not jobs:
        return []
    workers = min(workers or os.cpu_count() or 1, len(jobs))  # never more processes than jobs
    results = []
    # (a pool ends its workers at once when the block is left on an interrupt or an error)
    with process_pool(workers) if workers > 1 and len(jobs) > 1 else contextlib.nullcontext() as pool:
        mapped = pool.map(_run, jobs) if pool is not None else map(_run, jobs)
        for done, result in enumerate(mapped, 1):
            results.append(result)
            if progress is not None:
                progress(f"[{done}/{len(jobs)}] {result.name} {result.engine}: {result.wall_time_s:.2f} s")
    return results


@dataclass
class Validation:
    """Configurations against one measurement: a sled record, or each configuration's ODE run."""

    configs: list[str]
    engine: str
    reference_engine: str | None
    record: sled_data.SledRecord | None
    results: dict[str, DropResult]        # name -> the run under test
    references: dict[str, DropResult]     # name -> its ODE run (reference mode only)
    metrics: dict[str, Metrics]
    duration_s: float | None
    measured_events: Events | None = None  # data mode: the record's events
    notes: list[str] = field(default_factory=list)

    @property
    def measurement(self) -> str:
        if self.reference_engine:
            return f"{self.reference_engine} reference run of each configuration"
        return self.record.name if self.record else "record"

    # -- numbers ---------------------------------------------------------------------------------
    def rows(self) -> list[dict]:
        return [row for name in self.configs for row in self.metrics[name].rows()]

    def amplitude_errors(self) -> dict[str, dict[str, dict[str, float | None]]]:
        """``[config][signal][event]`` -> simulated - measured (mm), None when an event is missing."""
        return {n: self.metrics[n].amplitude_errors() for n in self.configs}

    def summary(self) -> dict:
        from mtbmj._package import __version__

        data = {
            "mtbmj_version": __version__,
            "measurement": self.measurement,
            "engine": self.engine,
            "reference_engine": self.reference_engine,
            "duration_s": self.duration_s,
            "sign_convention": "error = simulated - measured; positive amplitude error over-predicts the "
                               "displacement, positive timing error is late",
            "record": self.record.info() if self.record else None,
            "measured_events": self.measured_events.to_dict() if self.measured_events else None,
            "configs": {n: self.metrics[n].to_dict() for n in self.configs},
            "end_of_travel": self.end_of_travel(),
            "notes": list(self.notes),
        }
        return data

    def end_of_travel(self) -> dict[str, dict]:
        """Each configuration's run under test: its end-of-travel report (``mtbmj.readout.endtravel``)."""
        keys = ("travel_mm", "travel_used_mm", "travel_used_percent", "travel_remaining_mm", "bottomed_out",
                "bumper", "hard_stop", "rim_strikes")
        return {n: {k: self.results[n].summary[k] for k in keys} for n in self.configs}

    def envelope_lines(self) -> list[str]:
        """One phrase per configuration whose run reached the bumper, the hard stop or the rim."""
        from mtbmj.readout.endtravel import line

        return [f"{n} {line(self.results[n].summary)[2:]}" for n in self.configs if line(self.results[n].summary)]

    def csv_bytes(self) -> bytes:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(CSV_COLUMNS)
        for row in self.rows():
            writer.writerow(["" if row[c] is None else (f"{row[c]:.6g}" if isinstance(row[c], float)
                                                        else output.spreadsheet_text(row[c])) for c in CSV_COLUMNS])
        return buffer.getvalue().encode()

    # -- figures ---------------------------------------------------------------------------------
    def _colours(self) -> dict[str, tuple]:
        import matplotlib

        colours = {}
        for key, (_, _, cmap_name) in GROUPS.items():
            members = [n for n in self.configs if group_of(n) == key]
            cmap = matplotlib.colormaps[cmap_name]
            for i, name in enumerate(members):
                shade = 0.9 if len(members) == 1 else 0.45 + 0.5 * i / (len(members) - 1)
                colours[name] = cmap(shade)
        return colours

    def fig10(self):
        """The paper's Fig. 10: amplitude error per event, one bar per configuration, grouped
        spring (blue) / damper (red) / tire (green), panels sled, fork, tire."""
        colours = self._colours()
        order = [n for key in GROUPS for n in self.configs if group_of(n) == key]
        groups = [group_of(n) for n in order]
        # bar positions inside an event cluster, with a gap between study groups
        slots, pos = [], 0.0
        for i, g in enumerate(groups):
            if i and g != groups[i - 1]:
                pos += 0.6
            slots.append(pos)
            pos += 1.0
        span = max(pos, 1.0)
        width = 0.8 / span
        offsets = [(s - (span - 1.0) / 2.0) * width for s in slots]
        fig, axes = _subplots(3, 1, sharex=True, figsize=(max(8.0, 1.2 + 0.18 * len(order) * len(EVENTS)), 8.5))
        x = np.arange(len(EVENTS))
        for ax, s in zip(axes, SIGNALS):
            for name, off in zip(order, offsets):
                errs = self.metrics[name].amplitude_errors()[s]
                values = np.array([np.nan if errs[e] is None else errs[e] for e in EVENTS])
                ax.bar(x + off, np.nan_to_num(values), width * 0.95, color=colours[name], label=name,
                       edgecolor="black", linewidth=0.3)
                missing = np.isnan(values)
                if missing.any():
                    ax.plot((x + off)[missing], np.zeros(missing.sum()), "x", color=colours[name], ms=5, mew=1.2)
            ax.axhline(0.0, color="black", lw=0.8)
            ax.set_ylabel(f"{s} amplitude error [mm]")
            ax.grid(True, axis="y", alpha=0.3)
        axes[-1].set_xticks(x, [LABELS[e] for e in EVENTS])
        handles, labels = axes[0].get_legend_handles_labels()
        axes[0].legend(handles, labels, fontsize="small", ncol=min(len(order), 7), loc="upper left",
                       bbox_to_anchor=(0.0, 1.32 if len(order) > 7 else 1.22), frameon=False)
        what = "ODE reference" if self.reference_engine else "measurement"
        axes[-1].set_xlabel(f"event (error = {self.engine} - {what}; positive over-predicts; x = event missing)")
        return fig

    def overlay_figures(self) -> dict[str, object]:
        """Measured and simulated histories: one figure per study group (data mode) or per
        configuration (reference mode); the measurement black dash-dot as in the paper."""
        colours = self._colours()
        figures = {}
        if self.reference_engine:
            for name in self.configs:
                fig, axes = _subplots(3, 1, sharex=True, figsize=(8, 7.5))
                ref = self.references[name].signals
                _plot(axes, ref, f"{name} {self.reference_engine} (reference)", color="black", lw=1.2, ls="-.")
                _plot(axes, self.results[name].signals, f"{name} {self.engine}", color=colours[name], lw=1.0)
                _mark(axes, self.metrics[name].measured)
                fig.suptitle(f"{name}: {self.engine} against the {self.reference_engine} reference")
                figures[f"overlay_{_safe(name)}.png"] = fig
            return figures
        measured = self.record.signals(start_s=-0.01, end_s=self.duration_s)
        for key, (title, _, _) in GROUPS.items():
            members = [n for n in self.configs if group_of(n) == key]
            if not members:
                continue
            fig, axes = _subplots(3, 1, sharex=True, figsize=(8, 7.5))
            _plot(axes, measured, "measured" + (" (synthetic)" if self.record.synthetic else ""),
                  color="black", lw=1.2, ls="-.")
            for name in members:
                _plot(axes, self.results[name].signals, f"{name} {self.engine}", color=colours[name], lw=1.0)
            _mark(axes, self.measured_events)
            fig.suptitle(f"{title}: {self.engine} against {Path(self.record.name).name}")
            figures[f"overlay_{key}.png"] = fig
        return figures

    # -- files -----------------------------------------------------------------------------------
    def files(self) -> dict[str, bytes]:
        """Everything ``write`` puts in an output directory, rendered in memory first."""
        images = {"fig10_amplitude_errors.png": _png(self.fig10())}
        for name, fig in self.overlay_figures().items():
            images[name] = _png(fig)
        files = dict(images)
        files["validation_metrics.csv"] = self.csv_bytes()
        files["validation_summary.json"] = output.json_bytes(_jsonable(self.summary()))
        files["validation_report.html"] = self.html(images).encode()
        return files

    def write(self, out_dir: str | Path) -> list[Path]:
        return output.write_atomically(out_dir, self.files())

    def html(self, images: Mapping[str, bytes]) -> str:
        return _html(self, images)


# -- running -------------------------------------------------------------------------------------
def run_validation(data, configs: Sequence, reference_engine: str | None = None, engine: str = "mujoco",
                   duration: float | None = None, *, overrides=None, workers: int | None = None,
                   sled_offset_mm: float = 0.0, fork_offset_mm: float = 0.0, touch_s: float | None = None,
                   progress: Callable[[str], None] | None = None) -> Validation:
    """Run ``configs`` (preset names, TOML paths or ``Config``) on ``engine`` and compare each with
    the measurement: the sled record ``data`` (a path or a ``SledRecord``), or, with
    ``reference_engine="ode"``, the ODE run of the same configuration (``data`` may then be None;
    given, it only sets the default duration). ``duration``: simulated time after touch (default:
    the record's length after touch, or the configuration's own). ``touch_s``: time zero on the
    record's clock (default: found by ``mtbmj.measured.time_zero``). Runs go to a process pool."""
    if engine not in ENGINES:
        raise ConfigError(f"engine: {engine!r} is not one of {', '.join(ENGINES)}")
    if reference_engine is not None:
        if reference_engine not in ENGINES:
            raise ConfigError(f"reference: {reference_engine!r} is not one of {', '.join(ENGINES)}")
        if reference_engine == engine:
            raise ConfigError(f"reference: the engine under test is already {engine}; nothing to compare")
    if duration is not None and not duration > 0:
        raise ConfigError(f"duration: must be positive, got {duration}")
    if not configs:
        raise ConfigError("validate: no configurations given")
    record = None
    if data is not None:
        if isinstance(data, sled_data.SledRecord):
            record = data
        else:
            record = sled_data.read_sled(data, sled_offset_mm=sled_offset_mm, fork_offset_mm=fork_offset_mm,
                                         touch_s=touch_s) \
                if isinstance(data, (str, Path)) else sled_data.load(data, touch_s=touch_s)
    elif reference_engine is None:
        raise ConfigError("validate: no sled data given (a record file, or reference_engine='ode')")
    if duration is None and record is not None:
        duration = round(record.duration_s, 6)
    resolved = [resolve(c, overrides) for c in configs]
    names = _unique([c.name for c in resolved])
    resolved = [Config(n, c.values, c.sources) for n, c in zip(names, resolved)]
    jobs = [(c, engine, duration) for c in resolved]
    if reference_engine:
        jobs += [(c, reference_engine, duration) for c in resolved]
    runs = _run_all(jobs, workers, progress)
    results = {r.name: r for r in runs if r.engine == engine}
    references = {r.name: r for r in runs if r.engine == reference_engine} if reference_engine else {}
    metrics, notes = {}, []
    measured_events = None
    if reference_engine:
        for name in names:
            metrics[name] = compare(references[name].signals, results[name].signals, name,
                                    group=group_of(name), engine=engine, measurement=reference_engine)
        if record is not None:
            notes.append(f"the record {record.name} only set the duration; the measurement is the "
                         f"{reference_engine} run of each configuration")
    else:
        end = duration if duration is not None else record.duration_s
        measured = record.signals(0.0, end)
        measured_events = detect(measured)
        for name in names:
            metrics[name] = compare(measured, results[name].signals, name, measured_events=measured_events,
                                    group=group_of(name), engine=engine, measurement="data")
        if record.synthetic:
            notes.append("the record is SYNTHETIC (marked so in its header), not a measurement")
    return Validation(configs=names, engine=engine, reference_engine=reference_engine, record=record,
                      results=results, references=references, metrics=metrics, duration_s=duration,
                      measured_events=measured_events, notes=notes)


def write_validation(out_dir: str | Path, validation: Validation) -> list[Path]:
    return validation.write(out_dir)


# -- helpers -------------------------------------------------------------------------------------
def _unique(names: list[str]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n}#{seen[n]}")
    return out


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name)


def _subplots(rows: int, cols: int, figsize, **kwargs):
    """A figure of its own (object API: no pyplot, the user's backend untouched) and its axes."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.subplots(rows, cols, **kwargs)


def _png(fig) -> bytes:
    from mtbmj.readout.quicklook import png

    return png(fig, dpi=100)


def _plot(axes, signals, label, **kw):
    for ax, s in zip(axes, SIGNALS):
        ax.plot(signals["time_s"], signals[f"{s}_mm"], label=label, **kw)
        ax.set_ylabel(f"{s} [mm]")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time after tire touch [s]")
    axes[0].legend(fontsize="small", ncol=2)


def _mark(axes, events: Events | None):
    if events is None:
        return
    for ax, s in zip(axes, SIGNALS):
        for e in EVENTS:
            ev = events.get(s, e)
            if ev is not None:
                ax.plot(ev.time_s, ev.value_mm, "o", mfc="none", mec="black", ms=6)


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if np.isfinite(v) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def _fmt(value, scale=1.0, digits=2) -> str:
    return "&ndash;" if value is None else f"{value * scale:+.{digits}f}"


CSS = """
body{font-family:sans-serif;margin:1.5em auto;max-width:1100px;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em}
table{border-collapse:collapse;font-size:0.8em;margin:0.5em 0}
th,td{border:1px solid #bbb;padding:2px 5px;text-align:right}th{background:#eee}
td.l,th.l{text-align:left}.warn{background:#fff3cd;border:1px solid #e0c36b;padding:0.5em 0.8em}
img{max-width:100%;height:auto;display:block;margin:0.5em 0}.small{font-size:0.85em;color:#555}
"""


def _html(v: Validation, images: Mapping[str, bytes]) -> str:
    from mtbmj._package import __version__

    e = html.escape

    def img(name, alt):
        data = base64.b64encode(images[name]).decode()
        return f'<img id="{e(name)}" alt="{e(alt)}" src="data:image/png;base64,{data}">'

    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>mtbmj validation: {e(v.measurement)}</title>", f"<style>{CSS}</style></head><body>",
             "<h1>mtbmj validation</h1>"]
    meta = [("measurement", v.measurement), ("engine under test", v.engine),
            ("configurations", ", ".join(v.configs)),
            ("duration after touch", "configuration default" if v.duration_s is None else f"{v.duration_s:.3f} s"),
            ("mtbmj", __version__)]
    if v.record is not None and not v.reference_engine:
        info = v.record.info()
        meta += [("touch (time zero) on the record's clock", f"{info['touch_in_file_s']:.4f} s"),
                 ("how time zero was found", info["time_zero"]),
                 ("sample rate", f"{info['sample_rate_Hz']:.0f} Hz"),
                 ("sensor noise (std)", ", ".join(f"{k} {val:.3f} mm" for k, val in info["noise_mm"].items())),
                 ("tire", info["tire"])]
    parts.append('<table id="meta">' + "".join(f'<tr><th class="l">{e(k)}</th><td class="l">{e(str(val))}</td></tr>'
                                                for k, val in meta) + "</table>")
    for note in v.notes:
        parts.append(f'<p class="warn">{e(note)}</p>')
    if v.record is not None and v.record.comments and not v.reference_engine:
        parts.append('<p class="small">Record header: ' + e(" ".join(v.record.comments)) + "</p>")
    parts.append("<h2>Amplitude errors at the key events (the paper's Fig. 10)</h2>")
    parts.append('<p class="small">error = simulated &minus; measured: positive over-predicts the displacement. '
                 "Bars grouped by study: fork spring S1&ndash;S7 blue, fork damping S8&ndash;S10 red, "
                 "tire S11&ndash;S14 green, others grey; &times; marks an event missing in the model or the "
                 "measurement.</p>")
    parts.append(img("fig10_amplitude_errors.png", "Fig. 10: amplitude errors per event"))

    # amplitude-error table
    head = "".join(f"<th>{e(s)} {e(LABELS[ev])}</th>" for s in SIGNALS for ev in EVENTS)
    rows = []
    for name in v.configs:
        m = v.metrics[name]
        amp = m.amplitude_errors()
        cells = "".join(f"<td>{_fmt(amp[s][ev])}</td>" for s in SIGNALS for ev in EVENTS)
        rows.append(f'<tr><th class="l">{e(name)}</th>{cells}</tr>')
    parts.append("<h2>Amplitude error [mm]</h2>")
    parts.append(f'<table id="metrics"><tr><th class="l">config</th>{head}</tr>{"".join(rows)}</table>')
    rows = []
    for name in v.configs:
        tim = v.metrics[name].timing_errors()
        cells = "".join(f"<td>{_fmt(tim[s][ev], 1e3, 1)}</td>" for s in SIGNALS for ev in EVENTS)
        rows.append(f'<tr><th class="l">{e(name)}</th>{cells}</tr>')
    parts.append("<h2>Timing error [ms] (positive: the model is late)</h2>")
    parts.append(f'<table id="timing"><tr><th class="l">config</th>{head}</tr>{"".join(rows)}</table>')
    head = "".join(f"<th>{e(s)} {e(p)}</th>" for s in SIGNALS for p in PHASES)
    rows = []
    for name in v.configs:
        rms = v.metrics[name].rms_mm
        cells = "".join("<td>&ndash;</td>" if rms[s][p] is None else f"<td>{rms[s][p]:.2f}</td>"
                        for s in SIGNALS for p in PHASES)
        rows.append(f'<tr><th class="l">{e(name)}</th>{cells}</tr>')
    parts.append("<h2>RMS error [mm] over the record and per phase (impact, air, landing/settling)</h2>")
    parts.append(f'<table id="rms"><tr><th class="l">config</th>{head}</tr>{"".join(rows)}</table>')
    rows = []
    for name in v.configs:
        m = v.metrics[name]
        flags = "; ".join(m.simulated.flags) or "textbook pattern"
        rows.append(f'<tr><th class="l">{e(name)}</th><td class="l">{"yes" if m.simulated.lifts_off else "never"}</td>'
                    f'<td class="l">{"yes" if m.simulated.at_rest else "no"}</td><td class="l">{e(flags)}</td></tr>')
    parts.append("<h2>Response pattern of each configuration</h2>")
    if v.measured_events is not None:
        parts.append('<p class="small">Measurement: ' + e("; ".join(v.measured_events.flags) or "textbook pattern")
                     + (f"; lift-off {v.measured_events.lift_off_s:.3f} s" if v.measured_events.lifts_off else "")
                     + (f", landing {v.measured_events.landing_s:.3f} s" if v.measured_events.lands else "") + "</p>")
    parts.append('<table id="flags"><tr><th class="l">config</th><th class="l">lifts off</th>'
                 f'<th class="l">at rest</th><th class="l">notes</th></tr>{"".join(rows)}</table>')
    parts.append("<h2>Measured and simulated histories</h2>")
    parts.append('<p class="small">Measurement black dash-dot, circles at its events; t = 0 at tire touch.</p>')
    for name in images:
        if name.startswith("overlay_"):
            parts.append(img(name, name[:-4].replace("_", " ")))
    parts.append('<p class="small">Files beside this report: validation_metrics.csv (every metric), '
                 "validation_summary.json, the PNG figures.</p></body></html>")
    return "\n".join(parts) + "\n"


__all__ = ["Validation", "run_validation", "write_validation", "GROUPS", "group_of"]

"""The quick-look figure every ``drop`` and ``roll`` writes (``quicklook.png``): fork travel
against its travel and bumper, the tire against its rim, and the forces, with every bumper
engagement, hard-stop contact and rim strike (``mtbmj.readout.endtravel``) shaded where it happens.
Engine-rate signals, so the deepest millimetre drawn is the one reported."""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from mtbmj.readout.endtravel import episodes

OFF_SCALE = 4.0  # forces beyond 4 x the 99th percentile are named, not drawn to scale
SHADES = {"bumper": ("tab:orange", "bumper"), "hard_stop": ("tab:red", "hard stop"),
          "rim_strikes": ("tab:red", "rim strike")}

# The smallest change of each quantity a figure draws as a change: a signal that varies by less
# (a pitch held at 1.0439 deg give or take 1e-9, a speed of 5.000-5.001 m/s) is round-off and is
# drawn as a constant with its value, and no axis spans less than MIN_SPAN of them.
RESOLUTION = {"mm": 0.01, "deg": 0.01, "m/s": 0.01, "m/s²": 0.01, "N": 1.0, "kN": 0.001}
MIN_SPAN = 10  # resolutions: a change of one resolution is at most a tenth of the panel's height
# A signal with more cycles than this in a panel (about 600 pixels wide) draws as a solid band:
# the figure adds a zoom panel on the run's peak
DENSE_CYCLES = 60
ZOOM_CYCLES = (3, 9)  # cycles before and after the peak in the zoom panel


def figure_class():
    """matplotlib's ``Figure`` (the object API: the caller's backend is left alone), imported so
    that a home matplotlib cannot write to (a read-only image, a service user) costs no line on
    stderr: matplotlib then keeps its caches in a temporary folder it removes at exit, and says so
    through its logger, which is quietened for the import only."""
    import logging

    logger = logging.getLogger("matplotlib")
    quiet = logging.NullHandler()
    logger.addHandler(quiet)
    try:
        from matplotlib import font_manager  # noqa: F401  (its cache folder is chosen on import)
        from matplotlib.figure import Figure
    finally:
        logger.removeHandler(quiet)
    return Figure


def decimals(resolution: float) -> int:
    """Decimals that write a value to ``resolution`` (0.01 -> 2, 1 -> 0)."""
    return max(0, int(-np.floor(np.log10(resolution) + 1e-9)))


def hold_resolution(ax, lines, unit: str, resolution: float | None = None) -> None:
    """Draw round-off as what it is: each of ``lines`` (``Line2D`` of ``ax``) that varies by less
    than ``resolution`` (by default ``RESOLUTION[unit]``) becomes a flat line at its mean, its
    legend label saying ``constant <value> <unit>``; the axis shows no offset (no
    ``1e-9+1.0439``) and spans at least ``MIN_SPAN`` resolutions."""
    res = RESOLUTION[unit] if resolution is None else float(resolution)
    digits = decimals(res)
    drawn = []
    for line in lines:
        y = np.asarray(line.get_ydata(), float)
        finite = y[np.isfinite(y)]
        if not finite.size:
            continue
        if float(np.ptp(finite)) < res:
            level = round(float(np.mean(finite)), digits) + 0.0  # + 0.0: no "-0.00"
            line.set_ydata(np.where(np.isfinite(y), level, np.nan))
            text = f"constant {level:.{digits}f} {unit}"
            label = line.get_label()
            line.set_label(f"{label}, {text}" if label and not label.startswith("_") else text)
            finite = np.array([level])
        drawn.append(finite)
    ax.ticklabel_format(axis="y", useOffset=False)
    if not drawn:
        return
    ax.relim()
    ax.autoscale_view()
    low, high = ax.get_ylim()
    span = MIN_SPAN * res
    if high - low < span:
        values = np.concatenate(drawn)
        mid = 0.5 * (float(np.min(values)) + float(np.max(values)))
        ax.set_ylim(mid - 0.5 * span, mid + 0.5 * span)


def mark_peak(ax, time: np.ndarray, signal: np.ndarray, color: str, unit: str = "mm", what: str = "peak",
              digits: int = 1):
    """An open marker on the largest value of ``signal``, its value and time in the legend (the
    number the run is about, where the legend never covers it: see ``legend_above``). A
    ``PathCollection``, so the panel's lines stay the signals. None for a constant (within
    ``RESOLUTION[unit]``): it has no peak."""
    y = np.asarray(signal, float)
    if not np.isfinite(y).any() or np.nanmax(y) - np.nanmin(y) < RESOLUTION.get(unit, 0.0):
        return None
    i = int(np.nanargmax(y))
    ax.margins(y=max(ax.margins()[1], 0.1))  # room over the peak: its marker clear of the panel's edge
    return ax.scatter([time[i]], [y[i]], s=40, facecolors="none", edgecolors=color, linewidths=1.4, zorder=5,
                      label=f"{what} {y[i]:.{digits}f} {unit} at {time[i]:.3f} s")


def legend_above(ax, fontsize: float = 7, title: str | None = None) -> None:
    """The legend of ``ax`` in a row above it (under ``title`` if given), off the data: a legend
    inside the axes covers whatever is drawn under it, on a drop the travel peak the run is
    about."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles and not title:
        return
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextToPath

    # as many columns as fit across the axes (about the figure's width less the y-axis label)
    width_pt = ax.figure.get_figwidth() * 72.0 - 90.0
    measure = TextToPath()
    prop = FontProperties(size=fontsize)
    widths = [measure.get_text_width_height_descent(label, prop, ismath=False)[0] + 4.2 * fontsize
              for label in labels]  # the text, its handle and the spaces around it
    ncol = len(labels)
    while ncol > 1 and max(sum(widths[k:k + ncol]) for k in range(0, len(widths), ncol)) > width_pt:
        ncol -= 1
    ax.legend(handles, labels, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=max(ncol, 1), fontsize=fontsize,
              frameon=False, borderaxespad=0.15, handlelength=1.8, columnspacing=1.2, title=title,
              title_fontsize=fontsize + 0.5, alignment="left")


def dense_window(time: np.ndarray, signal: np.ndarray) -> tuple[float, float] | None:
    """The time window of a zoom panel when ``signal`` has more than ``DENSE_CYCLES`` cycles (a
    long washboard run, drawn across the page as a solid band): ``ZOOM_CYCLES`` of its cycles
    before and after its peak (kept within the run); None when the whole run reads as it is."""
    t = np.asarray(time, float)
    peaks = cycle_peaks(signal)
    if t.size < 3 or peaks.size <= DENSE_CYCLES:
        return None
    period = float(np.median(np.diff(t[peaks])))
    before, after = ZOOM_CYCLES
    width = (before + after) * period
    start = min(float(t[int(np.argmax(signal))]) - before * period, float(t[-1]) - width)
    start = max(float(t[0]), start)
    return start, min(float(t[-1]), start + width)


def zoom_panel(ax, time: np.ndarray, series: Sequence[tuple[str, np.ndarray, str]], window: tuple[float, float],
               unit: str, cycles: int | None = None) -> None:
    """The zoom panel: ``series`` (label, signal, colour) within ``window`` only (so the y-axis
    fits what is shown), the window and the run's ``cycles`` named over its legend."""
    t = np.asarray(time, float)
    inside = (t >= window[0]) & (t <= window[1])
    lines = [ax.plot(t[inside], np.asarray(y, float)[inside], color=colour, lw=1.2, label=label)[0]
             for label, y, colour in series]
    ax.set_xlim(*window)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"zoom [{unit}]")
    whole = f" ({cycles} cycles over the run: the panels above draw them as a band)" if cycles else ""
    hold_resolution(ax, lines, unit)
    ax.grid(True, alpha=0.3)
    legend_above(ax, title=f"zoom: {window[0]:.2f}-{window[1]:.2f} s around the peak{whole}")


def cycle_peaks(signal: np.ndarray) -> np.ndarray:
    """Indices of the cycles' peaks of ``signal``: maxima standing out by 5 % of its range (none
    for a constant or a signal with gaps)."""
    from scipy.signal import find_peaks

    y = np.asarray(signal, float)
    if not y.size or not np.isfinite(y).all() or float(np.ptp(y)) <= 0.0:
        return np.zeros(0, int)
    return find_peaks(y, prominence=0.05 * float(np.ptp(y)))[0]


def count_cycles(signal: np.ndarray) -> int:
    return int(cycle_peaks(signal).size)


def stacked_axes(fig, n: int, zoom: bool):
    """``n`` panels sharing the time axis, and under them a zoom panel of its own time axis when
    ``zoom`` (last in the list)."""
    gs = fig.add_gridspec(n + int(zoom), 1, height_ratios=[1.0] * n + ([1.25] if zoom else []))
    axes = [fig.add_subplot(gs[0])]
    axes += [fig.add_subplot(gs[k], sharex=axes[0]) for k in range(1, n)]
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    if zoom:
        axes.append(fig.add_subplot(gs[n]))
    return axes


def config_title(config) -> str:
    """What a configuration is, for a figure's title: a preset by its name; a file by its folder
    and name and the description it carries (``mtbmj sag`` writes ``config.toml`` with "S12 set to
    30 % sag under 80 kg", which the name alone, "config", does not say)."""
    from pathlib import Path

    from mtbmj.config import preset_names

    sources = getattr(config, "sources", ())
    last = str(sources[-1]) if sources else ""
    if not last.lower().endswith(".toml") or config.name.lower() in {n.lower() for n in preset_names()}:
        return config.name
    path = Path(last)
    where = f"{path.parent.name}/{path.name}" if path.parent.name else path.name
    description = config.values.get("description") if hasattr(config, "values") else None
    return f"{where}: {description}" if description else where


def run_title(config, headline: str, width: int = 110) -> str:
    """A quick-look's title: the run's one-line headline, under what its configuration is when
    the name alone does not say it (``config_title``)."""
    import textwrap

    what = config_title(config)
    head = textwrap.fill(headline, width)
    return head if what == config.name else f"{textwrap.fill(what, width)}\n{head}"


def _shade(ax, time: np.ndarray, signal: np.ndarray, threshold: float | None, element: str) -> int:
    if threshold is None:
        return 0
    colour, label = SHADES[element]
    runs = episodes(signal, threshold)
    for k, run in enumerate(runs):
        ax.axvspan(time[run.start], time[min(run.stop, time.size - 1)], color=colour, alpha=0.25, lw=0,
                   label=f"{label} ({len(runs)}x)" if k == 0 else None)
    return len(runs)


def figure(time_s: np.ndarray, fork_mm: np.ndarray, tire_mm: np.ndarray, forces: Mapping[str, np.ndarray],
           report: Mapping, title: str, extra: Sequence[tuple[str, np.ndarray, str]] = ()):
    """The quick-look figure: ``extra`` panels (label, signal, unit) first (e.g. the terrain),
    then fork travel (its peak marked), tire deflection and ``forces`` (name -> N); legends above
    the panels, off the data. ``report``: the run's end-of-travel report
    (``endtravel.end_of_travel``) for the lines and the shading. A run whose fork goes through
    more than ``DENSE_CYCLES`` cycles (a long washboard) gets a zoom panel on its peak, last."""
    Figure = figure_class()
    t = np.asarray(time_s, float)
    fork = np.asarray(fork_mm, float)
    tire = np.asarray(tire_mm, float)
    n = len(extra) + 3
    window = dense_window(t, fork)
    fig = Figure(figsize=(8.0, 2.0 + 1.9 * (n + (1.25 if window else 0.0))), layout="constrained")
    axes = stacked_axes(fig, n, window is not None)
    for ax, (label, signal, unit) in zip(axes, extra):
        line, = ax.plot(t, signal, color="0.3", lw=1.0)
        ax.set_ylabel(f"{label} [{unit}]")
        if unit in RESOLUTION:
            hold_resolution(ax, [line], unit)
    ax_fork, ax_tire, ax_force = axes[len(extra):n]
    travel = report["travel_mm"]
    fork_line, = ax_fork.plot(t, fork, color="tab:blue", lw=1.0, label="fork travel")
    mark_peak(ax_fork, t, fork, "tab:blue", what="fork peak")
    ax_fork.axhline(travel, color="k", lw=0.8, ls="--", label=f"full travel {travel:g} mm")
    if report.get("bumper_engages_at_mm") is not None:
        ax_fork.axhline(report["bumper_engages_at_mm"], color="tab:orange", lw=0.8, ls=":",
                        label=f"bumper from {report['bumper_engages_at_mm']:g} mm")
    _shade(ax_fork, t, fork, report.get("bumper_engages_at_mm"), "bumper")
    _shade(ax_fork, t, fork, travel, "hard_stop")
    ax_fork.set_ylim(min(0.0, float(np.min(fork))) - 2.0, max(travel, float(np.max(fork))) * 1.08)
    ax_fork.set_ylabel("fork travel [mm]")
    hold_resolution(ax_fork, [fork_line], "mm")
    tire_line, = ax_tire.plot(t, tire, color="tab:green", lw=1.0, label="tire deflection")
    ax_tire.axhline(0.0, color="0.6", lw=0.6)
    rim = report.get("rim_max_deflection_mm")
    if rim is not None:
        ax_tire.axhline(rim, color="tab:red", lw=0.8, ls="--", label=f"rim at {rim:g} mm")
    _shade(ax_tire, t, tire, rim, "rim_strikes")
    ax_tire.set_ylabel("tire [mm]\n(negative: clearance)")
    hold_resolution(ax_tire, [tire_line], "mm")
    peaks = []
    typical = 0.0
    force_lines = []
    for name, values in forces.items():
        kn = np.asarray(values, float) / 1e3
        label = name.removesuffix("_N").replace("_", " ")
        force_lines += ax_force.plot(t, kn, lw=1.0, label=label)
        peaks.append((label, float(np.max(kn)), float(np.min(kn))))
        typical = max(typical, float(np.percentile(np.abs(kn), 99.0)))
    top = max(p[1] for p in peaks)
    bottom = min(p[2] for p in peaks)
    off = []
    if typical > 0.0 and max(top, -bottom) > OFF_SCALE * typical:
        # a stop or the rim peaks at 100 kN where the ride's forces are 1-3 kN: draw the ride and
        # name the peaks, which the one-line summary reports too
        limit = OFF_SCALE * typical
        ax_force.set_ylim(max(bottom, -limit) * 1.05 if bottom < 0 else -0.05 * limit, min(top, limit) * 1.05)
        off = [f"{label} {hi:.0f} kN" for label, hi, _ in peaks if hi > limit]
    ax_force.set_ylabel("force [kN]")
    hold_resolution(ax_force, force_lines, "kN")
    if off:  # named in the legend row, off the data
        ax_force.plot([], [], ls="none", label="off scale: peaks " + ", ".join(off))
    axes[n - 1].set_xlabel("time [s]")
    if window is not None:
        series = [(label, signal, "0.3") for label, signal, unit in extra if unit == "mm"]
        series += [("fork travel", fork, "tab:blue"), ("tire deflection", tire, "tab:green")]
        zoom_panel(axes[n], t, series, window, "mm", cycles=count_cycles(fork))
        for ax in axes[:n]:
            ax.axvspan(*window, color="0.5", alpha=0.15, lw=0, label="zoomed below" if ax is ax_fork else None)
    for ax in axes[:n]:
        ax.grid(True, alpha=0.3)
        legend_above(ax)
    fig.suptitle(title, fontsize=9)
    return fig


def plain_text(fig):
    """``fig`` with every text in it drawn as written: a configuration, bike, terrain or folder
    name with ``$...$`` in it would otherwise be parsed as mathtext (a traceback after the whole run
    for an unbalanced one, a formula for a balanced one). No figure of mtbmj uses mathtext."""
    from matplotlib.text import Text

    for text in fig.findobj(Text):
        text.set_parse_math(False)
    return fig


def png(fig, dpi: int = 90) -> bytes:
    import io

    buffer = io.BytesIO()
    plain_text(fig).savefig(buffer, format="png", dpi=dpi)
    return buffer.getvalue()


__all__ = ["figure", "png", "plain_text"]

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
    then fork travel, tire deflection and ``forces`` (name -> N). ``report``: the run's
    end-of-travel report (``endtravel.end_of_travel``) for the lines and the shading."""
    Figure = figure_class()
    t = np.asarray(time_s, float)
    n = len(extra) + 3
    fig = Figure(figsize=(8.0, 2.0 + 1.9 * n), layout="constrained")
    axes = fig.subplots(n, 1, sharex=True)
    for ax, (label, signal, unit) in zip(axes, extra):
        ax.plot(t, signal, color="0.3", lw=1.0)
        ax.set_ylabel(f"{label} [{unit}]")
    ax_fork, ax_tire, ax_force = axes[len(extra):]
    travel = report["travel_mm"]
    ax_fork.plot(t, fork_mm, color="tab:blue", lw=1.0, label="fork travel")
    ax_fork.axhline(travel, color="k", lw=0.8, ls="--", label=f"full travel {travel:g} mm")
    if report.get("bumper_engages_at_mm") is not None:
        ax_fork.axhline(report["bumper_engages_at_mm"], color="tab:orange", lw=0.8, ls=":",
                        label=f"bumper from {report['bumper_engages_at_mm']:g} mm")
    _shade(ax_fork, t, np.asarray(fork_mm, float), report.get("bumper_engages_at_mm"), "bumper")
    _shade(ax_fork, t, np.asarray(fork_mm, float), travel, "hard_stop")
    ax_fork.set_ylim(min(0.0, float(np.min(fork_mm))) - 2.0, max(travel, float(np.max(fork_mm))) * 1.08)
    ax_fork.set_ylabel("fork travel [mm]")
    ax_tire.plot(t, tire_mm, color="tab:green", lw=1.0, label="tire deflection")
    ax_tire.axhline(0.0, color="0.6", lw=0.6)
    rim = report.get("rim_max_deflection_mm")
    if rim is not None:
        ax_tire.axhline(rim, color="tab:red", lw=0.8, ls="--", label=f"rim at {rim:g} mm")
    _shade(ax_tire, t, np.asarray(tire_mm, float), rim, "rim_strikes")
    ax_tire.set_ylabel("tire [mm]\n(negative: clearance)")
    peaks = []
    typical = 0.0
    for name, values in forces.items():
        kn = np.asarray(values, float) / 1e3
        label = name.removesuffix("_N").replace("_", " ")
        ax_force.plot(t, kn, lw=1.0, label=label)
        peaks.append((label, float(np.max(kn)), float(np.min(kn))))
        typical = max(typical, float(np.percentile(np.abs(kn), 99.0)))
    top = max(p[1] for p in peaks)
    bottom = min(p[2] for p in peaks)
    if typical > 0.0 and max(top, -bottom) > OFF_SCALE * typical:
        # a stop or the rim peaks at 100 kN where the ride's forces are 1-3 kN: draw the ride and
        # name the peaks, which the one-line summary reports too
        limit = OFF_SCALE * typical
        ax_force.set_ylim(max(bottom, -limit) * 1.05 if bottom < 0 else -0.05 * limit, min(top, limit) * 1.05)
        off = [f"{label} {hi:.0f} kN" for label, hi, _ in peaks if hi > limit]
        ax_force.text(0.01, 0.95, "off scale: peaks " + ", ".join(off), transform=ax_force.transAxes,
                      fontsize=7, va="top", color="tab:red")
    ax_force.set_ylabel("force [kN]")
    ax_force.set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="upper right", ncol=2)
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

"""The figure a sweep over one or two keys writes (``sweep.png``): the main outputs against the
varied key (one key: lines), or over the two keys (a grid: heat maps; sampled points: coloured
dots). Variants that failed are left out (and counted in the title); a sweep over three or more
keys draws no figure (its table is the place to look). The axes of a grid are ticked at the values
run and no others, each heat-map cell centred on its value with the value written in it; counts
(bumper engagements, rim strikes) get a colour per whole number and a colour bar of whole numbers."""
from __future__ import annotations

from typing import Sequence

import numpy as np

# (column, label with unit): what a rider or tuner reads first
MAIN_OUTPUTS = (
    ("max_fork_mm", "fork peak [mm]"),
    ("travel_remaining_mm", "travel remaining [mm]"),
    ("max_tire_mm", "tire peak [mm]"),
    ("bumper_count", "bumper engagements"),
    ("rim_strikes_count", "rim strikes"),
    ("energy_dissipated_J", "energy dissipated [J]"),
)


MAX_TICKED = 12  # values on an axis that each get a tick label (more: every k-th is labelled)
MAX_WRITTEN = 100  # heat-map cells that get their value written in them


def sweep_figure(table, keys: Sequence[str], title: str = "", main_outputs=MAIN_OUTPUTS):
    """The figure for a sweep whose varied keys are ``keys`` (one or two), or None; ``main_outputs``
    the (column, label) drawn (a bike sweep draws its own; a column ending in ``_count`` is a count)."""
    if not 1 <= len(keys) <= 2:
        return None
    from matplotlib.ticker import MaxNLocator

    from mtbmj.readout.quicklook import figure_class

    Figure = figure_class()

    ok = table[table["status"] == "ok"]
    failed = int(len(table) - len(ok))
    outputs = [(c, label) for c, label in main_outputs if c in ok.columns]
    if ok.empty or not outputs:
        return None
    cols = 3 if len(keys) == 2 else 2
    rows = -(-len(outputs) // cols)
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    x = ok[keys[0]].to_numpy(float)
    for ax, (column, label) in zip(axes, outputs):
        values = ok[column].to_numpy(float)
        count = column.endswith("_count")
        heading = label
        if count and np.isfinite(values).any() and not np.nanmax(np.abs(values)):
            heading = f"{label} (none in any variant)"
        if len(keys) == 1:
            order = np.argsort(x)
            ax.plot(x[order], values[order], "o-", ms=3, lw=1.2)
            ax.set_xlabel(keys[0])
            ax.set_ylabel(label)
            if heading != label:
                ax.set_title(heading, fontsize=9)
            ax.grid(True, alpha=0.3)
            _ticks_at(ax.xaxis, np.unique(x))
            if column == "travel_remaining_mm":
                ax.axhline(0.0, color="tab:red", lw=0.8, ls="--")
            if count:
                ax.yaxis.set_major_locator(MaxNLocator(integer=True))
                ax.set_ylim(np.nanmin(values) - 0.5, max(np.nanmax(values), np.nanmin(values) + 1.0) + 0.5)
            continue
        y = ok[keys[1]].to_numpy(float)
        xs, ys = np.unique(x), np.unique(y)
        colours = _count_colours(values) if count else {"cmap": "viridis"}
        if xs.size * ys.size == len(ok) and xs.size > 1 and ys.size > 1:  # a full grid: a heat map
            grid = np.full((ys.size, xs.size), np.nan)
            grid[np.searchsorted(ys, y), np.searchsorted(xs, x)] = values
            mesh = ax.pcolormesh(_edges(xs), _edges(ys), grid, shading="flat", **colours)
            _ticks_at(ax.xaxis, xs)
            _ticks_at(ax.yaxis, ys)
            if grid.size <= MAX_WRITTEN:
                _write_cells(ax, mesh, xs, ys, grid, count)
        else:  # sampled points
            mesh = ax.scatter(x, y, c=values, s=14, **colours)
        bar = fig.colorbar(mesh, ax=ax, label=label)
        if count:
            levels = colours["norm"].boundaries[:-1] + 0.5
            bar.set_ticks(levels if levels.size <= MAX_TICKED else
                          MaxNLocator(integer=True).tick_values(levels[0], levels[-1]))
            bar.ax.yaxis.set_major_formatter("{x:.0f}")
            bar.minorticks_off()
        ax.set_xlabel(keys[0])
        ax.set_ylabel(keys[1])
        ax.set_title(heading, fontsize=9)
    for ax in axes[len(outputs):]:
        ax.set_visible(False)
    note = f" ({failed} failed variants left out)" if failed else ""
    fig.suptitle(f"{title}{note}", fontsize=10)
    return fig


def _ticks_at(axis, values: np.ndarray) -> None:
    """Ticks at exactly the values run (every k-th labelled when there are many), none between."""
    from matplotlib.ticker import NullLocator

    step = max(1, -(-values.size // MAX_TICKED))
    axis.set_ticks(values, [f"{v:g}" if k % step == 0 else "" for k, v in enumerate(values)])
    axis.set_minor_locator(NullLocator())


def _count_colours(values: np.ndarray) -> dict:
    """A colour per whole number from the lowest count to the highest (one colour when every
    variant counts the same)."""
    from matplotlib import colormaps
    from matplotlib.colors import BoundaryNorm

    finite = values[np.isfinite(values)]
    low = float(np.floor(finite.min())) if finite.size else 0.0
    high = float(np.ceil(finite.max())) if finite.size else 0.0
    boundaries = np.arange(low - 0.5, high + 1.0, 1.0)
    cmap = colormaps["viridis"].resampled(max(1, boundaries.size - 1))
    return {"cmap": cmap, "norm": BoundaryNorm(boundaries, cmap.N)}


def _write_cells(ax, mesh, xs, ys, grid, count: bool) -> None:
    """Each cell's value at its centre, dark on light colours and light on dark."""
    for i, yv in enumerate(ys):
        for j, xv in enumerate(xs):
            v = grid[i, j]
            if not np.isfinite(v):
                continue
            r, g, b, _ = mesh.cmap(mesh.norm(v))
            ink = "k" if 0.299 * r + 0.587 * g + 0.114 * b > 0.5 else "w"
            ax.text(xv, yv, f"{v:.0f}" if count else f"{v:.4g}", ha="center", va="center", fontsize=7, color=ink)


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around sorted centres (half-way between neighbours, mirrored at the ends)."""
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate(([2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]))


__all__ = ["sweep_figure", "MAIN_OUTPUTS"]

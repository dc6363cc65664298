"""The figure a sweep over one or two keys writes (``sweep.png``): the main outputs against the
varied key (one key: lines), or over the two keys (a grid: heat maps; sampled points: coloured
dots). Variants that failed are left out (and counted in the title); a sweep over three or more
keys draws no figure (its table is the place to look)."""
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


def sweep_figure(table, keys: Sequence[str], title: str = ""):
    """The figure for a sweep whose varied keys are ``keys`` (one or two), or None."""
    if not 1 <= len(keys) <= 2:
        return None
    from matplotlib.ticker import MaxNLocator

    from mtbmj.readout.quicklook import figure_class

    Figure = figure_class()

    ok = table[table["status"] == "ok"]
    failed = int(len(table) - len(ok))
    outputs = [(c, label) for c, label in MAIN_OUTPUTS if c in ok.columns]
    if ok.empty or not outputs:
        return None
    cols = 3 if len(keys) == 2 else 2
    rows = -(-len(outputs) // cols)
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    x = ok[keys[0]].to_numpy(float)
    for ax, (column, label) in zip(axes, outputs):
        values = ok[column].to_numpy(float)
        if len(keys) == 1:
            order = np.argsort(x)
            ax.plot(x[order], values[order], "o-", ms=3, lw=1.2)
            ax.set_xlabel(keys[0])
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
            if column == "travel_remaining_mm":
                ax.axhline(0.0, color="tab:red", lw=0.8, ls="--")
            if column.endswith("_count"):
                ax.yaxis.set_major_locator(MaxNLocator(integer=True))
            continue
        y = ok[keys[1]].to_numpy(float)
        xs, ys = np.unique(x), np.unique(y)
        if xs.size * ys.size == len(ok) and xs.size > 1 and ys.size > 1:  # a full grid: a heat map
            grid = np.full((ys.size, xs.size), np.nan)
            grid[np.searchsorted(ys, y), np.searchsorted(xs, x)] = values
            mesh = ax.pcolormesh(_edges(xs), _edges(ys), grid, shading="flat", cmap="viridis")
        else:  # sampled points
            mesh = ax.scatter(x, y, c=values, s=14, cmap="viridis")
        bar = fig.colorbar(mesh, ax=ax, label=label)
        if column.endswith("_count"):
            bar.locator = MaxNLocator(integer=True)
            bar.update_ticks()
        ax.set_xlabel(keys[0])
        ax.set_ylabel(keys[1])
        ax.set_title(label, fontsize=9)
    for ax in axes[len(outputs):]:
        ax.set_visible(False)
    note = f" ({failed} failed variants left out)" if failed else ""
    fig.suptitle(f"{title}{note}", fontsize=10)
    return fig


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around sorted centres (half-way between neighbours, mirrored at the ends)."""
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate(([2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]))


__all__ = ["sweep_figure", "MAIN_OUTPUTS"]

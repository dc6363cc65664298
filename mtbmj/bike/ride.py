"""A simulated bike run beside a real ride: the travel histograms of both ends, each in % of its
own travel, on the same axes (``mtbmj bike ... --ride FILE.SST`` or ``--ride example``).

The real ride is a Sufni SST recording read by ``mtbmj.ride.telemetry`` (the shipped example is a
ride of the SST preset's bike, a Clash 2022: its fork travel, shock stroke and leverage curve are
the preset's). What can agree: the share of travel each end spends its time in (sag, how deep the
terrain pushes), the front/rear balance (mean travel of each end in % of its travel) and the
bottom-outs. What cannot: the real trail, speed and rider are unknown, and the simulated terrain is
one feature of the library, not that trail; the comparison shows a model's range against a ride's,
not a fit.
"""
from __future__ import annotations

import numpy as np


def compare(result, sst: str = "example", bin_percent: float = 5.0) -> dict:
    """Travel histograms and balance of ``result`` (a ``BikeResult``) and of the SST ride ``sst``
    (a path, or "example" for the shipped ride), JSON-ready."""
    from mtbmj.ride import metrics, telemetry

    path = telemetry.example_path() if sst == "example" else sst
    ride = telemetry.read_sst(path)
    raw = result.raw
    sim_front_max = result.summary["front"]["travel_mm"]
    sim_rear_max = result.summary["rear_wheel_travel_mm"]
    out = {"ride": ride.name, "ride_duration_s": ride.duration_s, "simulation": f"bike {result.name} over "
           f"{result.scenario} at {result.summary['speed_m_per_s']:g} m/s", "bin_percent": bin_percent}
    for end, sim, sim_max, real, real_max in (
            ("front", raw["front_travel_mm"], sim_front_max, ride.fork_mm, ride.fork_max_mm),
            ("rear", raw["rear_travel_mm"], sim_rear_max, ride.rear_mm, ride.rear_max_mm)):
        entry = {"simulated": metrics.travel_histogram(sim, sim_max, bin_percent).to_dict(),
                 "simulated_mean_percent": float(np.mean(sim) / sim_max * 100.0)}
        if real is not None:
            entry["ride"] = metrics.travel_histogram(real, real_max, bin_percent).to_dict()
            entry["ride_mean_percent"] = float(np.mean(real) / real_max * 100.0)
        out[end] = entry
    return out


def figure(comparison: dict):
    """Travel histograms of both ends: simulated and ridden, each in % of its own travel."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 6), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    for ax, end, title in zip(axes, ("front", "rear"), ("front (fork)", "rear (wheel)")):
        entry = comparison[end]
        for key, label, style in (("simulated", comparison["simulation"], {"alpha": 0.6}),
                                  ("ride", f"ride {comparison['ride']}", {"alpha": 0.5})):
            if key not in entry:
                continue
            h = entry[key]
            edges = np.asarray(h["bin_edges_percent"])
            ax.bar(edges[:-1], h["time_percent"], width=np.diff(edges), align="edge",
                   label=f"{label} (mean {entry[key + '_mean_percent']:.0f} % of {h['travel_max_mm']:.0f} mm)",
                   **style)
        ax.set_ylabel(f"{title}\n% of time")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1].set_xlabel("travel, % of each end's own travel")
    fig.suptitle("simulated bike and a real ride: travel histograms (the real trail is not the simulated one)",
                 fontsize=9)
    return fig


def png(comparison: dict) -> bytes:
    from mtbmj.readout import quicklook

    return quicklook.png(figure(comparison), dpi=90)


__all__ = ["compare", "figure", "png"]

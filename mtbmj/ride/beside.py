"""A simulated bike run beside a real ride: the travel histograms of both ends, each in % of its
own travel, on the same axes (``mtbmj bike ... --ride FILE.SST`` or ``--ride example``).

The real ride is a Sufni SST recording read by ``mtbmj.measured.telemetry`` (the shipped example is a
ride of the SST preset's bike, a Clash 2022: its fork travel, shock stroke and leverage curve are
the preset's). What can agree: the share of travel each end spends its time in (sag, how deep the
terrain pushes), the front/rear balance (mean travel of each end in % of its travel) and the
bottom-outs. What cannot: the real trail, speed and rider are unknown, and the simulated terrain is
one feature of the library, not that trail; the comparison shows a model's range against a ride's,
not a fit.
"""
from __future__ import annotations

import numpy as np

from mtbmj.measured import bob as bob_mod


def _read(result, sst: str):
    """The ride ``sst`` (a path, or "example") read through the bike ``result`` rode (its sensors,
    travels and leverage: ``mtbmj.bike.spec.ride_decoding``), as telemetry, advise and bob read it."""
    from mtbmj.bike.spec import ride_decoding
    from mtbmj.measured import telemetry

    return telemetry.read_sst(telemetry.ride_path(sst), **ride_decoding(result.prepared.spec))


def compare(result, sst: str = "example", bin_percent: float = 5.0) -> dict:
    """Travel histograms and balance of ``result`` (a ``BikeResult``) and of the SST ride ``sst``
    (a path, or "example" for the shipped ride), JSON-ready."""
    from mtbmj.measured import metrics

    ride = _read(result, sst)
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


def bob_compare(result, sst: str) -> dict:
    """The pedal bob of a pedalling bike run (a ``BikeResult``) and of a recorded ride ``sst`` (a
    path, or "example" for the shipped ride), both ends, JSON-ready; the run's bob is its summary's,
    read over its second half (``run_stretch``)."""
    ride = _read(result, sst)
    raw = result.raw
    t = raw["time_s"]
    pedal = result.summary["drive"]["pedal"]
    out = {"ride": ride.name, "ride_notes": list(ride.notes),
           "simulation": f"bike {result.name} over {result.scenario}, pedalling {pedal['cadence_rpm']:g} rpm "
                         f"at {pedal['power_W']:g} W{' seated' if result.info.get('seated') else ' standing'}"}
    for end, real in (("front", ride.fork_mm), ("rear", ride.rear_mm)):
        simulated = pedal[f"{end}_bob"]  # read over the same stretch when the run was summarised
        if "unread" in simulated:
            raise bob_mod.BobError(simulated["unread"])
        entry = {"simulated": simulated}
        if real is not None:
            try:
                entry["ride"] = bob_mod.bob(ride.time_s, real).to_dict()
            except bob_mod.BobError as error:
                entry["ride_unread"] = str(error)
        out[end] = entry
    out["series"] = {"simulated": (t, raw["front_travel_mm"], raw["rear_travel_mm"]),
                     "ride": (ride.time_s, ride.fork_mm, ride.rear_mm)}
    return out


def bob_figure(comparison: dict):
    """Each end's bob: four seconds of the high-passed travel, simulated and ridden, and both
    spectra with the bob frequency marked."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 7), layout="constrained")
    ax = fig.subplots(2, 2)
    series = comparison["series"]
    for row, (end, index, title) in enumerate((("rear", 2, "rear wheel"), ("front", 1, "fork"))):
        entry = comparison[end]
        for key, label, color in (("simulated", "simulated", "C0"), ("ride", f"ride {comparison['ride']}", "C1")):
            if key not in entry:
                continue
            b = entry[key]
            t, x = series[key][0], series[key][index]
            tt, y = bob_mod.high_passed(t, x, b["window_s"])
            show = tt <= 4.0
            ax[row, 0].plot(tt[show], y[show], color=color,
                            label=f"{label}: {b['frequency_Hz']:.2f} Hz, {b['amplitude_mm']:.1f} mm peak to peak")
            f, a = bob_mod.spectrum(t, x, b["window_s"])
            sel = f <= 6.0
            ax[row, 1].plot(f[sel], a[sel], color=color, label=label)
            ax[row, 1].axvline(b["frequency_Hz"], color=color, linestyle="--", linewidth=0.8)
        ax[row, 0].set(xlabel="time in the pedalling stretch (s)", ylabel=f"{title} travel, high-passed (mm)",
                       title=f"{title}: bob", xlim=(0.0, 4.0))
        ax[row, 0].legend(fontsize=8, loc="upper right")
        ax[row, 1].set(xlabel="frequency (Hz)", ylabel="amplitude density (mm/sqrt(Hz))",
                       title=f"{title}: spectrum (dashed: the bob frequency)", xlim=(0.0, 6.0))
        ax[row, 1].legend(fontsize=8)
        for a in ax[row]:
            a.grid(alpha=0.3)
    fig.suptitle(f"pedal bob: {comparison['simulation']} beside ride {comparison['ride']}", fontsize=9)
    return fig


def bob_png(comparison: dict) -> bytes:
    from mtbmj.readout import quicklook

    return quicklook.png(bob_figure(comparison), dpi=90)


def bob_json_ready(comparison: dict) -> dict:
    """The comparison without its time series."""
    return {k: v for k, v in comparison.items() if k != "series"}


def files(result, sst: str = "example") -> dict:
    """The files a bike run writes beside a real ride ``sst`` (a path, or "example"): both ends'
    travel histograms (ride_comparison.json and .png) and, for a pedalling run, both ends' pedal bob
    (bob.json and .png). ``BikeResult.write(out, extra=files(result, sst))`` writes them with the run."""
    from mtbmj import output

    comparison = compare(result, sst)
    out = {"ride_comparison.json": output.json_bytes(comparison), "ride_comparison.png": png(comparison)}
    if "pedal" in result.summary["drive"]:  # a pedalling run: its bob beside the ride's
        bobs = bob_compare(result, sst)
        out["bob.json"] = output.json_bytes(bob_json_ready(bobs))
        out["bob.png"] = bob_png(bobs)
    return out

"""The bike run's quick-look figure: terrain under each wheel, travel at both ends (their peaks
marked) and the shock stroke, pitch, tire loads, the rider's vertical acceleration and the speed,
against time. Legends sit above the panels, off the data; a signal that varies by less than its
resolution (``quicklook.RESOLUTION``) is drawn as the constant it is; a run whose front travel goes
through many cycles (a long washboard) gets a zoom panel on its peak."""
from __future__ import annotations

import numpy as np


def figure(result):
    import textwrap

    from mtbmj.readout import quicklook

    Figure = quicklook.figure_class()
    r, s = result.raw, result.summary
    t = np.asarray(r["time_s"], float)
    window = quicklook.dense_window(t, r["front_travel_mm"])
    fig = Figure(figsize=(8, 11 + (2.2 if window else 0.0)), layout="constrained")
    axes = quicklook.stacked_axes(fig, 6, window is not None)
    ax = axes[0]
    lines = ax.plot(t, r["terrain_front_mm"], label="under the front axle")
    lines += ax.plot(t, r["terrain_rear_mm"], label="under the rear axle")
    ax.set_ylabel("terrain [mm]")
    quicklook.hold_resolution(ax, lines, "mm")
    ax = axes[1]
    lines = ax.plot(t, r["front_travel_mm"], label=f"front travel (of {s['front']['travel_mm']:g} mm)")
    lines += ax.plot(t, r["rear_travel_mm"], label=f"rear wheel travel (of {s['rear_wheel_travel_mm']:g} mm)")
    lines += ax.plot(t, r["stroke_mm"], label=f"shock stroke (of {s['rear']['travel_mm']:g} mm)")
    for line, what in zip(lines, ("front peak", "rear peak")):  # a constant has none
        quicklook.mark_peak(ax, t, line.get_ydata(), line.get_color(), what=what)
    ax.set_ylabel("travel [mm]")
    quicklook.hold_resolution(ax, lines, "mm")
    ax = axes[2]
    lines = ax.plot(t, r["pitch_deg"], color="k")
    ax.set_ylabel("pitch, nose up [deg]")
    quicklook.hold_resolution(ax, lines, "deg")
    ax = axes[3]
    lines = ax.plot(t, r["front_tire_N"], label="front")
    lines += ax.plot(t, r["rear_tire_N"], label="rear")
    ax.set_ylabel("tire load [N]")
    quicklook.hold_resolution(ax, lines, "N")
    ax = axes[4]
    lines = ax.plot(t, r["rider_acc_z_m_per_s2"], color="tab:red",
                    label=f"RMS {s['rider_acceleration_rms_m_per_s2']:.2f} m/s² over the run")
    ax.set_ylabel("rider vertical\nacceleration [m/s²]")
    quicklook.hold_resolution(ax, lines, "m/s²")
    ax = axes[5]
    lines = ax.plot(t, r["speed_m_per_s"], color="tab:green")
    ax.set_ylabel("speed [m/s]")
    quicklook.hold_resolution(ax, lines, "m/s")
    ax.set_xlabel("time [s]")
    if window is not None:
        series = [("front terrain", r["terrain_front_mm"], "0.3"),
                  ("front travel", r["front_travel_mm"], "tab:blue"),
                  ("rear wheel travel", r["rear_travel_mm"], "tab:orange")]
        quicklook.zoom_panel(axes[6], t, series, window, "mm", cycles=quicklook.count_cycles(r["front_travel_mm"]))
    crash = s.get("crash")
    for ax in axes[:6]:
        if crash:  # the run ends here
            ax.axvline(crash["time_s"], color="tab:red", lw=1.5, ls="--",
                       label=f"crash ({crash['kind']})" if ax is axes[2] else None)
        if window is not None:
            ax.axvspan(*window, color="0.5", alpha=0.15, lw=0, label="zoomed below" if ax is axes[1] else None)
        ax.grid(True, alpha=0.3)
        quicklook.legend_above(ax, fontsize=8)
    fig.suptitle(textwrap.fill(result.headline(), 100), fontsize=9)
    return fig


def png(result) -> bytes:
    from mtbmj.readout import quicklook

    return quicklook.png(figure(result), dpi=90)


__all__ = ["figure", "png"]

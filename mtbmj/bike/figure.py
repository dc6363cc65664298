"""The bike run's quick-look figure: terrain under each wheel, travel at both ends and the shock
stroke, pitch, tire loads, the rider's vertical acceleration and the speed, against time."""
from __future__ import annotations


def figure(result):
    from matplotlib.figure import Figure

    r, s = result.raw, result.summary
    t = r["time_s"]
    fig = Figure(figsize=(8, 11), layout="constrained")
    axes = fig.subplots(6, 1, sharex=True)
    ax = axes[0]
    ax.plot(t, r["terrain_front_mm"], label="under the front axle")
    ax.plot(t, r["terrain_rear_mm"], label="under the rear axle")
    ax.set_ylabel("terrain [mm]")
    ax = axes[1]
    ax.plot(t, r["front_travel_mm"], label=f"front travel (of {s['front']['travel_mm']:g} mm)")
    ax.plot(t, r["rear_travel_mm"], label=f"rear wheel travel (of {s['rear_wheel_travel_mm']:g} mm)")
    ax.plot(t, r["stroke_mm"], label=f"shock stroke (of {s['rear']['travel_mm']:g} mm)")
    ax.set_ylabel("travel [mm]")
    ax = axes[2]
    ax.plot(t, r["pitch_deg"], color="k")
    ax.set_ylabel("pitch, nose up [deg]")
    ax = axes[3]
    ax.plot(t, r["front_tire_N"], label="front")
    ax.plot(t, r["rear_tire_N"], label="rear")
    ax.set_ylabel("tire load [N]")
    ax = axes[4]
    ax.plot(t, r["rider_acc_z_m_per_s2"], color="tab:red",
            label=f"RMS {s['rider_acceleration_rms_m_per_s2']:.2f} m/s²")
    ax.set_ylabel("rider vertical\nacceleration [m/s²]")
    ax = axes[5]
    ax.plot(t, r["speed_m_per_s"], color="tab:green")
    ax.set_ylabel("speed [m/s]")
    ax.set_xlabel("time [s]")
    crash = s.get("crash")
    for ax in axes:
        if crash:  # the run ends here
            ax.axvline(crash["time_s"], color="tab:red", lw=1.5, ls="--",
                       label=f"crash ({crash['kind']})" if ax is axes[2] else None)
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper right", fontsize=8)
    import textwrap

    fig.suptitle(textwrap.fill(result.headline(), 100), fontsize=9)
    return fig


def png(result) -> bytes:
    from mtbmj.readout import quicklook

    return quicklook.png(figure(result), dpi=90)


__all__ = ["figure", "png"]

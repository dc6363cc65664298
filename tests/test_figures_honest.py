"""Figures that mislead at a glance (issue 37, item 7): each figure checked for what it shows,
not only that it is written.

* the legend never covers the travel peak a drop or landing run is about (the peak is marked);
* round-off is drawn as the constant it is, and no axis shows an offset like ``1e-9+1.0439``;
* a sweep's heat map is ticked at the values run, its cells centred on them, counts in whole
  numbers;
* a telemetry velocity panel is sized to the data, and names what lies beyond it;
* a study figure is titled by the presets drawn, and says when two engines draw one line;
* a long washboard run gets a zoom panel, and a sag folder's quick-look says what it is."""
from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.transforms import Bbox

import mtbmj
from mtbmj.bike.figure import figure as bike_figure
from mtbmj.readout import quicklook


def drawn(fig):
    """``fig`` laid out and drawn (on Agg), so that positions, legends and tick texts are final."""
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig


def overlap_px(a, b) -> float:
    """Area in pixels shared by two display-space boxes."""
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(w, 0.0) * max(h, 0.0)


def peak_markers(fig):
    """(axes, the marker collection) of every marked peak in ``fig``."""
    return [(ax, c) for ax in fig.axes for c in ax.collections
            if isinstance(c, PathCollection) and re.match(r"(fork|front|rear) peak ", c.get_label())]


# --- legends off the peaks -------------------------------------------------------------------------

@pytest.fixture(scope="module")
def landing_runs():
    return {"drop": mtbmj.run_drop("S12", duration=0.5),
            "roll": mtbmj.run_roll("drop", 5.0),
            "bike": mtbmj.run_bike("trail", "drop", speed_m_per_s=5.0)}


def _peaks_expected(kind, result):
    s = result.summary
    if kind == "bike":
        return {"front peak": s["max_front_travel_mm"], "rear peak": float(np.max(result.raw["rear_travel_mm"]))}
    return {"fork peak": s["max_fork_mm"]}


@pytest.mark.parametrize("kind", ["drop", "roll", "bike"])
def test_no_legend_covers_the_marked_travel_peak(landing_runs, kind):
    result = landing_runs[kind]
    fig = drawn(result.quicklook())
    markers = peak_markers(fig)
    expected = _peaks_expected(kind, result)
    assert sorted(c.get_label().split(" ")[0] + " peak" for _, c in markers) == sorted(expected)
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    assert legends
    for ax, marker in markers:
        (t, y), = marker.get_offsets()
        name = marker.get_label().split(" ")[0] + " peak"
        assert y == pytest.approx(expected[name], abs=1e-9)  # the peak the run reports is the one marked
        assert f"{expected[name]:.1f} mm" in marker.get_label()
        x_px, y_px = ax.transData.transform((t, y))
        assert ax.bbox.contains(x_px, y_px)  # on the panel, not clipped
        r = 8.0  # the marker and a little room around it, in pixels
        around = Bbox.from_extents(x_px - r, y_px - r, x_px + r, y_px + r)
        for legend in legends:
            assert overlap_px(legend.get_window_extent(), around) == 0.0, (kind, name, legend.get_texts()[0].get_text())
    for legend in legends:  # and no legend lies on any panel's data area at all
        for ax in fig.axes:
            assert overlap_px(legend.get_window_extent(), ax.bbox) < 1.0, kind


# --- round-off drawn as signal ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def flat_bike():
    return mtbmj.run_bike("trail", "flat", speed_m_per_s=4.0, duration=0.3)


def test_a_flat_bike_run_draws_pitch_and_speed_as_constants_without_offsets(flat_bike):
    r = flat_bike.raw
    # the premise: on flat ground pitch and speed move by round-off only
    assert np.ptp(r["pitch_deg"]) < quicklook.RESOLUTION["deg"]
    assert np.ptp(r["speed_m_per_s"]) < quicklook.RESOLUTION["m/s"]
    fig = drawn(bike_figure(flat_bike))
    for ax in fig.axes:
        assert ax.yaxis.get_offset_text().get_text() == "", ax.get_ylabel()
        assert ax.xaxis.get_offset_text().get_text() == "", ax.get_ylabel()
    axes = {ax.get_ylabel(): ax for ax in fig.axes}
    for label, key, unit in (("pitch, nose up [deg]", "pitch_deg", "deg"), ("speed [m/s]", "speed_m_per_s", "m/s")):
        ax = axes[label]
        low, high = ax.get_ylim()
        assert high - low >= quicklook.RESOLUTION[unit]
        line, = ax.get_lines()
        assert np.ptp(line.get_ydata()) == 0.0  # drawn flat
        value = f"{np.mean(r[key]):.2f}"
        assert f"constant {value} {unit}" in [t.get_text() for t in ax.get_legend().get_texts()]
        ticks = [t.get_text().replace("\N{MINUS SIGN}", "-") for t in ax.get_yticklabels() if t.get_text()]
        assert all(len(t.split(".")[-1]) <= 3 for t in ticks), ticks  # plain numbers, not 1.3911054350
        assert low <= float(value) <= high


def test_round_off_is_flattened_and_a_real_change_is_not():
    from matplotlib.figure import Figure

    t = np.linspace(0.0, 1.0, 501)
    fig = Figure()
    ax_held, ax_real, ax_small = fig.subplots(3, 1)
    held, = ax_held.plot(t, 1.0439 + 1e-9 * t)  # a pitch held: round-off
    real, = ax_real.plot(t, 5.0 + 0.05 * np.sin(8 * t))  # a speed that does change
    small, = ax_small.plot(t, 5.0 + 0.011 * t)  # just over the resolution
    quicklook.hold_resolution(ax_held, [held], "deg")
    quicklook.hold_resolution(ax_real, [real], "m/s")
    quicklook.hold_resolution(ax_small, [small], "m/s")
    drawn(fig)
    assert np.all(held.get_ydata() == 1.04) and held.get_label() == "constant 1.04 deg"
    assert ax_held.yaxis.get_offset_text().get_text() == ""
    assert np.ptp(real.get_ydata()) == pytest.approx(0.1, rel=0.05) and "constant" not in real.get_label()
    # a change of 1.1 resolutions is drawn, on an axis of at least MIN_SPAN resolutions, so it reads as small
    assert np.ptp(small.get_ydata()) == pytest.approx(0.011)
    low, high = ax_small.get_ylim()
    assert high - low >= quicklook.MIN_SPAN * quicklook.RESOLUTION["m/s"] - 1e-12
    assert all(ax.yaxis.get_offset_text().get_text() == "" for ax in fig.axes)


# --- the sweep's heat maps --------------------------------------------------------------------------

def _sweep_table():
    rows = []
    for psi in (75.0, 95.0):
        for tire in (20.0, 25.0, 30.0):
            rows.append({"fork.spring.air_pressure_psi": psi, "tire.pressure_psi": tire, "status": "ok",
                         "max_fork_mm": 120.0 - 0.3 * psi + 0.1 * tire, "bumper_count": 0,
                         "rim_strikes_count": int((tire == 20.0) + (psi == 75.0) * 2)})
    return pd.DataFrame(rows)


def test_a_sweep_heat_map_is_ticked_at_the_values_run_and_counts_are_whole():
    from mtbmj.sweep.figure import sweep_figure

    fig = drawn(sweep_figure(_sweep_table(), ["fork.spring.air_pressure_psi", "tire.pressure_psi"], "t"))
    panels = {ax.get_title(): ax for ax in fig.axes if ax.get_title()}  # (the colour bars have none)
    assert set(panels) == {"fork peak [mm]", "bumper engagements (none in any variant)", "rim strikes"}
    for ax in panels.values():
        assert list(ax.get_xticks()) == [75.0, 95.0]
        assert [t.get_text() for t in ax.get_xticklabels()] == ["75", "95"]
        assert list(ax.get_yticks()) == [20.0, 25.0, 30.0]
        assert not len(ax.xaxis.get_minorticklocs()) and not len(ax.yaxis.get_minorticklocs())
        mesh = ax.collections[0]
        corners = mesh.get_coordinates()  # (rows + 1, columns + 1, 2): the cells' corners
        centres_x = 0.5 * (corners[0, :-1, 0] + corners[0, 1:, 0])
        centres_y = 0.5 * (corners[:-1, 0, 1] + corners[1:, 0, 1])
        assert np.allclose(centres_x, [75.0, 95.0]) and np.allclose(centres_y, [20.0, 25.0, 30.0])
    for title, values in (("bumper engagements (none in any variant)", [0]), ("rim strikes", [0, 1, 2, 3])):
        bar = panels[title].collections[0].colorbar
        assert list(bar.get_ticks()) == values
        assert [t.get_text() for t in bar.ax.get_yticklabels()] == [str(v) for v in values]
        assert not len(bar.ax.yaxis.get_minorticklocs())
    bar = panels["fork peak [mm]"].collections[0].colorbar  # not a count: a continuous scale
    assert bar.norm.vmin == pytest.approx(120 - 0.3 * 95 + 2.0) and bar.norm.vmax == pytest.approx(120 - 0.3 * 75 + 3.0)
    written = sorted(t.get_text() for t in panels["rim strikes"].texts)
    assert written == sorted(str(v) for v in _sweep_table()["rim_strikes_count"])


# --- telemetry velocity panels ---------------------------------------------------------------------

def test_telemetry_velocity_panels_are_sized_to_the_data():
    from mtbmj.measured import telemetry
    from mtbmj.ride import comparison

    result = comparison.compare(telemetry.read_sst(telemetry.example_path()), [])
    summary = result.summary
    fig = drawn(result.figure())
    panels = [ax for ax in fig.axes if "velocity" in ax.get_xlabel()]
    assert len(panels) == 2
    for ax, end in zip(panels, ("fork", "rear")):
        h = summary["measured"][end]["velocity"]
        edges, time = np.array(h["bin_edges_mm_per_s"]), np.array(h["time_percent"])
        low, high = ax.get_xlim()
        assert low == -high
        # 99.9 % of the time within +-L for the smallest bin edge L, counted here afresh
        outer = np.maximum(np.abs(edges[:-1]), np.abs(edges[1:]))
        span = min(L for L in np.unique(outer) if time[outer <= L].sum() >= 0.999 * time.sum())
        assert span <= high <= 1.2 * span + 1e-9
        assert high < 0.7 * edges[-1]  # not the +-3000 mm/s of the bins
        left_out = time[outer > high].sum()
        assert 0.0 < left_out <= 0.1
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        note, = [t for t in texts if t.startswith("beyond")]
        assert f"±{high:.0f} mm/s" in note and f"measured {left_out:.2g} %" in note
        assert f"{h['compression']['max_mm_per_s']:+.0f}" in note  # the fastest stroke is named
        for other in fig.axes:  # legends under the axes, off the bars
            assert overlap_px(ax.get_legend().get_window_extent(), other.bbox) < 1.0


# --- study titles -----------------------------------------------------------------------------------

def test_a_study_figure_is_titled_by_the_presets_drawn():
    from mtbmj.drop import study

    results = {n: {"mujoco": mtbmj.run_drop(n, duration=0.3), "ode": mtbmj.run_drop(n, "ode", duration=0.3)}
               for n in ("S1", "S12")}
    title, names = study.GROUPS["spring"]
    fig = study.group_figure(results, title, names)
    head, engines = fig.get_suptitle().split("\n")
    assert head == "Fork spring study S1 only (of S1-S7)"
    assert len(fig.axes[1].get_lines()) == 2  # S1 on both engines: two lines, one over the other
    gap = max(d["max_abs_mm"] for d in results["S1"]["ode"].difference(results["S1"]["mujoco"]).values())
    assert gap < 0.05  # the premise: the dashed ODE line lies under the solid MuJoCo one
    assert engines == f"MuJoCo solid, ODE dashed (at most {gap:.2g} mm from MuJoCo)"
    title, names = study.GROUPS["tire"]
    assert study.group_figure(results, title, names).get_suptitle().startswith("Tire study S12 only (of S11-S14)\n")
    assert study.group_title(*study.GROUPS["spring"], study.GROUPS["spring"][1]) == "Fork spring study S1-S7"
    assert study.span(["S1", "S12"]) == "S1, S12" and study.span(["S8", "S9", "S10"]) == "S8-S10"


# --- long runs and sag folders ----------------------------------------------------------------------

def test_a_long_washboard_quicklook_has_a_readable_zoom_on_its_peak():
    from scipy.signal import find_peaks

    result = mtbmj.run_roll("washboard:length_m=30", 5.0)
    r = result.raw
    fig = drawn(result.quicklook())
    assert len(fig.axes) == 5  # terrain, fork, tire, forces, and the zoom
    main, zoom = fig.axes[:4], fig.axes[4]
    whole = main[1].get_xlim()
    assert whole[1] - whole[0] >= 0.9 * (r["time_s"][-1] - r["time_s"][0])
    low, high = zoom.get_xlim()
    peak_t = r["time_s"][int(np.argmax(r["fork_mm"]))]
    assert low <= peak_t <= high
    fork, = [line for line in zoom.get_lines() if line.get_label() == "fork travel"]
    assert fork.get_xdata().min() >= low and fork.get_xdata().max() <= high
    cycles = find_peaks(fork.get_ydata(), prominence=0.05 * np.ptp(r["fork_mm"]))[0].size
    assert 5 <= cycles <= 15  # a dozen cycles: each reads as a cycle, not a band
    assert f"{low:.2f}-{high:.2f} s" in zoom.get_legend().get_title().get_text()
    for ax in main:  # the window is marked on every panel above
        spans = [p for p in ax.patches if p.get_label() == "zoomed below" or (p.get_facecolor()[:3] == (0.5, 0.5, 0.5))]
        assert spans, ax.get_ylabel()
    short = drawn(mtbmj.run_drop("S12", duration=0.5).quicklook())
    assert len(short.axes) == 3  # a drop reads as it is: no zoom


def test_a_quicklook_from_a_sag_folder_says_what_it_is(tmp_path):
    setting = mtbmj.solve_sag("S12", 80.0, 30.0)
    setting.write(tmp_path / "sag")
    run = mtbmj.run_drop(str(tmp_path / "sag" / "config.toml"), duration=0.3)
    assert run.name == "config"
    first = run.quicklook().get_suptitle().split("\n")[0]
    assert first == "sag/config.toml: S12 set to 30 % sag under 80 kg (mtbmj sag)"
    preset = mtbmj.run_drop("S12", duration=0.3).quicklook().get_suptitle()
    assert preset.startswith("S12 (mujoco): fork peak")  # a preset's name says what it is

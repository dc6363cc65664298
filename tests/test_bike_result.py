"""What a rider reads from a bike run (issue 39 item 7): comfort and grip over the terrain's feature
window, not the run's length; the speed range and masses in the headline; BikeResult's plot,
quicklook, to_csv and difference; the bottom bracket's height."""
from __future__ import annotations

import numpy as np
import pytest

import mtbmj
from mtbmj.bike import run as bike_run
from mtbmj.bike import summary as bike_summary
from mtbmj.rolling import terrain as terrain_mod


@pytest.fixture(scope="module")
def roots():
    return {d: mtbmj.run_bike("trail", "root", speed_m_per_s=5.0, duration=d) for d in (3.0, 4.0)}


def test_the_feature_window_does_not_depend_on_the_run_length(roots):
    """The same root: rider 2.15 vs 2.74 m/s2 RMS and load variation 31 vs 40 % at 1 s vs 0.6 s."""
    a, b = (roots[d].summary["feature"] for d in (3.0, 4.0))
    assert a["closed"] and b["closed"] and a["window_s"] == pytest.approx(b["window_s"])
    assert a["rider_acceleration_rms_m_per_s2"] == pytest.approx(b["rider_acceleration_rms_m_per_s2"], rel=1e-12)
    assert a["tire_load_variation"] == pytest.approx(b["tire_load_variation"], rel=1e-12)
    # while the whole run's figures do (the longer run adds quiet rolling)
    assert roots[4.0].summary["rider_acceleration_rms_m_per_s2"] < roots[3.0].summary["rider_acceleration_rms_m_per_s2"]
    assert "over the feature (" in roots[3.0].headline()


def test_the_window_spans_the_feature_from_front_tyre_to_rear_tyre(roots):
    """The root (a half cylinder of 50 mm radius from 1.5 m) spans 1.5-1.6 m: the window opens when
    the front axle is a tyre radius before it and shuts 0.5 s after the rear axle is a radius past it."""
    r = roots[3.0]
    ter = terrain_mod.make("root")
    start, end = bike_summary.feature_span(ter)
    assert (start, end) == pytest.approx((1.5, 1.6), abs=1e-9)
    radius = r.prepared.front_tire.radius
    t, fx, rx = r.raw["time_s"], r.raw["front_axle_x_m"], r.raw["rear_axle_x_m"]
    t0 = t[np.argmax(fx >= start - radius)]
    t1 = t[np.argmax(rx >= end + radius)] + bike_summary.SETTLE_S
    w = r.summary["feature"]["window_s"]
    assert w[0] == pytest.approx(t0, abs=1e-9) and w[1] == pytest.approx(t1, abs=2 * r.prepared.timestep)


def test_bike_result_plot_to_csv_and_difference(roots, tmp_path):
    a, b = roots[3.0], mtbmj.run_bike("trail", "root", speed_m_per_s=4.0, duration=3.0)
    fig = a.plot()
    b.plot(axes=fig.axes)
    assert [ax.get_ylabel() for ax in fig.axes] == ["front travel [mm]", "rear wheel travel [mm]", "pitch, nose up [deg]"]
    assert all(len(ax.lines) == 2 for ax in fig.axes)
    assert a.quicklook().axes[2].get_ylabel() == "pitch, nose up [deg]"
    path = a.to_csv(tmp_path / "run.csv")
    rows = np.genfromtxt(path, delimiter=",", names=True, skip_header=2)
    assert rows.size == a.raw["time_s"].size and np.allclose(rows["front_travel_mm"], a.raw["front_travel_mm"], atol=1e-6)
    same = a.difference(a)
    assert all(v["max_abs"] == 0.0 for v in same.values())
    diff = a.difference(b)
    i = np.argmax(np.abs(a.raw["front_travel_mm"] - b.raw["front_travel_mm"]))
    assert diff["front_travel_mm"]["max_abs"] == pytest.approx(abs(a.raw["front_travel_mm"][i] - b.raw["front_travel_mm"][i]))


def test_the_bottom_bracket_height_is_its_height_above_the_ground(roots):
    r = roots[3.0]
    h = r.raw["bb_height_mm"]
    assert 250.0 < h[0] < 400.0  # a trail bike's BB at sag (about 330 mm: geometry charts)
    # over the root the ground rises under the BB: the height above it dips while the BB itself does not fall
    assert "bb_height_mm" in bike_run.COLUMNS


@pytest.mark.parametrize("scenario", ["rock", "drop", "rock_garden"])
def test_a_run_of_the_default_length_closes_its_feature_window(scenario):
    """At 5 m/s the default duration covers the rear tyre leaving the feature and ``SETTLE_S`` more
    (found here from the run's own axle positions, not from ``default_duration``): the summary's
    window closes and the headline does not say the run ended before it settled (it did on every
    fixed feature before)."""
    r = mtbmj.run_bike("sst", scenario, 5.0)
    span = bike_summary.feature_span(terrain_mod.make(scenario))
    radius = r.prepared.front_tire.radius
    past = np.flatnonzero(r.raw["rear_axle_x_m"] >= span[1] + radius)
    assert past.size and r.raw["time_s"][past[0]] + bike_summary.SETTLE_S <= r.raw["time_s"][-1] + 1e-9
    assert r.summary["feature"]["closed"] and "before it settled" not in r.headline()

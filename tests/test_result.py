"""The result object and the sled-logger view of a run."""
import json

import numpy as np
import pandas as pd
import pytest

import mtbmj
from mtbmj import compose
from mtbmj.drop import measure


@pytest.fixture(scope="module")
def s12():
    return mtbmj.run_drop("S12", duration=0.8)


def test_logged_signals_follow_the_sled_conventions(s12):
    t = s12.time
    assert np.allclose(np.diff(t), 1e-3)  # 1 kHz
    # zero at tire touch (MuJoCo starts the contact 1e-12 m deep) and at full extension
    assert s12["sled_mm"][0] == pytest.approx(0.0, abs=1e-8) and s12["fork_mm"][0] == 0.0
    assert np.allclose(s12["tire_mm"], s12["sled_mm"] - s12["fork_mm"], atol=1e-9)
    assert s12["sled_velocity_mm_per_s"][0] == pytest.approx(1365.25, abs=0.1)  # compression positive
    assert s12.summary["events"]["fork"]["peak1"]["value_mm"] > 0
    # the raw engine trace stays available at the engine rate
    assert np.allclose(np.diff(s12.raw["time_s"]), s12.trace.info["timestep_s"])


def test_antialias_filter_passes_motion_and_blocks_content_above_400_hz():
    setup = compose.setup(mtbmj.load_config("S1"))
    t = np.arange(0, 1.0, 1e-4)
    slow = np.sin(2 * np.pi * 20 * t)
    fast = np.sin(2 * np.pi * 2000 * t)
    raw = {"time_s": t, "slow": slow, "fast": fast}
    logged = measure.logged(setup, raw)
    late = logged["time_s"] > 0.2
    assert np.max(np.abs(logged["fast"][late])) < 0.01
    assert np.max(np.abs(logged["slow"][late])) == pytest.approx(1.0, abs=0.02)


def test_summary_reports_the_drop_events(s12):
    s = s12.summary
    assert s["impact_speed_m_per_s"] == pytest.approx(1.3652, abs=1e-4)
    assert s["lifts_off"] and s["fork_tops_out"]
    for name in ("sled", "fork", "tire"):
        ev = s["events"][name]
        assert ev["peak1"]["time_s"] < s["lift_off_s"] < ev["topping"]["time_s"] < s["landing_s"] < ev["peak2"]["time_s"]
    assert s["energy"]["dissipated_J"] > 0.5 * s["energy"]["input_J"]
    json.dumps(s)  # JSON-ready


def test_never_lifting_off_is_reported_as_such():
    r = mtbmj.run_drop("S1", overrides={"sled.drop_height_mm": 5.0}, duration=0.8)
    assert r.summary["lifts_off"] is False
    assert r.summary["lift_off_s"] is None and r.summary["events"]["fork"]["topping"] is None


def test_export_to_pandas_csv_and_plot(s12, tmp_path):
    frame = s12.to_pandas()
    assert list(frame.columns) == list(measure.COLUMNS[1:])
    assert frame.index.name == "time_s" and len(frame) == len(s12.time)
    path = s12.to_csv(tmp_path / "s12.csv")
    back = pd.read_csv(path, comment="#")
    assert list(back.columns) == list(measure.COLUMNS)
    assert np.allclose(back["fork_mm"], s12["fork_mm"], rtol=1e-7, atol=1e-7)
    fig = s12.plot()
    assert len(fig.axes) == 3 and fig.axes[1].get_ylabel().startswith("fork")
    assert len(fig.axes[0].lines) == 1


def test_difference_between_engines(s12):
    ode = mtbmj.run_drop("S12", engine="ode", duration=0.8)
    diff = s12.difference(ode)
    assert set(diff) == {"sled_mm", "fork_mm", "tire_mm"}
    assert all(0.0 < d["max_abs_mm"] < 0.1 for d in diff.values())
    assert s12.difference(s12)["fork_mm"]["max_abs_mm"] == 0.0

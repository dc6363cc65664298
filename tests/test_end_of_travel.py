"""One definition of the end of travel (issue 23): bumper engagement, hard-stop contact, rim
strikes and the travel left, the same keys from drop, sweep and roll, on the engine signals.

The counts are checked against a counter written here (a plain loop with the same hysteresis),
the peak bumper force against the bumper's closed form, the rolling tire's clearance in the air
against the axle's height over flat ground; the sweep's row against the drop of the same fork."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

import mtbmj
from mtbmj import cli
from mtbmj.config import load
from mtbmj.readout.endtravel import RELEASE_MM, end_of_travel, episodes, line

HARD = {"sled.drop_height_mm": 600.0}  # S12 from 600 mm: bumper, hard stop and rim


def count_loop(signal, threshold, release=RELEASE_MM):
    """Episodes above ``threshold``, each ending ``release`` below it: a plain loop."""
    count, inside, deepest = 0, False, -math.inf
    for value in signal:
        if not inside and value > threshold:
            count, inside = count + 1, True
        elif inside and value < threshold - release:
            inside = False
        if value > threshold:
            deepest = max(deepest, value)
    return count, (deepest if count else None)


def test_episodes_hold_through_dips_shallower_than_the_release():
    signal = np.array([0, 5, 11, 10.8, 11.2, 9.0, 12, 12, 3, 10.2, 0])
    assert [(r.start, r.stop) for r in episodes(signal, 10.0)] == [(2, 5), (6, 8), (9, 10)]
    assert count_loop(signal, 10.0) == (3, 12.0)
    assert episodes(np.zeros(5), 1.0) == []


@pytest.fixture(scope="module")
def hard_drop():
    return mtbmj.run_drop("S12", overrides=HARD)


def test_a_hard_drop_reports_bumper_stop_and_rim_from_its_engine_signals(hard_drop):
    s, raw = hard_drop.summary, hard_drop.raw
    cfg = load("S12")
    travel, bumper_length = cfg["fork.travel_mm"], cfg["fork.stops.bumper_length_mm"]
    for key, signal, threshold in (("bumper", raw["fork_mm"], travel - bumper_length),
                                   ("hard_stop", raw["fork_mm"], travel),
                                   ("rim_strikes", raw["tire_mm"], cfg["tire.max_deflection_mm"])):
        count, deepest = count_loop(signal, threshold)
        assert count >= 1, key
        assert s[key]["count"] == count and s[key]["deepest_mm"] == pytest.approx(deepest), key
    # the bumper's force is quadratic in its engagement: its peak is at the deepest point
    r = (s["bumper"]["deepest_mm"] - (travel - bumper_length)) / bumper_length
    assert s["bumper"]["peak_force_N"] == pytest.approx(cfg["fork.stops.bumper_force_N"] * r * r, rel=1e-9)
    assert s["travel_remaining_mm"] == pytest.approx(travel - np.max(raw["fork_mm"]))
    assert s["travel_remaining_mm"] < 0 and s["bottomed_out"] is True
    assert "bottomed out on the bumper" in line(s) and "struck the rim" in line(s) and "hit the hard stop" in line(s)


def test_the_drop_command_names_the_bottom_out_and_writes_a_figure(tmp_path, capsys):
    out = tmp_path / "s4"
    assert cli.main(["drop", "S4", "--set", "sled.drop_height_mm=300", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["bumper"]["count"] >= 1 and summary["hard_stop"]["count"] == 0
    assert f"bottomed out on the bumper {summary['bumper']['count']}x" in printed
    assert summary["travel_remaining_mm"] == pytest.approx(120.0 - summary["max_fork_mm"])
    assert (out / "quicklook.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_gentle_drop_reports_nothing_engaged(tmp_path, capsys):
    r = mtbmj.run_drop("S12")
    assert not r.summary["bottomed_out"] and line(r.summary) == ""
    assert {r.summary[k]["count"] for k in ("bumper", "hard_stop", "rim_strikes")} == {0}
    assert r.summary["travel_remaining_mm"] > 0


def test_a_sweep_reports_what_the_drop_reports(hard_drop, tmp_path):
    out = tmp_path / "sweep"
    assert cli.main(["sweep", "S12", "--vary", "sled.drop_height_mm=500:600:2", "--engine", "mujoco",
                     "--out", str(out), "--quiet"]) == 0
    import pandas as pd

    table = pd.read_parquet(out / "sweep.parquet")
    row = table[table["sled.drop_height_mm"] == 600.0].iloc[0]
    for key in ("bumper", "hard_stop", "rim_strikes"):
        assert row[f"{key}_count"] == hard_drop.summary[key]["count"], key
        assert row[f"{key}_deepest_mm"] == pytest.approx(hard_drop.summary[key]["deepest_mm"], abs=1e-6), key
    assert row["travel_remaining_mm"] == pytest.approx(hard_drop.summary["travel_remaining_mm"], abs=1e-6)
    # flags are booleans in the table, not the text "true"/"false"
    assert str(table["bottomed_out"].dtype) == "boolean" and bool(row["bottomed_out"]) is True
    assert str(table["at_rest"].dtype) == "boolean"


@pytest.fixture(scope="module")
def rolled():
    from mtbmj.rolling.frontend import run_roll

    return run_roll("drop:height_mm=600", 5.0)


def test_a_rolling_drop_reports_with_the_same_definition(rolled):
    s, raw = rolled.summary, rolled.raw
    cfg = load("S12")
    for key, signal, threshold in (("bumper", raw["fork_mm"], cfg["fork.travel_mm"] - cfg["fork.stops.bumper_length_mm"]),
                                   ("hard_stop", raw["fork_mm"], cfg["fork.travel_mm"]),
                                   ("rim_strikes", raw["tire_mm"], cfg["tire.max_deflection_mm"])):
        count, deepest = count_loop(signal, threshold)
        assert s[key]["count"] == count and count >= 1, key
        assert s[key]["deepest_mm"] == pytest.approx(deepest), key
    report = end_of_travel(_setup(), raw["fork_mm"], raw["fork_velocity_mm_per_s"], raw["tire_mm"],
                           time_s=raw["time_s"])
    assert {k: report[k] for k in ("bumper", "hard_stop", "rim_strikes")} == \
        {k: s[k] for k in ("bumper", "hard_stop", "rim_strikes")}


def _setup():
    from mtbmj import compose

    return compose.setup(load("S12"))


def test_the_rolling_tire_in_the_air_reports_its_clearance(rolled):
    """Over the flat ground after the drop, the tire's clearance is the axle's height over the
    ground less the radius: the start's axle height (radius - static deflection on flat ground)
    plus the axle's rise, less the ground under it."""
    from mtbmj.rolling.terrain import LEAD_IN_M as edge  # the drop's edge (terrain.drop's default at_m)

    raw, s = rolled.raw, rolled.summary
    start_ground = raw["terrain_mm"][0]
    axle = start_ground + (_setup().tire_radius * 1e3 - s["static_tire_mm"]) + raw["axle_z_mm"]
    expected = _setup().tire_radius * 1e3 - (axle - raw["terrain_mm"])
    # airborne past the old -10 mm clip, where the ledge (corner and wall) is farther away than the
    # ground straight below
    away = ((raw["x_m"] - edge) * 1e3 > (axle - raw["terrain_mm"]) + 10.0) & (expected < -12.0)
    assert np.count_nonzero(away) > 100
    assert np.max(np.abs(raw["tire_mm"][away] - expected[away])) < 1e-6
    assert raw["tire_mm"].min() < -100.0


def test_the_roll_command_names_rim_strikes(tmp_path, capsys):
    out = tmp_path / "roll"
    assert cli.main(["roll", "drop:height_mm=600", "--speed", "5", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["rim_strikes"]["count"] >= 1 and "struck the rim" in printed
    assert "N back" in printed and "-0 N back" not in printed
    assert (out / "quicklook.png").exists()
    assert summary["ride_metrics"]["bottom_outs"]["rule"].startswith("telemetry")


def test_study_and_validate_report_the_same_engagement_as_drop(tmp_path, capsys):
    drop = mtbmj.run_drop("S4", overrides={"sled.drop_height_mm": 300.0})
    assert drop.summary["bumper"]["count"] >= 1
    phrase = line(drop.summary)[2:]
    assert cli.main(["study", "--presets", "S4", "--engines", "mujoco", "--set", "sled.drop_height_mm=300",
                     "--out", str(tmp_path / "study"), "--quiet"]) == 0
    assert f"S4 (mujoco) {phrase}" in capsys.readouterr().out
    study = json.loads((tmp_path / "study" / "study_summary.json").read_text())
    assert study["S4"]["mujoco"]["bumper"] == drop.summary["bumper"]
    assert cli.main(["validate", "example", "--presets", "S4", "--set", "sled.drop_height_mm=300",
                     "--out", str(tmp_path / "validate"), "--quiet"]) == 0
    assert f"S4 {phrase}" in capsys.readouterr().out
    summary = json.loads((tmp_path / "validate" / "validation_summary.json").read_text())
    assert summary["end_of_travel"]["S4"]["bumper"]["count"] == drop.summary["bumper"]["count"]


def test_a_sweep_over_one_key_draws_its_outputs_against_it(tmp_path, capsys):
    """sweep.png: one panel per main output, its line the table's column against the key."""
    out = tmp_path / "sweep"
    assert cli.main(["sweep", "S12", "--vary", "sled.drop_height_mm=100:600:4", "--engine", "fast",
                     "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    import pandas as pd

    from mtbmj.sweep.figure import MAIN_OUTPUTS, sweep_figure

    table = pd.read_parquet(out / "sweep.parquet")
    assert (out / "sweep.png").read_bytes()[:4] == b"\x89PNG"
    hit = int((table["bumper_count"] > 0).sum())
    assert hit >= 1 and f"{hit} variants bottomed out on the bumper" in printed
    fig = sweep_figure(table, ["sled.drop_height_mm"])
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_ylabel() for ax in axes] == [label for _, label in MAIN_OUTPUTS]
    for ax, (column, _) in zip(axes, MAIN_OUTPUTS):
        assert ax.get_xlabel() == "sled.drop_height_mm"
        x, y = ax.lines[0].get_data()
        assert list(x) == [100.0, 100.0 + 500 / 3, 100.0 + 1000 / 3, 600.0]
        assert np.allclose(y, table.sort_values("sled.drop_height_mm")[column].to_numpy(float))


def test_a_sweep_over_two_keys_draws_heat_maps_of_the_grid(tmp_path):
    import pandas as pd

    from mtbmj.sweep.figure import sweep_figure

    out = tmp_path / "sweep"
    assert cli.main(["sweep", "S12", "--vary", "sled.drop_height_mm=100:300:3", "--vary",
                     "fork.spring.preload_N=100:300:2", "--engine", "fast", "--out", str(out), "--quiet"]) == 0
    table = pd.read_parquet(out / "sweep.parquet")
    fig = sweep_figure(table, ["sled.drop_height_mm", "fork.spring.preload_N"])
    ax = fig.axes[0]
    grid = ax.collections[0].get_array().reshape(2, 3)  # preload rows, drop height columns
    for _, row in table.iterrows():
        i = [100.0, 300.0].index(row["fork.spring.preload_N"])
        j = [100.0, 200.0, 300.0].index(row["sled.drop_height_mm"])
        assert grid[i, j] == pytest.approx(row["max_fork_mm"])
    assert ax.get_xlabel() == "sled.drop_height_mm" and ax.get_ylabel() == "fork.spring.preload_N"
    three = sweep_figure(table.assign(x=1.0), ["sled.drop_height_mm", "fork.spring.preload_N", "x"])
    assert three is None  # three keys: the table is the place to look
    assert cli.main(["sweep", "S12", "--vary", "sled.drop_height_mm=100:300:2", "--engine", "fast",
                     "--out", str(tmp_path / "plain"), "--quiet", "--no-figure"]) == 0
    assert not (tmp_path / "plain" / "sweep.png").exists()


def test_a_sweep_over_metres_typed_into_a_mm_key_warns_and_runs(tmp_path, capsys):
    assert cli.main(["sweep", "S12", "--vary", "sled.drop_height_mm=0.1:0.3:2", "--engine", "fast",
                     "--out", str(tmp_path / "sweep"), "--quiet", "--no-figure"]) == 0
    err = capsys.readouterr().err
    assert err.count("mtbmj: warning:") == 1
    assert "--vary sled.drop_height_mm=0.1:0.3:2" in err and "probably meant 0.1 m = 100 mm" in err

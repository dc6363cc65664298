"""Damper clicks (``fork.damper.model = "clicks"``): curves measured at several adjuster positions,
interpolated between them; the fit from several dyno files; a sweep over clicks."""
import json

import numpy as np
import pytest

import mtbmj
from mtbmj import cli, compose
from mtbmj.config import load
from mtbmj.errors import ConfigError
from mtbmj.identify.dyno_synthetic import DAMPER_TABLE, write_damper_record
from mtbmj.identify.run import identify

V = [-1500.0, -800.0, -400.0, -150.0, -50.0, 0.0, 50.0, 150.0, 400.0, 800.0, 1500.0]
TABLE_F = np.array(DAMPER_TABLE["fork.damper.force_N"])


def _random_clicks_config(rng, positions):
    """Rows from the reference table scaled by a random, decreasing factor per position."""
    scale = np.sort(rng.uniform(0.5, 2.0, len(positions)))[::-1]
    comp = [tuple(TABLE_F[6:] * s) for s in scale]
    reb = [tuple(TABLE_F[:5] * s * rng.uniform(0.9, 1.1)) for s in scale]
    values = {"fork.damper.model": "clicks", "fork.damper.velocity_mm_per_s": V,
              "fork.damper.compression_clicks_measured": positions, "fork.damper.rebound_clicks_measured": positions,
              "fork.damper.compression_force_N": comp, "fork.damper.rebound_force_N": reb}
    return values, np.array(comp), np.array(reb)


def test_setting_interpolates_linearly_in_clicks_between_measured_positions():
    rng = np.random.default_rng(1616)
    positions = [0.0, 5.0, 9.0, 16.0]
    values, comp, reb = _random_clicks_config(rng, positions)
    for _ in range(10):
        c_set, r_set = (float(k) for k in rng.integers(0, 17, 2))
        cfg = load("S12", {**values, "fork.damper.compression_clicks": c_set, "fork.damper.rebound_clicks": r_set})
        damper = compose.fork_law(cfg).damper
        for j, v in enumerate(V[6:]):
            i = np.searchsorted(positions, c_set, side="right") - 1
            i = min(i, len(positions) - 2)
            w = (c_set - positions[i]) / (positions[i + 1] - positions[i])
            expected = (1 - w) * comp[i, j] + w * comp[i + 1, j]
            assert damper.force(v * 1e-3) == pytest.approx(expected, rel=1e-12)
        for j, v in enumerate(V[:5]):
            expected = np.interp(r_set, positions, reb[:, j])
            assert damper.force(v * 1e-3) == pytest.approx(expected, rel=1e-12)
        if c_set in positions:  # at a measured position: that row exactly
            assert damper.force(V[-1] * 1e-3) == pytest.approx(comp[positions.index(c_set), -1], rel=1e-14)


@pytest.mark.parametrize("change,key", [
    ({"fork.damper.compression_clicks": 17.0}, "fork.damper.compression_clicks"),
    ({"fork.damper.rebound_clicks": 2.5}, "fork.damper.rebound_clicks"),
    ({"fork.damper.compression_clicks_measured": [0.0, 9.0, 5.0, 16.0]}, "fork.damper.compression_clicks_measured"),
    ({"fork.damper.rebound_clicks_measured": [0.0, 16.0]}, "fork.damper.rebound_force_N"),
    ({"fork.damper.compression_force_N": [[1.0, 2.0, 3.0]] * 4}, "fork.damper.compression_force_N"),
    ({"fork.damper.rebound_force_N": [[-10.0, -20.0, -30.0, -40.0, -50.0]] * 4}, "fork.damper.rebound_force_N"),
])
def test_bad_clicks_input_names_the_key(change, key, tmp_path, capsys):
    values, _, _ = _random_clicks_config(np.random.default_rng(3), [0.0, 5.0, 9.0, 16.0])
    values.update({"fork.damper.compression_clicks": 4.0, "fork.damper.rebound_clicks": 8.0})
    compose.fork_law(load("S12", values))  # the base case is accepted
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        compose.fork_law(load("S12", {**values, **change}))
    config = tmp_path / "c.toml"
    config.write_text(load("S12", values).to_toml())
    out = tmp_path / "out"
    settings = [a for k, v in change.items() for a in ("--set", f"{k}={json.dumps(v)}")]
    assert cli.main(["drop", str(config), *settings, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0]
    assert not out.exists()


def test_fit_from_dyno_files_at_several_clicks_recovers_each_curve(tmp_path):
    rng = np.random.default_rng(2016)
    positions = [0, 7, 14]
    scales = np.sort(rng.uniform(0.6, 1.8, 3))[::-1]
    files = []
    for clicks, s in zip(positions, scales):
        truth = dict(DAMPER_TABLE, **{"fork.damper.force_N": list(TABLE_F * s)})
        files.append(write_damper_record(tmp_path / f"dyno_{clicks}.csv", truth, seed=int(clicks) + 1))
    ident = identify("damper", files, clicks=positions)
    written = ident.write(tmp_path / "fit")
    cfg = load(tmp_path / "fit" / "fit.toml")
    assert cfg["fork.damper.model"] == "clicks"
    assert cfg["fork.friction.coulomb_N"] == pytest.approx(DAMPER_TABLE["fork.friction.coulomb_N"], abs=2.0)
    grid = np.asarray(cfg["fork.damper.velocity_mm_per_s"]) * 1e-3
    for k, (clicks, s) in enumerate(zip(positions, scales)):
        damper = compose.fork_law(cfg.with_overrides({"fork.damper.compression_clicks": float(clicks),
                                                      "fork.damper.rebound_clicks": float(clicks)})).damper
        true = np.interp(grid, np.asarray(V) * 1e-3, TABLE_F * s)
        got = np.array([damper.force(v) for v in grid])
        assert np.max(np.abs(got - true)) < 0.03 * np.max(np.abs(true)) + 3.0, clicks
    assert {p.name for p in written} == {"fit.toml", "fit.json", "fit.png"}
    result = mtbmj.run_drop(cfg, duration=0.3)
    assert result.summary["max_fork_mm"] > 0


def test_fit_with_mismatched_clicks_exits_2(tmp_path, capsys):
    a = write_damper_record(tmp_path / "a.csv", seed=1)
    b = write_damper_record(tmp_path / "b.csv", seed=2)
    out = tmp_path / "fit"
    assert cli.main(["fit", "damper", str(a), str(b), "--clicks", "0,6,12", "--out", str(out)]) == 2
    assert cli.main(["fit", "damper", str(a), str(b), "--out", str(out)]) == 2
    assert cli.main(["fit", "damper", str(a), str(b), "--clicks", "0,x", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all("clicks" in line for line in err)
    assert not out.exists()


def test_a_sweep_varies_clicks(tmp_path):
    from mtbmj.sweep import read_table, run_sweep

    values, _, _ = _random_clicks_config(np.random.default_rng(5), [0.0, 8.0, 16.0])
    values.update({"fork.damper.compression_clicks": 8.0, "fork.damper.rebound_clicks": 8.0})
    config = load("S12", values)
    variants = [{"fork.damper.rebound_clicks": float(c)} for c in (0, 8, 16)]
    run_sweep(config, variants, tmp_path / "sweep", duration=0.6)
    table = read_table(tmp_path / "sweep").sort_values("fork.damper.rebound_clicks")
    single = mtbmj.run_drop(config.with_overrides({"fork.damper.rebound_clicks": 16.0}), duration=0.6)
    row = table[table["fork.damper.rebound_clicks"] == 16.0].iloc[0]
    assert row["fork_peak1_mm"] == pytest.approx(single.summary["events"]["fork"]["peak1"]["value_mm"], abs=1e-6)
    lift = table["lift_off_s"].to_numpy()
    assert len(set(np.round(lift, 4))) == 3  # the rebound setting changes when the wheel leaves the ground


def test_a_clicks_config_round_trips_through_toml(tmp_path):
    values, _, _ = _random_clicks_config(np.random.default_rng(9), [0.0, 4.0, 12.0])
    values.update({"fork.damper.compression_clicks": 3.0, "fork.damper.rebound_clicks": 12.0})
    cfg = load("S12", values)
    path = tmp_path / "again.toml"
    path.write_text(cfg.to_toml())
    assert load(path).values == cfg.values

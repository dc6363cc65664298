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


def _refused_naming(values, change, key, tmp_path, capsys):
    """``values`` (S12 overrides) compose; with ``change`` they are refused naming ``key``, from
    Python and as one line from ``mtbmj drop`` (exit 2, nothing written)."""
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
    _refused_naming(values, change, key, tmp_path, capsys)


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
    assert cli.main(["fit", "damper", str(a), str(b), "--clicks", "0", "--clicks", "x", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 4 and all("clicks" in line for line in err)
    assert not out.exists()


def test_one_dyno_file_at_two_positions_is_refused_naming_both(tmp_path, capsys):
    """The same file given at 0 and 6 clicks (twice, or a copy) was fitted as two positions: one test
    read at two settings, an adjuster that changes nothing. Refused in one line naming both; the
    same record made twice at another seed (another test of the same damper) is not refused for it."""
    a = write_damper_record(tmp_path / "a.csv", seed=1)
    b = write_damper_record(tmp_path / "b.csv", seed=2)
    (tmp_path / "copy.csv").write_bytes(a.read_bytes())
    out = tmp_path / "fit"
    for files, named in (([a, a], "a.csv: the same record as"), ([a, tmp_path / "copy.csv"], "copy.csv: the same record as")):
        assert cli.main(["fit", "damper", *map(str, files), "--clicks", "0,6", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and named in err and "labelled 0 clicks and 6 clicks" in err, err
        assert not out.exists()
    cli.main(["fit", "damper", str(a), str(b), "--clicks", "0,6", "--out", str(out)])
    assert "the same record" not in capsys.readouterr().err


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


# --- low- and high-speed adjusters per stroke ----------------------------------------------------

CIRCUITS = ("low_speed_compression", "high_speed_compression", "low_speed_rebound", "high_speed_rebound")
LABELS = ("lsc", "hsc", "lsr", "hsr")
VG = np.array([-1500, -1200, -900, -700, -500, -350, -250, -150, -80, -40, -15, 0,
               15, 40, 80, 150, 250, 350, 500, 700, 900, 1200, 1500.0])


def _digressive(v_mm_per_s, lsc, hsc, lsr, hsr):
    """A closed-form two-stage damper, written here and nowhere in the package: a low-speed bleed
    that saturates at a knee (its slope opening up with the low-speed clicks) plus a high-speed
    stack (opening up with the high-speed clicks). The knee moves with the high-speed setting, so
    the two adjusters do not simply add: the additive model is an approximation of it."""
    v = np.asarray(v_mm_per_s, dtype=float) * 1e-3
    out = np.zeros_like(v)
    c, r = v > 0, v < 0
    knee = 0.12 * (1 + 0.04 * hsc)
    out[c] = 2200 * np.exp(-0.1 * lsc) * knee * np.tanh(v[c] / knee) + (450 * np.exp(-0.08 * hsc) + 300) * v[c]
    knee = 0.10 * (1 + 0.04 * hsr)
    out[r] = 3000 * np.exp(-0.1 * lsr) * knee * np.tanh(v[r] / knee) + (600 * np.exp(-0.08 * hsr) + 250) * v[r]
    return out


def _split_config(rng):
    """Random rows for the four adjusters, each swept with its stroke partner at the reference."""
    values = {"fork.damper.model": "clicks", "fork.damper.velocity_mm_per_s": V}
    rows = {}
    for stroke, side, pair in (("compression", slice(6, None), CIRCUITS[:2]), ("rebound", slice(0, 5), CIRCUITS[2:])):
        base = TABLE_F[side] * rng.uniform(0.8, 1.2)
        for circuit, ref, positions in zip(pair, (4.0, 2.0), ([0.0, 4.0, 10.0], [0.0, 2.0, 6.0])):
            # each click from the reference scales the curve by a random few per cent (softer with
            # more clicks from closed), the low-speed adjuster more at low speeds
            slope = rng.uniform(0.02, 0.05)
            weight = np.exp(-np.abs(np.asarray(V)[side]) / 600.0) if circuit.startswith("low") else 1.0
            table = np.array([base * (1.0 - slope * (p - ref) * weight) for p in positions])
            table = np.maximum.accumulate(table, axis=1)
            rows[circuit] = (positions, table, ref)
            values.update({f"fork.damper.{circuit}_clicks_measured": positions,
                           f"fork.damper.{circuit}_force_N": [tuple(r) for r in table],
                           f"fork.damper.{circuit}_reference_clicks": ref,
                           f"fork.damper.{circuit}_clicks": ref})
    return values, rows


def test_low_and_high_speed_adjusters_add_around_their_shared_reference():
    rng = np.random.default_rng(4242)
    values, rows = _split_config(rng)
    for _ in range(12):
        setting = {c: float(rng.integers(0, 11 if c.startswith("low") else 7)) for c in CIRCUITS}
        cfg = load("S12", {**values, **{f"fork.damper.{c}_clicks": s for c, s in setting.items()}})
        damper = compose.fork_law(cfg).damper
        for pair, velocities in ((CIRCUITS[:2], V[6:]), (CIRCUITS[2:], V[:5])):
            (pl, tl, rl), (ph, th, rh) = rows[pair[0]], rows[pair[1]]
            at = [np.array([np.interp(setting[c], p, t[:, j]) for j in range(len(velocities))])
                  for c, p, t in ((pair[0], pl, tl), (pair[1], ph, th))]
            base = 0.5 * (tl[pl.index(rl)] + th[ph.index(rh)])
            expected = at[0] + at[1] - base
            got = [damper.force(v * 1e-3) for v in velocities]
            assert got == pytest.approx(expected, rel=1e-12, abs=1e-9)
    at_ref = compose.fork_law(load("S12", values)).damper  # both at their references: the shared curve
    assert at_ref.force(V[-1] * 1e-3) == pytest.approx(rows[CIRCUITS[0]][1][1][-1], rel=1e-12)


@pytest.mark.parametrize("change,key", [
    ({"fork.damper.low_speed_compression_reference_clicks": 3.0}, "fork.damper.low_speed_compression_reference_clicks"),
    ({"fork.damper.high_speed_rebound_clicks": 7.0}, "fork.damper.high_speed_rebound_clicks"),
    ({"fork.damper.compression_clicks": 2.0}, "fork.damper.compression_clicks"),
    ({"fork.damper.high_speed_compression_force_N": [[1.0, 2.0, 3.0, 4.0, 5.0]] * 3},
     "fork.damper.high_speed_compression_force_N"),
    ({"fork.damper.low_speed_rebound_force_N": [[-3000.0, -2000.0, -1000.0, -100.0, -10.0]] * 3},
     "fork.damper.high_speed_rebound_force_N"),
])
def test_bad_low_high_speed_input_names_the_key(change, key, tmp_path, capsys):
    values, _ = _split_config(np.random.default_rng(8))
    _refused_naming(values, change, key, tmp_path, capsys)


def _dyno_files(tmp_path, design, additive=False):
    def truth(s):
        s = dict(zip(LABELS, s))
        if additive:  # the knee held still: the adjusters' effects add exactly
            comp = _digressive(VG, s["lsc"], 0, s["lsr"], 0) + _digressive(VG, 0, s["hsc"], 0, s["hsr"]) \
                - _digressive(VG, 0, 0, 0, 0)
            return dict(DAMPER_TABLE, **{"fork.damper.velocity_mm_per_s": list(VG), "fork.damper.force_N": list(comp)})
        return dict(DAMPER_TABLE, **{"fork.damper.velocity_mm_per_s": list(VG),
                                     "fork.damper.force_N": list(_digressive(VG, **s))})
    return [write_damper_record(tmp_path / f"dyno_{k}.csv", truth(s), seed=100 + k) for k, s in enumerate(design)]


def _one_at_a_time(ref, sweeps):
    design = [tuple(ref)]
    for i, positions in enumerate(sweeps):
        for p in positions:
            s = list(ref)
            s[i] = p
            if tuple(s) not in design:
                design.append(tuple(s))
    return design


def _setting_keys(setting):
    return {f"fork.damper.{c}_clicks": float(s) for c, s in zip(CIRCUITS, setting)}


def test_fit_of_low_and_high_speed_sweeps_predicts_unmeasured_settings(tmp_path):
    """Dyno files from a one-at-a-time sweep of each adjuster around a reference (the usual bench
    session); the fitted damper is then asked for settings never measured together, and compared
    with the closed form that made the files."""
    ref = (6.0, 4.0, 5.0, 3.0)
    design = _one_at_a_time(ref, ([0.0, 12.0], [0.0, 10.0], [0.0, 12.0], [0.0, 8.0]))
    files = _dyno_files(tmp_path, design)
    out = tmp_path / "fit"
    args = ["fit", "damper", *map(str, files)]
    for s in design:
        args += ["--clicks", ",".join(f"{name}={p:g}" for name, p in zip(LABELS, s))]
    assert cli.main([*args, "--out", str(out)]) == 0
    cfg = load(out / "fit.toml")
    for c, r in zip(CIRCUITS, ref):  # the written setting is the reference the sweeps shared
        assert cfg[f"fork.damper.{c}_reference_clicks"] == r and cfg[f"fork.damper.{c}_clicks"] == r
    grid = np.asarray(cfg["fork.damper.velocity_mm_per_s"])
    rng = np.random.default_rng(77)
    for setting in [*design, *[(float(rng.integers(0, 13)), float(rng.integers(0, 11)), float(rng.integers(0, 13)),
                                float(rng.integers(0, 9))) for _ in range(12)]]:
        damper = compose.fork_law(cfg.with_overrides(_setting_keys(setting))).damper
        got = np.array([damper.force(v * 1e-3) for v in grid])
        true = _digressive(grid, *setting)
        # dyno noise and the table fit (about 1 %), linear interpolation in clicks of a law that is
        # exponential in them, and the knee's shift with the high-speed clicks the model leaves out
        assert np.max(np.abs(got - true)) < 0.05 * np.max(np.abs(true)) + 3.0, setting
    single = mtbmj.run_drop(cfg.with_overrides(_setting_keys((12.0, 10.0, 0.0, 0.0))), duration=0.3)
    assert single.summary["max_fork_mm"] > 0


def test_additive_fit_is_exact_up_to_noise_when_the_adjusters_add(tmp_path):
    """With the knee held still the truth is additive, so settings never measured together are
    predicted as well as measured ones (the least-squares split has nothing to leave out)."""
    ref = (4.0, 4.0, 4.0, 4.0)
    design = _one_at_a_time(ref, ([0.0, 8.0], [0.0, 8.0], [0.0, 8.0], [0.0, 8.0]))
    files = _dyno_files(tmp_path, design, additive=True)
    ident = identify("damper", files, clicks=[dict(zip(LABELS, s)) for s in design])
    cfg = load("S12", {**ident.results["clicks"].values, "fork.damper.model": "clicks"})
    grid = np.asarray(cfg["fork.damper.velocity_mm_per_s"])
    errors = {}
    for setting in [(0.0, 8.0, 8.0, 0.0), (8.0, 0.0, 0.0, 8.0), (0.0, 0.0, 8.0, 8.0), *design]:
        damper = compose.fork_law(cfg.with_overrides(_setting_keys(setting))).damper
        true = (_digressive(grid, setting[0], 0, setting[2], 0) + _digressive(grid, 0, setting[1], 0, setting[3])
                - _digressive(grid, 0, 0, 0, 0))
        got = np.array([damper.force(v * 1e-3) for v in grid])
        errors[setting] = np.max(np.abs(got - true)) / np.max(np.abs(true))
    measured = max(errors[s] for s in design)
    corners = max(errors[s] for s in errors if s not in design)
    assert measured < 0.03 and corners < 0.03 and corners < 2.5 * measured


def test_more_open_high_speed_compression_bottoms_deeper(tmp_path):
    """A hard drop through a sweep of the high-speed compression adjuster: opening it (more clicks
    from closed) lets the fork go deeper at Peak 1; the low-speed one matters less at impact speed."""
    from mtbmj.sweep import read_table, run_sweep

    values = {"fork.damper.model": "clicks", "fork.damper.velocity_mm_per_s": list(VG)}
    for c, label, positions, ref in zip(CIRCUITS, LABELS, ([0.0, 6.0, 12.0], [0.0, 5.0, 10.0], [0.0, 6.0, 12.0],
                                                           [0.0, 5.0, 10.0]), (6.0, 5.0, 6.0, 5.0)):
        reference = dict(zip(LABELS, (6.0, 5.0, 6.0, 5.0)))
        side = VG > 0 if "compression" in c else VG < 0
        table = [tuple(_digressive(VG, **{**reference, label: p})[side]) for p in positions]
        values.update({f"fork.damper.{c}_clicks_measured": positions, f"fork.damper.{c}_force_N": table,
                       f"fork.damper.{c}_reference_clicks": ref, f"fork.damper.{c}_clicks": ref})
    config = load("S12", {**values, "sled.drop_height_mm": 300.0})
    variants = [{"fork.damper.high_speed_compression_clicks": h} for h in (0.0, 5.0, 10.0)]
    run_sweep(config, variants, tmp_path / "sweep", duration=0.4)
    table = read_table(tmp_path / "sweep").sort_values("fork.damper.high_speed_compression_clicks")
    peak = table["fork_peak1_mm"].to_numpy()
    assert np.all(np.diff(peak) > 0.5), peak


def test_fit_with_bad_adjuster_labels_exits_2(tmp_path, capsys):
    a = write_damper_record(tmp_path / "a.csv", seed=1)
    b = write_damper_record(tmp_path / "b.csv", seed=2)
    out = tmp_path / "fit"
    base = ["fit", "damper", str(a), str(b), "--out", str(out)]
    cases = [["--clicks", "lsc=0,hsc=2,r=1", "--clicks", "lsc=4,hsc=2"],        # rebound unlabelled in one file
             ["--clicks", "lsc=0,hsc=2,r=1", "--clicks", "lsc=4,hsc=2,xyz=1"],  # unknown adjuster
             ["--clicks", "lsc=0,hsc=2,r=1", "--clicks", "lsc=4,hsc=2,r"],      # no value
             ["--clicks", "lsc=0,hsc=0,r=1", "--clicks", "lsc=4,hsc=4,r=1"],    # never one adjuster at a time
             ["--clicks", "lsc=0,hsc=2,r=1", "--clicks", "lsc=4,hsc=2,r=-1"]]   # negative clicks
    for extra in cases:
        assert cli.main([*base, *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == len(cases) and all("--clicks" in line for line in err)
    assert not out.exists()

"""``mtbmj curve`` / ``mtbmj.readout.curves`` and the air study's spring-curve figure: the curves drawn are
the closed forms of the configured laws (written out here from the configuration's numbers, not
taken from the law library), the figures show what they say (axis labels with units, the stroke
from the top stop to full travel, a y range the spring's own, one line per click)."""
import csv
import math

import numpy as np
import pytest

from mtbmj import output
from mtbmj.cli import main
from mtbmj.config import load
from mtbmj.readout.curves import damper_curve, damper_figure, fork_curves, spring_curve, spring_figure
from mtbmj.identify.dyno_synthetic import DAMPER_TABLE
from helpers import one_line

G = 9.81
PSI = 6894.757293168
P_ATM = 101325.0


def _coil(rng):
    """S1's linear coil with a random rate, preload, top-out rate and bumper (the numbers the
    closed form below uses)."""
    v = {"fork.spring.rate_N_per_mm": float(rng.uniform(8, 25)), "fork.spring.preload": True,
         "fork.spring.preload_N": float(rng.uniform(80, 300)), "fork.spring.top_out": True,
         "fork.spring.top_out_rate_N_per_mm": float(rng.uniform(25, 60)),
         "fork.stops.bumper_force_N": float(rng.uniform(1500, 4000)),
         "fork.stops.bumper_length_mm": float(rng.uniform(5, 15)), "fork.stops.extension_mm": float(rng.uniform(3, 8)),
         "sled.body_mass_kg": float(rng.uniform(45, 80))}
    return v


@pytest.mark.parametrize("seed", [23, 230, 2300])
def test_a_coil_curve_is_rate_times_travel_plus_preload_with_top_out_and_bumper(seed):
    values = _coil(np.random.default_rng(seed))
    curve = spring_curve("S1", values)
    k, p = values["fork.spring.rate_N_per_mm"], values["fork.spring.preload_N"]
    kt, b = values["fork.spring.top_out_rate_N_per_mm"], values["fork.stops.bumper_force_N"]
    travel = 120.0
    start = travel - values["fork.stops.bumper_length_mm"]
    engaged = p / kt  # mm: the top-out spring is free beyond it
    x = curve.travel_mm
    assert x[0] == pytest.approx(-values["fork.stops.extension_mm"]) and x[-1] == pytest.approx(travel)
    main_spring = p + k * x
    top_out = -kt * np.maximum(0.0, engaged - x)
    bumper = b * (np.clip(x - start, 0.0, None) / values["fork.stops.bumper_length_mm"]) ** 2
    np.testing.assert_allclose(curve.main_N, main_spring, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(curve.top_out_N, top_out, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(curve.bumper_N, bumper, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(curve.spring_N, main_spring + top_out + bumper, rtol=1e-12, atol=1e-9)
    for at in (engaged + 1.0, 40.0, 80.0, start - 0.5):  # a few points in the open: rate x travel + preload
        assert np.interp(at, x, curve.spring_N) == pytest.approx(k * at + p, rel=1e-9)
    assert curve.spring_N[0] == pytest.approx(p + k * x[0] - kt * (engaged - x[0]))
    assert curve.bumper_N[-1] == pytest.approx(b, rel=1e-12)  # the bumper's force at full travel
    assert curve.spring_N[-1] - (k * travel + p) == pytest.approx(b, rel=1e-9)
    weight = values["sled.body_mass_kg"] * G
    assert curve.sag_mm == pytest.approx((weight - p) / k, rel=1e-9)  # beyond the top-out's reach here
    assert curve.load_N == pytest.approx(weight)


def test_the_spring_figure_shows_the_stroke_in_mm_and_n_on_the_springs_own_scale():
    values = _coil(np.random.default_rng(5))
    curve = spring_curve("S1", values)
    fig = spring_figure(curve)
    (ax,) = fig.axes
    assert "mm" in ax.get_xlabel() and "travel" in ax.get_xlabel()
    assert "(N)" in ax.get_ylabel() and "force" in ax.get_ylabel()
    assert ax.get_xlim() == pytest.approx((-values["fork.stops.extension_mm"], 120.0))
    top = values["fork.spring.rate_N_per_mm"] * 120 + values["fork.spring.preload_N"] + values["fork.stops.bumper_force_N"]
    low, high = ax.get_ylim()
    assert top < high < 1.15 * top  # the spring's own range, not the hard stop's (which would be ~1e7 N)
    bottom = curve.spring_N[0]
    assert 1.15 * bottom - 0.15 * top < low < bottom
    labels = [line.get_label() for line in ax.get_lines() if not line.get_label().startswith("_")]
    for part in ("spring at rest (sum)", "main spring + preload", "top-out spring"):
        assert part in labels
    assert any(label.startswith("bottom-out bumper") for label in labels)
    assert any(label.startswith(f"preload {values['fork.spring.preload_N']:g}") for label in labels)
    sag = [line for line in ax.get_lines() if line.get_marker() == "o"]
    assert len(sag) == 1 and sag[0].get_xdata()[0] == pytest.approx(curve.sag_mm)


def test_a_directional_spring_is_drawn_on_each_stroke():
    """S2: compression rate 17.0, rebound 15.93 N/mm (reference.toml), no preload: each stroke's
    curve is its rate x travel, at rest their mean."""
    c = load("S2")
    curve = spring_curve("S2")
    x = curve.travel_mm
    inside = (x > 0) & (x < curve.bumper_start_mm)
    kc, kr = c["fork.spring.compression_rate_N_per_mm"], c["fork.spring.rebound_rate_N_per_mm"]
    np.testing.assert_allclose(curve.compression_N[inside], kc * x[inside], rtol=1e-9)
    np.testing.assert_allclose(curve.rebound_N[inside], kr * x[inside], rtol=1e-9)
    np.testing.assert_allclose(curve.spring_N[inside], 0.5 * (kc + kr) * x[inside], rtol=1e-9)
    labels = [line.get_label() for line in spring_figure(curve).axes[0].get_lines()]
    assert "on the compression stroke" in labels and "on the rebound stroke" in labels


def test_an_air_curve_is_the_gas_law_and_its_spacers_are_drawn():
    """Negative chamber off: A [(p + p_atm) (V / (V - A x))^n - p_atm] beyond the top-out's reach,
    one curve per spacer count 0-3, each stiffer at full travel than the one before."""
    curve = spring_curve("air120", {"fork.spring.negative_volume_cm3": 0.0})
    c = curve.config
    a = math.pi * (c["fork.spring.piston_diameter_mm"] * 1e-3) ** 2 / 4
    v = (c["fork.spring.air_volume_cm3"] - c["fork.spring.tokens"] * c["fork.spring.token_volume_cm3"]) * 1e-6
    n = c["fork.spring.polytropic_index"]
    p = c["fork.spring.air_pressure_psi"] * PSI
    x = curve.travel_mm * 1e-3
    free = x > curve.top_out_engagement_mm * 1e-3
    gas = a * ((p + P_ATM) * (v / (v - a * x[free])) ** n - P_ATM)
    np.testing.assert_allclose(curve.main_N[free], gas, rtol=1e-9)
    assert curve.preload_N == pytest.approx(a * p, rel=1e-12)  # the air's force at full extension
    fig = spring_figure(curve)
    left, right = fig.axes
    labels = [line.get_label() for line in right.get_lines() if not line.get_label().startswith("_")]
    assert labels == ["0 spacers", "1 spacer", "2 spacers", "3 spacers"]
    ends = [line.get_ydata()[-1] for line in right.get_lines() if line.get_label() in labels]
    assert all(b > a for a, b in zip(ends, ends[1:]))
    for ax in (left, right):
        assert ax.get_xlim() == pytest.approx((-c.get("fork.stops.extension_mm", 5.0), c["fork.travel_mm"]))
        assert -2000 < ax.get_ylim()[0] < 0 < 5000 < ax.get_ylim()[1] < 10000


def test_the_air_study_figure_draws_the_stroke_on_a_sane_scale():
    """The air study's spring curves (which drew into the top stop: every curve flat at 0 on a
    -7e6 N axis) span the stroke from the top stop to full travel on the springs' own scale."""
    from mtbmj.drop.air_study import spring_curves_figure, static_sag_mm, variants

    base = load("air120")
    fig = spring_curves_figure(base)
    left, right = fig.axes
    for ax, names in ((left, 4), (right, 3)):
        assert ax.get_xlim() == pytest.approx((-5.0, 120.0))
        low, high = ax.get_ylim()
        assert -1000 < low < 0 and 3000 < high < 10000
        lines = [line for line in ax.get_lines() if not line.get_label().startswith("_")]
        assert len(lines) == names
        for line in lines:
            y = np.asarray(line.get_ydata())
            assert np.ptp(y) > 1000 and low <= y.min() and y.max() <= high  # a curve, drawn whole
        assert "mm" in ax.get_xlabel() and "(N)" in ax.get_ylabel()
    dots = [line for line in left.get_lines() if line.get_marker() == "o"]
    sags = [static_sag_mm(base.with_overrides(change)) for name, (g, change) in variants(base).items()
            if g == "spacers"]
    assert sorted(d.get_xdata()[0] for d in dots) == pytest.approx(sorted(sags))


# --- damper -----------------------------------------------------------------------------------------

V = [-1500.0, -800.0, -400.0, -150.0, -50.0, 0.0, 50.0, 150.0, 400.0, 800.0, 1500.0]
TABLE_F = np.array(DAMPER_TABLE["fork.damper.force_N"])


def _clicks(positions, scale):
    return {"fork.damper.model": "clicks", "fork.damper.velocity_mm_per_s": V,
            "fork.damper.compression_clicks_measured": positions, "fork.damper.rebound_clicks_measured": positions,
            "fork.damper.compression_force_N": [tuple(TABLE_F[6:] * s) for s in scale],
            "fork.damper.rebound_force_N": [tuple(TABLE_F[:5] * s) for s in scale],
            "fork.damper.compression_clicks": 4.0, "fork.damper.rebound_clicks": 9.0}


def test_a_clicks_damper_gets_one_line_per_click_interpolated_between_measured_rows():
    positions, scale = [0.0, 5.0, 9.0, 16.0], [1.8, 1.3, 1.0, 0.6]
    curve = damper_curve("S12", _clicks(positions, scale))
    coulomb = load("S12")["fork.friction.coulomb_N"]
    assert [c.adjuster for c in curve.clicks] == ["compression", "rebound"]
    for lines, rows, side in ((curve.clicks[0], TABLE_F[6:], 1), (curve.clicks[1], TABLE_F[:5], -1)):
        assert sorted(lines.force_N) == list(range(0, 17))
        grid = [v for v in V if side * v > 0]
        for click, force in lines.force_N.items():
            factor = np.interp(click, positions, scale)  # rows scale linearly: so does the interpolation
            at = np.interp(grid, lines.velocity_mm_per_s, force)
            np.testing.assert_allclose(at, rows * factor, rtol=1e-12)
    fig = damper_figure(curve)
    at_setting = fig.axes[0]
    comp, = [ax for ax in fig.axes if ax.get_title().startswith("compression adjuster: one line per click")]
    reb, = [ax for ax in fig.axes if ax.get_title().startswith("rebound adjuster: one line per click")]
    for ax, setting in ((comp, 4), (reb, 9)):
        lines = [line for line in ax.get_lines() if line.get_label().endswith("clicks") or "setting" in line.get_label()]
        assert len(lines) == 17  # one line per click, 0-16
        thick = [line for line in lines if line.get_linewidth() > 2]
        assert len(thick) == 1 and thick[0].get_label() == f"{setting} clicks (setting)"
        assert "mm/s" in ax.get_xlabel() and "(N)" in ax.get_ylabel()
    # at the settings: hydraulic + the Coulomb friction (F_C tanh(v / 5 mm/s): F_C at the table's ends)
    total = dict(zip(curve.velocity_mm_per_s, curve.total_N))
    assert total[1500.0] == pytest.approx(TABLE_F[-1] * np.interp(4, positions, scale) + coulomb, rel=1e-9)
    assert total[-1500.0] == pytest.approx(TABLE_F[0] * np.interp(9, positions, scale) - coulomb, rel=1e-9)
    assert at_setting.get_xlim() == pytest.approx((-1500.0, 1500.0))


def test_a_linear_damper_is_c_times_v_and_draws_three_lines():
    c = load("S1")["fork.damper.coefficient_N_s_per_m"]
    curve = damper_curve("S1")
    np.testing.assert_allclose(curve.damper_N, c * curve.velocity_mm_per_s * 1e-3, rtol=1e-12)
    assert not np.any(curve.friction_N) and not curve.clicks
    assert curve.velocity_mm_per_s[0] == -1500.0 and curve.velocity_mm_per_s[-1] == 1500.0
    (ax,) = damper_figure(curve).axes
    assert len([line for line in ax.get_lines() if not line.get_label().startswith("_")]) == 3
    assert ax.get_ylim() == pytest.approx((-c * 1.5 * 1.12, c * 1.5 * 1.12), rel=1e-9)  # +-1.5 m/s, 6 % margin


# --- the command ------------------------------------------------------------------------------------

def _rows(path):
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    return list(csv.DictReader(lines))


def test_curve_command_writes_figures_and_tables_and_replaces_its_own_output(tmp_path, capsys):
    out = tmp_path / "curve"
    argv = ["curve", "S12", "--set", "fork.stops.bumper_force_N=2500", "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "sag 26.8 mm" in printed and "2500 N of it the bumper" in printed
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [".lock", output.RECORD, "config.toml", "curve.json", "damper_curve.csv", "damper_curve.png",
         "spring_curve.csv", "spring_curve.png"])
    rows = _rows(out / "spring_curve.csv")
    assert float(rows[-1]["travel_mm"]) == 120.0 and float(rows[-1]["bumper_N"]) == pytest.approx(2500.0)
    assert float(rows[0]["travel_mm"]) == -5.0
    for png in ("spring_curve.png", "damper_curve.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(argv) == 0  # its own earlier result is replaced
    assert output.foreign_entry(out) is None


def test_curve_command_with_clicks_writes_the_click_table(tmp_path, capsys):
    config = tmp_path / "clicks.toml"
    config.write_text(load("S12", _clicks([0.0, 6.0, 12.0], [1.5, 1.0, 0.7])).to_toml())
    out = tmp_path / "c"
    assert main(["curve", str(config), "--out", str(out)]) == 0
    assert "13 clicks of compression, 13 clicks of rebound" in capsys.readouterr().out
    rows = _rows(out / "damper_clicks.csv")
    assert {r["clicks"] for r in rows if r["adjuster_key"] == "fork.damper.rebound_clicks"} == {str(i) for i in range(13)}
    at = [r for r in rows if r["adjuster_key"] == "fork.damper.compression_clicks" and r["clicks"] == "6"
          and float(r["velocity_mm_per_s"]) == 1500.0]
    assert float(at[0]["damper_N"]) == pytest.approx(TABLE_F[-1], rel=1e-9)


@pytest.mark.parametrize("argv, needle", [
    (["S12", "--set", "fork.stops.bumper_length_mm=500"], "fork.stops.bumper_length_mm"),
    (["S12", "--max-velocity-mm-per-s", "-3"], "--max-velocity-mm-per-s"),
    (["S12", "--max-velocity-mm-per-s", "nan"], "--max-velocity-mm-per-s"),
    (["no-such-preset"], "no-such-preset"),
    (["air120", "--set", "fork.spring.tokens=30"], "fork.spring.tokens"),
])
def test_bad_curve_input_is_one_line_and_writes_nothing(tmp_path, capsys, argv, needle):
    out = tmp_path / "curve"
    one_line(capsys, ["curve", *argv, "--out", out], needle)
    assert not out.exists()


def test_a_spring_that_cannot_carry_the_load_has_no_sag():
    soft = {"fork.spring.rate_N_per_mm": 5.0, "fork.stops.bumper_force_N": 100.0, "sled.body_mass_kg": 80.0}
    curve = spring_curve("S1", soft)  # 5 N/mm x 120 mm + 100 N = 700 N < 80 kg x g
    assert curve.sag_mm is None and curve.spring_N[-1] == pytest.approx(700.0)
    assert "no sag" in fork_curves("S1", soft).line()  # drawn all the same


def test_the_figures_page_runs_as_written(tmp_path, monkeypatch, capsys):
    """Every command of docs/figures.md, in its order, from an empty folder: exit 0, and the files
    the page names are there."""
    import re
    import shlex
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "figures.md").read_text()
    commands = [shlex.split(line, comments=True) for block in re.findall(r"```bash\n(.*?)```", page, flags=re.S)
                for line in block.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert all(c[0] == "mtbmj" for c in commands)
    assert {c[1] for c in commands} >= {"curve", "compare"}
    monkeypatch.chdir(tmp_path)
    for argv in commands:
        assert main(argv[1:]) == 0, " ".join(argv)
    for name in ("spring_curve.png", "spring_curve.csv", "damper_curve.png", "damper_curve.csv", "curve.json"):
        assert (tmp_path / "out" / "curve-s12" / name).is_file()
    assert (tmp_path / "out" / "curve-clicks" / "damper_clicks.csv").is_file()
    header = (tmp_path / "out" / "curve-air120" / "spring_curve.csv").read_text().splitlines()[1]
    assert all(f"spring_{n}_spacers_N" in header for n in range(4))
    for name in ("compare.png", "differences.csv", "compare.json"):
        assert (tmp_path / "out" / "compare" / name).is_file() and (tmp_path / "out" / "compare-rock" / name).is_file()

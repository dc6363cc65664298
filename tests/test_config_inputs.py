"""Issue 23: a configuration in a rider's terms (rider and bike mass with the front share, a spring
rate in lb/in, pressures in bar), exactly one way per source; tire pressures riders run; and
one-line warnings for values far outside what any bike or sled has (unit mistakes), with the run
going on. Expected values are worked out here by hand from the unit definitions and the stated
derivation, not taken from the code under test."""
import json
import warnings

import pytest

import mtbmj
from mtbmj import cli, compose
from mtbmj.config import ConfigWarning, load
from mtbmj.errors import ConfigError

from helpers import one_line

# the conversions from the definitions: 1 lbf = 4.4482216152605 N, 1 in = 25.4 mm (both exact);
# 1 psi = 1 lbf / in2 = 6894.757293168 Pa, 1 bar = 1e5 Pa
N_PER_MM_PER_LB_PER_IN = 4.4482216152605 / 25.4
PSI_PER_BAR = 1e5 / (4.4482216152605 / 0.0254 ** 2)


def test_the_conversions_are_a_riders_chart():
    """1 lb/in = 0.17512684 N/mm and 1 bar = 14.5037738 psi, to the 8 digits a chart prints."""
    assert load("S1", {"fork.spring.rate_lb_per_in": 100.0})["fork.spring.rate_N_per_mm"] == pytest.approx(
        17.512684, abs=0.5e-6)
    assert load("S1", {"tire.pressure_bar": 1.5})["tire.pressure_psi"] == pytest.approx(21.7556607, abs=1.5 * 0.5e-7)
RIDER = {"sled.rider_mass_kg": 85.0, "sled.bike_mass_kg": 11.0, "sled.front_share_percent": 58.0}


def write(path, text):
    path.write_text(text)
    return path


def quiet_load(*args):
    """``load`` with its warnings caught (a test that expects none checks ``warnings`` itself)."""
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        return load(*args)


# --------------------------------------------------------------------------------- rider inputs


def test_rider_inputs_give_the_sprung_front_mass():
    c = load("S12", RIDER)
    # 58 % of (85 + 11) kg on the front wheel, less the 2.3 kg wheel itself (unsprung)
    assert c["sled.body_mass_kg"] == pytest.approx(0.58 * 96.0 - 2.3, rel=1e-12)  # 53.38 kg
    assert compose.setup(c).body_mass == pytest.approx(53.38, rel=1e-12)
    assert c.warnings == []
    # the paper's 53.2 kg sled is the same rider and bike at 57.8125 % front
    paper = load("S12", {**RIDER, "sled.front_share_percent": 57.8125})
    assert paper["sled.body_mass_kg"] == pytest.approx(53.2, rel=1e-12)


def test_rider_inputs_run_the_same_drop_as_the_mass_they_give():
    by_rider = mtbmj.run_drop("S12", "fast", overrides=RIDER, duration=0.4)
    by_mass = mtbmj.run_drop("S12", "fast", overrides={"sled.body_mass_kg": 0.58 * 96.0 - 2.3}, duration=0.4)
    assert by_rider.summary["max_fork_mm"] == pytest.approx(by_mass.summary["max_fork_mm"], abs=1e-9)
    assert by_rider.summary["max_fork_mm"] != pytest.approx(
        mtbmj.run_drop("S12", "fast", duration=0.4).summary["max_fork_mm"], abs=1e-3)  # 53.38 is not 53.2


def test_rider_inputs_in_a_file_on_a_preset_replace_its_body_mass(tmp_path):
    f = write(tmp_path / "me.toml", 'base = "S12"\n[sled]\nrider_mass_kg = 72\nbike_mass_kg = 14.5\n'
                                    'front_share_percent = 40\n')
    c = load(f)
    assert c["sled.body_mass_kg"] == pytest.approx(0.40 * 86.5 - 2.3, rel=1e-12)
    # a file on top of it changes the rider alone: bike and share come from the base file
    g = write(tmp_path / "heavier.toml", 'base = "me.toml"\n[sled]\nrider_mass_kg = 95\n')
    assert load(g)["sled.body_mass_kg"] == pytest.approx(0.40 * 109.5 - 2.3, rel=1e-12)
    # a lighter front wheel leaves more of the same front load on the fork
    assert load(f, {"sled.wheel_mass_kg": 1.8})["sled.body_mass_kg"] == pytest.approx(0.40 * 86.5 - 1.8, rel=1e-12)
    # the sprung mass given later replaces the rider inputs (an override, like any key's)
    h = load(f, {"sled.body_mass_kg": 60.0})
    assert h["sled.body_mass_kg"] == 60.0 and "sled.rider_mass_kg" not in h.values


def test_a_rider_configuration_round_trips_through_its_toml(tmp_path):
    c = load("S12", RIDER)
    text = c.to_toml()
    assert "rider_mass_kg = 85.0" in text and "body_mass_kg" not in text  # derived again when read
    back = load(write(tmp_path / "copy.toml", text))
    assert dict(back.values) == dict(c.values) and back.digest() == c.digest()


@pytest.mark.parametrize("given, needles", [
    ({**RIDER, "sled.body_mass_kg": 53.2}, ["sled.body_mass_kg", "sled.rider_mass_kg", "two ways"]),
    ({"sled.rider_mass_kg": 85.0}, ["sled.rider_mass_kg", "sled.bike_mass_kg", "sled.front_share_percent"]),
    ({"sled.rider_mass_kg": 85.0, "sled.front_share_percent": 58.0}, ["sled.bike_mass_kg"]),
    ({**RIDER, "sled.front_share_percent": 120.0}, ["sled.front_share_percent", "100"]),
    ({**RIDER, "sled.front_share_percent": 0.0}, ["sled.front_share_percent", "positive"]),
    ({**RIDER, "sled.front_share_percent": 2.0}, ["sled.wheel_mass_kg", "nothing"]),  # 1.92 kg < 2.3 kg wheel
    # a share typed as a fraction leaves nothing for the fork either; the line says what was meant
    ({**RIDER, "sled.front_share_percent": 0.58}, ["sled.front_share_percent", "probably meant 0.58 as a fraction = 58 %"]),
    ({**RIDER, "sled.bike_mass_kg": -11.0}, ["sled.bike_mass_kg", "positive"]),
])
def test_bad_rider_inputs_name_the_keys(tmp_path, capsys, given, needles):
    with pytest.raises(ConfigError) as exc:
        load("S12", given)
    for needle in needles:
        assert needle in str(exc.value)
    out = tmp_path / "out"
    argv = ["drop", "S12", "--quiet", "--out", out]
    for key, value in given.items():
        argv += ["--set", f"{key}={value}"]
    one_line(capsys, argv, *needles)
    assert not out.exists()


def test_both_ways_in_one_file_is_refused_naming_the_file_and_keys(tmp_path, capsys):
    f = write(tmp_path / "both.toml", 'base = "S12"\n[sled]\nbody_mass_kg = 50\nrider_mass_kg = 80\n'
                                      'bike_mass_kg = 12\nfront_share_percent = 55\n')
    with pytest.raises(ConfigError) as exc:
        load(f)
    assert all(n in str(exc.value) for n in ("both.toml", "sled.body_mass_kg", "sled.rider_mass_kg"))
    one_line(capsys, ["drop", f, "--out", tmp_path / "out"], "both.toml", "sled.body_mass_kg", "sled.rider_mass_kg")
    assert not (tmp_path / "out").exists()


def test_rider_inputs_from_the_command_line(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["drop", "S12", "--engine", "fast", "--quiet", "--duration", "0.05", "--out", out]
    for key, value in RIDER.items():
        argv += ["--set", f"{key}={value:g}"]
    assert cli.main([str(a) for a in argv]) == 0
    assert capsys.readouterr().err == ""
    written = (out / "config.toml").read_text()
    assert "rider_mass_kg = 85.0" in written and "front_share_percent = 58.0" in written


# ---------------------------------------------------------------------------- alternative units


def test_spring_rate_in_lb_per_in():
    c = load("S1", {"fork.spring.rate_lb_per_in": 90.0})
    assert c["fork.spring.rate_N_per_mm"] == pytest.approx(90.0 * N_PER_MM_PER_LB_PER_IN, rel=1e-12)  # 15.76 N/mm
    assert "fork.spring.rate_lb_per_in" not in c.values  # downstream sees the canonical key only
    assert compose.setup(c).fork.spring.main.rate == pytest.approx(90.0 * N_PER_MM_PER_LB_PER_IN * 1e3, rel=1e-12)


def test_air_pressure_in_bar_on_a_preset_that_gives_psi():
    c = load("air120", {"fork.spring.air_pressure_bar": 6.0})
    assert c["fork.spring.air_pressure_psi"] == pytest.approx(6.0 * PSI_PER_BAR, rel=1e-12)  # 87.02 psi
    same = load("air120", {"fork.spring.air_pressure_psi": 6.0 * PSI_PER_BAR})
    fork, expected = compose.setup(c).fork.spring, compose.setup(same).fork.spring
    for x in (0.0, 0.03, 0.09):
        assert fork.force(x, 0.0) == pytest.approx(expected.force(x, 0.0), rel=1e-12)


def test_tire_pressure_in_bar():
    c = load("S12", {"tire.pressure_bar": 1.5})
    psi = 1.5 * PSI_PER_BAR  # 21.76 psi
    assert c["tire.pressure_psi"] == pytest.approx(psi, rel=1e-12)
    # k_static = 62 N/mm x p / 25 psi; impact 1.38 x static (docs/air.md, "Tire pressure")
    assert compose.setup(c).tire.impact.rate == pytest.approx(1.38 * 62.0 * psi / 25.0 * 1e3, rel=1e-12)


@pytest.mark.parametrize("pair", [
    {"fork.spring.rate_N_per_mm": 15.0, "fork.spring.rate_lb_per_in": 85.0},
    {"fork.spring.air_pressure_psi": 85.0, "fork.spring.air_pressure_bar": 5.9},
    {"tire.pressure_psi": 22.0, "tire.pressure_bar": 1.5},
])
def test_both_units_of_a_pair_are_refused(tmp_path, capsys, pair):
    keys = list(pair)
    with pytest.raises(ConfigError) as exc:
        load("air120", pair)
    assert all(k in str(exc.value) for k in keys)
    section, _, _ = keys[0].rpartition(".")
    f = write(tmp_path / "two.toml", f'base = "air120"\n[{section}]\n' + "".join(
        f"{k.rpartition('.')[2]} = {v}\n" for k, v in pair.items()))
    one_line(capsys, ["drop", f, "--out", tmp_path / "out"], "two.toml", *keys)
    one_line(capsys, ["drop", "air120", "--set", f"{keys[0]}={pair[keys[0]]}", "--set", f"{keys[1]}={pair[keys[1]]}",
                      "--out", tmp_path / "out"], *keys)
    assert not (tmp_path / "out").exists()


def test_a_file_in_one_unit_is_overridden_in_the_other(tmp_path):
    f = write(tmp_path / "coil.toml", 'base = "S1"\n[fork.spring]\nrate_lb_per_in = 80\n')
    assert load(f)["fork.spring.rate_N_per_mm"] == pytest.approx(80 * N_PER_MM_PER_LB_PER_IN, rel=1e-12)
    assert load(f, {"fork.spring.rate_N_per_mm": 12.0})["fork.spring.rate_N_per_mm"] == 12.0


@pytest.mark.parametrize("key, value, needle", [
    ("fork.spring.air_pressure_bar", -1.0, "negative"),
    ("tire.pressure_bar", 0.0, "positive"),
    ("tire.pressure_psi", -2.0, "positive"),
    ("fork.spring.rate_lb_per_in", 0.0, "positive"),
])
def test_impossible_values_in_the_new_keys_are_refused(tmp_path, capsys, key, value, needle):
    one_line(capsys, ["drop", "air120", "--set", f"{key}={value}", "--out", tmp_path / "out"], key, needle)
    assert not (tmp_path / "out").exists()


def test_a_key_without_its_unit_names_both_units():
    with pytest.raises(ConfigError) as exc:
        load("S1", {"fork.spring.rate": 90})
    assert "fork.spring.rate_N_per_mm" in str(exc.value) and "fork.spring.rate_lb_per_in" in str(exc.value)


# ------------------------------------------------------------------------------- plausibility


# What a careless user types, and what they meant (worked out here).
MISTAKES = [
    ("sled.drop_height_mm", 0.3, "0.3 m = 300 mm"),                      # metres in a mm key
    ("fork.spring.rate_N_per_mm", 6000, "6000 N/m = 6 N/mm"),             # N/m in an N/mm key
    ("sled.body_mass_kg", 48000, "48000 g = 48 kg"),                      # grams in a kg key
    ("fork.travel_mm", 0.12, "0.12 m = 120 mm"),
    ("fork.travel_mm", 4.7, "4.7 in = 119.4 mm"),                         # inches
    ("tire.impact_rate_N_per_mm", 85100, "85100 N/m = 85.1 N/mm"),
    ("fork.damper.coefficient_N_s_per_m", 0.2, "0.2 N s/mm = 200 N s/m"),
    ("sled.wheel_mass_kg", 2300, "2300 g = 2.3 kg"),
    ("sled.rider_mass_kg", 85000, "85000 g = 85 kg"),
    ("sled.front_share_percent", 5, "a value within 20-80 %"),           # (as a fraction: refused, see above)
    ("tire.pressure_psi", 1.7, "1.7 bar = 24.66 psi"),
    ("tire.pressure_bar", 25, "25 psi = 1.724 bar"),
    ("fork.spring.air_pressure_psi", 6, "6 bar = 87.02 psi"),
    ("fork.spring.air_pressure_psi", 600, "600 kPa = 87.02 psi"),
    ("tire.radius_mm", 0.37, "0.37 m = 370 mm"),
]


@pytest.mark.parametrize("key, value, meant", MISTAKES)
def test_a_unit_mistake_gets_a_warning_saying_what_was_probably_meant(key, value, meant):
    given = {**RIDER, key: value} if key in RIDER else {key: value}
    with pytest.warns(ConfigWarning) as caught:
        c = load("air120", given)
    assert len(c.warnings) == 1 and len(caught) == 1
    line = c.warnings[0]
    assert line == str(caught[0].message)
    assert line.startswith(f"{key} = {value:g} ") and line.endswith(f"probably meant {meant}"), line


@pytest.mark.parametrize("key, value, meant", MISTAKES[:3])
def test_the_command_line_warns_once_and_runs(tmp_path, capsys, key, value, meant):
    out = tmp_path / "out"
    assert cli.main(["drop", "S1", "--set", f"{key}={value}", "--engine", "fast", "--duration", "0.2", "--quiet",
                     "--out", str(out)]) == 0
    captured = capsys.readouterr()
    err = captured.err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"mtbmj: warning: {key} = {value:g} "), err
    assert err[0].endswith(f"probably meant {meant}")
    assert (out / "summary.json").is_file() and "wrote" in captured.out


def test_the_issues_reproduction_drop_height_on_the_default_engine(tmp_path, capsys):
    out = tmp_path / "out"
    assert cli.main(["drop", "S12", "--set", "sled.drop_height_mm=0.3", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.count("mtbmj: warning: sled.drop_height_mm = 0.3 mm") == 1 and "probably meant 0.3 m = 300 mm" in err
    assert json.loads((out / "summary.json").read_text())


def test_no_preset_has_an_implausible_value():
    from mtbmj.config import preset_names

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in preset_names():
            assert load(name).warnings == [], name


@pytest.mark.parametrize("name", ["S12", "air120", "S1"])
def test_a_preset_run_prints_no_warning(tmp_path, capsys, name):
    assert cli.main(["drop", name, "--engine", "fast", "--duration", "0.1", "--quiet", "--out",
                     str(tmp_path / "out")]) == 0
    assert capsys.readouterr().err == ""


def test_real_bikes_are_plausible():
    """Values of real bikes (a downhill fork, a heavy rider on an e-bike, a 27.5 x 2.6 tire at 30 psi
    in bar) get no plausibility warning."""
    real = {"fork.travel_mm": 200.0, "sled.rider_mass_kg": 110.0, "sled.bike_mass_kg": 25.0,
            "sled.front_share_percent": 45.0, "tire.radius_mm": 350.0, "fork.spring.rate_lb_per_in": 60.0,
            "sled.drop_height_mm": 1500.0, "fork.damper.coefficient_N_s_per_m": 3000.0}
    c = load("S1", real)
    assert c.warnings == []
    tire = quiet_load("S1", {"tire.pressure_bar": 2.07})  # 30 psi: plausible, but outside the measured 15-25 psi
    assert len(tire.warnings) == 1 and "extrapolated" in tire.warnings[0] and "probably meant" not in tire.warnings[0]


def test_a_study_prints_a_warning_once_for_all_its_configurations(tmp_path, capsys):
    assert cli.main(["study", "--presets", "S1,S2", "--engines", "fast", "--duration", "0.05", "--workers", "1",
                     "--quiet", "--set", "sled.drop_height_mm=0.3", "--out", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == ["mtbmj: warning: sled.drop_height_mm = 0.3 mm is far below what any bike or sled has "
                   "(1-5000 mm): probably meant 0.3 m = 300 mm"]


def test_a_refused_run_prints_only_its_error(tmp_path, capsys):
    one_line(capsys, ["drop", "S12", "--set", "sled.drop_height_mm=0.3", "--set", "tire.model=tubeless",
                      "--out", tmp_path / "out"], "tire.model")


def test_a_refusal_caused_by_a_unit_mistake_says_so_in_its_one_line(tmp_path, capsys):
    # 0.12 mm of travel is refused (the top-out spring would stay engaged); metres were meant
    err = one_line(capsys, ["drop", "S12", "--set", "fork.travel_mm=0.12", "--out", tmp_path / "out"],
                   "fork.travel_mm", "probably meant 0.12 m = 120 mm")
    assert err.count("probably meant") == 1
    # a warning about another key than the refusal names stays out of the line
    err = one_line(capsys, ["drop", "S12", "--set", "fork.travel_mm=0.12", "--set", "sled.body_mass_kg=48000",
                            "--out", tmp_path / "out"], "fork.travel_mm", "probably meant 0.12 m")
    assert "sled.body_mass_kg" not in err
    assert not (tmp_path / "out").exists()


def test_a_diverged_run_names_the_implausible_value_in_its_one_line(tmp_path, capsys):
    err = one_line(capsys, ["drop", "S1", "--set", "sled.drop_height_mm=1e7", "--out", tmp_path / "out"],
                   "diverged", "sled.drop_height_mm = 1e+07 mm")
    assert "probably meant a value within" in err


def test_the_python_api_warns_and_changes_no_global_warning_state(tmp_path):
    before = list(warnings.filters), warnings.showwarning
    with pytest.warns(ConfigWarning, match="sled.body_mass_kg = 48000"):
        result = mtbmj.run_drop("S12", "fast", overrides={"sled.body_mass_kg": 48000}, duration=0.05)
    assert result.config.warnings and "48 kg" in result.config.warnings[0]
    base = quiet_load("S12")
    with pytest.warns(ConfigWarning, match="sled.drop_height_mm = 0.3"):  # overrides on a loaded Config
        mtbmj.run_drop(base, "fast", overrides={"sled.drop_height_mm": 0.3}, duration=0.05)
    assert cli.main(["drop", "S12", "--set", "sled.body_mass_kg=48000", "--engine", "fast", "--duration", "0.05",
                     "--quiet", "--out", str(tmp_path / "out")]) == 0
    assert (list(warnings.filters), warnings.showwarning) == before


def test_a_later_value_clears_the_earlier_warning(tmp_path):
    f = write(tmp_path / "odd.toml", 'base = "S12"\n[sled]\ndrop_height_mm = 0.3\n')
    assert len(quiet_load(f).warnings) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load(f, {"sled.drop_height_mm": 300.0}).warnings == []


def test_the_warning_and_the_tire_model_state_the_same_measured_range():
    from mtbmj.config import TIRE_PRESSURE_MEASURED_PSI
    from mtbmj.controllers import tire

    assert [p / 6894.757293168 for p in tire.PRESSURE_RANGE] == pytest.approx(TIRE_PRESSURE_MEASURED_PSI, rel=1e-12)
    assert TIRE_PRESSURE_MEASURED_PSI == (15.0, 25.0)  # 1.03 to 1.72 bar (docs/reference.md section 3)


def test_a_byte_order_mark_is_not_part_of_the_file(tmp_path, capsys):
    """A configuration saved by Notepad or Excel as "UTF-8" starts with a byte-order mark: it was
    refused as "not valid TOML (Invalid statement (at line 1, column 1))"."""
    text = 'base = "S12"\r\n[sled]\r\nbody_mass_kg = 60.0\r\n'
    (tmp_path / "plain.toml").write_text(text)
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load(str(tmp_path / "bom.toml")).values == load(str(tmp_path / "plain.toml")).values
    assert load(str(tmp_path / "bom.toml")).values["sled.body_mass_kg"] == 60.0
    assert cli.main(["drop", str(tmp_path / "bom.toml"), "--duration", "0.05", "--no-figure", "--quiet",
                     "--out", str(tmp_path / "out")]) == 0, capsys.readouterr().err

"""Careless input, round 32: what round 31b (``tests/test_fuzz_careless31b.py``) left, then new cases typed as a
new user would across the commands. Each case failed before its fix: a run out of the model's envelope that
said nothing, a unit slip not named, a traceback or a refusal for a false reason. Inputs are written here."""
from __future__ import annotations

import re
import warnings

import pytest

from mtbmj import limits
from mtbmj.rolling import terrain as T
from helpers import command_err, refused
from conftest import SHARED_DATA

KMH = 1000.0 / 3600.0  # m/s per km/h, by the definitions of the kilometre and the hour


# --- 1. what round 31b left: a rock garden scaled to rocks of metres; a speed typed in km/h -----------------

def test_a_rock_garden_scaled_past_a_trail_is_named():
    """``rock_garden:height_scale=20`` (its 110 mm rock made 2.2 m) ran unsaid: height_scale is no ``_mm`` key.
    The garden's rocks are 50-110 mm (the docstring of ``rock_garden``); x20 is 2200 mm, over the 1000 mm
    a wheel rolls over; x9 (990 mm) is not."""
    with pytest.warns(Warning, match=re.escape("terrain rock_garden: height_scale = 20 makes its tallest rock "
                                               "2200 mm, over 1000 mm, taller than any trail feature")):
        T.make("rock_garden:height_scale=20")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        T.make("rock_garden:height_scale=9")
        T.make("rock_garden")


def test_a_speed_typed_in_km_per_h_names_km_per_h():
    """``--speed 40`` (km/h) warned "(a unit mistake?)" alone: m/s had no slip in the units' table."""
    with pytest.warns(Warning, match=re.escape(f"(a unit mistake? probably meant 40 km/h = {40 * KMH:.4g} m/s)")):
        limits.argument("--speed", "40")
    with pytest.warns(Warning, match=re.escape("(a unit mistake?)")):  # the other side: 0.1 m/s is no km/h slip
        limits.argument("--speed", "0.1")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert limits.argument("--speed", "12") == 12.0


# --- 2. a terrain's size past what the tyre's search can cut: a traceback of numpy's MemoryError before ----------

@pytest.mark.parametrize("spec, said", [
    # one wave 3 km long: 6e5 points at 5 mm (washboard's docstring); wavelength_mm=1e9 was 38.7 GiB of scratch
    ("washboard:wavelength_mm=3e6", "terrain washboard: wavelength_mm = 3e+06 mm is 3000 m, longer than the 2000 m"),
    ("rock:length_mm=3e6", "terrain rock: length_mm = 3e+06 mm is 3000 m, longer than the 2000 m"),
    # a rock 1e12 mm (1e9 m) high: up and down its flanks 2e9 m of surface, cut into 1 cm pieces (5.82 TiB)
    ("rock:height_mm=1e12", "terrain rock: its surface, along its distances and up and down its heights, is 2e+09 m"),
])
def test_a_terrain_past_what_can_be_cut_is_refused_by_its_key(spec, said):
    with pytest.raises(T.TerrainError, match=re.escape(said)):
        T.make(spec)


def test_a_csv_terrain_kilometres_long_or_high_is_refused_in_one_line(tmp_path, capfd):
    """A 10 km profile's distances typed in mm under distance_m (1e7 m), or a spike of 1e12 mm: numpy's MemoryError
    (exit 1, a traceback: 29.8 GiB, 5.82 TiB) when the tyre's search cut the profile into 1 cm pieces. Now one line
    naming the file. (An 8 km one runs with its unit warning: tests/test_rolling.py.)"""
    long_ = tmp_path / "long.csv"
    long_.write_text("distance_m,height_mm\n0,0\n5e6,40\n1e7,0\n")
    tall = tmp_path / "tall.csv"
    tall.write_text("distance_m,height_mm\n0,0\n10,0\n10.5,1e12\n11,0\n20,0\n")
    for path, said in ((long_, "is 1e+07 m long, more than the 100000 m"), (tall, "is 2e+09 m long")):
        stamp = path.stat().st_mtime_ns
        line = refused(["roll", path, "--speed", "5", "--duration", "0.01", "--out", tmp_path / "out"],
                       tmp_path / "out", capfd, f"{path}: its surface")
        assert said in line and path.stat().st_mtime_ns == stamp, line
    # the other side: a 2 km washboard and a 2 km climb at 40 % (its longest surface, 2.15 km) are terrains
    for spec in ("washboard:length_m=2000", "climb:length_m=2000,grade_percent=40"):
        assert T.make(spec).x.size > 2


def test_a_terrain_key_given_twice_is_refused():
    """``rock:height_mm=100,height_mm=200`` ran on 200 mm unsaid."""
    with pytest.raises(T.TerrainError, match=re.escape("height_mm given twice ('100' and '200'); give it once")):
        T.make("rock:height_mm=100,height_mm=200")


# --- 3. an output file on a read-only file system: the line said "permission denied" ---------------------------

def test_a_read_only_file_system_is_named_so(tmp_path, monkeypatch):
    """``mtbmj render S12 --out /mnt/ro/x.gif`` on a file system mounted read-only (tried on a tmpfs mounted ro):
    "(permission denied)", where no permission would help. os.access fails alike for both (EROFS, EACCES); the
    file system's flags, given here as statvfs gives them, tell them apart."""
    import os
    from types import SimpleNamespace

    from mtbmj import output
    from mtbmj.errors import MtbmjError

    monkeypatch.setattr(os, "access", lambda *args, **kwargs: False)
    real = os.statvfs
    monkeypatch.setattr(os, "statvfs", lambda path: SimpleNamespace(f_flag=real(path).f_flag | os.ST_RDONLY))
    with pytest.raises(MtbmjError, match=re.escape(f"cannot write in {tmp_path} (a read-only file system)")):
        output.check_file_target(tmp_path / "x.gif")
    monkeypatch.setattr(os, "statvfs", lambda path: SimpleNamespace(f_flag=real(path).f_flag & ~os.ST_RDONLY))
    with pytest.raises(MtbmjError, match=re.escape(f"cannot write in {tmp_path} (permission denied)")):
        output.check_file_target(tmp_path / "x.gif")


# --- 4. a unit typed in an option's value: "'6m/s' is not a number", the way out unnamed -----------------------

LB = 0.45359237  # kg per lb, by definition
MPH = 1609.344 / 3600.0  # m/s per mph, by definition


@pytest.mark.parametrize("argv, said", [
    (["roll", "rock", "--speed", "6m/s"], "'6m/s' is not a number (the unit is the option's, m/s: give the number "
                                          "alone, 6)"),
    (["roll", "rock", "--speed", "20km/h"], f"(the option is in m/s: 20 km/h = {20 * KMH:.4g} m/s, give {20 * KMH:.4g})"),
    (["roll", "rock", "--speed", "12mph"], f"12 mph = {12 * MPH:.4g} m/s"),
    (["sag", "air120", "--load-kg", "80kg"], "'80kg' is not a number (the unit is the option's, kg"),
    (["sag", "air120", "--load-kg", "180 lb"], f"(the option is in kg: 180 lb = {180 * LB:.4g} kg, give {180 * LB:.4g})"),
    (["sag", "air120", "--load-kg", "70", "--sag-percent", "20%"], "(the unit is the option's, %: give the number alone, 20)"),
    (["curve", "S12", "--max-velocity-mm-per-s", "3m/s"], "3 m/s = 3000 mm/s, give 3000"),
    (["roll", "rock", "--speed", "5", "--duration", "2s"], "(the unit is the option's, s: give the number alone, 2)"),
    (["linkage", "trail", "--chainring", "32t"], "'32t' is not a whole number (the option takes a number in teeth"),
])
def test_a_unit_typed_in_an_options_value_names_the_number_to_give(tmp_path, capfd, argv, said):
    refused(argv + ["--out", tmp_path / "out"], tmp_path / "out", capfd, said)


def test_a_word_that_is_no_number_draws_no_unit_note(tmp_path, capfd):
    line = refused(["roll", "rock", "--speed", "fast", "--out", tmp_path / "out"], tmp_path / "out", capfd,
                   "'fast' is not a number")
    assert line.endswith("'fast' is not a number"), line


# --- 5. an empty name, an empty key, a bike key's value typed with its unit: lines for false reasons --------------

@pytest.mark.parametrize("argv, said", [
    (["drop", ""], "'': an empty name; give a preset or the path of a TOML configuration"),  # was ".: is a directory"
    (["sag", " ", "--load-kg", "70", "--sag-percent", "20"], "' ': an empty name"),
    (["bike", "", "root", "--speed", "4"], "'': an empty name; give a preset or the path of a bike description"),
    (["drop", "S12", "--set", "=5"], "--set =5: no key before '='; expected key=value"),  # was ": unknown key"
    (["bike", "sst", "root", "--speed", "4", "--set", "rider.mass_kg=78kg"],
     "rider.mass_kg: must be a plain number (the unit is in the key name), got '78kg'"),  # was "a finite number"
])
def test_an_empty_name_or_key_and_a_unit_in_a_bike_value_say_their_cause(tmp_path, capfd, argv, said):
    out = tmp_path / ("out.gif" if argv[0] == "render" else "out")
    refused(argv + ["--out", out], out, capfd, said)


def test_a_preset_and_a_bike_key_typed_right_are_taken():
    from mtbmj.bike import spec
    from mtbmj.config import load

    assert load("S12").name == "S12"
    rider = spec.load("sst", {"rider.mass_kg": 78}).rider
    assert rider.mass + rider.on_bike_mass == pytest.approx(78.0)  # the rider's mass, split on and off the bike


def test_render_of_an_empty_name_says_so():
    """``mtbmj render ''`` said ".: not a run directory (no config.toml)" (the empty name read as the current
    folder). Called below the headless-rendering check, which the tests' MUJOCO_GL=disable stops first."""
    from mtbmj.errors import MtbmjError
    from mtbmj.rolling import render

    with pytest.raises(MtbmjError, match=re.escape("'': an empty name; give a preset or the path of a TOML")):
        render.drop_trajectory("")


# --- 6. the Python entry points given what the command line refuses: ran, or a false reason -------------------

@pytest.mark.parametrize("call, said", [
    # 1e6 m/s ran (the command line refuses above 100 m/s, beyond the model); before any model is built
    (lambda m: m.run_roll("rock", 1e6, duration=0.01), "speed: 1e+06 m/s is outside the range allowed: above 0 and "
                                                       "at most 100 m/s"),
    (lambda m: m.run_bike("sst", "root", 1e6, duration=0.01), "speed: 1e+06 m/s is outside the range allowed"),
    # "90" was unpacked as cadence "9", power "0": "cadence '9' rpm is outside what a rider turns"
    (lambda m: m.run_bike("sst", "root", 4, duration=0.01, pedal="90"), "pedal: must be (cadence_rpm, power_W), "
                                                                         "got '90'"),
    # nan was "the front wheel (at x = nan m) does not start on level ground clear of the terrain's features"
    (lambda m: m.run_bike("sst", "root", 4, duration=0.01, start_x=float("nan")), "start_x: must be a finite number "
                                                                                   "of m"),
    # a plain ValueError "sled: the tolerance must be a positive number" after the ODE reference had run
    (lambda m: m.crosscheck("S12", tolerance_mm=0, duration=0.01), "tolerance_mm: must be a positive number of mm, "
                                                                   "got 0"),
    # the str '70' shown as 70: "must be a positive number of kg, got 70"
    (lambda m: m.solve_sag("air120", "70", 20), "--load-kg: must be a positive number of kg, got '70'"),
])
def test_the_python_entry_points_refuse_what_the_commands_refuse_with_the_cause(monkeypatch, call, said):
    import mtbmj
    from mtbmj.drop import crosscheck
    from mtbmj.errors import ConfigError

    def ran(*args, **kwargs):
        raise AssertionError("a run was made before the input was checked")

    monkeypatch.setattr(crosscheck, "run_drop", ran)
    with pytest.raises(ConfigError, match=re.escape(said)):
        call(mtbmj)


def test_a_ridden_speed_from_python_runs():
    import mtbmj

    result = mtbmj.run_roll("rock", 100.0, duration=0.002)  # the top of the range allowed is taken
    assert result.summary is not None


# --- 7. files and names a careless user gives twice: which one, said -------------------------------------------

def test_a_column_named_twice_is_named(tmp_path, capfd):
    """"a column is named twice" did not say which (a spreadsheet's header of a dozen keys)."""
    table = tmp_path / "variants.csv"
    table.write_text("sled.drop_height_mm,sled.body_mass_kg,sled.drop_height_mm\n100,20,200\n")
    refused(["sweep", "S12", "--from-csv", table, "--engine", "ode", "--out", tmp_path / "out"], tmp_path / "out",
            capfd, "the column sled.drop_height_mm is named twice")
    ride = tmp_path / "ride.csv"
    ride.write_text("time_s,fork_mm,shock_mm,fork_mm\n0,1,2,3\n0.001,1,2,3\n")
    refused(["telemetry", ride, "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "line 1: the column fork_mm is named twice")


def test_fit_given_example_twice_says_so(tmp_path, capfd):
    """``mtbmj fit spring example example``: "example: no such file", the first taken as the shipped record."""
    refused(["fit", "spring", "example", "example", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "'example' is the shipped record alone; give it once")


def test_minus_infinity_typed_as_an_options_value_is_refused_as_a_value(tmp_path, capfd):
    """``--speed -inf`` was "argument --speed: expected one argument" (argparse read -inf as an option)."""
    for option, typed in (("--speed", "-inf"), ("--start-m", "-INF"), ("--speed", "-nan")):
        argv = ["bike", "sst", "root", "--speed", "4"] if option == "--start-m" else ["roll", "rock"]
        refused(argv + [option, typed, "--out", tmp_path / "out"], tmp_path / "out", capfd,
                f"argument {option}: must be a finite number, got '{typed}'")


def test_a_stock_fork_driven_through_its_stops_is_not_blamed_on_its_rates(tmp_path, capfd):
    """``mtbmj roll step_up:height_mm=300 --speed 15`` on the stock S12: "a force law gave a non-finite or huge force
    (a rate, damping or preload far beyond any bike's?)", where no key was changed; the cause is the impact."""
    line = refused(["roll", "step_up:height_mm=300", "--speed", "15", "--out", tmp_path / "out"], tmp_path / "out",
                   capfd, "rolling run diverged before t = ")
    assert "an impact through the end stops harder than the step resolves, a feature that tall at that speed?" in line


def test_an_out_under_a_tilde_the_shell_left_is_the_home_folder(tmp_path, capfd, monkeypatch):
    """``--out=~/sag`` (bash expands no ~ after '='): a folder named '~' made in the current one, the line saying
    "wrote ... to ~/sag" as if it were the home folder's."""
    from helpers import command_said

    home, here = tmp_path / "home", tmp_path / "here"
    home.mkdir()
    here.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(here)
    status, said = command_said(["sag", "air120", "--load-kg", "70", "--sag-percent", "20", "--out=~/sag"], capfd)
    assert status == 0, said
    assert (home / "sag" / "config.toml").is_file() and not (here / "~").exists(), said
    assert f"wrote {home / 'sag' / 'config.toml'}" in said, said


def test_bob_given_an_empty_stance_says_so(tmp_path, capfd):
    """``--stance ''`` ran as the default (all standing) and ended on a crash of the standing rider's run."""
    refused(["bob", f"{SHARED_DATA}/sst/00649.SST", "--bike", "sst", "--stance", "", "--out", tmp_path / "out"],
            tmp_path / "out", capfd, "--stance '': names no stance; give standing or seated, one per record")


@pytest.mark.parametrize("argv, said", [
    (["compare", "", ""], "argument RUN: '': an empty name"),  # was ".: given twice (as .)"
    (["telemetry", "example", "--compare", ""], "argument --compare: '': an empty name"),  # ".: no timeseries.csv"
    (["telemetry", ""], "argument FILE.SST: '': an empty name"),
    (["sweep", "S12", "--from-csv", " "], "argument --from-csv: ' ': an empty name"),
    (["validate", "example", "--presets", ""], "--presets: no preset names in ''"),  # ran S1-S14, the default
])
def test_an_empty_file_name_or_list_is_refused_as_empty(tmp_path, capfd, argv, said):
    refused(argv + ["--out", tmp_path / "out"], tmp_path / "out", capfd, said)


def test_a_table_given_a_value_says_it_is_a_table(tmp_path, capfd):
    """``sled = 5`` in a file (or ``--set fork.spring=5``): "sled: unknown key", where sled is the sled's table."""
    bad = tmp_path / "bad.toml"
    bad.write_text('base = "S12"\nsled = 5\n')
    refused(["drop", bad, "--out", tmp_path / "out"], tmp_path / "out", capfd,
            f"{bad}: sled: is a table of keys (e.g. sled.")
    refused(["drop", "S12", "--set", "fork.spring=5", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "fork.spring: is a table of keys (e.g. fork.spring.")
    refused(["drop", "S12", "--set", "slde=5", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "slde: unknown key")  # the other side: no table of that name


def test_a_value_toml_reads_as_a_date_is_shown_as_typed(tmp_path, capfd):
    """``drop_height_mm = 2024-05-27`` (a date typed where a number goes): "got datetime.date(2024, 5, 27)"."""
    bad = tmp_path / "dated.toml"
    bad.write_text('base = "S12"\n[sled]\ndrop_height_mm = 2024-05-27\n')
    refused(["drop", bad, "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "sled.drop_height_mm: must be a number, got 2024-05-27 (TOML reads it as a date or a time)")


def test_an_output_file_name_too_long_is_refused_before_its_folders_are_made(tmp_path, capfd):
    """``synth spring S12 --out new/xxx...(300).csv``: "cannot write the record (File name too long)" after the run,
    the folder new/ left made; render's alike ("File name too long", no --out named). NAME_MAX is 255 bytes here."""
    from mtbmj import output
    from mtbmj.errors import MtbmjError

    long_name = "x" * 300
    out = tmp_path / "new" / f"{long_name}.csv"
    status, err = command_err(["synth", "spring", "S12", "--out", out], capfd)
    assert status == 2 and err.count("\n") == 1 and "a name of 304 bytes, longer than the 255" in err, err
    assert not (tmp_path / "new").exists() and not list(tmp_path.iterdir())
    with pytest.raises(MtbmjError, match=re.escape("a name of 300 bytes, longer than the 255 the file system in")):
        output.check_file_target(tmp_path / "new" / long_name / "run.gif")
    assert output.check_file_target(tmp_path / "new" / ("x" * 255) / "run.gif")  # the other side: 255 bytes fit

"""Careless input, round 32b: what round 32 (``tests/test_fuzz_careless32.py``) left, then more of its kind.
Each case failed before its fix: a line naming two ranges, an empty list run as none, argparse's line where the
cause was a unit, a name read for a file it does not mean, a path not expanded, a Python call that said nothing
where the command line warns. Inputs are written here."""
from __future__ import annotations

import re
import warnings

import pytest

from helpers import command_err, refused
from conftest import SHARED_DATA

MINIMAL_RECORD = f"{SHARED_DATA}/sst/00649.SST"


# --- 1. a pedalling rider's power and cadence: one range, the model's -----------------------------------------

@pytest.mark.parametrize("argv, said", [
    # was "--power: 5000 W is outside what a rider keeps up (above 0 W, at most 1500 W) (note: --power = 5000 W is
    # outside 0-2500 W, what bikes, riders and records have (a unit mistake?))": two ranges, one of them false
    (["bob", MINIMAL_RECORD, "--power", "5000"], "--power: 5000 W is outside the range allowed: above 0 and at most "
                                                 "1500 W (what a rider keeps up)"),
    (["bike", "sst", "root", "--pedal", "90", "--power", "5000"], "--power: 5000 W is outside the range allowed: "
                                                                  "above 0 and at most 1500 W"),
    # --pedal 200 named 20-150 rpm beside 30-130 rpm
    (["bike", "sst", "root", "--pedal", "200"], "--pedal: 200 rpm is outside the range allowed: at least 30 and at "
                                                "most 130 rpm (what a rider turns)"),
    (["bike", "sst", "root", "--pedal", "25"], "--pedal: 25 rpm is outside the range allowed: at least 30"),
])
def test_a_pedalling_riders_power_or_cadence_names_one_range(tmp_path, capfd, argv, said):
    line = refused(argv + ["--out", tmp_path / "out"], tmp_path / "out", capfd, said)
    assert "note:" not in line and line.count(" W") + line.count(" rpm") <= 3, line  # no second range beside it


def test_the_gates_pedalling_range_is_the_models():
    """One source (round depth33): the drive's law (floor 1) reads the numeric gate's range (floor 0), where the
    two were written apart and held equal by this test."""
    from mtbmj import limits
    from mtbmj.controllers import drive

    assert drive.PEDAL_RPM is limits.PEDAL_RPM and drive.PEDAL_POWER_W is limits.PEDAL_POWER_W
    power, cadence = limits.ARGUMENTS["--power"], limits.ARGUMENTS["--pedal"]
    assert (power.low or 0.0, power.high) == limits.PEDAL_POWER_W and power.open_low and power.plausible is None
    assert (cadence.low, cadence.high) == limits.PEDAL_RPM and cadence.plausible is None


# --- 2. an empty list of parts to lock: ran with none locked -------------------------------------------------

@pytest.mark.parametrize("typed", ["", " , "])
def test_bike_given_an_empty_lock_says_so(tmp_path, capfd, typed):
    """``mtbmj bike sst root --speed 4 --lock ''`` ran with nothing locked (the empty list read as no --lock), as
    ``bob --stance ''`` ran as all standing before round 32."""
    refused(["bike", "sst", "root", "--speed", "4", "--duration", "0.01", "--lock", typed, "--out", tmp_path / "out"],
            tmp_path / "out", capfd, f"--lock {typed!r}: names no part; give rear, pitch, rider, comma-separated")


# --- 3. a unit typed apart after an option's number: argparse's "unrecognized arguments: km/h" -----------------

KMH = 1000.0 / 3600.0  # m/s per km/h, by the definitions of the kilometre and the hour
LB = 0.45359237  # kg per lb, by definition


@pytest.mark.parametrize("argv, said", [
    (["roll", "rock", "--speed", "20", "km/h"], f"argument --speed: '20 km/h' is a number and its unit (the option is "
                                                f"in m/s: 20 km/h = {20 * KMH:.4g} m/s, give {20 * KMH:.4g})"),
    (["roll", "rock", "--speed=20", "km/h"], f"20 km/h = {20 * KMH:.4g} m/s"),
    # the unit taken for the terrain, the terrain then unrecognized: "unrecognized arguments: rock"
    (["roll", "--speed", "20", "km/h", "rock"], f"20 km/h = {20 * KMH:.4g} m/s"),
    (["roll", "rock", "--speed", "6", "m/s"], "'6 m/s' is a number and its unit (the unit is the option's, m/s: give "
                                              "the number alone, 6)"),
    (["roll", "rock", "--speed", "5", "--duration", "2", "s"], "(the unit is the option's, s: give the number alone, 2)"),
    (["linkage", "trail", "--chainring", "32", "teeth"], "'32 teeth' is a number and its unit"),
])
def test_a_unit_typed_apart_names_the_number_to_give(tmp_path, capfd, argv, said):
    refused(argv + ["--out", tmp_path / "out"], tmp_path / "out", capfd, said)


def test_a_unit_typed_apart_draws_no_note_of_the_number_read_without_it(tmp_path, capfd):
    """180 read as kg warns (5-150 kg); beside the line saying it was 180 lb, that note would call it 180 kg."""
    line = refused(["sag", "air120", "--load-kg", "180", "lb", "--sag-percent", "20", "--out", tmp_path / "out"],
                   tmp_path / "out", capfd, f"(the option is in kg: 180 lb = {180 * LB:.4g} kg, give {180 * LB:.4g})")
    assert "note:" not in line and "180 kg" not in line, line


def test_a_word_after_a_number_that_is_no_unit_is_left_to_argparse(tmp_path, capfd):
    line = refused(["roll", "rock", "--speed", "5", "fast", "--out", tmp_path / "out"], tmp_path / "out", capfd,
                   "unrecognized arguments: fast")
    assert "a number and its unit" not in line, line


# --- 4. bob given 'example', the shipped ride the other ride commands take: "example: cannot read" -------------

@pytest.mark.parametrize("name", ["example", "Example"])
def test_bob_given_the_shipped_example_says_it_is_a_trail_ride(tmp_path, capfd, name):
    refused(["bob", name, "--out", tmp_path / "out"], tmp_path / "out", capfd,
            f"{name}: the shipped example (00649.SST) is a trail ride, no pedalling; bob reads Sufni SST recordings "
            f"of pedalling")


def test_bob_given_a_file_named_example_reads_it(tmp_path, capfd, monkeypatch):
    """The other side: a file of that name in the current folder is the user's (as ``ride_path`` has it)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "example").write_bytes(b"not an SST file")
    line = refused(["bob", "example", "--out", tmp_path / "out"], tmp_path / "out", capfd, "example")
    assert "shipped" not in line, line


# --- 5. an input path under a ~ the shell left (quoted, or after '='): "cannot read", where --out was expanded -------

@pytest.mark.parametrize("argv, said", [
    (["telemetry", "~/ride.SST"], None),  # typed as Path
    (["telemetry", "--bike=sst", "~/ride.SST"], None),
    (["bike", "sst", "root", "--speed", "4", "--ride=~/ride.SST", "--duration", "0.01"], None),  # typed as str
    (["roll", "rock", "--speed", "5", "--config=~/none.toml"], "{home}/none.toml: no such configuration file"),
    (["drop", "~/none.toml"], "{home}/none.toml: no such configuration file"),
])
def test_an_input_under_a_tilde_is_in_the_home_folder(tmp_path, capfd, monkeypatch, argv, said):
    import shutil

    home, here = tmp_path / "home", tmp_path / "here"
    home.mkdir()
    here.mkdir()
    shutil.copy(MINIMAL_RECORD, home / "ride.SST")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(here)
    out = tmp_path / "out"
    if said is not None:  # a file that is not there is named where it was looked for: the home folder
        refused(argv + ["--out", out], out, capfd, said.format(home=home))
        return
    status, err = command_err(argv + ["--out", out], capfd)
    assert status == 0 and "cannot read" not in err and out.is_dir(), err


def test_every_argument_typed_as_str_is_an_input_or_no_path():
    """The arguments left untyped (str) across every command name no file: each that does is typed through
    ``common.INPUT_NAMES`` (its ~ expanded). A new input added untyped fails here, naming it."""
    import argparse

    from mtbmj.cli import build_parser

    not_paths = {"bound", "clicks", "engines", "fork_set", "free", "friction", "lock", "model", "output", "presets",
                 "scheduler", "set", "shock_set", "stance", "static_sag_mm", "try_set", "vary", "predict_clicks"}
    untyped = set()

    def walk(parser):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    walk(sub)
            elif type(action) in (argparse._StoreAction, argparse._AppendAction, argparse._ExtendAction) \
                    and action.type is None and not action.choices:
                untyped.add(action.dest)

    walk(build_parser())
    assert untyped and untyped <= not_paths, sorted(untyped - not_paths)
    assert "bike" not in untyped and "ride" not in untyped  # the other side: inputs are typed


# --- 6. the Python entry points given what the command line warns about: nothing said --------------------------

def _speed_line(value):
    return (f"--speed = {value:g} m/s is outside 0.3-30 m/s, what bikes, riders and records have (a unit mistake? "
            f"probably meant {value:g} km/h = {value * KMH:.4g} m/s)")


@pytest.mark.parametrize("call, said", [
    (lambda m: m.run_roll("rock", 40, duration=0.002), _speed_line(40)),
    (lambda m: m.run_bike("sst", "root", 40, duration=0.002), _speed_line(40)),
    (lambda m: m.solve_sag("air120", 180, 20), f"--load-kg = 180 kg is outside 5-150 kg, what bikes, riders and records "
                                                f"have (a unit mistake? probably meant 180 lb = {180 * LB:.4g} kg)"),
    (lambda m: m.solve_sag("air120", 70, 0.2), "--sag-percent = 0.2 % is outside 5-50 %, what bikes, riders and "
                                               "records have (a unit mistake? probably meant 0.2 as a fraction = 20 %)"),
])
def test_the_python_entry_points_warn_as_the_command_line_does(call, said):
    """Each warning once (a run checks its speed twice), the line the command line gives (``limits.plausible``)."""
    import mtbmj
    from mtbmj.errors import ConfigWarning, MtbmjError

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            call(mtbmj)
        except MtbmjError:  # 0.2 % sag: no pressure gives it; the warning names the slip
            pass
    lines = [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)]
    assert lines.count(said) == 1, lines


def test_the_command_line_warns_once_and_a_ridden_speed_warns_nothing(tmp_path, capfd):
    from helpers import command_said

    status, said = command_said(["roll", "rock", "--speed", "40", "--duration", "0.002", "--out", tmp_path / "o"], capfd)
    assert status == 0 and said.count("mtbmj: warning:") == 1 and _speed_line(40) in said, said
    import mtbmj

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mtbmj.run_roll("rock", 5, duration=0.002)
        mtbmj.solve_sag("air120", 70, 20)


# --- 7. the hunt: ranges the gate named that were not the model's ---------------------------------------------

@pytest.mark.parametrize("argv, said", [
    # "--sag-percent: must be between 0 and 100 (percent of travel), got 100.0 (note: ... outside 5-50 %)": the gate
    # had let 100 through ("at most 100"); bike sag's "must be within 0-100 %, got 100.0" said 100 was within
    (["sag", "air120", "--load-kg", "70", "--sag-percent", "100"], "argument --sag-percent: 100 % is outside the range "
                                                                  "allowed: above 0 and below 100 %"),
    (["sag", "sst", "--bike", "--front-sag-percent", "100", "--rear-sag-percent", "30"],
     "argument --front-sag-percent: 100 % is outside the range allowed: above 0 and below 100 %"),
    # "head angle: must be in (45, 90]" after the gate let 40 through as (0, 90] with a warning left off the line
    (["roll", "rock", "--speed", "5", "--head-angle", "40"], "argument --head-angle: 40 deg is outside the range "
                                                             "allowed: above 45 and at most 90 deg"),
    # the radians the rig's own line named, kept where the gate now refuses first
    (["roll", "rock", "--speed", "5", "--head-angle", "1.13"], "(a unit mistake? probably meant 1.13 rad = 64.74 deg)"),
])
def test_a_range_the_gate_names_is_the_models(tmp_path, capfd, argv, said):
    line = refused(argv + ["--out", tmp_path / "out"], tmp_path / "out", capfd, said)
    assert "note:" not in line, line


def test_the_python_sag_line_names_an_open_range():
    from mtbmj.bike import sag
    from mtbmj.errors import ConfigError

    with pytest.raises(ConfigError, match=re.escape("--front-sag-percent: must be above 0 and below 100 %, got 100")):
        sag.solve("sst", 100, 30)


# --- 8. the hunt: a comma list typed with a comma too many or in capitals --------------------------------------

def test_a_lock_in_capitals_or_with_a_comma_too_many_is_read(tmp_path, capfd, monkeypatch):
    """``--lock rear,`` was "lock: '' is not one of rear, pitch, rider" (the empty word read as a part, the line naming
    run_bike's argument); ``--lock Rear`` refused where ``--stance Standing`` and ``--engine MuJoCo`` are read."""
    from mtbmj.bike import run as bike_run
    from mtbmj.errors import ConfigError

    seen = []

    def reached(*args, lock=(), **kwargs):
        seen.append(lock)
        raise ConfigError("reached the run")

    monkeypatch.setattr(bike_run, "run_bike", reached)
    for typed, parts in (("rear,", ("rear",)), ("Rear, PITCH", ("rear", "pitch"))):
        refused(["bike", "sst", "root", "--speed", "4", "--lock", typed, "--out", tmp_path / "out"], tmp_path / "out",
                capfd, "reached the run")
        assert seen.pop() == parts
    refused(["bike", "sst", "root", "--speed", "4", "--lock", "fork", "--out", tmp_path / "out"], tmp_path / "out",
            capfd, "--lock: 'fork' is not one of rear, pitch, rider")  # the other side: no such part


def test_a_stance_with_a_comma_too_many_is_one_stance(tmp_path, capfd, monkeypatch):
    """``bob REC --stance standing,`` was "stance: one per record (1), got 2": the empty word counted as a stance."""
    from mtbmj.errors import ConfigError
    from mtbmj.ride import pedalling

    seen = []

    def reached(records, bike, stances, *rest):
        seen.append(stances)
        raise ConfigError("reached the runs")

    monkeypatch.setattr(pedalling, "against", reached)
    refused(["bob", MINIMAL_RECORD, "--stance", "standing,", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "reached the runs")
    assert seen == [["standing"]]


def test_a_head_angle_from_python_warns_as_the_command_line_does(tmp_path, capfd):
    """``run_roll(..., head_angle_deg=50)`` said nothing; ``--head-angle 50`` warns (55-80 deg)."""
    import mtbmj
    from mtbmj.errors import ConfigWarning
    from helpers import command_said

    said = "--head-angle = 50 deg is outside 55-80 deg, what bikes, riders and records have (a unit mistake?)"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mtbmj.run_roll("rock", 5, head_angle_deg=50, duration=0.002)
    assert [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)] == [said]
    status, out = command_said(["roll", "rock", "--speed", "5", "--head-angle", "50", "--duration", "0.002", "--out",
                                tmp_path / "o"], capfd)
    assert status == 0 and out.count(said) == 1, out
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mtbmj.run_roll("rock", 5, head_angle_deg=65, duration=0.002)  # the other side


def test_a_crosscheck_tolerance_from_python_is_held_as_the_command_lines(monkeypatch):
    """``crosscheck("S12", tolerance_mm=5000)`` ran (``--tolerance-mm 5000`` is refused, at most 1000 mm) and 50 mm
    said nothing (``--tolerance-mm 50`` warns, 1e-4-10 mm)."""
    import mtbmj
    from mtbmj.drop import crosscheck
    from mtbmj.errors import ConfigError, ConfigWarning

    def ran(*args, **kwargs):
        raise ConfigError("a run was made")

    monkeypatch.setattr(crosscheck, "run_drop", ran)
    with pytest.raises(ConfigError, match=re.escape("tolerance_mm: 5000 mm is outside the range allowed: above 0 and "
                                                    "at most 1000 mm")):
        mtbmj.crosscheck("S12", tolerance_mm=5000)
    with warnings.catch_warnings(record=True) as caught, pytest.raises(ConfigError, match="a run was made"):
        warnings.simplefilter("always")
        mtbmj.crosscheck("S12", tolerance_mm=50)
    assert [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)] == [
        "--tolerance-mm = 50 mm is outside 0.0001-10 mm, what bikes, riders and records have (a unit mistake?)"]


# --- 9. the hunt: a model named in capitals, frames per second typed as fps ------------------------------------

def test_a_fit_model_in_capitals_is_the_model(tmp_path, capfd):
    """``fit spring example --model Linear``: "unknown model 'Linear' (one of linear, ...)"; ``--engine MuJoCo`` and
    ``--rider Active`` are read in any case."""
    from mtbmj.cli import build_parser

    for kind in ("spring", "damper"):
        args = build_parser().parse_args(["fit", kind, "example", "--model", "Linear", "--friction", "LuGre"])
        assert (args.model, args.friction) == ("linear", "lugre")
    refused(["fit", "spring", "example", "--model", "Nope", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "unknown model 'nope' (one of linear,")  # the other side: no such model


def test_frames_per_second_typed_as_fps_names_the_number(tmp_path, capfd):
    """``render S12 --fps 30 fps``: "unrecognized arguments: fps"; ``30fps``: "(the option takes a number in
    frames/s, without a unit)", as if fps were another unit."""
    for argv in (["--fps", "30", "fps"], ["--fps", "30fps"]):
        refused(["render", "S12", *argv, "--out", tmp_path / "out.gif"], tmp_path / "out.gif", capfd,
                "(the unit is the option's, frames/s: give the number alone, 30)")


def test_fit_bounce_given_example_says_it_has_none(tmp_path, capfd):
    """``fit bounce example --clicks 0``: "example: cannot read (No such file or directory)", where ``fit spring
    example`` takes its shipped record."""
    refused(["fit", "bounce", "example", "--clicks", "0", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "example: fit bounce has no shipped example (the shipped ride, 00649.SST, is a trail ride, no seat slam)")

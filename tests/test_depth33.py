"""Round depth33: what round 32 noticed and left, each mended at its cause. Inputs are written here."""
from __future__ import annotations

import re
import warnings

import pytest

from mtbmj.errors import ConfigError
from conftest import SHARED_DATA


# --- 1. a command option's number given from Python: one check against the option's range -------------------

def test_a_start_given_from_python_is_held_to_the_start_options_range():
    """``run_bike(start_x=-1e5)`` went on to the terrain (``mtbmj bike --start-m -1e5`` is refused before any
    work: at least -10000 m); now the same range, named ``start_x``, as speed and tolerance_mm are held."""
    from mtbmj.bike import run as R

    for start, shown in ((-1e6, "-1e+06"), (2e5, "200000")):
        with pytest.raises(ConfigError, match=re.escape(f"start_x: {shown} m is outside the range allowed: at least "
                                                        f"-100000 and at most 100000 m")):
            R.prepare("sst", "flat", 4.0, start_x=start)
    with pytest.raises(ConfigError, match=re.escape("start_x: must be a finite number of m (the front axle's start), "
                                                    "got nan")):
        R.prepare("sst", "flat", 4.0, start_x=float("nan"))


def test_a_saved_bike_run_far_along_its_terrain_renders_without_a_word_about_its_start(tmp_path, capfd):
    """review33a: a bike run on a CSV terrain whose distances start at 12 km (its default start, the terrain's) was
    refused by render ("cannot replay this bike run (start_x: 12000 m is outside the range allowed ...)"), and one
    starting at 150 m warned "--start-m = 150 m is outside -100-100 m" where nobody typed --start-m: the saved start
    is the terrain's. A start typed past 100 m (a reconstructed ride's terrain.csv runs for hundreds) is no slip either: no warning."""
    import numpy as np

    from mtbmj.bike import replay
    from mtbmj.cli import main

    for start in (12000.0, 150.0):
        x = start + np.linspace(0.0, 30.0, 301)
        z = np.where(x < start + 5.0, 0.0, 20.0 * np.sin(x - start))  # mm: level for its first 5 m
        csv = tmp_path / f"far{start:g}.csv"
        np.savetxt(csv, np.c_[x, z], delimiter=",", header="distance_m,height_mm", comments="", fmt="%.6f")
        run = tmp_path / f"run{start:g}"
        assert main(["bike", "sst", str(csv), "--speed", "4", "--duration", "0.3", "--out", str(run), "--quiet",
                     "--no-figure"]) == 0
        capfd.readouterr()
        with warnings.catch_warnings():  # what render replays the run through (the tests run without a GL)
            warnings.simplefilter("error")
            replay.rerun(run, duration=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["bike", "sst", str(tmp_path / "far150.csv"), "--speed", "4", "--duration", "0.2", "--start-m",
                     "152", "--out", str(tmp_path / "run152"), "--quiet", "--no-figure"]) == 0
    assert "outside" not in capfd.readouterr().err


# --- 2. bob's run length: one rule, from Python and from the command line -------------------------------------

@pytest.mark.shared_data("sst", "00649.SST")
def test_bobs_run_length_is_one_rule_from_python_and_the_command(tmp_path, capfd):
    """``against(duration_s=...)`` and ``mtbmj bob --duration`` wrote the rule twice and told it apart: 5.0 s
    said "5.0 s" from Python and "5 s" from the command, a string '20' and NaN were "too short" (NaN is no
    length, '20' no number). Now one check (``pedalling.check_run_s``), naming each side's own label."""
    import shutil

    from mtbmj.ride import pedalling
    from helpers import refused

    record = tmp_path / "ride.SST"  # a copy: the shipped example by its own path is refused for another reason
    shutil.copy(f"{SHARED_DATA}/sst/00649.SST", record)
    out = tmp_path / "out"
    line = refused(["bob", record, "--duration", "5", "--out", out], out, capfd, "--duration: 5 s is too short")
    with pytest.raises(ConfigError) as python:
        pedalling.against([record], duration_s=5.0)
    assert str(python.value) == line.removeprefix("mtbmj: error: ").replace("--duration", "duration_s")
    with pytest.raises(ConfigError, match=re.escape("duration_s: must be a number of seconds, got '20'")):
        pedalling.against([record], duration_s="20")
    with pytest.raises(ConfigError, match=re.escape("duration_s: must be a positive finite number of seconds, "
                                                    "got nan")):
        pedalling.against([record], duration_s=float("nan"))


# --- 3. a unit typed apart, read as the positional after it ------------------------------------------------------

@pytest.mark.parametrize("argv, said", [
    # the unit taken as a record, a scenario, a configuration: "W: cannot read", "unknown scenario 's'",
    # "km/h: unknown preset" before
    (["bob", "--power", "250", "W", "REC.SST"],
     "argument --power: '250 W' is a number and its unit (the unit is the option's, W: give the number alone, 250)"),
    (["roll", "--speed", "4", "--duration", "0.2", "s"],
     "argument --duration: '0.2 s' is a number and its unit (the unit is the option's, s: give the number alone, "
     "0.2)"),
    (["validate", "example", "--duration", "0.5", "km/h"],
     "argument --duration: '0.5 km/h' is a number and its unit (the option takes a number in s, without a unit)"),
])
def test_a_unit_typed_apart_and_read_as_a_positional_is_named(argv, said, tmp_path, capfd, monkeypatch):
    from helpers import refused

    monkeypatch.chdir(tmp_path)  # no file named as the unit here (one so named is read: tests/test_review32.py)
    out = tmp_path / "out"
    refused([*argv, "--out", out], out, capfd, said)


@pytest.mark.shared_data("sst", "00649.SST")
def test_a_file_named_as_a_unit_after_a_number_is_still_read(tmp_path, capfd, monkeypatch):
    """The other side: ``bob --power 250 W`` with a record named ``W`` in the folder reads it (a trail ride, not a
    pedalling one: refused for what it is, not for a unit)."""
    import shutil

    from helpers import command_err

    monkeypatch.chdir(tmp_path)
    shutil.copy(f"{SHARED_DATA}/sst/00649.SST", tmp_path / "W")
    status, err = command_err(["bob", "--power", "250", "W", "--duration", "5", "--out", tmp_path / "out"], capfd)
    assert status == 2 and "is a number and its unit" not in err and "--duration: 5 s is too short" in err, err


# --- 4. a run length refused deep in a run names the option typed, or the key it came from ---------------------

@pytest.mark.parametrize("argv, said", [
    (["drop", "S12", "--duration", "1e9"], "mtbmj: error: --duration: 1e+09 s in steps of 0.001 s"),
    (["drop", "S12", "--duration", "1e-6"], "mtbmj: error: --duration: 1e-06 s is shorter than one logger sample"),
    (["roll", "flat", "--speed", "4", "--duration", "1e9"], "mtbmj: error: --duration: 1e+09 s in steps of"),
    (["study", "--presets", "S12,S1", "--duration", "1e9"], "mtbmj: error: S12: --duration: 1e+09 s in steps of"),
    # no --duration typed: the configuration's length, by its key
    (["drop", "S12", "--set", "solver.timestep_s=1e-7", "--set", "solver.duration_s=1000"],
     "mtbmj: error: solver.duration_s: 1000 s in steps of 1e-07 s"),
])
def test_a_run_length_refused_in_the_run_names_the_option_typed(argv, said, tmp_path, capfd):
    """``mtbmj drop S12 --duration 1e9`` said "duration: ... needing about 931 TiB" where every other option's
    refusal names the option (``--duration:``); a configuration's solver.duration_s so refused said "duration" too."""
    from helpers import refused

    out = tmp_path / "out"
    assert refused([*argv, "--out", out], out, capfd, said).startswith(said)


def test_a_run_length_from_python_keeps_its_argument_name():
    from mtbmj.drop.run import run_drop

    with pytest.raises(ConfigError, match=re.escape("duration: 1e+09 s in steps of 0.001 s")) as caught:
        run_drop("S12", duration=1e9)
    assert not str(caught.value).startswith("--")


# --- 5. an empty lock from Python ---------------------------------------------------------------------------------

def test_an_empty_lock_from_python_is_refused_as_the_commands_is(tmp_path, capfd):
    """``run_bike(lock='')`` ran with nothing locked where ``mtbmj bike --lock ''`` is refused; now refused alike,
    before any work. A part given as a str stays one part."""
    from mtbmj.bike import run as R
    from helpers import refused

    out = tmp_path / "out"
    refused(["bike", "sst", "flat", "--speed", "4", "--lock", "", "--out", out], out, capfd, "names no part")
    for empty in ("", "  "):
        with pytest.raises(ConfigError, match=re.escape(f"lock {empty!r}: names no part; give rear, pitch, rider")):
            R.run_bike("sst", "flat", 4.0, duration=0.01, lock=empty)
    with pytest.raises(ConfigError, match=re.escape("lock: 'seat' is not one of rear, pitch, rider")):  # one part
        R.run_bike("sst", "flat", 4.0, duration=0.01, lock="seat")  # still read as one part


# --- 7. a sensor unplugged partway through a ride ------------------------------------------------------------------

def unplugged(tmp_path, column: int, fraction: float = 0.4):
    """A copy of the shipped ride (SST version 3: a 16-byte header, then fork and shock uint16 counts) whose
    ``column`` (0 fork, 1 shock) holds its count from ``1 - fraction`` of the ride to the end, as a sensor unplugged
    then reads; the sample it holds from."""
    import numpy as np

    raw = open(f"{SHARED_DATA}/sst/00649.SST", "rb").read()
    counts = np.frombuffer(raw[16:], "<u2").reshape(-1, 2).copy()
    start = int(round((1.0 - fraction) * len(counts)))
    counts[start:, column] = counts[start, column]
    path = tmp_path / f"unplugged{column}.SST"
    path.write_bytes(raw[:16] + counts.tobytes())
    return path, start


@pytest.mark.shared_data("sst", "00649.SST")
@pytest.mark.parametrize("column, end, other", [(0, "fork", "shock"), (1, "shock", "fork")])
def test_a_sensor_unplugged_partway_is_warned_about_naming_the_end_and_when(tmp_path, column, end, other):
    """A fork or shock reading one count over the last 40 % of the ride (76.4 s at 1000 Hz: from 45.8 s) was read
    silently as a ride whose end stopped moving; now one line naming the end and from when."""
    from mtbmj.measured import telemetry

    path, start = unplugged(tmp_path, column)
    lines = telemetry.quality(telemetry.read_ride(path))
    said = [line for line in lines if "unplugged or stuck partway" in line]
    assert len(said) == 1, lines
    assert said[0].startswith(f"{path.name}: the {end}'s travel holds at ") and \
        f"mm from {start / 1000.0:.1f} s to the end (the last 30.6 s, 40 % of the ride) while the {other}'s moves" \
        in said[0], said[0]
    # the other side: the shipped ride itself (its ends' held tails 1.0 and 1.6 s), and a held tail shorter than
    # HELD_TAIL_S (a rider rolled to a stop)
    assert not [line for line in telemetry.quality(telemetry.read_ride(f"{SHARED_DATA}/sst/00649.SST"))
                if "partway" in line]
    short, _ = unplugged(tmp_path, column, fraction=0.05)  # the last 3.8 s
    assert not [line for line in telemetry.quality(telemetry.read_ride(short)) if "partway" in line]


@pytest.mark.shared_data("sst", "00649.SST")
def test_a_rider_who_stops_is_not_a_sensor_unplugged(tmp_path):
    """review33a: a ride that ends with the rider stopped, the shock still from 30.1 s and the fork from 31.4 s
    (00094's first 50 s), was warned as "the shock's travel holds ... while the fork's moves: its sensor unplugged
    or stuck partway": the fork's last second of settling fell inside the shock's held stretch. Made here from the
    shipped ride: the shock held over the last 30 %, the fork 1.3 s later; warned only where the other end moves
    on HELD_MOVING_S (3 s) into the held stretch or more (the fork held from 10 s later: warned). review33b: the
    rule first written (the other end moving on for HELD_TAIL_S) left a fork unplugged 5-6.5 s before the end
    silent, the other end's own stop at the ride's end counted against it: warned now."""
    import numpy as np

    from mtbmj.measured import telemetry

    raw = open(f"{SHARED_DATA}/sst/00649.SST", "rb").read()
    counts = np.frombuffer(raw[16:], "<u2").reshape(-1, 2).copy()
    start = int(round(0.7 * len(counts)))
    for later, warned in ((1300, False), (10000, True)):  # samples at 1000 Hz: the fork held 1.3 s / 10 s later
        c = counts.copy()
        c[start:, 1] = c[start, 1]
        c[start + later:, 0] = c[start + later, 0]
        path = tmp_path / f"stopped{later}.SST"
        path.write_bytes(raw[:16] + c.tobytes())
        said = [line for line in telemetry.quality(telemetry.read_ride(path)) if "unplugged or stuck partway" in line]
        assert bool(said) == warned, (later, said)
        if warned:
            assert len(said) == 1 and "the shock's travel holds at" in said[0], said
    n = len(counts)
    for seconds in (5.0, 5.5, 6.5):  # the fork alone unplugged that long before the end (the shock rides on)
        c = counts.copy()
        held = n - int(seconds * 1000)
        c[held:, 0] = c[held, 0]
        path = tmp_path / f"fork_last{seconds:g}.SST"
        path.write_bytes(raw[:16] + c.tobytes())
        said = [line for line in telemetry.quality(telemetry.read_ride(path)) if "unplugged or stuck partway" in line]
        assert len(said) == 1 and "the fork's travel holds at" in said[0], (seconds, said)


@pytest.mark.shared_data("sst", "00649.SST")
@pytest.mark.parametrize("argv", [["telemetry"], ["reconstruct", "--bike", "sst"], ["advise", "--bike", "sst"]])
def test_the_ride_commands_warn_of_a_sensor_unplugged_partway(tmp_path, capfd, monkeypatch, argv):
    """``mtbmj telemetry`` (the ride summarized), ``reconstruct`` and ``advise``: the line, before any work (their
    runs stood in for here by a run that stops: its refusal carries the warnings said before it)."""
    from mtbmj.errors import RunError
    from mtbmj.ride import advise, reconstruct
    from helpers import command_said

    def stop(*args, **kwargs):
        raise RunError("stood in: stopped before the run")

    monkeypatch.setattr(reconstruct, "reconstruct", stop)
    monkeypatch.setattr(advise, "advise", stop)
    path, _ = unplugged(tmp_path, 0)
    status, said = command_said([argv[0], path, *argv[1:], "--out", tmp_path / "out"], capfd)
    assert "the fork's travel holds at" in said and "from 45.8 s to the end" in said, said
    assert status == (0 if argv[0] == "telemetry" else 2), said

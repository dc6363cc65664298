"""Careless input, round 33: the Python entry points of mtbmj, mtbmj.sweep, mtbmj.ride, mtbmj.identify and
mtbmj.rolling given what a new user types there (a str where a list or a switch goes, a str or a float where a
count goes, one mapping where a list of them goes, None), a fork's file holding a bike's table, and a file that is
a symbolic link leading nowhere. Each case failed before its fix: a deep AttributeError or TypeError, a str read
letter by letter, a silent run on the wrong value, or a refusal for a false reason. Inputs are written here."""
from __future__ import annotations

import math
import os
import re

import numpy as np
import pytest

import mtbmj
from mtbmj import limits, ride, rolling, sweep
from mtbmj.drop.air_study import run_air_study
from mtbmj.identify import identify
from mtbmj.identify.examples import example_paths
from helpers import command_said, refused

DROP = "sled.drop_height_mm"
TIME = np.arange(1000) / 1000.0  # 1 s at 1 kHz
TRAVEL = 50.0 + 40.0 * np.sin(20.0 * TIME)  # mm, within a 180 mm fork


def _range():
    return sweep.parse_vary(f"{DROP}=100:600:3")


# --- 1. a switch, a count, a list of names given from Python as something else --------------------------------

@pytest.mark.parametrize("call, said", [
    # "no" is true to Python: seated="no" ran seated, rear_tire="no" with the rear tire on
    (lambda tmp: mtbmj.run_bike("sst", "root", 4, duration=0.01, seated="no"), "seated: must be True or False, got 'no'"),
    (lambda tmp: mtbmj.run_bike("sst", "root", 4, duration=0.01, rear_tire="no"), "rear_tire: must be True or False"),
    # [] of presets ran the whole study (14 presets on two engines); [] of engines said "workers: must be at least 1"
    (lambda tmp: mtbmj.run_study(presets=[]), "presets: an empty list; give at least one, e.g. ['S12']"),
    (lambda tmp: mtbmj.run_study(presets=["S1"], engines=[]), "engines: an empty list"),
    # "'<' not supported between instances of 'str' and 'int'", "'float' object cannot be interpreted as an integer"
    (lambda tmp: mtbmj.run_study(presets=["S1"], workers="2"), "--workers: must be a whole number, got '2'"),
    (lambda tmp: run_air_study(workers=1.5), "--workers: must be a whole number, got 1.5"),
    (lambda tmp: sweep.sample([_range()], "4"), "--samples: must be a whole number, got '4'"),
    # numpy's "SeedSequence expects int or sequence of ints" and "expected non-negative integer"
    (lambda tmp: sweep.sample([_range()], 4, seed="a"), "--seed: must be a whole number, got 'a'"),
    (lambda tmp: sweep.sample([_range()], 4, seed=-1), "--seed: must be at least 0, got -1"),
    # "'f' is not a numeric sweep output": the name read letter by letter
    (lambda tmp: sweep.run_sensitivity("S12", [sweep.parse_vary(f"{DROP}=100:600")], "fork_peak1_mm", tmp / "s"),
     "outputs: must be a list of names, e.g. ['fork_peak1_mm'], got the str 'fork_peak1_mm'"),
    # "'str' object has no attribute 'items'" for one variant not in a list, and for a str
    (lambda tmp: sweep.run_sweep("S12", {DROP: 300}, tmp / "s", duration=0.02),
     "variants: must be a list of mappings of key to value, e.g. [{'sled.drop_height_mm': 300}, "
     "{'sled.drop_height_mm': 400}], got a dict (one variant: put it in a list)"),
    (lambda tmp: sweep.run_sweep("S12", [f"{DROP}=300"], tmp / "s", duration=0.02),
     "variants[0]: must be a mapping of key to value"),
    (lambda tmp: sweep.run_sweep("S12", [{DROP: 300}], tmp / "s", workers="2"), "--workers: must be a whole number"),
    (lambda tmp: sweep.run_sweep("S12", [{DROP: 300}], tmp / "s", resume="no"), "resume: must be True or False"),
    # "'NoneType' object has no attribute 'partition'", "'str' object has no attribute 'key'"
    (lambda tmp: sweep.parse_vary(None), "--vary: must be a str key=lo:hi:n (a grid) or key=lo:hi"),
    (lambda tmp: sweep.grid(f"{DROP}=100:600:3"), "ranges: must be a list of Range"),
])
def test_a_python_argument_of_the_wrong_kind_is_named(tmp_path, call, said):
    with pytest.raises(ValueError) as caught:
        call(tmp_path)
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)
    assert not (tmp_path / "s").exists()  # refused before any folder was made


@pytest.mark.parametrize("call, said", [
    # "'int' object has no attribute 'rpartition'"
    (lambda: mtbmj.run_drop("S12", overrides={1: 300}, duration=0.01),
     "overrides: each key must be a str naming the key, e.g. {'sled.drop_height_mm': 300}, got 1"),
    # "'NoneType' object has no attribute 'mode'"
    (lambda: mtbmj.run_roll("root", 4, drive=None, duration=0.01), "drive: must be one of rider, servo, coast or a "
                                                                    "controllers.drive.Drive, got None"),
    # the str '20' shown as 20; True taken as 1 %
    (lambda: mtbmj.solve_sag("air120", 70, "20"), "--sag-percent: must be between 0 and 100 (percent of travel), "
                                                  "got '20'"),
    (lambda: mtbmj.solve_sag("air120", 70, True), "got True"),
    # fps=0 a ZeroDivisionError, "30" "can't multiply sequence by non-int", nan numpy's own; -1 ran
    (lambda: rolling.roll_trajectory("root", 4, fps=0, duration=0.05), "fps: must be a positive number of "
                                                                       "frames/s, got 0"),
    (lambda: rolling.roll_trajectory("root", 4, fps=-1, duration=0.05), "fps: must be a positive number of "
                                                                        "frames/s, got -1"),
    (lambda: rolling.roll_trajectory("root", 4, fps=20000, duration=0.05), "fps: 20000 frames/s is outside the "
                                                                           "range allowed: above 0 and at most 10000"),
    (lambda: rolling.roll_trajectory("root", 4, fps="30", duration=0.05), "fps: must be a positive number of "
                                                                          "frames/s, got '30'"),
])
def test_a_python_value_of_the_wrong_kind_is_named(call, said):
    with pytest.raises(ValueError) as caught:
        call()
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)


def test_a_difference_with_no_result_or_another_rigs_names_the_other():
    """``r.difference(None)`` was "'NoneType' object has no attribute 'raw'"; a roll's result beside a drop's
    was "results are not on the same time grid"."""
    drop = mtbmj.run_drop("S12", duration=0.02)
    for other, said in ((None, "other: must be a run's result to difference with (DropResult), got None"),
                        ("S12", "other: must be a run's result to difference with (DropResult), got a str"),
                        (mtbmj.run_roll("root", 4, duration=0.02), "other: a RollResult has no sled_mm to "
                                                                    "difference with this DropResult's; give a result "
                                                                    "of the same rig")):
        with pytest.raises(ValueError, match=f"^{re.escape(said)}$"):
            drop.difference(other)
    # the other side: two drops still difference
    assert drop.difference(mtbmj.run_drop("S12", duration=0.02, engine="ode"))["fork_mm"]["max_abs_mm"] < 0.1


# --- 2. identify, given what the command line's fit refuses -----------------------------------------------------

@pytest.mark.parametrize("kind, kwargs, said", [
    # "e: no such file": the file's name read letter by letter
    ("spring", dict(data="dyno.csv"), "data: must be a list of files, e.g. ['dyno.csv'], got the str 'dyno.csv'"),
    # "fit_drop: a free parameter is listed twice"
    ("drop", dict(free="fork.spring.rate_N_per_mm"), "free: must be a list of keys, e.g. "
                                                     "['fork.spring.rate_N_per_mm'], got the str"),
    # "--clicks: 3 positions for 1 dyno files" ("1,2" is three characters)
    ("damper", dict(clicks="1,2"), "clicks: must be a list of positions, one per file, e.g. [12], got the str '1,2'"),
    # 0, "2" and 1.5 ran (one start)
    ("drop", dict(starts=0), "starts: must be at least 1, got 0"),
    ("drop", dict(starts="2"), "starts: must be a whole number, got '2'"),
    # "fit_drop: the fit did not converge (the model run fails at the optimum)"
    ("drop", dict(engine="x"), "engine: 'x' is not one of mujoco, ode, fast"),
    # numpy's "ufunc 'isfinite' not supported for the input types"; "must be real number, not str"
    ("drop", dict(touch_s="0.1"), "touch_s: must be a number of s, got '0.1'"),
    ("tire", dict(mass_kg="3"), "mass_kg: must be a number of kg, got '3'"),
    # "--bound 1: not a free parameter": a list's items read as keys
    ("drop", dict(bounds=[1, 2]), "bounds: must be a mapping of key to (low, high)"),
    # an MtbmjError, not the ValueError a bad argument is
    ("nope", dict(), "fit: unknown kind 'nope' (one of spring, damper, tire, drop)"),
])
def test_identify_given_an_argument_of_the_wrong_kind_names_it(kind, kwargs, said):
    data = kwargs.pop("data", None) or example_paths(kind if kind != "nope" else "spring")
    with pytest.raises(ValueError) as caught:
        identify(kind, data, **kwargs)
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)


# --- 3. a ride's metrics from Python -----------------------------------------------------------------------------

@pytest.mark.parametrize("args, kwargs, said", [
    # the str "180" was taken as 180 mm, "100" and "5" likewise; "no" kept airborne samples out (it is true)
    ((TIME, TRAVEL, "180"), {}, "travel_max_mm: must be a number, got '180'"),
    ((TIME, TRAVEL, 180), dict(threshold_mm_per_s="100"), "threshold_mm_per_s: must be a number, got '100'"),
    ((TIME, TRAVEL, 180), dict(bin_percent="5"), "bin_percent: must be a number, got '5'"),
    ((TIME, TRAVEL, 180), dict(exclude_airtime="no"), "exclude_airtime: must be True or False, got 'no'"),
    # nan counted no bottom-out at all; "3" met "'<' not supported"
    ((TIME, TRAVEL, 180), dict(margin_mm=math.nan), "margin_mm: must be a number of mm, not negative, got nan"),
    ((TIME, TRAVEL, 180), dict(margin_mm="3"), "margin_mm: must be a number of mm, not negative, got '3'"),
    # None was "time_s: not finite at sample 0"; "x" numpy's "could not convert string to float: 'x'"; None as the
    # travel's top "float() argument must be a string or a real number"
    ((None, TRAVEL, 180), {}, "time_s: must be a sequence of numbers, got None"),
    ((TIME, "x", 180), {}, "travel_mm: must be a sequence of numbers, got 'x'"),
    ((TIME, TRAVEL, None), {}, "travel_max_mm: must be a number, got None"),
])
def test_summarize_given_a_value_of_the_wrong_kind_names_it(args, kwargs, said):
    with pytest.raises(ValueError) as caught:
        ride.summarize(*args, **kwargs)
    assert said in str(caught.value) and "\n" not in str(caught.value), str(caught.value)


def test_the_right_kinds_are_taken_numpy_s_too():
    """The other side of the checks above: numpy's bools, whole numbers and floats pass as Python's do."""
    assert limits.switch("x", np.bool_(False)) is False and limits.switch("x", True) is True
    assert limits.whole("x", np.int64(3), 1) == 3 and limits.whole("x", None, 1) is None
    assert limits.names("x", ("S1", "S12"), "S12") == ["S1", "S12"] and limits.names("x", None, "S12") is None
    assert len(sweep.sample([sweep.parse_vary(f"{DROP}=100:600")], np.int64(4), seed=np.int64(1))) == 4
    summary = ride.summarize(list(TIME), list(TRAVEL), np.float64(180.0), margin_mm=0, exclude_airtime=np.bool_(True))
    assert summary["travel_max_mm"] == 180.0
    model, times, qpos = rolling.roll_trajectory("root", 4, fps=np.float64(100.0), duration=0.05)
    assert len(times) == len(qpos) >= 5


# --- 4. files a user made by hand ---------------------------------------------------------------------------------

def test_a_forks_file_holding_a_bikes_table_names_the_key(tmp_path, capfd, monkeypatch):
    """``base = "S12"`` with a ``[rider]`` table: ``presets --show`` took the file for a bike's and said "base 'S12'
    must be a preset name or a .toml file ('S12' is no preset of a bike description: other.toml is a fork's, a file
    of the other kind)", where ``drop`` named the key; both name the key now."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text('base = "S12"\n[rider]\nmass_kg = 80\n')
    said = "mine.toml: rider.mass_kg: unknown key (did you mean sled.rider_mass_kg?)"
    for argv in (["presets", "--show", "mine.toml"], ["drop", "mine.toml", "--out", tmp_path / "out"]):
        line = refused(argv, tmp_path / "out", capfd, said)
        assert "base" not in line
    # the other side: a bike file (its base a bike's) is still shown as one
    (tmp_path / "bike.toml").write_text('base = "trail"\n[rider]\nmass_kg = 80\n')

    status, shown = command_said(["presets", "--show", "bike.toml"], capfd)
    assert status == 0 and "rider.mass_kg = 80" in shown, shown


def test_a_symbolic_link_leading_nowhere_is_named_so(tmp_path, capfd, monkeypatch):
    """A link in a loop was "loop.toml: no such configuration file" (or "no such file"), the file in plain sight."""
    monkeypatch.chdir(tmp_path)
    os.symlink("other.toml", "loop.toml")
    os.symlink("loop.toml", "other.toml")
    os.symlink("gone.csv", "broken.csv")
    out = tmp_path / "out"
    refused(["drop", "loop.toml", "--out", out], out, capfd,
            "loop.toml: no such configuration file (loop.toml is a symbolic link to other.toml, a loop of links)")
    refused(["fit", "spring", "broken.csv", "--out", out], out, capfd,
            "broken.csv: no such file (broken.csv is a symbolic link to gone.csv, which is not there)")

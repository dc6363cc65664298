"""Careless input, round 28: what round 27 (``tests/test_fuzz_careless27.py``) left, then what is new since
session 26 typed as a careless user would. Each case failed before its fix: a run that said nothing of a key
that changed nothing, a runner that did not do what was asked without a word, argparse's own words for a
list typed with spaces, a crawl run for hours before its warning, a traceback or a refusal for a false
reason. Inputs are written here (configuration and bike files, rides, terrains); a refusal is one line,
exit 2, nothing written at --out and nothing left beside it."""
from __future__ import annotations

import json

import pytest

from helpers import command_err as _err, refused


def warned(err: str, *needles) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("mtbmj: warning: ") and all(n in line for n in needles)]


# --- 1. a file's own key its model does not read: one warning line naming the key and the file ----------

def test_a_fork_files_own_key_its_spring_does_not_read_is_said(tmp_path, capfd):
    """S1's spring is linear: a file on it setting the progressive rate changed nothing, silently. Now one
    warning line names the key, the file and what the model reads; the key the model reads is not warned
    of, nor are the keys the file's base (the reference) sets for other models."""
    unread = tmp_path / "soft.toml"
    unread.write_text('base = "S1"\n[fork.spring]\nprogressive_rate_N_per_mm = 9\n')
    read = tmp_path / "stiff.toml"
    read.write_text('base = "S1"\n[fork.spring]\nrate_N_per_mm = 9\n')
    for path, expect in ((unread, 1), (read, 0)):
        status, err = _err(["drop", path, "--engine", "ode", "--duration", "0.02", "--quiet",
                            "--out", tmp_path / path.stem], capfd)
        assert status == 0, err
        lines = warned(err, "does not read")
        assert len(lines) == expect, err
        if expect:
            assert "fork.spring.progressive_rate_N_per_mm" in lines[0] and str(path) in lines[0]
            assert "'linear'" in lines[0] and "rate_N_per_mm" in lines[0]


def test_a_whole_configuration_without_a_base_is_not_held_to_it(tmp_path, capfd):
    """A file with no base gives every key, as the reference does (S12 written out whole): the keys it
    carries for the models it did not choose pass unsaid; the same keys over a base are said."""
    from mtbmj.config import load

    whole = tmp_path / "whole.toml"
    whole.write_text(load("S12").to_toml())
    on_base = tmp_path / "on_base.toml"
    on_base.write_text('base = "S12"\n[fork.damper]\ncoefficient_N_s_per_m = 900\n')
    said = {}
    for path in (whole, on_base):
        status, err = _err(["drop", path, "--engine", "ode", "--duration", "0.02", "--quiet",
                            "--out", tmp_path / path.stem], capfd)
        assert status == 0, err
        said[path.stem] = warned(err, "does not read")
    assert said["whole"] == [] and len(said["on_base"]) == 1 and "coefficient_N_s_per_m" in said["on_base"][0]


def test_a_bike_files_own_set_key_its_fork_does_not_read_is_said(tmp_path, capfd):
    """The SST fork's spring is progressive: a bike file on it whose [fork.set] gives the linear rate ran
    as if it had none. One warning line names the key, the file and its table; the preset itself (whose
    shock.set the same keys are read from) says nothing."""
    bike = tmp_path / "mine.toml"
    bike.write_text('base = "sst"\n[fork.set]\n"fork.spring.rate_N_per_mm" = 9.0\n')
    lines = {}
    for name, ref in (("mine", bike), ("sst", "sst")):
        status, err = _err(["bike", ref, "flat", "--speed", "3", "--duration", "0.1", "--quiet", "--no-figure",
                            "--out", tmp_path / name], capfd)
        assert status == 0, err
        lines[name] = warned(err, "does not read")
    assert len(lines["mine"]) == 1 and lines["sst"] == [], lines
    assert all(s in lines["mine"][0] for s in ("fork.spring.rate_N_per_mm", str(bike), "[fork.set]", "'progressive'"))


def test_a_misspelt_key_in_a_bike_files_set_table_names_the_file(tmp_path, capfd):
    """'fork.sprng.rate_N_per_mm' in [fork.set] was refused without naming the file it is in."""
    bike = tmp_path / "typo.toml"
    bike.write_text('base = "sst"\n[fork.set]\n"fork.sprng.rate_N_per_mm" = 9.0\n')
    line = refused(["bike", bike, "flat", "--speed", "3", "--duration", "0.1", "--quiet", "--out", tmp_path / "o"],
                   tmp_path / "o", capfd, str(bike))
    assert "[fork.set]" in line and "fork.spring.rate_N_per_mm" in line  # the key meant


def test_the_passive_riders_height_names_the_file(tmp_path, capfd):
    """rider.height_m in a bike file run by the passive rider: the warning line names the file now."""
    bike = tmp_path / "tall.toml"
    bike.write_text('base = "sst"\n[rider]\nheight_m = 1.9\n')
    status, err = _err(["bike", bike, "flat", "--speed", "3", "--duration", "0.1", "--quiet", "--no-figure",
                        "--out", tmp_path / "o"], capfd)
    assert status == 0, err
    lines = warned(err, "rider.height_m")
    assert len(lines) == 1 and str(bike) in lines[0], err


# --- 2. --runner batch with an engine that has none ---------------------------------------------------

def test_runner_batch_on_the_ode_engine_says_it_runs_one_by_one(tmp_path, capfd):
    lines = {}
    for engine in ("ode", "mujoco"):
        status, err = _err(["sweep", "S1", "--vary", "fork.spring.preload_N=100:200:2", "--engine", engine,
                            "--runner", "batch", "--duration", "0.02", "--workers", "1", "--quiet", "--no-figure",
                            "--out", tmp_path / engine], capfd)
        assert status == 0, err
        lines[engine] = warned(err, "--runner batch")
    assert len(lines["ode"]) == 1 and "runs alone" in lines["ode"][0] and lines["mujoco"] == [], lines


# --- 3. a comma list typed with spaces -----------------------------------------------------------------

@pytest.mark.parametrize("typed, said", [
    (["r1.csv", "r2.csv", "--clicks", "0", "8"], "--clicks 0,8"),
    (["--clicks", "0", "8", "r1.csv", "r2.csv"], "--clicks 0,8"),  # 8 was read as a record
    (["r1.csv", "r2.csv", "--clicks", "0,", "8"], "--clicks 0,8"),
    (["r1.csv", "r2.csv", "--clicks=0", "8"], "--clicks 0,8"),
    (["r1.csv", "r2.csv", "--clicks", "0,8", "--predict-clicks", "4", "12"], "--predict-clicks 4,12"),
])
def test_a_comma_list_typed_with_spaces_names_the_way_out(tmp_path, capfd, typed, said, monkeypatch):
    """argparse said "unrecognized arguments: 8" (or "8: cannot read"): now the line shows the list typed right."""
    monkeypatch.chdir(tmp_path)
    for name in ("r1.csv", "r2.csv"):
        (tmp_path / name).write_text("time_s,travel_mm\n0,1\n")
    out = tmp_path / "fit"
    line = refused(["fit", "bounce", *typed, "--out", out], out, capfd, said)
    assert "comma list" in line


def test_a_comma_list_typed_right_is_not_held_to_it(tmp_path, capfd, monkeypatch):
    """The check is not a blanket one: the list typed with commas reaches the records (refused for them)."""
    monkeypatch.chdir(tmp_path)
    for name in ("r1.csv", "r2.csv"):
        (tmp_path / name).write_text("time_s,travel_mm\n0,1\n")
    line = refused(["fit", "bounce", "r1.csv", "r2.csv", "--clicks", "0,8", "--out", tmp_path / "fit"],
                   tmp_path / "fit", capfd, "r1.csv")
    assert "comma list" not in line


# --- 4. a crawl: refused before the run ------------------------------------------------------------------

@pytest.mark.parametrize("command", [["roll", "rock"], ["bike", "sst", "rock"]])
def test_a_crawl_over_the_terrain_is_refused_before_the_run(tmp_path, capfd, command):
    """--speed 0.001 ran for hours (the default length: the terrain crossed, 3800 s simulated) and
    warned at the end; now refused before any work, naming the way out (its plausibility note rides along)."""
    out = tmp_path / "o"
    line = refused([*command, "--speed", "0.001", "--out", out], out, capfd, "--speed 0.001 m/s")
    assert "--duration" in line and "simulated time" in line


def test_a_slow_speed_with_a_duration_runs(tmp_path, capfd):
    """The refusal is of the default length only: with --duration the slow roll runs (and says its speed
    is outside what bikes have)."""
    status, err = _err(["roll", "rock", "--speed", "0.001", "--duration", "0.05", "--quiet", "--no-figure",
                        "--out", tmp_path / "o"], capfd)
    assert status == 0, err
    assert warned(err, "--speed")
    assert (tmp_path / "o").is_dir()


# --- fuzzing what is new since session 26: a reconstruction's folder and files ---------------------------

def _reconstruction_folder(folder):
    """A folder as ``mtbmj reconstruct`` leaves it, written here: terrain.csv (a 20 m profile, 0.1 m rows,
    a 40 mm bump) and a reconstruction.json beside it."""
    folder.mkdir()
    rows = [f"{0.1 * i:.1f},{40.0 if 80 <= i < 90 else 0.0:g}" for i in range(201)]
    (folder / "terrain.csv").write_text("distance_m,height_mm\n" + "\n".join(rows) + "\n")
    (folder / "reconstruction.json").write_text(json.dumps({"drop_levels": [], "beyond_trail": []}, indent=1))
    return folder


@pytest.mark.parametrize("command", [["roll"], ["bike", "sst"]])
@pytest.mark.parametrize("given", ["rec", "rec/reconstruction.json"])
def test_a_reconstructions_folder_or_json_as_the_terrain_names_its_terrain_csv(tmp_path, capfd, monkeypatch,
                                                                               command, given):
    """The folder was "unknown scenario 'rec'", its reconstruction.json "line 2: 2 cells for 1 columns";
    now both name the profile beside them, rec/terrain.csv, which runs."""
    monkeypatch.chdir(tmp_path)
    _reconstruction_folder(tmp_path / "rec")
    out = tmp_path / "o"
    line = refused([*command, given, "--speed", "3", "--duration", "0.1", "--quiet", "--out", out], out, capfd,
                   "rec/terrain.csv")
    assert "not a terrain profile" in line
    status, err = _err([*command, "rec/terrain.csv", "--speed", "3", "--duration", "0.1", "--quiet", "--no-figure",
                        "--out", out], capfd)
    assert status == 0, err


def test_a_folder_named_as_a_scenario_is_the_scenario(tmp_path, capfd, monkeypatch):
    """The folder check is not a blanket one: a folder called rock (an earlier run's --out) leaves
    ``roll rock`` the rock."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rock").mkdir()
    status, err = _err(["roll", "rock", "--speed", "3", "--duration", "0.1", "--quiet", "--no-figure",
                        "--out", tmp_path / "o"], capfd)
    assert status == 0, err


@pytest.mark.parametrize("typed, there", [("REC/TERRAIN.CSV", "rec/terrain.csv"), ("rec/Terrain.csv", "rec/terrain.csv")])
def test_a_terrain_csv_in_another_case_is_pointed_at(tmp_path, capfd, monkeypatch, typed, there):
    """'REC/TERRAIN.CSV: no such file' named nothing; a folder on the way in another case is followed too."""
    monkeypatch.chdir(tmp_path)
    _reconstruction_folder(tmp_path / "rec")
    out = tmp_path / "o"
    refused(["bike", "sst", typed, "--speed", "3", "--duration", "0.1", "--quiet", "--out", out], out, capfd,
            f"(there is {there})")


def test_advise_try_in_another_case_is_pointed_at(tmp_path, capfd, monkeypatch):
    """--try BIKE.toml beside bike.toml said "no such bike file" only. Refused before the ride is read: the
    ride here is a placeholder (the --try check comes first)."""
    from helpers import write_sst
    import numpy as np

    monkeypatch.chdir(tmp_path)
    (tmp_path / "bike.toml").write_text('base = "sst"\n')
    t = np.arange(0.0, 20.0, 1e-3)
    write_sst(tmp_path / "ride.SST", 40.0 + 5.0 * np.sin(t), 50.0 + 5.0 * np.sin(t))
    out = tmp_path / "advice"
    refused(["advise", "ride.SST", "--bike", "bike.toml", "--try", "BIKE.toml", "--out", out], out, capfd,
            "(there is bike.toml)")


@pytest.mark.parametrize("command", ["reconstruct", "telemetry"])
def test_a_file_an_mtbmj_command_wrote_given_as_a_ride_says_so(tmp_path, capfd, command):
    """A run folder's timeseries.csv (or reconstruct's series.csv) given as the ride was "unknown column
    'time_s'..." alone; now the line says which command wrote it. A CSV of the user's with the same
    header is not said to be mtbmj's."""
    run = tmp_path / "run"
    status, err = _err(["bike", "sst", "flat", "--speed", "3", "--duration", "0.1", "--quiet", "--no-figure",
                        "--out", run], capfd)
    assert status == 0, err
    mine = tmp_path / "mine.csv"
    mine.write_text((run / "timeseries.csv").read_text())
    out = tmp_path / "o"
    line = refused([command, run / "timeseries.csv", "--bike", "sst", "--out", out], out, capfd, "unknown column")
    assert "what mtbmj bike wrote, not a ride" in line
    line = refused([command, mine, "--bike", "sst", "--out", out], out, capfd, "unknown column")
    assert "mtbmj bike" not in line

"""Careless input, round 27: what a new user types on the commands earlier rounds covered least
(study, fit's kinds, bike's --start-m, sweep, sensitivity, presets --show, the fork's keys typed with
a unit only, --out onto another command's folder). Each case failed before its fix: a traceback, a
refusal for a false reason, a run that did not do what was asked, or a message that did not name
the way out. Inputs are written here; refusals are checked by ``helpers.check`` (one line, exit 2,
nothing written at --out, nothing left beside it)."""
from __future__ import annotations

import json

import pytest

from helpers import fresh
from mtbmj.cli import main


def _err(argv, capfd) -> tuple[int, str]:
    capfd.readouterr()
    status = main([str(a) for a in argv])
    return status, capfd.readouterr().err


def refused(argv, out, capfd, said: str) -> str:
    """``mtbmj argv`` refused: exit 2, one line holding ``said``, no traceback, nothing at ``out`` or
    beside it; the line."""
    status, err = _err(argv, capfd)
    lines = err.splitlines()
    assert status == 2 and len(lines) == 1 and lines[0].startswith("mtbmj: error: "), (status, err)
    assert said in lines[0], lines[0]
    assert not out.exists() and not [p for p in out.parent.iterdir() if p.name.startswith(f".{out.name}.")]
    return lines[0]


# --- study: a preset in another case, a file, a list with a space or a trailing comma ----------------

@pytest.mark.parametrize("presets,names", [("s1", ["S1"]), ("S1, S2", ["S1", "S2"]), ("S1,", ["S1"])])
def test_study_takes_presets_as_typed(tmp_path, capfd, presets, names):
    """'s1' was a KeyError traceback (exit 1: the run named itself S1), 'S1, S2' refused ' S2' as
    an unknown preset and 'S1,' read '' as the current folder."""
    out = tmp_path / "study"
    status, err = _err(["study", "--presets", presets, "--engines", "ode", "--duration", "0.02", "--quiet",
                        "--out", out], capfd)
    assert status == 0, err
    assert sorted(json.loads((out / "study_summary.json").read_text())) == names


def test_study_takes_a_configuration_file(tmp_path, capfd):
    """A TOML file among --presets: the run is named after the file's stem (it was a KeyError)."""
    config = tmp_path / "soft.toml"
    config.write_text('base = "S1"\n[fork.spring]\npreload_N = 150\n')
    out = tmp_path / "study"
    status, err = _err(["study", "--presets", f"{config},S1", "--engines", "ode", "--duration", "0.02", "--quiet",
                        "--out", out], capfd)
    assert status == 0, err
    assert sorted(json.loads((out / "study_summary.json").read_text())) == ["S1", "soft"]


@pytest.mark.parametrize("presets,said", [("S1,s1", "S1 is named twice"), ("", "no preset named"),
                                          (" , ", "no preset named")])
def test_study_refuses_a_preset_twice_or_none(tmp_path, capfd, presets, said):
    """'S1,s1' ran S1 twice into one result; an empty --presets ran all fourteen."""
    _, out = fresh(tmp_path)
    refused(["study", "--presets", presets, "--engines", "ode", "--duration", "0.02", "--out", out], out, capfd, said)


# --- bike --start-m: the default duration from the start; a start past everything refused ---------

def test_a_start_before_the_terrain_still_crosses_the_feature(tmp_path, capfd):
    """From --start-m -5 the default run ended 5 m short: the rear never reached the rock (its
    travel the static 48 mm, no window closed). Now the run is as long as the distance asks and the
    rear's peak is the one a start at the terrain's start gives (a naive baseline: the static rear)."""
    runs = {}
    for name, start in (("at0", []), ("before", ["--start-m", "-5"])):
        out = tmp_path / name
        status, err = _err(["bike", "sst", "rock", "--speed", "3", *start, "--quiet", "--no-figure", "--out", out],
                           capfd)
        assert status == 0, err
        runs[name] = json.loads((out / "summary.json").read_text())
    at0, before = runs["at0"], runs["before"]
    assert at0["max_rear_travel_mm"] > at0["static_rear_travel_mm"] + 10.0  # the rock reaches the rear
    assert before["max_rear_travel_mm"] == pytest.approx(at0["max_rear_travel_mm"], abs=0.5)
    assert before["feature"]["closed"]
    assert before["start_m"] == pytest.approx(-5.0)
    assert before["duration_s"] == pytest.approx(at0["duration_s"] + 5.0 / 3.0, abs=0.01)  # 5 m more at 3 m/s


@pytest.mark.parametrize("scenario,start,said", [("rock", "30", "past the feature of rock"),
                                                 ("rock", "3.7", "the rear axle at 2.44 m"),
                                                 ("flat", "10", "past the end of the terrain flat")])
def test_a_start_past_everything_is_refused(tmp_path, capfd, scenario, start, said):
    """--start-m 30 past a rock ran on the level ground beyond and reported '0 % tire-load variation
    over the feature'; now one line. --start-m 9 on flat (10 m) still runs."""
    _, out = fresh(tmp_path)
    refused(["bike", "sst", scenario, "--speed", "3", "--start-m", start, "--quiet", "--no-figure", "--out", out],
            out, capfd, said)


# --- rider.height_m: read by the active rider only --------------------------------------------------

def test_the_passive_rider_says_it_does_not_read_the_height(tmp_path, capfd):
    """A passive run given rider.height_m said nothing (the height changed nothing); now one warning
    line, and none for the active rider, who reads it, nor for a run without the key."""
    lines = {}
    for name, extra in (("passive", ["--set", "rider.height_m=1.9"]), ("plain", []),
                        ("active", ["--set", "rider.height_m=1.9", "--rider", "active"])):
        out = tmp_path / name
        status, err = _err(["bike", "sst", "flat", "--speed", "3", "--duration", "0.2", *extra, "--quiet",
                            "--no-figure", "--out", out], capfd)
        assert status == 0, err
        lines[name] = [line for line in err.splitlines() if "rider.height_m" in line]
    assert len(lines["passive"]) == 1 and "active rider only" in lines["passive"][0]
    assert lines["plain"] == [] and lines["active"] == []

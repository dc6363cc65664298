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

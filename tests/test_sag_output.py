"""``mtbmj sag``'s output is an mtbmj result (issue 23): it carries the output record, so the
command and ``solve_sag(...).write()`` replace their own earlier config.toml, from either side,
and still refuse a folder holding anything else, with the folder left as it was."""
import json

import pytest

import mtbmj
from mtbmj import output
from mtbmj.cli import main
from mtbmj.config import load
from mtbmj.errors import MtbmjError


def _psi(folder):
    return load(folder / "config.toml")["fork.spring.air_pressure_psi"]


def test_the_command_replaces_its_own_result(tmp_path, capsys):
    out = tmp_path / "sag"
    assert main(["sag", "air120", "--load-kg", "60", "--sag-percent", "25", "--out", str(out)]) == 0
    first = _psi(out)
    record = output.read_record(out)
    assert record["command"] == "sag" and "config.toml" in record["files"]
    assert main(["sag", "air120", "--load-kg", "80", "--sag-percent", "25", "--out", str(out)]) == 0
    assert _psi(out) > first  # the heavier load's pressure, not the old file
    assert sorted(p.name for p in out.iterdir()) == [".lock", output.RECORD, "config.toml"]
    assert load(out / "config.toml")["sled.body_mass_kg"] == 80.0


def test_write_replaces_its_own_result_and_the_commands(tmp_path, capsys):
    out = tmp_path / "sag"
    light = mtbmj.solve_sag("S12", 55.0, 25.0)
    heavy = mtbmj.solve_sag("S12", 75.0, 25.0)
    assert light.write(out) == [out / "config.toml"]
    assert heavy.write(out) == [out / "config.toml"]  # no traceback on its own folder
    assert load(out / "config.toml")["fork.spring.preload_N"] == pytest.approx(heavy.value)
    assert output.foreign_entry(out) is None
    assert main(["sag", "S12", "--load-kg", "55", "--sag-percent", "25", "--out", str(out)]) == 0
    assert load(out / "config.toml")["fork.spring.preload_N"] == pytest.approx(light.value)
    heavy.write(out)  # and the Python side replaces the command's
    assert load(out / "config.toml")["fork.spring.preload_N"] == pytest.approx(heavy.value)
    assert json.loads((out / output.RECORD).read_text())["files"] == [".lock", "config.toml"]


def test_write_still_refuses_a_folder_of_the_users(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "config.toml").write_text("# my own fork\n")
    with pytest.raises(MtbmjError, match="mtbmj did not write"):
        mtbmj.solve_sag("air120", 70.0, 20.0).write(out)
    assert (out / "config.toml").read_text() == "# my own fork\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]

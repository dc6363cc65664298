"""docs/own_bike.md's commands, run as written (in order, from a folder holding the page's example
bike where the repository holds it): each exits 0 and writes what the page says it writes."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from mtbmj.cli import main
from helpers import shell_commands

REPO = Path(__file__).resolve().parents[1]
PAGE = REPO / "docs" / "own_bike.md"


@pytest.mark.slow
def test_every_command_of_the_page_runs(tmp_path, monkeypatch, capsys):
    (tmp_path / "docs").mkdir()
    shutil.copytree(REPO / "docs" / "bikes", tmp_path / "docs" / "bikes")
    monkeypatch.chdir(tmp_path)
    commands = [argv for _, argv in shell_commands(PAGE)]
    assert [c[:2] for c in commands] == [["mtbmj", "presets"], ["mtbmj", "sag"], ["mtbmj", "bike"],
                                         ["mtbmj", "crosscheck"], ["mtbmj", "bike"], ["mtbmj", "compare"],
                                         ["mtbmj", "telemetry"]]
    for argv in commands:
        assert main(argv[1:]) == 0, argv
    out = capsys.readouterr().out
    assert "geometry.head_angle_deg = 64.5" in out
    assert "gives 20.0 % front sag" in out and "gives 30.0 % rear" in out
    assert "within the tolerances" in out
    for folder in ("my_sag", "my_root", "my_95kg", "my_compare", "my_tel"):
        assert any((tmp_path / "out" / folder).iterdir()), folder

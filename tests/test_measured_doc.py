"""docs/measured.md is what benchmarks/report.py writes from the committed results
(benchmarks/results/*.json), so the page cannot drift from its data; every command it shows names a
script in benchmarks/ and parses with that script's options; a row whose results file is missing is
left out; the page keeps its cells short and tells no history."""
from __future__ import annotations

import argparse
import importlib.util
import json
import re
import shlex
import shutil
import sys
from pathlib import Path

import pytest

from helpers import script_parser

REPO = Path(__file__).resolve().parents[1]
BENCH = REPO / "benchmarks"
PAGE = REPO / "docs" / "measured.md"


@pytest.fixture(scope="module")
def report():
    spec = importlib.util.spec_from_file_location("mtbmj_bench_report", BENCH / "report.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks its module up
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(spec.name, None)


def table_rows(text: str) -> list[list[str]]:
    """The cells of every table row of the page (header and rule lines left out)."""
    rows = []
    for line in text.splitlines():
        if line.startswith("| ") and not line.startswith("| figure"):
            rows.append([c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]])
    return rows


def test_the_page_is_what_report_py_writes(report):
    assert PAGE.read_text() == report.render(), (
        "docs/measured.md differs from what benchmarks/report.py writes: run python benchmarks/report.py")


def test_every_command_names_a_script_and_its_options():
    commands = [cell.strip("`") for row in table_rows(PAGE.read_text()) for cell in row[-1:]]
    assert len(commands) >= 20
    for command in set(commands):
        argv = shlex.split(command)
        assert argv[0] == "python" and argv[1].startswith("benchmarks/"), command
        script = REPO / argv[1]
        assert script.is_file(), f"{command}: no {argv[1]}"
        parser = script_parser(script)
        try:
            parser.parse_args(argv[2:])
        except (argparse.ArgumentError, SystemExit) as exc:  # pragma: no cover - the message says which
            pytest.fail(f"{command}: {exc}")


def test_the_parser_check_catches_a_wrong_option():
    with pytest.raises((argparse.ArgumentError, SystemExit)):
        script_parser(BENCH / "sweep.py").parse_args(["--variants", "200", "--wokers", "2"])
    with pytest.raises((argparse.ArgumentError, SystemExit)):
        script_parser(BENCH / "dropfit.py").parse_args(["--fit-engine", "slow"])


def test_every_results_file_named_exists_and_cells_are_short():
    text = PAGE.read_text()
    for row in table_rows(text):
        assert len(row) == 5, row
        assert all(len(cell) <= 200 for cell in row), row
    for name in set(re.findall(r"--out benchmarks/results/(\S+\.json)", text)):
        assert (BENCH / "results" / name).is_file(), name


def test_the_page_tells_no_history():
    text = PAGE.read_text().lower()
    for phrase in ("last figures", "stops ago", "this stop", "at the last", "used to", "no longer", "was once"):
        assert phrase not in text, phrase


def test_a_missing_results_file_gives_no_rows(report, tmp_path, monkeypatch):
    """Rows come only from the files that are there; a file that records its date and commit shows
    them."""
    data = json.loads((BENCH / "results" / "native_loop.json").read_text())
    data.update(measured_at="2030-01-02", commit="abc1234")
    (tmp_path / "native_loop.json").write_text(json.dumps(data))
    shutil.copy(BENCH / "results" / "rolling.json", tmp_path / "rolling.json")
    monkeypatch.setattr(report, "RESULTS", tmp_path)
    rows = table_rows(report.render())
    assert {shlex.split(row[-1].strip("`"))[1] for row in rows} == {"benchmarks/native_loop.py", "benchmarks/rolling.py"}
    assert rows[0][3].startswith("2030-01-02, abc1234")
    assert "## Fits" not in report.render()


def test_no_cell_shows_a_number_that_is_not_one():
    """A figure with nothing behind it (a ride whose whole bike diverged before any checked sample)
    is said in words, never printed as nan or inf."""
    for row in table_rows(PAGE.read_text()):
        for cell in row:
            assert not re.search(r"\b(nan|inf)\b", cell.lower()), cell


def test_a_ride_with_no_sample_checked_says_so(report):
    """reconstruct_rides_rows on a ride written here whose checks have no sample (all nan)."""
    nan = float("nan")
    ride = {"folder": "sst_v2", "ride": "X.SST", "version": 2, "seconds": 122.0,
            "speed_profile": {"median_m_per_s": 6.37, "min_m_per_s": 5.73, "max_m_per_s": 6.47, "windows_accepted": 3,
                              "windows_rejected": 45},
            "speed_sd_median_m_per_s": 0.15, "rear_correlation": None, "whole_bike": {"diverged_s": 57.7},
            "checks": {"rear_predicted_rms_mm": nan, "baseline_delayed_fork_rms_mm": nan, "baseline_rear_mean_rms_mm": nan,
                       "samples_checked_percent": 0.0, "passes": False}}
    [row] = report.reconstruct_rides_rows({"beat_margin_percent": 40.0, "rides": [ride], "command": "x"})["reconstruct"]
    assert "no sample checked" in row.measured and "nan" not in row.measured
    assert row.measured.endswith("**fails** (the whole bike diverged at 57.7 s)")

"""Every shipped example runs as the docs show it, exits 0 and passes its own check (issue 37
item 5): ``mtbmj fit spring|damper|tire|drop example``, ``mtbmj validate example`` and
``mtbmj telemetry example``. An example must show the tool working.

What each is checked against comes from outside the code under test: the truths the generators
wrote into the records' headers (the parameters of the synthetic records, the sled record's true
touch) and the SST format's own sample count (16-byte header, 4 bytes a sample)."""
from __future__ import annotations

import json
import re

import pytest

from mtbmj import cli
from mtbmj.identify.examples import data_dir


def run(capsys, argv):
    status = cli.main([str(a) for a in argv])
    return status, capsys.readouterr().out


def header(name: str) -> str:
    """The comment lines of a shipped record, as one text."""
    lines = (data_dir() / name).read_text().splitlines()
    return " ".join(line.lstrip("# ") for line in lines if line.startswith("#"))


def truth(name: str) -> dict[str, float]:
    """``key=value`` pairs of numbers a generator wrote into a record's header."""
    return {k: float(v) for k, v in re.findall(r"([a-z_.]+_(?:N|N_s_per_m|N_per_mm|mm))=([0-9.]+)", header(name))}


def fitted(tmp_path, capsys, kind):
    out = tmp_path / kind
    status, printed = run(capsys, ["fit", kind, "example", "--out", out])
    summary = json.loads((out / "fit.json").read_text())
    return status, printed, summary


@pytest.mark.parametrize("kind", ["spring", "damper", "tire"])
def test_a_bench_fit_example_exits_0_with_its_check_passed(tmp_path, capsys, kind):
    status, printed, summary = fitted(tmp_path, capsys, kind)
    assert status == 0, printed
    assert summary["model_check_passed"] is True and summary["synthetic_data"] is True
    assert "model check passed" in printed and "model check FAILED" not in printed
    checks = [m["model_check"] for m in summary["models"].values() if "model_check" in m]
    assert checks and all(c["passed"] for c in checks)


def test_the_damper_example_finds_the_damper_its_header_names(tmp_path, capsys):
    _, _, summary = fitted(tmp_path, capsys, "damper")
    written = summary["models"][summary["chosen"][0]]
    for key, value in truth("damper_example.csv").items():
        low, high = written["ci95"][key]
        assert low <= value <= high, (key, value, low, high)


@pytest.mark.slow
def test_the_drop_example_exits_0_and_finds_what_made_it(tmp_path, capsys):
    status, printed, summary = fitted(tmp_path, capsys, "drop")
    assert status == 0, printed
    assert summary["model_check_passed"] is True and "model check passed" in printed
    drop = summary["models"]["drop"]
    made = truth("sled_example.csv")
    assert set(made) == set(drop["values"]) == {"tire.impact_rate_N_per_mm", "fork.spring.preload_N"}
    for key, value in made.items():
        low, high = drop["ci95"][key]
        assert low <= value <= high, (key, value, low, high)
    assert "NOT A CLEAN RESULT" not in (tmp_path / "drop" / "fit.toml").read_text()


@pytest.mark.slow
def test_validate_example_exits_0_with_every_event_found(tmp_path, capsys):
    out = tmp_path / "validate"
    status, printed = run(capsys, ["validate", "example", "--out", out, "--quiet"])
    assert status == 0, printed
    summary = json.loads((out / "validation_summary.json").read_text())
    assert summary["record"]["synthetic"] is True and len(summary["configs"]) == 14
    assert summary["measured_events"]["flags"] == []  # lift-off, landing, every peak and the rest found
    touch = float(re.search(r"true touch at t = ([0-9.]+) s", header("sled_example.csv")).group(1))
    assert summary["record"]["touch_in_file_s"] == pytest.approx(touch, abs=5e-4)  # half a 1 kHz sample


def test_telemetry_example_exits_0_and_reads_the_whole_file(tmp_path, capsys):
    from mtbmj.measured import telemetry

    out = tmp_path / "telemetry"
    status, printed = run(capsys, ["telemetry", "example", "--out", out])
    assert status == 0, printed
    measured = json.loads((out / "telemetry.json").read_text())["measured"]
    path = telemetry.example_path()
    assert measured["samples"] == (path.stat().st_size - 16) // 4
    assert measured["fork"]["samples"] == measured["rear"]["samples"] == measured["samples"]

"""A run folder that lies is not replayed as truth (issue 37 item 2): its files must be regular
files within their size limits, and a bike folder's summary must agree with its own time series."""
import json
import os
import shutil

import pytest

from mtbmj import cli


@pytest.fixture(scope="module")
def bike_dir(tmp_path_factory):
    from mtbmj.bike.run import run_bike

    folder = tmp_path_factory.mktemp("bike") / "run"
    run_bike("sst", "flat", 4.0, duration=0.4).write(folder, figure=False)
    return folder


def _copy(bike_dir, tmp_path):
    target = tmp_path / "run"
    shutil.copytree(bike_dir, target)
    return target


@pytest.mark.parametrize("name", ["manifest.json", "summary.json", "timeseries.csv"])
@pytest.mark.parametrize("kind", ["fifo", "dev_zero"])
def test_special_files_are_refused_at_once(bike_dir, tmp_path, monkeypatch, capsys, name, kind):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    run = _copy(bike_dir, tmp_path)
    (run / name).unlink()
    if kind == "fifo":
        os.mkfifo(run / name)
    else:
        (run / name).symlink_to("/dev/zero")
    assert cli.main(["render", str(run), "--out", str(tmp_path / "v.gif"), "--width", "32", "--height", "32"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and name in err and "not a regular file" in err
    assert not (tmp_path / "v.gif").exists()


@pytest.mark.parametrize("seconds", [60.0, 0.2, 0.0])
def test_an_edited_duration_is_refused(bike_dir, tmp_path, monkeypatch, capsys, seconds):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    run = _copy(bike_dir, tmp_path)
    summary = json.loads((run / "summary.json").read_text())
    summary["duration_s"] = seconds
    (run / "summary.json").write_text(json.dumps(summary))
    assert cli.main(["render", str(run), "--out", str(tmp_path / "v.gif"), "--width", "32", "--height", "32"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "summary.json says" in err and "0.4 s" in err
    assert not (tmp_path / "v.gif").exists()


def test_a_cut_time_series_is_refused(bike_dir, tmp_path, monkeypatch, capsys):
    """Half the rows removed (the duration in the summary then disagrees too)."""
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    run = _copy(bike_dir, tmp_path)
    lines = (run / "timeseries.csv").read_text().splitlines(keepends=True)
    (run / "timeseries.csv").write_text("".join(lines[: len(lines) // 2]))
    assert cli.main(["render", str(run), "--out", str(tmp_path / "v.gif"), "--width", "32", "--height", "32"]) == 2
    assert capsys.readouterr().err.count("\n") == 1

"""A bike run folder in ``mtbmj telemetry --compare`` (both ends beside the real SST ride, on the
same axes) and in ``mtbmj render`` (the video ``mtbmj bike --video`` draws)."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest

from mtbmj import cli
from mtbmj.bike.run import run_bike
from mtbmj.ride import comparison
from mtbmj.measured import telemetry
from mtbmj.rolling import render


@pytest.fixture(scope="module")
def bike_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("bike") / "run"
    run_bike("sst", "root:at_m=0.4", 4.0, 0.3).write(out)
    return out


def test_telemetry_compares_both_ends_of_a_bike_run(bike_dir, tmp_path, capsys):
    out = tmp_path / "tel"
    assert cli.main(["telemetry", "example", "--compare", str(bike_dir), "--out", str(out)]) == 0
    assert "compared 1 run(s)" in capsys.readouterr().out
    summary = json.loads((out / "telemetry.json").read_text())
    (run,) = summary["simulated"]
    assert set(run) >= {"fork", "rear"}
    assert run["fork"]["travel_max_mm"] == 180.0  # the SST preset's fork
    assert run["rear"]["travel_max_mm"] == pytest.approx(174.0)  # its rear wheel travel
    assert sum(run["rear"]["travel_histogram"]["time_percent"]) == pytest.approx(100.0, abs=0.01)
    # the figure: fork and rear rows, each travel axis in % with the ride's mm on top, ride and run on it
    record = telemetry.read_sst(telemetry.example_path())
    fig = comparison.figure(summary)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()  # lays out the secondary (mm) axes
    travel_axes = [ax for ax in fig.axes if "travel [%" in ax.get_xlabel()]
    assert [ax.get_xlabel().split()[0] for ax in travel_axes] == ["fork", "rear"]
    for ax, top in zip(travel_axes, (record.fork_max_mm, record.rear_max_mm)):
        assert ax.get_xlim() == (0.0, 100.0)
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any(t.startswith("simulated sst (bike)") for t in labels)
        assert any(t.startswith("measured") for t in labels)
        (mm,) = [c for c in ax.child_axes]
        assert mm.get_xlabel() == f"{ax.get_xlabel().split()[0]} travel [mm] of the ride's {top:.0f} mm"
        assert mm.get_xlim() == pytest.approx((0.0, top))  # 0 .. the ride's travel in mm
    velocity_axes = [ax for ax in fig.axes if "velocity [mm/s]" in ax.get_xlabel()]
    assert len(velocity_axes) == 2
    png = (out / "telemetry.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"


def test_telemetry_refuses_a_folder_that_is_no_run(tmp_path, capsys):
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "timeseries.csv").write_text("time_s,speed\n0,1\n0.1,1\n")
    out = tmp_path / "tel"
    assert cli.main(["telemetry", "example", "--compare", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "neither a drop or roll run" in err and "nor a bike run" in err
    assert not out.exists()


def test_telemetry_of_a_ride_too_short_for_a_velocity_names_the_file(tmp_path, capsys):
    """A travel CSV of two samples (a careless export): one line naming the file and what a velocity needs,
    exit 2, nothing written; five samples are enough (the line is about length, not the file)."""
    out = tmp_path / "tel"
    for n, status in ((2, 2), (5, 0)):
        ride = tmp_path / f"ride{n}.csv"
        ride.write_text("time_s,fork_mm,rear_mm\n" + "".join(f"{i / 1000},{10 + i},{12 + i}\n" for i in range(n)))
        assert cli.main(["telemetry", str(ride), "--out", str(out)]) == status
        err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("mtbmj: error")]
        if status:
            assert err == [f"mtbmj: error: ride{n}.csv: travel_mm: 2 samples are too few for a velocity (its "
                           "Savitzky-Golay fit of order 3 needs 5 or more)"], err
            assert not out.exists()
        else:
            assert not err


@pytest.fixture()
def backend(monkeypatch):
    monkeypatch.delenv("MUJOCO_GL", raising=False)  # conftest disables GL for dm_control
    try:
        return render.gl_backend()
    except render.RenderError as exc:
        pytest.skip(f"no headless GL backend: {exc}")


def test_render_a_bike_folder(bike_dir, tmp_path, backend, capsys):
    from PIL import Image

    gif = tmp_path / "bike.gif"
    assert cli.main(["render", str(bike_dir), "--out", str(gif), "--width", "160", "--height", "120"]) == 0
    assert "bike sst over root:at_m=0.4" in capsys.readouterr().out
    img = Image.open(io.BytesIO(gif.read_bytes()))
    assert img.size == (160, 120)
    assert img.n_frames == 9  # 0.3 s at 30 frames/s
    frames = []
    for k in (0, img.n_frames - 1):
        img.seek(k)
        frames.append(np.asarray(img.convert("RGB"), dtype=float))
    assert frames[0].std() > 5.0  # not blank
    assert np.abs(frames[0] - frames[1]).mean() > 0.1  # the bike moves (the caption's time at least)


def test_render_refuses_a_bike_folder_that_does_not_replay(bike_dir, tmp_path, backend, capsys):
    import shutil

    changed = tmp_path / "changed"
    shutil.copytree(bike_dir, changed)
    summary = json.loads((changed / "summary.json").read_text())
    summary["speed_m_per_s"] = 5.0  # no longer the run its timeseries records
    (changed / "summary.json").write_text(json.dumps(summary))
    gif = tmp_path / "x.gif"
    assert cli.main(["render", str(changed), "--out", str(gif)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "does not reproduce" in err
    assert not gif.exists()

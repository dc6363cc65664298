"""Headless video: frames of a short drop show the model (not blank, not the empty scene, moving
between frames) and the GIF and MP4 files decode. Skips only when no GL backend can be created."""
import numpy as np
import pytest

from mtbmj import cli
from mtbmj.cli import render as cli_render
from mtbmj.rolling import render

SIZE = (160, 120)


@pytest.fixture(scope="module")
def backend():
    with pytest.MonkeyPatch.context() as mp:
        # conftest disables GL for dm_control (MUJOCO_GL=disable); rendering asks for it here.
        mp.delenv("MUJOCO_GL", raising=False)
        try:
            name = render.gl_backend()
        except render.RenderError as exc:
            pytest.skip(f"no headless GL backend: {exc}")
        yield name


@pytest.fixture(scope="module")
def drop(backend):
    traj = render.trajectory("S1", fps=30, duration=0.3)
    return traj, list(render.frames(traj, *SIZE, caption=False))


def run_cli(argv):
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    if "render" in sub.choices:
        return cli.main(argv)
    original = cli.build_parser

    def build():
        p = original()
        cli_render.add_parser(next(a for a in p._actions if a.__class__.__name__ == "_SubParsersAction"))
        return p

    cli.build_parser = build
    try:
        return cli.main(argv)
    finally:
        cli.build_parser = original


def test_frames_show_the_model(drop):
    traj, images = drop
    fall = np.sqrt(2 * 0.095 / 9.81)  # S1 drops from 95 mm: the free fall is prepended
    assert traj.times[0] == pytest.approx(-fall) and len(images) == traj.times.size
    assert all(i.shape == (SIZE[1], SIZE[0], 3) and i.dtype == np.uint8 for i in images)
    assert min(float(i.std()) for i in images) > 10  # not blank
    # The empty scene: the same camera with every model geom but the floor made invisible.
    model = traj.model
    rgba = model.geom_rgba.copy()
    floor = model.geom("floor").id
    model.geom_rgba[np.arange(model.ngeom) != floor, 3] = 0.0
    try:
        (empty,) = render.frames(render.Trajectory(model, traj.times[:1], traj.qpos[:1], ""), *SIZE, caption=False)
    finally:
        model.geom_rgba[:] = rgba
    changed = np.any(np.abs(images[0].astype(int) - empty.astype(int)) > 20, axis=2)
    assert changed.mean() > 0.05  # the tire alone covers more than this
    columns = np.flatnonzero(changed.any(axis=0))
    assert abs(columns.mean() - SIZE[0] / 2) < SIZE[0] * 0.1  # the sled is at x = 0, mid-frame
    # The model moves: the sled falls, compresses the fork and rebounds.
    assert np.abs(images[0].astype(int) - images[-1].astype(int)).max() > 50


def test_gif_and_mp4_decode(backend, tmp_path):
    gif = render.render("S1", tmp_path / "drop.gif", fps=20, width=SIZE[0], height=SIZE[1], duration=0.2)
    from PIL import Image

    with Image.open(gif["path"]) as img:
        assert img.size == SIZE and img.n_frames == gif["frames"] >= 6
        img.seek(img.n_frames - 1)
        assert np.asarray(img.convert("RGB")).std() > 10
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg", reason="MP4 needs imageio-ffmpeg")
    mp4 = render.render("S1", tmp_path / "drop.mp4", fps=20, width=SIZE[0], height=SIZE[1], duration=0.2)
    reader = imageio_ffmpeg.read_frames(mp4["path"])
    meta = reader.__next__()
    decoded = [np.frombuffer(f, np.uint8).reshape(SIZE[1], SIZE[0], 3) for f in reader]
    assert tuple(meta["size"]) == SIZE and len(decoded) == mp4["frames"]
    assert decoded[0].std() > 10
    # no temporary files left; beside each video, the record that it is mtbmj's
    assert sorted(p.name for p in tmp_path.iterdir()) == [".drop.gif.mtbmj-file.json", ".drop.mp4.mtbmj-file.json",
                                                          "drop.gif", "drop.mp4"]


def test_run_directory_is_replayed(backend, tmp_path, capsys, monkeypatch):
    import mtbmj

    monkeypatch.delenv("MUJOCO_GL", raising=False)
    run_dir = tmp_path / "s1"
    result = mtbmj.run_drop("S1", duration=0.3)
    result.write(run_dir)
    traj = render.trajectory(run_dir, fps=50)
    after = traj.times >= 0
    sled = traj.qpos[after, 0]
    assert sled == pytest.approx(np.interp(traj.times[after], result.raw["time_s"], result.raw["sled_mm"] / 1e3), abs=1e-9)
    assert run_cli(["render", str(run_dir), "--out", str(tmp_path / "v.gif"), "--width", "96", "--height", "64",
                    "--duration", "0.1"]) == 0
    assert "wrote" in capsys.readouterr().out and (tmp_path / "v.gif").stat().st_size > 1000


@pytest.mark.parametrize("args, cause", [
    (["S1", "--out", "{d}/video.avi"], "unknown video format '.avi'"),
    (["S1", "--out", "{d}/video"], "unknown video format"),
    (["S1", "--out", "{d}/v.mp4", "--width", "161"], "even sizes"),
    (["S1", "--out", "{d}/v.gif", "--fps", "0"], "--fps"),
    (["S1", "--out", "{d}/v.gif", "--duration", "-1"], "--duration"),
    (["NoSuchPreset", "--out", "{d}/v.gif"], "NoSuchPreset"),
])
def test_bad_input_is_one_line(tmp_path, capsys, monkeypatch, args, cause):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    argv = ["render"] + [a.format(d=tmp_path) for a in args]
    assert run_cli(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and cause in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_disabled_gl_is_one_line(monkeypatch):
    monkeypatch.setattr(render, "_chosen", None)
    monkeypatch.setenv("MUJOCO_GL", "disable")
    with pytest.raises(render.RenderError, match="MUJOCO_GL=disable"):
        render.gl_backend()


def test_rolling_run_directory(backend, tmp_path):
    """A rolling run directory is re-simulated through mtbmj.rolling.frontend.roll_trajectory and rendered."""
    rolling = pytest.importorskip("mtbmj.rolling.frontend", reason="mtbmj.rolling.frontend not present")
    run_dir = tmp_path / "roll"
    rolling.run_roll("washboard", 4.0, duration=0.3).write(run_dir)
    done = render.render(run_dir, tmp_path / "roll.gif", fps=20, width=96, height=64)
    assert done["frames"] >= 6 and done["label"].startswith("roll washboard")
    from PIL import Image

    with Image.open(done["path"]) as img:
        first = np.asarray(img.convert("RGB")).astype(int)
        img.seek(img.n_frames - 1)
        last = np.asarray(img.convert("RGB")).astype(int)
    assert first.std() > 10 and np.abs(first - last).max() > 30  # visible and moving


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_a_killed_render_leaves_nothing_beside_its_target(backend, tmp_path, sig):
    """``mtbmj render`` killed while it writes its MP4: no file, hidden or not, beside the target.
    SIGTERM removes the staged video before the process ends; after SIGKILL the staged video lies in
    the private staging folder of the temporary folder, which the next staging removes."""
    import os
    import signal
    import subprocess
    import sys
    import tempfile
    import time

    from mtbmj import output

    pytest.importorskip("imageio_ffmpeg", reason="MP4 needs imageio-ffmpeg")
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    folder = tmp_path / "videos"
    folder.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    env.update(TMPDIR=str(temporary), MUJOCO_GL=backend)
    command = "import sys; from mtbmj.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen([sys.executable, "-c", command, "render", "S12", "--out", str(folder / "v.mp4"),
                             "--width", "320", "--height", "240", "--fps", "240"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        staged = []
        while time.monotonic() < deadline and proc.poll() is None:  # mid-way: frames are being written
            staged = [p for d in temporary.glob(output.STAGE_PREFIX + "*") for p in d.glob("v.mp4")]
            if staged and staged[0].stat().st_size > 0:
                break
            time.sleep(0.05)
        assert proc.poll() is None and staged, "render ended before it was caught writing"
        proc.send_signal(getattr(signal, sig))
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -getattr(signal, sig)
    assert list(folder.iterdir()) == []  # nothing beside the target, not even a hidden file
    if sig == "SIGTERM":
        assert list(temporary.iterdir()) == []
    else:
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(tempfile, "tempdir", str(temporary))
            output.clear_stale_stages()  # what the next staging does first
        assert list(temporary.iterdir()) == []

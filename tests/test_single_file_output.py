"""Single output files (``render --out FILE``): a file mtbmj did not write is never replaced, and
nothing a killed or failed run stages is left behind for good.

Most of these go through :func:`mtbmj.output.staged_file` directly (no GL needed); the command line's
refusal of a user's GIF is checked through ``render`` where a headless GL backend exists.
"""
import os
import signal
import stat
import subprocess
import sys
import textwrap

import pytest

from mtbmj import output
from mtbmj.errors import MtbmjError


def _write(path, data: bytes):
    with output.staged_file(path, command="test") as stage:
        stage.write_bytes(data)


def _snapshot(folder):
    return sorted((p.name, p.read_bytes() if p.is_file() else None) for p in folder.iterdir())


def test_a_users_file_is_never_replaced(tmp_path):
    holiday = tmp_path / "holiday.gif"
    holiday.write_bytes(b"GIF89a the user's holiday")
    before = (holiday.read_bytes(), holiday.stat().st_mtime_ns)
    with pytest.raises(MtbmjError, match="not written by mtbmj") as err:
        _write(holiday, b"new video")
    assert "\n" not in str(err.value) and "holiday.gif" in str(err.value)
    assert (holiday.read_bytes(), holiday.stat().st_mtime_ns) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["holiday.gif"]


def test_our_file_is_replaced_and_an_edited_one_is_not(tmp_path):
    video = tmp_path / "sub" / "v.gif"
    _write(video, b"first")
    assert video.read_bytes() == b"first"
    _write(video, b"second, longer")  # ours, unchanged since: replaced
    assert video.read_bytes() == b"second, longer"
    assert sorted(p.name for p in video.parent.iterdir()) == [".v.gif.mtbmj-file.json", "v.gif"]
    # The user edits the file (same size, other bytes): it is theirs now.
    video.write_bytes(b"SECOND, LONGER")
    with pytest.raises(MtbmjError, match="changed since"):
        _write(video, b"third")
    assert video.read_bytes() == b"SECOND, LONGER"
    # A record copied beside another file does not make that file ours.
    other = tmp_path / "sub" / "w.gif"
    other.write_bytes(b"second, longer")
    (tmp_path / "sub" / ".w.gif.mtbmj-file.json").write_bytes((tmp_path / "sub" / ".v.gif.mtbmj-file.json").read_bytes())
    with pytest.raises(MtbmjError, match="not written by mtbmj"):
        _write(other, b"x")
    assert other.read_bytes() == b"second, longer"


@pytest.mark.parametrize("kind", ["symlink", "fifo", "directory"])
def test_special_targets_are_refused_untouched(tmp_path, kind):
    target = tmp_path / "v.gif"
    if kind == "symlink":
        (tmp_path / "real.gif").write_bytes(b"real")
        target.symlink_to(tmp_path / "real.gif")
    elif kind == "fifo":
        os.mkfifo(target)
    else:
        target.mkdir()
    before = _snapshot(tmp_path) if kind != "fifo" else None
    with pytest.raises(MtbmjError) as err:
        _write(target, b"video")
    assert "\n" not in str(err.value)
    if kind == "fifo":
        assert stat.S_ISFIFO(os.lstat(target).st_mode) and len(list(tmp_path.iterdir())) == 1
    else:
        assert _snapshot(tmp_path) == before


def test_a_file_that_appears_during_the_work_is_kept(tmp_path):
    video = tmp_path / "v.gif"
    with pytest.raises(MtbmjError, match="appeared|not written by mtbmj"):
        with output.staged_file(video, command="test") as stage:
            stage.write_bytes(b"ours")
            video.write_bytes(b"the user's, written meanwhile")
    assert video.read_bytes() == b"the user's, written meanwhile"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.gif"]


def test_a_failed_or_interrupted_write_leaves_nothing(tmp_path):
    video = tmp_path / "new" / "deeper" / "v.gif"
    for exc in (RuntimeError("boom"), KeyboardInterrupt()):
        with pytest.raises(type(exc)):
            with output.staged_file(video, command="test") as stage:
                stage.write_bytes(b"half a vid")
                raise exc
        assert list(tmp_path.iterdir()) == []  # not even the folders it made


def test_a_killed_write_is_cleaned_by_the_next_one(tmp_path, monkeypatch):
    """SIGKILL mid-write: nothing is left beside the target (the file is staged in a private folder
    of the temporary folder), and the next write removes that folder (its process is gone)."""
    import tempfile

    video = tmp_path / "v.gif"
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    child = textwrap.dedent(f"""
        import os, signal
        from mtbmj import output
        with output.staged_file({str(video)!r}, command="test") as stage:
            stage.write_bytes(b"half")
            os.kill(os.getpid(), signal.SIGKILL)
    """)
    proc = subprocess.run([sys.executable, "-c", child], capture_output=True,
                          env={**os.environ, "TMPDIR": str(temporary)})
    assert proc.returncode == -signal.SIGKILL
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tmp"]  # nothing beside the target ...
    left = [p.name for p in temporary.iterdir()]
    assert len(left) == 1 and left[0].startswith(output.STAGE_PREFIX)  # ... its staging, in the temporary folder
    # a hidden file of the user's with a similar name is not touched
    (tmp_path / ".v.gif.notes").write_bytes(b"mine")
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    _write(video, b"whole")  # ... and the next write removes the killed run's staging
    assert sorted(p.name for p in tmp_path.iterdir()) == [".v.gif.mtbmj-file.json", ".v.gif.notes", "tmp", "v.gif"]
    assert list(temporary.iterdir()) == []


def test_a_terminated_write_leaves_nothing(tmp_path):
    """SIGTERM (and SIGHUP) mid-write: the staged file is removed and the process ends by the signal."""
    video = tmp_path / "v.gif"
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    for sig in (signal.SIGTERM, signal.SIGHUP):
        child = textwrap.dedent(f"""
            import os, signal, time
            from mtbmj import output
            with output.staged_file({str(video)!r}, command="test") as stage:
                stage.write_bytes(b"half")
                os.kill(os.getpid(), {int(sig)})
                time.sleep(5)
                print("survived")
        """)
        proc = subprocess.run([sys.executable, "-c", child], capture_output=True,
                              env={**os.environ, "TMPDIR": str(temporary)})
        assert proc.returncode == -sig and b"survived" not in proc.stdout
        assert sorted(p.name for p in tmp_path.iterdir()) == ["tmp"] and list(temporary.iterdir()) == []


def test_render_command_refuses_a_users_gif(tmp_path, monkeypatch, capsys):
    """The reproduction: ``mtbmj render RUN --out holiday.gif`` over the user's GIF exits 2 in one
    line before any simulation, the file untouched; a second render over its own GIF replaces it."""
    from mtbmj import cli
    from mtbmj.rolling import render

    monkeypatch.delenv("MUJOCO_GL", raising=False)
    holiday = tmp_path / "holiday.gif"
    holiday.write_bytes(b"GIF89a the user's holiday")
    monkeypatch.setattr(render, "trajectory", lambda *a, **k: pytest.fail("simulated before refusing"))
    assert cli.main(["render", "S1", "--out", str(holiday), "--width", "32", "--height", "32"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holiday.gif" in err and "Traceback" not in err
    assert holiday.read_bytes() == b"GIF89a the user's holiday"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["holiday.gif"]

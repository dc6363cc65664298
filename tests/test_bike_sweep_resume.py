"""A bike sweep killed mid-run (SIGKILL) and resumed writes the table an uninterrupted run writes,
byte for byte (issue 40: the same journal and resume as drop sweeps); a folder holding a journal is
not overwritten without --resume."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

ARGS = ["sweep", "trail", "--roll", "root:at_m=0.4", "--speed", "5", "--duration", "0.6",
        "--vary", "rider.mass_kg=70:90:6", "--quiet"]


def _sweep(out, *extra, wait=True):
    cmd = [sys.executable, "-m", "mtbmj.cli", *ARGS, *extra, "--out", str(out)]
    if not wait:
        return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600)


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL")
def test_a_killed_bike_sweep_resumes_to_the_same_table(tmp_path):
    whole = _sweep(tmp_path / "whole")
    assert whole.returncode == 0, whole.stderr
    out = tmp_path / "killed"
    proc = _sweep(out, wait=False)
    journal = out / "journal"
    deadline = time.time() + 300
    while time.time() < deadline:
        if journal.is_dir() and len(list(journal.glob("part-*.json"))) >= 2:
            break
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the sweep ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    parts = len(list(journal.glob("part-*.json")))
    assert 2 <= parts < 6 and not (out / "sweep.csv").exists()
    again = _sweep(out)  # without --resume: refused, nothing touched
    assert again.returncode == 2 and "pass --resume" in again.stderr
    assert len(list(journal.glob("part-*.json"))) == parts
    resumed = _sweep(out, "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert (out / "sweep.csv").read_bytes() == (tmp_path / "whole" / "sweep.csv").read_bytes()
    assert len(list(journal.glob("part-*.json"))) == 6  # only the missing variants ran


# --- issue 49: the journal key covers the content of every file a variant reads -----------------

from pathlib import Path  # noqa: E402

from mtbmj.cli import main  # noqa: E402


def _terrain(path: Path, height_mm: float) -> None:
    """A flat profile with one rectangular step of ``height_mm`` 1.0-1.3 m in (made here)."""
    rows = ["distance_m,height_mm"]
    for i in range(400):
        x = i * 0.01
        rows.append(f"{x:.2f},{height_mm if 1.0 < x < 1.3 else 0.0:.1f}")
    path.write_text("\n".join(rows) + "\n")


def _inputs(folder: Path) -> None:
    """A bike file on a base file on the trail preset, the base naming a leverage CSV, the bike a fork
    configuration file (on the reference preset), and a terrain CSV: every kind of file a variant reads."""
    _terrain(folder / "terrain.csv", 60.0)
    (folder / "lev.csv").write_text("wheel_travel_mm,ratio\n0,2.65\n60,2.43\n120,2.23\n")
    (folder / "base.toml").write_text('base = "trail"\n[leverage]\ncsv = "lev.csv"\n[bike]\nframe_mass_kg = 7.2\n')
    (folder / "fork.toml").write_text('base = "reference"\n[fork.friction]\ncoulomb_N = 20.0\n')
    (folder / "bike.toml").write_text('base = "base.toml"\n[fork]\nconfig = "fork.toml"\n[rider]\ncom_mm = [72.2, 950.6]\n')


SWEEP = ["sweep", "bike.toml", "--roll", "terrain.csv", "--speed", "5", "--duration", "0.5",
         "--vary", "rider.mass_kg=70:90:2", "--quiet"]


def _parts(out: Path) -> int:
    return len(list((out / "journal").glob("part-*.json")))


def test_resume_recomputes_the_variants_whose_input_files_were_edited(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    _inputs(tmp_path)
    out = tmp_path / "out"
    assert main(SWEEP + ["--out", "out"]) == 0
    assert _parts(out) == 2
    first = (out / "sweep.csv").read_bytes()
    # nothing edited (and a file no variant reads touched): every row from the journal
    (tmp_path / "notes.txt").write_text("unrelated\n")
    assert main(SWEEP + ["--out", "out", "--resume"]) == 0
    assert _parts(out) == 2 and (out / "sweep.csv").read_bytes() == first

    edits = {
        "terrain CSV": lambda: _terrain(tmp_path / "terrain.csv", 90.0),
        "bike file": lambda: (tmp_path / "bike.toml").write_text(
            (tmp_path / "bike.toml").read_text().replace("[72.2, 950.6]", "[40.0, 950.6]")),
        "base file": lambda: (tmp_path / "base.toml").write_text(
            (tmp_path / "base.toml").read_text().replace("7.2", "9.5")),
        "leverage CSV": lambda: (tmp_path / "lev.csv").write_text(
            "wheel_travel_mm,ratio\n0,2.9\n60,2.6\n120,2.3\n"),
        "fork configuration": lambda: (tmp_path / "fork.toml").write_text(
            (tmp_path / "fork.toml").read_text().replace("20.0", "120.0")),
    }
    parts = _parts(out)
    previous = first
    for n, (kind, edit) in enumerate(edits.items()):
        edit()
        assert main(SWEEP + ["--out", "out", "--resume"]) == 0, kind
        assert _parts(out) == parts + 2, f"{kind}: the edited input's variants were not computed again"
        parts += 2
        resumed = (out / "sweep.csv").read_bytes()
        assert resumed != previous, f"{kind}: the edit changed no row (the test's edit must matter)"
        # the resumed table is what a fresh sweep on the edited inputs writes
        assert main(SWEEP + ["--out", f"fresh{n}"]) == 0, kind
        assert resumed == (tmp_path / f"fresh{n}" / "sweep.csv").read_bytes(), kind
        previous = resumed
    # and once more without an edit: all from the journal
    assert main(SWEEP + ["--out", "out", "--resume"]) == 0
    assert _parts(out) == parts and (out / "sweep.csv").read_bytes() == previous
    capsys.readouterr()

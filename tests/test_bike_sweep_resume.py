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

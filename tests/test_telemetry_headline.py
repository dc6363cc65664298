"""What a rider reads first from a ride (issue 41 item 1, part): the maximum travel, bottom-outs and
dynamic sag per end (the histogram's mode, 'fork peak 25-30 %', stays in the figure and JSON); the
recorded bike's own fork travel, shock stroke and leverage curve (--bike); a ride too short, or a
sensor missing or stuck, said so. The rides are written here as SST version-2 files (the README's
calibration inverted in tests/test_bounce.py)."""
from __future__ import annotations

import math
import struct

import numpy as np

from mtbmj.cli import main
from helpers import FORK, RATE, SHOCK, counts_of

SECONDS = 40.0


def _ride(path, fork_mm, shock_mm, seconds=SECONDS, shock_absent=False):
    fork = np.clip(np.rint(counts_of(fork_mm, *FORK)), 0, None).astype("<u2")
    shock = (np.full(fork.size, 0xFFFF, dtype="<u2") if shock_absent else
             np.clip(np.rint(counts_of(shock_mm, *SHOCK)), 0, None).astype("<u2"))
    path.write_bytes(struct.pack("<3sBH", b"SST", 2, RATE) + np.column_stack((fork, shock)).astype("<u2").tobytes())
    return path


def _sines(seconds=SECONDS):
    t = np.arange(int(seconds * RATE)) / RATE
    return 50.0 + 40.0 * np.sin(2 * np.pi * 1.3 * t), 20.0 + 15.0 * np.sin(2 * np.pi * 1.1 * t + 0.4)


def test_the_headline_gives_max_travel_bottom_outs_and_dynamic_sag(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    fork, shock = _sines()
    _ride(tmp_path / "ride.SST", fork, shock)
    assert main(["telemetry", "ride.SST", "--out", "tel"]) == 0
    out = capsys.readouterr().out
    # the fork: 90 mm deepest of 180 (50 %), mean 50 mm (28 %): the sine's own numbers
    assert "fork max 50 % (90.0 of 180 mm), 0 bottom-outs, dynamic sag 28 %" in out
    assert "peak " not in out  # the histogram's mode is not the headline


def test_the_recorded_bikes_curve_decodes_the_rear(tmp_path, monkeypatch, capsys):
    """The rear wheel's travel through the --bike's own leverage curve: the trail bike's 50 mm
    stroke is 2.65 -> 2.23 over 120 mm of wheel travel, then its last ratio."""
    monkeypatch.chdir(tmp_path)
    fork, shock = _sines()
    _ride(tmp_path / "ride.SST", fork, shock)
    assert main(["telemetry", "ride.SST", "--bike", "trail", "--out", "tel"]) == 0
    out = capsys.readouterr().out
    w = np.linspace(0.0, 120.0, 5)
    r = np.array([2.65, 2.54, 2.43, 2.33, 2.23])
    # the stroke of the table, piece by piece (ratio linear in w: ds = dw / r(w), integrated exactly)
    pieces = [(w[i + 1] - w[i]) * math.log(r[i] / r[i + 1]) / (r[i] - r[i + 1]) for i in range(4)]
    table_stroke = sum(pieces)
    wheel_at_50 = 120.0 + (50.0 - table_stroke) * 2.23
    assert f"fork max 69 % (90.0 of 130 mm)" in out and f"of {wheel_at_50:.0f} mm" in out


def test_a_short_ride_and_a_missing_or_stuck_sensor_are_said(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    fork, shock = _sines(10.0)
    _ride(tmp_path / "short.SST", fork, shock, seconds=10.0)
    assert main(["telemetry", "short.SST", "--out", "a"]) == 0
    assert "shorter than 30 s" in capsys.readouterr().err
    fork, shock = _sines()
    _ride(tmp_path / "noshock.SST", fork, shock, shock_absent=True)
    assert main(["telemetry", "noshock.SST", "--out", "b"]) == 0
    assert "no shock sensor in this file" in capsys.readouterr().err
    _ride(tmp_path / "stuck.SST", fork, np.full(fork.size, 20.0))
    assert main(["telemetry", "stuck.SST", "--out", "c"]) == 0
    assert "the shock sensor never moved" in capsys.readouterr().err

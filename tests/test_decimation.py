"""A fast record read at the reconstruction's rate (``TelemetryRecord.decimated``): what a
suspension does kept, undelayed; what lies above the new Nyquist frequency removed, not folded
down; a record at that rate or slower left as it is. Checked on signals made here."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.measured.telemetry import TelemetryRecord


def record(rate, seconds=4.0, tone_hz=5.0, hiss_hz=None, steps_mm=None):
    t = np.arange(int(seconds * rate)) / rate
    fork = 40.0 + 20.0 * np.sin(2 * np.pi * tone_hz * t)
    rear = 50.0 + 10.0 * np.sin(2 * np.pi * 2.0 * t + 0.3)
    if hiss_hz is not None:
        fork = fork + 3.0 * np.sin(2 * np.pi * hiss_hz * t)
    if steps_mm is not None:  # a recorder's counts: the travel in steps
        fork, rear = np.round(fork / steps_mm) * steps_mm, np.round(rear / steps_mm) * steps_mm
    return TelemetryRecord("made.SST", 2, float(rate), 0, t, fork, None, rear)


def test_a_5_khz_record_is_read_at_1_khz_undelayed():
    r = record(5000.0, steps_mm=0.2)
    d = r.decimated(1000.0)
    assert d.sample_rate_Hz == 1000.0 and d.time_s.size == r.time_s.size // 5
    assert np.array_equal(d.time_s, r.time_s[::5])
    inner = slice(200, -200)  # the filter's ends
    truth = 40.0 + 20.0 * np.sin(2 * np.pi * 5.0 * d.time_s)
    assert np.max(np.abs(d.fork_mm[inner] - truth[inner])) < 0.2  # within a count step, no lag
    assert d.shock_mm is None and any("every 5th sample" in n for n in d.notes)


def test_what_lies_above_the_new_nyquist_is_removed_not_folded():
    # 2.1 kHz at 5 kHz: kept every 5th sample it would fold to 100 Hz; low-passed first it is gone
    r = record(5000.0, hiss_hz=2100.0)
    d = r.decimated(1000.0)
    inner = slice(200, -200)
    truth = 40.0 + 20.0 * np.sin(2 * np.pi * 5.0 * d.time_s)
    assert np.max(np.abs(d.fork_mm[inner] - truth[inner])) < 0.05
    naive = r.fork_mm[::5]  # the deliberately wrong reading: folded
    assert np.max(np.abs(naive[inner] - truth[inner])) > 1.0


@pytest.mark.parametrize("rate", [1000.0, 500.0])
def test_a_record_at_the_rate_or_slower_is_left_as_it_is(rate):
    r = record(rate)
    assert r.decimated(1000.0) is r

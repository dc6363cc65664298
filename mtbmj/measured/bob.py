"""Pedal bob: how often and how far a pedalling bike's suspension moves with the pedal strokes, read
the same way from a recorded ride and from a simulated one (``mtbmj bike ... --pedal RPM --ride
SST`` writes both side by side).

A rider's legs push twice a crank turn, so pedalling moves the suspension at twice the cadence.
``bob`` takes one end's travel over the pedalling stretch:

* the stretch: ``start_s``-``end_s`` when given; else from 2 s after the end first carries the rider
  (travel above 2 mm: sag) to 2 s before it last does, which leaves out getting on and off;
* the slow part (the rider's weight shifts, the gradient) is taken out by a zero-phase high-pass
  (Butterworth, 2nd order, 0.7 Hz, run forward and back);
* the frequency is the peak of its power spectrum (Welch, 4 s segments, padded to 0.01 Hz) within
  1-5 Hz (cadences of 30-150 rpm), refined by a parabola through the peak's three bins;
* the amplitude is the median over the stretch's cycles of each cycle's peak to peak (the
  high-passed travel, low-passed at four times that frequency to leave the sensor's noise out, its
  maximum less its minimum between successive upward crossings of zero by the travel band-passed
  at 0.6-1.6 times that frequency), in mm: what a rider sees as the bob of each stroke.

Recorded amplitudes carry the record's own calibration (a version-2 SST file's are approximate; its
frequencies are exact). The figure (``figure``) shows each end's bob beside the record's.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from mtbmj.errors import MtbmjError

BAND_HZ = (1.0, 5.0)
HIGH_PASS_HZ = 0.7
ON_BIKE_MM = 2.0
TRIM_S = 2.0
MIN_STRETCH_S = 4.0
# The band-pass reaches 1.6 times the bob's frequency, up to 5 Hz: 8 Hz, which a record must
# sample at more than twice (its Nyquist frequency) with room for the filter: 20 Hz at least.
MIN_RATE_HZ = 20.0


class BobError(MtbmjError):
    """A travel record that holds no pedalling stretch long enough to read a bob from."""


@dataclass(frozen=True)
class Bob:
    frequency_Hz: float
    amplitude_mm: float  # median peak to peak per cycle
    amplitude_iqr_mm: tuple  # its interquartile range over the cycles
    cycles: int
    mean_mm: float  # the travel's mean over the stretch (sag while pedalling)
    window_s: tuple

    @property
    def cadence_rpm(self) -> float:
        """The cadence the bob implies: two strokes a turn."""
        return self.frequency_Hz / 2.0 * 60.0

    def to_dict(self) -> dict:
        out = asdict(self)
        out["amplitude_iqr_mm"] = list(self.amplitude_iqr_mm)
        out["window_s"] = list(self.window_s)
        out["cadence_rpm"] = self.cadence_rpm
        return out


def stretch(time_s, travel_mm) -> tuple[float, float]:
    """The pedalling stretch of a record: 2 s after the end first carries the rider (travel above
    2 mm) to 2 s before it last does."""
    t = np.asarray(time_s, float)
    on = np.flatnonzero(np.asarray(travel_mm, float) > ON_BIKE_MM)
    if on.size == 0:
        raise BobError("bob: the travel never rises above 2 mm: nobody rode it")
    return float(t[on[0]] + TRIM_S), float(t[on[-1]] - TRIM_S)


def bob(time_s, travel_mm, start_s: float | None = None, end_s: float | None = None) -> Bob:
    """The pedal bob of one end's travel (see the module doc)."""
    from scipy import signal

    t = np.asarray(time_s, float)
    x = np.asarray(travel_mm, float)
    if t.size < 2 or t.size != x.size:
        raise BobError("bob: time and travel must be two series of the same length")
    auto = stretch(t, x) if start_s is None or end_s is None else (start_s, end_s)
    start = auto[0] if start_s is None else float(start_s)
    end = auto[1] if end_s is None else float(end_s)
    if end - start < MIN_STRETCH_S - 0.01:  # (a run's last sample lies a step before its end)
        found = (f" ({TRIM_S:g} s after the travel first rises above {ON_BIKE_MM:g} mm, at {start - TRIM_S:.1f} s, to "
                 f"{TRIM_S:g} s before it last does, at {end + TRIM_S:.1f} s)") if start_s is None and end_s is None else ""
        span = f"{start:.1f}-{end:.1f} s" if end > start else "empty"
        raise BobError(f"bob: the pedalling stretch{found} is {span}: shorter than {MIN_STRETCH_S:g} s")
    t, x, y, fs = _high_passed(t, x, (start, end))
    f, p = _power_spectrum(y, fs)
    band = np.flatnonzero((f >= BAND_HZ[0]) & (f <= BAND_HZ[1]))
    i = int(band[np.argmax(p[band])])
    peak = float(f[i])
    if 0 < i < f.size - 1:
        a, b, c = np.log(p[i - 1:i + 2] + 1e-300)
        den = a - 2 * b + c
        if den < 0:
            peak += 0.5 * (a - c) / den * (f[1] - f[0])
    sos = signal.butter(2, [0.6 * peak, min(1.6 * peak, 0.45 * fs)], btype="bandpass", fs=fs, output="sos")
    z = signal.sosfiltfilt(sos, y)
    up = np.flatnonzero((z[:-1] < 0.0) & (z[1:] >= 0.0))
    if 4.0 * peak < 0.45 * fs:  # the sensor's noise out, the stroke's shape (its first harmonics) kept
        y = signal.sosfiltfilt(signal.butter(2, 4.0 * peak, btype="lowpass", fs=fs, output="sos"), y)
    swings = np.array([np.ptp(y[a:b + 1]) for a, b in zip(up[:-1], up[1:])])
    if swings.size < 3:
        raise BobError(f"bob: fewer than 3 pedal strokes in {start:.1f}-{end:.1f} s")
    q1, med, q3 = np.percentile(swings, [25, 50, 75])
    return Bob(peak, float(med), (float(q1), float(q3)), int(swings.size), float(x.mean()), (start, end))


def _high_passed(t, x, window_s):
    """(t, x, y, fs) over the stretch ``window_s``: its times and travel, the travel less its mean
    high-passed (zero phase, ``HIGH_PASS_HZ``), the sample rate."""
    from scipy import signal

    keep = (t >= window_s[0]) & (t <= window_s[1])
    t, x = t[keep], x[keep]
    if t.size < 2:
        raise BobError(f"bob: no samples in the stretch {window_s[0]:.1f}-{window_s[1]:.1f} s")
    fs = 1.0 / float(np.median(np.diff(t)))
    if not (np.isfinite(fs) and fs >= MIN_RATE_HZ):
        raise BobError(f"bob: a sample rate of {fs:g} Hz is too slow to read a bob of up to {BAND_HZ[1]:g} Hz "
                       f"({MIN_RATE_HZ:g} Hz at least)")
    y = signal.sosfiltfilt(signal.butter(2, HIGH_PASS_HZ, btype="highpass", fs=fs, output="sos"), x - x.mean())
    return t, x, y, fs


def _power_spectrum(y, fs):
    """(frequency Hz, power density) of ``y``: Welch, 4 s segments, padded to 0.01 Hz."""
    from scipy import signal

    seg = min(y.size, int(round(4.0 * fs)))
    return signal.welch(y, fs=fs, nperseg=seg, nfft=max(seg, int(2 ** np.ceil(np.log2(fs / 0.01)))))


def high_passed(time_s, travel_mm, window_s) -> tuple[np.ndarray, np.ndarray]:
    """(time from the stretch's start s, travel high-passed mm) over ``window_s``, as ``bob`` reads
    it: what the figures draw."""
    t, _, y, _ = _high_passed(np.asarray(time_s, float), np.asarray(travel_mm, float), window_s)
    return t - t[0], y


def spectrum(time_s, travel_mm, window_s) -> tuple[np.ndarray, np.ndarray]:
    """(frequency Hz, amplitude spectral density mm/sqrt(Hz)) of the high-passed travel over the
    stretch, as ``bob`` reads it."""
    _, _, y, fs = _high_passed(np.asarray(time_s, float), np.asarray(travel_mm, float), window_s)
    f, p = _power_spectrum(y, fs)
    return f, np.sqrt(p)


def run_stretch(time_s) -> tuple[float, float]:
    """A pedalling run's stretch: its second half, from 2 s on at the earliest (the start's speed
    settles first: the rider's power against the climb)."""
    end = float(np.asarray(time_s)[-1])
    return max(TRIM_S, 0.5 * end), end


__all__ = ["Bob", "BobError", "bob", "stretch", "run_stretch", "high_passed", "spectrum"]

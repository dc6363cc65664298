"""Finding the extremes of a noisy record, the tools the event detector (``events``), the time-zero
search (``validation.time_zero``) and the fits' noise floors share: the sensor noise level
(``noise_sigma``), cubic Savitzky-Golay smoothing (``smooth``), scipy's peak finder
(``find_peaks``) and the least-squares parabola through an extreme (``parabola``).

The drop path does not import ``scipy.signal`` (about half a second of start-up): the smoothing
and the peak finder are written out here and tested against scipy's on generated inputs
(``tests/test_validation.py``).
"""
from __future__ import annotations

import numpy as np


def noise_sigma(y: np.ndarray) -> float:
    """Standard deviation of white sensor noise, from the third differences (robust: median
    absolute deviation), which the smooth motion hardly contributes to at 1 kHz."""
    y = np.asarray(y, float)
    if y.size < 8:
        return 0.0
    d3 = np.diff(y, 3)
    return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0))  # var(d3) = 20 var(noise)


_SAVGOL: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def savgol_operator(width: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """scipy's cubic Savitzky-Golay filter of ``width`` samples in its "interp" mode, as linear
    operators (cached per width): the convolution kernel for the interior and,
    for each end, the matrix that evaluates the cubic fitted to the first (last) ``width`` samples
    at the first (last) ``width // 2`` of them. The same filter as ``savgol_filter(y, width, 3,
    mode="interp")`` without its per-call fits of the ends (half the cost of a drop's events)."""
    if width not in _SAVGOL:
        half = width // 2
        x = np.arange(width, dtype=float) - half
        vander = np.vander(x / half, 4)
        project = vander @ np.linalg.pinv(vander)  # least-squares cubic through the window, evaluated on it
        # its middle row weighs the window for the middle sample (flipped for np.convolve)
        _SAVGOL[width] = (project[half][::-1].copy(), project[:half].copy(), project[width - half:].copy())
    return _SAVGOL[width]


def smooth(y: np.ndarray, dt: float, window_s: float) -> np.ndarray:
    """``y`` (samples ``dt`` apart) through the cubic Savitzky-Golay filter of ``window_s`` (an odd
    number of samples, at least 5): ``savgol_filter(y, width, 3, mode="interp")``; a signal no
    longer than the window is returned as it is."""
    width = max(5, int(round(window_s / dt)) | 1)
    y = np.asarray(y, float)
    if y.size <= width:
        return y
    kernel, head, tail = savgol_operator(width)
    half = width // 2
    out = np.empty_like(y)
    out[half:y.size - half] = np.convolve(y, kernel, mode="valid")
    out[:half] = head @ y[:width]
    out[y.size - half:] = tail @ y[y.size - width:]
    return out


DIRECT_SCAN_LIMIT = 2_000_000  # peaks x samples up to which find_peaks scans per peak


def find_peaks(x: np.ndarray, prominence: float) -> np.ndarray:
    """Indices of the peaks of ``x`` with at least ``prominence``, as
    ``scipy.signal.find_peaks(x, prominence=prominence)[0]`` finds them (a flat peak at the
    middle of its plateau, rounded down; the prominence against the higher of the lowest points
    on either side before the signal rises above the peak), without importing ``scipy.signal``
    (about half a second of every drop's start)."""
    x = np.asarray(x, dtype=float)
    if x.size < 3:
        return np.zeros(0, dtype=np.intp)
    # candidate peaks: a rise, then a run of equal values (possibly none), then a fall
    change = np.flatnonzero(np.diff(x) != 0.0)  # i: x[i + 1] differs from x[i]
    if change.size < 2:
        return np.zeros(0, dtype=np.intp)
    rises = x[change + 1] > x[change]
    at = np.flatnonzero(rises[:-1] & ~rises[1:])  # a rise into change[j] + 1, a fall after change[j + 1]
    left, right = change[at] + 1, change[at + 1]
    peaks = (left + right) // 2
    if peaks.size == 0:
        return peaks.astype(np.intp)
    if peaks.size * x.size <= DIRECT_SCAN_LIMIT:
        lows = np.empty(peaks.size)
        for n, i in enumerate(peaks):  # few peaks: one vectorised scan each way per peak
            above = np.flatnonzero(x[:i] > x[i])
            lo = above[-1] + 1 if above.size else 0
            above = np.flatnonzero(x[i + 1:] > x[i])
            hi = i + above[0] if above.size else x.size - 1
            lows[n] = max(x[lo:i + 1].min(), x[i:hi + 1].min())
        return peaks[x[peaks] - lows >= prominence].astype(np.intp)
    # many peaks on a long record: each peak's reach by binary lifting on a table of window
    # maxima, and the lowest point within from a table of window minima
    highs, mins = [x], [x]
    while 2 * (1 << (len(highs) - 1)) <= x.size:
        half = 1 << (len(highs) - 1)
        highs.append(np.maximum(highs[-1][:-half], highs[-1][half:]))
        mins.append(np.minimum(mins[-1][:-half], mins[-1][half:]))
    height = x[peaks]
    lo, hi = peaks.copy(), peaks.copy()
    for k in range(len(highs) - 1, -1, -1):
        width = 1 << k
        can = lo - width >= 0
        step = np.where(can, highs[k][np.where(can, lo - width, 0)] <= height, False)
        lo = np.where(step, lo - width, lo)
        can = hi + width <= x.size - 1
        step = np.where(can, highs[k][np.where(can, hi + 1, 0)] <= height, False)
        hi = np.where(step, hi + width, hi)

    def lowest(a, b):  # min of x[a..b] per peak
        k = np.floor(np.log2(b - a + 1)).astype(int)
        return np.array([min(mins[kk][aa], mins[kk][bb - (1 << kk) + 1]) for aa, bb, kk in zip(a, b, k)])

    prominences = height - np.maximum(lowest(lo, peaks), lowest(peaks, hi))
    return peaks[prominences >= prominence].astype(np.intp)


def parabola(tt: np.ndarray, yy: np.ndarray) -> tuple[float, float, float]:
    """Least-squares a t^2 + b t + c through (tt, yy), by the normal equations on t scaled to
    [-1, 1], solved by Cramer's rule (the same fit as ``np.polyfit(tt, yy, 2)``, without its SVD
    or a general solver: a drop's events make 14 such fits)."""
    scale = float(max(abs(tt[0]), abs(tt[-1]))) or 1.0
    u = tt / scale
    u2 = u * u
    s0, s1, s2, s3, s4 = float(u.size), float(u.sum()), float(u2.sum()), float(u2 @ u), float(u2 @ u2)
    t0, t1, t2 = float(yy.sum()), float(u @ yy), float(u2 @ yy)
    # | s4 s3 s2 | |a|   |t2|
    # | s3 s2 s1 | |b| = |t1|
    # | s2 s1 s0 | |c|   |t0|
    det = s4 * (s2 * s0 - s1 * s1) - s3 * (s3 * s0 - s1 * s2) + s2 * (s3 * s1 - s2 * s2)
    a = (t2 * (s2 * s0 - s1 * s1) - s3 * (t1 * s0 - s1 * t0) + s2 * (t1 * s1 - s2 * t0)) / det
    b = (s4 * (t1 * s0 - s1 * t0) - t2 * (s3 * s0 - s1 * s2) + s2 * (s3 * t0 - t1 * s2)) / det
    c = (s4 * (s2 * t0 - t1 * s1) - s3 * (s3 * t0 - t1 * s2) + t2 * (s3 * s1 - s2 * s2)) / det
    return a / scale ** 2, b / scale, c


__all__ = ["noise_sigma", "savgol_operator", "smooth", "find_peaks", "parabola", "DIRECT_SCAN_LIMIT"]

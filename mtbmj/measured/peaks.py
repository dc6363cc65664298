"""Finding the extremes of a noisy record, the tools the event detector (``events``), the time-zero
search (``validation.time_zero``) and the fits' noise floors share: the sensor noise level
(``noise_sigma``; ``noise_sigmas`` of several signals at once), cubic Savitzky-Golay smoothing
(``smooth``), scipy's peak finder (``find_peaks``; ``peaks_and_valleys`` of a signal and of its
negative at once) and the least-squares parabola through an extreme (``parabola``).

They run once per simulated drop, in sweeps of thousands: each stands in for a few whole-array
numpy calls rather than for loops over samples or peaks, and gives exactly (bitwise) the values of
the direct formulation it replaces (the medians of ``np.median``, the sums and BLAS dot products
of ``parabola``'s normal equations).

The drop path does not import ``scipy.signal`` (about half a second of start-up): the smoothing
and the peak finder are written out here and tested against scipy's on generated inputs
(``tests/test_validation.py``).
"""
from __future__ import annotations

import math

import numpy as np


def median_in_place(a: np.ndarray):
    """``np.median`` along the last axis of a float array without NaN, which it reorders (the
    same values: the mean of the middle two of an even count), from one partition in place:
    ``np.median``'s dispatch and reductions cost more than the partition on a drop's two
    thousand samples."""
    k = a.shape[-1] // 2
    a.partition(k, axis=-1)
    if a.shape[-1] % 2:
        return a[..., k].copy()
    return (a[..., :k].max(axis=-1) + a[..., k]) / 2.0


def noise_sigma(y: np.ndarray) -> float:
    """Standard deviation of white sensor noise, from the third differences (robust: median
    absolute deviation), which the smooth motion hardly contributes to at 1 kHz."""
    y = np.asarray(y, float)
    if y.size < 8:
        return 0.0
    if y.ndim != 1:  # the median over all rows' differences
        d3 = np.diff(y, 3)
        return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0))  # var(d3) = 20 var(noise)
    return noise_sigmas(y[None, :])[0]


def noise_sigmas(rows: np.ndarray) -> list[float]:
    """``noise_sigma`` of each row of a 2-d float array (rows of at least 8 samples), all rows at
    once: the event detector takes the sled, the fork and the tire together."""
    d = rows[:, 1:] - rows[:, :-1]  # np.diff(rows, 3), one difference at a time as np.diff takes them
    d = d[:, 1:] - d[:, :-1]
    d3 = d[:, 1:] - d[:, :-1]
    if not math.isfinite(d3.sum()):  # NaN or infinite differences: as np.median takes them
        return [float(1.4826 * np.median(np.abs(row - np.median(row))) / np.sqrt(20.0)) for row in d3]
    center = median_in_place(d3)  # reorders each row: the deviations' median does not depend on their order
    np.subtract(d3, center[:, None], out=d3)
    np.abs(d3, out=d3)
    return (1.4826 * median_in_place(d3) / np.sqrt(20.0)).tolist()  # var(d3) = 20 var(noise)


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
    width = smooth_width(dt, window_s)
    y = np.asarray(y, float)
    if y.size <= width:
        return y
    return smooth_into(y, width, np.empty_like(y))


def smooth_width(dt: float, window_s: float) -> int:
    """The Savitzky-Golay window of ``smooth``, in samples."""
    return max(5, int(round(window_s / dt)) | 1)


def smooth_into(y: np.ndarray, width: int, out: np.ndarray) -> np.ndarray:
    """``smooth`` of the 1-d float array ``y`` with a window of ``width`` samples, written to
    ``out`` (a copy of ``y`` if it is no longer than the window)."""
    if y.size <= width:
        out[:] = y
        return out
    kernel, head, tail = savgol_operator(width)
    half = width // 2
    out[half:y.size - half] = np.convolve(y, kernel, mode="valid")
    out[:half] = head @ y[:width]
    out[y.size - half:] = tail @ y[y.size - width:]
    return out


DIRECT_SCAN_LIMIT = 64  # candidate peaks up to which find_peaks walks them in Python (a stack)


def find_peaks(x: np.ndarray, prominence: float) -> np.ndarray:
    """Indices of the peaks of ``x`` with at least ``prominence``, as
    ``scipy.signal.find_peaks(x, prominence=prominence)[0]`` finds them (a flat peak at the
    middle of its plateau, rounded down; the prominence against the higher of the lowest points
    on either side before the signal rises above the peak), without importing ``scipy.signal``
    (about half a second of every drop's start).

    The lowest point on either side is found from the candidate peaks alone: the signal first
    rises above a peak on the slope of the nearest higher candidate peak (or not at all), so the
    lowest point before it is the lowest of the valleys between the two (or the record's end).
    Each peak's nearest higher ones come from a stack walk over the candidates, or, beyond
    ``DIRECT_SCAN_LIMIT`` candidates, from vectorised pointer jumping. A record holding NaN or
    infinite values is scanned per peak (``_find_peaks_nonfinite``)."""
    return peaks_and_valleys(x, prominence, valleys=False)[0]


def peaks_and_valleys(x: np.ndarray, prominence: float,
                      valleys: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """``(find_peaks(x, prominence), find_peaks(-x, prominence))`` (the second None without
    ``valleys``), sharing the search for the candidates: the event detector takes both of the sled."""
    x = np.asarray(x, dtype=float)
    none = np.zeros(0, dtype=np.intp)
    if x.size < 3:
        return none, none.copy() if valleys else None
    step = x[1:] - x[:-1]
    if not math.isfinite(step.sum()):  # NaN or infinite values (or steps beyond the float range)
        return _find_peaks_nonfinite(x, prominence), _find_peaks_nonfinite(-x, prominence) if valleys else None
    # candidate peaks: a rise, then a run of equal values (possibly none), then a fall; candidate
    # valleys (the peaks of -x): a fall, a run, a rise
    rises = step > 0.0
    if (step == 0.0).any():  # runs of equal values: where the signal turns, from its changes alone
        change = (step != 0.0).nonzero()[0]  # i: x[i + 1] differs from x[i]
        if change.size < 2:
            return none, none.copy() if valleys else None
        rising = rises[change]
        turn = (rising[:-1] != rising[1:]).nonzero()[0]  # into change[j] + 1, out after change[j + 1]
        middle = (change[turn] + 1 + change[turn + 1]) // 2
    else:
        rising = rises
        turn = (rises[:-1] != rises[1:]).nonzero()[0]  # into sample j + 1 and out of it
        middle = turn + 1
    up = rising[turn]
    found = _prominent(x, middle[up], prominence)
    return found, _prominent(-x, middle[~up], prominence) if valleys else None


def _prominent(x: np.ndarray, peaks: np.ndarray, prominence: float) -> np.ndarray:
    """The ``peaks`` (candidate peaks of the finite ``x``, ascending) with at least ``prominence``."""
    if peaks.size == 0:
        return peaks.astype(np.intp)
    heights = x[peaks]
    edge = x[:peaks[0]].min()  # lowest before the first peak
    between = np.minimum.reduceat(x, peaks)  # [k]: lowest from peak k to peak k + 1 (or the end)
    if peaks.size <= DIRECT_SCAN_LIMIT:
        h, v = heights.tolist(), [edge] + between.tolist()  # v[k]: lowest between peak k - 1 (or the start) and peak k
        left, right = _reach_low_walk(h, v), _reach_low_walk(h[::-1], v[::-1])[::-1]
        keep = [p for p, top, a, b in zip(peaks.tolist(), h, left, right) if top - max(a, b) >= prominence]
        return np.array(keep, dtype=np.intp)
    v = np.concatenate(([edge], between))
    lows = np.maximum(_reach_low_jump(heights, v), _reach_low_jump(heights[::-1], v[::-1])[::-1])
    return peaks[heights - lows >= prominence].astype(np.intp)


def _reach_low_walk(h: list, v: list) -> list:
    """For each peak (heights ``h``; ``v[k]`` the lowest point between peak k - 1, or the start,
    and peak k), the lowest point between it and the nearest strictly higher peak before it (or
    the start): one pass with a stack of the peaks not yet overtopped."""
    low: list = []
    stack: list = []
    for j, height in enumerate(h):
        m = v[j]
        while stack and h[stack[-1]] <= height:
            k = stack.pop()
            if low[k] < m:
                m = low[k]
        low.append(m)
        stack.append(j)
    return low


def _reach_low_jump(h: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``_reach_low_walk`` vectorised, by pointer jumping: each peak points at an earlier one and
    holds the lowest point back to it; while the one pointed at is no higher, it takes over that
    one's pointer and low (all peaks at once, from the values before the round)."""
    n = h.size
    height = np.empty(n + 1)
    height[0] = np.inf  # node 0: the start, higher than any (finite) peak; node j + 1: peak j
    height[1:] = h
    to = np.arange(-1, n)
    low = np.empty(n + 1)
    low[0] = np.inf
    low[1:] = v[:n]
    todo = 1 + np.flatnonzero(height[to[1:]] <= h)
    while todo.size:
        back = to[todo]
        low[todo] = np.minimum(low[todo], low[back])
        to[todo] = to[back]
        todo = todo[height[to[todo]] <= height[todo]]
    return low[1:]


NONFINITE_SCAN_LIMIT = 2_000_000  # peaks x samples up to which _find_peaks_nonfinite scans per peak


def _find_peaks_nonfinite(x: np.ndarray, prominence: float) -> np.ndarray:
    """``find_peaks`` of a record holding NaN or infinite values, which the walk over the candidate
    peaks cannot order: found as before that walk, by scipy's scans each way per peak (beyond
    ``NONFINITE_SCAN_LIMIT`` peaks x samples, by binary lifting on tables of window extremes; with
    NaN the two need not agree)."""
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
    if peaks.size * x.size <= NONFINITE_SCAN_LIMIT:
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
    if (type(tt) is np.ndarray and tt.dtype == np.float64 and tt.ndim == 1 and type(yy) is np.ndarray
            and yy.dtype == np.float64 and yy.shape == tt.shape and yy.flags.c_contiguous):
        return parabola_rows(tt, yy)
    scale = float(max(abs(tt[0]), abs(tt[-1]))) or 1.0
    u = tt / scale
    u2 = u * u
    s1, s2, s3, s4 = float(u.sum()), float(u2.sum()), float(u2 @ u), float(u2 @ u2)
    t0, t1, t2 = float(yy.sum()), float(u @ yy), float(u2 @ yy)
    return _cramer(float(u.size), s1, s2, s3, s4, t0, t1, t2, scale)


def parabola_rows(tt: np.ndarray, yy: np.ndarray) -> tuple[float, float, float]:
    """``parabola`` of a float vector ``tt`` and a contiguous float vector ``yy`` as long: the
    same sums (pairwise, row by row: the rows u, u^2 and yy summed in one call) and the same BLAS
    dot products (the ``dot`` of two contiguous float vectors is their matrix product's)."""
    scale = float(max(abs(tt[0]), abs(tt[-1]))) or 1.0
    rows = np.empty((3, tt.size))
    u, u2 = rows[0], rows[1]
    np.divide(tt, scale, out=u)
    np.multiply(u, u, out=u2)
    rows[2] = yy
    s1, s2, t0 = np.add.reduce(rows, 1).tolist()
    return _cramer(float(tt.size), s1, s2, float(u2.dot(u)), float(u2.dot(u2)), t0, float(u.dot(yy)),
                   float(u2.dot(yy)), scale)


def _cramer(s0, s1, s2, s3, s4, t0, t1, t2, scale) -> tuple[float, float, float]:
    """The parabola's coefficients from the sums of u^k (s) and of u^k y (t), u = t / scale."""
    # | s4 s3 s2 | |a|   |t2|
    # | s3 s2 s1 | |b| = |t1|
    # | s2 s1 s0 | |c|   |t0|
    det = s4 * (s2 * s0 - s1 * s1) - s3 * (s3 * s0 - s1 * s2) + s2 * (s3 * s1 - s2 * s2)
    a = (t2 * (s2 * s0 - s1 * s1) - s3 * (t1 * s0 - s1 * t0) + s2 * (t1 * s1 - s2 * t0)) / det
    b = (s4 * (t1 * s0 - s1 * t0) - t2 * (s3 * s0 - s1 * s2) + s2 * (s3 * t0 - t1 * s2)) / det
    c = (s4 * (s2 * t0 - t1 * s1) - s3 * (s3 * t0 - t1 * s2) + t2 * (s3 * s1 - s2 * s2)) / det
    return a / scale ** 2, b / scale, c


__all__ = ["median_in_place", "noise_sigma", "noise_sigmas", "parabola_rows", "savgol_operator", "smooth", "smooth_width", "smooth_into", "find_peaks",
           "peaks_and_valleys", "parabola", "DIRECT_SCAN_LIMIT"]

"""What the fork's record holds about the rear (``Reconstruction.checks()``'s ``bound_fork_filter_*``,
issue 51): the rear's RMS error of the best linear filter from the fork's record to the rear's, fitted
on the rear's record itself and tested where it was not fitted. Reported beside the naive baselines,
never part of the pass. It bounds what a linear reading of the fork's record (these taps) can do; the
whole bike is not linear (flights, stops, the tyres leaving the ground), so a bound above the pass
mark alone does not say the model cannot pass (the tests' made ride: the filter 4.8 mm, the mark 4.1, the model
3.6). With the rear moving with the fork at once (a load on both ends, which the front's record alone
cannot tell from terrain) it says why the rides' rear cannot be checked from their front.

The filter (:func:`fork_filter_bound`): the rear at t from the fork's record low-passed at
``LOWPASS_HZ`` (a 4th-order Butterworth run forward and back) read by taps every ``TAP_S`` in two
families, ``AT_ONCE_REACH_S`` either side of the fork's moment and ``AT_LAG_REACH_S`` either side of
the wheelbase lag behind it (wheelbase / speed(t), following the speed), plus a constant: a two-sided
FIR that follows the speed. Cross-validated: the samples checked, in their order, cut into blocks of
``BLOCK_S`` seconds of them, every other block one fold; the filter fitted on every ``TAP_S``-th
sample of one fold and tested on every sample of the other at the record's rate, both ways; the
bound is the RMS over both tests' samples, each fold's error less its mean (the constant, like the
baselines' offset, set on the samples judged: a ride's rear level drifts between its parts). The
fit: ridge least squares, the weight one of ``RIDGES`` times the taps' mean power (the constant
free), or no filter at all (the constant alone), whichever fitted on either half in time of the fold
best predicts the other. The fork's record past its ends is held at its end values. numpy and scipy
only: 0.03-0.3 s for a 100 s ride at 1 kHz.

Folds in halves of the ride instead (the first half against the second) let a filter fitted on one
part of a ride extrapolate on the other: on the shared 00094 the second half was left at 89 mm RMS,
4.5 times the rear's spread.
"""
from __future__ import annotations

import numpy as np

TAP_S = 0.01  # s between the filter's taps
LOWPASS_HZ = 30.0  # the fork's record low-passed here before the taps read it (below their 50 Hz)
AT_ONCE_REACH_S = 0.5  # the taps about the fork's moment reach this far either side of it
AT_LAG_REACH_S = 0.1  # the taps about the wheelbase lag reach this far either side of it
BLOCK_S = 5.0  # s of samples checked per block of a fold (every other block one fold)
RIDGES = (1e-4, 1e-3, 1e-2, 1e-1, 1.0)  # the ridge's weights tried, times the taps' mean power


def _read(smooth, pos) -> np.ndarray:
    """``smooth`` read at the fractional sample positions ``pos`` (linear between samples, held past
    its ends)."""
    pos = np.clip(pos, 0.0, smooth.size - 1.0)
    i = np.minimum(pos.astype(np.intp), smooth.size - 2)
    w = pos - i
    return (1.0 - w) * smooth[i] + w * smooth[i + 1]


def _columns(smooth, at, families):
    """Per tap, the fork's record read at the samples ``at`` less the tap's family's delay (samples,
    per sample of the record; None: none) and the tap's offset."""
    for delay, offsets in families:
        base = at if delay is None else at - delay[at]
        for o in offsets:
            yield _read(smooth, base - o)


def _moments(X, y) -> tuple:
    """(centred Gram, centred X'y, column means, mean of y) of the rows ``X``, ``y``."""
    mx, my = X.mean(axis=0), float(y.mean())
    Xc = X - mx
    return Xc.T @ Xc, Xc.T @ (y - my), mx, my


def _fit(smooth, rear, rows, families) -> tuple:
    """(filter, constant, ridge weight or None for no filter): the ridge least squares of the rear at
    the samples ``rows`` on the fork's record read by the taps (the ridge the weight times the taps'
    mean power, the constant free), the weight that of ``RIDGES`` (or no filter) whose fit on either
    half of ``rows`` in time best predicts the other (one eigendecomposition per half for all)."""
    X = np.column_stack(list(_columns(smooth, rows, families)))
    y = rear[rows]
    later = np.arange(rows.size) >= rows.size // 2
    parts = [(X[q], y[q], _moments(X[q], y[q])) for q in (~later, later)]
    choices = list(RIDGES) + [None]
    scores = np.zeros(len(choices))
    for i, (_, _, (G, c, mx, my)) in enumerate(parts):
        Xo, yo, _ = parts[1 - i]
        s, V = np.linalg.eigh(G)
        proj = V.T @ c
        for j, weight in enumerate(choices):
            h = np.zeros(c.size) if weight is None else V @ (proj / (s + weight * float(np.trace(G)) / G.shape[0] + 1e-12))
            scores[j] += float(np.sum((Xo @ h + (my - float(mx @ h)) - yo) ** 2))
    weight = choices[int(np.argmin(scores))]
    G, c, mx, my = _moments(X, y)
    if weight is None:
        return np.zeros(c.size), my, None
    G[np.diag_indices_from(G)] += weight * float(np.trace(G)) / G.shape[0] + 1e-12
    h = np.linalg.solve(G, c)
    return h, my - float(mx @ h), weight


def _apply(smooth, h, b, at, families) -> np.ndarray:
    """The filter at the samples ``at``: each family of taps a convolution of the record (held at its
    ends) read at ``at`` less the family's delay (reading between samples is linear, so it commutes
    with whole-sample shifts: the same as the taps read one by one)."""
    from scipy.signal import oaconvolve

    out = np.full(at.size, b)
    used = 0
    for delay, offsets in families:
        reach = int(max(abs(offsets[0]), abs(offsets[-1])))
        kernel = np.zeros(2 * reach + 1)
        kernel[(offsets + reach).astype(np.intp)] = h[used:used + offsets.size]
        used += offsets.size
        g = oaconvolve(np.pad(smooth, reach, mode="edge"), kernel, mode="valid")  # g[i] = sum_k h_k smooth[i - o_k]
        out += g[at] if delay is None else _read(g, at - delay[at])
    return out


def fork_filter_bound(t, fork, rear, valid, lags=None) -> dict | None:
    """The bound (see the module doc) on the samples ``valid``: ``fork`` and ``rear`` the ends'
    records (mm on ``t``), ``lags`` the rear's lag behind the front (s on ``t``; None: the taps about
    the fork's moment alone). {"rms_mm" (the bound), "folds_rms_mm" (each fold's test), "reach_s"
    (the taps' reach either side of the fork's moment and of the wheelbase lag), "taps", "lowpass_Hz",
    "ridge_weights" (each fold's; None: no filter, the constant alone), "block_s", "fitted_on"}; None
    where half of either fold has no more samples fitted on than the filter has taps."""
    from scipy.signal import butter, sosfiltfilt

    t = np.asarray(t, float)
    fork, rear = np.asarray(fork, float), np.asarray(rear, float)
    valid = np.asarray(valid, bool) & np.isfinite(rear)
    dt = float(t[1] - t[0])
    step = max(int(round(TAP_S / dt)), 1)

    def offsets(reach_s):
        reach = int(round(reach_s / dt))
        return np.arange(-reach, reach + 1, step).astype(float)  # samples either side of the moment

    families = [(None, offsets(AT_ONCE_REACH_S))]
    if lags is not None:
        delay = np.asarray(lags, float) / dt
        valid &= np.isfinite(delay)
        families.append((delay, offsets(AT_LAG_REACH_S)))
    cut = min(LOWPASS_HZ, 0.3 / dt)
    smooth = sosfiltfilt(butter(4, cut, fs=1.0 / dt, output="sos"), fork) if fork.size > 30 else fork.copy()
    idx = np.flatnonzero(valid)
    taps = sum(o.size for _, o in families)
    block = np.arange(idx.size) // max(int(round(BLOCK_S / dt)), 1)
    folds = (idx[block % 2 == 0], idx[block % 2 == 1])
    if min(f[::step].size for f in folds) <= 2 * taps:  # each half of a fold has more rows than taps
        return None
    errors, each, weights = [], [], []
    for fit_on, test_on in ((folds[0], folds[1]), (folds[1], folds[0])):
        h, b, weight = _fit(smooth, rear, fit_on[::step], families)
        e = _apply(smooth, h, b, test_on, families) - rear[test_on]
        e -= e.mean()
        errors.append(e)
        each.append(float(np.sqrt(np.mean(e * e))))
        weights.append(weight)
    pooled = np.concatenate(errors)
    return {"rms_mm": float(np.sqrt(np.mean(pooled * pooled))), "folds_rms_mm": each,
            "reach_s": {"about_the_fork_moment": AT_ONCE_REACH_S,
                        "about_the_wheelbase_lag": None if lags is None else AT_LAG_REACH_S},
            "taps": int(taps), "lowpass_Hz": float(cut), "ridge_weights": weights, "block_s": BLOCK_S,
            "fitted_on": "the rear's record itself: every other block of the samples checked, tested on the "
                         "others, both ways; each fold's constant set on the samples tested"}


__all__ = ["AT_LAG_REACH_S", "AT_ONCE_REACH_S", "BLOCK_S", "LOWPASS_HZ", "RIDGES", "TAP_S", "fork_filter_bound"]

"""The reconstruction's rear check band by band (``Reconstruction.checks()["bands"]``), and per band
when the rear moves: the rear's record, the rear predicted and the fork's record each band-passed
(``BANDS``) and compared on the samples checked.

Per band (:func:`band_checks`): the record's RMS (the error of predicting nothing there, the mean's),
the prediction's RMS error and correlation, the delayed fork's RMS error with its least-squares scale
in that band, and ``described`` (the prediction ``BEAT_MARGIN`` below the better of those two).

Per band, when the rear's lag behind the front is known (:func:`timing`, reported, never part of a
verdict): the rear predicted read ``q`` lags later (``q`` from ``SHIFT_LAGS``: -1 is the rear
predicted moved a whole wheelbase / speed earlier, to the moment the front met what the rear predicted
answers), the ``q`` at which it correlates best with the rear's record and that correlation
(``shift_lags``, ``shift_correlation``); and the fork's record in that band against the rear's at
the lag (``fork_at_lag_correlation``) and at the same moment (``fork_now_correlation``). A
prediction whose timing is the ride's peaks at ``q`` = 0; one whose rear answers a wheelbase late
where the ride's rear answered at once peaks at -1; a timing error of the speed alone moves the peak
by the speed's relative error.

The share of the rear's ground met at the front's moment (:func:`at_once_share`, reported beside,
never judged by) and the error it is chosen by (:func:`timing_error`) are here too.
"""
from __future__ import annotations

import math

import numpy as np

BEAT_MARGIN = 0.40  # the rear predicted must be this much (40 %) lower in RMS than the better naive baseline
# the rear's check again per band of frequency (Hz): what each band of the rear's motion is on a ride
BANDS = (((0.05, 0.5), "the rider's slow load"), ((0.5, 2.0), "the body's heave and pitch"),
         ((2.0, 10.0), "the wheels over the terrain"))
SHIFT_LAGS = np.round(np.arange(-1.5, 0.5001, 0.05), 2)  # the shifts searched, in lags (wheelbase / speed)


def _corr(a, b) -> float:
    return float(np.corrcoef(a, b)[0, 1]) if np.std(a) > 0 and np.std(b) > 0 else 0.0


def timing(t, rear, predicted, fork, lags, valid) -> dict:
    """When the rear moves in one band (see the module doc): ``rear``, ``predicted`` and ``fork``
    band-passed already (mm on ``t``), ``lags`` the rear's lag behind the front (s on ``t``), on the
    ``valid`` samples. {"shift_lags", "shift_correlation", "correlation_by_shift" ([q, r] pairs),
    "fork_at_lag_correlation", "fork_now_correlation"}."""
    by = [(float(q), _corr(np.interp(t - q * lags, t, predicted)[valid], rear[valid])) for q in SHIFT_LAGS]
    q, r = max(by, key=lambda qr: qr[1])
    return {"shift_lags": q, "shift_correlation": r, "correlation_by_shift": [[a, round(b, 3)] for a, b in by],
            "fork_at_lag_correlation": _corr(np.interp(t - lags, t, fork)[valid], rear[valid]),
            "fork_now_correlation": _corr(fork[valid], rear[valid])}


def band_checks(t, rear, predicted, fork_delayed, valid, fork=None, lags=None) -> list:
    """The rear's check per band of ``BANDS``: the rear's record, the rear predicted and the delayed fork
    (mm on ``t``) each band-passed over the whole record (a 2nd-order Butterworth run forward and back;
    a missing prediction taken as the record's mean), compared on the ``valid`` samples; with the fork's
    record as recorded (``fork``, mm) and the rear's lag (``lags``, s on ``t``) also its :func:`timing`
    under ``"timing"``. A band the record is too short or too coarsely sampled for is left out."""
    from scipy.signal import butter, sosfiltfilt

    t = np.asarray(t, float)
    fs = 1.0 / float(t[1] - t[0])
    out = []
    if int(np.count_nonzero(valid)) < 3 or t.size < 30:
        return out
    fill = lambda x: np.where(np.isfinite(x), x, float(np.nanmean(rear)))  # noqa: E731
    rms = lambda x: float(np.sqrt(np.mean(x * x)))  # noqa: E731
    for (lo, hi), what in BANDS:
        if hi >= 0.5 * fs or t.size * lo / fs < 2.0:  # the record too short or too coarse for this band
            continue
        sos = butter(2, (lo, hi), btype="bandpass", fs=fs, output="sos")
        whole = [sosfiltfilt(sos, fill(np.asarray(x, float))) for x in (rear, predicted, fork_delayed)]
        r, p, f = (x[valid] for x in whole)
        scale = float(f @ r / (f @ f)) if f @ f > 0 else 0.0
        err, base_fork, base_mean = rms(p - r), rms(scale * f - r), rms(r)
        band = {"band_Hz": [lo, hi], "what": what, "record_rms_mm": base_mean, "predicted_error_rms_mm": err,
                "predicted_correlation": _corr(p, r), "delayed_fork_error_rms_mm": base_fork,
                "described": bool(err <= (1.0 - BEAT_MARGIN) * min(base_fork, base_mean))}
        if fork is not None and lags is not None:
            band["timing"] = timing(t, whole[0], whole[1], sosfiltfilt(sos, np.asarray(fork, float)),
                                    np.asarray(lags, float), valid)
        out.append(band)
    return out


def timing_error(rear, predicted, valid) -> float:
    """The RMS (mm) of the rear predicted less the record, each less its mean, on the ``valid`` samples
    (its timing and shape, not its level); infinite where it is not a number on any of them."""
    ok = valid & np.isfinite(predicted)
    if not ok.any():
        return math.inf
    e = (predicted - rear)[ok]
    return float(np.sqrt(np.mean((e - e.mean()) ** 2)) + (math.inf if ok.sum() < valid.sum() else 0.0))


def at_once_share(rear, at_lag, at_once, valid) -> float:
    """The share (0..1) of the rear's ground met at the front's moment that best matches the rear's
    record (mm) on the ``valid`` samples, from the rear predicted with none of it (``at_lag``) and with
    all of it (``at_once``): least squares on the series less their means (the timing alone, never a
    height), the rear predicted taken linear in the share between the two, clipped to 0..1; 0 where
    the two do not differ or there are fewer than 3 samples. The whole bike is not linear in it (the
    terrain found moves with the rear's ground through the pitch): ``reconstruct`` rides the share
    found and keeps whichever of none, all and it matches the record best."""
    ok = valid & np.isfinite(at_lag) & np.isfinite(at_once)
    if ok.sum() < 3:
        return 0.0
    e0 = (at_lag - rear)[ok]
    d = (at_once - at_lag)[ok]
    e0, d = e0 - e0.mean(), d - d.mean()
    if not d @ d > 0.0:
        return 0.0
    return float(min(max(-(e0 @ d) / (d @ d), 0.0), 1.0))


__all__ = ["BANDS", "BEAT_MARGIN", "SHIFT_LAGS", "band_checks", "timing", "timing_error", "at_once_share"]

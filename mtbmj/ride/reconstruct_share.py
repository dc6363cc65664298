"""The rider's load on both ends at once, read from the fork by the terrain's spectrum (issue 51 items 2
and 3; used by :func:`mtbmj.ride.reconstruct_bike.rear_ground` in the reconstruction's check).

The ground the whole bike finds under its front wheel holds the terrain and whatever else pushed the
fork: a load on both ends at once (the rider pumping or pushing down, a berm, a compression), which the
rear meets at the front's moment, not a wheelbase later. Which part is which is read from the found
ground's own spectrum, never from the rear's record: terrain roughness follows ISO 8608's law, a
displacement PSD falling as the spatial frequency to the power ``-ISO_EXPONENT`` (at a speed v the
temporal frequency is f = v n, so in time too it falls as f^-2 where the speed holds over a spectral
segment). That law is fitted on the found ground in ``FIT_HZ``, where the rider's loads are small
next to the terrain; in ``BAND_HZ`` the share of the found ground's PSD above the law,

    S(f) = clip(1 - c f^-w / PSD_found(f), 0, 1)  (0 outside ``BAND_HZ``),

is taken as a load on both ends at once: the rear meets S(f) of the found ground at the front's
moment and the rest, 1 - S(f), a wheelbase later (:func:`met_at_once`, zero-phase in the frequency
domain). On a ground of terrain alone the found PSD lies on the law and S is near 0: the rear meets it
a wheelbase later, as before. Three guards keep terrain that is not roughness out of S, each found on a
made ride where the rear meets everything a wheelbase later and the first version broke the check: the
PSD is the median of short segments' (a drop's or a jump's few seconds do not pull it); each flight's
level change is left out of what is met at once (:func:`levelled`: a step filtered into the band rings
before and after it); a ground whose slope in ``FIT_HZ`` is no roughness law's (``SLOPE_RANGE``) gives
no share. Nothing here is fitted on the rear's record.

Measured (docs/rolling.md, issue 51 (5)): the rear predicted better on eleven of the twelve shared rides
that give a speed (00083 unchanged), below the delayed fork on seven, none passing; the made rides still
pass (3.73 -> 3.43 mm; the drops' ride 3.30 -> 3.65), the pumped one nearer its rear (6.51 -> 5.26).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.fft import irfft, rfft, rfftfreq
from scipy.signal import welch

# The rider's loads on both ends at once: above the slow load the reconstruction already gives the
# rider at the front (reconstruct_bike.SLOW_HZ, 0.3 Hz), below the sprung masses' bounce on the tyres
# and springs (2-3 Hz on the shared bikes) and what a rider's limbs can drive (pumping 0.5-2 Hz)
BAND_HZ = (0.3, 3.0)
# ISO 8608's law fitted here: above the rider's band, below the wheels' hop on their tyres (10-20 Hz),
# where the found ground is the terrain's roughness
FIT_HZ = (3.0, 10.0)
ISO_EXPONENT = 2.0  # ISO 8608 (road surface profiles): G_d(n) = G_d(n0) (n / n0)^-w, its classes with w = 2
# Welch's segment: 0.25 Hz apart (eleven bins across ``BAND_HZ``, 29 across ``FIT_HZ``), short enough that
# the median of the segments' spectra passes over a drop or a jump (a made ride with two drops and a kicker
# in 30 s read 0.13-0.35 of its 0.5-2.5 Hz as a load with 8 s segments averaged, 0-0.04 at 0.5-2 Hz so)
SEGMENT_S = 4.0
PAD_S = 5.0  # each end mirrored (odd) this long before the filter, so the ride's ends do not wrap round
SHOWN_HZ = (0.5, 1.0, 1.5, 2.0, 2.5)  # the share reported at these frequencies
# The found ground's own log-log slope in ``FIT_HZ`` must lie here for the law to be read at all: roughness
# of ISO 8608's kind (the shared rides' found grounds 1.8-2.9; a ground of isolated 1-3 m bumps on flat ground,
# tests/test_reconstruct.py, falls at 6.7: no roughness law there, and extrapolated it took bumps for a load)
SLOPE_RANGE = (-3.5, -1.5)
# each flight's level change left out of the share met at once, with this much either side: 0 (0.2 s took
# 22-56 % of the SST version-2 trail sections' samples, whose found ground then fell out of SLOPE_RANGE)
FLIGHT_MARGIN_S = 0.0


def levelled(ground, air, dt: float) -> np.ndarray:
    """``ground`` with each flight's level change taken out (its slope 0 over the flight ``air`` and
    ``FLIGHT_MARGIN_S`` either side): a drop's or a jump's step is terrain the rear meets a wheelbase
    later; filtered into the band it would ring before and after it at the rear's moment."""
    g = np.where(np.isfinite(ground), np.asarray(ground, float), 0.0)
    if air is None or not np.any(air):
        return g
    w = int(round(FLIGHT_MARGIN_S / dt))
    near = np.convolve(np.asarray(air, float), np.ones(2 * w + 1), mode="same") > 0.0
    slope = np.diff(g, prepend=g[0])
    slope[near] = 0.0
    return np.cumsum(slope)


def share(ground, dt: float) -> tuple:
    """(f Hz, S(f), c): the share of the found ``ground`` (m at step ``dt``) that is a load on both ends
    at once, on Welch's frequencies (the median of the segments' spectra: a load the rider keeps up along
    the ride, not a drop's or a jump's few seconds), and the ISO law's level c (m^2/Hz at 1 Hz) fitted in
    ``FIT_HZ``. A ground too short or too level to read a spectrum from (no PSD in ``FIT_HZ``), or whose
    slope there is not a roughness law's (``SLOPE_RANGE``): S is 0."""
    g = np.asarray(ground, float)
    g = np.where(np.isfinite(g), g, 0.0)
    f, psd = welch(g - g.mean(), fs=1.0 / dt, nperseg=min(g.size, int(round(SEGMENT_S / dt))), average="median")
    fit = (f >= FIT_HZ[0]) & (f <= FIT_HZ[1]) & (psd > 0.0)
    if np.count_nonzero(fit) < 2:
        return f, np.zeros(f.size), 0.0
    slope = np.polyfit(np.log(f[fit]), np.log(psd[fit]), 1)[0]
    if not SLOPE_RANGE[0] <= slope <= SLOPE_RANGE[1]:
        return f, np.zeros(f.size), 0.0
    c = float(np.exp(np.mean(np.log(psd[fit]) + ISO_EXPONENT * np.log(f[fit]))))
    band = (f >= BAND_HZ[0]) & (f <= BAND_HZ[1]) & (psd > 0.0)
    s = np.zeros(f.size)
    s[band] = np.clip(1.0 - c * f[band] ** -ISO_EXPONENT / psd[band], 0.0, 1.0)
    return f, s, c


def filtered(x, dt: float, f, s) -> np.ndarray:
    """``x`` (on step ``dt``) through the zero-phase gain ``s`` given at frequencies ``f`` (linear
    between them), its ends mirrored (odd) ``PAD_S`` long first."""
    x = np.asarray(x, float)
    n = x.size
    p = min(n - 1, int(round(PAD_S / dt)))
    y = np.pad(x, p, mode="reflect", reflect_type="odd") if p > 0 else x
    gain = np.interp(rfftfreq(y.size, dt), f, s)
    return irfft(rfft(y) * gain, y.size)[p:p + n]


def met_at_once(t, lag, ground, air=None) -> np.ndarray:
    """The ground the rear meets (m on ``t``): the found ``ground`` ``lag`` (s) later, its share S
    (:func:`share`) met instead at the front's moment, each flight ``air``'s level change (:func:`levelled`)
    left a wheelbase later."""
    dt = float(t[1] - t[0])
    behind = np.interp(t - lag, t, ground)
    flat = levelled(ground, air, dt)
    f, s, _ = share(flat, dt)
    if not s.any():
        return behind
    return behind - filtered(np.interp(t - lag, t, flat), dt, f, s) + filtered(flat, dt, f, s)


def described(ground, dt: float, valid=None, air=None) -> dict:
    """What ``reconstruction.json`` says of the share used on the found ``ground``: the bands, the law,
    the share at ``SHOWN_HZ`` and the RMS (mm) of the part of the ground the rear meets at once (on the
    ``valid`` samples, all if None)."""
    flat = levelled(ground, air, dt)
    f, s, c = share(flat, dt)
    part = filtered(flat, dt, f, s) if s.any() else np.zeros(np.asarray(ground).size)
    v = np.ones(part.size, bool) if valid is None else np.asarray(valid, bool)
    rms = 1e3 * float(np.sqrt(np.mean(part[v] ** 2))) if v.any() else math.nan
    return {"at_once_rms_mm": rms, "band_Hz": list(BAND_HZ), "fit_Hz": list(FIT_HZ),
            "iso_8608_exponent": ISO_EXPONENT, "iso_level_mm2_per_Hz_at_1_Hz": 1e6 * c,
            "share_at_Hz": {f"{h:g}": float(np.interp(h, f, s)) for h in SHOWN_HZ},
            "what": "the rear meets this share of the ground found at the front's moment (a load on both ends at "
                    "once: the found ground's PSD above the ISO 8608 f^-2 law fitted on its own "
                    f"{FIT_HZ[0]:g}-{FIT_HZ[1]:g} Hz, in {BAND_HZ[0]:g}-{BAND_HZ[1]:g} Hz only), the rest a "
                    "wheelbase later; from the fork's record alone (mtbmj/ride/reconstruct_share.py)"}


__all__ = ["BAND_HZ", "FIT_HZ", "ISO_EXPONENT", "SLOPE_RANGE", "share", "filtered", "met_at_once", "described"]

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
a wheelbase later, as before. Nothing here is fitted on the rear's record.

Measured (docs/rolling.md, issue 51 (5)): the rear predicted better on all twelve shared rides that
give a speed; the made ride still passes; the pumped made rides nearer their rear.
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
ISO_EXPONENT = 2.0  # ISO 8608:2016 (road profiles), clause 5: G_d(n) = G_d(n0) (n / n0)^-w with w = 2
SEGMENT_S = 8.0  # Welch's segment: 0.125 Hz apart, a dozen bins across ``FIT_HZ`` and ``BAND_HZ`` each
PAD_S = 5.0  # each end mirrored (odd) this long before the filter, so the ride's ends do not wrap round
SHOWN_HZ = (0.5, 1.0, 1.5, 2.0, 2.5)  # the share reported at these frequencies


def share(ground, dt: float) -> tuple:
    """(f Hz, S(f), c): the share of the found ``ground`` (m at step ``dt``) that is a load on both ends
    at once, on Welch's frequencies, and the ISO law's level c (m^2/Hz at 1 Hz) fitted in ``FIT_HZ``.
    A ground too short or too level to read a spectrum from (no PSD in ``FIT_HZ``): S is 0."""
    g = np.asarray(ground, float)
    g = np.where(np.isfinite(g), g, 0.0)
    f, psd = welch(g - g.mean(), fs=1.0 / dt, nperseg=min(g.size, int(round(SEGMENT_S / dt))))
    fit = (f >= FIT_HZ[0]) & (f <= FIT_HZ[1]) & (psd > 0.0)
    if not fit.any():
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


def met_at_once(behind, ground, dt: float) -> np.ndarray:
    """The ground the rear meets: ``behind`` (the found ``ground`` a wheelbase later, m on step ``dt``)
    with its share S taken instead from ``ground`` at the front's moment (:func:`share`)."""
    f, s, _ = share(ground, dt)
    if not s.any():
        return np.asarray(behind, float)
    return np.asarray(behind, float) - filtered(behind, dt, f, s) + filtered(ground, dt, f, s)


def described(ground, dt: float, valid=None) -> dict:
    """What ``reconstruction.json`` says of the share used on the found ``ground``: the bands, the law,
    the share at ``SHOWN_HZ`` and the RMS (mm) of the part of the ground the rear meets at once (on the
    ``valid`` samples, all if None)."""
    f, s, c = share(ground, dt)
    part = filtered(ground, dt, f, s) if s.any() else np.zeros(np.asarray(ground).size)
    v = np.ones(part.size, bool) if valid is None else np.asarray(valid, bool)
    rms = 1e3 * float(np.sqrt(np.mean(part[v] ** 2))) if v.any() else math.nan
    return {"at_once_rms_mm": rms, "band_Hz": list(BAND_HZ), "fit_Hz": list(FIT_HZ),
            "iso_8608_exponent": ISO_EXPONENT, "iso_level_mm2_per_Hz_at_1_Hz": 1e6 * c,
            "share_at_Hz": {f"{h:g}": float(np.interp(h, f, s)) for h in SHOWN_HZ},
            "what": "the rear meets this share of the ground found at the front's moment (a load on both ends at "
                    "once: the found ground's PSD above the ISO 8608 f^-2 law fitted on its own "
                    f"{FIT_HZ[0]:g}-{FIT_HZ[1]:g} Hz, in {BAND_HZ[0]:g}-{BAND_HZ[1]:g} Hz only), the rest a "
                    "wheelbase later; from the fork's record alone (mtbmj/ride/reconstruct_share.py)"}


__all__ = ["BAND_HZ", "FIT_HZ", "ISO_EXPONENT", "share", "filtered", "met_at_once", "described"]

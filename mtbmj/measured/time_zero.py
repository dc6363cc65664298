"""Time zero of a sled record: the moment the tire tread touches the ground. One rule, used by
``mtbmj validate``, ``mtbmj fit drop`` and the Python API (``validation.sled_data``,
``identify.dropfit``).

The tire signal (sled - fork, zeroed at tread touch) is the negative gap between tread and ground
while the sled falls; it rises through zero at touch. A record comes in one of three shapes:

- **free fall**: the record shows the tire in the air (its smoothed signal below minus a
  noise-scaled level) before the first impact. This includes a
  logger on its own clock that hangs, releases and falls, and a logger with a short pre-trigger.
  The touch is found from the fall itself: over the last ``FALL_WINDOW_S`` before the signal
  reaches zero, the samples that are certainly before touch are fitted with the free-fall
  parabola (gravity ``GRAVITY_MM_PER_S2`` known, offset and speed fitted); its zero crossing,
  less the anti-aliasing filter's group delay (a filtered ramp is the ramp delayed by it), is the
  touch. With too few samples of fall, a straight line through the samples near zero stands in.
- **starts at impact**: the first rise into contact comes before any free fall and the record's
  first sample lies within ``START_BAND_MM`` (or the noise band) of zero: the record was cut at
  touch, like every run of the package, and its first sample is the touch.
- anything else (a record that starts with the tire already loaded, or never loads it) has no
  touch that can be found: refused with one line naming why. ``touch_s`` given explicitly (the
  ``--touch-s`` option) overrides the search.

Flights after the impact (lift-off, landing) never count as the free fall: the first contact
decides which shape the record has. The clock of the record is kept: the touch is reported on it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.measured.peaks import noise_sigma
from mtbmj.errors import MtbmjError

GRAVITY_MM_PER_S2 = 9806.65
FALL_WINDOW_S = 0.06      # the part of the fall fitted with the parabola
START_BAND_MM = 3.0       # a record starting within this of zero (or the noise band) starts at impact
START_RISE_S = 0.03       # ... and must be clearly loaded within this time
MIN_AFTER_TOUCH_S = 0.05  # a record must go on at least this long after touch
MAX_TOUCH_BEFORE_S = 0.5  # a touch given may lie this far before the record's start (cut after touch)
KINDS = ("free fall", "starts at impact", "given")


class TouchError(MtbmjError):
    """No touch can be found in a record: one line naming the record and why."""


@dataclass(frozen=True)
class Touch:
    """Where time zero lies on the record's clock and how it was found."""

    touch_s: float            # on the record's own clock
    kind: str                 # one of KINDS
    fall_s: float = 0.0       # free fall seen before touch (s)
    impact_speed_m_per_s: float | None = None  # the slope of the fall at touch (free fall only)
    stderr_s: float = 0.0     # standard error of touch_s from the noise of the fitted fall

    def describe(self) -> str:
        where = f"t = {self.touch_s:.4f} s on the record's clock"
        if self.kind == "given":
            return f"time zero given: {where}"
        if self.kind == "starts at impact":
            return f"time zero: the record starts at impact (its first sample, {where})"
        speed = "" if self.impact_speed_m_per_s is None else f", impact at {self.impact_speed_m_per_s:.3f} m/s"
        return (f"time zero: tire touch found at the end of the free fall ({self.fall_s * 1e3:.0f} ms of the record "
                f"before it), {where}{speed}")

    def to_dict(self) -> dict:
        return {"touch_in_file_s": self.touch_s, "kind": self.kind, "fall_s": self.fall_s,
                "impact_speed_m_per_s": self.impact_speed_m_per_s, "stderr_s": self.stderr_s,
                "description": self.describe()}


def antialias_delay_s(antialias_Hz: float | None, order: int = 4) -> float:
    """Group delay at low frequency of an order-``order`` Butterworth low-pass: what it delays a ramp."""
    if not antialias_Hz:
        return 0.0
    poles = np.exp(1j * np.pi * (2 * np.arange(1, order + 1) + order - 1) / (2 * order))
    return float(np.sum(-1.0 / poles).real / (2 * np.pi * antialias_Hz))


def _smooth(y: np.ndarray, width: int) -> np.ndarray:
    if width <= 1 or y.size < width:
        return y.astype(float)
    kernel = np.ones(width) / width
    padded = np.concatenate([np.full(width // 2, y[0]), y, np.full(width - 1 - width // 2, y[-1])])
    return np.convolve(padded, kernel, mode="valid")


def _line_crossing(t, y, smooth, start, first, band, dt) -> float:
    """Zero crossing of a line through the samples near zero between ``start`` and a little past
    ``first`` (or of the smoothed signal when too few)."""
    window = np.arange(start, min(first + int(round(0.006 / dt)) + 1, y.size))
    window = window[np.abs(smooth[window]) <= band]
    if window.size >= 3:
        slope, intercept = np.polyfit(t[window], y[window], 1)
        if slope > 0:
            return float(-intercept / slope)
    j = max(start, first - 1)
    while j > start and smooth[j] > 0:
        j -= 1
    y0, y1 = smooth[j], smooth[j + 1]
    return float(t[j] + (t[j + 1] - t[j]) * (-y0 / (y1 - y0))) if y1 != y0 else float(t[j])


def find_touch(time_s, tire_mm, name: str = "record", antialias_Hz: float | None = 400.0,
               touch_s: float | None = None) -> Touch:
    """Time zero of a record (see the module docstring); ``touch_s`` given overrides the search
    (it must lie within the record, at least ``MIN_AFTER_TOUCH_S`` before its end)."""
    t = np.asarray(time_s, float)
    y = np.asarray(tire_mm, float)
    if touch_s is not None:
        if not np.isfinite(touch_s) or not t[0] - MAX_TOUCH_BEFORE_S <= touch_s <= t[-1] - MIN_AFTER_TOUCH_S:
            raise TouchError(f"{name}: --touch-s {touch_s:g} is not within the record "
                             f"({t[0] - MAX_TOUCH_BEFORE_S:.4f} s to {t[-1] - MIN_AFTER_TOUCH_S:.4f} s: at most "
                             f"{MAX_TOUCH_BEFORE_S:g} s before its start and {MIN_AFTER_TOUCH_S * 1e3:.0f} ms "
                             "before its end)")
        return Touch(float(touch_s), "given")
    dt = float(np.median(np.diff(t)))
    sigma = noise_sigma(y)
    level = max(2.0, 8.0 * sigma)  # "clearly in the air" / "clearly in contact"
    band = max(3.0, 10.0 * sigma)
    smooth = _smooth(y, max(1, int(round(0.003 / dt)) | 1))
    loaded = np.flatnonzero(smooth > level)
    if loaded.size == 0:
        raise TouchError(f"{name}: no impact in the record (the tire deflection never exceeds {level:.1f} mm; "
                         f"largest {float(np.max(y)):.2f} mm)")
    first = int(loaded[0])
    air = np.flatnonzero(smooth[:first] < -level)
    delay = antialias_delay_s(antialias_Hz)
    if air.size:
        start = int(air[-1])  # the last sample clearly in the air before the impact
        fall_from = int(air[0])
        crude = _line_crossing(t, y, smooth, start, first, band, dt)
        touch, speed = crude - delay, None
        stderr = max(sigma, 0.01) / max(np.max(np.abs(np.diff(smooth[start:first + 1]))) / dt, 1.0)
        # the fitted fall: samples certainly before touch (the filter's output is the delayed
        # parabola up to the physical touch, where it reads -v * delay)
        near = np.flatnonzero((np.abs(smooth - 0.0) <= band) & (np.arange(y.size) <= first))
        slope = np.polyfit(t[near], y[near], 1)[0] if near.size >= 2 else 0.0
        if slope > 0:
            limit = -(slope * delay) - 3.0 * sigma - 0.2
            pick = np.arange(fall_from, first)
            pick = pick[(t[pick] >= crude - FALL_WINDOW_S) & (y[pick] <= limit) & (t[pick] <= crude)]
            if pick.size >= 5:
                tau = t[pick] - crude
                (b, a), cov = np.polyfit(tau, y[pick] - 0.5 * GRAVITY_MM_PER_S2 * tau**2, 1, cov="unscaled")
                resid = y[pick] - 0.5 * GRAVITY_MM_PER_S2 * tau**2 - (a + b * tau)
                spread = float(np.std(resid))
                # coloured noise (the anti-aliasing filter): inflate by the AR(1) variance factor
                rho = float(np.clip(resid[1:] @ resid[:-1] / max(resid @ resid, 1e-300), 0.0, 0.95))
                sigma_fit = (max(spread, sigma) * np.sqrt(pick.size / max(pick.size - 2, 1))
                             * np.sqrt((1 + rho) / (1 - rho)))
                # a + b tau + g/2 tau^2 = 0 near tau = 0
                disc = b * b - 2.0 * GRAVITY_MM_PER_S2 * a
                if b > 0 and disc >= 0:
                    root = (-b + np.sqrt(disc)) / GRAVITY_MM_PER_S2
                    touch = crude + float(root) - delay
                    speed = float(b + GRAVITY_MM_PER_S2 * root) * 1e-3
                    grad = np.array([root, 1.0])  # d(crossing)/d(b, a) times the slope at the crossing
                    stderr = float(sigma_fit * np.sqrt(grad @ cov @ grad)) / (speed * 1e3)
        touch = float(np.clip(touch, t[fall_from], t[first]))
        found = Touch(touch, "free fall", fall_s=float(max(touch - t[fall_from], 0.0)), impact_speed_m_per_s=speed,
                      stderr_s=float(stderr))
    else:
        head = y[: max(1, int(round(0.003 / dt)))]
        if abs(float(np.median(head))) > max(START_BAND_MM, band):
            raise TouchError(f"{name}: no touch in the record: it starts with the tire already "
                             f"{'deflected' if np.median(head) > 0 else 'off the ground by'} "
                             f"{abs(float(np.median(head))):.1f} mm and shows no free fall before the impact "
                             "(is tire = sled - fork zeroed at tread touch? give --touch-s to set time zero)")
        if t[first] - t[0] > START_RISE_S:
            raise TouchError(f"{name}: no touch in the record: it starts near zero but the tire is only loaded "
                             f"{(t[first] - t[0]) * 1e3:.0f} ms later, with no free fall before "
                             "(give --touch-s to set time zero)")
        found = Touch(float(t[0]), "starts at impact")
    if t[-1] - found.touch_s < MIN_AFTER_TOUCH_S:
        raise TouchError(f"{name}: the record ends {max(t[-1] - found.touch_s, 0.0) * 1e3:.0f} ms after the tire "
                         f"touches the ground; the impact is not in it")
    return found


__all__ = ["Touch", "TouchError", "find_touch", "antialias_delay_s", "KINDS"]

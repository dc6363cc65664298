"""The leverage curve, the one class for the bike and the telemetry: the leverage ratio LR =
d(rear wheel travel) / d(shock stroke) piecewise linear in the rear wheel travel (SI), the shock
stroke its exact integral and the travel at a stroke its inverse; in mm too, as a ride is decoded
(``stroke_mm``, ``wheel_travel_mm``). Its lookups are plain functions of the table, which the
compiled bike callback and the reconstruction's quarter cars compile (``leverage_ratio``,
``leverage_stroke``, ``stroke_piece``)."""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Leverage:
    """Leverage ratio LR = d(rear wheel travel) / d(shock stroke), piecewise linear in the rear
    wheel travel ``travel`` (m, from 0, strictly increasing); constant past the table's ends.
    The shock stroke is s(w) = integral from 0 to w of dw / LR(w), exact on each linear piece."""

    travel: tuple[float, ...]
    ratio: tuple[float, ...]

    def __post_init__(self):
        w, r = [float(x) for x in self.travel], [float(x) for x in self.ratio]
        s = [0.0]
        for i in range(len(w) - 1):  # the stroke at each table point, exact for a ratio linear in w
            s.append(s[-1] + stroke_piece(r[i], r[i + 1], w[i + 1] - w[i], w[i + 1] - w[i]))
        # plain lists: the callback asks for one value at a time, where bisect beats numpy
        object.__setattr__(self, "_w", w)
        object.__setattr__(self, "_r", r)
        object.__setattr__(self, "_s", s)

    def ratio_at(self, w: float) -> float:
        """LR at rear wheel travel ``w`` (m)."""
        return leverage_ratio(self._w, self._r, bisect.bisect_right(self._w, w) - 1, w)

    def stroke(self, w: float) -> float:
        """Shock stroke (m) at rear wheel travel ``w`` (m); below 0 and past the table the ratio
        is held at its end value."""
        return leverage_stroke(self._w, self._r, self._s, bisect.bisect_right(self._w, w) - 1, w)

    def ratios(self, w) -> np.ndarray:
        """``ratio_at`` over an array of rear wheel travels (m): the same arithmetic in numpy, to the bit."""
        w = np.asarray(w, dtype=float)
        w_tab, r = np.asarray(self._w, dtype=float), np.asarray(self._r, dtype=float)
        i = np.clip(np.searchsorted(w_tab, w, side="right") - 1, 0, w_tab.size - 2)
        inside = r[i] + (r[i + 1] - r[i]) * (w - w_tab[i]) / (w_tab[i + 1] - w_tab[i])
        return np.where(w <= w_tab[0], r[0], np.where(w >= w_tab[-1], r[-1], inside))

    def strokes(self, w) -> np.ndarray:
        """``stroke`` over an array of rear wheel travels (m): the same pieces, in numpy."""
        w = np.asarray(w, dtype=float)
        w_tab, r, s = (np.asarray(v, dtype=float) for v in (self._w, self._r, self._s))
        n = w_tab.size
        i = np.clip(np.searchsorted(w_tab, w, side="right") - 1, 0, n - 2)
        r0, r1, h, x = r[i], r[i + 1], w_tab[i + 1] - w_tab[i], w - w_tab[i]
        b = (r1 - r0) / h
        linear = np.abs(b) * x < 1e-9 * r0
        with np.errstate(divide="ignore", invalid="ignore"):  # the linear pieces' log is not used
            piece = np.where(linear, x / r0, np.log((r0 + b * x) / r0) / np.where(linear, 1.0, b))
        out = s[i] + piece
        out = np.where(w <= 0.0, w / r[0], out)
        return np.where(w >= w_tab[n - 1], s[n - 1] + (w - w_tab[n - 1]) / r[n - 1], out)

    @property
    def table(self) -> tuple[list[float], list[float], list[float]]:
        """(travel, ratio, stroke) at the table's points (m, -, m): the lookups' arguments."""
        return self._w, self._r, self._s

    def travel_at_stroke(self, stroke: float) -> float:
        """The rear wheel travel (m) at shock ``stroke`` (m): ``stroke``'s inverse, the ratio held at
        the table's ends beyond them."""
        w, r, s = self._w, self._r, self._s
        if stroke <= 0.0:
            return stroke * r[0]
        if stroke >= s[-1]:
            return w[-1] + (stroke - s[-1]) * r[-1]
        i = bisect.bisect_right(s, stroke) - 1
        b, ds = (r[i + 1] - r[i]) / (w[i + 1] - w[i]), stroke - s[i]
        return w[i] + (ds * r[i] if abs(b) * ds < 1e-12 else r[i] * math.expm1(b * ds) / b)

    @property
    def full_travel(self) -> float:
        return float(self._w[-1])

    @property
    def full_stroke(self) -> float:
        return float(self._s[-1])

    # In mm, as the telemetry decodes a ride: the ratio is linear in the wheel travel on each piece,
    # as the methods above read it: ds = dw / r(w), so on a piece from (w0, r0) with slope b the
    # stroke is s0 + ln(1 + b x / r0) / b (x / r0 where b = 0), and the inverse
    # x = r0 (exp(b (s - s0)) - 1) / b: exact, both ways.
    @property
    def wheel_mm(self) -> tuple[float, ...]:
        """The table's rear wheel travels in mm."""
        return tuple(w * 1e3 for w in self.travel)

    def _stroke_table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        w, r = np.asarray(self.wheel_mm, float), np.asarray(self.ratio, float)
        w = w - w[0]
        h = np.diff(w)
        b = np.diff(r) / h
        flat = np.abs(b) * h < 1e-9 * r[:-1]
        with np.errstate(divide="ignore", invalid="ignore"):
            piece = np.where(flat, h / r[:-1], np.log(r[1:] / r[:-1]) / np.where(flat, 1.0, b))
        return w, np.concatenate(([0.0], np.cumsum(piece))), np.where(flat, 0.0, b)

    def _piece(self, x, along_stroke: bool):
        """The table in mm (travel, stroke, slope), the ratios, ``x`` as an array, the piece each
        ``x`` lies on (along the stroke or the travel) and how far into it."""
        w, s, b = self._stroke_table()
        r = np.asarray(self.ratio, float)
        x = np.asarray(x, dtype=float)
        knots = s if along_stroke else w
        i = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, knots.size - 2)
        return w, s, b, r, x, i, np.clip(x - knots[i], 0.0, None)

    def stroke_mm(self, wheel_travel_mm) -> np.ndarray:
        """Shock stroke (mm) at rear wheel travels (mm), vectorised; the last ratio holds past the table."""
        w, s, b, r, x, i, dx = self._piece(wheel_travel_mm, False)
        with np.errstate(divide="ignore", invalid="ignore"):
            inside = s[i] + np.where(b[i] == 0.0, dx / r[i], np.log1p(b[i] * dx / r[i]) / np.where(b[i] == 0.0, 1.0, b[i]))
        beyond = s[-1] + (x - w[-1]) / r[-1]  # past the table: the last ratio holds
        return np.where(x > w[-1], beyond, np.where(x < 0.0, x / r[0], inside))

    def wheel_travel_mm(self, stroke_mm) -> np.ndarray:
        """Rear wheel travel (mm) at shock strokes (mm): ``stroke_mm``'s inverse."""
        w, s, b, r, x, i, ds = self._piece(stroke_mm, True)
        with np.errstate(over="ignore", invalid="ignore"):
            inside = w[i] + np.where(b[i] == 0.0, ds * r[i], r[i] * np.expm1(b[i] * ds) / np.where(b[i] == 0.0, 1.0, b[i]))
        beyond = w[-1] + (x - s[-1]) * r[-1]
        return np.where(x > s[-1], beyond, np.where(x < 0.0, x * r[0], inside))


def stroke_piece(r0: float, r1: float, h: float, x: float) -> float:
    """Integral from 0 to x of du / (r0 + (r1 - r0) u / h)."""
    b = (r1 - r0) / h
    if abs(b) * x < 1e-9 * r0:
        return x / r0
    return math.log((r0 + b * x) / r0) / b


# The leverage curve's lookups as plain functions of the table (travel w_tab, ratio r, stroke s at
# each point) and the piece i = bisect_right(w_tab, w) - 1 holding w: ``Leverage`` calls them on
# its lists, the compiled bike callback (``mtbmj.bike.callback_compiled``) compiles these same
# functions and finds i by its own bisection.
def leverage_ratio(w_tab, r, i, w: float) -> float:
    """LR at rear wheel travel ``w`` (m); constant past the table's ends."""
    n = len(w_tab)
    if w <= w_tab[0]:
        return r[0]
    if w >= w_tab[n - 1]:
        return r[n - 1]
    return r[i] + (r[i + 1] - r[i]) * (w - w_tab[i]) / (w_tab[i + 1] - w_tab[i])


def leverage_stroke(w_tab, r, s, i, w: float) -> float:
    """Shock stroke (m) at rear wheel travel ``w`` (m), the ratio held at its end values outside
    the table."""
    n = len(w_tab)
    if w <= 0.0:
        return w / r[0]
    if w >= w_tab[n - 1]:
        return s[n - 1] + (w - w_tab[n - 1]) / r[n - 1]
    return s[i] + stroke_piece(r[i], r[i + 1], w_tab[i + 1] - w_tab[i], w - w_tab[i])


__all__ = ["Leverage", "leverage_ratio", "leverage_stroke", "stroke_piece"]

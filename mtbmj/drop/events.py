"""Events of a drop, robust to sensor noise and to responses that differ from the textbook.

The textbook response (the paper, Fig. 4): Peak 1 (the impact absorbed), the tire leaves the ground
and the fork tops out (the topping event: the extreme in the air), landing and Peak 2, then in
contact Valley 1, Peak 3 and rest. Detection, on signals aligned to t = 0 at tire touch:

1. Every signal is smoothed (Savitzky-Golay, 11 ms, cubic: peak heights survive, noise does not).
2. Contact: the tire is in the air while its (smoothed) signal is below minus a noise-scaled
   level for at least ``MIN_AIRTIME_S``; lift-off and landing are the zero crossings around it.
3. The sled (the sprung mass, the smoothest signal) fixes the pattern: Peak 1 is its maximum before
   lift-off, Peak 2 its first prominent peak after landing, then the first prominent valley and
   peak. Prominence is scaled by the sled's range and by the noise, so sensor noise and small
   ringing are not events. A run that never lifts off has no topping; Peak 2 is then the next
   prominent peak after the rebound valley.
4. The fork and tire take their extreme in the window around each sled event (from halfway to the
   previous sled event to halfway to the next), so a ringing tire gives its largest excursion
   there, not one of its wiggles. An extreme at the edge of its window is no peak: the event is None.
   Topping: the sled and the tire take their lowest point in the air (the top of the flight, a
   rounded minimum); the fork, which sits on a flat plateau at full extension while in the air,
   takes the moment it reaches full extension: the first time after Peak 1 (before landing) that
   its smoothed signal comes within ``TOP_BAND_MM`` (or 5 x its noise) of its lowest value there,
   with that lowest value as the event's value. The minimum of a plateau has no time; its start has.
5. Rest: the system is at rest when the sled moves less than ``REST_TOLERANCE_MM`` (plus
   noise) over the last ``REST_WINDOW_S`` (as ``mtbmj drop`` decides); the rest value is the mean there and its time the
   settling time (the last exit from a band around it). Otherwise rest is None and the run is
   flagged "never comes to rest".

A missing event is None and listed in ``flags``: never forced into the pattern.
"""
from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from mtbmj.measured.peaks import (median_in_place, parabola_rows, noise_sigmas, parabola, peaks_and_valleys, smooth_into,
                               smooth_width)
from mtbmj.errors import MtbmjError


class EventsError(MtbmjError, ValueError):
    """Too little of a run or record to find its events (one line; also a ValueError, as before)."""

SIGNALS = ("sled", "fork", "tire")
EVENTS = ("peak1", "topping", "peak2", "valley1", "peak3", "rest")
LABELS = {"peak1": "Peak 1", "topping": "Topping", "peak2": "Peak 2", "valley1": "Valley 1",
          "peak3": "Peak 3", "rest": "Rest"}
SMOOTH_S = 0.011            # Savitzky-Golay window
MIN_AIRTIME_S = 0.005       # shorter losses of contact are not a lift-off
REST_WINDOW_S = 0.2         # the last 0.2 s decide whether the system is at rest
REST_TOLERANCE_MM = 0.5     # peak-to-peak motion allowed at rest (plus noise)
SETTLE_BAND_MM = 1.0        # the settling time is the last exit from rest +/- this (plus noise)
PROMINENCE_FRACTION = 0.02  # of the sled's range after touch
TOP_BAND_MM = 0.3           # the fork "reaches full extension" within this of its lowest value in the air


@dataclass(frozen=True)
class Event:
    time_s: float
    value_mm: float

    def to_dict(self) -> dict:
        return {"time_s": self.time_s, "value_mm": self.value_mm}


@dataclass
class Events:
    """Events of sled, fork and tire (``signals[signal][event]`` -> ``Event`` or None) and the
    run's flags."""

    signals: dict[str, dict[str, Event | None]]
    lift_off_s: float | None
    landing_s: float | None
    at_rest: bool
    rest_motion_mm: dict[str, float]
    noise_mm: dict[str, float]
    end_s: float
    flags: list[str] = field(default_factory=list)

    @property
    def lifts_off(self) -> bool:
        return self.lift_off_s is not None

    @property
    def lands(self) -> bool:
        return self.landing_s is not None

    def get(self, signal: str, event: str) -> Event | None:
        return self.signals[signal][event]

    def to_dict(self) -> dict:
        return {
            "lifts_off": self.lifts_off, "lift_off_s": self.lift_off_s, "landing_s": self.landing_s,
            "at_rest": self.at_rest, "rest_motion_mm": self.rest_motion_mm, "noise_mm": self.noise_mm,
            "end_s": self.end_s, "flags": list(self.flags),
            "events": {s: {e: (ev.to_dict() if ev else None) for e, ev in per.items()}
                       for s, per in self.signals.items()},
        }


NEAR = 48  # samples each side of an extreme walked at once (in Python or vectorised); on from there in slices
_OFFSETS = np.arange(-NEAR, NEAR + 1)


def _reach(y: np.ndarray, yi: float, height: float, near: int, step: int, stop: int) -> int:
    """The last sample reached walking on from ``near`` one ``step`` (-1 or +1) at a time while
    the next one lies within ``height`` of ``yi``, at most to ``stop`` (0 or ``y.size - 1``):
    searched in growing slices rather than sample by sample."""
    span = 4 * NEAR
    while near != stop:
        far = max(stop, near - span) if step < 0 else min(stop, near + span)
        seg = y[far:near] if step < 0 else y[near + 1:far + 1]
        out = np.abs(seg - yi) <= height
        np.logical_not(out, out=out)  # not within (NaN is not within, as in the walk)
        if step < 0:
            k = int(out[::-1].argmax())
            if out[seg.size - 1 - k]:
                return near - k
        else:
            k = int(out.argmax())
            if out[k]:
                return near + k
        near = far
        span *= 4
    return near


def _runs(ys: np.ndarray, row: list[int], index: list[int], height: list[float]) -> tuple[list[int], list[int]]:
    """The first and last of the samples around sample ``index[j]`` of the row ``row[j]`` of ``ys``
    that lie within ``height[j]`` of it without a break, for each ``j``: the ``NEAR`` samples each
    side of all of them in one vectorised pass, searched on in slices past them."""
    n = ys.shape[1]
    i = np.array(index)
    pos = i[:, None] + _OFFSETS
    inside = (pos >= 0) & (pos < n)  # the record's ends stop a walk
    near = ys[np.array(row)[:, None], np.clip(pos, 0, n - 1)]
    within = np.abs(near - near[:, NEAR, None]) <= np.array(height)[:, None]
    within &= inside
    back, on = within[:, NEAR - 1::-1], within[:, NEAR + 1:]  # the samples before (nearest first) and after
    lo = (i - np.where(back.all(axis=1), NEAR, back.argmin(axis=1))).tolist()
    hi = (i + np.where(on.all(axis=1), NEAR, on.argmin(axis=1))).tolist()
    for j, k in enumerate(index):  # runs past NEAR samples: on in slices
        if lo[j] == k - NEAR and lo[j] > 0:
            lo[j] = _reach(ys[row[j]], ys[row[j], k], height[j], lo[j], -1, 0)
        if hi[j] == k + NEAR and hi[j] < n - 1:
            hi[j] = _reach(ys[row[j]], ys[row[j], k], height[j], hi[j], 1, n - 1)
    return lo, hi


def _vertex(t: np.ndarray, y: np.ndarray, data: np.ndarray, i: int, lo: int, hi: int, fit=parabola) -> Event:
    """The extreme at sample ``i`` of ``y`` from the parabola through ``data`` over the run of
    samples ``lo``..``hi`` around it (widened to two samples each side); ``fit`` is ``parabola``
    or, for contiguous float rows, its core without the checks."""
    last = y.size - 1
    lo, hi = max(0, min(lo, i - 2)), min(last, max(hi, i + 2))
    if hi - lo >= 4:
        tt = t[lo:hi + 1] - t[i]
        a, b, c = fit(tt, data[lo:hi + 1])
        if a != 0:
            vertex = -b / (2 * a)
            if tt[0] <= vertex <= tt[-1]:
                return Event(float(t[i] + vertex), float(c - b * b / (4 * a)))
    return Event(float(t[i]), float(y[i]))


def _refine_all(t: np.ndarray, ys: np.ndarray, raw: np.ndarray, sigma: list[float],
                jobs: list[tuple[int, int]]) -> list[Event]:
    """The extreme near each (row, sample) of ``jobs``, refined: a least-squares parabola through
    the raw ``raw[row]`` over the samples around it where the smoothed ``ys[row]`` stays within a
    height scaled by the noise ``sigma[row]`` (vertex time and value: sub-sample and insensitive
    to noise on a flat peak). The runs are found together, and rows of contiguous floats
    (``detect``'s) fitted by the parabola's core."""
    if not jobs:
        return []
    row = [r for r, _ in jobs]
    index = [i for _, i in jobs]
    lo, hi = _runs(ys, row, index, [max(0.2, 10.0 * sigma[r]) for r in row])
    if t.dtype != np.float64 or raw.dtype != np.float64 or raw.strides[1] != raw.itemsize:
        return [_vertex(t, ys[r], raw[r], i, a, b) for r, i, a, b in zip(row, index, lo, hi)]
    return [_vertex(t, ys[r], raw[r], i, a, b, parabola_rows) for r, i, a, b in zip(row, index, lo, hi)]


def _crossing(t, y, i, j) -> float:
    """Time where y crosses zero between samples i and j = i + 1."""
    if y[j] == y[i]:
        return float(t[i])
    return float(t[i] + (t[j] - t[i]) * (-y[i]) / (y[j] - y[i]))


def _entry_time(t, y, k, level) -> float:
    """Time the falling ``y`` crosses ``level`` between samples k - 1 and k (sub-sample)."""
    if k == 0 or y[k - 1] == y[k]:
        return float(t[k])
    return float(t[k - 1] + (t[k] - t[k - 1]) * (y[k - 1] - level) / (y[k - 1] - y[k]))


def _contact(t, tire_s, sigma, start) -> tuple[int | None, float | None, int | None, float | None]:
    """Lift-off and landing (index just after the crossing, crossing time) from the smoothed tire."""
    level = max(0.3, 5.0 * sigma)
    dt = t[1] - t[0]
    air = tire_s < -level
    air[:start] = False
    need = max(1, math.ceil(MIN_AIRTIME_S / dt))
    i = start
    n = t.size
    while i < n:  # runs of air from i on (argmax of a mask: its first True, found without a full scan)
        a = i + int(air[i:].argmax())
        if not air[a]:
            return None, None, None, None
        b = a + int(air[a:].argmin())
        if air[b]:
            b = n
        if b - a >= need or b == n and b - a >= min(need, 2):
            k = a  # back to the first of the negative samples before the run (from start on)
            while k > start:
                lo = max(start, k - 64)
                dry = (~(tire_s[lo:k] < 0)).nonzero()[0]
                if dry.size:
                    k = lo + int(dry[-1]) + 1
                    break
                k = lo
            lift_t = _crossing(t, tire_s, k - 1, k) if k > 0 else float(t[k])
            if b == n:
                return k, lift_t, None, None
            up = tire_s[b:] >= 0
            m = int(up.argmax())
            if not up[m]:
                return k, lift_t, None, None
            m += b
            return k, lift_t, m, _crossing(t, tire_s, m - 1, m)
        i = b
    return None, None, None, None


def _window_index(y, lo, hi, kind) -> int | None:
    """The sample of the extreme (``kind`` "max" or "min") of ``y`` in the window ``lo``..``hi``,
    None when it is at the window's edge (monotone there: no extreme of this signal in it)."""
    lo, hi = max(int(lo), 0), min(int(hi), y.size - 1)
    if hi - lo < 2:
        return None
    seg = y[lo:hi + 1]
    k = int(seg.argmax() if kind == "max" else seg.argmin())
    if (k == 0 and lo > 0) or k == seg.size - 1:
        return None
    return lo + k


def detect(signals: Mapping[str, np.ndarray], start_s: float = 0.0) -> Events:
    """Events of one run or record: ``signals`` has ``time_s``, ``sled_mm``, ``fork_mm``,
    ``tire_mm`` on a uniform grid, t = 0 at tire touch. Only t >= ``start_s`` is used."""
    t_all = np.asarray(signals["time_s"], float)
    steps = t_all[1:] - t_all[:-1] if t_all.ndim == 1 else np.zeros(0)
    # time that never goes back (the usual record): t >= start_s is a slice, as is the last REST_WINDOW_S
    ordered = bool(steps.size and steps.min() >= 0.0)
    if ordered:
        first = int(t_all.searchsorted(start_s - 1e-12))
        keep = slice(first, None)
        t, steps = t_all[first:], steps[first:]
    else:
        keep = t_all >= start_s - 1e-12
        t = t_all[keep]
        steps = t[1:] - t[:-1]
    if t.size < 20:
        raise EventsError(f"{t.size} samples after touch, too few to find the events (at least 20; "
                          f"a longer --duration)")
    # np.median(np.diff(t)) (reordering steps); with NaN among them, as np.median takes it
    dt = float(median_in_place(steps) if ordered else np.median(steps))
    # the signals as the rows of one array (raw), smoothed as the rows of another (sm)
    rows = np.empty((len(SIGNALS), t.size))
    for j, s in enumerate(SIGNALS):
        values = np.asarray(signals[f"{s}_mm"], float)
        # (the boolean mask says when the lengths differ)
        rows[j] = values[keep if values.shape == t_all.shape else t_all >= start_s - 1e-12]
    raw = dict(zip(SIGNALS, rows))
    noise = dict(zip(SIGNALS, noise_sigmas(rows)))
    width = smooth_width(dt, SMOOTH_S)
    smoothed = np.empty_like(rows)
    for j in range(len(SIGNALS)):
        smooth_into(rows[j], width, smoothed[j])
    sm = dict(zip(SIGNALS, smoothed))
    flags: list[str] = []
    none = {e: None for e in EVENTS}
    out = {s: dict(none) for s in SIGNALS}

    lift_i, lift_t, land_i, land_t = _contact(t, sm["tire"], noise["tire"], 0)
    sled = sm["sled"]
    prominence = max(0.5, 6.0 * noise["sled"], PROMINENCE_FRACTION * float(sled.max() - sled.min()))
    peaks, valleys = (found.tolist() for found in peaks_and_valleys(sled, prominence))

    def first_after(indices, i):
        k = bisect_right(indices, i)  # indices ascending
        return indices[k] if k < len(indices) else None

    # sled pattern (indices)
    idx: dict[str, int | None] = dict.fromkeys(("peak1", "topping", "peak2", "valley1", "peak3"))
    rebound = None
    if lift_i is not None:
        idx["peak1"] = int(np.argmax(sled[:lift_i + 1]))
        if idx["peak1"] in (0, lift_i):
            idx["peak1"] = None
        end_air = land_i if land_i is not None else t.size - 1
        idx["topping"] = lift_i + int(np.argmin(sled[lift_i:end_air + 1]))
        if land_i is not None:
            idx["peak2"] = first_after(peaks, land_i)
    else:
        flags.append("never lifts off")
        idx["peak1"] = first_after(peaks, 0)
        if idx["peak1"] is not None:
            rebound = first_after(valleys, idx["peak1"])
            if rebound is not None:
                idx["peak2"] = first_after(peaks, rebound)
    if lift_i is not None and land_i is None:
        flags.append("does not land before the record ends")
    if idx["peak2"] is not None:
        idx["valley1"] = first_after(valleys, idx["peak2"])
    if idx["valley1"] is not None:
        idx["peak3"] = first_after(peaks, idx["valley1"])
    next_valley = first_after(valleys, idx["peak3"]) if idx["peak3"] is not None else None

    # the extremes to refine (all together, at the end): (signal, event) -> (row, sample)
    jobs: dict[tuple[str, str], tuple[int, int]] = {}
    for name in ("peak1", "topping", "peak2", "valley1", "peak3"):
        if idx[name] is not None:
            jobs["sled", name] = (SIGNALS.index("sled"), idx[name])

    def mid(a, b):
        return None if a is None or b is None else (a + b) // 2

    last = t.size - 1
    windows: dict[str, tuple[int, int, str] | None] = {}
    # Peak 1: from touch to lift-off (or halfway to the rebound valley)
    if idx["peak1"] is not None:
        windows["peak1"] = (0, lift_i if lift_i is not None else (mid(idx["peak1"], rebound) or last), "max")
    if idx["topping"] is not None:
        windows["topping"] = (lift_i, land_i if land_i is not None else last, "min")
    if idx["peak2"] is not None:
        lo = land_i if land_i is not None else mid(rebound, idx["peak2"])
        windows["peak2"] = (lo, mid(idx["peak2"], idx["valley1"]) or last, "max")
    if idx["valley1"] is not None:
        windows["valley1"] = (mid(idx["peak2"], idx["valley1"]), mid(idx["valley1"], idx["peak3"]) or last, "min")
    if idx["peak3"] is not None:
        windows["peak3"] = (mid(idx["valley1"], idx["peak3"]), mid(idx["peak3"], next_valley) or last, "max")
    for name, window in windows.items():
        lo, hi, kind = window
        for s in ("fork", "tire"):
            row = SIGNALS.index(s)
            if name == "topping" and s == "fork":  # the moment it reaches full extension
                start = idx["peak1"] if idx["peak1"] is not None else lo
                seg = sm[s][start:hi + 1]
                lowest = float(seg.min())
                level = lowest + max(TOP_BAND_MM, 5.0 * noise[s])
                k = start + int((seg <= level).argmax())
                out[s][name] = Event(_entry_time(t, sm[s], k, level), lowest)
            elif name == "topping":  # the lowest point in the air
                jobs[s, name] = (row, lo + int(sm[s][lo:hi + 1].argmin()))
            else:
                k = _window_index(sm[s], lo, hi, kind)
                if k is not None:
                    jobs[s, name] = (row, k)
    refined = _refine_all(t, smoothed, rows, [noise[s] for s in SIGNALS], list(jobs.values()))
    for (s, name), event in zip(jobs, refined):
        out[s][name] = event

    # rest
    window = slice(int(t.searchsorted(t[-1] - REST_WINDOW_S)), None) if ordered else t >= t[-1] - REST_WINDOW_S
    last_sm = smoothed[:, window]
    motion = dict(zip(SIGNALS, (last_sm.max(axis=1) - last_sm.min(axis=1)).tolist()))  # np.ptp of each
    # the sled decides (as in mtbmj.drop.summary): friction lets the fork creep by a fraction of a mm
    at_rest = bool(t[-1] >= REST_WINDOW_S and motion["sled"] <= REST_TOLERANCE_MM + 4.0 * noise["sled"])
    if at_rest:
        # np.mean of each (signal by signal: the sums of a 2-d array's rows may be taken in another order)
        values = np.array([np.add.reduce(row) / row.size for row in (raw[s][window] for s in SIGNALS)])
        bands = np.array([SETTLE_BAND_MM + 4.0 * noise[s] for s in SIGNALS])
        outside = np.abs(smoothed - values[:, None]) > bands[:, None]
        back = outside[:, ::-1].argmax(axis=1).tolist()  # the last sample outside the band, counted from the end
        for j, (s, value, k) in enumerate(zip(SIGNALS, values.tolist(), back)):
            settle = float(t[min(last - k + 1, last)]) if outside[j, last - k] else float(t[0])
            out[s]["rest"] = Event(settle, value)
    else:
        flags.append(f"never comes to rest (sled still moves {motion['sled']:.1f} mm in the last "
                     f"{REST_WINDOW_S:g} s)")
    missing = [LABELS[e] for e in ("peak1", "peak2", "valley1", "peak3")
               if any(out[s][e] is None for s in SIGNALS)]
    if missing:
        flags.append("no " + ", ".join(missing) + " in " +
                     ("all signals" if all(all(out[s][LABELS_INV[m]] is None for s in SIGNALS) for m in missing)
                      else "some signals"))
    return Events(signals=out, lift_off_s=lift_t, landing_s=land_t, at_rest=at_rest, rest_motion_mm=motion,
                  noise_mm=noise, end_s=float(t[-1]), flags=flags)


LABELS_INV = {v: k for k, v in LABELS.items()}


def detect_result(result) -> Events:
    """Events of a ``DropResult`` from its logged (1 kHz) signals."""
    return detect(result.signals)

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

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from mtbmj.drop.peaks import find_peaks, noise_sigma, parabola, smooth
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


def _refine(t: np.ndarray, y: np.ndarray, i: int, raw: np.ndarray | None = None, sigma: float = 0.0) -> Event:
    """The extreme near sample ``i`` of the smoothed ``y``, refined by a least-squares parabola
    through the raw samples around it that lie within a noise-scaled height of the extreme
    (vertex time and value: sub-sample and insensitive to noise on a flat peak)."""
    data = y if raw is None else raw
    height = max(0.2, 10.0 * sigma)
    lo = hi = i
    while lo > 0 and abs(y[lo - 1] - y[i]) <= height:
        lo -= 1
    while hi < y.size - 1 and abs(y[hi + 1] - y[i]) <= height:
        hi += 1
    lo, hi = max(0, min(lo, i - 2)), min(y.size - 1, max(hi, i + 2))
    if hi - lo >= 4:
        tt = t[lo:hi + 1] - t[i]
        a, b, c = parabola(tt, data[lo:hi + 1])
        if a != 0:
            vertex = -b / (2 * a)
            if tt[0] <= vertex <= tt[-1]:
                return Event(float(t[i] + vertex), float(c - b * b / (4 * a)))
    return Event(float(t[i]), float(y[i]))


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
    need = max(1, int(np.ceil(MIN_AIRTIME_S / dt)))
    i = start
    n = t.size
    while i < n:
        run = np.flatnonzero(air[i:])
        if not run.size:
            return None, None, None, None
        a = i + int(run[0])
        back = np.flatnonzero(~air[a:])
        b = a + int(back[0]) if back.size else n
        if b - a >= need or b == n and b - a >= min(need, 2):
            k = a
            while k > start and tire_s[k - 1] < 0:
                k -= 1
            lift_t = _crossing(t, tire_s, k - 1, k) if k > 0 else float(t[k])
            up = np.flatnonzero(tire_s[b:] >= 0) if b < n else np.array([], int)
            if not up.size:
                return k, lift_t, None, None
            m = b + int(up[0])
            return k, lift_t, m, _crossing(t, tire_s, m - 1, m)
        i = b
    return None, None, None, None


def _window_extreme(t, y, lo, hi, kind, raw=None, sigma=0.0) -> Event | None:
    lo, hi = max(int(lo), 0), min(int(hi), y.size - 1)
    if hi - lo < 2:
        return None
    seg = y[lo:hi + 1]
    k = int(np.argmax(seg) if kind == "max" else np.argmin(seg))
    if (k == 0 and lo > 0) or k == seg.size - 1:
        return None  # monotone here: no extreme of this signal in the window
    return _refine(t, y, lo + k, raw, sigma)


def detect(signals: Mapping[str, np.ndarray], start_s: float = 0.0) -> Events:
    """Events of one run or record: ``signals`` has ``time_s``, ``sled_mm``, ``fork_mm``,
    ``tire_mm`` on a uniform grid, t = 0 at tire touch. Only t >= ``start_s`` is used."""
    t_all = np.asarray(signals["time_s"], float)
    keep = t_all >= start_s - 1e-12
    t = t_all[keep]
    if t.size < 20:
        raise EventsError(f"{t.size} samples after touch, too few to find the events (at least 20; "
                          f"a longer --duration)")
    dt = float(np.median(np.diff(t)))
    raw = {s: np.asarray(signals[f"{s}_mm"], float)[keep] for s in SIGNALS}
    noise = {s: noise_sigma(raw[s]) for s in SIGNALS}
    sm = {s: smooth(raw[s], dt, SMOOTH_S) for s in SIGNALS}
    flags: list[str] = []
    none = {e: None for e in EVENTS}
    out = {s: dict(none) for s in SIGNALS}

    lift_i, lift_t, land_i, land_t = _contact(t, sm["tire"], noise["tire"], 0)
    sled = sm["sled"]
    prominence = max(0.5, 6.0 * noise["sled"], PROMINENCE_FRACTION * float(np.ptp(sled)))
    peaks = find_peaks(sled, prominence)
    valleys = find_peaks(-sled, prominence)

    def first_after(indices, i):
        later = indices[indices > i]
        return int(later[0]) if later.size else None

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

    for name in ("peak1", "topping", "peak2", "valley1", "peak3"):
        if idx[name] is not None:
            out["sled"][name] = _refine(t, sled, idx[name], raw["sled"], noise["sled"])

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
            if name == "topping" and s == "fork":  # the moment it reaches full extension
                start = idx["peak1"] if idx["peak1"] is not None else lo
                seg = sm[s][start:hi + 1]
                lowest = float(np.min(seg))
                k = start + int(np.argmax(seg <= lowest + max(TOP_BAND_MM, 5.0 * noise[s])))
                out[s][name] = Event(_entry_time(t, sm[s], k, lowest + max(TOP_BAND_MM, 5.0 * noise[s])), lowest)
            elif name == "topping":  # the lowest point in the air
                seg = sm[s][lo:hi + 1]
                k = lo + int(np.argmin(seg))
                out[s][name] = _refine(t, sm[s], k, raw[s], noise[s])
            else:
                out[s][name] = _window_extreme(t, sm[s], lo, hi, kind, raw[s], noise[s])

    # rest
    window = t >= t[-1] - REST_WINDOW_S
    motion = {s: float(np.ptp(sm[s][window])) for s in SIGNALS}
    # the sled decides (as in mtbmj.drop.summary): friction lets the fork creep by a fraction of a mm
    at_rest = bool(t[-1] >= REST_WINDOW_S and motion["sled"] <= REST_TOLERANCE_MM + 4.0 * noise["sled"])
    if at_rest:
        for s in SIGNALS:
            value = float(np.mean(raw[s][window]))
            band = SETTLE_BAND_MM + 4.0 * noise[s]
            outside = np.flatnonzero(np.abs(sm[s] - value) > band)
            settle = float(t[min(int(outside[-1]) + 1, last)]) if outside.size else float(t[0])
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

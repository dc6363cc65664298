"""A bike run's set speed along the terrain (``run_bike(..., speed_profile=(x_m, v_m_per_s))``): the rider's
drive holds the speed the profile gives where the front axle is, not one speed for the whole run.

A recorded ride is not ridden at one speed (the shared rides' reconstructed speeds run from 1.3 to 7.3 m/s
within one ride), and the speed sets how hard each bump is met: the same terrain ridden at the ride's
median speed over-drives its slow stretches and under-drives its fast ones. The reconstruction lays the
terrain out along the distance its speed profile integrates to (``mtbmj.ride.reconstruct``), so the
speed at each place is known where the terrain is.

How: the run is stepped in chunks (``mtbmj.runpath.loop.chunked``) of ``UPDATE_S`` of simulated time
on a run at one step; under a refinement plan (the bike's, wherever its stepping refines near the stops,
so nearly always) the plan's own chunks set the updates instead: ``REFINE_CHUNK`` coarse steps, 0.512 s
at the 0.5 ms step, fewer after a fine stretch (measured; not mended, as mending it changes every
answer made with a profile). Between chunks the set speed is the profile's at the front axle's place (the frame's x from the
state, the front axle's offset at rest: the pitch's few millimetres left out). The drive then holds it
within its limits (``controllers.drive.drive_force``: ``drive.push_N``, ``power_W``, ``brake_N``): where
the ride accelerated harder than those allow, the run lags, and says nothing of it here (the run's own
speed is in its output). The passive and the active rider's drive hold a set speed this way (the active
rider's callback, ``mtbmj.bike.rider_control.RiderCallback.set_speed``, passes it to the drive it wraps and to
its controller's look-ahead before an edge); a pedalling rider's speed is what the pedals make of it."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.errors import ConfigError

UPDATE_S = 0.25  # s between updates of the set speed on a run at one step (see the module doc; 0.1: 8 % slower)
SPEED_RANGE = (0.3, 30.0)  # m/s: a profile beyond is not a ride's
SPAN_PER_LENGTH = 10.0  # a profile with fewer than two places along a terrain is taken where the places around it
# span at most this many terrain lengths (places every 5 m, a 1 m section) and at most SPAN_MAX_M: a profile in mm
SPAN_MAX_M = 50.0  # spans 1000 times its metres, so on a long terrain only an absolute cap tells it (places every 10 m
# of a 1 km trail written in mm span 10000 "m" about it, 10 terrain lengths)


@dataclass(frozen=True)
class SpeedProfile:
    """The set speed ``v`` (m/s) at each place ``x`` (m, the terrain's x, increasing); held past the ends."""

    x: np.ndarray
    v: np.ndarray

    @classmethod
    def checked(cls, profile, said: str = "speed_profile") -> SpeedProfile:
        """``profile`` (x_m, v_m_per_s) as a :class:`SpeedProfile`; a ``ConfigError`` naming what is wrong,
        after ``said`` (what the caller calls the profile)."""
        try:
            x, v = (np.asarray(a, float) for a in profile)
        except (TypeError, ValueError):
            raise ConfigError(f"{said}: give two sequences, the places (m) and the speeds (m/s)") from None
        if x.ndim != 1 or x.shape != v.shape or x.size < 2:
            raise ConfigError(f"{said}: places and speeds of one length, at least 2 (got {x.shape} and {v.shape})")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(v))):
            raise ConfigError(f"{said}: a place or a speed is not a number")
        if np.any(np.diff(x) <= 0.0):
            i = int(np.argmax(np.diff(x) <= 0.0)) + 1
            raise ConfigError(f"{said}: the places must increase (place {i}: {x[i]:g} m after {x[i - 1]:g} m)")
        lo, hi = SPEED_RANGE
        if np.any(v < lo) or np.any(v > hi):
            bad = float(v[np.argmax((v < lo) | (v > hi))])
            raise ConfigError(f"{said}: a speed of {bad:g} m/s is outside {lo:g}-{hi:g} m/s (a ride's)")
        return cls(x, v)

    def at(self, x: float) -> float:
        return float(np.interp(x, self.x, self.v))

    def along(self, start: float, end: float, said: str = "speed_profile") -> SpeedProfile:
        """Itself where at least two of its places lie along the terrain ``start``..``end`` (m), or where its
        places bracket the terrain within a span of at most ``SPAN_PER_LENGTH`` terrain lengths and ``SPAN_MAX_M`` (a trail's
        profile, a short section of it ridden); else a ``ConfigError`` after ``said`` (held flat past its
        ends, or one segment stretched over it, it would set about one speed, silently: distances in mm,
        another terrain's profile)."""
        inside = np.flatnonzero((self.x >= start) & (self.x <= end))
        below, above = self.x[self.x <= start], self.x[self.x >= end]
        bracketed = (below.size and above.size
                     and above[0] - below[-1] <= min(SPAN_PER_LENGTH * max(end - start, 1e-9), SPAN_MAX_M))
        if inside.size < 2 and not bracketed:
            raise ConfigError(f"{said}: {'only place ' + str(inside[0] + 1) if inside.size else 'no place'} of "
                              f"{self.x.size} lies along the terrain ({start:g}-{end:g} m; its places run "
                              f"{self.x[0]:g}-{self.x[-1]:g} m): distances in mm, or another terrain's profile? (one "
                              f"speed for the whole run: --speed)")
        return self


def read_csv(path) -> SpeedProfile:
    """A speed profile from a CSV of exactly the columns ``distance_m`` (the terrain's x, as a terrain CSV's)
    and ``speed_m_per_s`` (``mtbmj reconstruct`` writes one, ``speed.csv``, beside its ``terrain.csv``); a
    ``ConfigError`` naming the file and what is wrong."""
    from mtbmj.errors import MtbmjError
    from mtbmj.measured.records import read_record

    try:
        rec = read_record(path)
    except MtbmjError as exc:
        raise ConfigError(f"--speed-profile: {exc}") from None
    if rec.units != {"distance": "m", "speed": "m_per_s"}:
        have = ", ".join(f"{q}_{u}" for q, u in rec.units.items())
        over_time = ": a speed over time, what reconstruct and advise --speed-csv take" if "time" in rec.units else ""
        raise ConfigError(f"--speed-profile: {path}: a speed profile needs exactly the columns distance_m, "
                          f"speed_m_per_s (has {have}{over_time})")
    return SpeedProfile.checked((rec["distance"], rec["speed"]), f"--speed-profile: {path}")


def steering(profile: SpeedProfile, callback, watch, x_col: int, x_offset: float):
    """The run loop's ``stop`` (``mtbmj.runpath.loop.stepped``) for a run on ``profile``: after each chunk the
    callback's set speed (``set_speed``) is the profile's at the front axle (state column ``x_col`` plus
    ``x_offset``), then the run's own ``watch`` (its crash check, or None) decides whether it ends."""

    def stop(first, states, sensors):
        if len(states):
            callback.set_speed(profile.at(float(states[-1, x_col]) + x_offset))
        return None if watch is None else watch(first, states, sensors)

    return stop


__all__ = ["SPAN_MAX_M", "SPAN_PER_LENGTH", "SpeedProfile", "UPDATE_S", "read_csv", "steering"]

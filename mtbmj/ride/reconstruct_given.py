"""The speed along a ride given by the rider (``mtbmj reconstruct RIDE --speed M_PER_S`` or ``--speed-csv
FILE``; ``mtbmj.ride.reconstruct.reconstruct(record, bike, speed=...)``), used where the record holds none
and, where given, in place of the lag's: a GPS track or a bike computer (time and speed on the ride's
clock) or a known steady speed.

A CSV has the columns ``time_s`` and ``speed_m_per_s`` (any unit ``mtbmj.measured.records`` reads, the
quantities ``time`` and ``speed``), its time increasing, each speed from 0 to the plausible top of
``--speed`` (``mtbmj.limits``: 30 m/s), and it covers the ride (its first row at most ``COVER_S``
after the ride's first sample, its last at most ``COVER_S`` before the ride's last; held flat past its
ends), at least two of its rows within the ride (not a time in ms under ``time_s``) and a speed of at least
``MIN_USED`` somewhere on it (not a column of zeros), its median over the ride at most ``FAST`` (not km/h
read as m/s). It is interpolated linearly onto the ride's samples. A row that breaks one of these is refused
in one line naming the file and the row (the data rows counted from 1), before any work. A speed
below ``MIN_USED`` (standing) is taken as ``MIN_USED`` for the rear's lag and the distance (the lag
would be endless). The given speed is laid out in the lag's windows (their mean speed each, kind
"given") so the summary lists it as it lists the lag's; the profile used is the given one itself.

The lag's speed is still sought (``mtbmj.ride.reconstruct_speed``, strict and tracked windows): where it
gives one, the two are compared window by window (the given speed's mean over the window against the
window's lag speed) and both are reported, never one silently preferred; the given one is used, and
the speed is not found again from the rear predicted (that would replace it). Where the lag gives none,
its reason is reported.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtbmj.errors import ConfigError
from mtbmj.ride.reconstruct_speed import WINDOW_HOP, WINDOW_S, ReconstructError

COVER_S = 1.0  # s a speed CSV may start after the ride's first sample or end before its last (a GPS's 1 Hz step)
MIN_USED = 0.3  # m/s: a given speed below this (standing) is taken as it (``--speed``'s plausible low)
FAST = 20.0  # m/s: a trail ridden at a median over this (72 km/h) is no ride: km/h read as m/s
AGREE = 0.10  # the given speed and the lag's within this share of the lag's (median over windows): they agree


def _top() -> float:
    from mtbmj.limits import ARGUMENTS

    return float(ARGUMENTS["--speed"].plausible[1])


@dataclass(frozen=True)
class GivenSpeed:
    """A speed given by the rider: ``speed`` (m/s) at ``time_s`` (s, the ride's clock), or one speed
    (``time_s`` None); ``said``: how it was given, in words."""

    time_s: np.ndarray | None
    speed: np.ndarray
    said: str
    column: str = "speed_m_per_s"  # the CSV's speed column (a speed in another unit read into m/s)

    def at(self, t) -> np.ndarray:
        """The given speed at the times ``t`` (s, the ride's clock), at least ``MIN_USED``."""
        t = np.asarray(t, float)
        v = np.full(t.shape, float(self.speed[0])) if self.time_s is None else np.interp(t, self.time_s, self.speed)
        return np.maximum(v, MIN_USED)

    def check_length(self, t, name: str) -> None:
        """Refuse (one line) a ride (samples ``t``, s) shorter than one speed window (``WINDOW_S``): the given
        speed is laid out and its rear checked in such windows (the lag's longer minimum does not hold: where
        the lag gives none, that is reported beside the speed given)."""
        length = float(len(t) * (t[1] - t[0])) if len(t) > 1 else 0.0  # samples times their step, as the windows count
        if length < WINDOW_S - 1e-9:
            raise ReconstructError(f"{name}: the ride is {length:.3g} s: a reconstruction at the speed given "
                                   f"({self.said}) needs at least one {WINDOW_S:g} s window of it to check the rear in")

    def check_covers(self, t0: float, t1: float, name: str = "", short: str = "") -> None:
        """Refuse (one line) a CSV whose time does not cover the ride's ``t0``..``t1`` (s), that holds
        fewer than two rows within it (a time in ms under ``time_s``), whose speed is below ``MIN_USED``
        over the whole ride (a column of zeros: the bike never moves) or its median above ``FAST`` (km/h);
        ``short``: words added where it ends before the ride's end (why a shorter run does not do)."""
        if self.time_s is None:
            return
        t, v = self.time_s, self.speed
        ride = f"{name + ' runs' if name else 'the ride runs'} {t0:g}-{t1:g} s"
        if t[0] > t0 + COVER_S:
            after = (" (all of it after the ride's end: a clock of the day? the time is the ride's clock, "
                     f"{t0:g} s at its first sample)") if t[0] > t1 else ""
            raise ConfigError(f"{self.said}: row 1 (time {t[0]:g} s) starts after the ride's start: {ride}; "
                              f"the speed must cover the ride (within {COVER_S:g} s){after}")
        if t[-1] < t1 - COVER_S:
            raise ConfigError(f"{self.said}: row {t.size} (time {t[-1]:g} s), its last, ends "
                              f"before the ride's end: {ride}; the speed must cover the ride (within {COVER_S:g} s){short}")
        inside = np.flatnonzero((t >= t0 - COVER_S) & (t <= t1 + COVER_S))
        if inside.size < 2:
            raise ConfigError(f"{self.said}: {'only row ' + str(inside[0] + 1) if inside.size else 'no row'} of "
                              f"{t.size} falls within the ride ({ride}), its rows {float(np.median(np.diff(t))):g} s "
                              f"apart (median): a time in ms under time_s? (one speed for the whole ride: --speed)")
        on_ride = np.interp(np.concatenate([np.linspace(t0, t1, 1001), t[inside]]), t, v)
        if on_ride.max() < MIN_USED:
            raise ConfigError(f"{self.said}: every speed over the ride ({ride}) is below {MIN_USED:g} m/s (at most "
                              f"{on_ride.max():g} m/s): the bike never moves in it (a column of zeros?); the terrain "
                              f"is found along the distance ridden")
        median = float(np.median(np.interp(np.linspace(t0, t1, 1001), t, v)))
        if median > FAST:
            raise ConfigError(f"{self.said}: column {self.column}: a median of {median:.3g} m/s over the ride ({ride}) "
                              f"is no trail ridden (at most {FAST:g} m/s, {3.6 * FAST:g} km/h): km/h under "
                              f"{self.column}? ({median / 3.6:.3g} m/s if so: write it in m/s)")


def checked(time_s, speed, said: str, column: str = "speed_m_per_s") -> GivenSpeed:
    """A speed over time (``time_s`` s, ``speed`` m/s; ``column`` the CSV's name for it) checked row by row: a
    ``ConfigError`` after ``said`` naming the first row (from 1) that is not plausible."""
    t, v = np.asarray(time_s, float).ravel(), np.asarray(speed, float).ravel()
    if t.size != v.size or t.size < 2:
        raise ConfigError(f"{said}: {t.size} time(s) and {v.size} speed(s): a speed over time needs at least two "
                          f"rows of both")
    bad = np.flatnonzero(~(np.isfinite(t) & np.isfinite(v)))
    if bad.size:
        raise ConfigError(f"{said}: row {bad[0] + 1}: a time or a speed that is not a number")
    back = np.flatnonzero(np.diff(t) <= 0.0)
    if back.size:
        i = int(back[0]) + 1
        raise ConfigError(f"{said}: row {i + 1}: time {t[i]:g} s after {t[i - 1]:g} s in row {i}: the time must "
                          f"increase")
    top = _top()
    out = np.flatnonzero((v < 0.0) | (v > top))
    if out.size:
        i = int(out[0])
        why = "negative" if v[i] < 0 else "no bike is ridden so fast" + (
            f"; km/h? {v[i] / 3.6:.3g} m/s if so: write it in m/s" if v[i] <= 3.6 * top else "")
        raise ConfigError(f"{said}: row {i + 1} (time {t[i]:g} s): speed {v[i]:.3g} m/s is outside 0-{top:g} m/s "
                          f"({why})")
    return GivenSpeed(t, v, said, column)


def constant(v: float) -> GivenSpeed:
    """One speed (m/s) for the whole ride; a ``ConfigError`` where it is not a ridden one (> 0, at most 30 m/s,
    the fastest a bike is ridden; a whole ride at most ``FAST``: km/h typed)."""
    top = _top()
    if not (isinstance(v, (int, float)) and math.isfinite(v) and 0.0 < v <= top):
        raise ConfigError(f"--speed {v!r}: a ride's speed given is a number above 0 and at most {top:g} m/s, the "
                          f"fastest a bike is ridden (a run of the model's own, mtbmj bike or roll, may go faster)")
    if v > FAST:  # a whole ride at it is no trail ridden (the CSV's median is held to the same)
        raise ConfigError(f"--speed {v:g}: a whole ride at over {FAST:g} m/s ({3.6 * FAST:g} km/h) is no trail ridden: "
                          f"km/h? ({v / 3.6:.3g} m/s if so: give it in m/s)")
    return GivenSpeed(None, np.array([float(v)]), f"a constant {float(v):g} m/s")


def read_csv(path) -> GivenSpeed:
    """A speed over time from a CSV (the module doc); a ``ConfigError`` naming the file, and the row where one
    is not plausible."""
    from mtbmj.errors import MtbmjError
    from mtbmj.measured.records import read_record

    said = f"--speed-csv {path}"
    try:
        rec = read_record(path)
    except MtbmjError as exc:
        raise ConfigError(f"--speed-csv: {exc}") from None
    if set(rec.units) != {"time", "speed"}:
        have = ", ".join(f"{q}_{u}" for q, u in rec.units.items())
        along = (": a speed along the distance, what mtbmj bike --speed-profile takes" if "distance" in rec.units
                 else "")
        raise ConfigError(f"{said}: a speed over time needs exactly the columns time_s and speed_m_per_s (has {have}"
                          f"{along})")
    return checked(rec["time"], rec["speed"], said, column=f"speed_{rec.units['speed']}")


def given(speed) -> GivenSpeed:
    """``reconstruct``'s ``speed=``: a number (m/s, constant), a path of a CSV, (time_s, speed_m_per_s)
    sequences, or a :class:`GivenSpeed`."""
    if isinstance(speed, GivenSpeed):
        return speed
    import numbers

    if isinstance(speed, numbers.Real) and not isinstance(speed, bool):
        return constant(float(speed))
    if isinstance(speed, str) or hasattr(speed, "__fspath__"):
        return read_csv(speed)
    try:
        time_s, v = speed
    except (TypeError, ValueError):
        raise ConfigError("speed: give a number (m/s), a CSV's path, or (time_s, speed_m_per_s)") from None
    return checked(time_s, v, "speed")


def compared(speed_at, lag, window_s_default: float = WINDOW_S) -> dict:
    """The given speed (``speed_at``: a function of the reconstructed ride's time) beside the lag's
    (``lag``: ``reconstruct_speed``'s answer, or the ``ReconstructError`` that refused it): per lag window
    with a speed, the given speed's mean over it against it."""
    if isinstance(lag, Exception):
        return {"windows_compared": 0, "lag_gives_none": str(lag)}
    w = lag.get("window_s", window_s_default)
    pairs = [(float(np.mean(speed_at(np.linspace(a, a + w, 51)))), v, kind)
             for (a, v, _), kind in zip(lag["windows"], lag.get("kinds") or [None] * len(lag["windows"])) if v is not None]
    g, v = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
    ratio = float(np.median(g / v))
    return {"windows_compared": len(pairs), "windows_tracked": sum(p[2] == "tracked" for p in pairs),
            "lag_median_m_per_s": float(np.median(v)), "given_median_m_per_s": float(np.median(g)),
            "given_over_lag_median": ratio, "apart_median_m_per_s": float(np.median(np.abs(g - v))),
            "apart_max_m_per_s": float(np.max(np.abs(g - v))),
            "windows_apart_over_percent": 100.0 * AGREE,
            "windows_apart_over": int(np.sum(np.abs(g / v - 1.0) > AGREE)),
            "agree": bool(abs(ratio - 1.0) <= AGREE)}


def profile(speed: GivenSpeed, t, offset: float, wheelbase: float, lag) -> dict:
    """The speed dict ``reconstruct`` uses (``reconstruct_speed``'s keys) from the given ``speed`` on the
    ride's samples ``t`` (s from ``offset`` s of the record: a part of it reconstructed), laid out in the
    lag's windows, with the lag's answer (or refusal) ``lag`` compared ("given": how it was given,
    "lag": :func:`compared`, "lag_profile": the lag's answer)."""
    t = np.asarray(t, float)

    def at(time):
        return speed.at(np.asarray(time, float) + offset)

    hop = WINDOW_HOP * WINDOW_S
    starts = np.arange(0.0, max(float(t[-1] - t[0]), hop), hop) + float(t[0])
    windows = [(float(a), float(np.mean(at(np.linspace(a, a + WINDOW_S, 51)))), math.nan) for a in starts]
    median = float(np.median(at(t)))
    return {"speed_m_per_s": median, "lag_s": wheelbase / median, "windows": windows, "sd": [None] * len(windows),
            "why": [None] * len(windows), "wheelbase_m": wheelbase, "window_s": WINDOW_S,
            "sources": ["given"] * len(windows), "kinds": ["given"] * len(windows), "speed_at": at,
            "from": f"given: {speed.said}", "given": speed.said, "lag": compared(at, lag),
            "lag_profile": None if isinstance(lag, Exception) else lag,
            "found_from": f"given by the rider ({speed.said}), used as given; the lag between the two ends "
                          f"sought beside it and compared (speed_given.lag)"}


def summary(speed: dict) -> dict:
    """``reconstruction.json``'s ``speed_given``: how the speed was given and the lag's beside it ({} where
    the speed was not given)."""
    if "given" not in speed:
        return {}
    return {"speed_given": {"given": speed["given"], "used": True, "lag": speed["lag"],
                            "agree_within_percent": 100.0 * AGREE}}


def words(speed: dict) -> str:
    """The line's words on a given speed and the lag's beside it."""
    c = speed["lag"]
    out = f"speed given ({speed['given']}, used), {speed['speed_m_per_s']:.2f} m/s median; "
    if not c["windows_compared"]:
        return out + f"the lag gives none: {c['lag_gives_none']}"
    return out + (f"the lag gives {c['lag_median_m_per_s']:.2f} m/s median in {c['windows_compared']} windows "
                  f"({c['windows_tracked']} tracked): the given {c['given_over_lag_median']:.2f} times the lag's "
                  f"(median), {c['apart_median_m_per_s']:.2f} m/s apart (median, at most "
                  f"{c['apart_max_m_per_s']:.2f}), {c['windows_apart_over']} window(s) over "
                  f"{c['windows_apart_over_percent']:g} % apart: they "
                  + ("agree" if c["agree"] else f"DISAGREE by over {c['windows_apart_over_percent']:g} %"))


def speed_panel(a, rec) -> None:
    """The speed along the ride of ``rec`` (a ``Reconstruction``): each window that gave one at its time
    with two standard errors, the profile between them (what the distance is integrated from), and
    where the speed was found again, the first estimate's windows (the two ends' lag) beside them;
    where the speed was given, the given profile and the lag's windows beside it."""
    sp = rec.speed
    given = "given" in sp
    a.plot(rec.t, sp["speed_at"](rec.t), color="0.3",
           label=f"speed given: {sp['given']} (the distance's)" if given else "speed profile (the distance's)")
    if given:
        stages = [(sp["lag_profile"], "C1", "s", "the two ends' lag, beside")] if sp.get("lag_profile") else []
    else:
        stages = [(sp, "C0", "o", "windows: " + ("the rear predicted aligned" if "first" in sp else
                                                  "the two ends' lag"))]
    if "first" in sp:
        stages.append((sp["first"], "C1", "s", "first estimate: the two ends' lag"))
    for stage, colour, marker, label in stages:
        half = 0.5 * stage["window_s"]
        kinds = stage.get("kinds") or [None] * len(stage["windows"])
        for tracked_only in (False, True):
            pts = [(start + half, v, sd) for (start, v, _), sd, kind in
                   zip(stage["windows"], stage["sd"] or [None] * len(kinds), kinds)
                   if v is not None and (kind == "tracked") == tracked_only]
            if pts:
                a.errorbar([c for c, _, _ in pts], [v for _, v, _ in pts],
                           yerr=[2.0 * (sd or 0.0) for _, _, sd in pts], fmt="x" if tracked_only else marker,
                           color=colour, mfc="none" if stage is not sp else colour, ms=5, capsize=2,
                           label=f"{label}{', tracked' if tracked_only else ''} ({len(pts)}, +-2 standard errors)")
    a.set(xlabel="time (s)", ylabel="speed (m/s)",
          title=f"Speed along the ride: median {sp['speed_m_per_s']:.2f} m/s " + (
              f"(given: {sp['given']})" if given else f"(wheelbase {rec.wheelbase:.3f} m / the lag per window)"))


__all__ = ["GivenSpeed", "COVER_S", "MIN_USED", "FAST", "AGREE", "checked", "constant", "read_csv", "given", "compared",
           "profile", "summary", "words", "speed_panel"]

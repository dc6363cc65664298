"""The speed along a ride from the lag between its two ends (``mtbmj reconstruct``'s first step;
mtbmj/ride/reconstruct.py's module doc says how it is used).

The rear wheel meets what the front met a wheelbase later: the lag that best aligns two series of the
ends (normalised cross-correlation, the peak refined by a parabola) gives v = wheelbase / lag per
window of ``WINDOW_S`` seconds, a window starting every ``WINDOW_HOP`` of one (overlapping: a speed
every 2.5 s, the profile linear between them). A window gives no speed, and says why, where its correlation peak is
below ``MIN_CORRELATION``, has a second peak within ``AMBIGUOUS`` of it, lies at either end of the lags
searched or has its lobe reach an end, where its ``SUB_WINDOWS`` parts do not find their lags within
the best peak or its speed's standard error (from those parts' lags) exceeds ``MAX_SPEED_SD`` of it,
where either end's travel spans less than ``STILL_MM`` (standing), or where the rest of the ride
contradicts it (:func:`drop_unsupported`: both overlapping neighbours against it, or alone and
``FAR`` times off the ride's median). A ride shorter than one window
and the slowest lag searched (:func:`min_seconds`) is refused before any work. Those are the
strict windows; :func:`tracked` fills the gaps near them with a speed tracked through the windows'
correlograms (each window marked "strict" or "tracked" in "kinds", a tracked one with a wider
uncertainty), never where no strict window lies within ``TRACK_ANCHOR_S``.
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.errors import MtbmjError

WINDOW_S = 5.0  # seconds per window of the speed estimate
WINDOW_HOP = 0.5  # a window starts every this share of a window (they overlap): the profile's points
MIN_CORRELATION = 0.3  # a window whose best normalised correlation is below this gives no speed
LAG_HIGHPASS_HZ = 5.0  # travel records high-passed before the lag is sought (the rider's slow motions out)
AMBIGUOUS = 0.9  # a second correlation peak this close to the best leaves the lag undecided
GROUND_HIGHPASS_HZ = 1.0  # the two ends' grounds high-passed before the lag is sought
SPEED_RANGE = (1.0, 15.0)  # m/s the lag is searched for
SUB_WINDOWS = 4  # a window's lag found again in this many parts of it: their spread is its uncertainty
MAX_SPEED_SD = 0.10  # a window whose speed's standard error exceeds this share of it gives no speed
NEIGHBOURS_AGREE = 0.15  # two overlapping neighbours this close (share of their mean) agree on the speed ...
OUTLIER = 0.25  # ... and a window between them this far from their mean gives no speed (drop_unsupported)
FAR = 2.0  # a window no neighbour supports, this many times off the median of the ride's other windows ...
FAR_OTHERS = 3  # ... of at least this many, gives no speed
STILL_MM = 1.0  # a window where either end's travel spans less than this is standing: it gives no speed
REFINE_WINDOW_S = 2.5  # seconds per window of the speed found again from the rear predicted (refine)
REFINE_SPAN = 0.5  # the lag left is searched within +- this share of the first estimate's lag
REFINE_MIN_CORRELATION = 0.5  # a refining window whose best correlation is below this gives no speed
TRACK_ANCHOR_S = 20.0  # a tracked window's centre lies within this many seconds of a strict window's centre
TRACK_MARGIN = 0.30  # a tracked speed is sought within the neighbouring strict windows' speeds widened by this share
TRACK_PENALTY = 20.0  # the tracked path's cost per (change of ln speed)^2 from one window to the next
TRACK_MIN_CORRELATION = 0.2  # a tracked window whose correlation at the path is below this gives no speed
TRACK_SNAP = 0.02  # the path's speed taken to its window's nearest correlation peak within this change of ln speed
TRACK_PARTS = 2  # ... and at least this many of its SUB_WINDOWS parts find their best speed in the range there
TRACK_PARTS_SPAN = 0.05  # ... within this change of ln speed of the window's (a speed changing within it spreads them)
TRACK_SD = 0.10  # a tracked window's standard error, as a share of its speed
TRACK_GRID = 400  # log-spaced speeds over SPEED_RANGE the path runs on


class ReconstructError(MtbmjError):
    """A ride that cannot be reconstructed: one line naming why."""



def min_seconds(wheelbase: float, window_s: float = WINDOW_S) -> float:
    """The shortest ride a speed can be sought in: one window and the slowest lag searched."""
    return window_s + wheelbase / SPEED_RANGE[0]


def check_length(t, wheelbase: float, window_s: float, name: str = "") -> None:
    """Refuse (one line) a record too short for one speed window and the slowest lag searched."""
    dt = float(t[1] - t[0]) if len(t) > 1 else math.nan
    need = min_seconds(wheelbase, window_s)
    if not len(t) > 1 or not (math.isfinite(dt) and dt > 0) or \
            len(t) < int(round(window_s / dt)) + int(math.ceil(wheelbase / SPEED_RANGE[0] / dt)):
        length = len(t) * dt if math.isfinite(dt) else 0.0
        raise ReconstructError(f"{name + ': ' if name else ''}the ride is {length:.1f} s: a speed needs at least one "
                               f"{window_s:g} s window and the slowest lag searched "
                               f"({wheelbase / SPEED_RANGE[0]:.2f} s), {need:.2f} s: no speed estimate")


def _scores(a, b, k_lo: int, k_hi: int, n: int):
    """Normalised correlation of ``a[:n]`` with ``b[k:k + n]`` for k in k_lo..k_hi (each mean
    removed): the products by FFT, each shifted stretch's spread from running sums."""
    from scipy.signal import correlate

    a0 = a[:n] - a[:n].mean()
    aa = float(a0 @ a0)
    seg = np.asarray(b[k_lo:k_hi + n], float)
    seg = seg - seg.mean()  # the sums below lose nothing to a large mean
    num = correlate(seg, a0, mode="valid", method="fft")
    c1 = np.concatenate(([0.0], np.cumsum(seg)))
    c2 = np.concatenate(([0.0], np.cumsum(seg * seg)))
    s1, s2 = c1[n:] - c1[:-n], c2[n:] - c2[:-n]
    bb = np.maximum(s2 - s1 * s1 / n, 0.0)
    den = np.sqrt(aa * bb)
    ok = den > 1e-12 * max(aa, 1e-300) * n
    out = np.zeros(num.size)
    out[ok] = num[ok] / den[ok]
    return out[:k_hi - k_lo + 1]


def _vertex(s, i: int) -> float:
    """The parabola's vertex through s[i-1], s[i], s[i+1], as a shift from i (0 at an edge)."""
    if 0 < i < s.size - 1:
        den = s[i - 1] - 2 * s[i] + s[i + 1]
        return 0.5 * (s[i - 1] - s[i + 1]) / den if den < 0 else 0.0
    return 0.0


def _best(a, b, k_lo: int, k_hi: int, dt: float, min_correlation: float = MIN_CORRELATION):
    """The lag (s) that best aligns ``a[:n]`` with ``b[k:k + n]`` for k in k_lo..k_hi (n = a.size - k_hi):
    (lag s or None, correlation, why none, the lag's standard error s); see :func:`speed_from_lag`."""
    n = a.size - k_hi
    if n < 10:
        return None, 0.0, "too short", None
    s = _scores(a, b, k_lo, k_hi, n)
    i = int(np.argmax(s))
    if i == 0 or i == s.size - 1:  # the best lag at the end of the search: the peak lies outside it
        return None, float(s[i]), "the best lag at the edge of the search", None
    if s[i] < min_correlation:
        return None, float(s[i]), f"best correlation below {min_correlation:g}", None
    low = np.flatnonzero(s <= 0.5 * s[i])  # the best peak's lobe: down to half its height each side
    left, right = (low[low < i].max() if np.any(low < i) else -1), (low[low > i].min() if np.any(low > i) else s.size)
    if left < 0 or right >= s.size:  # the peak's lobe runs into the end of the search: it may lie beyond
        return None, float(s[i]), "the best peak's lobe reaches the edge of the search", None
    peaks = np.flatnonzero((s[1:-1] > s[:-2]) & (s[1:-1] >= s[2:])) + 1
    if np.any(((peaks < left) | (peaks > right)) & (s[peaks] >= AMBIGUOUS * s[i])):
        return None, float(s[i]), f"a second peak within {AMBIGUOUS:g} of the best", None  # periodic: no speed
    lag = (k_lo + i + _vertex(s, i)) * dt
    # the lag's standard error: found again in each part of the window, within the best lobe
    a_lo, a_hi = k_lo + max(left, 0), k_lo + min(right, s.size - 1)
    part = n // SUB_WINDOWS
    lags = []
    for j in range(SUB_WINDOWS):  # each part's own best lag over the whole search, kept if within the lobe
        sub = _scores(a[j * part:], b[j * part:], k_lo, k_hi, part)
        m = int(np.argmax(sub))
        if a_lo < k_lo + m < a_hi:
            lags.append((k_lo + m + _vertex(sub, m)) * dt)
    if len(lags) < SUB_WINDOWS - 1:  # the parts do not find the window's lag: it is not one lag
        return None, float(s[i]), (f"its parts disagree ({SUB_WINDOWS - len(lags)} of {SUB_WINDOWS} find their "
                                   f"own best lag outside the window's best peak)"), None
    sd = float(np.std(lags, ddof=1)) / math.sqrt(len(lags))
    return lag, float(s[i]), None, max(sd, dt / math.sqrt(12.0))  # no finer than the sample step's


def _scatter(sd: float, lag: float) -> str | None:
    """Why a window whose lag ``lag`` (s) has the standard error ``sd`` (s) gives no speed: its parts'
    lags scatter over ``MAX_SPEED_SD`` of it; None where they do not."""
    if sd / lag > MAX_SPEED_SD:
        return f"its parts' lags scatter (the speed uncertain by {100 * sd / lag:.0f} %, over {100 * MAX_SPEED_SD:g} %)"
    return None


def _layout(t, front, rear, wheelbase: float, window_s: float, highpass_hz: float, travel):
    """What :func:`speed_from_lag` and :func:`tracked` share: (dt, the two series high-passed at
    ``highpass_hz`` and differentiated, the shortest and longest lag searched in samples, a window's
    samples, the windows' first samples, a test of whether both ends move in a window (None without
    ``travel``))."""
    dt = float(t[1] - t[0])
    from scipy.signal import butter, sosfiltfilt

    sos = butter(2, highpass_hz, btype="highpass", fs=1.0 / dt, output="sos")
    vf = np.gradient(sosfiltfilt(sos, np.asarray(front, float)), dt)
    vr = np.gradient(sosfiltfilt(sos, np.asarray(rear, float)), dt)
    lo, hi = wheelbase / SPEED_RANGE[1], wheelbase / SPEED_RANGE[0]
    k_lo, k_hi = max(1, int(math.floor(lo / dt))), int(math.ceil(hi / dt))
    step = int(round(window_s / dt))
    moving = None
    if travel is not None:
        tf, tr = (np.asarray(x, float) for x in travel)
        moving = lambda a: (np.ptp(tf[a:a + step]) >= STILL_MM  # noqa: E731
                            and np.ptp(tr[a:a + step + k_hi]) >= STILL_MM)
    hop = max(1, int(round(WINDOW_HOP * step)))
    return dt, vf, vr, k_lo, k_hi, step, range(0, max(vf.size - k_hi - step // 2, 1), hop), moving


def speed_from_lag(t, front, rear, wheelbase: float, window_s: float = WINDOW_S, highpass_hz: float = LAG_HIGHPASS_HZ,
                   travel=None) -> dict:
    """{"speed_m_per_s": the median of the windows' speeds, "lag_s", "windows": [(start_s, speed or
    None, correlation)], "sd": each window's speed's standard error (m/s, or None), "why": why each
    window gave no speed (None where it gave one), "speed_at": a function of time (the windows'
    speeds at their centres, linear between, held past the first and last)}: see the module doc.
    ``front`` and ``rear`` are series (any units) on ``t``; both are high-passed at ``highpass_hz``
    first (what the terrain does, not the rider's slow weight shifts, which reach both ends at
    once). ``travel`` (front mm, rear mm on ``t``), where given: a window where either end spans
    less than ``STILL_MM`` is standing and gives no speed (what its filtered series hold there is
    the filters' tails, which align at any lag). A window whose best lag is at either end of the
    lags searched gives none (the peak is outside the search); so does one with a second peak
    (outside the best one's lobe, down to half its height) at least ``AMBIGUOUS`` times as high,
    or a best correlation below ``MIN_CORRELATION``. A window's standard error: the lag found again
    in each of its ``SUB_WINDOWS`` parts within the best peak's lobe, their spread over the root of
    their number; a window where more than one part finds its own best lag (over the whole search)
    outside that lobe (the window holds more than one lag) gives no speed."""
    check_length(t, wheelbase, window_s)
    dt, vf, vr, k_lo, k_hi, step, starts, moving = _layout(t, front, rear, wheelbase, window_s, highpass_hz, travel)
    windows, sds, whys = [], [], []
    standing = 0
    for start in starts:
        if moving is not None and not moving(start):
            windows.append((start * dt, None, 0.0))  # standing: nothing the terrain did to align
            sds.append(None)
            whys.append(f"standing (an end moving less than {STILL_MM:g} mm)")
            standing += 1
            continue
        wl, wc, why, sd = _best(vf[start:start + step + k_hi], vr[start:start + step + k_hi], k_lo, k_hi, dt)
        v = None if wl is None else wheelbase / wl
        if v is not None and _scatter(sd, wl):  # its parts disagree: no speed to take from it
            v, why = None, _scatter(sd, wl)
        windows.append((start * dt, v, wc))
        sds.append(None if v is None else v * sd / wl)
        whys.append(why)
    return _profile(windows, sds, whys, wheelbase, window_s)


def drop_unsupported(windows, sds, whys) -> None:
    """Windows whose speed the rest of the ride contradicts, given no speed (in place). A window spans
    the second half of the one before it and the first half of the one after it, so (a) where those
    two agree (within ``NEIGHBOURS_AGREE`` of their mean) its speed cannot lie more than ``OUTLIER``
    from their mean (and more than three standard errors): its peak is another lag's; (b) a window
    neither neighbour supports (none gives a speed within ``OUTLIER`` of its) whose speed is more than
    ``FAR`` times off the median of the ride's other windows (at least ``FAR_OTHERS`` of them) stands
    alone against the ride: its lag is not the wheelbase's (the terrain's distance axis, integrated
    from the speed, would be stretched or squeezed that many times around it)."""
    speeds = [v for _, v, _ in windows]
    out = []
    for k, v in enumerate(speeds):
        if v is None:
            continue
        before = speeds[k - 1] if k > 0 else None
        after = speeds[k + 1] if k + 1 < len(speeds) else None
        if before is not None and after is not None:
            mean = 0.5 * (before + after)
            spread = 3.0 * math.sqrt((sds[k] or 0.0) ** 2 + 0.25 * ((sds[k - 1] or 0.0) ** 2 + (sds[k + 1] or 0.0) ** 2))
            if abs(before - after) <= NEIGHBOURS_AGREE * mean and abs(v - mean) > max(OUTLIER * mean, spread):
                out.append((k, f"its speed {v:.2f} m/s where the two windows it overlaps give {before:.2f} and "
                               f"{after:.2f}: another lag's peak"))
                continue
        if any(n is not None and abs(n - v) <= OUTLIER * v for n in (before, after)):
            continue  # a neighbour supports it
        others = [u for j, u in enumerate(speeds) if u is not None and j != k]
        if len(others) >= FAR_OTHERS:
            median = float(np.median(others))
            if not median / FAR <= v <= median * FAR:
                out.append((k, f"its speed {v:.2f} m/s, alone (no overlapping window near it), {max(v / median, median / v):.1f} "
                               f"times off the {median:.2f} m/s median of the ride's {len(others)} other windows"))
    for k, why in out:
        windows[k] = (windows[k][0], None, windows[k][2])
        sds[k], whys[k] = None, why


def refine(t, recorded, predicted, lags, wheelbase: float, window_s: float = REFINE_WINDOW_S, flights=()) -> dict:
    """The speed found again from the lag left between the rear's record and the rear predicted
    (both mm on ``t``) through the bike over terrain laid a lag ``lags`` (s, on ``t``, the first
    estimate's) behind the front: where the first estimate's lag is right the two align at no shift;
    where it is off by d, the record runs d behind the prediction. Both are the same kind of series
    (the rear's travel through the same suspension), so they align far better than the two ends'
    grounds do, and a shorter window (``REFINE_WINDOW_S``) can be used. Per window (starting every
    half window, in the rear's time) the shift d is searched within +- ``REFINE_SPAN`` of the local
    lag, with the rejections of :func:`speed_from_lag` (the edge of the search, a second peak, parts
    that disagree, a correlation below ``REFINE_MIN_CORRELATION``, an uncertainty over
    ``MAX_SPEED_SD``, the rear standing, the prediction missing past a divergence) and of
    :func:`drop_unsupported`; its speed wheelbase / (lag + d) is put where the window's motion is (the
    centre of the record's squared velocity over it: a window's lag is mostly that of its largest
    motions), less half the lag (midway between the front's and the rear's meeting the terrain); a
    window's start and end in the answer are that time -+ half a window. The rear's
    record sets only when the rear met what the front met (the speed), never the terrain's heights.
    ``flights``: the front's flights ((start s, end s)); each one's stretch a lag later, the rear's
    flight, is left out of the alignment (both series' speeds set to 0 there): when the rear lands is
    the flight's, the drop's depth and the take-off's speed as the model found them, not the ride's
    speed (kept in, the made whole-bike ride's worst window is 3.9 % off, left out 1.6 %).
    Returns speed_from_lag's answer (``ReconstructError`` where no window gives a speed)."""
    from scipy.signal import butter, sosfiltfilt

    dt = float(t[1] - t[0])
    recorded, predicted = np.asarray(recorded, float), np.asarray(predicted, float)
    missing = ~np.isfinite(predicted)
    sos = butter(2, LAG_HIGHPASS_HZ, btype="highpass", fs=1.0 / dt, output="sos")
    a = np.gradient(sosfiltfilt(sos, recorded), dt)
    b = np.gradient(sosfiltfilt(sos, np.where(missing, 0.0, predicted)), dt)
    lags = np.asarray(lags, float)
    for f0, f1 in flights:  # the rear's flight (the front's a lag later): when it lands is the model's flight's
        i0, i1 = (min(int(np.searchsorted(t, f)), t.size - 1) for f in (f0, f1))
        a[int(np.searchsorted(t, f0 + lags[i0])):int(np.searchsorted(t, f1 + lags[i1]))] = 0.0
        b[int(np.searchsorted(t, f0 + lags[i0])):int(np.searchsorted(t, f1 + lags[i1]))] = 0.0
    step = int(round(window_s / dt))
    far = int(math.ceil(REFINE_SPAN * float(np.max(lags)) / dt)) + 1
    windows, sds, whys = [], [], []
    for st in range(far, max(t.size - step - far, far + 1), max(1, step // 2)):
        here = float(lags[st + step // 2])
        k = max(2, int(math.ceil(REFINE_SPAN * here / dt)))
        why, v, sd, c = None, None, None, 0.0
        if missing[st - k:st + step + k].any():
            why = "the rear predicted is missing here (the whole bike diverged before it)"
        elif np.ptp(recorded[st:st + step]) < STILL_MM:
            why = f"standing (the rear moving less than {STILL_MM:g} mm)"
        else:
            lag_b, c, why, sd_lag = _best(a[st:st + step + 2 * k], b[st - k:st + step + k], 0, 2 * k, dt,
                                          REFINE_MIN_CORRELATION)
            if lag_b is not None:
                lag = here + k * dt - lag_b
                if not wheelbase / SPEED_RANGE[1] < lag < wheelbase / SPEED_RANGE[0]:
                    why = f"its lag {lag:.3f} s outside {SPEED_RANGE[0]:g}-{SPEED_RANGE[1]:g} m/s"
                elif _scatter(sd_lag, lag):
                    why = _scatter(sd_lag, lag)
                else:
                    v, sd = wheelbase / lag, wheelbase / lag * sd_lag / lag
        # the lag is that of where the window's motion is: its time the centre of the record's squared
        # velocity over it, less half the lag (between the front's and the rear's meeting the terrain)
        weight = a[st:st + step] ** 2
        total = float(weight.sum())
        centre = (st + (float(np.arange(step) @ weight) / total if total > 0 else 0.5 * step)) * dt
        mid = centre - 0.5 * window_s - 0.5 * (wheelbase / v if v is not None else here)
        windows.append((mid, v, float(c)))
        sds.append(sd)
        whys.append(why)
    return _profile(windows, sds, whys, wheelbase, window_s)


def merged(first: dict, again: dict) -> dict:
    """The speed profile from the windows :func:`refine` accepted, with the first estimate's (the two
    ends' lag) kept where no refined window lies within one of its windows of them (a stretch the
    rear predicted does not align). The answer has the refined windows as "windows" (their sources
    "the rear predicted"), the first estimate's as "first", and a profile linear between all kept
    centres ("speed_at")."""
    w1, w2 = first["window_s"], again["window_s"]
    points = [(a + 0.5 * w2, v) for a, v, _ in again["windows"] if v is not None]
    refined = np.array([c for c, _ in points])
    kept = [(a + 0.5 * w1, v) for a, v, _ in first["windows"] if v is not None]
    points += [(c, v) for c, v in kept if not refined.size or np.min(np.abs(refined - c)) > w1]
    points.sort()
    centres, speeds = np.array([c for c, _ in points]), np.array([v for _, v in points])
    out = dict(again)
    out["first"] = first
    out["sources"] = ["the rear predicted" if v is not None else None for _, v, _ in again["windows"]]
    out["first_kept"] = len(points) - int(refined.size)
    out["speed_m_per_s"] = float(np.median(speeds))
    out["lag_s"] = first["wheelbase_m"] / out["speed_m_per_s"]
    out["speed_at"] = lambda time: np.interp(time, centres, speeds)
    return out


def _profile(windows, sds, whys, wheelbase: float, window_s: float, sources=None, kinds=None,
             contradicted: bool = True) -> dict:
    """speed_from_lag's answer from its windows: refused in one line where no window gave a speed.
    A window the rest of the ride contradicts gives none (:func:`drop_unsupported`; not asked again by
    :func:`tracked`, whose windows must not overrule the strict ones they are anchored on). "kinds" says per
    window "strict" (its own lag, the rejections above) or "tracked" (:func:`tracked`), None where it
    gave no speed."""
    windows, sds, whys = list(windows), list(sds), list(whys)
    if contradicted:
        drop_unsupported(windows, sds, whys)
    if sources is not None:
        sources = [src if w[1] is not None else None for src, w in zip(sources, windows)]
    kinds = [(k or "strict") if w[1] is not None else None
             for k, w in zip(kinds or [None] * len(windows), windows)]
    good = [(a + 0.5 * window_s, v) for a, v, _ in windows if v is not None]
    if not good:
        top = max((c for _, _, c in windows), default=0.0)
        from collections import Counter

        counts = Counter((w or "").split(" (")[0] for w in whys)
        counts.pop("", None)
        reasons = "; ".join(f"{n} {why}" for why, n in counts.most_common())
        raise ReconstructError(f"the two ends' records do not align at any lag for {SPEED_RANGE[0]:g}-"
                               f"{SPEED_RANGE[1]:g} m/s in any {window_s:g} s window (best correlation {top:.2f}; "
                               f"of {len(windows)} windows: {reasons}): no speed from this ride; a speed given "
                               f"(--speed M_PER_S or --speed-csv FILE; speed= from Python) is used in its place")
    centres, speeds = np.array([c for c, _ in good]), np.array([v for _, v in good])
    speed = float(np.median(speeds))
    return {"speed_m_per_s": speed, "lag_s": wheelbase / speed, "windows": windows, "sd": sds, "why": whys,
            "wheelbase_m": wheelbase, "window_s": window_s, "sources": sources, "kinds": kinds,
            "speed_at": lambda time: np.interp(time, centres, speeds)}


def speed_from_either(t, first, second, wheelbase: float, names=("first", "second"), travel=None) -> dict:
    """The speed per window from ``first`` = (front, rear, high-pass Hz) where that window gives one,
    else from ``second`` (the same windows): two estimates of one lag, the second asked only where the
    first gives none. Each window's source named in "sources" (None where neither gave one; its
    reason then the first's and the second's)."""
    answers = []
    for front, rear, hz in (first, second):
        try:
            answers.append(speed_from_lag(t, front, rear, wheelbase, highpass_hz=hz, travel=travel))
        except ReconstructError as exc:
            answers.append(exc)
    if all(isinstance(a, ReconstructError) for a in answers):
        raise answers[1]
    ok = [a for a in answers if not isinstance(a, ReconstructError)]
    base = ok[0]
    windows, sds, whys, sources = [], [], [], []
    for i in range(len(base["windows"])):
        for name, a in zip(names, answers):
            if not isinstance(a, ReconstructError) and a["windows"][i][1] is not None:
                windows.append(a["windows"][i]), sds.append(a["sd"][i]), whys.append(None), sources.append(name)
                break
        else:
            reasons = [(name, a["why"][i]) for name, a in zip(names, answers) if not isinstance(a, ReconstructError)]
            if len({why for _, why in reasons}) == 1:  # both say the same (standing): said once
                whys.append(reasons[0][1] or "no speed")
            else:
                whys.append("; ".join(f"{name}: {why}" for name, why in reasons) or "no speed")
            windows.append(base["windows"][i]), sds.append(None), sources.append(None)
    return _profile(windows, sds, whys, wheelbase, base["window_s"], sources)


def _path(scores, allowed, first_v, last_v, grid_ln):
    """The speeds (indices into the grid) through a run of windows that maximise the sum of each
    window's correlation at its speed less ``TRACK_PENALTY`` (change of ln speed)^2 from window to
    window, from the strict speed before the run (``first_v``, or None) to the one after it
    (``last_v``), each window's speed within ``allowed`` (a boolean row per window)."""
    pen = TRACK_PENALTY * (grid_ln[:, None] - grid_ln[None, :]) ** 2  # [to, from]
    blocked = -1e9
    acc = np.where(allowed[0], scores[0], blocked)
    if first_v is not None:
        acc = acc - TRACK_PENALTY * (grid_ln - math.log(first_v)) ** 2
    back = np.zeros(scores.shape, int)
    for w in range(1, scores.shape[0]):
        total = acc[None, :] - pen
        back[w] = np.argmax(total, axis=1)
        acc = total[np.arange(grid_ln.size), back[w]] + np.where(allowed[w], scores[w], blocked)
    if last_v is not None:
        acc = acc - TRACK_PENALTY * (grid_ln - math.log(last_v)) ** 2
    path = np.zeros(scores.shape[0], int)
    path[-1] = int(np.argmax(acc))
    for w in range(scores.shape[0] - 1, 0, -1):
        path[w - 1] = back[w, path[w]]
    return path


def tracked(t, sources, strict: dict, wheelbase: float, travel=None) -> dict:
    """The strict windows' speed profile (``strict``, :func:`speed_from_either`'s answer for the same
    ``sources``, a list of (front, rear, high-pass Hz)) with its gaps filled by a tracked speed. Per
    window, its correlation over speed is the mean of the sources' correlograms (on ``TRACK_GRID``
    log-spaced speeds); through each run of windows without a strict speed, a path (:func:`_path`)
    maximises the correlation along it less ``TRACK_PENALTY`` (change of ln speed)^2 between
    neighbouring windows, tied to the strict speeds at both ends of the run, and kept within them
    widened by ``TRACK_MARGIN`` (the lowest over 1 + margin, the highest times it). A window of the
    path gives a tracked speed only where its centre lies within ``TRACK_ANCHOR_S`` of a strict
    window's, it moves (not standing) and its correlation has a peak (inside the allowed range) within
    ``TRACK_SNAP`` (ln speed) of the path, of at least ``TRACK_MIN_CORRELATION``, which at least
    ``TRACK_PARTS`` of its ``SUB_WINDOWS`` parts find too (each part's best speed in the allowed range,
    its correlogram the sources' mean, within ``TRACK_PARTS_SPAN`` of it): its speed is that
    peak's (the nearest to the path, refined by a parabola); its standard error is
    ``TRACK_SD`` of its speed (the strict ones' are their parts' spread). The answer is
    speed_from_lag's, "kinds" saying per window "strict" or "tracked"; a ride with no strict window
    has no anchor and gets no tracked speed (the caller refuses it before)."""
    window_s = strict.get("window_s", WINDOW_S)
    layouts = [_layout(t, front, rear, wheelbase, window_s, hz, travel) for front, rear, hz in sources]
    dt, _, _, k_lo, k_hi, step, _, moving = layouts[0]
    grid = np.exp(np.linspace(math.log(SPEED_RANGE[0]), math.log(SPEED_RANGE[1]), TRACK_GRID))
    grid_ln = np.log(grid)
    at = wheelbase / grid / dt - k_lo  # each grid speed's lag as a (fractional) index into a correlogram
    windows = list(strict["windows"])
    n = len(windows)
    speeds = [v for _, v, _ in windows]
    kinds = list(strict.get("kinds") or [None if v is None else "strict" for v in speeds])
    sds = list(strict.get("sd") or [None] * n)
    whys = list(strict.get("why") or [None] * n)
    srcs = list(strict.get("sources") or [None] * n)
    centres = np.array([a + 0.5 * window_s for a, _, _ in windows])
    anchors = [k for k in range(n) if speeds[k] is not None]
    if not anchors:
        return strict
    k = 0
    while k < n:
        if speeds[k] is not None:
            k += 1
            continue
        j = k
        while j < n and speeds[j] is None:
            j += 1
        run = list(range(k, j))  # windows k..j-1 without a strict speed
        before = speeds[k - 1] if k > 0 else None
        after = speeds[j] if j < n else None
        ends = [v for v in (before, after) if v is not None]
        near = [w for w in run if np.min(np.abs(centres[anchors] - centres[w])) <= TRACK_ANCHOR_S]
        if ends and near:
            lo, hi = min(ends) / (1.0 + TRACK_MARGIN), max(ends) * (1.0 + TRACK_MARGIN)
            allowed = np.tile((grid >= lo) & (grid <= hi), (len(run), 1))
            scores = np.zeros((len(run), grid.size))
            has = np.zeros(len(run), bool)
            part_best = [[] for _ in run]  # each part's best grid speed within the allowed range
            for r, w in enumerate(run):
                start = int(round(windows[w][0] / dt))
                if moving is not None and not moving(start):
                    continue
                grams, parts = [], []
                for _, vf, vr, *_ in layouts:
                    a, b = vf[start:start + step + k_hi], vr[start:start + step + k_hi]
                    m = a.size - k_hi
                    if m >= 10 * SUB_WINDOWS:
                        grams.append(np.interp(at, np.arange(k_hi - k_lo + 1), _scores(a, b, k_lo, k_hi, m)))
                        p = m // SUB_WINDOWS
                        parts.append([np.interp(at, np.arange(k_hi - k_lo + 1),
                                                _scores(a[j * p:], b[j * p:], k_lo, k_hi, p)) for j in range(SUB_WINDOWS)])
                if grams:
                    scores[r], has[r] = np.mean(grams, axis=0), True
                    part_best[r] = [int(np.argmax(np.where(allowed[r], np.mean(g, axis=0), -np.inf)))
                                    for g in zip(*parts)]
            path = _path(scores, allowed, before, after, grid_ln)
            inside = np.flatnonzero(allowed[0])
            for r, w in enumerate(run):
                row = scores[r]
                peaks = inside[(inside > inside[0]) & (inside < inside[-1])]
                peaks = peaks[(row[peaks] > row[peaks - 1]) & (row[peaks] >= row[peaks + 1])]
                peaks = peaks[np.abs(grid_ln[peaks] - grid_ln[path[r]]) <= TRACK_SNAP]
                if w not in near or not has[r] or not peaks.size:
                    continue
                g = int(peaks[np.argmin(np.abs(grid_ln[peaks] - grid_ln[path[r]]))])
                c = float(row[g])
                agree = sum(abs(grid_ln[q] - grid_ln[g]) <= TRACK_PARTS_SPAN for q in part_best[r])
                if c >= TRACK_MIN_CORRELATION and agree >= TRACK_PARTS:
                    v = float(math.exp(grid_ln[g] + _vertex(row, g) * (grid_ln[1] - grid_ln[0])))
                    windows[w] = (windows[w][0], v, c)
                    sds[w], whys[w], kinds[w] = TRACK_SD * v, None, "tracked"
                    srcs[w] = "tracked between the strict windows"
        k = j
    for w in range(n):  # why a window left without a speed was not tracked either, said after its own reason
        if windows[w][1] is None and whys[w] and np.min(np.abs(centres[anchors] - centres[w])) > TRACK_ANCHOR_S:
            whys[w] = f"{whys[w]}; not tracked: no strict window within {TRACK_ANCHOR_S:g} s"
    return _profile(windows, sds, whys, wheelbase, window_s, srcs, kinds, contradicted=False)


__all__ = ["tracked", "TRACK_ANCHOR_S", "refine", "merged", "REFINE_WINDOW_S", "drop_unsupported", "WINDOW_S", "WINDOW_HOP", "SPEED_RANGE", "ReconstructError", "min_seconds", "check_length", "speed_from_lag", "speed_from_either"]

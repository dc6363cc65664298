"""The speed tracked between strict windows (mtbmj/ride/reconstruct_speed.py: ``tracked``, issue 51
item 1), on series written here: a terrain of random bumps ridden at a speed written here, the
front meeting it at x(t), the rear at x(t) - wheelbase, each with noise of its own."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.ride.reconstruct_speed import (TRACK_ANCHOR_S, ReconstructError, speed_from_lag, tracked)

RATE = 1000.0
WHEELBASE = 1.2


def speed_bump(t):
    """6 m/s, up by 15 % (to 6.9) between 15 and 22.5 s and back down by 30 s: a ramp the strict
    windows at 6 m/s on either side do not show (their line between them stays at 6)."""
    return 6.0 + 0.9 * np.interp(t, [0.0, 15.0, 22.5, 30.0, 1e9], [0.0, 0.0, 1.0, 0.0, 0.0])


def ride(seed=1, seconds=70.0, speed=speed_bump, noise=0.3):
    """(t, front, rear): the two ends over one terrain (bumps 0.1-1 m long) at ``speed``, each end
    with its own noise (``noise`` of the terrain's spread)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * RATE)) / RATE
    x = np.concatenate(([0.0], np.cumsum(0.5 * (speed(t[1:]) + speed(t[:-1])) / RATE))) + 5.0
    dx = 0.005
    grid = np.arange(0.0, x[-1] + 1.0, dx)
    bumps = np.convolve(rng.normal(size=grid.size), np.hanning(int(0.2 / dx)), mode="same")
    h = lambda s: np.interp(s, grid, bumps)  # noqa: E731
    front, rear = h(x), h(x - WHEELBASE)
    sd = noise * float(np.std(front))
    smooth = np.hanning(15) / np.hanning(15).sum()  # the noise as a sensor's: not white to 500 Hz
    front = front + sd * np.convolve(rng.normal(size=t.size), smooth, mode="same") / np.sqrt((smooth ** 2).sum())
    rear = rear + sd * np.convolve(rng.normal(size=t.size), smooth, mode="same") / np.sqrt((smooth ** 2).sum())
    return t, front, rear


def blanked(strict, keep):
    """The strict answer with only the windows ``keep(start_s)`` says keep: the others as a window the
    strict rejections refused."""
    out = dict(strict)
    out["windows"] = [(a, v if keep(a) else None, c) for a, v, c in strict["windows"]]
    out["sd"] = [sd if keep(a) else None for (a, _, _), sd in zip(strict["windows"], strict["sd"])]
    out["why"] = [why if keep(a) else "best correlation below 0.3" for (a, _, _), why in zip(strict["windows"],
                                                                                           strict["why"])]
    out["kinds"] = ["strict" if v is not None else None for _, v, _ in out["windows"]]
    return out


def test_the_tracked_windows_follow_a_speed_ramp_between_strict_anchors():
    """Strict windows kept only where their centres lie before 14 s and at 31-36 s (6 m/s on both
    sides of the ramp); tracked between them
    over the 6 -> 6.9 -> 6 m/s ramp, every tracked window within its stated standard error of the
    speed written at its centre, where the strict windows' line (6 m/s) is off by more than that at
    the ramp's top; the windows more than ``TRACK_ANCHOR_S`` from a strict one stay without a speed
    and say why."""
    t, front, rear = ride()
    strict = speed_from_lag(t, front, rear, WHEELBASE)
    w = strict["window_s"]
    keep = lambda a: a + 0.5 * w < 14.0 or 31.0 < a + 0.5 * w < 36.0  # noqa: E731
    assert all(v is not None for a, v, _ in strict["windows"] if keep(a))  # the anchors kept are all strict
    anchors = blanked(strict, keep)
    found = tracked(t, [(front, rear, 5.0)], anchors, WHEELBASE)
    track = [(a + 0.5 * w, v, sd) for (a, v, _), sd, kind in zip(found["windows"], found["sd"], found["kinds"])
             if kind == "tracked"]
    gap = [a + 0.5 * w for a, v, _ in anchors["windows"] if v is None and 14.0 < a + 0.5 * w < 31.0]
    assert len([c for c, _, _ in track if c < 31.0]) >= 0.8 * len(gap), (track, gap)
    for c, v, sd in track:
        assert abs(v - float(speed_bump(c))) <= sd, (c, v, float(speed_bump(c)), sd)
        assert min(abs(c - a) for a in (12.5, 32.5, 35.0)) <= TRACK_ANCHOR_S  # near an anchor only
    top = [(c, v, sd) for c, v, sd in track if abs(float(speed_bump(c)) - 6.9) < 0.2]
    assert top, "no tracked window at the ramp's top"
    for c, v, sd in top:  # the strict windows' line (6 m/s between them) is off there by more than sd
        assert abs(6.0 - float(speed_bump(c))) > sd and abs(v - 6.0) > 0.5 * abs(6.0 - float(speed_bump(c)))
    far = [k for k, (a, v, _) in enumerate(found["windows"])
           if v is None and a + 0.5 * w - 35.0 > TRACK_ANCHOR_S]
    assert far and all("not tracked: no strict window within" in found["why"][k] for k in far)


def test_the_rear_of_another_ride_gives_no_speed_and_no_tracked_windows():
    """The wrong input: the rear record of another ride (another terrain). The strict windows find
    no speed (refused in one line); given the right ride's strict windows as anchors, the tracked
    path through the wrong pair's correlograms gives no tracked window; the right pair, the same
    anchors, gives them (so the refusal is the input's)."""
    t, front, rear = ride()
    _, _, other = ride(seed=7)
    with pytest.raises(ReconstructError, match="do not align at any lag"):
        speed_from_lag(t, front, other, WHEELBASE)
    strict = speed_from_lag(t, front, rear, WHEELBASE)
    w = strict["window_s"]
    anchors = blanked(strict, lambda a: a + 0.5 * w < 14.0 or 31.0 < a + 0.5 * w < 36.0)
    wrong = tracked(t, [(front, other, 5.0)], anchors, WHEELBASE)
    assert not any(kind == "tracked" for kind in wrong["kinds"])
    right = tracked(t, [(front, rear, 5.0)], anchors, WHEELBASE)
    assert sum(kind == "tracked" for kind in right["kinds"]) >= 4

"""The compiled patch search's shortcuts (issue 52 item 7) give the search's answer to the bit.

``mtbmj.rolling.search_compiled`` cuts a static profile into its pieces once (``piece_table``), finds
the window from the last search's (``sorted_index``) and takes a run along which the distance falls,
then rises, at once (``falls_then_rises``); ``plain_search`` (``R_PLAIN``) searches as before. Checked
here against that plain search, computed in the test: every search's patches along trajectories over
library terrains and a profile made here as a ride's reconstruction is (points every 8.6-10.8 mm, its
slope changing at every one, no straight stretch a tyre's reach long), bit for bit, and whole runs of
the bike and the front end, every state and sensor bit for bit; ``falls_then_rises`` against
``share_depths`` on runs made here. A table one micrometre off is seen (the check can fail).
"""
from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "disable")

import math

import numpy as np
import pytest

from mtbmj.rolling import terrain as T
from mtbmj.rolling.tire import CAP_MIN_M, SHARE_BLOCKS, share_depths
from helpers import compiled_search


def rough_profile(length_m: float = 40.0, seed: int = 5, start_m: float = 1.0) -> T.Terrain:
    """A reconstruction's kind of terrain: 5 m level, then points every 8.6-10.8 mm (random) on a
    sum of waves of 0.1-8 m with noise of 1 mm, slopes up to about 0.5, two 80 mm steps smoothed
    over two points, then level again; the axle starts ``start_m`` in."""
    rng = np.random.default_rng(seed)
    x = [0.0]
    while x[-1] < length_m:
        x.append(x[-1] + rng.uniform(0.0086, 0.0108))
    x = np.array(x) + 5.0
    z = np.zeros_like(x)
    for wave, amp in ((8.0, 0.4), (2.3, 0.12), (0.7, 0.03), (0.23, 0.008), (0.1, 0.002)):
        z += amp * np.sin(2 * math.pi * x / wave + rng.uniform(0, 2 * math.pi))
    z += rng.normal(0.0, 0.001, z.size)
    for at in (15.0, 28.0):
        z[x > at] += 0.08
    z -= z[0]
    x = np.concatenate(([0.0], x, [x[-1] + 5.0]))
    z = np.concatenate(([0.0], z, [z[-1]]))
    return T.Terrain("rough", x, z, start_m, length_m)


def trajectory(terrain, x0, x1, radius, seed):
    """Axle positions as a rolling wheel meets them (forward 0.1-3 mm at a time, now and then back),
    the tyre from 30 mm deep to 8 mm clear of the ground."""
    rng = np.random.default_rng(seed)
    x, points = x0, []
    while x < x1:
        x += rng.uniform(0.1e-3, 3e-3) * (1.0 if rng.random() > 0.02 else -3.0)
        points.append((x, float(terrain.height(x)) + radius - rng.uniform(-0.008, 0.030)))
    return points


_compiled = compiled_search  # tests/helpers.py: skipped where the compiled path is not there


TERRAINS = {"rough": (rough_profile(), 5.5, 14.0),
            "root": (T.make("root:radius_mm=60,at_m=0.4"), -0.1, 1.0),
            "rock": (T.make("rock"), 0.9, 2.2),
            "ledge": (T.make("drop:height_mm=300,at_m=0.4"), -0.1, 0.9),
            "square_edge": (T.make("square_edge:height_mm=50,at_m=0.4"), -0.1, 1.0),
            "washboard": (T.make("washboard"), 1.0, 1.8),
            "gap": (T.Terrain("gap", np.array([-2.0, 0.0, 0.0, 0.1, 0.1, 3.0]), np.array([0, 0, -0.2, -0.2, 0, 0.0]),
                              0.0, 1.0), -0.45, 0.55)}


def _patch_rows(CR, slot):
    n = int(CR._INTS[slot, CR.R_NPATCH])
    return CR._FLOATS[slot, CR.F_PATCHES:CR.F_PATCHES + CR.PATCH_WIDTH * n].copy()


@pytest.mark.parametrize("name", list(TERRAINS))
def test_every_search_is_the_plain_search_to_the_bit(name):
    CR = _compiled()
    from mtbmj.rolling import frontend as R

    terrain, x0, x1 = TERRAINS[name]
    fast, plain = (R.prepare(terrain, 3.0, callback="compiled").callback for _ in range(2))
    plain.plain_search = True
    assert plain.plain_search and not fast.plain_search
    tire = R.prepare(terrain, 3.0, callback="compiled").tire
    points = trajectory(terrain, x0, x1, tire.radius, seed=sum(map(ord, name)))
    searched = 0
    for k, (cx, cz) in enumerate(points):
        a = CR.update_patches(CR._INTS[fast.slot], CR._FLOATS[fast.slot], cx, cz, 0.0)
        b = CR.update_patches(CR._INTS[plain.slot], CR._FLOATS[plain.slot], cx, cz, 0.0)
        assert a == b, (name, k)
        searched += a
        assert np.array_equal(_patch_rows(CR, fast.slot), _patch_rows(CR, plain.slot)), (name, k, cx, cz)
    assert searched > 100
    if name == "rough":  # no straight stretch holds a reach there: every refresh searches
        assert searched == len(points)
        # the check can fail: a table 1 um off under the trajectory is seen
        k = int(np.searchsorted(terrain.x, 0.5 * (x0 + x1))) - 1
        fast._pieces[4 * fast._pfirst[k] + 1] += 1e-6  # its first piece's start height
        differ = 0
        for cx, cz in points:
            CR.update_patches(CR._INTS[fast.slot], CR._FLOATS[fast.slot], cx, cz, 0.0)
            CR.update_patches(CR._INTS[plain.slot], CR._FLOATS[plain.slot], cx, cz, 0.0)
            differ += not np.array_equal(_patch_rows(CR, fast.slot), _patch_rows(CR, plain.slot))
        assert differ > 10


def test_the_table_is_each_segment_cut_as_the_search_cuts_it():
    """piece_table against the pieces of RadialTire.pieces (the Python reference) on segments the reach
    window does not clip, to the bit."""
    CR = _compiled()
    from mtbmj.rolling.tire import PIECE_M, RadialTire

    terrain = rough_profile(8.0, seed=2)
    first, pieces = CR.piece_table(terrain.x, terrain.z, PIECE_M)
    total = pieces.size // 4
    assert first[-1] == total > terrain.x.size  # some segments steep enough for two pieces
    tire = RadialTire(terrain, 0.3, 1e5, 100.0)
    reach = tire.radius + tire.margin
    for cx in (6.0, 7.7, 10.1):
        ax, az, ex, ez = tire.pieces(cx)
        i = int(np.searchsorted(terrain.x, cx - reach)) - 1
        j = int(np.searchsorted(terrain.x, cx + reach, side="right")) + 1
        # the window's first and last segments are clipped: the table holds the ones between
        q0, q1 = first[i + 1], first[j - 2]
        k0 = int(np.flatnonzero(ax == terrain.x[i + 1])[0])  # the first piece of the first whole segment
        got = pieces.reshape(-1, 4)[q0:q1].T
        want = np.stack([v[k0:k0 + q1 - q0] for v in (ax, az, ex, ez)])
        assert np.array_equal(got, want), cx


def _runs(rng):
    """Runs of squared distances (P2, V2) as the stream makes them: falling then rising with plateaus
    and vertices a round-off below the pieces, and rough ones with several minima."""
    out = []
    for _ in range(400):
        n = int(rng.integers(1, 30))
        shape = rng.random() < 0.6
        if shape:  # falls, then rises
            steps = np.round(rng.uniform(0, 3, n), 0) * rng.choice([1e-4, 1e-16], n)  # 0: a plateau
            along = np.concatenate(([0.0], np.cumsum(steps[:-1])))
            p = 0.09 + np.abs(along - along[int(rng.integers(0, n))])
        else:
            p = 0.09 + rng.choice([0.0, 1e-4, 2e-4, 1e-16], n)
        # each vertex at the farther of its pieces' ends (a round-off below it), or beyond it (a bump)
        v = np.maximum(p[:-1], p[1:]) + rng.choice([0.0, -1e-17] if shape else [0.0, 1e-5, -1e-17], max(n - 1, 0))
        out.append((p, v))
    return out


def test_falls_then_rises_is_share_depths_one_contact():
    _compiled()
    from mtbmj.rolling import search_compiled as SC

    rng = np.random.default_rng(3)
    taken = 0
    for p, v in _runs(rng):
        n = p.size
        cap = n + 4
        run = np.zeros((4 + SHARE_BLOCKS) * cap)
        run[:n], run[cap:cap + n - 1] = p, v
        j = SC.falls_then_rises(run, cap, n)
        work = np.zeros(SHARE_BLOCKS * n)
        k = share_depths(p.copy(), v.copy(), n, 0.3, CAP_MIN_M, work)
        g = np.empty(2 * n - 1)
        g[0::2], g[1::2] = p, np.maximum(v, np.maximum(p[:-1], p[1:]))
        dg = np.diff(g)
        up = np.flatnonzero(dg > 0.0)
        shortcut = up.size == 0 or not np.any(dg[up[0]:] < 0.0)  # RadialTire.patches' own test
        assert (j >= 0) == shortcut, (p, v)
        if j >= 0:
            taken += 1
            assert k == 1 and work[0] == j == int(np.argmin(g)) // 2, (p, v, j, work[:n])
            assert work[n] == work[2 * n] and work[3 * n] == math.inf
    assert 100 < taken < 400


def _bike_run(terrain, plain, duration):
    from mtbmj.bike.run import callback_kind, prepare, simulate

    p = prepare("sst", terrain, 6.0, drive="rider", callback="compiled")
    assert callback_kind(p.callback) == "compiled"
    p.callback.plain_search = plain
    states, sensors = simulate(p, duration)
    return np.asarray(states), np.asarray(sensors), p.callback.refreshes, p.callback.calls


def test_a_bike_run_is_the_plain_search_s_to_the_bit():
    """The bike over the rough profile (both wheels searched at every refresh off the lead-in): every
    state and sensor of the run equal to the bit with and without the shortcuts."""
    _compiled()
    terrain = rough_profile(start_m=4.5)  # the front wheel on the rough from the start
    fast = _bike_run(terrain, False, 1.0)
    plain = _bike_run(terrain, True, 1.0)
    assert fast[2] == plain[2] > 10000  # (a third of the calls: many steps refined, a search each 0.05 ms)
    assert np.array_equal(fast[0], plain[0]) and np.array_equal(fast[1], plain[1])


def test_a_front_end_run_is_the_plain_search_s_to_the_bit():
    _compiled()
    from mtbmj.rolling import frontend as R

    out = []
    for plain in (False, True):
        p = R.prepare(rough_profile(), 5.0, callback="compiled")
        p.callback.plain_search = plain
        states, sensors = R.simulate(p, 0.5)
        out.append((np.asarray(states), np.asarray(sensors), p.callback.refreshes))
    assert out[0][2] == out[1][2] > 0
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])


@pytest.mark.slow
def test_the_bike_on_the_shipped_ride_s_reconstruction_is_the_plain_search_s_to_the_bit():
    """As ``mtbmj advise`` rides it (benchmarks/patch_search.py): 20 s of the shipped ride, to the bit."""
    _compiled()
    from types import SimpleNamespace

    from mtbmj.bike.run import prepare, simulate
    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import advise, reconstruct

    how = SimpleNamespace(bike="sst", fork_max_mm=None, shock_max_mm=None)  # as mtbmj reads it (benchmarks/_bench.py)
    record = telemetry.read_ride(telemetry.example_path(), **decoding(how))
    rec = reconstruct.reconstruct(record, "sst")
    terrain = advise.terrain_of(rec)
    profile = rec.speed_along()
    out = []
    for plain in (True, False):
        p = prepare("sst", terrain, float(profile[1][0]), drive="rider", speed_profile=profile, callback="compiled")
        p.callback.plain_search = plain
        states, sensors = simulate(p, 20.0)
        out.append((np.asarray(states), np.asarray(sensors), p.callback.refreshes, p.callback.calls))
    assert out[0][2] == out[1][2] > 0.9 * out[0][3]
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])

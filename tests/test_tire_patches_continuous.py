"""The tire's force does not jump where contact patches split or merge (mtbmj/rolling/tire.py, module
doc 1).

Before, a stretch of profile within reach of the axle (radius + 10 mm) was one patch at its closest
point: two washboard crests under the tire with the trough between them inside the 10 mm margin were
one patch, the deeper crest's, and when the trough left the margin the second crest entered 3 mm
deep (the washboard at 5 m/s: a 339 N step, 34 % of the 988 N peak, in one 0.1 ms row). Now every
local minimum of the distance is a contact and the contacts of one stretch share the overlap's depth.

* the washboard run: the force's largest one-row change at most 10 % of its peak;
* two point-like crests made here (narrow triangles, a V trough between), the axle moved
  continuously: the Python tire's force and the compiled callback's (the same to round-off) have
  no step larger than a few k x the axle's move, and where the trough clears the tire the force is
  k (R - d1) n1 + k (R - d2) n2, worked out here from the crests' coordinates;
* flat ground, a bump and a square edge rolled over (one contact per stretch): the force is the
  old one-patch-per-stretch force, written here from the segments, to 1e-9 N.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import mtbmj
from mtbmj.rolling import terrain as T
from mtbmj.rolling.tire import RadialTire

R_TIRE, K_TIRE, B_TIRE = 0.37, 73.4e3, 150.0
HALF, H, V, W = 0.03, 0.05, 0.008, 0.002  # crests at +-HALF, H high, the V trough V deep, flanks W wide


def two_crests() -> T.Terrain:
    """Flat ground at 0 with two narrow triangular crests (H high, at x = -HALF and +HALF) and a V
    trough between them, its bottom V below the crests."""
    x = np.array([-2.0, -HALF - W, -HALF, 0.0, HALF, HALF + W, 2.0])
    z = np.array([0.0, 0.0, H, H - V, H, 0.0, 0.0])
    return T.Terrain("two_crests", x, z, -1.0, 3.0)


def crests_by_hand(cx, cz):
    """(Fx, Fz) of both crests pressed into a still tire (k (R - d) along (axle - crest)/d each), and
    the trough bottom's distance from the axle: the highest point between the crests as seen from it
    (the V's flanks are steep enough that each crest is its flank's closest point)."""
    fx = fz = 0.0
    for x in (-HALF, HALF):
        d = math.hypot(cx - x, cz - H)
        if d < R_TIRE:
            fx += K_TIRE * (R_TIRE - d) * (cx - x) / d
            fz += K_TIRE * (R_TIRE - d) * (cz - H) / d
    return fx, fz, math.hypot(cx, cz - (H - V))


def python_force(tire, cx, cz):
    fx, fz, *_ = tire.force(cx, cz, 0.0, 0.0, tire.patches(cx, cz))
    return fx, fz


def compiled_forces():
    """A function (cx, cz) -> (Fx, Fz) of the compiled rolling callback on the two crests (still,
    searched afresh at each position), or None where it cannot run here."""
    pytest.importorskip("numba")
    CR = pytest.importorskip("mtbmj.rolling.callback_compiled")
    if not CR.available():
        return None
    from mtbmj.rolling import frontend as R

    p = R.prepare(two_crests(), 1.0, callback="compiled")
    cb, model, data = p.callback, p.front.model, p.data
    assert isinstance(cb, CR.CompiledRollCallback)
    data.qvel[:] = 0.0

    def force(cx, cz):
        x0, z0, _, _ = cb.axle_state(data.qpos, data.qvel)
        data.qpos[cb.xq] += cx - x0
        data.qpos[cb.zq] += cz - z0
        cb.reset()
        cb(model, data)
        return float(data.ctrl[cb.a_tx]), float(data.ctrl[cb.a_tz])

    return force, p.tire


def paths():
    """Axle paths over the crests in steps of 10 um: straight down from clear of both crests until
    the trough is 8 mm into the tread, at x = -8, 0, 5 mm; across them at heights where the trough is
    in the margin, at the tread and 4 mm into it."""
    step = 1e-5
    down = np.arange(H + 0.373, H + 0.354, -step)
    across = np.arange(-0.012, 0.012, step)
    out = [[(x, z) for z in down] for x in (-0.008, 0.0, 0.005)]
    out += [[(x, z) for x in across] for z in (H - V + R_TIRE + 0.004, H - V + R_TIRE, H - V + R_TIRE - 0.004)]
    return out, step


def test_two_crests_force_is_continuous_and_the_closed_form_where_the_trough_clears():
    tire = RadialTire(two_crests(), R_TIRE, K_TIRE, B_TIRE)
    compiled = compiled_forces()
    if compiled is not None:
        compiled_force, ctire = compiled
        assert (ctire.radius, ctire.rate) == (R_TIRE, K_TIRE)  # the front end's tire is the one here
        assert ctire.rim.max_deflection > 0.02  # deeper than any depth below: the rim stays out
    trajectories, step = paths()
    clear = both = 0
    for path in trajectories:
        prev = prev_c = None
        for cx, cz in path:
            got = python_force(tire, cx, cz)
            if compiled is not None:
                cc = compiled_force(cx, cz)
                assert math.hypot(cc[0] - got[0], cc[1] - got[1]) <= 1e-6, (cx, cz, cc, got)
                if prev_c is not None:
                    assert math.hypot(cc[0] - prev_c[0], cc[1] - prev_c[1]) <= 3.0 * K_TIRE * step, (cx, cz)
                prev_c = cc
            if prev is not None:  # no step: a few k x the move (two contacts, and their shares)
                assert math.hypot(got[0] - prev[0], got[1] - prev[1]) <= 3.0 * K_TIRE * step, (cx, cz, got, prev)
            prev = got
            fx, fz, trough = crests_by_hand(cx, cz)
            if trough > R_TIRE:  # the trough clears the tread: two separate contacts
                clear += 1
                assert math.hypot(got[0] - fx, got[1] - fz) <= 1e-6, (cx, cz, got, (fx, fz))
                both += all(math.hypot(cx - x, cz - H) < R_TIRE for x in (-HALF, HALF)) and trough < R_TIRE + 0.01
    # the case that jumped: both crests touching, the trough clear of the tread but in the margin
    assert both > 500, both
    assert clear > 1000, clear


def test_washboard_force_has_no_jump():
    """Measured on main before the change: 339 N = 34 % of the 988 N peak at t = 1.1407 s; now 69 N,
    7.3 % of 951 N (the crests' own rise at 5 m/s)."""
    r = mtbmj.run_roll("washboard", 5.0, duration=2.0)
    f = r.raw["tire_force_N"]
    assert f.max() > 500.0  # the washboard works the tire
    assert np.max(np.abs(np.diff(f))) <= 0.10 * f.max()


def old_force(terrain, cx, cz, vx, vz, radius, rate, damping, margin=0.010):
    """The force of one patch per stretch within reach (the search before), written from the
    profile's segments: each connected part of the profile within reach of the axle acts at its
    closest point, max(0, k d + c tanh(3 d / 3 mm) dd/dt) along (axle - q)/|axle - q|. None where a
    part holds more than one local minimum of the distance (the case that changed)."""
    reach = radius + margin
    x = np.concatenate(([terrain.x[0] - 10.0], terrain.x, [terrain.x[-1] + 10.0]))
    z = np.concatenate(([terrain.z[0]], terrain.z, [terrain.z[-1]]))
    ax, az, ex, ez = x[:-1], z[:-1], np.diff(x), np.diff(z)
    s = np.clip(((cx - ax) * ex + (cz - az) * ez) / np.maximum(ex * ex + ez * ez, 1e-300), 0.0, 1.0)
    qx, qz = ax + s * ex, az + s * ez
    dist = np.hypot(cx - qx, cz - qz)
    vertex = np.hypot(cx - x, cz - z)  # vertex i + 1 ends segment i
    parts = []  # runs of segments within reach joined through a vertex within reach
    for i in np.flatnonzero(dist < reach):
        if parts and parts[-1][-1] == i - 1 and vertex[i] < reach:
            parts[-1].append(i)
        else:
            parts.append([i])
    fx = fz = 0.0
    for part in parts:
        values = []  # the distance's critical values along the part
        for n, i in enumerate(part):
            if n:
                values.append(vertex[i])
            values.append(dist[i])
        low = int(np.argmin(values))
        if np.any(np.diff(values[:low + 1]) > 1e-12) or np.any(np.diff(values[low:]) < -1e-12):
            return None  # not one local minimum: falls to it and rises after it
        i = min(part, key=lambda j: dist[j])
        d = radius - dist[i]
        if d > 0.0:
            nx, nz = (cx - qx[i]) / dist[i], (cz - qz[i]) / dist[i]
            dd = -(vx * nx + vz * nz)
            f = max(0.0, rate * d + damping * math.tanh(3.0 * d / 3e-3) * dd)
            fx, fz = fx + f * nx, fz + f * nz
    return fx, fz


def rolled(terrain, x0, x1, sink=0.006, step=1e-3):
    """The axle of a rigid circle of R_TIRE rolled over the profile from x0 to x1, ``sink`` lower:
    the highest centre over every profile point within reach."""
    px, pz = np.asarray(terrain.x), np.asarray(terrain.z)
    out = []
    for cx in np.arange(x0, x1, step):
        m = np.abs(px - cx) < R_TIRE
        top = np.max(pz[m] + np.sqrt(R_TIRE ** 2 - (px[m] - cx) ** 2)) if m.any() else R_TIRE
        out.append((cx, max(top, float(terrain.height(cx)) + R_TIRE) - sink))
    return out


@pytest.mark.parametrize("name, x0, x1", [("flat", -0.5, 0.5), ("rock", 0.9, 2.2), ("root", 0.8, 2.0),
                                          ("square_edge", 0.9, 2.2)])
def test_one_contact_per_stretch_is_unchanged(name, x0, x1):
    terrain = T.make(name)
    tire = RadialTire(terrain, R_TIRE, K_TIRE, B_TIRE)
    compared = 0
    for k, (cx, cz) in enumerate(rolled(terrain, x0, x1)):
        vx, vz = 5.0, 0.4 * math.sin(k)
        want = old_force(terrain, cx, cz, vx, vz, R_TIRE, K_TIRE, B_TIRE)
        if want is None:
            continue
        fx, fz, *_ = tire.force(cx, cz, vx, vz, tire.patches(cx, cz))
        assert abs(fx - want[0]) <= 1e-9 and abs(fz - want[1]) <= 1e-9, (name, cx, cz, (fx, fz), want)
        compared += want != (0.0, 0.0)
    assert compared > 0.9 * (x1 - x0) / 1e-3, compared


def test_pieces_run_as_their_segments_on_the_drum():
    """A run's pieces are consecutive along the profile, each ending where the next starts (the
    barrier between two contacts is read at that shared point). The drum's cleat has a face running
    backward in x; its pieces were turned round by the clip to the reach window, and the cleat's
    corner came out as two contacts at one point (two forces)."""
    drum = T.make("drum:radius_mm=500,cleat_height_mm=20,cleat_at_deg=10").with_speed(3.0)
    tire = RadialTire(drum, R_TIRE, K_TIRE, B_TIRE)
    rng = np.random.default_rng(5)
    backward = 0
    for k in range(200):
        cx, cz, t = rng.uniform(-0.05, 0.05), 0.36 + 0.01 * rng.random(), 0.013 * k
        ax, az, ex, ez = tire.pieces(cx, t)
        gap = np.hypot(ax[1:] - (ax[:-1] + ex[:-1]), az[1:] - (az[:-1] + ez[:-1]))
        inside = np.hypot(cx - ax[1:], cz - az[1:]) < R_TIRE + tire.margin  # the shared point within reach
        assert np.all(gap[inside] <= 1e-12), (cx, cz, t, gap[inside].max())
        backward += int(np.any(ex[1:][inside] < 0.0))
        points = [(round(p[0], 9), round(p[1], 9)) for p in tire.patches(cx, cz, t)]
        assert len(points) == len(set(points)), (cx, cz, t, points)
    assert backward > 10  # the cleat's face was met


def test_the_plain_share_depths_is_its_compiled_twin(monkeypatch):
    """Without numba the search runs share_depths as plain Python: the same patches as its twin."""
    from mtbmj.rolling import tire as tire_module

    tire = RadialTire(T.make("washboard"), R_TIRE, K_TIRE, B_TIRE)
    rng = np.random.default_rng(7)
    points = [(x, 0.02 + R_TIRE - rng.uniform(0.005, 0.03)) for x in rng.uniform(1.5, 3.0, 200)]
    twin = [tire.patches(cx, cz) for cx, cz in points]
    monkeypatch.setattr(tire_module, "_SHARE_DEPTHS", tire_module.share_depths)
    plain = [tire.patches(cx, cz) for cx, cz in points]
    assert sum(len(p) > 1 for p in plain) > 15  # runs of several contacts met (23 of the 200)
    for a, b in zip(plain, twin):
        assert len(a) == len(b)
        for pa, pb in zip(a, b):
            assert np.all(np.isclose(pa, pb, rtol=0.0, atol=1e-12)), (pa, pb)

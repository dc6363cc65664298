"""One patch search for the front end and the bike, one slot lookup for every compiled callback
(issue 38 item 4).

* ``mtbmj.rolling.tire.PatchSearch`` (the Python callbacks' search, kept over a straight stretch) and
  its compiled twin ``mtbmj.rolling.callback_compiled.update_patches`` (the compiled front end's and
  both of the compiled bike's wheels) against a brute-force search written here: the profile within
  the tire's reach split where it leaves the reach, and the exact closest point of each part, along
  trajectories that cross flats, ramps, edges, roots and rocks, so that the patch is kept over many
  refreshes and searched afresh off each straight stretch.
* ``controllers.native_data.find_slot`` against a table written here, and every compiled dispatcher
  (the drop's, the front end's, the bike's) serving each live model from its own slot only.
"""
from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco
import numpy as np
import pytest

import mtbmj
from mtbmj import compose
from mtbmj.rolling import terrain as T
from mtbmj.rolling.tire import PIECE_M, PatchSearch, RadialTire
from helpers import compiled_search

REACH_TOL = 1e-9  # relative: a closest point this near the reach is left to round-off (not compared)
GAP_M = 5 * PIECE_M  # parts of the profile within reach closer than this along it: the 10 mm pieces may join them


def brute_patches(terrain, cx: float, cz: float, radius: float, margin: float):
    """The patches of an axle at (cx, cz) by brute force, or None where the answer rests on round-off
    or on the 10 mm pieces: every segment of the whole profile (continued flat), the part of each
    within reach (|p - c| < radius + margin), consecutive parts joined where they meet (a vertex within
    reach), and each joined part's exact closest point: [(qx, qz, distance), ...] along the profile."""
    reach = radius + margin
    x = np.concatenate(([terrain.x[0] - 1e3], terrain.x, [terrain.x[-1] + 1e3]))
    z = np.concatenate(([terrain.z[0]], terrain.z, [terrain.z[-1]]))
    ax, az = x[:-1], z[:-1]
    ex, ez = np.diff(x), np.diff(z)
    length2 = ex * ex + ez * ez
    s = np.clip(((cx - ax) * ex + (cz - az) * ez) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    qx, qz = ax + s * ex, az + s * ez
    dist = np.hypot(cx - qx, cz - qz)
    if np.any(np.abs(dist - reach) <= REACH_TOL * reach):
        return None
    near = np.flatnonzero(dist < reach)
    length = np.sqrt(length2)
    along = np.concatenate(([0.0], np.cumsum(length)))  # arc length at each vertex
    parts = []  # (start, end) arc lengths of each segment's part within reach, in order
    for i in near:
        # |a - c + t e|^2 < reach^2 for t in (t0, t1)
        bx, bz = ax[i] - cx, az[i] - cz
        if length2[i] == 0.0:
            t0, t1 = 0.0, 1.0
        else:
            half = (bx * ex[i] + bz * ez[i]) / length2[i]
            root = np.sqrt(max(half * half - (bx * bx + bz * bz - reach * reach) / length2[i], 0.0))
            t0, t1 = max(-half - root, 0.0), min(-half + root, 1.0)
        parts.append((along[i] + t0 * length[i], along[i] + t1 * length[i], i))
    groups = []  # the joined parts: their segments, in order
    for k, (start, end, i) in enumerate(parts):
        if k and start - parts[k - 1][1] == 0.0:  # through a vertex within reach: the same part
            groups[-1].append(i)
            continue
        if k and start - parts[k - 1][1] < GAP_M:
            return None  # two parts this close along the profile: the pieces decide
        groups.append([i])
    patches = []
    for group in groups:
        minima = part_minima(group, dist, np.hypot(cx - x, cz - z))
        if minima is None:
            return None
        patches += [(qx[i], qz[i], dist[i]) for i in minima]
    if any(d <= 1e-9 * 1.01 for _, _, d in patches):
        return None
    return patches


def part_minima(group, dist, corner):
    """The contacts of one joined part (segments ``group``, consecutive; ``dist`` each segment's
    closest distance, ``corner`` each vertex's, vertex i + 1 between segments i and i + 1): the local
    minima of the distance along it, a segment's closest point or a corner shared by two (one
    minimum), each of a prominence (the lower over both sides of the highest distance to a lower
    point, less its own) beyond round-off; None where a minimum's prominence is within round-off of
    the search's cut (1e-12 m)."""
    values = []  # the distance's critical values along the part, each with its segment (or None)
    for k, i in enumerate(group):
        if k:
            values.append((max(corner[i], dist[i], dist[group[k - 1]]), None))
        values.append((dist[i], i))
    found = []
    for k, (v, i) in enumerate(values):
        if i is None:
            continue
        left = [w for w, _ in values[:k]]
        right = [w for w, _ in values[k + 1:]]
        if (left and left[-1] <= v + 1e-13) or (right and right[0] < v - 1e-13):
            continue  # a slope or a corner shared with the segment before: not a minimum here
        cols = []
        lower = [j for j, w in enumerate(left) if w <= v + 1e-13]  # of a level pair the earlier is the lower
        if lower:
            cols.append(max(left[lower[-1] + 1:]))
        lower = [j for j, w in enumerate(right) if w < v - 1e-13]
        if lower:
            cols.append(max(right[:lower[0]]))
        prominence = min(cols) - v if cols else np.inf
        if prominence <= 1e-9:
            if prominence > 1e-13:
                return None
            continue
        found.append(i)
    return found


def assert_same_lines(got, want, cx, cz, reach, where):
    """``got`` (the search's patches) acts as ``want`` (brute force): the same number of patches
    within reach, each on the same line (normal, distance from the axle) as the exact one. A patch
    kept over a straight stretch keeps its closest point of the last search, on the same line."""
    acting = [p for p in got if (cx - p[0]) * p[2] + (cz - p[1]) * p[3] < reach]
    assert len(acting) == len(want), (where, got, want)
    for (qx, qz, nx, nz, sx, sz, *_), (bx, bz, d) in zip(acting, want):
        assert (sx, sz) == (0.0, 0.0), where
        normal = ((cx - bx) / d, (cz - bz) / d)
        assert abs(nx - normal[0]) <= 1e-9 and abs(nz - normal[1]) <= 1e-9, (where, (nx, nz), normal)
        assert abs((cx - qx) * nx + (cz - qz) * nz - d) <= 1e-12, (where, d)
        assert abs((qx - bx) * nx + (qz - bz) * nz) <= 1e-12, where  # on the same line


TERRAINS = {
    "flat": (T.make("flat"), -0.3, 0.6),
    "root": (T.make("root:radius_mm=60,at_m=0.4"), -0.1, 1.0),
    "rock": (T.make("rock"), 0.9, 2.2),
    "step_up": (T.make("step_up:height_mm=50,at_m=0.4"), -0.1, 0.9),
    "ledge": (T.make("drop:height_mm=300,at_m=0.4"), -0.1, 0.9),
    "square_edge": (T.make("square_edge:height_mm=50,at_m=0.4"), -0.1, 1.0),
    "ramp": (T.Terrain("ramp", np.array([-2.0, 0.3, 0.8, 1.3, 4.0]), np.array([0.0, 0.0, 0.1, 0.1, 0.1]), 0.0,
                       2.0), 0.0, 1.6),
    "washboard": (T.make("washboard"), 1.0, 1.8),
    "gap": (T.Terrain("gap", np.array([-2.0, 0.0, 0.0, 0.1, 0.1, 3.0]), np.array([0, 0, -0.2, -0.2, 0, 0.0]), 0.0,
                      1.0), -0.45, 0.55),
}


def trajectory(terrain, x0, x1, radius, seed):
    """Axle positions as a rolling wheel meets them: forward in steps of 0.1-0.8 mm (now and then
    back), the tire from 30 mm deep in the ground to 8 mm clear of it."""
    rng = np.random.default_rng(seed)
    x, points = x0, []
    while x < x1:
        x += rng.uniform(0.1e-3, 0.8e-3) * (1.0 if rng.random() > 0.02 else -3.0)
        z = float(terrain.height(x)) + radius - rng.uniform(-0.008, 0.030)
        points.append((x, z))
    return points


def _tire(terrain):
    setup = compose.setup(mtbmj.load_config("S12"))
    from mtbmj.rolling.frontend import tire_values

    rate, damping = tire_values(setup)
    return RadialTire(terrain, setup.tire_radius, rate, damping, rim=setup.tire.rim)


@pytest.mark.parametrize("name", list(TERRAINS))
def test_the_python_search_acts_as_the_brute_force_search(name):
    terrain, x0, x1 = TERRAINS[name]
    tire = _tire(terrain)
    reach = tire.radius + tire.margin
    search = PatchSearch(tire)
    assert search.straight is not None
    points = trajectory(terrain, x0, x1, tire.radius, seed=k_seed(name))
    searched = compared = 0
    for k, (cx, cz) in enumerate(points):
        searched += search.refresh(cx, cz)
        want = brute_patches(terrain, cx, cz, tire.radius, tire.margin)
        if want is None:
            continue
        assert_same_lines(search.patches, want, cx, cz, reach, (name, k, cx, cz))
        compared += 1
    assert compared > 0.9 * len(points)
    assert len(points) - searched > 100, searched  # the patch was kept over straight stretches
    assert searched >= (1 if name == "flat" else 100), searched  # and searched afresh off them


def k_seed(name: str) -> int:
    return sum(map(ord, name))


def assert_same_patches(got, want, where):
    """The compiled search's patches are the Python search's (to round-off: bit-identical in practice)."""
    assert len(got) == len(want), (where, got, want)
    for a, b in zip(got, want):
        a, b = np.array(a), np.array(b)
        assert np.all(np.isclose(a, b, rtol=0.0, atol=1e-12)), (where, a, b)


def test_without_straight_stretches_every_refresh_searches():
    """The drum (a moving surface) and a terrain whose geometry is not its points: no shortcut."""
    drum = T.make("drum:radius_mm=500,cleat_height_mm=20,cleat_at_deg=10").with_speed(3.0)
    search = PatchSearch(_tire(drum))
    assert search.straight is None
    for k in range(50):
        t = 1e-3 * k
        assert search.refresh(0.0, 0.362, t)
        assert search.patches == search.tire.patches(0.0, 0.362, t)

    class Shifted(T.Terrain):
        def polyline(self, x_lo, x_hi, t=0.0):
            px, pz, vx, vz = super().polyline(x_lo, x_hi, t)
            return px, pz + 0.01, vx, vz

    flat = T.make("flat")
    shifted = Shifted(flat.name, flat.x, flat.z, flat.start_x, flat.length)
    assert PatchSearch(_tire(shifted)).straight is None


# ----------------------------------------------------------------------------------------------
# the compiled search: the front end's slot and the bike's wheel rows
# ----------------------------------------------------------------------------------------------
_compiled = compiled_search  # tests/helpers.py: skipped where the compiled path is not there


@pytest.mark.parametrize("name", ["root", "rock", "ledge", "ramp", "gap"])
def test_the_compiled_search_is_the_python_search(name):
    """update_patches on a compiled front end's slot: the same decisions (search or keep) and the
    same patches as PatchSearch at every refresh, and so the brute force's lines."""
    CR = _compiled()
    from mtbmj.rolling import frontend as R

    terrain, x0, x1 = TERRAINS[name]
    p = R.prepare(terrain, 3.0, callback="compiled")
    cb, tire = p.callback, p.tire
    I, F = CR._INTS[cb.slot], CR._FLOATS[cb.slot]
    cb.reset()
    search = PatchSearch(tire)
    reach = tire.radius + tire.margin
    for k, (cx, cz) in enumerate(trajectory(terrain, x0, x1, tire.radius, seed=k_seed(name) + 1)):
        assert bool(CR.update_patches(I, F, cx, cz, 0.0)) == search.refresh(cx, cz), (name, k)
        assert_same_patches(cb.patches, search.patches, (name, k))
        want = brute_patches(terrain, cx, cz, tire.radius, tire.margin)
        if want is not None:
            assert_same_lines(cb.patches, want, cx, cz, reach, (name, k))


def test_the_bike_wheels_use_the_same_compiled_search():
    """Each of the compiled bike's wheel rows is a slot of the front end's layout that update_patches
    serves: the same decisions and patches as a PatchSearch of that tire."""
    CR = _compiled()
    BC = pytest.importorskip("mtbmj.bike.callback_compiled")
    from mtbmj.bike import run

    terrain, x0, x1 = TERRAINS["root"]
    p = run.prepare("sst", "root:radius_mm=60,at_m=0.4", 4.0, callback="compiled")
    cb = p.callback
    assert isinstance(cb, BC.CompiledBikeCallback)
    cb.reset()
    WI, WF = BC.WI, BC.WF
    for k, tire in enumerate((p.front_tire, p.rear_tire)):
        I = BC._WINTS[cb.slot, k * WI:(k + 1) * WI]
        F = BC._WFLOATS[cb.slot, k * WF:(k + 1) * WF]
        search = PatchSearch(tire)
        kept = 0
        for j, (cx, cz) in enumerate(trajectory(p.terrain, x0, x1, tire.radius, seed=7 + k)):
            searched = bool(CR.update_patches(I, F, cx, cz, 0.0))
            assert searched == search.refresh(cx, cz), (k, j)
            assert_same_patches(cb.patches(k), search.patches, (k, j))
            kept += not searched
        assert kept > 200


def test_a_run_searches_less_where_the_profile_is_straight():
    """The front end on the root: both callbacks count the same searches, far fewer than the
    refreshes (two a step at 4 m/s), and agree as before (tests/test_rolling_compiled.py)."""
    _compiled()
    from mtbmj.rolling.frontend import run_roll

    py = run_roll("root:radius_mm=60,at_m=0.4", 4.0, duration=0.5, callback="python")
    cc = run_roll("root:radius_mm=60,at_m=0.4", 4.0, duration=0.5, callback="compiled")
    assert py.info["geometry_refreshes"] == cc.info["geometry_refreshes"]
    # RK4 at 0.1 ms: four evaluations a step, a refresh due at two of them (every 0.05 ms)
    refreshes = 2 * (py.info["callback_calls"] // 4)
    assert cc.info["geometry_refreshes"] < 0.7 * refreshes
    for name in ("fork_mm", "tire_mm", "axle_z_mm"):
        assert np.max(np.abs(py.raw[name] - cc.raw[name])) <= 1e-6, name


# ----------------------------------------------------------------------------------------------
# the one slot lookup
# ----------------------------------------------------------------------------------------------
def test_find_slot_is_the_first_used_row_holding_the_model():
    pytest.importorskip("numba")
    from mtbmj.controllers import native_data

    width = 5
    table = np.zeros((8, width), dtype=np.int64)
    table[:, 1:] = 77  # other columns never match
    table[[1, 3, 4, 6], 0] = [1000, 2000, 1000, 3000]  # 1000 twice: the first row is the one served
    address = table.ctypes.data
    for used in range(9):
        for model in (77, 1000, 2000, 3000, 4000):
            rows = np.flatnonzero(table[:used, 0] == model)
            want = int(rows[0]) if rows.size else -1
            assert native_data.find_slot(address, used, width, model) == want, (used, model)


def test_every_compiled_dispatcher_looks_its_slot_up_through_find_slot():
    pytest.importorskip("numba")
    from pathlib import Path

    from mtbmj.controllers import compiled, jit, native_data

    CR = _compiled()
    BC = pytest.importorskip("mtbmj.bike.callback_compiled")
    for module in (compiled, CR, BC):
        plain = module._dispatch._pyfunc
        reached = [plain.__globals__.get(n) for n in plain.__code__.co_names]
        assert native_data.find_slot in reached, module.__name__
        assert "native_data.py" in {Path(p).name for p in jit.compiled_sources(module._dispatch)}


def test_each_dispatcher_serves_each_live_model_from_its_own_slot_only():
    """Two models alive in each registry (the drop's fork, the front end, the bike) and models of
    none: the one dispatcher function of a registry, called with either model, acts on that model
    with that model's settings and counts the call in its slot alone; it leaves every other model
    (another registry's, or none's) as it was."""
    _compiled()
    from mtbmj import controllers as law
    from mtbmj.bike import run
    from mtbmj.controllers import compiled
    from mtbmj.drop import scene
    from mtbmj.rolling import frontend as R

    # the drop's fork: two scenes, a soft and a hard spring
    setup = compose.setup(mtbmj.load_config("S1"))
    scenes = [scene.build(setup), scene.build(setup)]
    laws = [law.ForkLaw(law.LinearSpring(k), law.LinearDamper(0.0), law.NoFriction()) for k in (1e4, 3e4)]
    forks = [compiled.CompiledForkCallback(sc.model, fl) for sc, fl in zip(scenes, laws)]
    # the front end: two front ends at two servo speeds
    rolls = [R.prepare("root", speed, drive="servo", callback="compiled") for speed in (2.0, 5.0)]
    # the bike: two bikes
    bikes = [run.prepare("sst", "flat", speed, callback="compiled") for speed in (3.0, 4.0)]

    def fork_data(i):
        data = mujoco.MjData(scenes[i].model)
        data.qpos[scenes[i].fork_qpos] = 0.05
        return data

    for caller in forks:  # either callback object is the one dispatcher
        for i, sc in enumerate(scenes):
            before = [f.calls for f in forks]
            data = fork_data(i)
            caller(sc.model, data)
            dof = int(sc.model.joint("fork").dofadr[0])
            assert data.qfrc_applied[dof] == -laws[i].force(0.05, 0.0)
            assert [f.calls - b for f, b in zip(forks, before)] == [int(j == i) for j in range(2)]
    for caller in rolls:
        for i, p in enumerate(rolls):
            before = [q.callback.calls for q in rolls]
            caller.callback(p.front.model, p.data)
            assert p.data.ctrl[p.callback.a_dv] == p.callback.speed == (2.0, 5.0)[i]
            assert [q.callback.calls - b for q, b in zip(rolls, before)] == [int(j == i) for j in range(2)]
    for caller in bikes:
        for i, p in enumerate(bikes):
            before = [q.callback.calls for q in bikes]
            caller.callback(p.bike.model, p.data)
            assert [q.callback.calls - b for q, b in zip(bikes, before)] == [int(j == i) for j in range(2)]
    # a model of another registry, or of none: left alone by every dispatcher, nothing counted
    stranger = scene.build(setup).model
    counts = [c.calls for c in forks] + [p.callback.calls for p in rolls + bikes]
    others = {id(forks[0]): rolls[0].front.model, id(rolls[0].callback): bikes[0].bike.model,
              id(bikes[0].callback): scenes[0].model}
    for caller in (forks[0], rolls[0].callback, bikes[0].callback):
        for model in (stranger, others[id(caller)]):
            data = mujoco.MjData(model)
            data.qpos[:] = 0.01
            snapshot = [a.copy() for a in (data.qpos, data.ctrl, data.qfrc_applied, data.act)]
            caller(model, data)
            for a, b in zip(snapshot, (data.qpos, data.ctrl, data.qfrc_applied, data.act)):
                assert np.array_equal(a, b)
    assert counts == [c.calls for c in forks] + [p.callback.calls for p in rolls + bikes]

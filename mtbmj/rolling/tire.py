"""The tire on terrain: a radial Kelvin-Voigt spring per contact patch, exact on any profile.

Why not MuJoCo contacts (docs/mujoco.md §2-3): a heightfield or mesh makes one contact per cell or
triangle in reach, each a full spring, so the stiffness multiplies by their number (11.8x on a
bump in the measurement), and the calibration of negative solref needs the inverse inertia A
along each contact normal, which changes on every edge and slope. Dividing solref by the contact
count each step fixes neither the count's jumps nor the varying A.

The model here instead computes the tire force from the terrain polyline itself:

1. Geometry (``patches``): the exact distance from the axle to every terrain segment near the
   wheel. A *patch* is a maximal run of consecutive segments within ``radius + margin`` of the
   axle; each patch contributes its closest point q and the unit normal n = (axle - q)/|axle - q|.
   The whole tire circle meets the whole profile: the tire hits a step at its corner, ahead of
   the axle, with a force tilted back (the horizontal axle force of an edge), bridges holes
   shorter than its chord, and rides a heightfield as one patch, not one spring per cell.
2. Force (``force``), per patch: radial deflection d = radius - (axle - q).n, its rate
   dd/dt = -(v_axle - v_surface).n, f = max(0, K d + B tanh(3 d / 3 mm) dd/dt) when d > 0, along
   n (``controllers.tire.rolling_tire_force``): the damping sets in over the patch's first
   millimetres, so rolling onto an edge meets no jump of c v n at first touch. One patch on one
   surface settled deeper than 3 mm is exactly the configured K and B: on a flat, on a bump top,
   on an edge, on a sampled (heightfield) profile. A contact can only push.

Geometry is refreshed every ``refresh`` seconds (0.05 ms, at most 0.25 mm of travel: chosen by
accuracy against the rolling reference, see ``REFRESH_S``) by the control callback; between
refreshes each patch is its tangent line at q, which is exact on straight segments and off by
s^2 / (2 rho) on a curved one (s the travel since the refresh, rho the radius of curvature). ``margin`` (10 mm) sees a patch coming before it
touches, so the force starts at d = 0 at the step where it should.

3. The refresh (``PatchSearch``, one per tire: the front end's and each of the bike's wheels; its
   compiled twin ``mtbmj.rolling.callback_compiled.update_patches``): the search above, except while
   the axle stays over the straight stretch of the profile (``StraightStretches``) that its single
   patch lies on. There the tire's whole reach is one straight line, the search would return that
   line's patch again, and the patch of the last search is kept: exact (the tangent line is the
   line) and free, on the flats and ramps where a run spends most of its time.
"""
from __future__ import annotations

import bisect
import math

import numpy as np

from mtbmj.controllers.tire import rolling_tire_force

MARGIN_M = 0.010
# The contact patches are found afresh every half engine step (0.05 ms) or 0.25 mm of axle travel,
# whichever comes first: chosen by accuracy against the rolling reference (mtbmj.rolling.reference,
# exact geometry at every evaluation). On the 50 mm root at 4 m/s the fork's travel differed from it
# by 0.10 mm with the old 1 ms / 5 mm refresh; on the washboard at 5 m/s and 90 degrees by 0.019 mm at
# 0.1 ms / 0.5 mm and 0.004 mm with this one.
REFRESH_S = 0.5e-4
REFRESH_DISTANCE_M = 0.25e-3
PIECE_M = 0.01


class RadialTire:
    """Tire of ``radius`` (m), radial ``rate`` (N/m) and ``damping`` (N s/m) on ``terrain``."""

    def __init__(self, terrain, radius: float, rate: float, damping: float, margin: float = MARGIN_M, rim=None):
        self.rim = rim  # controllers.Rim: past its maximum deflection the rim strikes, or None
        self.terrain = terrain
        self.radius = float(radius)
        self.rate = float(rate)
        self.damping = float(damping)
        self.margin = float(margin)

    def segment_distances(self, cx: float, cz: float, t: float = 0.0):
        """Distances from the axle to the terrain near it, cut into pieces of at most
        ``PIECE_M`` (so a long straight segment does not join a patch to an obstacle next to
        it), and the closest point of each piece."""
        reach = self.radius + self.margin
        px, pz, _, _ = self.terrain.polyline(cx - reach, cx + reach, t)
        ax, az = px[:-1], pz[:-1]
        ex, ez = px[1:] - ax, pz[1:] - az
        # clip the segments to the reach window in x before cutting them into pieces
        safe = np.where(ex != 0.0, ex, 1.0)
        t0 = np.where(ex != 0.0, np.clip((cx - reach - ax) / safe, 0.0, 1.0), 0.0)
        t1 = np.where(ex != 0.0, np.clip((cx + reach - ax) / safe, 0.0, 1.0), 1.0)
        ax, az, ex, ez = ax + t0 * ex, az + t0 * ez, (t1 - t0) * ex, (t1 - t0) * ez
        length = np.hypot(ex, ez)
        k = np.maximum(1, np.ceil(length / PIECE_M)).astype(np.intp)
        if k.max() > 1:
            idx = np.repeat(np.arange(k.size), k)
            kk = k[idx]
            first = np.repeat(np.cumsum(k) - k, k)
            f0 = (np.arange(idx.size) - first) / kk
            f1 = f0 + 1.0 / kk
            ax, az, ex, ez = ax[idx] + f0 * ex[idx], az[idx] + f0 * ez[idx], (f1 - f0) * ex[idx], (f1 - f0) * ez[idx]
        length2 = ex * ex + ez * ez
        length2 = np.where(length2 > 0.0, length2, 1.0)
        s = np.clip(((cx - ax) * ex + (cz - az) * ez) / length2, 0.0, 1.0)
        qx, qz = ax + s * ex, az + s * ez
        return np.hypot(cx - qx, cz - qz), qx, qz

    def distance(self, cx: float, cz: float, t: float = 0.0) -> float:
        """Exact shortest distance (m) from the axle to the terrain."""
        d, _, _ = self.segment_distances(cx, cz, t)
        return float(d.min())

    def patches(self, cx: float, cz: float, t: float = 0.0) -> list[tuple[float, ...]]:
        """Contact patches near the axle: (qx, qz, nx, nz, surface vx, surface vz) each."""
        d, qx, qz = self.segment_distances(cx, cz, t)
        near = d < self.radius + self.margin
        if not near.any():
            return []
        edges = np.flatnonzero(np.diff(np.concatenate(([0], near.view(np.int8), [0]))))
        out = []
        for a, b in zip(edges[::2], edges[1::2]):
            i = a + int(np.argmin(d[a:b]))
            dist = float(d[i])
            if dist <= 1e-9:
                continue
            x, z = float(qx[i]), float(qz[i])
            vx, vz = self.terrain.surface_velocity(x, z, t)
            out.append((x, z, (cx - x) / dist, (cz - z) / dist, vx, vz))
        return out

    def shallowest(self, cx, cz, patches, deepest):
        """The radial depth (m) of the shallowest patch in ``patches`` (negative: its clearance),
        ``deepest`` where there is none: where a new patch touches down beside a deep one."""
        r = self.radius
        return min((r - ((cx - qx) * nx + (cz - qz) * nz) for qx, qz, nx, nz, _, _ in patches), default=deepest)

    def force(self, cx, cz, vx, vz, patches):
        """(Fx, Fz, deepest deflection m, its rate m/s, active patches) on the axle."""
        r, k, b = self.radius, self.rate, self.damping
        fx = fz = 0.0
        deepest = -math.inf
        deepest_rate = 0.0
        active = 0
        for qx, qz, nx, nz, sx, sz in patches:
            d = r - ((cx - qx) * nx + (cz - qz) * nz)
            rate = -((vx - sx) * nx + (vz - sz) * nz)
            if d > deepest:
                deepest, deepest_rate = d, rate
            if d > 0.0:
                f = max(0.0, rolling_tire_force(k, b, d, rate))
                if self.rim is not None:
                    f += self.rim.force(d, rate)
                if f > 0.0:
                    fx += f * nx
                    fz += f * nz
                    active += 1
        if deepest == -math.inf:
            deepest = r - self.radius - self.margin
        return fx, fz, deepest, deepest_rate, active


def stretch(x, z, reach: float, i: int, cx: float):
    """``StraightStretches.segment`` on the corners (x, z), i = bisect_right(x, cx) - 1: (ok, x0, z0,
    x1, z1, lo, hi), ok False where no straight piece holds the reach (a plain function: the
    compiled callbacks compile it)."""
    n = len(x)
    if i < 0:  # before the profile (flat): the first stretch continued
        i = 0
    j = min(i + 1, n - 1)
    x0, z0, x1, z1 = x[i], z[i], x[j], z[j]
    lo = -math.inf if i == 0 else x0
    hi = math.inf if i >= n - 2 else x1
    if i >= n - 1:  # past the profile (flat): the last stretch continued
        x0, z0, x1, z1 = x[n - 2], z[n - 2], x[n - 1], z[n - 1]
        lo, hi = (x[n - 2] if n > 2 else -math.inf), math.inf
    ok = cx - reach >= lo and cx + reach <= hi and x1 > x0
    return ok, x0, z0, x1, z1, lo + reach, hi - reach


class StraightStretches:
    """Straight stretches of a static profile: where the whole reach of a tire (``reach``: radius +
    margin either side of the axle) lies on one straight segment, its contact patch is one straight
    line, known in closed form: the foot of the perpendicular from the axle, with the line's normal."""

    def __init__(self, terrain, reach: float):
        # the profile's corners: vertices where the slope changes (collinear neighbours merged, the
        # flat continuations before the first and after the last point included)
        x = [float(terrain.x[0]) - 1.0] + [float(v) for v in terrain.x] + [float(terrain.x[-1]) + 1.0]
        z = [float(terrain.z[0])] + [float(v) for v in terrain.z] + [float(terrain.z[-1])]
        keep_x, keep_z = [x[0]], [z[0]]
        for i in range(1, len(x) - 1):
            ax, az = x[i] - keep_x[-1], z[i] - keep_z[-1]
            bx, bz = x[i + 1] - x[i], z[i + 1] - z[i]
            if ax > 0.0 and bx > 0.0 and ax * bz == bx * az:
                continue  # on the line through its neighbours: not a corner
            keep_x.append(x[i])
            keep_z.append(z[i])
        keep_x.append(x[-1])
        keep_z.append(z[-1])
        self.x, self.z = keep_x, keep_z
        self.reach = float(reach)

    def segment(self, cx: float):
        """(x0, z0, x1, z1, lo, hi) of the straight piece holding [cx - reach, cx + reach], with
        the axle positions (lo, hi) for which that stays true, or None (an edge, a corner, a curve
        within reach)."""
        ok, x0, z0, x1, z1, lo, hi = stretch(self.x, self.z, self.reach, bisect.bisect_right(self.x, cx) - 1, cx)
        return (x0, z0, x1, z1, lo, hi) if ok else None

    def patch(self, cx: float, cz: float, radius: float, margin: float):
        """The one patch (qx, qz, nx, nz, 0, 0) of an axle over a straight stretch (a list of it,
        empty when the line is farther than radius + margin), or None off a straight stretch."""
        seg = self.segment(cx)
        if seg is None:
            return None
        x0, z0, x1, z1, _, _ = seg
        ex, ez = x1 - x0, z1 - z0
        length = math.hypot(ex, ez)
        ex, ez = ex / length, ez / length
        s = (cx - x0) * ex + (cz - z0) * ez
        qx, qz = x0 + s * ex, z0 + s * ez
        dist = math.hypot(cx - qx, cz - qz)
        if dist >= radius + margin or dist <= 1e-9:
            return []
        return [(qx, qz, (cx - qx) / dist, (cz - qz) / dist, 0.0, 0.0)]


def straight_stretches(tire: RadialTire) -> StraightStretches | None:
    """The straight stretches of ``tire``'s terrain at its reach, or None where the shortcut does not
    hold: a moving surface (the drum), or a terrain or tire whose geometry is not the stock search on
    the profile's points (a subclass overriding ``polyline`` or ``patches``)."""
    from mtbmj.rolling.terrain import Terrain

    ter = tire.terrain
    if ter.moving or type(ter).polyline is not Terrain.polyline or type(tire).patches is not RadialTire.patches:
        return None
    return StraightStretches(ter, tire.radius + tire.margin)


class PatchSearch:
    """The contact patches of one tire, refreshed by its control callback: searched afresh
    (``RadialTire.patches``), except while the axle stays over the straight stretch its one patch
    lies on (``valid``, the axle x interval; None: search at the next refresh), where the patch of
    the last search is kept. The front end's callback has one, the bike's one per wheel; the compiled
    callbacks do the same in ``mtbmj.rolling.callback_compiled.update_patches``."""

    def __init__(self, tire: RadialTire):
        self.tire = tire
        self.straight = straight_stretches(tire)
        self.patches: list = []
        self.valid: tuple[float, float] | None = None

    def reset(self) -> None:
        """Forget the patches: the next refresh searches."""
        self.patches, self.valid = [], None

    def refresh(self, cx: float, cz: float, t: float = 0.0) -> bool:
        """The patches for the axle at (cx, cz) at time t; True when it searched, False when it kept
        the last patch (the axle still over its straight stretch)."""
        valid = self.valid
        if valid is not None and valid[0] <= cx <= valid[1]:
            return False
        self.patches = self.tire.patches(cx, cz, t)
        seg = self.straight.segment(cx) if self.straight is not None and len(self.patches) == 1 else None
        self.valid = None if seg is None else (seg[4], seg[5])
        return True


__all__ = ["RadialTire", "PatchSearch", "StraightStretches", "stretch", "straight_stretches", "MARGIN_M",
           "REFRESH_S", "REFRESH_DISTANCE_M"]

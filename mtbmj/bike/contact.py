"""Straight stretches of a terrain profile: where the tire's contact patch is one straight line.

The radial tire (``mtbmj.rolling.tire.RadialTire``) finds its contact patches by the exact
distances from the axle to the profile cut into 10 mm pieces, which costs most of a bike run's
time. Where the whole reach of the tire (radius + margin either side of the axle) lies on one
straight segment of the profile (the flat lead-in, the flat between obstacles, a ramp), the answer
is known in closed form: one patch, the foot of the perpendicular from the axle onto that line,
with the line's normal. ``StraightStretches`` says where that holds; the engine's callback keeps
its patch there instead of searching again, and the reference computes the patch directly. Both
are exact: the search would return the same single patch.
"""
from __future__ import annotations

import bisect
import math


def stretch(x, z, reach: float, i: int, cx: float):
    """``StraightStretches.segment`` on the corners (x, z), i = bisect_right(x, cx) - 1: (ok, x0, z0,
    x1, z1, lo, hi), ok False where no straight piece holds the reach (a plain function: the
    compiled bike callback compiles it)."""
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


__all__ = ["StraightStretches", "stretch"]

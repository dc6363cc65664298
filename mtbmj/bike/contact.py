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


class StraightStretches:
    def __init__(self, terrain, reach: float):
        self.x = [float(v) for v in terrain.x]
        self.z = [float(v) for v in terrain.z]
        self.reach = float(reach)

    def segment(self, cx: float):
        """(x0, z0, x1, z1, lo, hi) of the straight piece holding [cx - reach, cx + reach], with
        the axle positions (lo, hi) for which that stays true, or None (an edge, a corner, a curve
        within reach)."""
        x, z, reach = self.x, self.z, self.reach
        i = bisect.bisect_right(x, cx) - 1
        if i < 0:
            x0, z0, x1, z1 = x[0] - 1.0, z[0], x[0], z[0]
            lo, hi = -math.inf, x[0]
        elif i >= len(x) - 1:
            x0, z0, x1, z1 = x[-1], z[-1], x[-1] + 1.0, z[-1]
            lo, hi = x[-1], math.inf
        else:
            x0, z0, x1, z1 = x[i], z[i], x[i + 1], z[i + 1]
            lo, hi = x0, x1
        if not (cx - reach >= lo and cx + reach <= hi) or x1 <= x0:
            return None
        return x0, z0, x1, z1, lo + reach, hi - reach

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


__all__ = ["StraightStretches"]

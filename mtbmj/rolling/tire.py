"""The tire on terrain: a radial Kelvin-Voigt spring per contact patch, exact on any profile.

Why not MuJoCo contacts (docs/mujoco.md §2-3): a heightfield or mesh makes one contact per cell or
triangle in reach, each a full spring, so the stiffness multiplies by their number (11.8x on a
bump in the measurement), and the calibration of negative solref needs the inverse inertia A
along each contact normal, which changes on every edge and slope. Dividing solref by the contact
count each step fixes neither the count's jumps nor the varying A.

The model here instead computes the tire force from the terrain polyline itself:

1. Geometry (``patches``): the exact distance from the axle to every terrain segment near the
   wheel, cut into pieces of at most 10 mm. A *run* is a maximal sequence of consecutive pieces
   within ``radius + margin`` of the axle; its *contacts* are the local minima of the distance
   along it (``share_depths``), each a patch with its closest point q and the unit normal
   n = (axle - q)/|axle - q|. The whole tire circle meets the whole profile: the tire hits a step at
   its corner, ahead of the axle, with a force tilted back (the horizontal axle force of an edge),
   bridges holes shorter than its chord, and rides a heightfield as one patch, not one spring per
   cell.

   Several contacts in one run share its depth, continuously in the axle's position. Seen as
   depths u = radius - distance, the tire's overlap with the terrain at each level h in (0, max u)
   is a set of intervals; each interval bears the thickness dh, shared among the contacts in it in
   proportion to what they bear above h. A contact alone bears its whole depth u (share 1:
   exactly the single patch of before on a flat, a bump, an edge). Two crests under the tire with
   the trough between them clear of it (deeper than the tread) bear u1 and u2; as the trough comes
   within the tire (its depth ub > 0), each keeps its depth down to ub and the overlap below it,
   ub deep, is shared in proportion: e_i = (u_i - ub) (1 + ub / (u1 + u2 - 2 ub)), summing to
   u1 + u2 - ub, the overlap's. A contact born at a fold of the distance (its prominence 0) bears 0;
   one merging into a deeper one bears 0 when it goes. Each patch carries its share e/u and its
   prominence (how far its distance stands below the way to a deeper contact).

   Why not one patch per run (the search before) or per minimum capped by its prominence: a run is one
   patch at its closest point until the trough between two crests leaves the margin, and then the
   second crest enters already millimetres deep (the washboard at 5 m/s: a 339 N jump, 34 % of the
   force's peak, in one 0.1 ms row). Capping each minimum but the deepest at its prominence makes
   the depth's sum continuous but not the force: when two minima swap which one is deeper, the
   full depth and the capped one swap between two normals (94 N on the same washboard). Sharing
   in proportion has no deepest to choose.
2. Force (``force``), per patch: radial deflection d = radius - (axle - q).n, its rate
   dd/dt = -(v_axle - v_surface).n, f = w max(0, K d + B tanh(3 d / 3 mm) dd/dt) when d > 0, along
   n (``controllers.tire.rolling_tire_force``), w the patch's share (1 alone): the damping sets in
   over the patch's first millimetres, so rolling onto an edge meets no jump of c v n at first
   touch. The share multiplies the law at the patch's own depth, not the law at the depth it
   bears: the spring part is then K e, and the damping's ramp sees the contact's depth, so a curve
   sampled in chords, whose flank nearly parallel to the tread makes a cluster of minima
   micrometres apart, acts as the one contact it is (the law at its share of depth would give each
   minimum of the cluster its own damping ramp, their sum up to their number times one contact's).
   One patch on one surface settled deeper than 3 mm is exactly the configured K and B: on a flat,
   on a bump top, on an edge, on a sampled (heightfield) profile. A contact can only push. The
   deflection probe is the deepest patch's d (the exact closest distance, as before); the touch
   probe (``shallowest``) the shallowest d of the patches of a prominence of at least 0.1 mm.

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
# A minimum whose prominence is below this (m) is no contact of its own: round-off makes such
# minima between the pieces of a straight line (a contact this shallow pushes with < 1e-7 N)
CAP_MIN_M = 1e-12
# The touch probe (``shallowest``) looks at patches of at least this prominence (m)
TOUCH_CAP_M = 1e-4


class RadialTire:
    """Tire of ``radius`` (m), radial ``rate`` (N/m) and ``damping`` (N s/m) on ``terrain``."""

    def __init__(self, terrain, radius: float, rate: float, damping: float, margin: float = MARGIN_M, rim=None):
        self.rim = rim  # controllers.Rim: past its maximum deflection the rim strikes, or None
        self.terrain = terrain
        self.radius = float(radius)
        self.rate = float(rate)
        self.damping = float(damping)
        self.margin = float(margin)

    def pieces(self, cx: float, t: float = 0.0):
        """The terrain near the axle cut into pieces of at most ``PIECE_M`` (so a long straight
        segment does not join a patch to an obstacle next to it), in order along the profile:
        (ax, az, ex, ez), each piece from (ax, az) to (ax + ex, az + ez)."""
        reach = self.radius + self.margin
        px, pz, _, _ = self.terrain.polyline(cx - reach, cx + reach, t)
        ax, az = px[:-1], pz[:-1]
        ex, ez = px[1:] - ax, pz[1:] - az
        # clip the segments to the reach window in x before cutting them into pieces, each running as
        # its segment does (one running backward, on the drum, too: a piece's end is the next one's start)
        safe = np.where(ex != 0.0, ex, 1.0)
        t0 = np.where(ex != 0.0, np.clip((cx - reach - ax) / safe, 0.0, 1.0), 0.0)
        t1 = np.where(ex != 0.0, np.clip((cx + reach - ax) / safe, 0.0, 1.0), 1.0)
        t0, t1 = np.minimum(t0, t1), np.maximum(t0, t1)
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
        return ax, az, ex, ez

    def segment_distances(self, cx: float, cz: float, t: float = 0.0):
        """Distances from the axle to the terrain's pieces near it (``pieces``), and the closest
        point of each piece."""
        ax, az, ex, ez = self.pieces(cx, t)
        qx, qz = closest_points(cx, cz, ax, az, ex, ez)
        return np.hypot(cx - qx, cz - qz), qx, qz

    def distance(self, cx: float, cz: float, t: float = 0.0) -> float:
        """Exact shortest distance (m) from the axle to the terrain."""
        d, _, _ = self.segment_distances(cx, cz, t)
        return float(d.min())

    def patches(self, cx: float, cz: float, t: float = 0.0) -> list[tuple[float, ...]]:
        """Contact patches near the axle: (qx, qz, nx, nz, surface vx, surface vz, share, prominence)
        each, one per contact of a run of pieces within reach (``share_depths``): ``share`` the
        fraction of its depth it bears (1 for a contact alone; its force is that fraction of the
        tire's law at its depth), ``prominence`` (m, inf for a run's deepest) how far it stands from
        a deeper one (module doc, 1)."""
        ax, az, ex, ez = self.pieces(cx, t)
        qx, qz = closest_points(cx, cz, ax, az, ex, ez)
        dx, dz = cx - qx, cz - qz
        d = np.hypot(dx, dz)
        near = d < self.radius + self.margin
        if not near.any():
            return []
        d2 = dx * dx + dz * dz
        ux, uz = cx - (ax + ex), cz - (az + ez)
        v2 = ux * ux + uz * uz  # each piece's end: the vertex it shares with the next
        edges = np.flatnonzero(np.diff(np.concatenate(([0], near.view(np.int8), [0]))))
        out = []
        r = self.radius
        for a, b in zip(edges[::2], edges[1::2]):
            n = int(b - a)
            # a run along which the distance falls, then rises (most): one contact, alone (share_depths'
            # answer: its first lowest point, the whole depth)
            g = np.empty(2 * n - 1)
            g[0::2] = d2[a:b]
            g[1::2] = np.maximum(v2[a:b - 1], np.maximum(d2[a:b - 1], d2[a + 1:b]))
            dg = np.diff(g)
            up = np.flatnonzero(dg > 0.0)
            if up.size == 0 or not np.any(dg[up[0]:] < 0.0):
                i = a + int(np.argmin(g)) // 2
                depth = r - math.sqrt(d2[i])
                work = np.array([i - a, depth, depth, math.inf])
                n, k = 1, 1
            else:
                work = np.empty(SHARE_BLOCKS * n)
                k = _share_depths()(d2[a:b], v2[a:b - 1].copy(), n, r, CAP_MIN_M, work)
            for c in range(k):
                i = a + int(work[c])
                dist = float(d[i])
                if dist <= 1e-9:
                    continue
                x, z = float(qx[i]), float(qz[i])
                vx, vz = self.terrain.surface_velocity(x, z, t)
                w = share(float(work[n + c]), float(work[2 * n + c]))
                out.append((x, z, (cx - x) / dist, (cz - z) / dist, vx, vz, w, float(work[3 * n + c])))
        return out

    def shallowest(self, cx, cz, patches, deepest):
        """The radial depth (m) of the shallowest patch in ``patches`` (negative: its clearance),
        ``deepest`` where there is none: where a new patch touches down beside a deep one. Patches of
        a prominence below ``TOUCH_CAP_M`` are not looked at (the chord sampling of a curve makes
        such minima, micrometres apart, in clusters that share one contact's depth)."""
        r = self.radius
        return min((r - ((cx - qx) * nx + (cz - qz) * nz) for qx, qz, nx, nz, _, _, _, prom in patches
                    if prom >= TOUCH_CAP_M), default=deepest)

    def force(self, cx, cz, vx, vz, patches):
        """(Fx, Fz, deepest deflection m, its rate m/s, active patches) on the axle: per patch its
        share of the tire's law at its radial deflection d and rate dd/dt."""
        r, k, b = self.radius, self.rate, self.damping
        fx = fz = 0.0
        deepest = -math.inf
        deepest_rate = 0.0
        active = 0
        for qx, qz, nx, nz, sx, sz, w, _ in patches:
            d = r - ((cx - qx) * nx + (cz - qz) * nz)
            rate = -((vx - sx) * nx + (vz - sz) * nz)
            if d > deepest:
                deepest, deepest_rate = d, rate
            if d > 0.0:
                f = max(0.0, rolling_tire_force(k, b, d, rate))
                if self.rim is not None:
                    f += self.rim.force(d, rate)
                f *= w
                if f > 0.0:
                    fx += f * nx
                    fz += f * nz
                    active += 1
        if deepest == -math.inf:
            deepest = r - self.radius - self.margin
        return fx, fz, deepest, deepest_rate, active


def share(depth: float, borne: float) -> float:
    """The fraction of its ``depth`` a contact bears (``share_depths``): 1 clear of the tire or alone."""
    if not depth > 0.0:
        return 1.0
    return min(1.0, max(0.0, borne / depth))


_SHARE_DEPTHS = None


def _share_depths():
    """``share_depths`` as the search calls it: its compiled twin where numba is here (the same
    source, the compiled search's; a run of many minima costs a Python loop per piece otherwise),
    else the plain function."""
    global _SHARE_DEPTHS
    if _SHARE_DEPTHS is None:
        from mtbmj.controllers.jit import law_function, numba

        _SHARE_DEPTHS = share_depths if numba is None else law_function(share_depths)
    return _SHARE_DEPTHS


def closest_points(cx, cz, ax, az, ex, ez):
    """The closest point to (cx, cz) of each piece (ax, az) + s (ex, ez), 0 <= s <= 1."""
    length2 = ex * ex + ez * ez
    length2 = np.where(length2 > 0.0, length2, 1.0)
    s = np.clip(((cx - ax) * ex + (cz - az) * ez) / length2, 0.0, 1.0)
    return ax + s * ex, az + s * ez


SHARE_BLOCKS = 9  # share_depths' work array: 9 blocks of n


def share_depths(P2, V2, n, radius, cap_min, W):
    """The contacts of one run of n pieces within reach of the axle and the depth each one bears;
    returns k, their number, with in W (9 blocks of n, ``SHARE_BLOCKS``), for contact t < k:
    W[t] its piece, W[n + t] its depth radius - distance, W[2 n + t] the depth it bears, W[3 n + t]
    its prominence (m; inf: the run's deepest). A plain function: the Python search calls it and
    the compiled one compiles it (``mtbmj.rolling.callback_compiled``), so they decide alike.

    P2: each piece's squared shortest distance from the axle; V2: the squared distance of the
    vertex between piece j and j + 1 (n - 1 of them; raised here to the pieces either side where
    round-off has it below them). The distance is convex along a piece, so along the run it goes
    P2[0], V2[0], P2[1], ... through all its critical values.

    1. The contacts: the local minima of the distance (a plateau is one: of equal values the
       earlier is the lower), each with its prominence, the lower over both sides of the highest
       distance between it and the nearest lower point on that side, less its own; minima of a
       prominence up to ``cap_min`` (round-off's) are not contacts. Between two neighbouring
       contacts the barrier is the highest distance between them.
    2. The depths they bear (module doc, 1): seen as depths u = radius - distance, the overlap
       of tire and terrain at each level h in (0, max u) is a set of intervals; each level's
       interval bears a thickness dh, shared among the contacts in it in proportion to the depths
       they bear above h. A contact alone bears its whole depth; where two intervals meet at a
       barrier of depth ub > 0, their shares are frozen and the merged interval's thickness below
       ub goes to its contacts in those proportions. The depths borne sum to the overlap's, are
       continuous in the axle's position (no choice of a deepest, which would swap) and go to 0
       with a contact's prominence."""
    IDX, U, E, PROM, BAR, LEFT, RIGHT, ETOT, HC = 0, n, 2 * n, 3 * n, 4 * n, 5 * n, 6 * n, 7 * n, 8 * n
    for j in range(n - 1):  # a vertex is no lower than the pieces either side
        v = V2[j]
        if P2[j] > v:
            v = P2[j]
        if P2[j + 1] > v:
            v = P2[j + 1]
        V2[j] = v
    m = 2 * n - 1
    k = 0
    last = -1  # the interleaved index of the last contact
    for j in range(n):
        i = 2 * j
        gi = P2[j]
        if i > 0 and not V2[j - 1] > gi:  # the left neighbour is lower (or level): no minimum
            continue
        if i < m - 1 and not V2[j] >= gi:  # the right neighbour is lower
            continue
        saddle = math.inf
        top = -math.inf
        for q in range(i - 1, -1, -1):  # the highest distance back to the nearest lower point
            g = V2[q >> 1] if q & 1 else P2[q >> 1]
            if g <= gi:
                saddle = top
                break
            if g > top:
                top = g
        top = -math.inf
        for q in range(i + 1, m):  # and on to the nearest lower one
            g = V2[q >> 1] if q & 1 else P2[q >> 1]
            if g < gi:
                if top < saddle:
                    saddle = top
                break
            if g > top:
                top = g
        dist = math.sqrt(gi)
        prom = math.inf if saddle == math.inf else math.sqrt(saddle) - dist
        if not prom > cap_min:
            continue
        if k > 0:  # the barrier to the previous contact: the highest distance between them
            top = -math.inf
            for q in range(last + 1, i):
                g = V2[q >> 1] if q & 1 else P2[q >> 1]
                if g > top:
                    top = g
            W[BAR + k - 1] = radius - math.sqrt(top)
        W[IDX + k] = j
        W[U + k] = radius - dist
        W[PROM + k] = prom
        W[E + k] = 0.0
        W[LEFT + k] = k
        W[RIGHT + k] = k
        W[ETOT + k] = 0.0
        W[HC + k] = radius - dist
        last = i
        k += 1
    # the barriers within the tire (depth > 0), from the deepest up: merge the intervals they part
    while True:
        b = -1
        deepest = 0.0
        for t in range(k - 1):
            if W[BAR + t] > deepest:
                deepest = W[BAR + t]
                b = t
        if b < 0:
            break
        W[BAR + b] = -math.inf  # done
        for a in (int(W[LEFT + b]), b + 1):  # bring both intervals' shares down to the barrier's level
            z = int(W[RIGHT + a])
            total = W[ETOT + a] + (W[HC + a] - deepest)
            if W[ETOT + a] > 0.0:
                f = total / W[ETOT + a]
                for t in range(a, z + 1):
                    W[E + t] *= f
            else:  # nothing borne yet (contacts born at this level): equal shares
                for t in range(a, z + 1):
                    W[E + t] = total / (z - a + 1)
            W[ETOT + a] = total
            W[HC + a] = deepest
        a = int(W[LEFT + b])
        z = int(W[RIGHT + b + 1])
        W[ETOT + a] += W[ETOT + b + 1]
        W[RIGHT + a] = z
        for t in range(b + 1, z + 1):
            W[LEFT + t] = a
    # down to the tread's level (h = 0); a contact clear of the tire bears its (negative) depth
    a = 0
    while a < k:
        z = int(W[RIGHT + a])
        if W[HC + a] > 0.0:
            total = W[ETOT + a] + W[HC + a]
            if W[ETOT + a] > 0.0:
                f = total / W[ETOT + a]
                for t in range(a, z + 1):
                    W[E + t] *= f
            else:
                for t in range(a, z + 1):
                    W[E + t] = total / (z - a + 1)
        else:
            for t in range(a, z + 1):
                W[E + t] = W[U + t]
        a = z + 1
    return k


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
        """The one patch (qx, qz, nx, nz, 0, 0, 1, inf) of an axle over a straight stretch (a list of it,
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
        return [(qx, qz, (cx - qx) / dist, (cz - qz) / dist, 0.0, 0.0, 1.0, math.inf)]


def straight_stretches(tire: RadialTire) -> StraightStretches | None:
    """The straight stretches of ``tire``'s terrain at its reach, or None where the shortcut does not
    hold: a moving surface (the drum), or a terrain or tire whose geometry is not the stock search on
    the profile's points (a subclass overriding ``polyline`` or ``patches``)."""
    from mtbmj.rolling.terrain import Terrain

    ter = tire.terrain
    if ter.moving or type(ter).polyline is not Terrain.polyline or type(tire).patches is not RadialTire.patches:
        return None
    return stretches_of(ter, tire.radius + tire.margin)


STRETCHES_KEPT = 4  # the straight stretches of this many (profile, reach) kept per process
_stretches: dict = {}


def stretches_of(terrain, reach: float) -> StraightStretches:
    """``StraightStretches(terrain, reach)``, built once per process for a profile of the same points
    and reach (every run of ``mtbmj advise`` rides one reconstructed terrain, each tire and the
    reference asked for it: the corner scan is a Python loop over every point), the last
    ``STRETCHES_KEPT`` kept. Read only once built, so shared."""
    import hashlib

    x, z = np.ascontiguousarray(terrain.x, float), np.ascontiguousarray(terrain.z, float)
    key = (hashlib.blake2b(x.tobytes() + b"|" + z.tobytes(), digest_size=16).hexdigest(), float(reach))
    found = _stretches.pop(key, None)
    if found is None:
        found = StraightStretches(terrain, reach)
    _stretches[key] = found  # the most recent last
    while len(_stretches) > STRETCHES_KEPT:
        _stretches.pop(next(iter(_stretches)))
    return found


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


__all__ = ["RadialTire", "PatchSearch", "StraightStretches", "stretch", "straight_stretches", "stretches_of", "share_depths", "share",
           "SHARE_BLOCKS", "closest_points", "MARGIN_M", "REFRESH_S", "REFRESH_DISTANCE_M", "CAP_MIN_M", "TOUCH_CAP_M"]

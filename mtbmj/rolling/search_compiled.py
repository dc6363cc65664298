"""The compiled patch search of the rolling front end and the bike's wheels: a slot row's layout
(the integer and float rows ``mtbmj.rolling.callback_compiled`` registers, each of the bike's
wheels a row of the same layout) and the kernels that search a row's terrain for its contact
patches: ``RadialTire.patches`` (``mtbmj.rolling.tire``) on the terrain polyline, streamed piece by
piece without allocating (``find_patches``), each run's contacts and their shares by the plain
function ``share_depths`` compiled (``run_contacts``), and ``PatchSearch.refresh`` (``update_patches``:
the patch kept while the axle stays over the straight stretch it lies on).

Three shortcuts give the same patches to the bit with less work (issue 52; on a ride's reconstruction,
points every 1 cm with the slope changing at each, no straight stretch holds a tyre's reach and every
refresh searches): a static profile is cut into its pieces once (``piece_table``: each segment the
reach window does not clip holds the very pieces ``find_patches`` would cut it into; ``find_patches_cut``
reads them in place, the window's two clipped segments, when near, sent back to ``find_patches``); the
window's ends are looked for from the last search's (``sorted_index``, a few steps, not two
bisections over the whole profile); and a run along which the distance falls, then rises, has its one
contact at its first lowest piece (``falls_then_rises``, the shortcut ``RadialTire.patches`` takes:
``share_depths``' answer, share 1, prominence inf, without its scans). ``R_PLAIN`` set searches as
before (``plain_search`` of the compiled callbacks: the tests' and ``benchmarks/patch_search.py``'s
baseline).

The terrain arrays, the straight stretches' corners and the scratch are numpy arrays owned by the
callback object (``stretch_arrays``, ``run_scratch``); the row holds their addresses. At most
``MAX_PATCHES`` patches per row and ``R_RUNCAP`` pieces per run: beyond either the row raises its
overflow flag (the run is redone on the Python path).
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.controllers.jit import kernel, law_function, numba as _numba

MAX_PATCHES = 64

# integer row of a slot
(R_MODEL, R_XQ, R_XV, R_ZQ, R_ZV, R_FQ, R_FV, R_A_STATE, R_A_FORK, R_A_DP, R_A_DV, R_A_TX, R_A_TZ, R_A_PROBE,
 R_ACT, R_HAS_STATE, R_DRUM, R_MOVING, R_NPTS, R_TX, R_TZ, R_SCRATCH, R_ISCRATCH, R_CAP, R_CALLS, R_REFRESHES,
 R_NPATCH, R_OVERFLOW, R_SCALED,
 R_NS, R_SX, R_SZ, R_VALID, R_A_TOUCH,  # the straight stretches (PatchSearch): corners, and whether kept
 R_PLAIN,  # 1: the search before its shortcuts (each segment cut at each search, each run through share_depths)
 R_PFIRST, R_PIECES, R_NPIECES,  # the static profile cut into pieces once (piece_table; R_NPIECES 0: none)
 R_AT_LO, R_AT_HI, R_AT_S,  # the last search's window (static_bounds) and stretch: where the next one looks first
 R_RUN, R_RUNCAP) = range(43)  # a run's pieces and share_depths' work: RUN_BLOCKS x R_RUNCAP doubles
INT_WIDTH = R_RUNCAP + 1  # one row per name above: the width follows the list
# float row of a slot: parameters, state, then MAX_PATCHES x (qx, qz, nx, nz, sx, sz, share, prominence)
(F_X0, F_Z0, F_L, F_COS, F_SIN, F_RADIUS, F_RATE, F_DAMPING, F_MARGIN, F_SPEED, F_XREF0, F_REFRESH, F_DRUM_R,
 F_OMEGA, F_PATCH_TIME, F_NEXT_REFRESH, F_LAST_X, F_REFRESH_DISTANCE, F_PIECE, F_DAMPER_SCALE,
 F_RIM_D, F_RIM_K, F_RIM_C, F_RIM_P0,  # the rim: max deflection, rate (0: no rim), damping
 F_DRIVE, F_DRIVE_KV, F_DRIVE_PUSH, F_DRIVE_POWER, F_DRIVE_BRAKE,  # controllers.drive
 F_LO, F_HI) = range(31)  # the axle x interval over which the kept patch holds (PatchSearch.valid)
F_PATCHES = F_HI + 1  # the patches follow the state's last row
PATCH_WIDTH = 8  # qx, qz, nx, nz, sx, sz, share, prominence (RadialTire.patches)
RUN_BLOCKS = 4  # a run's pieces: squared distances, of their ends, closest points x, z (then share_depths' work)
FLOAT_WIDTH = F_PATCHES + PATCH_WIDTH * MAX_PATCHES


if _numba is not None:
    from mtbmj.rolling import tire as _tire_model
    from mtbmj.controllers.native_data import f64_pointer as _f64_pointer, i64_pointer as _i64_pointer

    _stretch = law_function(_tire_model.stretch)  # the straight stretches (mtbmj.rolling.tire)
    CAP_MIN_M = _tire_model.CAP_MIN_M
    _share_depths = law_function(_tire_model.share_depths)  # a run's contacts and their depths
    _share = law_function(_tire_model.share)
    SHARE_BLOCKS = _tire_model.SHARE_BLOCKS

    @kernel
    def _clip01(value):
        """np.clip(value, 0.0, 1.0)"""
        if value < 0.0:
            return 0.0
        if value > 1.0:
            return 1.0
        return value

    @kernel
    def static_bounds(X, n, x_lo, x_hi):
        """The points [i, j) of Terrain.polyline(x_lo, x_hi): the last before x_lo to the first past x_hi."""
        lo, hi = 0, n
        while lo < hi:  # np.searchsorted(X, x_lo, side="left")
            mid = (lo + hi) >> 1
            if X[mid] < x_lo:
                lo = mid + 1
            else:
                hi = mid
        i = max(lo - 1, 0)
        lo, hi = 0, n
        while lo < hi:  # np.searchsorted(X, x_hi, side="right")
            mid = (lo + hi) >> 1
            if X[mid] <= x_hi:
                lo = mid + 1
            else:
                hi = mid
        return i, min(lo + 1, n)

    @kernel
    def sorted_index(X, n, x, at, right):
        """np.searchsorted(X[:n], x, side="right" if right else "left") for a sorted X and x not NaN,
        looked for from ``at`` (the last search's): a few steps where the axle moved little, else bisection."""
        k = min(max(at, 0), n)
        for _ in range(8):
            if k > 0 and (X[k - 1] > x if right else not X[k - 1] < x):  # k too far
                k -= 1
            elif k < n and (X[k] <= x if right else X[k] < x):  # not far enough
                k += 1
            else:
                return k
        lo, hi = 0, n
        while lo < hi:
            mid = (lo + hi) >> 1
            if (X[mid] <= x) if right else (X[mid] < x):
                lo = mid + 1
            else:
                hi = mid
        return lo

    @kernel
    def static_window(X, Z, n, x_lo, x_hi, PX, PZ):
        """Terrain.polyline(x_lo, x_hi) into PX, PZ; returns the number of points."""
        i, j = static_bounds(X, n, x_lo, x_hi)
        m = 0
        if X[i] > x_lo:
            PX[0] = x_lo - 1.0
            PZ[0] = Z[i]
            m = 1
        for k in range(i, j):
            PX[m] = X[k]
            PZ[m] = Z[k]
            m += 1
        if X[j - 1] < x_hi:
            PX[m] = x_hi + 1.0
            PZ[m] = Z[j - 1]
            m += 1
        return m

    @kernel
    def drum_window(A, RAD, n, omega, radius, t, x_lo, x_hi, PX, PZ, W, W2, J, J2):
        """DrumTerrain.polyline(x_lo, x_hi, t) into PX, PZ (W, W2, J, J2: scratch of n)."""
        wt = omega * t
        lim = math.asin(min(1.0, max(abs(x_lo), abs(x_hi)) / radius)) + 0.05
        # Candidates: the angles (sorted ascending) within lim (+ a margin far above round-off)
        # of wt modulo 2 pi, found by bisection, in index order; the exact test of
        # DrumTerrain.polyline then decides on each.
        centre = (wt + math.pi) % (2 * math.pi) - math.pi
        reach = lim + 1e-6
        m = 0
        turn = 2 * math.pi
        first = int(math.floor((A[0] - centre - reach) / turn))
        last = int(math.ceil((A[n - 1] - centre + reach) / turn))
        for q in range(first, last + 1):
            shift = q * turn
            lo_angle = centre + shift - reach
            hi_angle = centre + shift + reach
            if hi_angle < A[0] or lo_angle > A[n - 1]:
                continue
            lo, hi = 0, n
            while lo < hi:  # first index with A >= lo_angle
                mid = (lo + hi) >> 1
                if A[mid] < lo_angle:
                    lo = mid + 1
                else:
                    hi = mid
            for k in range(lo, n):
                if A[k] > hi_angle:
                    break
                w = (A[k] - wt + math.pi) % (2 * math.pi) - math.pi
                if abs(w) <= lim:
                    W[m] = w
                    J[m] = k
                    m += 1
        # np.argsort(kind="stable"): the kept angles are a rotated sorted run; rotate at the
        # first descent, then an insertion sort on (angle, index) (linear when already sorted)
        start = 0
        for k in range(1, m):
            if W[k] < W[k - 1]:
                start = k
                break
        for k in range(m):
            W2[k] = W[(start + k) % m]
            J2[k] = J[(start + k) % m]
        for k in range(1, m):
            w, j = W2[k], J2[k]
            i = k - 1
            while i >= 0 and (W2[i] > w or (W2[i] == w and J2[i] > j)):
                W2[i + 1] = W2[i]
                J2[i + 1] = J2[i]
                i -= 1
            W2[i + 1] = w
            J2[i + 1] = j
        for k in range(m):
            a = W2[k]
            r = RAD[J2[k]]
            PX[k] = r * math.sin(a)
            PZ[k] = r * math.cos(a) - radius
        return m

    @kernel
    def _emit(F, I, best, bx, bz, cx, cz, share, prominence):
        if best <= 1e-9:
            return
        p = I[R_NPATCH]
        if p >= MAX_PATCHES:
            I[R_OVERFLOW] = 1
            return
        o = F_PATCHES + PATCH_WIDTH * p
        F[o] = bx
        F[o + 1] = bz
        F[o + 2] = (cx - bx) / best
        F[o + 3] = (cz - bz) / best
        if I[R_DRUM]:  # DrumTerrain.surface_velocity
            w = F[F_OMEGA]
            F[o + 4] = -w * (bz + F[F_DRUM_R])
            F[o + 5] = w * bx
        else:
            F[o + 4] = 0.0
            F[o + 5] = 0.0
        F[o + 6] = share
        F[o + 7] = prominence
        I[R_NPATCH] = p + 1

    @kernel
    def falls_then_rises(RUN, cap, n):
        """The piece of a run's one contact where the distance along it (P2[0], V2[0], P2[1], ...,
        each vertex raised to the pieces either side, as share_depths raises it) falls, then rises:
        the first lowest (RadialTire.patches' shortcut: share_depths' one contact there, alone, its
        whole depth borne, prominence inf); -1 where it rises, then falls again (share_depths decides)."""
        low = RUN[0]
        at = 0
        rose = False
        for j in range(n - 1):
            p = RUN[j + 1]
            v = RUN[cap + j]  # share_depths' raised vertex, without writing it back
            if RUN[j] > v:
                v = RUN[j]
            if p > v:
                v = p
            if v > RUN[j]:
                rose = True
            if p < v and rose:
                return -1
            if p < low:
                low = p
                at = j + 1
        return at

    @kernel
    def run_contacts(F, I, RUN, cap, n, cx, cz):
        """The contacts of the run of n pieces in RUN (squared distances of the pieces [0, cap), of
        their ends [cap, 2 cap), closest points x [2 cap, 3 cap), z [3 cap, 4 cap); share_depths'
        work after) emitted as patches (RadialTire.patches): a run along which the distance falls,
        then rises (most) its one contact at once (falls_then_rises: share_depths' answer, share 1,
        prominence inf), any other through share_depths (every run with R_PLAIN set)."""
        if I[R_PLAIN] == 0:
            j = falls_then_rises(RUN, cap, n)
            if j >= 0:
                qx = RUN[2 * cap + j]
                qz = RUN[3 * cap + j]
                _emit(F, I, math.hypot(cx - qx, cz - qz), qx, qz, cx, cz, 1.0, math.inf)
                return
        W = RUN[4 * cap:]
        k = _share_depths(RUN[:cap], RUN[cap:2 * cap], n, F[F_RADIUS], CAP_MIN_M, W)
        for c in range(k):
            j = int(W[c])
            qx = RUN[2 * cap + j]
            qz = RUN[3 * cap + j]
            best = math.hypot(cx - qx, cz - qz)
            _emit(F, I, best, qx, qz, cx, cz, _share(W[n + c], W[2 * n + c]), W[3 * n + c])

    @kernel
    def find_patches(I, F, PX, PZ, m, cx, cz):
        """RadialTire.patches(cx, cz) over the polyline PX[:m], PZ[:m], streamed piece by piece
        (RadialTire.pieces), each run of pieces within reach gathered in the slot's run scratch and
        its contacts emitted (run_contacts) into the slot's patch rows."""
        I[R_NPATCH] = 0
        cap = I[R_RUNCAP]
        RUN = _numba.carray(_f64_pointer(I[R_RUN]), ((RUN_BLOCKS + SHARE_BLOCKS) * cap,))
        reach = F[F_RADIUS] + F[F_MARGIN]
        piece = F[F_PIECE]
        # A segment whose bounding box is farther than reach (with a margin far above round-off)
        # has no piece near the axle: skipping its pieces changes nothing but the time.
        far2 = (reach * (1.0 + 1e-9)) ** 2
        piece2 = (piece * (1.0 - 1e-9)) ** 2  # below round-off of hypot: a segment this short is one piece
        near2 = (reach * (1.0 - 1e-9)) ** 2  # within reach beyond round-off
        n = 0  # the pieces of the run so far (0: not in a run)
        for k in range(m - 1):
            ax = PX[k]
            az = PZ[k]
            bx1 = PX[k + 1]
            bz1 = PZ[k + 1]
            gx = max(min(ax, bx1) - cx, cx - max(ax, bx1), 0.0)
            gz = max(min(az, bz1) - cz, cz - max(az, bz1), 0.0)
            if gx * gx + gz * gz > far2:
                if n > 0:
                    run_contacts(F, I, RUN, cap, n, cx, cz)
                    n = 0
                continue
            ex = bx1 - ax
            ez = bz1 - az
            # clipped to the reach window in x (a segment running forward inside it is kept whole:
            # the clip's divisions would give exactly 0 and 1; one running backward, on the drum,
            # keeps its direction: a piece's end is the next one's start)
            if ex != 0.0 and not (ex > 0.0 and ax >= cx - reach and bx1 <= cx + reach):
                t0 = _clip01((cx - reach - ax) / ex)
                t1 = _clip01((cx + reach - ax) / ex)
                if t0 > t1:
                    t0, t1 = t1, t0
                ax, az, ex, ez = ax + t0 * ex, az + t0 * ez, (t1 - t0) * ex, (t1 - t0) * ez
            # pieces of at most ``piece``: one for a segment no longer than that (no square root)
            if ex * ex + ez * ez <= piece2:
                kk = 1
            else:
                kk = int(max(1.0, math.ceil(math.hypot(ex, ez) / piece)))
            for p in range(kk):
                if kk == 1:
                    pax = ax
                    paz = az
                    pex = ex
                    pez = ez
                else:
                    f0 = p / kk
                    f1 = f0 + 1.0 / kk
                    pax = ax + f0 * ex
                    paz = az + f0 * ez
                    pex = (f1 - f0) * ex
                    pez = (f1 - f0) * ez
                    # a piece whose bounding box is beyond reach is not near (as a segment's,
                    # above): its closest point is not worked out (a long flat segment has many)
                    gx = max(min(pax, pax + pex) - cx, cx - max(pax, pax + pex), 0.0)
                    gz = max(min(paz, paz + pez) - cz, cz - max(paz, paz + pez), 0.0)
                    if gx * gx + gz * gz > far2:
                        if n > 0:
                            run_contacts(F, I, RUN, cap, n, cx, cz)
                            n = 0
                        continue
                length2 = pex * pex + pez * pez
                if not (length2 > 0.0):
                    length2 = 1.0
                s = _clip01(((cx - pax) * pex + (cz - paz) * pez) / length2)
                qx = pax + s * pex
                qz = paz + s * pez
                dx = cx - qx
                dz = cz - qz
                d2 = dx * dx + dz * dz
                # No square root where the outcome is known beyond round-off: a piece far beyond
                # reach or well within it.
                if d2 > far2:
                    near = False
                elif d2 < near2:
                    near = True
                else:
                    near = math.hypot(dx, dz) < reach
                if near:
                    if n >= cap:  # more pieces in one run than the scratch holds: the Python path
                        I[R_OVERFLOW] = 1
                        return
                    ux = cx - (pax + pex)
                    uz = cz - (paz + pez)
                    RUN[n] = d2
                    RUN[cap + n] = ux * ux + uz * uz
                    RUN[2 * cap + n] = qx
                    RUN[3 * cap + n] = qz
                    n += 1
                elif n > 0:
                    run_contacts(F, I, RUN, cap, n, cx, cz)
                    n = 0
        if n > 0:
            run_contacts(F, I, RUN, cap, n, cx, cz)

    @kernel
    def find_patches_cut(I, F, X, Z, i, j, cx, cz):
        """find_patches on the static profile's points X[i:j], Z[i:j] in place (a window holding the
        reach: no flat continuation added), each segment's pieces read from the profile cut once
        (R_PFIRST, R_PIECES: piece_table, the very numbers find_patches works out for a segment the
        reach window does not clip), the same arithmetic on each piece. False, with nothing decided,
        where a segment the window clips comes within reach (find_patches then searches)."""
        I[R_NPATCH] = 0
        cap = I[R_RUNCAP]
        RUN = _numba.carray(_f64_pointer(I[R_RUN]), ((RUN_BLOCKS + SHARE_BLOCKS) * cap,))
        total = I[R_NPIECES]
        FIRST = _numba.carray(_i64_pointer(I[R_PFIRST]), (I[R_NPTS],))
        P = _numba.carray(_f64_pointer(I[R_PIECES]), (4 * total,))
        reach = F[F_RADIUS] + F[F_MARGIN]
        far2 = (reach * (1.0 + 1e-9)) ** 2  # as find_patches
        near2 = (reach * (1.0 - 1e-9)) ** 2
        n = 0
        for k in range(i, j - 1):
            ax = X[k]
            az = Z[k]
            bx1 = X[k + 1]
            bz1 = Z[k + 1]
            gx = max(min(ax, bx1) - cx, cx - max(ax, bx1), 0.0)
            gz = max(min(az, bz1) - cz, cz - max(az, bz1), 0.0)
            if gx * gx + gz * gz > far2:
                if n > 0:
                    run_contacts(F, I, RUN, cap, n, cx, cz)
                    n = 0
                continue
            ex = bx1 - ax
            if ex != 0.0 and not (ex > 0.0 and ax >= cx - reach and bx1 <= cx + reach):
                return False  # clipped by the window, and near: cut as find_patches cuts it
            q0 = FIRST[k]
            kk = FIRST[k + 1] - q0
            for q in range(q0, q0 + kk):
                pax = P[4 * q]
                paz = P[4 * q + 1]
                pex = P[4 * q + 2]
                pez = P[4 * q + 3]
                if kk > 1:  # find_patches' test of a piece's bounding box
                    gx = max(min(pax, pax + pex) - cx, cx - max(pax, pax + pex), 0.0)
                    gz = max(min(paz, paz + pez) - cz, cz - max(paz, paz + pez), 0.0)
                    if gx * gx + gz * gz > far2:
                        if n > 0:
                            run_contacts(F, I, RUN, cap, n, cx, cz)
                            n = 0
                        continue
                length2 = pex * pex + pez * pez
                if not (length2 > 0.0):
                    length2 = 1.0
                s = _clip01(((cx - pax) * pex + (cz - paz) * pez) / length2)
                qx = pax + s * pex
                qz = paz + s * pez
                dx = cx - qx
                dz = cz - qz
                d2 = dx * dx + dz * dz
                if d2 > far2:
                    near = False
                elif d2 < near2:
                    near = True
                else:
                    near = math.hypot(dx, dz) < reach
                if near:
                    if n >= cap:
                        I[R_OVERFLOW] = 1
                        return True
                    ux = cx - (pax + pex)
                    uz = cz - (paz + pez)
                    RUN[n] = d2
                    RUN[cap + n] = ux * ux + uz * uz
                    RUN[2 * cap + n] = qx
                    RUN[3 * cap + n] = qz
                    n += 1
                elif n > 0:
                    run_contacts(F, I, RUN, cap, n, cx, cz)
                    n = 0
        if n > 0:
            run_contacts(F, I, RUN, cap, n, cx, cz)
        return True

    @kernel
    def cut_profile(X, Z, n, piece, FIRST, P, total):
        """The pieces of each whole segment of the profile X[:n], Z[:n] (find_patches' arithmetic on a
        segment the reach window does not clip): FIRST[k] the first of segment k's (FIRST[n - 1] their
        number); with total > 0, their (ax, az, ex, ez) in P, four numbers a piece."""
        piece2 = (piece * (1.0 - 1e-9)) ** 2
        q = 0
        for k in range(n - 1):
            FIRST[k] = q
            ax = X[k]
            az = Z[k]
            ex = X[k + 1] - ax
            ez = Z[k + 1] - az
            if ex * ex + ez * ez <= piece2:  # find_patches' count
                kk = 1
            else:
                kk = int(max(1.0, math.ceil(math.hypot(ex, ez) / piece)))
            if total > 0:
                if kk == 1:
                    P[4 * q] = ax
                    P[4 * q + 1] = az
                    P[4 * q + 2] = ex
                    P[4 * q + 3] = ez
                else:
                    for p in range(kk):
                        f0 = p / kk
                        f1 = f0 + 1.0 / kk
                        o = 4 * (q + p)
                        P[o] = ax + f0 * ex
                        P[o + 1] = az + f0 * ez
                        P[o + 2] = (f1 - f0) * ex
                        P[o + 3] = (f1 - f0) * ez
            q += kk
        FIRST[n - 1] = q
        return q

    @kernel
    def refresh_patches(I, F, cx, cz, t):
        """RadialTire.patches: the patch search on the slot's terrain arrays (scratch: 2 x (n + 2)
        doubles on static terrain, 4 x on the drum, with 2 x integers)."""
        n = I[R_NPTS]
        cap = I[R_CAP]
        reach = F[F_RADIUS] + F[F_MARGIN]
        A = _numba.carray(_f64_pointer(I[R_TX]), (n,))
        B = _numba.carray(_f64_pointer(I[R_TZ]), (n,))
        if I[R_DRUM]:
            S = _numba.carray(_f64_pointer(I[R_SCRATCH]), (4 * cap,))
            PX, PZ = S[:cap], S[cap:2 * cap]
            J = _numba.carray(_i64_pointer(I[R_ISCRATCH]), (2 * cap,))
            m = drum_window(A, B, n, F[F_OMEGA], F[F_DRUM_R], t, cx - reach, cx + reach, PX, PZ,
                            S[2 * cap:3 * cap], S[3 * cap:], J[:cap], J[cap:])
        else:
            x_lo = cx - reach
            x_hi = cx + reach
            if I[R_NPIECES] > 0 and I[R_PLAIN] == 0 and x_lo == x_lo and x_hi == x_hi:  # the profile cut once
                lo = sorted_index(A, n, x_lo, I[R_AT_LO], False)  # static_bounds from the last search's window
                hi = sorted_index(A, n, x_hi, I[R_AT_HI], True)
                I[R_AT_LO] = lo
                I[R_AT_HI] = hi
                i, j = max(lo - 1, 0), min(hi + 1, n)
                if not A[i] > x_lo and not A[j - 1] < x_hi and find_patches_cut(I, F, A, B, i, j, cx, cz):
                    return  # (no flat continuation within reach, no clipped segment near)
            S = _numba.carray(_f64_pointer(I[R_SCRATCH]), (2 * cap,))
            PX, PZ = S[:cap], S[cap:]
            m = static_window(A, B, n, x_lo, x_hi, PX, PZ)
        find_patches(I, F, PX, PZ, m, cx, cz)

    @kernel
    def piece_index(X, n, x):
        """bisect.bisect_right(X[:n], x) - 1"""
        lo, hi = 0, n
        while lo < hi:
            mid = (lo + hi) >> 1
            if X[mid] <= x:
                lo = mid + 1
            else:
                hi = mid
        return lo - 1

    @kernel
    def update_patches(I, F, cx, cz, t):
        """PatchSearch.refresh on a slot's row (the front end's, or a wheel's of the bike): keep the
        patch while the axle stays within [F_LO, F_HI] (the straight stretch its one patch lies on),
        else search (refresh_patches) and, for one patch on a straight stretch, note the stretch.
        True when it searched."""
        if I[R_VALID] != 0 and F[F_LO] <= cx <= F[F_HI]:
            return False
        refresh_patches(I, F, cx, cz, t)
        I[R_VALID] = 0
        ns = I[R_NS]
        if I[R_NPATCH] == 1 and ns > 0:
            SX = _numba.carray(_f64_pointer(I[R_SX]), (ns,))
            SZ = _numba.carray(_f64_pointer(I[R_SZ]), (ns,))
            if I[R_PLAIN] == 0 and cx == cx:  # piece_index from the last search's
                at = sorted_index(SX, ns, cx, I[R_AT_S], True)
                I[R_AT_S] = at
                i = at - 1
            else:
                i = piece_index(SX, ns, cx)
            ok, _, _, _, _, lo, hi = _stretch(SX, SZ, F[F_RADIUS] + F[F_MARGIN], i, cx)
            if ok:
                I[R_VALID] = 1
                F[F_LO] = lo
                F[F_HI] = hi
        return True


def stretch_arrays(tire) -> tuple[np.ndarray, np.ndarray]:
    """The corners of ``tire``'s straight stretches (``mtbmj.rolling.tire.straight_stretches``) as the
    arrays a slot's R_SX, R_SZ point to; empty (no shortcut: R_NS 0) where it has none."""
    from mtbmj.rolling.tire import straight_stretches

    straight = straight_stretches(tire)
    if straight is None:
        return np.zeros(0), np.zeros(0)
    return np.array(straight.x, dtype=np.float64), np.array(straight.z, dtype=np.float64)


def piece_table(x: np.ndarray, z: np.ndarray, piece: float) -> tuple[np.ndarray, np.ndarray]:
    """A static profile's segments cut into pieces once (``cut_profile``): the first piece of each
    segment (n int64, the last their number) and the pieces' (ax, az, ex, ez), four numbers a piece, the
    arrays a slot's R_PFIRST, R_PIECES point to (R_NPIECES their number); empty without numba."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    z = np.ascontiguousarray(z, dtype=np.float64)
    n = int(x.size)
    first = np.zeros(max(n, 1), dtype=np.int64)
    if _numba is None or n < 2:
        return first, np.zeros(0)
    total = cut_profile(x, z, n, float(piece), first, np.zeros(0), 0)
    pieces = np.zeros(4 * total, dtype=np.float64)
    cut_profile(x, z, n, float(piece), first, pieces, total)
    return first, pieces


def run_scratch(n: int, *tires) -> np.ndarray:
    """The scratch of a run of pieces (R_RUN, (RUN_BLOCKS + SHARE_BLOCKS) x R_RUNCAP doubles: the
    pieces' numbers and share_depths' work) for a profile of n points and
    ``tires``: room for every point's segment and the pieces of a reach's width twice over; a run
    longer than that (a profile folded many times within reach) raises the overflow flag."""
    from mtbmj.rolling.tire import PIECE_M, SHARE_BLOCKS

    reach = max(t.radius + t.margin for t in tires)
    cap = 2 * (n + 2) + 4 * int(math.ceil(2 * reach / PIECE_M)) + 16
    return np.zeros((RUN_BLOCKS + SHARE_BLOCKS) * cap, dtype=np.float64)


__all__ = sorted(name for name in globals() if name.startswith(("R_", "F_"))) + [
    "MAX_PATCHES", "PATCH_WIDTH", "RUN_BLOCKS", "INT_WIDTH", "FLOAT_WIDTH", "stretch_arrays", "run_scratch",
    "piece_table"]

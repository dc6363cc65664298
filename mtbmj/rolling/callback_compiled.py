"""Compiled rolling callback: the fork law, the radial tire and the speed servo of
``mtbmj.rolling.frontend.RollCallback`` as native code that MuJoCo calls every step.

``RollCallback`` (Python) stays the specification and the fallback; this module evaluates the same
arithmetic in the same order, including the terrain geometry (``RadialTire.patches`` on the
terrain polyline, refreshed on the same schedule, every ``refresh`` s of simulated time or 0.25 mm
of axle travel, and kept over the same straight stretches: ``PatchSearch``), so the results agree
with the Python path to round-off (~1e-12 m; bit-identical in practice on static terrain).

Design
------
* The fork law is flattened by ``controllers.lawcodes.flatten`` and evaluated by its compiled
  kernels (``controllers.kernels``: ``fork_force``, ``state_rate``, and the spring/damper/friction
  parts for a scaled damper); the tire, the rim and the drive are their modules' own functions
  compiled (``controllers.jit.law_function``); nothing of them is repeated here.
* One numba ``cfunc`` serves every ``CompiledRollCallback``: it looks the ``mjModel*`` up in a
  registry of its own (a ``controllers.native_data.Registry``, as the drop's callback has, but a
  separate one, so neither dispatcher ever acts on the other's models) and leaves every other model alone. A slot holds
  integer indices (joints, actuators, array addresses, counters) and float parameters plus the
  callback's state: the contact patches (closest point q, normal n, surface velocity) of the last
  refresh, its time, the next refresh time, the axle x at the refresh.
* The terrain polyline (static profile x, z; or the drum's polar cleat profile), the corners of
  its straight stretches and scratch buffers are numpy arrays owned by the callback object; the
  slot holds their addresses. The patch search (``Terrain.polyline`` +
  ``RadialTire.segment_distances`` + ``RadialTire.patches``: ``refresh_patches``) runs in compiled
  code, streaming over the pieces without allocating; ``update_patches`` refreshes as
  ``mtbmj.rolling.tire.PatchSearch`` does (the patch kept while the axle stays over the straight
  stretch it lies on, on static terrain). It is the one search of the front end and of both wheels
  of the bike (``mtbmj.bike.callback_compiled``, each wheel a row in this slot layout).
* ``mjData`` is read through the offsets of ``controllers.native_data.mjdata_layout`` (mujoco's own
  struct description), checked against live arrays before first use.
* The callback state is per model, like ``RollCallback``'s: one ``mjData`` at a time per model.

Limits: at most ``MAX_PATCHES`` patches at once (far more than any terrain meets under one tire);
beyond that the slot raises its overflow flag and ``mtbmj.rolling.frontend.simulate`` reruns on the Python
path. A terrain or tire subclass, or a law with no compiled form, runs on the Python path.
"""
from __future__ import annotations

import ctypes
import math
import threading
import time
import weakref

import numpy as np

from mtbmj.controllers import drive as _drive
from mtbmj.controllers.compiled import unavailable_reason
from mtbmj.controllers.drive import Drive
from mtbmj.controllers.jit import FALLBACK_MESSAGE, callback, kernel, law_function, numba as _numba
from mtbmj.controllers.lawcodes import FLOAT_WIDTH as LAW_FLOAT_WIDTH, INT_WIDTH as LAW_INT_WIDTH
from mtbmj.controllers.lawcodes import UnsupportedLaw, flatten
from mtbmj.controllers.native_data import Registry, mjdata_layout, verify
from mtbmj.controllers.stops import STIFFENING_M
from mtbmj.runpath.callbacks import CompiledShell

MAX_PATCHES = 64
SLOTS = 64

# integer row of a slot
(R_MODEL, R_XQ, R_XV, R_ZQ, R_ZV, R_FQ, R_FV, R_A_STATE, R_A_FORK, R_A_DP, R_A_DV, R_A_TX, R_A_TZ, R_A_PROBE,
 R_ACT, R_HAS_STATE, R_DRUM, R_MOVING, R_NPTS, R_TX, R_TZ, R_SCRATCH, R_ISCRATCH, R_CAP, R_CALLS, R_REFRESHES,
 R_NPATCH, R_OVERFLOW, R_SCALED,
 R_NS, R_SX, R_SZ, R_VALID, R_A_TOUCH) = range(34)  # the straight stretches (PatchSearch): corners, and whether kept
INT_WIDTH = 36
# float row of a slot: parameters, state, then MAX_PATCHES x (qx, qz, nx, nz, sx, sz)
(F_X0, F_Z0, F_L, F_COS, F_SIN, F_RADIUS, F_RATE, F_DAMPING, F_MARGIN, F_SPEED, F_XREF0, F_REFRESH, F_DRUM_R,
 F_OMEGA, F_PATCH_TIME, F_NEXT_REFRESH, F_LAST_X, F_REFRESH_DISTANCE, F_PIECE, F_DAMPER_SCALE,
 F_RIM_D, F_RIM_K, F_RIM_C, F_RIM_P0,  # the rim: max deflection, rate (0: no rim), damping
 F_DRIVE, F_DRIVE_KV, F_DRIVE_PUSH, F_DRIVE_POWER, F_DRIVE_BRAKE,  # controllers.drive
 F_LO, F_HI) = range(31)  # the axle x interval over which the kept patch holds (PatchSearch.valid)
F_PATCHES = 31  # (F_HI = 30 is the last of the state)
FLOAT_WIDTH = F_PATCHES + 6 * MAX_PATCHES

REGISTRY = Registry("mtbmj_rolling_registry_v2", SLOTS,
                    {"ints": (INT_WIDTH, np.int64), "floats": (FLOAT_WIDTH, np.float64),
                     "law_ints": (LAW_INT_WIDTH, np.int64), "law_floats": (LAW_FLOAT_WIDTH, np.float64)},
                    ("qpos", "qvel", "act", "ctrl", "time"))
M_USED, M_INTS, M_FLOATS, M_LAW_INTS, M_LAW_FLOATS, M_QPOS, M_QVEL, M_ACT, M_CTRL, M_TIME = (
    REGISTRY.index[name] for name in ("used", "ints", "floats", "law_ints", "law_floats", "qpos", "qvel", "act",
                                      "ctrl", "time"))
_INTS, _FLOATS = REGISTRY.tables["ints"], REGISTRY.tables["floats"]


class UnsupportedRolling(TypeError):
    """A tire or terrain this module cannot compile (the Python path still runs it)."""


COMPILE_SECONDS: float | None = None
if _numba is not None:
    from mtbmj.controllers import kernels as _kernels
    from mtbmj.controllers import tire as _tire
    from mtbmj.rolling import tire as _tire_model
    from mtbmj.controllers.native_data import address_of as _address_of, f64_pointer as _f64_pointer
    from mtbmj.controllers.native_data import find_slot as _find_slot
    from mtbmj.controllers.native_data import i64_pointer as _i64_pointer, pointer_field as _pointer_field
    from numba import types as _t

    _compile_start = time.perf_counter()
    _registry = REGISTRY.reader()
    _fork_force, _state_rate = _kernels.fork_force, _kernels.state_rate
    _spring_force, _damper_force, _friction_force = _kernels.spring_force, _kernels.damper_force, \
        _kernels.friction_force
    rim_force = _kernels.rim_force  # the one rim law (controllers.stops)
    tire_force = law_function(_tire.rolling_tire_force)  # the one rolling tire law
    _stretch = law_function(_tire_model.stretch)  # the straight stretches (mtbmj.rolling.tire)
    drive_force = law_function(_drive.drive_force)  # the rider's drive (controllers.drive)

    @kernel
    def _clip01(value):
        """np.clip(value, 0.0, 1.0)"""
        if value < 0.0:
            return 0.0
        if value > 1.0:
            return 1.0
        return value

    @kernel
    def static_window(X, Z, n, x_lo, x_hi, PX, PZ):
        """Terrain.polyline(x_lo, x_hi) into PX, PZ; returns the number of points."""
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
        j = min(lo + 1, n)
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
    def _emit(F, I, best, bx, bz, cx, cz):
        if best <= 1e-9:
            return
        p = I[R_NPATCH]
        if p >= MAX_PATCHES:
            I[R_OVERFLOW] = 1
            return
        o = F_PATCHES + 6 * p
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
        I[R_NPATCH] = p + 1

    @kernel
    def find_patches(I, F, PX, PZ, m, cx, cz):
        """RadialTire.patches(cx, cz) over the polyline PX[:m], PZ[:m], streamed piece by piece
        (RadialTire.segment_distances), into the slot's patch rows."""
        I[R_NPATCH] = 0
        reach = F[F_RADIUS] + F[F_MARGIN]
        piece = F[F_PIECE]
        # A segment whose bounding box is farther than reach (with a margin far above round-off)
        # has no piece near the axle: skipping its pieces changes nothing but the time.
        far2 = (reach * (1.0 + 1e-9)) ** 2
        piece2 = (piece * (1.0 - 1e-9)) ** 2  # below round-off of hypot: a segment this short is one piece
        near2 = (reach * (1.0 - 1e-9)) ** 2  # within reach beyond round-off
        in_run = False
        best = bx = bz = 0.0
        best2 = 0.0  # the squared distance of the run's closest point so far (it bounds the next)
        for k in range(m - 1):
            ax = PX[k]
            az = PZ[k]
            bx1 = PX[k + 1]
            bz1 = PZ[k + 1]
            gx = max(min(ax, bx1) - cx, cx - max(ax, bx1), 0.0)
            gz = max(min(az, bz1) - cz, cz - max(az, bz1), 0.0)
            if gx * gx + gz * gz > far2:
                if in_run:
                    in_run = False
                    _emit(F, I, best, bx, bz, cx, cz)
                continue
            ex = bx1 - ax
            ez = bz1 - az
            # clipped to the reach window in x (a segment running forward inside it is kept whole:
            # the clip's divisions would give exactly 0 and 1; one running backward, on the drum,
            # is turned round by them)
            if ex != 0.0 and not (ex > 0.0 and ax >= cx - reach and bx1 <= cx + reach):
                t0 = _clip01((cx - reach - ax) / ex)
                t1 = _clip01((cx + reach - ax) / ex)
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
                        if in_run:
                            in_run = False
                            _emit(F, I, best, bx, bz, cx, cz)
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
                # reach, or one well within reach but farther than the run's closest so far (by a
                # relative 1e-12, far above round-off, so the decisions are those of the distances).
                if d2 > far2:
                    d = reach
                elif in_run and near2 > d2 > best2 * (1.0 + 1e-12):
                    d = best
                else:
                    d = math.hypot(dx, dz)
                if d < reach:
                    if not in_run:
                        in_run = True
                        best, bx, bz = d, qx, qz
                        best2 = d2
                    elif d < best:
                        best, bx, bz = d, qx, qz
                        best2 = d2
                elif in_run:
                    in_run = False
                    _emit(F, I, best, bx, bz, cx, cz)
        if in_run:
            _emit(F, I, best, bx, bz, cx, cz)

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
            S = _numba.carray(_f64_pointer(I[R_SCRATCH]), (2 * cap,))
            PX, PZ = S[:cap], S[cap:]
            m = static_window(A, B, n, cx - reach, cx + reach, PX, PZ)
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
            ok, _, _, _, _, lo, hi = _stretch(SX, SZ, F[F_RADIUS] + F[F_MARGIN], piece_index(SX, ns, cx), cx)
            if ok:
                I[R_VALID] = 1
                F[F_LO] = lo
                F[F_HI] = hi
        return True

    @callback(_t.void(_t.voidptr, _t.voidptr))
    def _dispatch(m, d):
        slot = _find_slot(_registry(M_INTS), _registry(M_USED), INT_WIDTH, _address_of(m))
        if slot < 0:
            return  # not one of ours: leave the model alone
        I = _numba.carray(_i64_pointer(_registry(M_INTS) + 8 * INT_WIDTH * slot), (INT_WIDTH,))
        F = _numba.carray(_f64_pointer(_registry(M_FLOATS) + 8 * FLOAT_WIDTH * slot), (FLOAT_WIDTH,))
        LI = _numba.carray(_i64_pointer(_registry(M_LAW_INTS) + 8 * LAW_INT_WIDTH * slot), (LAW_INT_WIDTH,))
        LP = _numba.carray(_f64_pointer(_registry(M_LAW_FLOATS) + 8 * LAW_FLOAT_WIDTH * slot), (LAW_FLOAT_WIDTH,))
        I[R_CALLS] += 1
        qpos = _pointer_field(d, _registry(M_QPOS))
        qvel = _pointer_field(d, _registry(M_QVEL))
        ctrl = _pointer_field(d, _registry(M_CTRL))
        t = _f64_pointer(_address_of(d) + _registry(M_TIME))[0]
        # the fork (RollCallback: law.force, or the semi-active scaled damper)
        x = qpos[I[R_FQ]]
        v = qvel[I[R_FV]]
        z = _pointer_field(d, _registry(M_ACT))[I[R_ACT]] if I[R_HAS_STATE] else 0.0
        if I[R_SCALED]:
            force = _spring_force(LI, LP, x, v) + F[F_DAMPER_SCALE] * _damper_force(LI, LP, v) + \
                _friction_force(LI, LP, v, z)
        else:
            force = _fork_force(LI, LP, x, v, z)
        if I[R_HAS_STATE]:
            ctrl[I[R_A_STATE]] = _state_rate(LI, LP, v, z)
        ctrl[I[R_A_FORK]] = -force
        # the axle (RollCallback.axle_state)
        qf = qpos[I[R_FQ]]
        vf = qvel[I[R_FV]]
        c = F[F_COS]
        sn = F[F_SIN]
        cx = F[F_X0] + qpos[I[R_XQ]] + (F[F_L] - qf) * c
        cz = F[F_Z0] + qpos[I[R_ZQ]] - (F[F_L] - qf) * sn
        vx = qvel[I[R_XV]] - vf * c
        vz = qvel[I[R_ZV]] + vf * sn
        if t >= F[F_NEXT_REFRESH] or abs(cx - F[F_LAST_X]) > F[F_REFRESH_DISTANCE]:
            if update_patches(I, F, cx, cz, t):
                I[R_REFRESHES] += 1
            F[F_PATCH_TIME] = t
            F[F_NEXT_REFRESH] = t + F[F_REFRESH] - 1e-12
            F[F_LAST_X] = cx
        # the tire (RadialTire.force), patches moved with a moving surface since the refresh
        r = F[F_RADIUS]
        k = F[F_RATE]
        b = F[F_DAMPING]
        npatch = I[R_NPATCH]
        shift = npatch > 0 and I[R_MOVING] != 0
        dt = t - F[F_PATCH_TIME]
        fx = 0.0
        fz = 0.0
        deepest = -math.inf
        shallowest = math.inf
        for p in range(npatch):
            o = F_PATCHES + 6 * p
            qx, qz, nx, nz, sx, sz = F[o], F[o + 1], F[o + 2], F[o + 3], F[o + 4], F[o + 5]
            if shift:
                qx = qx + sx * dt
                qz = qz + sz * dt
            dp = r - ((cx - qx) * nx + (cz - qz) * nz)
            rate = -((vx - sx) * nx + (vz - sz) * nz)
            if dp > deepest:
                deepest = dp
            if dp < shallowest:
                shallowest = dp
            if dp > 0.0:
                f = tire_force(k, b, dp, rate)
                if f < 0.0:
                    f = 0.0
                if F[F_RIM_K] > 0.0:  # the rim strikes (Rim.force)
                    f += rim_force(F[F_RIM_D], F[F_RIM_K], F[F_RIM_C], dp, rate)
                if f > 0.0:
                    fx += f * nx
                    fz += f * nz
        if deepest == -math.inf:
            deepest = r - F[F_RADIUS] - F[F_MARGIN]
        ctrl[I[R_A_PROBE]] = deepest
        ctrl[I[R_A_TOUCH]] = deepest if shallowest == math.inf else shallowest
        ctrl[I[R_A_TX]] = fx
        ctrl[I[R_A_TZ]] = fz
        if F[F_DRIVE] == 0.0:  # controllers.drive: the ideal servo on x0 + v t
            ctrl[I[R_A_DP]] = F[F_XREF0] + F[F_SPEED] * t
            ctrl[I[R_A_DV]] = F[F_SPEED]
        else:  # the rider (1) or coasting (2): position term 0, velocity term the drive's force
            xq = qpos[I[R_XQ]]
            vxq = qvel[I[R_XV]]
            fd = 0.0
            if F[F_DRIVE] == 1.0:
                fd = drive_force(F[F_SPEED], vxq, F[F_DRIVE_KV], F[F_DRIVE_PUSH], F[F_DRIVE_POWER], F[F_DRIVE_BRAKE])
            ctrl[I[R_A_DP]] = xq
            ctrl[I[R_A_DV]] = vxq + fd / F[F_DRIVE_KV]

    COMPILE_SECONDS = time.perf_counter() - _compile_start

_DISPATCHER = None
_DISPATCHER_LOCK = threading.Lock()


def _dispatcher(model):
    """The compiled rolling dispatcher, its registry header filled with the mjData offsets
    (checked against live arrays of a model once per process, ``native_data.verify``)."""
    global _DISPATCHER
    with _DISPATCHER_LOCK:
        if _DISPATCHER is None:
            if _numba is None:
                raise RuntimeError(FALLBACK_MESSAGE)
            reason = verify(model)
            if reason is not None:
                raise RuntimeError(reason)
            REGISTRY.bind_layout(mjdata_layout())
            _DISPATCHER = _dispatch
        return _DISPATCHER


def available() -> bool:
    """True when the compiled rolling path can run here."""
    return unavailable_reason() is None


def stretch_arrays(tire) -> tuple[np.ndarray, np.ndarray]:
    """The corners of ``tire``'s straight stretches (``mtbmj.rolling.tire.straight_stretches``) as the
    arrays a slot's R_SX, R_SZ point to; empty (no shortcut: R_NS 0) where it has none."""
    from mtbmj.rolling.tire import straight_stretches

    straight = straight_stretches(tire)
    if straight is None:
        return np.zeros(0), np.zeros(0)
    return np.array(straight.x, dtype=np.float64), np.array(straight.z, dtype=np.float64)


def _float_field(index: int, doc: str):
    def get(self):
        return float(_FLOATS[self.slot, index])

    def set(self, value):
        _FLOATS[self.slot, index] = float(value)

    return property(get, set, doc=doc)


def _int_field(index: int, doc: str):
    def get(self):
        return int(_INTS[self.slot, index]) if self._finalizer.alive else self._closed.get(index, 0)

    def set(self, value):
        _INTS[self.slot, index] = int(value)

    return property(get, set, doc=doc)


class CompiledRollCallback(CompiledShell, ctypes._CFuncPtr):
    """Compiled counterpart of ``mtbmj.rolling.frontend.RollCallback`` (same constructor, same attributes):
    a C function pointer for ``mujoco.set_mjcb_control`` / ``controllers.installed`` that writes
    the fork force, the LuGre state rate, the tire force and deflection probe and the speed
    servo's references into ``ctrl``.

    It acts only on ``front.model`` (a newer callback for the same model retires it). ``speed``,
    ``x_ref0``, ``refresh`` and ``damper_scale`` can be changed between steps; ``reset()`` forgets
    the contact patches (the next step recomputes them); ``calls``, ``refreshes`` and
    ``overflowed`` are read back from the compiled slot.
    """

    _flags_ = ctypes._FUNCFLAG_CDECL
    _argtypes_ = (ctypes.c_void_p, ctypes.c_void_p)
    _restype_ = None
    registry = REGISTRY

    def __new__(cls, front, fork_law, tire, speed, x_ref0, refresh=None, drive=None):
        reason = unavailable_reason()
        if reason is not None:
            raise RuntimeError(reason)
        return super().__new__(cls, _dispatcher(front.model).address)

    def __init__(self, front, fork_law, tire, speed, x_ref0, refresh=None, drive=None):
        from mtbmj.rolling import terrain as terrain_mod
        from mtbmj.rolling import tire as tire_model
        from mtbmj.rolling.callback import find_indices

        law_ints, law_floats = flatten(fork_law)  # UnsupportedLaw for a law with no compiled form
        if type(tire) is not tire_model.RadialTire:
            raise UnsupportedRolling(f"tire {type(tire).__name__} has no compiled form")
        ter = tire.terrain
        drum = type(ter) is terrain_mod.DrumTerrain
        if not drum and type(ter) is not terrain_mod.Terrain:
            raise UnsupportedRolling(f"terrain {type(ter).__name__} has no compiled form")
        m = front.model
        self._model = m  # keeps the mjModel (and so its address) alive while the slot is used
        self._address = m._address
        self.front, self.law, self.tire = front, fork_law, tire
        find_indices(self, front, fork_law)  # what it reads of the model, as RollCallback
        if drum:
            self._ta = np.ascontiguousarray(ter.polar[:, 0], dtype=np.float64)
            self._tb = np.ascontiguousarray(ter.polar[:, 1], dtype=np.float64)
        else:
            self._ta = np.ascontiguousarray(ter.x, dtype=np.float64)
            self._tb = np.ascontiguousarray(ter.z, dtype=np.float64)
        n = int(self._ta.size)
        if n < 1 or self._tb.size != n:
            raise UnsupportedRolling("terrain profile is empty or ragged")
        if not np.all(np.diff(self._ta) >= 0.0):  # the bisections assume sorted x (drum: angles)
            raise UnsupportedRolling("terrain profile is not sorted")
        cap = n + 2
        self._scratch = np.zeros(4 * cap, dtype=np.float64)
        self._iscratch = np.zeros(2 * cap, dtype=np.int64)
        self._closed: dict = {}
        self._sx, self._sz = stretch_arrays(tire)

        ints = np.zeros(INT_WIDTH, dtype=np.int64)
        ints[[R_XQ, R_XV, R_ZQ, R_ZV, R_FQ, R_FV]] = [self.xq, self.xv, self.zq, self.zv, self.fq, self.fv]
        ints[[R_A_STATE, R_A_FORK, R_A_DP, R_A_DV, R_A_TX, R_A_TZ, R_A_PROBE, R_ACT]] = [
            self.a_state, self.a_fork, self.a_dp, self.a_dv, self.a_tx, self.a_tz, self.a_probe, self.act_index]
        ints[R_A_TOUCH] = self.a_touch
        ints[R_HAS_STATE] = int(bool(self.has_state))
        ints[R_DRUM], ints[R_MOVING] = int(drum), int(bool(ter.moving))
        ints[R_NPTS], ints[R_CAP] = n, cap
        ints[R_TX], ints[R_TZ] = self._ta.ctypes.data, self._tb.ctypes.data
        ints[R_SCRATCH], ints[R_ISCRATCH] = self._scratch.ctypes.data, self._iscratch.ctypes.data
        ints[R_NS], ints[R_SX], ints[R_SZ] = self._sx.size, self._sx.ctypes.data, self._sz.ctypes.data
        floats = np.zeros(FLOAT_WIDTH, dtype=np.float64)
        floats[[F_X0, F_Z0, F_L, F_COS, F_SIN]] = [front.chassis_x0, front.chassis_z0, front.fork_length,
                                                    self.cos, self.sin]
        floats[[F_RADIUS, F_RATE, F_DAMPING, F_MARGIN]] = [tire.radius, tire.rate, tire.damping, tire.margin]
        if tire.rim is not None:
            floats[[F_RIM_D, F_RIM_K, F_RIM_C, F_RIM_P0]] = [tire.rim.max_deflection, tire.rim.rate, tire.rim.damping,
                                                            STIFFENING_M]
        floats[F_SPEED], floats[F_XREF0] = float(speed), float(x_ref0)
        self.drive = drive if drive is not None else Drive("servo")
        floats[[F_DRIVE, F_DRIVE_KV, F_DRIVE_PUSH, F_DRIVE_POWER, F_DRIVE_BRAKE]] = [
            float(self.drive.code), self.drive.kv, self.drive.push, self.drive.power, self.drive.brake]
        if self.drive.mode != "servo" and not self.drive.kv > 0.0:
            raise UnsupportedRolling("a rider or coasting drive needs the velocity actuator's gain")
        floats[F_REFRESH] = float(tire_model.REFRESH_S if refresh is None else refresh)
        floats[F_REFRESH_DISTANCE], floats[F_PIECE] = tire_model.REFRESH_DISTANCE_M, tire_model.PIECE_M
        if drum:
            floats[F_DRUM_R], floats[F_OMEGA] = ter.radius, ter.omega
        floats[F_NEXT_REFRESH], floats[F_LAST_X] = -math.inf, math.inf
        slot = REGISTRY.claim(m._address, {"ints": ints, "floats": floats, "law_ints": law_ints,
                                           "law_floats": law_floats}, "compiled rolling callbacks")
        self.slot = slot
        self._finalizer = weakref.finalize(self, REGISTRY.release, slot)

    speed = _float_field(F_SPEED, "servo speed (m/s)")
    x_ref0 = _float_field(F_XREF0, "servo reference at t = 0 (m)")
    refresh = _float_field(F_REFRESH, "geometry refresh interval (s)")
    patch_time = _float_field(F_PATCH_TIME, "simulated time of the last refresh (s)")
    next_refresh = _float_field(F_NEXT_REFRESH, "time of the next refresh (s)")
    last_x = _float_field(F_LAST_X, "axle x at the last refresh (m)")
    calls = _int_field(R_CALLS, "calls for this callback's model")
    refreshes = _int_field(R_REFRESHES, "geometry refreshes")

    @property
    def overflowed(self) -> bool:
        """True if more than MAX_PATCHES patches were met (the run must be redone in Python)."""
        return bool(self._int(R_OVERFLOW))

    def _int(self, index):
        return int(_INTS[self.slot, index]) if self._finalizer.alive else self._closed.get(index, 0)

    @property
    def damper_scale(self):
        """None (passive) or the factor on the hydraulic damper force (semi-active command)."""
        return float(_FLOATS[self.slot, F_DAMPER_SCALE]) if _INTS[self.slot, R_SCALED] else None

    @damper_scale.setter
    def damper_scale(self, value) -> None:
        if value is None:
            _INTS[self.slot, R_SCALED] = 0
        else:
            _FLOATS[self.slot, F_DAMPER_SCALE] = float(value)
            _INTS[self.slot, R_SCALED] = 1

    @property
    def patches(self) -> list[tuple[float, ...]]:
        """The contact patches of the last refresh: (qx, qz, nx, nz, surface vx, surface vz)."""
        n = int(_INTS[self.slot, R_NPATCH])
        rows = _FLOATS[self.slot, F_PATCHES:F_PATCHES + 6 * n].reshape(n, 6)
        return [tuple(float(v) for v in row) for row in rows]

    def reset(self) -> None:
        """Forget the patches: the next step recomputes them (RollCallback.reset)."""
        _INTS[self.slot, R_NPATCH] = 0
        _INTS[self.slot, R_VALID] = 0
        _FLOATS[self.slot, F_NEXT_REFRESH] = -math.inf
        _FLOATS[self.slot, F_LAST_X] = math.inf

    def bind(self, data) -> None:
        """No-op (``RollCallback`` caches numpy views; the compiled path reads ``mjData*``)."""

    def axle_state(self, qpos, qvel):
        return self.front.axle_state(qpos, qvel, (self.xq, self.zq, self.fq, self.xv, self.zv, self.fv))

    def counters(self) -> dict:
        """The slot's counters (kept by ``close``)."""
        return {i: int(_INTS[self.slot, i]) for i in (R_CALLS, R_REFRESHES, R_OVERFLOW)}

    def __repr__(self):
        return f"<CompiledRollCallback slot={getattr(self, 'slot', None)} law={getattr(self, 'law', None)!r}>"


from mtbmj.controllers.compiled import warn_once  # noqa: E402  (one set of warnings for both callbacks)


__all__ = ["CompiledRollCallback", "UnsupportedLaw", "warn_once", "available", "UnsupportedRolling", "MAX_PATCHES",
           "stretch_arrays"]

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
  callback's state: the contact patches (closest point q, normal n, surface velocity, share,
  prominence) of the last
  refresh, its time, the next refresh time, the axle x at the refresh.
* The terrain polyline (static profile x, z; or the drum's polar cleat profile), the corners of
  its straight stretches and scratch buffers are numpy arrays owned by the callback object; the
  slot holds their addresses. The patch search (``Terrain.polyline`` + ``RadialTire.pieces`` +
  ``RadialTire.patches``: ``refresh_patches``, in ``mtbmj.rolling.search_compiled`` with the slot's
  layout) runs in compiled code, streaming over the pieces without allocating; each run's contacts
  and their shares are ``RadialTire``'s own ``share_depths`` compiled; ``update_patches`` refreshes as
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
from mtbmj.rolling import search_compiled as _search
from mtbmj.rolling.search_compiled import *  # noqa: F401,F403 - the slot layout (R_*, F_*), the search's face
from mtbmj.rolling.search_compiled import FLOAT_WIDTH, INT_WIDTH, MAX_PATCHES, PATCH_WIDTH, RUN_BLOCKS, \
    piece_table, run_scratch, stretch_arrays
from mtbmj.runpath.callbacks import CompiledShell

SLOTS = 64


REGISTRY = Registry("mtbmj_rolling_registry_v4", SLOTS,
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
    TOUCH_CAP_M = _tire_model.TOUCH_CAP_M
    # the patch search (mtbmj.rolling.search_compiled), also the bike's
    static_window, drum_window, find_patches, refresh_patches = (
        _search.static_window, _search.drum_window, _search.find_patches, _search.refresh_patches)
    piece_index, update_patches = _search.piece_index, _search.update_patches
    drive_force = law_function(_drive.drive_force)  # the rider's drive (controllers.drive)

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
            o = F_PATCHES + PATCH_WIDTH * p
            qx, qz, nx, nz, sx, sz = F[o], F[o + 1], F[o + 2], F[o + 3], F[o + 4], F[o + 5]
            if shift:
                qx = qx + sx * dt
                qz = qz + sz * dt
            dp = r - ((cx - qx) * nx + (cz - qz) * nz)
            rate = -((vx - sx) * nx + (vz - sz) * nz)
            if dp > deepest:
                deepest = dp
            if dp < shallowest and F[o + 7] >= TOUCH_CAP_M:  # RadialTire.shallowest
                shallowest = dp
            if dp > 0.0:
                f = tire_force(k, b, dp, rate)
                if f < 0.0:
                    f = 0.0
                if F[F_RIM_K] > 0.0:  # the rim strikes (Rim.force)
                    f += rim_force(F[F_RIM_D], F[F_RIM_K], F[F_RIM_C], dp, rate)
                f *= F[o + 6]  # its share (RadialTire.force)
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
        self._run = run_scratch(n, tire)
        self._closed: dict = {}
        self._sx, self._sz = stretch_arrays(tire)
        self._pfirst, self._pieces = (np.zeros(1, dtype=np.int64), np.zeros(0)) if drum else \
            piece_table(self._ta, self._tb, tire_model.PIECE_M)  # the static profile cut into pieces once

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
        ints[R_PFIRST], ints[R_PIECES], ints[R_NPIECES] = (self._pfirst.ctypes.data, self._pieces.ctypes.data,
                                                           self._pieces.size // 4)
        ints[R_RUN], ints[R_RUNCAP] = self._run.ctypes.data, self._run.size // (RUN_BLOCKS + tire_model.SHARE_BLOCKS)
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
        """The contact patches of the last refresh: (qx, qz, nx, nz, surface vx, surface vz, share,
        prominence): ``RadialTire.patches``."""
        n = int(_INTS[self.slot, R_NPATCH])
        rows = _FLOATS[self.slot, F_PATCHES:F_PATCHES + PATCH_WIDTH * n].reshape(n, PATCH_WIDTH)
        return [tuple(float(v) for v in row) for row in rows]

    @property
    def plain_search(self) -> bool:
        """True: the patch search as it was before its shortcuts (``R_PLAIN``; the bike's
        ``CompiledBikeCallback.plain_search``): the same patches to the bit, slower."""
        return bool(_INTS[self.slot, R_PLAIN])

    @plain_search.setter
    def plain_search(self, value: bool) -> None:
        _INTS[self.slot, R_PLAIN] = int(bool(value))

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
           "stretch_arrays", "run_scratch", "PATCH_WIDTH", "RUN_BLOCKS"]

"""Compiled fork force laws: the same laws as ``controllers.spring/damper/friction/fork``, run as
native code that MuJoCo calls without the GIL.

The plain-Python laws stay the specification and the test oracle; this module evaluates the same
arithmetic in the same order (bit-identical results in practice, ~1e-12 at worst) so that threads
in ``mujoco.rollout`` run in parallel.

Design
------
* A ``ForkLaw`` is flattened into one row of integer codes and one row of float64 parameters
  (``flatten``): the spring tree (Linear, Bilinear, Progressive, Air, Directional, TopOut, nested
  at will) becomes a short postfix program, the damper (Linear, Bilinear, Digressive, Table) and the friction law
  (NoFriction, Coulomb, CoulombViscous, Stiction, Stribeck, LuGre) one code each.
* The rows live in a process-wide registry (two numpy arrays that are never reallocated), one slot
  per ``CompiledForkCallback``, keyed by the ``mjModel*`` it was built for. One numba ``cfunc``
  (compiled once per process; the law interpreter it calls is cached on disk) serves every slot:
  it looks the ``mjModel*`` argument up in the registry and leaves every unregistered model alone,
  so a new law or a new model costs no compilation. A slot is freed when its callback object is
  collected (the callback keeps its model alive, so the address cannot be reused meanwhile).
* The state is read and the force written through the ``mjData*`` argument: the byte offsets of
  the ``qpos``, ``qvel``, ``act``, ``ctrl`` and ``qfrc_applied`` pointer fields come from mujoco's
  own struct description (``mujoco.introspect``, generated from its headers) laid out with ctypes,
  and are checked against the live arrays of every model at start-up (pointer values equal to the
  numpy arrays' addresses, and a sentinel written through the pointer read back through numpy).
* ``CompiledForkCallback`` *is* a ctypes function pointer (a ``ctypes._CFuncPtr`` subclass), which
  is what ``mujoco.set_mjcb_control`` accepts for a C callback; ``installed(callback)`` works with
  it unchanged. Its ``calls`` counts the calls for its model (atomically, across threads).

If numba is missing (or the struct layout cannot be verified) ``make_callback`` returns the Python
``ForkCallback`` and warns once.
"""
from __future__ import annotations

import contextlib
import ctypes
import logging
import math
import os
import threading
import time
import warnings
import weakref
from dataclasses import replace

import mujoco
import numpy as np

from mtbmj.controllers import damper as _damper
from mtbmj.controllers import friction as _friction
from mtbmj.controllers import spring as _spring
from mtbmj.controllers import stops as _stops
from mtbmj.controllers.callback import ForkCallback
from mtbmj.controllers.fork import ForkLaw
from mtbmj.errors import FallbackWarning

try:  # numba is optional: without it mtbmj runs the Python laws
    import numba as _numba
    from llvmlite import ir as _ir
    from numba import types as _t
    from numba.core import cgutils as _cgutils
    from numba.extending import intrinsic as _intrinsic
    _NUMBA_ERROR: Exception | None = None
except ImportError as error:  # pragma: no cover - exercised in a subprocess by the tests
    _numba = None
    _NUMBA_ERROR = error

FALLBACK_MESSAGE = "numba not installed: using the Python force laws"

# ----------------------------------------------------------------------------------------------
# Codes and registry layout
# ----------------------------------------------------------------------------------------------
SP_LINEAR, SP_BILINEAR, SP_PROGRESSIVE, SP_DIRECTIONAL, SP_TOPOUT, SP_STOPS = 1, 2, 3, 4, 5, 6
SP_AIR = 7
DA_LINEAR, DA_BILINEAR, DA_TABLE, DA_DIGRESSIVE = 1, 2, 3, 4
FR_NONE, FR_COULOMB, FR_COULOMB_VISCOUS, FR_STICTION, FR_STRIBECK, FR_LUGRE = 0, 1, 2, 3, 4, 5
FR_STICKING = 6  # Sticking around one of the static laws: I_FRICTION_INNER holds that law's code

# integer row of a slot
I_MODEL, I_QPOS, I_DOF, I_STATE, I_ACT, I_CTRL, I_COUNT, I_CALLS = 0, 1, 2, 3, 4, 5, 6, 7
I_DAMPER, I_DAMPER_AT, I_DAMPER_N, I_FRICTION, I_FRICTION_AT, I_NSPRING = 8, 9, 10, 11, 12, 13
I_SPRING = 14  # then (opcode, parameter offset) pairs
MAX_SPRING_OPS = 24
I_FRICTION_INNER = I_SPRING + 2 * MAX_SPRING_OPS  # 62
I_RIM, I_RIM_AT, I_SLED_QPOS, I_SLED_DOF = 63, 64, 65, 66  # the rim strike (drop scene only)
I_FLOOR, I_FLOOR_AT = 67, 68  # the soft contact's correction (drop scene only; controllers.tire.ContactFloor)
INT_WIDTH = 69
FLOAT_WIDTH = 1024
STACK_DEPTH = 16
SLOTS = 256

_INTS = np.zeros((SLOTS, INT_WIDTH), dtype=np.int64)
_FLOATS = np.zeros((SLOTS, FLOAT_WIDTH), dtype=np.float64)
# Registry header, read by the compiled dispatcher through an external symbol (see _registry):
M_USED, M_INTS, M_FLOATS, M_QPOS, M_QVEL, M_ACT, M_CTRL, M_QFRC = range(8)
META_WIDTH = 8
_META = np.zeros(META_WIDTH, dtype=np.int64)  # slots in use (high-water mark), addresses, offsets
_META[M_INTS], _META[M_FLOATS] = _INTS.ctypes.data, _FLOATS.ctypes.data
REGISTRY_SYMBOL = "mtbmj_fork_registry_v1"
_OWNED = np.zeros(SLOTS, dtype=bool)  # slot held by a live CompiledForkCallback (served or retired)
# re-entrant: a callback collected by the garbage collector frees its slot (weakref.finalize)
# wherever the collector runs, also inside a registry operation of this thread
_REGISTRY_LOCK = threading.RLock()

MJDATA_FIELDS = ("qpos", "qvel", "act", "ctrl", "qfrc_applied")


class UnsupportedLaw(TypeError):
    """A law this module cannot compile (the Python path still runs it)."""


# ----------------------------------------------------------------------------------------------
# Flattening a ForkLaw into codes and parameters (pure Python; no numba needed)
# ----------------------------------------------------------------------------------------------
def flatten(law: ForkLaw) -> tuple[list[int], list[float]]:
    """(integer row, float row) of ``law``, without the slot header (model, indices, counters)."""
    ints = [0] * INT_WIDTH
    floats: list[float] = []

    def put(*values) -> int:
        at = len(floats)
        floats.extend(float(a) for a in values)
        return at

    program: list[tuple[int, int]] = []
    depth = [0, 0]  # current, maximum

    def push():
        depth[0] += 1
        depth[1] = max(depth[1], depth[0])

    def spring(s):
        # Exact types only: a subclass may override force() and must run on the Python path.
        kind = type(s)
        if kind is _spring.LinearSpring:
            program.append((SP_LINEAR, put(s.rate)))
            push()
        elif kind is _spring.BilinearSpring:
            program.append((SP_BILINEAR, put(s.rate, s.rate_above_knee, s.knee)))
            push()
        elif kind is _spring.ProgressiveSpring:
            program.append((SP_PROGRESSIVE, put(s.rate, s.cubic)))
            push()
        elif kind is _spring.DirectionalSpring:
            spring(s.compression)
            spring(s.rebound)
            program.append((SP_DIRECTIONAL, put(s.band)))
            depth[0] -= 1
        elif kind is _spring.TopOutSpring:
            spring(s.main)
            program.append((SP_TOPOUT, put(s.top_out_rate, s.preload, s.engagement)))
        elif kind is _stops.EndStops:
            spring(s.main)
            program.append((SP_STOPS, put(s.bumper_start, s.bumper_length, s.bumper_force, s.travel,
                                          s.stop_rate, s.stop_damping, s.extension, _stops.STIFFENING_M)))
        elif kind is _spring.AirSpring:
            program.append((SP_AIR, put(s.area, s.absolute, s.volume, s.index, s.atmospheric,
                                        float(s.has_negative), s.positive_at_port, s.negative_at_port, s.port,
                                        s.limit, s.limit_force, s.limit_rate, s.offset)))
            push()
        else:
            raise UnsupportedLaw(f"spring law {kind.__name__} has no compiled form")

    if type(law) is not ForkLaw:
        raise UnsupportedLaw(f"{type(law).__name__} is not a ForkLaw")
    spring(law.spring)
    if len(program) > MAX_SPRING_OPS or depth[1] > STACK_DEPTH:
        raise UnsupportedLaw("spring law too deeply composed to compile")
    ints[I_NSPRING] = len(program)
    for k, (op, at) in enumerate(program):
        ints[I_SPRING + 2 * k] = op
        ints[I_SPRING + 2 * k + 1] = at

    d = law.damper
    kind = type(d)
    if kind is _damper.LinearDamper:
        ints[I_DAMPER], ints[I_DAMPER_AT] = DA_LINEAR, put(d.coefficient)
    elif kind is _damper.BilinearDamper:
        ints[I_DAMPER], ints[I_DAMPER_AT] = DA_BILINEAR, put(d.compression, d.rebound)
    elif kind is _damper.DigressiveDamper:
        ints[I_DAMPER], ints[I_DAMPER_AT] = DA_DIGRESSIVE, put(d.compression_low, d.compression_high, d.compression_knee,
                                                               d.rebound_low, d.rebound_high, d.rebound_knee)
    elif kind is _damper.TableDamper:
        n = len(d.velocity)
        ints[I_DAMPER], ints[I_DAMPER_N] = DA_TABLE, n
        ints[I_DAMPER_AT] = put(*d.velocity, *d.force_table, *d._slopes)
    else:
        raise UnsupportedLaw(f"damper law {kind.__name__} has no compiled form")

    f = law.friction
    kind = type(f)
    if kind is _friction.Sticking:
        ints[I_FRICTION] = FR_STICKING
        inner = f.inner
        codes = {_friction.Coulomb: FR_COULOMB, _friction.CoulombViscous: FR_COULOMB_VISCOUS,
                 _friction.Stiction: FR_STICTION, _friction.Stribeck: FR_STRIBECK}
        if type(inner) not in codes:
            raise UnsupportedLaw(f"friction law Sticking({type(inner).__name__}) has no compiled form")
        ints[I_FRICTION_INNER] = codes[type(inner)]
        ints[I_FRICTION_AT] = put(f.stiffness, f.damping, f.elastic, inner.coulomb,
                                  getattr(inner, "breakaway", 0.0), getattr(inner, "viscous", 0.0),
                                  getattr(inner, "stiction_band", 0.0) or getattr(inner, "stribeck_velocity", 1.0),
                                  getattr(inner, "exponent", 2.0), f.damping_velocity)
    elif kind is _friction.NoFriction:
        ints[I_FRICTION], ints[I_FRICTION_AT] = FR_NONE, put(0.0)
    elif kind is _friction.Coulomb:
        ints[I_FRICTION], ints[I_FRICTION_AT] = FR_COULOMB, put(f.coulomb, f.band)
    elif kind is _friction.CoulombViscous:
        ints[I_FRICTION], ints[I_FRICTION_AT] = FR_COULOMB_VISCOUS, put(f.coulomb, f.viscous, f.band)
    elif kind is _friction.Stiction:
        ints[I_FRICTION] = FR_STICTION
        ints[I_FRICTION_AT] = put(f.coulomb, f.breakaway, f.viscous, f.stiction_band, f.band)
    elif kind is _friction.Stribeck:
        ints[I_FRICTION] = FR_STRIBECK
        ints[I_FRICTION_AT] = put(f.coulomb, f.breakaway, f.viscous, f.stribeck_velocity, f.exponent, f.band)
    elif kind is _friction.LuGre:
        ints[I_FRICTION] = FR_LUGRE
        # 2.0 is stored, not written as a literal, so that (v / v_S) ** 2 is the same libm pow()
        # call Python makes for float ** int (a literal could be folded into v * v).
        ints[I_FRICTION_AT] = put(f.coulomb, f.breakaway, f.stribeck_velocity, f.stiffness, f.damping,
                                  f.viscous, 2.0)
    else:
        raise UnsupportedLaw(f"friction law {kind.__name__} has no compiled form")
    if len(floats) > FLOAT_WIDTH:
        raise UnsupportedLaw(f"law needs {len(floats)} parameters, more than {FLOAT_WIDTH}")
    ints[I_STATE] = int(bool(law.has_state))
    return ints, floats


def law_arrays(law: ForkLaw) -> tuple[np.ndarray, np.ndarray]:
    """``flatten(law)`` as the (int64, float64) arrays the kernels take (``fork_force(I, P, ...)``)."""
    ints, floats = flatten(law)
    P = np.zeros(FLOAT_WIDTH)
    P[: len(floats)] = floats
    return np.asarray(ints, dtype=np.int64), P


def modal_filter(phi, g_in, g_new, r, w, u, out) -> bool:
    """``mtbmj.drop.measure.logger_filter``'s recursion along ``u`` (signals x samples) into
    ``out``, ``w`` (signals x modes) updated in place; False when numba is missing."""
    if _numba is None:
        return False
    _modal_filter(phi, g_in, g_new, r, w, np.ascontiguousarray(u, dtype=np.float64), out)
    return True


def fork_forces_along(law: ForkLaw, x, v, z) -> np.ndarray | None:
    """ForkLaw.force along arrays through the compiled kernel, or None when it cannot run here
    (numba missing, or a law with no compiled form): the caller then uses the Python law."""
    if _numba is None:
        return None
    try:
        I, P = law_arrays(law)
    except UnsupportedLaw:
        return None
    x, v, z = (np.asarray(a, dtype=np.float64) for a in (x, v, z))  # strided views stay views
    out = np.empty(x.size)
    fork_forces(I, P, x, v, z, out)
    return out


# ----------------------------------------------------------------------------------------------
# mjData layout from mujoco's own struct description, checked against live arrays
# ----------------------------------------------------------------------------------------------
_SCALARS = {
    "mjtNum": ctypes.c_double, "double": ctypes.c_double, "float": ctypes.c_float, "int": ctypes.c_int,
    "unsigned int": ctypes.c_uint, "mjtSize": ctypes.c_int64, "int64_t": ctypes.c_int64,
    "uint64_t": ctypes.c_uint64, "size_t": ctypes.c_size_t, "uintptr_t": ctypes.c_size_t,
    "mjtBool": ctypes.c_ubyte, "mjtByte": ctypes.c_ubyte, "char": ctypes.c_char,
}
_STRUCT_CACHE: dict = {}
_LAYOUT: dict | None = None


def _ctype(t):
    from mujoco.introspect import ast_nodes, structs

    if isinstance(t, ast_nodes.PointerType):
        return ctypes.c_void_p
    if isinstance(t, ast_nodes.ArrayType):
        return _ctype(t.inner_type) * int(np.prod(t.extents))
    if t.name in _SCALARS:
        return _SCALARS[t.name]
    if t.name in structs.STRUCTS:
        return _struct(t.name)
    raise TypeError(f"no ctypes equivalent for {t.name!r} in mujoco's struct description")


def _struct(name: str):
    from mujoco.introspect import ast_nodes, structs

    if name not in _STRUCT_CACHE:
        fields = []
        for f in structs.STRUCTS[name].fields:
            if not isinstance(f, ast_nodes.StructFieldDecl):
                raise TypeError(f"{name}: anonymous struct/union members are not supported")
            fields.append((f.name, _ctype(f.type)))
        _STRUCT_CACHE[name] = type(name, (ctypes.Structure,), {"_fields_": fields})
    return _STRUCT_CACHE[name]


def mjdata_layout() -> dict:
    """Byte offsets in ``mjData`` of the pointer fields the callback uses (and of ``time``, for
    the check), laid out with ctypes from ``mujoco.introspect`` (mujoco's header description)."""
    global _LAYOUT
    if _LAYOUT is None:
        s = _struct("mjData")
        _LAYOUT = {name: getattr(s, name).offset for name in MJDATA_FIELDS + ("time",)}
    return dict(_LAYOUT)


def check_layout(model, layout: dict | None = None) -> None:
    """Check the offsets against a live ``MjData`` of ``model``: each pointer field holds the address
    of the numpy array mujoco exposes, and a sentinel written through it is read back by numpy.
    Raises RuntimeError on any mismatch."""
    layout = mjdata_layout() if layout is None else layout
    data = mujoco.MjData(model)
    data.time = 0.123456789
    base = data._address
    if ctypes.c_double.from_address(base + layout["time"]).value != data.time:
        raise RuntimeError("mjData layout check failed: 'time' is not where mujoco's struct description puts it")
    for name in MJDATA_FIELDS:
        array = getattr(data, name)
        pointer = ctypes.c_void_p.from_address(base + layout[name]).value
        if array.size == 0:
            continue
        if pointer != array.ctypes.data:
            raise RuntimeError(f"mjData layout check failed: pointer field {name!r} at byte {layout[name]} "
                               f"does not hold the address of data.{name}")
        cell = ctypes.c_double.from_address(pointer + 8 * (array.size - 1))
        old = float(array.flat[-1])
        cell.value = 1234.5678
        ok = array.flat[-1] == 1234.5678
        cell.value = old
        if not ok:
            raise RuntimeError(f"mjData layout check failed: a sentinel written through {name!r} was not read back")


# ----------------------------------------------------------------------------------------------
# The compiled interpreter and dispatcher
# ----------------------------------------------------------------------------------------------
COMPILE_SECONDS: float | None = None  # wall time to compile (or load from numba's cache) the kernels
COMPILE_LOG = logging.getLogger("mtbmj.compile")
# loading from numba's cache takes ~0.1-2 s (a loaded machine); compiling 10 s or more (MTBMJ_COMPILE_NOTICE_S sets it)
COMPILE_NOTICE_S = float(os.environ.get("MTBMJ_COMPILE_NOTICE_S", "3.0"))


def _notice(what: str) -> threading.Timer:
    """Log (INFO, logger ``mtbmj.compile``) that ``what`` is being compiled, if it is still going
    after ``COMPILE_NOTICE_S``: a cold first run says why it waits; a cached load stays silent.
    The library only logs; the command line shows the message on stderr. :func:`cold` says so at
    once where numba's cache shows that nothing is there to load."""
    timer = threading.Timer(COMPILE_NOTICE_S, _say_compiling, (what,))
    timer.daemon = True
    timer.start()
    return timer


def _say_compiling(what: str) -> None:
    COMPILE_LOG.info(f"compiling {what} for this machine (first run only; numba caches it)...")


def _say_now_if_cold(timer: threading.Timer, what: str, dispatcher) -> None:
    """With nothing in numba's cache for ``dispatcher`` (:func:`cold`), say at once that ``what``
    compiles, instead of after ``timer``."""
    if cold(dispatcher):
        timer.cancel()
        _say_compiling(what)


def cold(dispatcher) -> bool:
    """True when numba's on-disk cache holds no compiled code for ``dispatcher`` that it can load
    (no index, or one written for other sources): it is about to compile. False when it can load,
    or when that cannot be told (no disk cache; a numba without these internals): the timer of
    :func:`_notice` then decides."""
    try:
        return not dispatcher._cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - numba's internals: fall back to the timer
        return False


@contextlib.contextmanager
def compiling(what: str, dispatcher=None):
    """Around code that may compile numba functions (``dispatcher``, if given, is checked with
    :func:`cold` to say so at once): see ``_notice``."""
    timer = _notice(what)
    if dispatcher is not None:
        _say_now_if_cold(timer, what, dispatcher)
    try:
        yield
    finally:
        timer.cancel()




def can_cache(probe) -> bool:
    """Whether numba can keep compiled code on disk for the file that defines ``probe`` (any
    function). A read-only install run by a user without a writable home (services, containers)
    offers no cache directory: numba then raises at decoration ("no locator available"), and the
    kernels are compiled in memory for the process instead (same code, same results)."""
    try:
        _numba.njit(cache=True)(probe)  # lazy: nothing is compiled or written
    except RuntimeError as error:
        if "cannot cache" not in str(error):
            raise
        return False
    return True


CACHE: bool | None = None  # whether the kernels below are cached on disk (None: numba missing)
if _numba is not None:
    import llvmlite.binding as _llvm

    _compile_start = time.perf_counter()
    _compile_notice = _notice("the force laws")

    _llvm.add_symbol(REGISTRY_SYMBOL, _META.ctypes.data)

    @_intrinsic
    def _address_of(typingctx, pointer):
        """voidptr -> integer address."""
        def codegen(context, builder, signature, args):
            return builder.ptrtoint(args[0], context.get_value_type(_t.intp))
        return _t.intp(_t.voidptr), codegen

    @_intrinsic
    def _f64_pointer(typingctx, address):
        """integer address -> double*."""
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(_t.CPointer(_t.float64)))
        return _t.CPointer(_t.float64)(_t.intp), codegen

    @_intrinsic
    def _i64_pointer(typingctx, address):
        """integer address -> int64*."""
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(_t.CPointer(_t.int64)))
        return _t.CPointer(_t.int64)(_t.intp), codegen

    @_intrinsic
    def _pointer_field(typingctx, base, offset):
        """The double* stored at byte ``offset`` of the struct at ``base`` (an mjData pointer field)."""
        def codegen(context, builder, signature, args):
            struct, at = args
            slot_address = builder.add(builder.ptrtoint(struct, context.get_value_type(_t.intp)), at)
            value = builder.load(builder.inttoptr(slot_address, context.get_value_type(_t.CPointer(_t.intp))))
            return builder.inttoptr(value, context.get_value_type(_t.CPointer(_t.float64)))
        return _t.CPointer(_t.float64)(_t.voidptr, _t.intp), codegen

    @_intrinsic
    def _atomic_increment(typingctx, pointer):
        """*pointer += 1, atomically (the per-slot call counter; threads share it)."""
        def codegen(context, builder, signature, args):
            builder.atomic_rmw("add", args[0], _ir.Constant(_ir.IntType(64), 1), "monotonic")
            return context.get_dummy_value()
        return _t.void(_t.CPointer(_t.int64)), codegen

    @_intrinsic
    def _stack_buffer(typingctx):
        """A double[STACK_DEPTH] on the native stack (no allocation per call)."""
        def codegen(context, builder, signature, args):
            return _cgutils.alloca_once(builder, _ir.DoubleType(), size=STACK_DEPTH)
        return _t.CPointer(_t.float64)(), codegen

    CACHE = can_cache(lambda: None)
    _jit = dict(cache=CACHE, error_model="numpy", nogil=True)
    # the stops' and the rim's force law: the one Python function, compiled from its own source
    contact_force = _numba.njit(inline="always", **_jit)(_stops.contact_force)

    # A numpy array handed from one compiled function to the next is reference-counted at every
    # call (two atomic operations per array), which cost more than the law itself: 139 against
    # 39 ns for S1's fork force. The kernels that call the laws in a loop borrow views without
    # a reference count instead, valid while the caller holds the array.
    @_numba.njit(**_jit)
    def borrow_f64(a):
        """A view of the contiguous 1-d float64 array ``a`` that is not reference-counted."""
        return _numba.carray(_f64_pointer(a.ctypes.data), a.shape)

    @_numba.njit(**_jit)
    def borrow_i64(a):
        """A view of the contiguous 1-d int64 array ``a`` that is not reference-counted."""
        return _numba.carray(_i64_pointer(a.ctypes.data), a.shape)

    @_numba.njit(**_jit)
    def _air_force(P, o, x):
        """AirSpring.force; P[o:] = area, p + p_a, V, n, p_a, negative?, V_p, V_m, port, limit,
        force and rate at the limit, offset."""
        a = P[o]
        n = P[o + 3]
        negative = P[o + 5] != 0.0
        if negative and not (x - P[o + 8] >= 0.0):
            return -P[o + 12]
        if x - P[o + 9] >= 0.0:
            return P[o + 10] + P[o + 11] * (x - P[o + 9]) - P[o + 12]
        if negative:
            d = x - P[o + 8]
            vp = P[o + 6]
            vm = P[o + 7]
            return a * P[o + 1] * ((vp / (vp - a * d)) ** n - (vm / (vm + a * d)) ** n) - P[o + 12]
        return a * (P[o + 1] * (P[o + 2] / (P[o + 2] - a * x)) ** n - P[o + 4]) - P[o + 12]

    @_numba.njit(**_jit)
    def _spring_force(I, P, x, v):
        stack = _stack_buffer()
        top = 0
        for k in range(I[I_NSPRING]):
            op = I[I_SPRING + 2 * k]
            o = I[I_SPRING + 2 * k + 1]
            if op == SP_LINEAR:  # LinearSpring.force
                stack[top] = P[o] * x
                top += 1
            elif op == SP_BILINEAR:  # BilinearSpring.force
                knee = P[o + 2]
                if x - knee >= 0.0:
                    stack[top] = P[o] * knee + P[o + 1] * (x - knee)
                else:
                    stack[top] = P[o] * x
                top += 1
            elif op == SP_PROGRESSIVE:  # ProgressiveSpring.force
                stack[top] = P[o] * x + P[o + 1] * x * x * x
                top += 1
            elif op == SP_DIRECTIONAL:  # DirectionalSpring.force
                rebound = stack[top - 1]
                compression = stack[top - 2]
                top -= 2
                w = 0.5 * (1.0 + math.tanh(v / P[o]))
                stack[top] = w * compression + (1.0 - w) * rebound
                top += 1
            elif op == SP_AIR:  # AirSpring.force
                stack[top] = _air_force(P, o, x)
                top += 1
            elif op == SP_TOPOUT:  # TopOutSpring.force
                engagement = P[o + 2]
                force = P[o + 1] + stack[top - 1]
                if not (x - engagement >= 0.0):
                    force -= P[o] * (engagement - x)
                stack[top - 1] = force
            else:  # SP_STOPS, EndStops.force: bumper, compression stop, extension stop
                bumper = 0.0
                s = x - P[o]
                if s >= 0.0:
                    r = s / P[o + 1]
                    bumper = P[o + 2] * r * r
                stop = 0.0
                p = x - P[o + 3]
                if p >= 0.0:
                    f = contact_force(P[o + 4], P[o + 5], p, v)
                    if f >= 0.0:
                        stop = f
                top_stop = 0.0
                q = -P[o + 6] - x
                if q >= 0.0:
                    f = contact_force(P[o + 4], P[o + 5], q, -v)
                    if f >= 0.0:
                        top_stop = f
                stack[top - 1] = stack[top - 1] + bumper + stop - top_stop
        return stack[0]

    @_numba.njit(**_jit)
    def _damper_force(I, P, v):
        code = I[I_DAMPER]
        o = I[I_DAMPER_AT]
        if code == DA_LINEAR:  # LinearDamper.force
            return P[o] * v
        if code == DA_BILINEAR:  # BilinearDamper.force
            return (P[o] if v >= 0.0 else P[o + 1]) * v
        if code == DA_DIGRESSIVE:  # DigressiveDamper.force
            if v >= 0.0:
                if v - P[o + 2] >= 0.0:
                    return P[o] * P[o + 2] + P[o + 1] * (v - P[o + 2])
                return P[o] * v
            if v + P[o + 5] >= 0.0:
                return P[o + 3] * v
            return -P[o + 3] * P[o + 5] + P[o + 4] * (v + P[o + 5])
        n = I[I_DAMPER_N]  # TableDamper.force: velocity[n], force[n], slopes[n - 1]
        i = 0
        for j in range(1, n - 1):
            if v >= P[o + j]:
                i += 1
            else:
                break
        return P[o + n + i] + P[o + 2 * n + i] * (v - P[o + i])

    @_numba.njit(**_jit)
    def _lugre_rate(P, o, v, z):
        g = P[o] + (P[o + 1] - P[o]) * math.exp(-((v / P[o + 2]) ** P[o + 6]))  # LuGre.g
        speed = v if v >= 0.0 else -v
        return v - P[o + 3] * speed * z / g

    @_numba.njit(**_jit)
    def _sliding_level(code, P, o, v):
        """controllers.friction.sliding_level for the law stored at P[o + 3:] of a Sticking row."""
        fc = P[o + 3]
        if code == FR_STRIBECK:
            return fc + (P[o + 4] - fc) * math.exp(-abs(v / P[o + 6]) ** P[o + 7])
        if code == FR_STICTION:
            dv = P[o + 6]
            outside = v - dv >= 0.0 or not (v + dv >= 0.0)
            if not outside:
                return fc + (P[o + 4] - fc) * (1.0 - abs(v) / dv)
        return fc

    @_numba.njit(**_jit)
    def _sticking_rate(I, P, v, z):
        """Sticking.state_rate."""
        o = I[I_FRICTION_AT]
        z_ss = _sliding_level(I[I_FRICTION_INNER], P, o, v) / P[o]
        if (z > 0.0) != (v >= 0.0) or z == 0.0:
            return v
        r = abs(z) / z_ss
        elastic = P[o + 2]
        if r <= elastic:
            return v
        if r >= 1.0:
            alpha = 1.0
        else:
            alpha = 0.5 + 0.5 * math.sin(math.pi * (r - 0.5 * (1.0 + elastic)) / (1.0 - elastic))
        return v * (1.0 - alpha * r)

    @_numba.njit(**_jit)
    def _sticking_force(P, o, v, z, rate):
        """Sticking.force, given its state_rate ``rate``."""
        w = v / P[o + 8]
        damping = P[o + 1] * math.exp(-(w * w))
        return P[o] * z + damping * rate + P[o + 5] * v

    @_numba.njit(**_jit)
    def _friction_force(I, P, v, z):
        code = I[I_FRICTION]
        o = I[I_FRICTION_AT]
        if code == FR_STICKING:
            return _sticking_force(P, o, v, z, _sticking_rate(I, P, v, z))
        if code == FR_NONE:
            return 0.0
        if code == FR_COULOMB:
            return P[o] * math.tanh(v / P[o + 1])
        if code == FR_COULOMB_VISCOUS:
            return P[o] * math.tanh(v / P[o + 2]) + P[o + 1] * v
        if code == FR_STICTION:
            dv = P[o + 3]
            outside = v - dv >= 0.0 or not (v + dv >= 0.0)
            level = P[o]
            if not outside:
                level += (P[o + 1] - P[o]) * (1.0 - abs(v) / dv)
            return level * math.tanh(v / P[o + 4]) + P[o + 2] * v
        if code == FR_STRIBECK:
            level = P[o] + (P[o + 1] - P[o]) * math.exp(-abs(v / P[o + 3]) ** P[o + 4])
            return level * math.tanh(v / P[o + 5]) + P[o + 2] * v
        return P[o + 3] * z + P[o + 4] * _lugre_rate(P, o, v, z) + P[o + 5] * v  # LuGre.force

    @_numba.njit(**_jit)
    def fork_force(I, P, x, v, z):
        """ForkLaw.force(x, v, z) from a flattened law."""
        return _spring_force(I, P, x, v) + _damper_force(I, P, v) + _friction_force(I, P, v, z)

    @_numba.njit(**_jit)
    def fork_force_rate(I, P, x, v, z):
        """(fork_force, state_rate) at once: the stick state's rate is worked out once for both."""
        if I[I_FRICTION] == FR_STICKING:
            rate = _sticking_rate(I, P, v, z)
            friction = _sticking_force(P, I[I_FRICTION_AT], v, z, rate)
            return _spring_force(I, P, x, v) + _damper_force(I, P, v) + friction, rate
        return fork_force(I, P, x, v, z), state_rate(I, P, v, z)

    @_numba.njit(**_jit)
    def state_rate(I, P, v, z):
        """ForkLaw.state_rate(v, z) from a flattened law."""
        if I[I_FRICTION] == FR_STICKING:
            return _sticking_rate(I, P, v, z)
        if I[I_FRICTION] != FR_LUGRE:
            return 0.0
        return _lugre_rate(P, I[I_FRICTION_AT], v, z)

    @_numba.njit(**_jit)
    def _modal_filter(phi, g_in, g_new, r, w, u, out):
        """measure.logger_filter's recursion: y = 2 Re sum r (w + g_new u); w <- phi w + g_in u."""
        for s in range(u.shape[0]):
            for k in range(u.shape[1]):
                x = u[s, k]
                acc = 0.0
                for i in range(phi.size):
                    acc += (r[i] * (w[s, i] + g_new[i] * x)).real
                    w[s, i] = phi[i] * w[s, i] + g_in[i] * x
                out[s, k] = 2.0 * acc

    @_numba.njit(**_jit)
    def fork_forces(I, P, x, v, z, out):
        """``fork_force`` along a trace: out[i] = ForkLaw.force(x[i], v[i], z[i])."""
        I, P = borrow_i64(I), borrow_f64(P)
        for i in range(x.size):
            out[i] = fork_force(I, P, x[i], v[i], z[i])

    @_intrinsic
    def _registry(typingctx, index):
        """Entry ``index`` of the registry header, reached through the external symbol
        ``REGISTRY_SYMBOL`` (bound to ``_META`` with llvmlite's add_symbol at import): no address
        is baked into the code, so the dispatcher is cached on disk like the kernels."""
        def codegen(context, builder, signature, args):
            module = builder.module
            table = _ir.ArrayType(_ir.IntType(64), META_WIDTH)
            try:
                symbol = module.get_global(REGISTRY_SYMBOL)
            except KeyError:
                symbol = _ir.GlobalVariable(module, table, REGISTRY_SYMBOL)
                symbol.linkage = "external"
            at = builder.gep(symbol, [_ir.Constant(_ir.IntType(32), 0), args[0]])
            return builder.load(at)
        return _t.int64(_t.intp), codegen

    _say_now_if_cold(_compile_notice, "the force laws", fork_force)  # the dispatcher below compiles now

    @_numba.cfunc(_t.void(_t.voidptr, _t.voidptr), cache=CACHE, error_model="numpy")
    def _dispatch(m, d):
        model = _address_of(m)
        ints = _numba.carray(_i64_pointer(_registry(M_INTS)), (SLOTS, INT_WIDTH))
        slot = -1
        for s in range(_registry(M_USED)):
            if ints[s, I_MODEL] == model:
                slot = s
                break
        if slot < 0:
            return  # not one of ours: leave the model alone
        I = ints[slot]
        P = _numba.carray(_f64_pointer(_registry(M_FLOATS) + 8 * FLOAT_WIDTH * slot), (FLOAT_WIDTH,))
        if I[I_COUNT]:
            _atomic_increment(_i64_pointer(_registry(M_INTS) + 8 * (INT_WIDTH * slot + I_CALLS)))
        x = _pointer_field(d, _registry(M_QPOS))[I[I_QPOS]]
        v = _pointer_field(d, _registry(M_QVEL))[I[I_DOF]]
        qfrc = _pointer_field(d, _registry(M_QFRC))
        if I[I_STATE]:
            z = _pointer_field(d, _registry(M_ACT))[I[I_ACT]]
            f, rate = fork_force_rate(I, P, x, v, z)
            _pointer_field(d, _registry(M_CTRL))[I[I_CTRL]] = rate
            force = -f
        else:
            force = -fork_force(I, P, x, v, 0.0)
        if I[I_RIM] or I[I_FLOOR]:  # ground-side forces on the wheel: ForkCallback.__call__
            qpos = _pointer_field(d, _registry(M_QPOS))
            qvel = _pointer_field(d, _registry(M_QVEL))
            deflection = qpos[I[I_SLED_QPOS]] - x
            rate = qvel[I[I_SLED_DOF]] - v
            sled = 0.0
            if I[I_RIM]:  # Rim.force on the tire deflection (sled - fork), pushing the wheel up
                o = I[I_RIM_AT]
                p = deflection - P[o]
                rim = 0.0
                if p >= 0.0:
                    f = contact_force(P[o + 1], P[o + 2], p, rate)
                    if f >= 0.0:
                        rim = f
                sled = -rim
                force += rim
            if I[I_FLOOR]:  # ContactFloor.correction
                o = I[I_FLOOR_AT]
                c = 0.0
                if deflection > 0.0:
                    f = P[o + 2] * deflection + P[o + 3] * rate
                    if f > 0.0:
                        c = P[o] * (f + force - P[o + 1])
                sled -= c
                force += c
            qfrc[I[I_SLED_DOF]] = sled
        qfrc[I[I_DOF]] = force

    COMPILE_SECONDS = time.perf_counter() - _compile_start
    _compile_notice.cancel()

_DISPATCHER = None
_DISPATCHER_LOCK = threading.Lock()
_UNAVAILABLE: str | None = None


def _dispatcher(model=None):
    """The compiled dispatcher, its registry header filled with the mjData offsets; the first
    call (with a model) checks those offsets against live arrays of that model."""
    global _DISPATCHER, _UNAVAILABLE
    with _DISPATCHER_LOCK:
        if _DISPATCHER is None:
            if _numba is None:
                raise RuntimeError(FALLBACK_MESSAGE)
            layout = mjdata_layout()
            if model is not None:
                try:
                    check_layout(model, layout)
                except RuntimeError as error:
                    _UNAVAILABLE = f"compiled force laws unavailable ({error}): using the Python force laws"
                    raise RuntimeError(_UNAVAILABLE) from None
            for index, name in ((M_QPOS, "qpos"), (M_QVEL, "qvel"), (M_ACT, "act"), (M_CTRL, "ctrl"),
                                (M_QFRC, "qfrc_applied")):
                _META[index] = layout[name]
            _DISPATCHER = _dispatch
        return _DISPATCHER


def available() -> bool:
    """True when the compiled path can run here (numba importable, mjData layout resolvable)."""
    return unavailable_reason() is None


def unavailable_reason() -> str | None:
    global _UNAVAILABLE
    if _numba is None:
        return FALLBACK_MESSAGE
    if _UNAVAILABLE is None:
        try:
            mjdata_layout()
        except Exception as error:  # noqa: BLE001 - any failure means: use the Python path
            _UNAVAILABLE = f"compiled force laws unavailable ({error}): using the Python force laws"
    return _UNAVAILABLE or None


# ----------------------------------------------------------------------------------------------
# The callback object
# ----------------------------------------------------------------------------------------------
def _release(slot: int) -> None:
    with _REGISTRY_LOCK:
        _INTS[slot, I_MODEL] = 0  # first: the dispatcher stops serving the slot
        _INTS[slot] = 0
        _FLOATS[slot] = 0.0
        _OWNED[slot] = False
        while _META[M_USED] > 0 and not _OWNED[_META[M_USED] - 1]:
            _META[M_USED] -= 1


class CompiledForkCallback(ctypes._CFuncPtr):
    """Compiled counterpart of ``ForkCallback``: a C function pointer for
    ``mujoco.set_mjcb_control`` (or ``controllers.installed``) that writes -F_fork into the fork
    joint's ``qfrc_applied`` and, for LuGre, dz/dt into the integrator actuator's ``ctrl``.

    It acts only on ``model`` (and on the models of other live ``CompiledForkCallback`` objects,
    each with its own law: they share one compiled dispatcher), never on any other model. The
    newest callback built for a model defines its law: an older one for the same model is retired
    (it no longer acts; its ``calls`` stays readable). ``calls`` counts the calls for ``model``;
    pass ``count_calls=False`` to skip the atomic counter.
    """

    _flags_ = ctypes._FUNCFLAG_CDECL
    _argtypes_ = (ctypes.c_void_p, ctypes.c_void_p)
    _restype_ = None

    def __new__(cls, model, fork_law, fork_joint: str = "fork", state_actuator: str = "friction_state",
                count_calls: bool = True, rim=None, sled_joint: str = "sled", floor=None):
        reason = unavailable_reason()
        if reason is not None:
            raise RuntimeError(reason)
        return super().__new__(cls, _dispatcher(model).address)

    def __init__(self, model, fork_law, fork_joint: str = "fork", state_actuator: str = "friction_state",
                 count_calls: bool = True, rim=None, sled_joint: str = "sled", floor=None):
        ints, floats = flatten(fork_law)
        self.rim = rim
        self.floor = floor
        if rim is not None or floor is not None:  # on the tire deflection sled - fork (the drop scene)
            sled = model.joint(sled_joint)
            ints[I_SLED_QPOS], ints[I_SLED_DOF] = int(sled.qposadr[0]), int(sled.dofadr[0])
        if rim is not None:  # the rim strike
            ints[I_RIM], ints[I_RIM_AT] = 1, len(floats)
            floats = floats + [rim.max_deflection, rim.rate, rim.damping, _stops.STIFFENING_M]
        if floor is not None:  # the soft contact's correction
            ints[I_FLOOR], ints[I_FLOOR_AT] = 1, len(floats)
            floats = floats + [floor.factor, floor.wheel_weight, floor.rate, floor.damping]
        if len(floats) > FLOAT_WIDTH:
            raise UnsupportedLaw(f"law needs {len(floats)} parameters, more than {FLOAT_WIDTH}")
        joint = model.joint(fork_joint)
        actuator = model.actuator(state_actuator)
        self.law = fork_law
        self._model = model  # keeps the mjModel (and so its address) alive while the slot is used
        self.qpos_index = int(joint.qposadr[0])
        self.dof_index = int(joint.dofadr[0])
        self.has_state = fork_law.has_state
        self.ctrl_index = int(actuator.id)
        self.act_index = int(model.actuator_actadr[actuator.id])
        ints[I_QPOS], ints[I_DOF] = self.qpos_index, self.dof_index
        ints[I_ACT], ints[I_CTRL] = self.act_index, self.ctrl_index
        ints[I_COUNT] = int(bool(count_calls))
        with _REGISTRY_LOCK:
            free = np.flatnonzero(~_OWNED)
            if not free.size:
                raise RuntimeError(f"more than {SLOTS} compiled fork callbacks alive at once")
            slot = int(free[0])
            _OWNED[slot] = True
            _INTS[_INTS[:, I_MODEL] == model._address, I_MODEL] = 0  # retire older ones of this model
            _FLOATS[slot, : len(floats)] = floats
            row = np.asarray(ints, dtype=np.int64)
            row[I_MODEL] = 0
            _INTS[slot] = row
            _INTS[slot, I_MODEL] = model._address  # last: the slot goes live complete
            _META[M_USED] = max(_META[M_USED], slot + 1)
        self.slot = slot
        self._finalizer = weakref.finalize(self, _release, slot)

    @property
    def address(self) -> int:
        """The C function's address (``set_mjcb_control`` takes this object itself)."""
        return ctypes.cast(self, ctypes.c_void_p).value

    @property
    def active(self) -> bool:
        """True while this callback defines its model's law (not retired, not closed)."""
        return bool(_OWNED[self.slot]) and _INTS[self.slot, I_MODEL] == self._model._address and \
            self._finalizer.alive

    @property
    def calls(self) -> int:
        return int(_INTS[self.slot, I_CALLS]) if self._finalizer.alive else self._closed_calls

    @calls.setter
    def calls(self, value: int) -> None:
        _INTS[self.slot, I_CALLS] = value

    def __call__(self, m, d):
        """Call the compiled function from Python (as ``ForkCallback(m, d)``), e.g. in a test."""
        super().__call__(m._address, d._address)

    def bind(self, data) -> None:
        """No-op (``ForkCallback`` caches numpy views; the compiled path reads ``mjData*``)."""

    def set_tire(self, rate: float, damping: float) -> None:
        """The tire law's values changed (the switch): the contact correction follows."""
        if self.floor is not None and self._finalizer.alive:
            self.floor = replace(self.floor, rate=rate, damping=damping)
            at = int(_INTS[self.slot, I_FLOOR_AT])
            _FLOATS[self.slot, at + 2], _FLOATS[self.slot, at + 3] = rate, damping

    def close(self) -> None:
        """Free the registry slot now (also done when the object is collected)."""
        if self._finalizer.alive:
            self._closed_calls = self.calls
            self._finalizer()

    def __repr__(self):
        return f"<CompiledForkCallback slot={getattr(self, 'slot', None)} law={getattr(self, 'law', None)!r}>"


# ----------------------------------------------------------------------------------------------
# Choosing the path, and running a drop with a given callback
# ----------------------------------------------------------------------------------------------
_WARNED: set = set()


def _warn_once(message: str) -> None:
    if message not in _WARNED:
        _WARNED.add(message)
        warnings.warn(message, FallbackWarning, stacklevel=3)


def make_callback(model, law, prefer_compiled: bool = True, **kwargs):  # kwargs: rim=..., count_calls=...
    """``CompiledForkCallback`` when possible, else the Python ``ForkCallback`` (with a warning,
    once per reason: numba missing, layout not verifiable, or a law with no compiled form)."""
    if prefer_compiled:
        reason = unavailable_reason()
        if reason is None:
            try:
                return CompiledForkCallback(model, law, **kwargs)
            except UnsupportedLaw as error:
                _warn_once(f"{error}: using the Python force laws")
            except RuntimeError as error:  # the mjData layout check failed
                _warn_once(str(error))
        else:
            _warn_once(reason)
    kwargs.pop("count_calls", None)
    return ForkCallback(model, law, **kwargs)


__all__ = ["CompiledForkCallback", "make_callback", "available", "unavailable_reason", "flatten", "law_arrays",
           "fork_forces_along",
           "mjdata_layout", "check_layout", "UnsupportedLaw", "FALLBACK_MESSAGE"]

"""The drop's compiled fork callback: the fork law (``controllers.kernels``), the rim and the
soft contact's correction of ``ForkCallback`` as native code that MuJoCo calls without the GIL, so
threads in ``mujoco.rollout`` run in parallel.

The plain-Python laws stay the specification and the test oracle; the kernels compile the same
formulas (bit-identical results). One numba ``cfunc`` (compiled once; cached on disk) serves every
``CompiledForkCallback``: it looks the ``mjModel*`` argument up in its registry
(``controllers.native_data.Registry``) and leaves every unregistered model alone, so a new law or a
new model costs no compilation. The state is read and the force written through the ``mjData*``
argument, at the offsets ``controllers.native_data`` takes from mujoco's own struct description.

``CompiledForkCallback`` *is* a ctypes function pointer (a ``ctypes._CFuncPtr`` subclass), which is
what ``mujoco.set_mjcb_control`` accepts for a C callback; ``installed(callback)`` works with it
unchanged. Its ``calls`` counts the calls for its model (atomically, across threads).

If numba is missing (or the struct layout cannot be verified) the run path's chooser
(``mtbmj.runpath.callbacks.choose``, through ``mtbmj.drop.engine_mujoco.fork_callback``) takes the
Python ``ForkCallback`` and warns once (``unavailable_reason``, ``warn_once``).
"""
from __future__ import annotations

import ctypes
import threading
import warnings
import weakref
from dataclasses import replace

import numpy as np

from mtbmj.controllers.fork import ForkLaw
from mtbmj.controllers.jit import CACHE, FALLBACK_MESSAGE, callback, compiling, numba
from mtbmj.controllers.lawcodes import (
    FLOAT_WIDTH, I_ACT, I_CALLS, I_COUNT, I_CTRL, I_DOF, I_FLOOR, I_FLOOR_AT, I_QPOS, I_RIM, I_RIM_AT,
    I_SLED_DOF, I_SLED_QPOS, I_STATE, INT_WIDTH, UnsupportedLaw, flatten, law_arrays,
)
from mtbmj.controllers.layout import offsets, values
from mtbmj.controllers.native_data import MJDATA_FIELDS, Registry, check_layout, mjdata_layout, verified_reason, verify
from mtbmj.controllers.stops import Rim
from mtbmj.controllers.tire import ContactFloor
from mtbmj.errors import FallbackWarning

SLOTS = 256
REGISTRY = Registry("mtbmj_fork_registry_v2", SLOTS, {"ints": (INT_WIDTH, np.int64), "floats": (FLOAT_WIDTH, np.float64)},
                    MJDATA_FIELDS)
M_USED, M_INTS, M_FLOATS = REGISTRY.index["used"], REGISTRY.index["ints"], REGISTRY.index["floats"]
M_QPOS, M_QVEL, M_ACT, M_CTRL, M_QFRC = (REGISTRY.index[name] for name in MJDATA_FIELDS)
RIM, FLOOR = offsets(Rim), offsets(ContactFloor)
COMPILE_SECONDS: float | None = None


def fork_forces_along(law: ForkLaw, x, v, z) -> np.ndarray | None:
    """ForkLaw.force along arrays through the compiled kernel, or None when it cannot run here
    (numba missing, or a law with no compiled form): the caller then uses the Python law."""
    if numba is None:
        return None
    try:
        I, P = law_arrays(law)
    except UnsupportedLaw:
        return None
    from mtbmj.controllers import kernels

    # contiguous copies of strided views (a trace's columns): one compiled signature of the kernel,
    # whose inlined law takes seconds to compile, for a copy that takes microseconds
    x, v, z = (np.ascontiguousarray(a, dtype=np.float64) for a in (x, v, z))
    out = np.empty(x.size)
    kernels.fork_forces(I, P, x, v, z, out)
    return out


def modal_filter(phi, g_in, g_new, r, w, u, out) -> bool:
    """``mtbmj.drop.measure.logger_filter``'s recursion along ``u`` (signals x samples) into
    ``out``, ``w`` (signals x modes) updated in place; False when numba is missing."""
    if numba is None:
        return False
    from mtbmj.controllers import kernels

    kernels.modal_filter(phi, g_in, g_new, r, w, np.ascontiguousarray(u, dtype=np.float64), out)
    return True


if numba is not None:
    import time

    from mtbmj.controllers import kernels
    from mtbmj.controllers.native_data import (address_of, atomic_increment, f64_pointer, find_slot, i64_pointer,
                                               pointer_field)

    _start = time.perf_counter()
    fork_force, fork_force_rate, state_rate = kernels.fork_force, kernels.fork_force_rate, kernels.state_rate
    rim_force = kernels.rim_force
    _read = REGISTRY.reader()

    @callback(numba.types.void(numba.types.voidptr, numba.types.voidptr))
    def _dispatch(m, d):
        slot = find_slot(_read(M_INTS), _read(M_USED), INT_WIDTH, address_of(m))
        if slot < 0:
            return  # not one of ours: leave the model alone
        I = numba.carray(i64_pointer(_read(M_INTS) + 8 * INT_WIDTH * slot), (INT_WIDTH,))
        P = numba.carray(f64_pointer(_read(M_FLOATS) + 8 * FLOAT_WIDTH * slot), (FLOAT_WIDTH,))
        if I[I_COUNT]:
            atomic_increment(i64_pointer(_read(M_INTS) + 8 * (INT_WIDTH * slot + I_CALLS)))
        x = pointer_field(d, _read(M_QPOS))[I[I_QPOS]]
        v = pointer_field(d, _read(M_QVEL))[I[I_DOF]]
        qfrc = pointer_field(d, _read(M_QFRC))
        if I[I_STATE]:
            z = pointer_field(d, _read(M_ACT))[I[I_ACT]]
            f, rate = fork_force_rate(I, P, x, v, z)
            pointer_field(d, _read(M_CTRL))[I[I_CTRL]] = rate
            force = -f
        else:
            force = -fork_force(I, P, x, v, 0.0)
        if I[I_RIM] or I[I_FLOOR]:  # ground-side forces on the wheel: ForkCallback.__call__
            qpos = pointer_field(d, _read(M_QPOS))
            qvel = pointer_field(d, _read(M_QVEL))
            deflection = qpos[I[I_SLED_QPOS]] - x
            rate = qvel[I[I_SLED_DOF]] - v
            sled = 0.0
            if I[I_RIM]:  # Rim.force on the tire deflection (sled - fork), pushing the wheel up
                o = I[I_RIM_AT]
                rim = rim_force(P[o + RIM.max_deflection], P[o + RIM.rate], P[o + RIM.damping], deflection, rate)
                sled = -rim
                force += rim
            if I[I_FLOOR]:  # ContactFloor.correction
                o = I[I_FLOOR_AT]
                c = kernels.floor_correction(P[o + FLOOR.factor], P[o + FLOOR.wheel_weight], P[o + FLOOR.rate],
                                             P[o + FLOOR.damping], deflection, rate, force)
                sled -= c
                force += c
            qfrc[I[I_SLED_DOF]] = sled
        qfrc[I[I_DOF]] = force

    COMPILE_SECONDS = kernels.COMPILE_SECONDS + (time.perf_counter() - _start)

_DISPATCHER = None
_DISPATCHER_LOCK = threading.Lock()


def dispatcher(model=None):
    """The compiled dispatcher, its registry header filled with the mjData offsets; the first
    call (with a model) checks those offsets against live arrays of that model."""
    global _DISPATCHER
    with _DISPATCHER_LOCK:
        if _DISPATCHER is None:
            if numba is None:
                raise RuntimeError(FALLBACK_MESSAGE)
            if model is not None:
                reason = verify(model)
                if reason is not None:
                    raise RuntimeError(reason)
            REGISTRY.bind_layout(mjdata_layout())
            _DISPATCHER = _dispatch
        return _DISPATCHER


def available() -> bool:
    """True when the compiled path can run here (numba importable, mjData layout resolvable)."""
    return unavailable_reason() is None


def unavailable_reason() -> str | None:
    """Why the compiled path cannot run here, or None."""
    if numba is None:
        return FALLBACK_MESSAGE
    try:
        mjdata_layout()
    except Exception as error:  # noqa: BLE001 - any failure means: use the Python path
        return f"compiled force laws unavailable ({error}): using the Python force laws"
    return verified_reason()


# ----------------------------------------------------------------------------------------------
# The callback object
# ----------------------------------------------------------------------------------------------
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
        return super().__new__(cls, dispatcher(model).address)

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
            floats = floats + values(rim)
        if floor is not None:  # the soft contact's correction
            ints[I_FLOOR], ints[I_FLOOR_AT] = 1, len(floats)
            floats = floats + values(floor)
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
        row = np.asarray(ints, dtype=np.int64)
        slot = REGISTRY.claim(model._address, {"ints": row, "floats": floats}, "compiled fork callbacks")
        self.slot = slot
        self._finalizer = weakref.finalize(self, REGISTRY.release, slot)

    @property
    def address(self) -> int:
        """The C function's address (``set_mjcb_control`` takes this object itself)."""
        return ctypes.cast(self, ctypes.c_void_p).value

    @property
    def active(self) -> bool:
        """True while this callback defines its model's law (not retired, not closed)."""
        return REGISTRY.live(self.slot, self._model._address) and self._finalizer.alive

    @property
    def calls(self) -> int:
        return int(REGISTRY.tables["ints"][self.slot, I_CALLS]) if self._finalizer.alive else self._closed_calls

    @calls.setter
    def calls(self, value: int) -> None:
        REGISTRY.tables["ints"][self.slot, I_CALLS] = value

    def __call__(self, m, d):
        """Call the compiled function from Python (as ``ForkCallback(m, d)``), e.g. in a test."""
        super().__call__(m._address, d._address)

    def bind(self, data) -> None:
        """No-op (``ForkCallback`` caches numpy views; the compiled path reads ``mjData*``)."""

    def set_tire(self, rate: float, damping: float) -> None:
        """The tire law's values changed (the switch): the contact correction follows."""
        if self.floor is not None and self._finalizer.alive:
            self.floor = replace(self.floor, rate=rate, damping=damping)
            at = int(REGISTRY.tables["ints"][self.slot, I_FLOOR_AT])
            floats = REGISTRY.tables["floats"][self.slot]
            floats[at + FLOOR.rate], floats[at + FLOOR.damping] = rate, damping

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


def warn_once(message: str) -> None:
    """Warn (FallbackWarning) once per process for each distinct message."""
    if message not in _WARNED:
        _WARNED.add(message)
        warnings.warn(message, FallbackWarning, stacklevel=3)


__all__ = ["CompiledForkCallback", "available", "unavailable_reason", "dispatcher", "REGISTRY",
           "fork_forces_along", "modal_filter", "warn_once", "compiling", "CACHE", "COMPILE_SECONDS",
           # the rooms below, for the callers that reached them here
           "flatten", "law_arrays", "mjdata_layout", "check_layout", "UnsupportedLaw", "FALLBACK_MESSAGE"]

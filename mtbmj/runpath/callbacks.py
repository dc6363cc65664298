"""The choice of a rig's control callback and the rerun on its Python twin.

Every rig has a Python callback (the laws as plain Python, the reference behaviour) and a compiled
twin (the same functions compiled by numba). ``"auto"`` takes the compiled one when it can be made,
else the Python one with one warning per reason (numba missing, the mjData layout not verifiable,
a law, tire or terrain with no compiled form).
"""
from __future__ import annotations

import warnings
from typing import Callable

import numpy as np

from mtbmj.errors import FallbackWarning

KINDS = ("auto", "compiled", "python")


class CompiledShell:
    """The ctypes shell every compiled control callback shares, mixed in before ``ctypes._CFuncPtr``
    (whose subclass names ``_flags_``, ``_argtypes_`` and ``_restype_`` itself, as ctypes requires):
    its address, a call from Python as the Python twin's ``(m, d)``, whether it still holds its
    ``registry`` slot (``controllers.native_data.Registry``) and its model, and ``close``, which
    keeps ``counters()`` readable after the slot is freed."""

    registry = None  # the rig's registry of compiled slots

    @property
    def active(self) -> bool:
        return self.registry.live(self.slot, self._address) and self._finalizer.alive

    @property
    def address(self) -> int:
        import ctypes

        return ctypes.cast(self, ctypes.c_void_p).value

    def __call__(self, m, d):
        """Call the compiled function from Python (as the Python callback's ``(m, d)``)."""
        super().__call__(m._address, d._address)

    def close(self) -> None:
        """Free the registry slot now (also done when the object is collected)."""
        if self._finalizer.alive:
            self._closed = self.counters()
            self._finalizer()


def choose(kind: str, python: Callable, load: Callable, compiled: Callable, what: str):
    """The callback of ``kind``: ``python()`` makes the Python one; ``load()`` imports the module of
    the compiled one (numba is imported on the first compiled run only: it has
    ``unavailable_reason``, ``warn_once`` and the ``Unsupported*`` errors its constructor raises)
    and ``compiled(module)`` makes it; ``what`` names the rig in the fallback warning."""
    if kind == "python":
        return python()
    if kind not in KINDS:
        raise ValueError(f"callback: expected one of {', '.join(KINDS)}, got {kind!r}")
    module = load()
    if kind == "compiled":
        return compiled(module)
    reason = module.unavailable_reason()
    if reason is None:
        unsupported = tuple(getattr(module, n) for n in ("UnsupportedLaw", "UnsupportedRolling") if hasattr(module, n))
        try:
            return compiled(module)
        except unsupported as error:
            module.warn_once(f"{error}: using the Python {what} callback")
        except RuntimeError as error:  # the mjData layout check failed
            module.warn_once(str(error))
    else:
        module.warn_once(reason)
    return python()


def rerun_on_python(model, data, run: Callable, overflowed: Callable[[], bool], to_python: Callable[[], None],
                    what: str):
    """``run()`` from ``data``'s current state; if the compiled callback met more contact patches
    than it holds (``overflowed()``), that state is restored, ``to_python()`` installs the Python
    twin, and ``run()`` runs again, with one warning."""
    import mujoco

    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    start = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, start, kind)
    out = run()
    if overflowed():
        warnings.warn(f"compiled {what} callback: too many contact patches, rerunning on the Python path",
                      FallbackWarning, stacklevel=3)
        mujoco.mj_setState(model, data, start, kind)
        to_python()
        out = run()
    return out

"""numba for the force laws: whether it is here, how the kernels are compiled, and what a user is
told while they compile.

* ``numba`` is optional: ``numba`` below is the module or None, and ``FALLBACK_MESSAGE`` says what
  runs instead.
* ``law_function(fn)`` compiles a plain law function (``controllers.spring`` and the other law
  modules: the formulas the law objects call) with numba, the other plain functions it calls
  compiled with it. The function itself stays the plain Python the law objects call: one source,
  two ways of running it.
* ``OPTIONS`` are the options every kernel is compiled with (cached on disk where numba can keep a
  cache, no GIL, numpy's error model); ``compiling`` and ``cold`` log (logger ``mtbmj.compile``)
  that a first run compiles, and why it waits.
"""
from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import threading
import types
from pathlib import Path

try:  # numba is optional: without it mtbmj runs the Python laws
    import numba
    NUMBA_ERROR: Exception | None = None
except ImportError as error:  # pragma: no cover - exercised in a subprocess by the tests
    numba = None
    NUMBA_ERROR = error

FALLBACK_MESSAGE = "numba not installed: using the Python force laws"

COMPILE_LOG = logging.getLogger("mtbmj.compile")
# loading from numba's cache takes ~0.1-2 s (a loaded machine); compiling 10 s or more (MTBMJ_COMPILE_NOTICE_S sets it)
COMPILE_NOTICE_S = float(os.environ.get("MTBMJ_COMPILE_NOTICE_S", "3.0"))


def notice(what: str) -> threading.Timer:
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


def say_now_if_cold(timer: threading.Timer, what: str, dispatcher) -> None:
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
    timer = notice(what)
    if dispatcher is not None:
        say_now_if_cold(timer, what, dispatcher)
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
        numba.njit(cache=True)(probe)  # lazy: nothing is compiled or written
    except RuntimeError as error:
        if "cannot cache" not in str(error):
            raise
        return False
    return True


CACHE: bool | None = None  # whether the kernels are cached on disk (None: numba missing)
OPTIONS: dict = {}
if numba is not None:
    CACHE = can_cache(lambda: None)
    OPTIONS = dict(cache=CACHE, error_model="numpy", nogil=True)

# numba's disk cache keeps a compiled function while its own source file is unchanged; a kernel
# also holds the law formulas it inlines from the law modules, so its cache entry is keyed on those
# too: on the sources of every module of controllers/ (read once per process, well under 1 ms).
# Editing a formula then recompiles every kernel that holds it instead of loading stale code.
def _controllers_stamp() -> str:
    digest = hashlib.sha256()
    for path in sorted(Path(__file__).resolve().parent.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


LAW_SOURCES_STAMP = _controllers_stamp()
_KERNEL_CACHE = None


def _kernel_cache_class():
    """numba's FunctionCache whose source stamp also covers ``LAW_SOURCES_STAMP`` (numba's own
    locators, each extended; None if this numba lacks the internals, and plain caching is used)."""
    global _KERNEL_CACHE
    if _KERNEL_CACHE is None:
        try:
            from numba.core import caching

            def stamped(base):
                def get_source_stamp(self):
                    return (base.get_source_stamp(self), LAW_SOURCES_STAMP)
                return type(f"LawSources{base.__name__}", (base,), {"get_source_stamp": get_source_stamp})

            impl = type("LawSourcesCacheImpl", (caching.CompileResultCacheImpl,),
                        {"_locator_classes": [stamped(c) for c in caching.CompileResultCacheImpl._locator_classes]})
            _KERNEL_CACHE = type("LawSourcesFunctionCache", (caching.FunctionCache,), {"_impl_class": impl})
        except Exception:  # noqa: BLE001 - another numba: plain caching
            _KERNEL_CACHE = False
    return _KERNEL_CACHE or None


def kernel(fn=None, *, inline: bool = False):
    """``numba.njit(**OPTIONS)(fn)``, its disk cache keyed on the law sources too.

    ``inline=True``: compiled into every kernel that calls it, at numba's level, as the law
    functions are (``law_function``): the same code and numbers without a call per evaluation
    (``controllers.kernels.inlined``)."""
    if fn is None:
        return lambda f: kernel(f, inline=inline)
    options = {**OPTIONS, "inline": "always"} if inline else OPTIONS
    cache = _kernel_cache_class() if CACHE else None
    if cache is None:
        return numba.njit(**options)(fn)
    dispatcher = numba.njit(**{**options, "cache": False})(fn)
    dispatcher._cache = cache(fn)
    return dispatcher


def callback(signature):
    """``numba.cfunc(signature, cache=CACHE, error_model="numpy")``, its disk cache keyed on the
    law sources too (as numba's decorator builds it, with that cache)."""
    def build(fn):
        cache = _kernel_cache_class() if CACHE else None
        if cache is None:
            return numba.cfunc(signature, cache=bool(CACHE), error_model="numpy")(fn)
        from numba.core import sigutils
        from numba.core.ccallback import CFunc

        result = CFunc(fn, sigutils.normalize_signature(signature), locals={}, options={"error_model": "numpy"})
        result._cache = cache(fn)
        result.compile()
        return result
    return build


def rebound(fn, namespace: dict):
    """``fn`` with ``namespace`` for its globals (same code, name, defaults and closure): numba
    resolves the names a function calls in its globals when it compiles it, so a copy bound to
    other globals compiles against other functions of the same names."""
    clone = types.FunctionType(fn.__code__, namespace, fn.__name__, fn.__defaults__, fn.__closure__)
    clone.__qualname__, clone.__module__ = fn.__qualname__, fn.__module__
    return clone


_LAW_FUNCTIONS: dict = {}  # plain function -> its compiled twin
_LAW_GLOBALS: list = []  # the globals of every compiled twin: each sees every other twin by name
_LAW_LOCK = threading.Lock()


def law_function(fn):
    """``fn`` (a plain law function) compiled with numba, inlined into the kernels that call it.

    numba resolves a function's globals when it compiles it, and a plain function's globals are its
    module's: the twin is ``fn``'s code with a copy of those globals in which every plain function
    already handed to ``law_function`` is its compiled twin, so a formula that calls another (the
    stops call ``contact_force``) compiles as one. Call ``law_function`` for the callees too; the
    order does not matter (the globals are completed when a twin is made, numba reads them when it
    compiles, at the first call)."""
    with _LAW_LOCK:
        twin = _LAW_FUNCTIONS.get(fn)
        if twin is None:
            namespace = dict(fn.__globals__)
            twin = numba.njit(inline="always", **OPTIONS)(rebound(fn, namespace))
            _LAW_FUNCTIONS[fn] = twin
            _LAW_GLOBALS.append(namespace)
            for other in _LAW_GLOBALS:
                for plain, compiled in _LAW_FUNCTIONS.items():
                    if other.get(plain.__name__) is plain:
                        other[plain.__name__] = compiled
        return twin


def compiled_twins() -> dict:
    """plain law function -> its compiled twin, for every function ``law_function`` compiled."""
    with _LAW_LOCK:
        return dict(_LAW_FUNCTIONS)


__all__ = ["kernel", "rebound", "callback", "LAW_SOURCES_STAMP", "compiled_twins", "numba", "FALLBACK_MESSAGE", "CACHE", "OPTIONS", "law_function", "compiling", "cold", "can_cache",
           "COMPILE_LOG", "notice", "say_now_if_cold"]

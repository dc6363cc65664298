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
_FILE_DIGESTS: dict = {}
_DIGEST_LOCK = threading.Lock()


def _file_digest(path: str) -> str:
    with _DIGEST_LOCK:
        digest = _FILE_DIGESTS.get(path)
        if digest is None:
            try:
                digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()
            except OSError:
                digest = "missing"
            _FILE_DIGESTS[path] = digest
        return digest


def _python_function(value):
    """The plain Python function of ``value``: itself, a numba dispatcher's ``py_func`` or a
    cfunc's ``_pyfunc``; None for anything else."""
    if isinstance(value, types.FunctionType):
        return value
    for name in ("py_func", "_pyfunc"):
        inner = getattr(value, name, None) if not isinstance(value, types.ModuleType) else None
        if isinstance(inner, types.FunctionType):
            return inner
    return None


def _function_like(value) -> bool:
    return _python_function(value) is not None


def compiled_sources(fn) -> list[str]:
    """The source files of ``fn`` and of every function it reaches (by a global name, a module's
    attribute, a closure cell or a numba dispatcher's ``py_func``, transitively): the sources
    numba compiles into ``fn``'s machine code. Derived from the code, not listed by hand."""
    files: set[str] = set()
    seen: set[int] = set()
    stack = [fn]
    while stack:
        f = _python_function(stack.pop())
        if f is None or id(f) in seen:
            continue
        seen.add(id(f))
        files.add(f.__code__.co_filename)
        names: set[str] = set()
        codes = [f.__code__]
        while codes:
            code = codes.pop()
            names.update(code.co_names)
            codes.extend(c for c in code.co_consts if isinstance(c, types.CodeType))
        values = [f.__globals__[n] for n in names if n in f.__globals__]
        for cell in f.__closure__ or ():
            try:
                values.append(cell.cell_contents)
            except ValueError:  # an empty cell
                pass
        for value in values:
            if isinstance(value, types.ModuleType):
                members = vars(value)  # (not getattr: a module's __getattr__ may warn or import)
                stack.extend(a for a in (members.get(n) for n in names) if _function_like(a))
            elif _function_like(value):
                stack.append(value)
    return sorted(path for path in files if Path(path).is_file())


def sources_stamp(fn) -> str:
    """``LAW_SOURCES_STAMP`` (all of controllers/) and the contents of every file of
    :func:`compiled_sources`: what a compiled artifact of ``fn`` is keyed on."""
    digest = hashlib.sha256(LAW_SOURCES_STAMP.encode())
    for path in compiled_sources(fn):
        digest.update(Path(path).name.encode())
        digest.update(_file_digest(path).encode())
    return digest.hexdigest()


_CACHE_INTERNALS = None  # numba's caching module where it has the internals the stamp needs; False: not


def _kernel_cache_class(fn):
    """numba's FunctionCache for ``fn`` whose source stamp also covers :func:`sources_stamp` (numba's
    own locators, each extended; None if this numba lacks the internals: the caller then compiles in
    memory, never trusting the plain disk cache, which is keyed on ``fn``'s own file alone)."""
    global _CACHE_INTERNALS
    if _CACHE_INTERNALS is None:
        try:
            from numba.core import caching

            caching.CompileResultCacheImpl._locator_classes  # noqa: B018 - the internals used below
            caching.FunctionCache  # noqa: B018
            _CACHE_INTERNALS = caching
        except Exception:  # noqa: BLE001 - another numba
            _CACHE_INTERNALS = False
    caching = _CACHE_INTERNALS
    if not caching:
        return None
    stamp: list = []

    def stamped(base):
        def get_source_stamp(self):
            if not stamp:
                stamp.append(sources_stamp(fn))  # at the first load or save: every callee is defined by then
            return (base.get_source_stamp(self), stamp[0])
        return type(f"Sources{base.__name__}", (base,), {"get_source_stamp": get_source_stamp})

    impl = type("SourcesCacheImpl", (caching.CompileResultCacheImpl,),
                {"_locator_classes": [stamped(c) for c in caching.CompileResultCacheImpl._locator_classes]})
    return type("SourcesFunctionCache", (caching.FunctionCache,), {"_impl_class": impl})


def kernel(fn=None, *, inline: bool = False):
    """``numba.njit(**OPTIONS)(fn)``, its disk cache keyed on the law sources too.

    ``inline=True``: compiled into every kernel that calls it, at numba's level, as the law
    functions are (``law_function``): the same code and numbers without a call per evaluation
    (``controllers.kernels.inlined``)."""
    if fn is None:
        return lambda f: kernel(f, inline=inline)
    options = {**OPTIONS, "inline": "always"} if inline else OPTIONS
    cache = _kernel_cache_class(fn) if CACHE else None
    dispatcher = numba.njit(**{**options, "cache": False})(fn)  # in memory unless stamped below
    if cache is not None:
        dispatcher._cache = cache(fn)
    return dispatcher


def callback(signature):
    """``numba.cfunc(signature, cache=CACHE, error_model="numpy")``, its disk cache keyed on the
    law sources too (as numba's decorator builds it, with that cache)."""
    def build(fn):
        cache = _kernel_cache_class(fn) if CACHE else None
        if cache is None:  # in memory: the plain disk cache would be keyed on fn's own file alone
            return numba.cfunc(signature, cache=False, error_model="numpy")(fn)
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
            clone = rebound(fn, namespace)
            twin = numba.njit(inline="always", **{**OPTIONS, "cache": False})(clone)
            cache = _kernel_cache_class(clone) if CACHE else None
            if cache is not None:  # keyed on every source it reaches, as the kernels are
                twin._cache = cache(clone)
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

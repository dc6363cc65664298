"""Errors that the CLI reports as one line on stderr with exit status 2, and Ctrl-C, which it
reports as one line with exit status 130.

Ctrl-C: Python turns SIGINT into ``KeyboardInterrupt`` wherever the main thread happens to be, and
where that is a weakref callback, a finaliser or ``__del__`` the exception is printed as "Exception
ignored ..." and swallowed: the run would go on and exit 0. While :func:`interrupt_handling` is
active (the command line's run) the interrupt is also remembered, such swallowed reports are
silenced, and :func:`check_interrupt` (called by the output folder before it swaps a result into
place, and by the command line when a command returns) raises it again, so an interrupted command
never writes its result or exits 0.
"""
from __future__ import annotations

import contextlib
import signal
import sys
import threading


class MtbmjError(Exception):
    """Base class: a user-facing problem with a clear one-line cause."""


class ConfigError(MtbmjError, ValueError):
    """A configuration is missing a key, misspells one, or holds an invalid value; from Python, a bad
    argument's value too. A ``ValueError`` as well, as Python's own bad values are (``except ValueError``
    catches it). Every error whose cause is what the user gave, a value, a spec or a file's content, is one:
    ``ConfigError``, ``TerrainError`` (a terrain spec), ``RecordError`` and ``TelemetryError`` (a record or a
    ride file), ``MetricsError`` and ``EventsError`` (signals too short or not finite). Not so: ``RunError``
    (the model left its envelope), ``MissingExtra`` (the installation), ``RenderError`` (the machine's GL, or a run folder it cannot replay: left outside ``ValueError``, as most of its causes are the machine's),
    and the readers' and fits' own (``TouchError``, ``BobError``, ``BounceError``, the fit and
    reconstruction errors): well-formed data that does not hold what they look for."""


class FallbackWarning(UserWarning):
    """A faster path could not be used here (numba missing, a law without a compiled form, more
    contact patches than the compiled rolling callback holds); the run goes on along the Python
    path, with the same results. Not a failure: the command line shows it as a one-line note."""


class RunError(MtbmjError):
    """A run diverged (NaN, a MuJoCo warning) or could not be completed."""


class ConfigWarning(UserWarning):
    """A value far outside what any bike or sled has (most likely a unit mistake), or outside the
    range a model rests on: a configuration or bike key, or a command's numeric argument. The run
    proceeds; the command line prints each as one ``mtbmj: warning:`` line (``mtbmj.config``
    re-exports it)."""


@contextlib.contextmanager
def diverging(rig: str, until=None):
    """The block steps a run of ``rig``: a floating-point overflow, division by zero or invalid
    operation in numpy there means the run left the model's envelope, and ends it as one
    ``RunError`` line ("drop run diverged (overflow encountered in multiply)"; with ``until``, a
    function giving the time in s the stretch being stepped ends at, "drop run diverged before
    t = 0.1234 s: a numerical overflow or invalid value (overflow encountered in multiply)"). Only the
    stepping of a run is so guarded, never a fit or a reader, where a library may meet and
    handle such a value itself. numpy's error state is per thread (and context), so a guarded
    run leaves other threads alone; a ``RuntimeWarning`` a caller's own filter made an error in
    the block is reported the same way."""
    import numpy as np

    try:
        with np.errstate(over="raise", divide="raise", invalid="raise"):
            yield
    except (FloatingPointError, RuntimeWarning) as exc:
        if until is None:
            raise RunError(f"{rig} run diverged ({exc})") from None
        raise RunError(f"{rig} run diverged before t = {until():.4f} s: a numerical overflow or invalid value "
                       f"({exc})") from None


_interrupt = {"interrupted": False, "active": False}


def interrupted() -> bool:
    """Whether Ctrl-C came while :func:`interrupt_handling` was active."""
    return _interrupt["interrupted"]


def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` if Ctrl-C came while :func:`interrupt_handling` is active, even if the
    first one was swallowed (outside it, a caller's Ctrl-C is the caller's own affair)."""
    if _interrupt["active"] and _interrupt["interrupted"]:
        raise KeyboardInterrupt


def _on_sigint(signum, frame):
    _interrupt["interrupted"] = True
    raise KeyboardInterrupt


def _quiet_unraisable(previous):
    def hook(unraisable):
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            return  # remembered by the handler; reported once by the command line
        previous(unraisable)

    return hook


@contextlib.contextmanager
def interrupt_handling():
    """Within the block, SIGINT raises ``KeyboardInterrupt`` and is remembered; reports of it
    being ignored are not printed. The caller's handler and hook are restored afterwards (only
    in the main thread, where Python allows a signal handler to be set)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _interrupt["interrupted"], _interrupt["active"] = False, True
    previous_handler = signal.getsignal(signal.SIGINT)
    previous_hook = sys.unraisablehook
    signal.signal(signal.SIGINT, _on_sigint)
    sys.unraisablehook = _quiet_unraisable(previous_hook)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous_handler if previous_handler is not None else signal.SIG_DFL)
        sys.unraisablehook = previous_hook
        _interrupt["active"] = False  # ``interrupted()`` still tells, until the next command

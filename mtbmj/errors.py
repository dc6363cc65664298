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


class ConfigError(MtbmjError):
    """A configuration is missing a key, misspells one, or holds an invalid value."""


class FallbackWarning(UserWarning):
    """A faster path could not be used here (numba missing, a law without a compiled form, more
    contact patches than the compiled rolling callback holds); the run goes on along the Python
    path, with the same results. Not a failure: the command line shows it as a one-line note."""


class RunError(MtbmjError):
    """A run diverged (NaN, a MuJoCo warning) or could not be completed."""


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

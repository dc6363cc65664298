"""When the drop reaches for the compiled (numba) laws.

Loading numba and the cached laws into a fresh process takes about a second, three times a
default drop's whole run; the Python laws give the same trajectories and forces bit for bit, at
about 0.1 ms more per MuJoCo step. So a drop uses the compiled laws once they are in the process
(a sweep, the fast engine, an earlier long run: they cost nothing more to reach then), or when the
run is long enough to repay loading them, ``COMPILED_FROM_STEPS`` steps. Only the logged signals
can differ, in their last bits (about 1e-13 mm: the filter's compiled and numpy recursions round
differently).

A process that makes one drop after another (a notebook's loop over ``run_drop``) gets there
without being told: from its ``BACKGROUND_FROM_CALL``-th drop, a daemon thread loads numba and the
cached laws while the drops go on with the Python laws, and each drop after the load has finished
takes the compiled ones; from the ``WAIT_FROM_CALL``-th drop, one that finds the load still under
way waits for it (the Python laws beside a load run at half speed). A command that makes one drop (``mtbmj drop``) says so (``one_shot``) and
never starts that thread: its start-up stays what it was. ``MTBMJ_BACKGROUND_LOAD=0`` in the
environment turns the thread off. A process forked while that load is under way (a sweep's pool,
or the caller's own multiprocessing) first waits for it to finish: its child would otherwise wait
for ever on the import the load holds. Nothing here imports numba.
"""
from __future__ import annotations

import os
import sys
import threading

COMPILED_FROM_STEPS = 10_000  # MuJoCo steps (10 s at the default 1 ms) from which loading numba pays
BACKGROUND_FROM_CALL = 1  # the drop of a process from which the compiled laws load in the background
WAIT_FROM_CALL = 3  # from this drop on, a drop waits for a load under way instead of competing with it

_lock = threading.Lock()
_state = {"calls": 0, "one_shot": False, "thread": None}


def loaded() -> bool:
    """Whether the compiled laws can be taken now without waiting: numba is in the process and no
    background load of it is under way (a process forked from one with a load under way, a pool's
    worker, finds the thread stopped and numba as the fork left it)."""
    thread = _state["thread"]
    if thread is not None and thread.is_alive():
        return False
    return sys.modules.get("numba") is not None


def worth(steps: float) -> bool:
    """Whether work of about ``steps`` MuJoCo steps should run on the compiled laws."""
    return loaded() or steps >= COMPILED_FROM_STEPS


def expect_many() -> None:
    """For a caller about to make many runs in this process (a sweep's worker, a fit, a study):
    load numba and the compiled laws now, so that every run takes them (waiting for a background
    load under way). Without numba, nothing."""
    thread = _state["thread"]
    if thread is not None:
        thread.join()
    if not loaded():
        from mtbmj.controllers import compiled  # noqa: F401  (imports numba when it is installed)


def one_shot() -> None:
    """This process makes one drop (a command): no background load, which would only compete
    with it for the interpreter."""
    _state["one_shot"] = True


def drop_started() -> None:
    """A drop is starting (``run_drop``): from the ``BACKGROUND_FROM_CALL``-th, load the
    compiled laws in a daemon thread unless they are here, the process said it makes one drop, or
    the environment says not to."""
    with _lock:
        _state["calls"] += 1
        thread = _state["thread"]
        if thread is not None and _state["calls"] >= WAIT_FROM_CALL:
            thread.join()  # the rest of the load costs less than a drop on the Python laws beside it
        if (_state["thread"] is not None or _state["one_shot"] or _state["calls"] < BACKGROUND_FROM_CALL
                or sys.modules.get("numba") is not None or os.environ.get("MTBMJ_BACKGROUND_LOAD", "1") == "0"):
            return
        thread = threading.Thread(target=_load, name="mtbmj-load-compiled-laws", daemon=True)
        _state["thread"] = thread
        if not _state.get("fork_hook"):
            # A process forked while the load holds the import lock (a sweep's pool, or the
            # caller's own multiprocessing) would wait for that lock for ever in its child: the
            # thread that holds it is not copied. So a fork first lets the load finish. Hooks run
            # in the reverse order of their registration, and logging's takes its module lock,
            # which the load needs (numba logs): logging registers first, so ours runs before it.
            import logging  # noqa: F401  (registers logging's own fork hook before ours)

            os.register_at_fork(before=_finish_load_before_fork)
            _state["fork_hook"] = True
        thread.start()


def _finish_load_before_fork() -> None:
    """Wait for a load under way, however long: a cold first compile holds the import of
    ``controllers.compiled`` for tens of seconds, and a child forked meanwhile would never get it."""
    thread = _state["thread"]
    if thread is not None and thread.is_alive() and thread is not threading.current_thread():
        thread.join()


def _load() -> None:
    """The background load: numba, the compiled laws and the logger's filter kernel, each called
    once on a tiny input so that their cached machine code is in memory. A failure (numba missing
    or broken) leaves the drops on the Python laws, which say so as they always have."""
    try:
        import numpy as np

        from mtbmj.controllers import compiled

        if compiled.available():
            compiled.dispatcher()
            w = np.zeros((1, 4), complex)
            compiled.modal_filter(np.ones(4, complex), np.zeros(4, complex), np.zeros(4, complex),
                                  np.zeros(4, complex), w, np.zeros((1, 2)), np.empty((1, 2)))
    except Exception:  # noqa: BLE001 - the Python laws stay; the drop path reports numba's absence itself
        pass


__all__ = ["COMPILED_FROM_STEPS", "BACKGROUND_FROM_CALL", "loaded", "worth", "expect_many", "one_shot",
           "drop_started"]

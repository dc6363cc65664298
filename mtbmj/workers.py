"""Worker processes that die with the process that started them.

Every command that runs work in parallel (study, validate, sweep, sensitivity, fit) makes its
pool with :func:`process_pool`. Each worker first arranges to exit when its parent does, even
when the parent is killed with SIGKILL and can clean nothing up: on Linux the kernel's
parent-death signal (``prctl(PR_SET_PDEATHSIG, SIGKILL)``), elsewhere a watchdog thread that
notices the worker has been re-parented. So no orphan keeps computing, holding memory and the
caller's pipes. Ctrl-C is unchanged: the workers get SIGINT with the rest of the process group.
"""
from __future__ import annotations

import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Callable

_PR_SET_PDEATHSIG = 1


def exit_with_parent(parent: int) -> None:
    """Make this process exit when the process ``parent`` dies (call it first in a worker)."""
    import signal

    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0:
            if os.getppid() != parent:  # the parent died before prctl took effect
                os._exit(1)
            return
    except (OSError, AttributeError):
        pass

    def watch():
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="mtbmj-exit-with-parent", daemon=True).start()


def _start_worker(parent: int, initializer: Callable | None, initargs: tuple) -> None:
    exit_with_parent(parent)
    if initializer is not None:
        initializer(*initargs)


def process_pool(workers: int, initializer: Callable | None = None, initargs: tuple = (),
                 mp_context=None) -> ProcessPoolExecutor:
    """A ``ProcessPoolExecutor`` of ``workers`` processes that exit with this one; ``initializer``
    (a top-level function) runs in each worker after that is arranged.

    Call it from the main thread: the parent-death signal follows the thread that starts the
    workers."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=mp_context, initializer=_start_worker,
                               initargs=(os.getpid(), initializer, initargs))

"""Worker processes that die with the process that started them.

Every command that runs work in parallel (study, validate, sweep, sensitivity, fit) makes its
pool with :func:`process_pool`. Each worker first arranges to exit when its parent does, even
when the parent is killed with SIGKILL and can clean nothing up: on Linux the kernel's
parent-death signal (``prctl(PR_SET_PDEATHSIG, SIGKILL)``), elsewhere a watchdog thread that
notices the worker has been re-parented. So no orphan keeps computing, holding memory and the
caller's pipes. Workers ignore SIGINT, which a terminal's Ctrl-C sends to the whole process group:
the parent alone reports the interrupt and ends them (:meth:`Pool.terminate`, which leaving a
``with process_pool(...)`` block on an exception does), so no worker prints a traceback of its own.
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


BLAS_THREADS_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> None:
    """This process's linear algebra on one thread, for the rest of its life: the BLAS libraries
    loaded now (``threadpoolctl``) and those loaded later (their environment variables, where the
    user set none). Only for a process of the package's own (a pool's worker, the ``mtbmj``
    executable), never behind a caller: a pool already keeps every core busy, and BLAS threads
    beside it spin against the other processes (measured on two cores with another process busy: a
    122 x 122 eigh of the reconstruction's bound took 0.22 s with OpenBLAS's threads, 1 ms with one;
    on a quiet machine no difference was measured)."""
    for name in BLAS_THREADS_ENV:
        os.environ.setdefault(name, "1")
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # a core dependency; without it only the libraries loaded from here on are held
        return
    threadpool_limits(limits=1, user_api="blas")


def _start_worker(parent: int, initializer: Callable | None, initargs: tuple) -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to report
    exit_with_parent(parent)
    one_blas_thread()  # the worker is the pool's: one core each
    if initializer is not None:
        initializer(*initargs)


class Pool(ProcessPoolExecutor):
    """A ``ProcessPoolExecutor`` whose workers exit with this process and ignore Ctrl-C. Leaving
    its ``with`` block on an exception (an interrupt, an error) ends the workers at once instead
    of waiting for the tasks they are running."""

    @property
    def workers(self) -> int:
        """How many processes the pool runs at once."""
        return self._max_workers

    def terminate(self) -> None:
        """Kill the workers and drop the queued tasks; returns without waiting for them. Every
        unfinished future gets ``BrokenProcessPool`` now; the executor's own work items get
        stand-in futures, so what its manager thread does with them afterwards touches no future
        of the caller's (Python 3.11's raises ``InvalidStateError`` marking a future broken that
        a ``map`` has cancelled meanwhile)."""
        from concurrent.futures import Future
        from concurrent.futures.process import BrokenProcessPool

        for item in list((getattr(self, "_pending_work_items", None) or {}).values()):
            future = getattr(item, "future", None)
            if future is None:
                continue
            if not future.done():
                try:
                    future.set_exception(BrokenProcessPool("the pool was terminated"))
                except Exception:  # noqa: BLE001 - cancelled or finished meanwhile
                    pass
            item.future = Future()
        for process in list((getattr(self, "_processes", None) or {}).values()):
            try:
                process.kill()
            except (OSError, ValueError, AttributeError):
                pass
        self.shutdown(wait=False)

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None:
            self.terminate()
            return False
        return super().__exit__(exc_type, exc, tb)


def process_pool(workers: int, initializer: Callable | None = None, initargs: tuple = (),
                 mp_context=None) -> Pool:
    """A :class:`Pool` of ``workers`` processes that exit with this one; ``initializer``
    (a top-level function) runs in each worker after that is arranged. The only way the package
    makes a process pool (``tests/test_ownership.py`` fails on any other).

    Call it from the main thread: the parent-death signal follows the thread that starts the
    workers."""
    if workers < 1:
        raise ValueError(f"workers: must be at least 1, got {workers}")
    return Pool(max_workers=workers, mp_context=mp_context, initializer=_start_worker,
                initargs=(os.getpid(), initializer, initargs))

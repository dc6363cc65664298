"""A process forked while another of its threads holds a compiled callback registry's lock (the
garbage collector runs a callback's finalizer, which frees its slot, in whatever thread it runs:
a sweep's table-library import, the test runner's I/O thread) must not hand its child a lock no
thread will ever release: a sweep's worker waited for ever on its first claim (seen twice in this
suite). Made deterministic here: a thread holds the lock while the main thread forks."""
import importlib
import os
import threading
import time

import pytest

REGISTRIES = ["mtbmj.controllers.compiled", "mtbmj.rolling.callback_compiled", "mtbmj.bike.callback_compiled"]


@pytest.mark.parametrize("module", REGISTRIES)
def test_a_fork_while_another_thread_holds_the_registry_gives_a_child_that_can_claim(module):
    pytest.importorskip("numba")
    registry = importlib.import_module(module).REGISTRY
    held, done = threading.Event(), threading.Event()

    def hold():
        with registry.lock:
            held.set()
            time.sleep(0.3)
        done.set()

    thread = threading.Thread(target=hold)
    thread.start()
    held.wait()
    pid = os.fork()
    if pid == 0:  # the child: the registry's lock must be free here
        got = registry.lock.acquire(timeout=5)
        os._exit(0 if got else 3)
    _, status = os.waitpid(pid, 0)
    thread.join()
    assert done.is_set()
    assert os.waitstatus_to_exitcode(status) == 0, "the child found the registry locked for ever"
    assert registry.lock.acquire(timeout=5)  # and the parent's lock is free again
    registry.lock.release()

"""A process that drops again and again reaches the compiled laws on its own (issue 27): from its
first ``run_drop`` a daemon thread loads numba and the cached laws, and from the third drop on
every drop runs on them; a command (one drop) never starts that thread; the environment can turn
it off. Each case runs in a fresh interpreter, where numba is not yet loaded. Speed is measured
in benchmarks/native_loop.py, not here."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

LOOP = """
import json, sys, threading
import mtbmj
kinds = [mtbmj.run_drop("S12", duration=0.3).trace.info["callback"] for _ in range(5)]
print(json.dumps({"kinds": kinds, "numba": "numba" in sys.modules,
                  "threads": sorted(t.name for t in threading.enumerate())}))
"""

COMMAND = """
import json, sys, threading
from mtbmj.cli import main
status = main(["drop", "S12", "--duration", "0.3", "--quiet", "--no-figure", "--out", sys.argv[1]])
print(json.dumps({"status": status, "numba": "numba" in sys.modules,
                  "threads": sorted(t.name for t in threading.enumerate())}))
"""


def run(code: str, *args, **env) -> dict:
    done = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True,
                          timeout=600, env={**os.environ, **env}, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_loop_of_drops_reaches_the_compiled_laws_from_its_third_drop():
    pytest.importorskip("numba")
    got = run(LOOP)
    assert got["kinds"][2:] == ["compiled"] * 3, got
    assert got["numba"]


def test_the_first_drops_of_a_loop_do_not_wait_for_the_load():
    """A drop that finds numba not yet loaded takes the Python laws (it does not block on the
    load): the first one of a fresh process always does."""
    pytest.importorskip("numba")
    assert run(LOOP)["kinds"][0] == "python"


def test_a_command_never_loads_in_the_background(tmp_path):
    got = run(COMMAND, tmp_path / "out")
    assert got["status"] == 0 and not got["numba"]
    assert "mtbmj-load-compiled-laws" not in got["threads"]


def test_the_environment_turns_the_background_load_off():
    got = run(LOOP, MTBMJ_BACKGROUND_LOAD="0")
    assert got["kinds"] == ["python"] * 5 and not got["numba"]


FORK = """
import json, multiprocessing, sys, threading
import mtbmj

def child(queue):
    from mtbmj.controllers import compiled  # the import the background load may be holding
    queue.put(compiled.available())

mtbmj.run_drop("S12", duration=0.05)  # starts the background load, then returns at once
loading = any(t.name == "mtbmj-load-compiled-laws" and t.is_alive() for t in threading.enumerate())
context = multiprocessing.get_context("fork")
queue = context.Queue()
process = context.Process(target=child, args=(queue,))
process.start()
process.join(120)
finished = process.exitcode == 0
if not finished:
    process.kill()
print(json.dumps({"loading_at_fork": loading, "child_finished": finished,
                  "child_has_laws": queue.get(timeout=1) if finished else None}))
"""


@pytest.mark.skipif(sys.platform != "linux", reason="fork start method")
def test_a_process_forked_during_the_background_load_does_not_hang():
    """A child forked while the load held the import lock waited for ever on it (a sweep's pool
    after a drop hung the test suite): a fork now lets the load finish first."""
    out = run(FORK)
    assert out["child_finished"] and out["child_has_laws"] in (True, False), out

"""Ctrl-C and kills (issue 21): an interrupted command exits 130 with the one line
``mtbmj: interrupted`` whatever it was doing, its workers print nothing and do not outlive it,
and its ``--out`` holds the old result or the new one."""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
import weakref
from pathlib import Path

import numpy as np
import pytest

from mtbmj import output
from mtbmj.cli.common import Parser, run
from helpers import gone  # waits for processes to end, kills what outlives the wait

CLI = [sys.executable, "-m", "mtbmj.cli"]


def _parser(func) -> Parser:
    parser = Parser(prog="mtbmj")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    sub.add_parser("work").set_defaults(func=func)
    return parser


def test_an_interrupt_swallowed_in_a_weakref_callback_still_ends_the_command(capfd):
    """SIGINT landing inside a weakref callback: Python reports it as "Exception ignored" and goes
    on. The command must still exit 130 with one line, and never write or exit 0."""
    done = []

    class Thing:
        pass

    def work(args):
        thing = Thing()
        weakref.finalize(thing, lambda: (os.kill(os.getpid(), signal.SIGINT), time.sleep(0.05)))
        del thing  # the callback runs here, the interrupt raised inside it and swallowed
        done.append("went on")
        return 0

    previous, hook = signal.getsignal(signal.SIGINT), sys.unraisablehook
    status = run(_parser(work), ["work"])
    assert signal.getsignal(signal.SIGINT) is previous and sys.unraisablehook is hook  # the caller's, restored
    err = capfd.readouterr().err
    assert done == ["went on"]  # it was swallowed there: the command's end caught it
    assert status == 130 and err == "mtbmj: interrupted\n", err


def test_an_interrupt_before_the_swap_keeps_the_old_result(tmp_path, capfd):
    out = tmp_path / "o"
    output.write_atomically(out, {"a.csv": b"old\n"})

    class Thing:
        pass

    def work(args):
        thing = Thing()
        weakref.finalize(thing, lambda: (os.kill(os.getpid(), signal.SIGINT), time.sleep(0.05)))
        del thing
        output.write_atomically(out, {"a.csv": b"new\n"})
        return 0

    assert run(_parser(work), ["work"]) == 130
    assert capfd.readouterr().err == "mtbmj: interrupted\n"
    assert (out / "a.csv").read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o"]


def test_pool_workers_ignore_the_terminals_sigint():
    from mtbmj.workers import process_pool

    with process_pool(1) as pool:
        handler = pool.submit(_sigint_handler).result()
    assert handler == int(signal.SIG_IGN)


def _sigint_handler():
    handler = signal.getsignal(signal.SIGINT)
    return int(handler) if isinstance(handler, (int, signal.Handlers)) else -1


def _children(pid: int) -> list[int]:
    try:
        return [int(p) for p in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except FileNotFoundError:
        return []


def _state(pid: int) -> str | None:
    """The process's state letter (``Z``: exited, not yet reaped), ``None`` when it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().split(")")[-1].split()[0]
    except FileNotFoundError:
        return None


def _start(argv, cwd):
    """The command in a session of its own, as in a terminal: Ctrl-C is SIGINT to the group."""
    return subprocess.Popen(CLI + argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, env=dict(os.environ, MUJOCO_GL="disable"))


def _with_workers(proc, count=2, timeout=60.0) -> list[int]:
    end = time.monotonic() + timeout
    children = []
    while len(children) < count and time.monotonic() < end and proc.poll() is None:
        children = _children(proc.pid)
        time.sleep(0.02)
    return children


AIR = ["air-study", "--duration", "0.6", "--workers", "2", "--quiet"]


@pytest.mark.parametrize("how", ["SIGKILL", "SIGINT"])
def test_air_study_killed_or_interrupted_leaves_no_orphan_and_the_old_result(tmp_path, how):
    out = tmp_path / "as"
    output.write_atomically(out, {"air_study.csv": b"the old result\n"})
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".lock"}
    proc = _start(AIR + ["--out", str(out)], tmp_path)
    children = _with_workers(proc)
    assert len(children) >= 2, "air-study did not start its workers"
    time.sleep(0.3)
    if how == "SIGKILL":
        proc.send_signal(signal.SIGKILL)
    else:
        os.killpg(proc.pid, signal.SIGINT)  # the terminal's Ctrl-C reaches the whole group
    stdout, stderr = proc.communicate(timeout=60)
    assert gone(children), f"workers outlived air-study ({how})"
    if how == "SIGINT":
        assert proc.returncode == 130 and stderr == "mtbmj: interrupted\n", (proc.returncode, stderr)
    else:
        assert proc.returncode == -signal.SIGKILL
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".lock"}
    assert after == before  # the old result, whole
    assert sorted(p.name for p in tmp_path.iterdir()) in (["as"], ["as"] + [p.name for p in tmp_path.iterdir()
                                                                             if p.name.startswith(".as.new-")])
    output.write_atomically(out, {"x": b"1"})  # the next write clears what a killed run left beside it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["as"]


WHOLE_VALIDATION = {"fig10_amplitude_errors.png", "validation_metrics.csv", "validation_summary.json",
                    "validation_report.html"}


def ctrl_c_trials(tmp_path, trials: int, seed: int, argv) -> list[tuple[float, int, str]]:
    """``trials`` runs of ``mtbmj argv``, each interrupted (SIGINT to its process group) at a
    seeded random moment between its start and its typical end. Returns (moment, status, stderr)."""
    rng = np.random.default_rng(seed)
    wholes = []
    for _ in range(2):  # the second run is the warm one the trials repeat
        start = time.monotonic()
        first = subprocess.run(CLI + argv + ["--out", str(tmp_path / "timing")], cwd=tmp_path, capture_output=True,
                               text=True, env=dict(os.environ, MUJOCO_GL="disable"))
        assert first.returncode == 0, first.stderr
        wholes.append(time.monotonic() - start)
    whole = min(wholes)
    results = []
    trial = 0
    while len(results) < trials:
        trial += 1
        assert trial <= 3 * trials, "the command kept finishing before its interrupt"
        moment = float(rng.uniform(0.05, 0.9 * whole))
        out = tmp_path / f"t{trial}"
        proc = _start(argv + ["--out", str(out)], tmp_path)
        time.sleep(moment)
        children = _children(proc.pid)
        if _state(proc.pid) in ("Z", None):  # it had already finished: this moment interrupts nothing
            proc.communicate(timeout=120)
            continue
        os.killpg(proc.pid, signal.SIGINT)
        _, stderr = proc.communicate(timeout=120)
        assert gone(children), f"trial {trial}: workers outlived the interrupt"
        results.append((moment, proc.returncode, stderr))
        if out.exists():  # nothing half-written: no result, or the whole one (interrupted after its swap)
            assert output.foreign_entry(out) is None
            names = set(os.listdir(out)) - set(output.BOOKKEEPING)
            assert not names or WHOLE_VALIDATION <= names, sorted(names)
    return results


@pytest.mark.slow
def test_25_ctrl_c_trials_on_validate(tmp_path):
    """25 interrupts at random moments of ``mtbmj validate`` on four configurations in two
    workers: every one exits 130 with exactly one line (none 0, none with a traceback)."""
    argv = ["validate", "example", "--presets", "S1,S4,S9,S12", "--workers", "2", "--quiet"]
    results = ctrl_c_trials(tmp_path, 25, 20261125, argv)
    bad = [(round(m, 3), s, e) for m, s, e in results if s != 130 or e != "mtbmj: interrupted\n"]
    assert bad == [], bad


def _slow(x):
    time.sleep(0.3)
    return x


def test_terminating_a_pool_mid_map_ends_its_workers_and_raises_nothing_in_its_threads(monkeypatch):
    """A ``map`` left by an exception (its remaining futures cancelled) and the pool terminated:
    the workers are gone at once, every future is done, and the executor's manager thread
    raises nothing (Python 3.11's would, marking a cancelled future broken)."""
    import threading

    from mtbmj.workers import process_pool

    errors = []
    monkeypatch.setattr(threading, "excepthook", lambda args: errors.append(args.exc_value))
    for _ in range(3):
        pool = process_pool(2)
        futures = [pool.submit(_slow, i) for i in range(12)]
        mapped = pool.map(_slow, range(12))
        next(mapped)
        workers = list(pool._processes)
        mapped.close()  # cancels what the map had not started
        pool.terminate()
        assert gone(workers, timeout=5.0)
        time.sleep(0.2)
        assert all(f.done() for f in futures)
    assert errors == []

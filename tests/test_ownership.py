"""``--out`` never loses what is not mtbmj's (issue 21): a folder is replaced only when its record
names every entry in it, every writer takes the folder's lock, every command can replace its own
earlier result, and an ``--out`` that holds one of the command's inputs is refused.

The folders here are made by hand, the way a user's project folder looks, not by the code under
test; every refusal is checked for its one line, its exit status 2 and for every byte of the
user's files being where it was."""
from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from mtbmj import output
from mtbmj.cli import main
from mtbmj.errors import MtbmjError
from helpers import one_line as refused  # exit 2, one line naming every needle

ROOT = Path(__file__).resolve().parents[1]


def snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


# the names the old rule took for an mtbmj result: each alone made a folder of the user's replaceable
LOOKALIKES = {
    "manifest.json": b'{"name": "my-web-app"}\n',
    ".lock": b"",
    "journal": None,  # a folder
    "fit.json": b'{"rate": 1}\n',
    "sweep.json": b"{}\n",
}


@pytest.mark.parametrize("name", sorted(LOOKALIKES))
@pytest.mark.parametrize("command", [
    ["drop", "S12", "--duration", "0.05", "--quiet"],
    ["fit", "spring", "example"],
    ["sag", "S12", "--load-kg", "53", "--sag-percent", "25"],
])
def test_a_folder_of_the_users_is_never_replaced_whatever_its_file_names(tmp_path, capsys, name, command):
    proj = tmp_path / "proj"
    proj.mkdir()
    content = LOOKALIKES[name]
    if content is None:
        (proj / name).mkdir()
        (proj / name / "notes.md").write_text("mine\n")
    else:
        (proj / name).write_bytes(content)
    (proj / "src.py").write_text("precious = True\n")
    before = snapshot(proj)
    refused(capsys, command + ["--out", proj], "mtbmj did not write", str(proj))
    assert snapshot(proj) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["proj"]  # no staging folder left beside it


def test_the_python_api_refuses_the_same_folder(tmp_path):
    from mtbmj.drop.run import run_drop

    proj = tmp_path / "proj"
    proj.mkdir()
    (proj / "manifest.json").write_text('{"name": "my-web-app"}\n')
    (proj / "src.py").write_text("precious = True\n")
    before = snapshot(proj)
    result = run_drop("S12", duration=0.05)
    with pytest.raises(MtbmjError, match="src.py|manifest.json"):
        result.write(proj)
    assert snapshot(proj) == before


def test_a_file_put_into_a_result_is_never_removed(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["drop", "S1", "--duration", "0.05", "--quiet", "--out", str(out)]) == 0
    record = json.loads((out / output.RECORD).read_text())
    assert record["format"] == output.RECORD_FORMAT and record["command"] == "drop"
    assert sorted(record["files"]) == sorted(p.name for p in out.iterdir() if p.name != output.RECORD)
    (out / "my_notes.txt").write_text("S1 looks soft\n")
    refused(capsys, ["drop", "S12", "--duration", "0.05", "--quiet", "--out", out], "my_notes.txt")
    assert (out / "my_notes.txt").read_text() == "S1 looks soft\n"
    # a forged record cannot name a file into mtbmj's: a record of another format counts as none
    (out / output.RECORD).write_text(json.dumps({"files": ["my_notes.txt"]}))
    refused(capsys, ["drop", "S12", "--duration", "0.05", "--quiet", "--out", out], "mtbmj did not write")
    assert (out / "my_notes.txt").read_text() == "S1 looks soft\n"


def test_a_file_appearing_during_the_run_is_kept(tmp_path, monkeypatch):
    """Someone saves a file into the folder while the run computes: the swap is refused and the
    file stays (the folder is checked again just before the swap)."""
    out = tmp_path / "run"
    output.write_atomically(out, {"a.csv": b"old\n"})
    real = output._swap_into_place

    def late(stage, target):
        raise AssertionError("swapped although a foreign file appeared")

    with pytest.raises(MtbmjError, match="late.txt"):
        with output.staged_folder(out) as stage:
            output.write_file(stage / "a.csv", b"new\n")
            (out / "late.txt").write_text("saved meanwhile\n")
            monkeypatch.setattr(output, "_swap_into_place", late)
    monkeypatch.setattr(output, "_swap_into_place", real)
    assert (out / "late.txt").read_text() == "saved meanwhile\n" and (out / "a.csv").read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


@pytest.mark.parametrize("command", [
    ["sag", "S12", "--load-kg", "53", "--sag-percent", "25"],
    ["sag", "air120", "--load-kg", "60", "--sag-percent", "25"],
    ["fit", "spring", "example"],
    ["drop", "S12", "--duration", "0.05", "--quiet"],
])
def test_every_command_replaces_its_own_result(tmp_path, command):
    out = tmp_path / "o"
    assert main(command + ["--out", str(out)]) == 0
    first = snapshot(out)
    assert main(command + ["--out", str(out)]) == 0
    assert set(snapshot(out)) == set(first)
    assert output.foreign_entry(out) is None


def test_air_study_replaces_its_own_result_and_checks_out_before_the_work(tmp_path, capsys):
    out = tmp_path / "as"
    argv = ["air-study", "--duration", "0.02", "--workers", "1", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    assert main(argv) == 0  # its default folder twice, as a user runs it
    assert {"air_study.csv", "air_spring_curves.png", output.RECORD} <= set(os.listdir(out))
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("years of work\n")
    start = time.perf_counter()
    refused(capsys, ["air-study", "--quiet", "--out", mine], "thesis.tex")
    assert time.perf_counter() - start < 3.0  # refused before 18 drops of 1.5 s, not after
    assert snapshot(mine) == {"thesis.tex": b"years of work\n"}


def test_an_out_holding_an_input_is_refused(tmp_path, capsys):
    prev = tmp_path / "prev"
    assert main(["drop", "S12", "--duration", "0.3", "--quiet", "--out", str(prev)]) == 0
    before = snapshot(prev)
    refused(capsys, ["validate", prev / "timeseries.csv", "S12", "--quiet", "--out", prev],
            "timeseries.csv", "reads")
    refused(capsys, ["drop", prev / "config.toml", "--quiet", "--out", prev], "config.toml", "reads")
    refused(capsys, ["telemetry", "example", "--compare", prev, "--out", prev], "reads")
    assert snapshot(prev) == before


def test_an_out_name_with_a_line_break_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    refused(capsys, ["drop", "S12", "--duration", "0.05", "--quiet", "--out", "x\ny"], "--out", "line break")
    refused(capsys, ["synth", "spring", "S12", "--out", "a\rb.csv"], "--out")
    assert os.listdir(tmp_path) == []


# --- one lock for every writer --------------------------------------------------------------------

SWEEP = ["sweep", "S12", "--vary", "fork.spring.preload_N=150:300:400", "--engine", "ode", "--duration", "0.3",
         "--workers", "1", "--quiet"]


def test_a_drop_into_a_running_sweeps_folder_is_refused_naming_the_sweep(tmp_path, capsys):
    out = tmp_path / "sw"
    code = "import sys; from mtbmj.cli import main; sys.exit(main(sys.argv[1:]))"
    sweep = subprocess.Popen([sys.executable, "-c", code, *SWEEP, "--out", str(out)],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        end = time.monotonic() + 60
        while not (out / "journal").is_dir() and time.monotonic() < end and sweep.poll() is None:
            time.sleep(0.05)
        assert (out / "journal").is_dir(), "the sweep did not start its journal"
        # the journal's committed parts (a part being written by the running sweep is a temporary
        # .part-*.tmp that the sweep renames when done: it is the sweep's own work, not the drop's)
        committed = lambda: {k: v for k, v in snapshot(out / "journal").items()  # noqa: E731
                             if not (Path(k).name.startswith(".") and k.endswith(".tmp"))}
        journal = committed()
        err = refused(capsys, ["drop", "S12", "--duration", "0.05", "--quiet", "--out", out],
                      "another mtbmj run", "sweep", f"process {sweep.pid}")
        assert "sweep" in err
        now = committed()
        assert all(now.get(k) == v for k, v in journal.items())  # the sweep's journal untouched
        assert not (out / "summary.json").exists()
        refused(capsys, SWEEP + ["--out", out], "another mtbmj run")
    finally:
        sweep.kill()
        sweep.wait()
        sweep.stderr.close()
    # the sweep is gone: its folder (a journal to resume) can be taken again
    assert main(SWEEP[:3] + ["fork.spring.preload_N=150:300:2", *SWEEP[4:], "--resume", "--out", str(out)]) == 0


HOLD = textwrap.dedent("""
    import sys, time
    from mtbmj import output
    with output.claim(sys.argv[1], "fit drop"):
        print("held", flush=True)
        time.sleep(60)
""")


@pytest.mark.parametrize("command", [
    ["drop", "S12", "--duration", "0.05", "--quiet"],
    ["fit", "spring", "example"],
    ["sag", "S12", "--load-kg", "53", "--sag-percent", "25"],
    ["roll", "flat", "--speed", "3", "--duration", "0.1", "--quiet"],
    ["study", "--presets", "S1", "--quiet"],
    ["sweep", "S12", "--vary", "fork.spring.preload_N=150:300:2", "--duration", "0.05", "--quiet"],
])
def test_every_writer_takes_the_lock(tmp_path, capsys, command):
    out = tmp_path / "o"
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        start = time.perf_counter()
        refused(capsys, command + ["--out", out], "another mtbmj run (mtbmj fit drop", f"process {holder.pid}")
        assert time.perf_counter() - start < 3.0  # at once, before the work
        assert sorted(os.listdir(out)) == [".lock"]
    finally:
        holder.kill()
        holder.wait()
        holder.stdout.close()


def test_nested_claims_in_one_process_share_the_lock(tmp_path):
    out = tmp_path / "o"
    with output.claim(out, "drop") as outer:
        with output.claim(out) as inner:
            assert inner is outer
        output.write_atomically(out, {"a.csv": b"1\n"})  # the staged write reuses the claim
        assert (out / ".lock").read_text().startswith("mtbmj drop (process")
    assert output.read_record(out)["files"] == [".lock", "a.csv"]


def test_a_refused_or_failed_run_leaves_no_folder_it_made(tmp_path, capsys):
    out = tmp_path / "new" / "deeper"
    refused(capsys, ["drop", "S12", "--set", "sled.body_mass_kg=-1", "--quiet", "--out", out], "sled.body_mass_kg")
    assert os.listdir(tmp_path) == []


# --- every pool from mtbmj.workers -------------------------------------------------------------

POOL_MAKERS = {"ProcessPoolExecutor", "Pool", "Process", "ThreadPoolExecutor"}


def test_every_process_pool_comes_from_mtbmj_workers():
    """The package makes processes only through ``mtbmj.workers.process_pool`` (workers that die
    with their parent and leave Ctrl-C to it): any other pool or process in the source fails."""
    offenders = []
    for folder in ("mtbmj", "controllers", "validation", "mjcf"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path == ROOT / "mtbmj" / "workers.py":
                continue
            tree = ast.parse(path.read_text(), str(path))
            for node in ast.walk(tree):
                name = None
                if isinstance(node, ast.Call):
                    func = node.func
                    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
                elif isinstance(node, ast.ImportFrom) and node.module in ("concurrent.futures", "multiprocessing",
                                                                           "multiprocessing.pool"):
                    name = next((a.name for a in node.names if a.name in POOL_MAKERS - {"ThreadPoolExecutor"}), None)
                if name in POOL_MAKERS - {"ThreadPoolExecutor"}:
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno} {name}")
    assert offenders == []


def test_the_pool_finder_finds_a_plain_pool(tmp_path):
    """The scan above is not blind: the source air-study had before this issue is caught."""
    source = "from concurrent.futures import ProcessPoolExecutor\nwith ProcessPoolExecutor(max_workers=2) as p:\n    pass\n"
    names = [n.func.id for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Call) and hasattr(n.func, "id")]
    assert "ProcessPoolExecutor" in names and "ProcessPoolExecutor" in POOL_MAKERS


def test_a_result_of_an_older_mtbmj_is_refused_with_a_hint(tmp_path, capsys):
    """A folder an mtbmj before output records wrote (no record) is refused like any other, and
    the line says what it is; a user's own manifest.json gets no such hint."""
    old = tmp_path / "old"
    assert main(["drop", "S12", "--duration", "0.05", "--quiet", "--out", str(old)]) == 0
    (old / output.RECORD).unlink()
    (old / ".lock").unlink()
    before = snapshot(old)
    refused(capsys, ["drop", "S12", "--duration", "0.05", "--quiet", "--out", old], "older than its output records")
    assert snapshot(old) == before
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "manifest.json").write_text('{"name": "my-web-app", "versions": {"node": "20"}}\n')
    err = refused(capsys, ["drop", "S12", "--duration", "0.05", "--quiet", "--out", mine], "manifest.json")
    assert "older than its output records" not in err


@pytest.mark.parametrize("target", ["a folder of the user's", "an empty folder", "nowhere"])
def test_a_symbolic_link_as_out_is_refused_before_the_work_and_nothing_is_left_behind(tmp_path, capsys, target):
    """A careless ``--out link`` (to a project, to an empty folder, dangling): one line at once,
    and the folder it points to is not touched (no lock file left in it)."""
    folder = tmp_path / "folder"
    if target != "nowhere":
        folder.mkdir()
        if target == "a folder of the user's":
            (folder / "a.txt").write_text("keep\n")
    (tmp_path / "link").symlink_to(folder)
    before = snapshot(folder) if folder.exists() else None
    start = time.perf_counter()
    refused(capsys, ["drop", "S12", "--quiet", "--out", tmp_path / "link"], "symbolic link")
    assert time.perf_counter() - start < 3.0
    assert (snapshot(folder) if folder.exists() else None) == before


def test_a_pools_workers_do_linear_algebra_on_one_thread_and_the_caller_keeps_its_own():
    """The pool's workers are the package's: BLAS on one thread each (N workers on N cores; threads
    beside them spin against the other workers). The caller's own process keeps its threads and its
    environment. Run in a fresh interpreter without the test processes' own setting."""
    script = textwrap.dedent("""
        import json, os
        import numpy
        from threadpoolctl import threadpool_info
        from mtbmj.workers import process_pool

        def blas():
            return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

        def in_worker():
            return blas(), os.environ.get("OPENBLAS_NUM_THREADS")

        if __name__ == "__main__":
            before, env = blas(), dict(os.environ)
            with process_pool(1) as pool:
                worker = pool.submit(in_worker).result()
            print(json.dumps({"before": before, "after": blas(), "worker": worker[0], "worker_env": worker[1],
                              "env_kept": env == dict(os.environ)}))
    """)
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                            "MKL_NUM_THREADS")}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["before"] and out["before"] == out["after"] and out["env_kept"]
    assert out["worker"] == [1] * len(out["worker"]) and out["worker"]

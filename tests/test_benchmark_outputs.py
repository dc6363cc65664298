"""A benchmark writes its results where its ``--out`` says, and with no ``--out`` to a scratch file
outside the repository, never over a committed file (benchmarks/results/, mtbmj/data/...).

Every script of benchmarks/ with a command-line parser lists ``--out`` in its ``--help``;
``_bench.write_json`` with no path writes under the system's temporary folder and nothing under
benchmarks/results, and with a path writes exactly there; docs/measured.md's commands (written by
benchmarks/report.py) each refresh the results file their row is read from."""
from __future__ import annotations

import argparse
import importlib.util
import json
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
BENCH = REPO / "benchmarks"
RESULTS = BENCH / "results"


def scripts_with_a_parser() -> list[Path]:
    """The benchmarks/*.py that run as a command with options (an argparse parser and a main)."""
    return sorted(p for p in BENCH.glob("*.py")
                  if "ArgumentParser(" in (text := p.read_text()) and 'if __name__ == "__main__"' in text)


SCRIPTS = scripts_with_a_parser()

# One interpreter runs every script's --help in turn (as ``python benchmarks/X.py --help`` would:
# the script's folder first on sys.path, run as __main__), so the shared imports are paid once.
HELP_DRIVER = """
import contextlib, io, json, runpy, sys, traceback
bench, paths = sys.argv[1], sys.argv[2:]
sys.path.insert(0, bench)
got = {}
for path in paths:
    buf = io.StringIO()
    sys.argv = [path, "--help"]
    code = None
    try:
        with contextlib.redirect_stdout(buf):
            runpy.run_path(path, run_name="__main__")
    except SystemExit as exc:
        code = exc.code
    except BaseException:
        code = traceback.format_exc()
    got[path] = {"code": code, "help": buf.getvalue()}
print("@@HELP@@" + json.dumps(got))
"""


@pytest.fixture(scope="module")
def helps() -> dict:
    done = subprocess.run([sys.executable, "-c", HELP_DRIVER, str(BENCH), *map(str, SCRIPTS)], cwd=REPO,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and "@@HELP@@" in done.stdout, done.stderr[-3000:]
    return json.loads(done.stdout.split("@@HELP@@", 1)[1])


@pytest.fixture(scope="module")
def bench():
    """benchmarks/_bench.py as a module."""
    spec = importlib.util.spec_from_file_location("mtbmj_bench_helpers", BENCH / "_bench.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_scripts_are_found():
    names = {p.name for p in SCRIPTS}
    assert len(names) >= 20, names
    assert {"sweep.py", "bike_speed.py", "report.py", "make_sled_example.py", "calibrate.py"} <= names
    assert "_bench.py" not in names


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_help_lists_out(helps, script):
    got = helps[str(script)]
    assert got["code"] in (0, None), f"{script.name} --help: {got['code']}"
    assert re.search(r"^\s*--out PATH\b", got["help"], re.M), f"{script.name} --help lists no --out PATH:\n{got['help']}"


def results_files() -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in RESULTS.iterdir()} if RESULTS.is_dir() else {}


def test_write_json_with_no_path_writes_to_the_scratch_folder(bench, tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # what tempfile.gettempdir() returns
    before = results_files()
    path = bench.write_json(str(BENCH / "bench_outputs_probe.py"), {"value": 1.5})
    assert path == tmp_path / "mtbmj-benchmarks" / "bench_outputs_probe.json"
    assert path.is_file()
    assert not path.resolve().is_relative_to(REPO)
    data = json.loads(path.read_text())
    assert data["value"] == 1.5 and data["measured_at"] and "environment" in data
    assert results_files() == before  # nothing new or rewritten under benchmarks/results
    assert not (RESULTS / "bench_outputs_probe.json").exists()


def test_write_json_with_a_path_writes_exactly_there(bench, tmp_path, monkeypatch):
    scratch = tmp_path / "temp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    before = results_files()
    target = tmp_path / "made" / "here.json"  # its folder is made
    path = bench.write_json(str(BENCH / "accuracy.py"), {"rows": [1, 2]}, target)
    assert path == target and target.is_file()
    assert json.loads(target.read_text())["rows"] == [1, 2]
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*")) == ["made", "made/here.json", "temp"]
    assert results_files() == before


def test_the_out_option(bench, tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    parser = argparse.ArgumentParser(prog="x.py")
    bench.add_out_option(parser, str(BENCH / "x.py"))
    assert parser.parse_args([]).out is None
    assert parser.parse_args(["--out", "a/b.json"]).out == Path("a/b.json")
    text = "".join(parser.format_help().split())  # argparse wraps the lines (at hyphens too)
    assert str(tmp_path / "mtbmj-benchmarks" / "x.json") in text
    assert "--outbenchmarks/results/x.json" in text
    with pytest.raises(SystemExit):  # a folder is not a results file
        parser.parse_args(["--out", str(tmp_path)])


def test_measured_page_commands_refresh_their_own_results_file():
    spec = importlib.util.spec_from_file_location("mtbmj_bench_report_out", BENCH / "report.py")
    report = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = report  # its dataclass looks its module up
    try:
        spec.loader.exec_module(report)
        rows = [row for table in report.collect().values() for row, _ in table]
    finally:
        sys.modules.pop(spec.name, None)
    assert len(rows) >= 20
    for row in rows:
        argv = shlex.split(row.command)
        assert argv.count("--out") == 1, row.command
        assert argv[argv.index("--out") + 1] == f"benchmarks/results/{row.json_name}", row.command
        assert (RESULTS / row.json_name).is_file(), row.json_name


def shown_benchmark_commands() -> list[tuple[str, list[str]]]:
    """(page, argv) of every ``python benchmarks/X.py ...`` command the README and docs pages show:
    in fenced shell blocks (read as test_docs_commands reads them) and in inline code, where a
    command may wrap over a line break."""
    from helpers import PAGES, shell_commands

    found = []
    for page in PAGES:
        found += [(page.name, argv) for _, argv in shell_commands(page) if argv[1:2] and argv[1].startswith("benchmarks/")]
        prose = re.sub(r"^\s*```.*?^\s*```", "", page.read_text(), flags=re.S | re.M)
        found += [(page.name, shlex.split(" ".join(span.split())))
                  for span in re.findall(r"`(python3? benchmarks/[^`]+)`", prose)]
    return found


def test_every_benchmark_command_shown_parses_and_says_where_it_writes():
    """Each command shown takes the script's options as written; each names its results file with
    ``--out``, but report.py (it writes docs/measured.md, from the results alone) and calibrate.py
    (shown for the table it prints; the text says where its reference.toml goes)."""
    from helpers import script_parser

    shown = shown_benchmark_commands()
    assert {page for page, _ in shown} >= {"bike.md", "measured.md", "fitting.md", "identification.md"}
    for page, argv in shown:
        script = REPO / argv[1]
        assert script.is_file(), f"{page}: {' '.join(argv)}: no {argv[1]}"
        try:
            script_parser(script).parse_args(argv[2:])
        except (argparse.ArgumentError, SystemExit) as exc:  # pragma: no cover - the message says which
            pytest.fail(f"{page}: {' '.join(argv)}: {exc}")
        if script.name not in ("report.py", "calibrate.py"):
            assert "--out" in argv[2:], f"{page}: {' '.join(argv)} does not say where it writes (--out)"

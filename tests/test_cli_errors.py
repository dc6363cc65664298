"""The ``mtbmj`` command on bad input: exit status 2, exactly one line on stderr naming the key or
the cause, no traceback, and no output left behind. Plus one successful drop and its files.

Every case runs the CLI in a process of its own, once per module; the tests inspect the results.
Importing mtbmj costs a few seconds of CPU, so a representative subset runs as
``python -m mtbmj.cli`` (in parallel) and the rest in children forked from the test process.
"""
import csv
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mtbmj
from mtbmj import cli, output
from mtbmj.drop import run as drop
from mtbmj.config import load

PNG = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\x01\xff\xfe"
S3_WITHOUT_KNEE = "\n".join(l for l in load("S3").to_toml().splitlines() if not l.startswith("knee_mm")) + "\n"
TABLE_V = "[-1500, -800, -400, -150, -50, 0, 50, 150, 400, 1500, 800]"
FILES = {
    "noknee.toml": S3_WITHOUT_KNEE,
    "typo.toml": 'base = "S12"\n[fork.spring]\nrate_N_per_m = 5\n',
    "nan.toml": 'base = "S12"\n[fork.spring]\nprogressive_rate_N_per_mm = nan\n',
    "syntax.toml": 'base = "S12"\n[fork.spring\nrate_N_per_mm = 5\n',
    "notes.txt": "Shopping list: tubes, tyre levers, chain lube.\n",
    "picture.png": PNG,
}

# name -> (arguments after "drop", strings the one stderr line must contain)
ERRORS = {
    "missing_key": (["{dir}/noknee.toml"], ["fork.spring.knee_mm"]),
    "misspelled_key": (["S1", "--set", "fork.spring.rat_N_per_mm=5"],
                       ["fork.spring.rat_N_per_mm", "did you mean fork.spring.rate_N_per_mm"]),
    "misspelled_key_in_file": (["{dir}/typo.toml"], ["fork.spring.rate_N_per_m", "did you mean fork.spring.rate_N_per_mm"]),
    "value_without_unit": (["S1", "--set", "fork.spring.rate=5"], ["fork.spring.rate", "fork.spring.rate_N_per_mm"]),
    "string_with_unit": (["S1", "--set", 'fork.spring.rate_N_per_mm="5 N/mm"'], ["fork.spring.rate_N_per_mm"]),
    "negative_mass": (["S1", "--set", "sled.body_mass_kg=-53.2"], ["sled.body_mass_kg"]),
    "negative_rate": (["S1", "--set", "fork.spring.rate_N_per_mm=-10"], ["fork.spring.rate_N_per_mm"]),
    "knee_outside_travel": (["S3", "--set", "fork.spring.knee_mm=150"], ["fork.spring.knee_mm"]),
    "non_monotonic_table": (["S10", "--set", f"fork.damper.velocity_mm_per_s={TABLE_V}"],
                            ["fork.damper.velocity_mm_per_s"]),
    "too_short_table": (["S10", "--set", "fork.damper.velocity_mm_per_s=[-100, 0, 100]",
                         "--set", "fork.damper.force_N=[-10, 0, 10]"], ["fork.damper.velocity_mm_per_s"]),
    "mismatched_table": (["S10", "--set", "fork.damper.force_N=[-300, -175, -95, -40, -12, 0, 14, 45, 115, 225]"],
                         ["fork.damper.force_N"]),
    "nan_override": (["S1", "--set", "fork.spring.rate_N_per_mm=nan"], ["fork.spring.rate_N_per_mm"]),
    "nan_in_file": (["{dir}/nan.toml"], ["fork.spring.progressive_rate_N_per_mm"]),
    "unknown_preset": (["S15"], ["S15"]),
    "unknown_model": (["S1", "--set", "fork.spring.model=helical"], ["fork.spring.model", "helical"]),
    "preload_without_top_out": (["S1", "--set", "fork.spring.preload=true"], ["fork.spring.preload"]),
    "timestep_too_large": (["S1", "--set", "solver.timestep_s=0.01"], ["solver.timestep_s"]),
    "invalid_toml_syntax": (["{dir}/syntax.toml"], ["syntax.toml", "TOML"]),
    "negative_duration": (["S1", "--duration", "-1"], ["--duration"]),
    "not_toml_text": (["{dir}/notes.txt"], ["notes.txt"]),
    "not_toml_binary": (["{dir}/picture.png"], ["picture.png"]),
    "missing_file": (["{dir}/nothere.toml"], ["nothere.toml"]),
    "unknown_engine": (["S1", "--engine", "bullet"], ["--engine", "bullet"]),
    # Runs that pass validation and then diverge, each through a different check:
    # a MuJoCo warning (BADQVEL at an absurd impact speed), the runaway-displacement guard,
    # and a floating-point overflow in the ODE reference (a RuntimeWarning).
    "diverge_mujoco_warning": (["S1", "--set", "sled.drop_height_mm=1e25"], ["diverged", "BADQVEL"]),
    "diverge_runaway": (["S1", "--set", "sled.drop_height_mm=1e7"], ["diverged"]),
    "diverge_ode_overflow": (["S1", "--engine", "ode", "--set", "sled.drop_height_mm=1e30"], ["diverged"]),
    "beyond_any_fork": (["S12", "--set", "sled.wheel_mass_kg=1e200"], ["sled.wheel_mass_kg", "beyond"]),
}
# cases whose --out directory exists beforehand (with a file in it) and must be left unchanged
EXISTING_OUT = {
    "existing_out_bad_value": (["S1", "--set", "sled.body_mass_kg=-1"], ["sled.body_mass_kg"]),
    "existing_out_diverge": (["S1", "--set", "sled.drop_height_mm=1e7"], ["diverged"]),
}
SUCCESS = {"success": (["S1", "--duration", "0.3"], [])}


# These run as ``python -m mtbmj.cli``; the others in a child forked from this (already imported)
# process that calls ``mtbmj.cli.main`` with its own stdout/stderr file descriptors, working
# directory and exit status - the same observable behaviour without paying the import each time.
REAL_SUBPROCESS = {"success", "unknown_preset", "not_toml_binary", "diverge_mujoco_warning"}


def _snapshot(path: Path) -> dict:
    if not path.exists():
        return {}
    return {str(p.relative_to(path)): (p.read_bytes() if p.is_file() else None) for p in sorted(path.rglob("*"))}


def _forked_main(argv, cwd: Path, stdout_path: Path, stderr_path: Path) -> int:
    """Run ``mtbmj.cli.main(argv)`` in a forked child; return its exit status."""
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # child: never returns into pytest
        code = 1
        try:
            os.chdir(cwd)
            for fd, path in ((1, stdout_path), (2, stderr_path)):
                target = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
                os.dup2(target, fd)
                os.close(target)
            sys.stdout = open(1, "w", closefd=False, buffering=1)
            sys.stderr = open(2, "w", closefd=False, buffering=1)
            code = cli.main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException:
            import traceback

            traceback.print_exc()  # as the interpreter would for an uncaught exception
            code = 1
        finally:
            try:
                sys.stdout.flush()
                sys.stderr.flush()
            finally:
                os._exit(code)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status)


def _prepare(name, args, files_dir: Path, root: Path):
    cwd = root / name / "cwd"  # an empty working directory: nothing may appear in it
    cwd.mkdir(parents=True)
    out = root / name / "out"
    if name in EXISTING_OUT:  # the result of an earlier run, as mtbmj records it
        output.write_atomically(out, {"keep.txt": b"results of an earlier run\n"})
    argv = ["drop", *[a.replace("{dir}", str(files_dir)) for a in args], "--out", str(out)]
    return cwd, out, argv


def _result(name, code, cwd, out, before, stdout_path, stderr_path):
    proc = subprocess.CompletedProcess(name, code, stdout_path.read_text(), stderr_path.read_text())
    return {"proc": proc, "out": out, "cwd": cwd, "before": before, "after": _snapshot(out),
            "cwd_after": _snapshot(cwd)}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    files_dir = tmp_path_factory.mktemp("inputs")
    for fname, content in FILES.items():
        path = files_dir / fname
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)
    root = tmp_path_factory.mktemp("cli")
    logs = tmp_path_factory.mktemp("logs")
    env = dict(os.environ, MUJOCO_GL="disable")
    results, started = {}, []
    cases = {**SUCCESS, **ERRORS, **EXISTING_OUT}
    # start the real subprocesses (they run in parallel) ...
    for name in REAL_SUBPROCESS:
        cwd, out, argv = _prepare(name, cases[name][0], files_dir, root)
        before = _snapshot(out)
        so, se = logs / f"{name}.out", logs / f"{name}.err"
        with open(so, "w") as fo, open(se, "w") as fe:
            proc = subprocess.Popen([sys.executable, "-m", "mtbmj.cli", *argv], cwd=cwd, env=env,
                                    stdout=fo, stderr=fe, stdin=subprocess.DEVNULL)
        started.append((name, proc, cwd, out, before, so, se))
    # ... while the forked children run one by one
    for name, (args, _) in cases.items():
        if name in REAL_SUBPROCESS:
            continue
        cwd, out, argv = _prepare(name, args, files_dir, root)
        before = _snapshot(out)
        so, se = logs / f"{name}.out", logs / f"{name}.err"
        code = _forked_main(argv, cwd, so, se)
        results[name] = _result(name, code, cwd, out, before, so, se)
    for name, proc, cwd, out, before, so, se in started:
        code = proc.wait(timeout=300)
        results[name] = _result(name, code, cwd, out, before, so, se)
    return results


def _check_one_line_error(result, needles):
    proc = result["proc"]
    err = proc.stderr
    assert proc.returncode == 2, f"exit status {proc.returncode}; stderr:\n{err}"
    assert "Traceback" not in err, err
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), f"stderr must be exactly one line, got {len(lines)}:\n{err}"
    line = lines[0]
    assert line.strip() and line.startswith("mtbmj: error: "), line
    for needle in needles:
        assert needle in line, f"{needle!r} not named in {line!r}"
    assert proc.stdout == "", f"nothing on stdout for a failed run, got {proc.stdout!r}"
    assert result["cwd_after"] == {}, f"files left in the working directory: {sorted(result['cwd_after'])}"


@pytest.mark.parametrize("name", list(ERRORS))
def test_bad_input_exits_2_with_one_line_and_writes_nothing(runs, name):
    result = runs[name]
    _check_one_line_error(result, ERRORS[name][1])
    assert not result["out"].exists(), f"--out directory created: {sorted(result['after'])}"


@pytest.mark.parametrize("name", list(EXISTING_OUT))
def test_failed_run_leaves_an_existing_out_directory_unchanged(runs, name):
    result = runs[name]
    _check_one_line_error(result, EXISTING_OUT[name][1])
    assert result["before"]["keep.txt"] == b"results of an earlier run\n"
    # the same files, the same bytes; the lock file alone names its last holder
    assert {k: v for k, v in result["after"].items() if k != ".lock"} == \
        {k: v for k, v in result["before"].items() if k != ".lock"}
    assert set(result["after"]) == set(result["before"])


# --------------------------------------------------------------------------------------- success


def test_drop_writes_results(runs):
    result = runs["success"]
    proc, out = result["proc"], result["out"]
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "S1" in proc.stdout and str(out) in proc.stdout
    names = sorted(p.name for p in out.iterdir())
    assert {"timeseries.csv", "summary.json", "manifest.json"} <= set(names)
    assert not [n for n in names if n.endswith(".tmp") or n.startswith(".") and n not in (".lock", output.RECORD)], names
    assert sorted(output.read_record(out)["files"]) == sorted(n for n in names if n != output.RECORD)
    assert result["cwd_after"] == {}

    # timeseries.csv: the sled logger's columns at 1 kHz over the requested 0.3 s
    text = (out / "timeseries.csv").read_text()
    rows = [line for line in text.splitlines() if not line.startswith("#")]
    header = next(csv.reader([rows[0]]))
    assert header == ["time_s", "sled_mm", "fork_mm", "tire_mm", "sled_velocity_mm_per_s",
                      "fork_velocity_mm_per_s", "tire_velocity_mm_per_s", "fork_force_N", "tire_force_N"]
    data = np.loadtxt(io.StringIO("\n".join(rows[1:])), delimiter=",")
    col = {name: data[:, i] for i, name in enumerate(header)}
    assert np.all(np.isfinite(data))
    assert np.allclose(np.diff(col["time_s"]), 1e-3)
    assert col["time_s"][0] == 0.0 and col["time_s"][-1] == pytest.approx(0.3)
    assert np.allclose(col["tire_mm"], col["sled_mm"] - col["fork_mm"], atol=1e-5)
    assert col["sled_velocity_mm_per_s"][0] == pytest.approx((2 * 9.81 * 0.095) ** 0.5 * 1e3, rel=1e-6)
    assert 80 < col["fork_mm"].max() < 200  # the fork compresses on impact
    # the tire never pulls: in the engine trace; the logged force may ring slightly below zero
    # after lift-off, as any anti-aliasing filter does after a sharp drop
    raw_rows = [line for line in (out / "timeseries_raw.csv").read_text().splitlines() if not line.startswith("#")]
    raw = np.loadtxt(io.StringIO("\n".join(raw_rows[1:])), delimiter=",")
    assert np.all(raw[:, header.index("tire_force_N")] >= 0.0)
    assert np.all(col["tire_force_N"] >= -0.02 * col["tire_force_N"].max())

    # summary.json
    summary = json.loads((out / "summary.json").read_text())
    assert summary["impact_speed_m_per_s"] == pytest.approx((2 * 9.81 * 0.095) ** 0.5)
    assert summary["max_fork_mm"] == pytest.approx(col["fork_mm"].max(), rel=0.05)

    # manifest.json: the config hash and the versions that produced the run
    manifest = json.loads((out / "manifest.json").read_text())
    import mujoco
    import scipy

    assert manifest["config_sha256"] == load("S1").digest()
    assert manifest["versions"]["mtbmj"] == mtbmj.__version__
    assert manifest["versions"]["mujoco"] == mujoco.__version__
    assert manifest["versions"]["scipy"] == scipy.__version__
    assert manifest["engine"] == "mujoco" and manifest["name"] == "S1"
    if (out / "config.toml").exists():  # the written configuration reproduces the hash
        assert load(out / "config.toml").digest() == manifest["config_sha256"]


# ----------------------------------------------------------------- in-process divergence (patched)


def _patched_engine(monkeypatch, make_trace):
    real = drop.ENGINES["mujoco"]

    def engine(setup, duration=None, progress=None):
        return make_trace(real(setup, duration, progress))

    monkeypatch.setitem(drop.ENGINES, "mujoco", engine)


def _main_fails_cleanly(capsys, tmp_path, needle):
    out = tmp_path / "out"
    code = cli.main(["drop", "S1", "--out", str(out), "--duration", "0.2", "--quiet"])
    captured = capsys.readouterr()
    assert code == 2, captured.err
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("mtbmj: error: "), captured.err
    assert needle in lines[0]
    assert "Traceback" not in captured.err
    assert not out.exists()


def test_engine_returning_nan_is_reported_as_divergence(monkeypatch, capsys, tmp_path):
    """An engine whose trace turns NaN half way must not produce result files."""
    import dataclasses

    def nan_half_way(trace):
        sled = trace.sled.copy()
        sled[sled.size // 2:] = np.nan
        return dataclasses.replace(trace, sled=sled)

    _patched_engine(monkeypatch, nan_half_way)
    _main_fails_cleanly(capsys, tmp_path, "diverged")


def test_engine_run_error_is_one_line(monkeypatch, capsys, tmp_path):
    def fail(trace):
        raise mtbmj.RunError("run diverged before t = 0.1000 s: MuJoCo warning BADQACC")

    _patched_engine(monkeypatch, fail)
    _main_fails_cleanly(capsys, tmp_path, "BADQACC")


def test_engine_overflow_warning_is_one_line(monkeypatch, capsys, tmp_path):
    def overflow(trace):
        np.float64(1e300) * np.float64(1e300)  # RuntimeWarning: overflow
        return trace

    _patched_engine(monkeypatch, overflow)
    _main_fails_cleanly(capsys, tmp_path, "diverged")

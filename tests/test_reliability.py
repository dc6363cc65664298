"""Reliability (issue 13): the red-team reproducers, each refused in one line or handled; whole
output folders appear at once (also under SIGKILL mid-write); workers die with their parent."""
from __future__ import annotations

import os
import shutil
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mtbmj import output
from mtbmj.cli import main
from mtbmj.errors import MtbmjError

from helpers import gone, one_line

PRESET_RATE = "fork.spring.preload_N"


# --- 1, 11, 14: sweeps ------------------------------------------------------------------------


@pytest.mark.parametrize("csv_text, needle", [
    ("sled.drop_height_mm\n95\nabc\n", "row 3, column sled.drop_height_mm: 'abc' is not a number"),
    ("fork.damper.model\nlinear\n3\n", "row 3, column fork.damper.model: 3 is not a word"),
    ("fork.spring.preload\ntrue\n2\n", "row 3, column fork.spring.preload: 2 is not true or false"),
])
def test_a_bad_sweep_cell_is_refused_before_any_work(tmp_path, capsys, csv_text, needle):
    (tmp_path / "v.csv").write_text(csv_text)
    one_line(capsys, ["sweep", "S12", "--from-csv", tmp_path / "v.csv", "--out", tmp_path / "sw", "--quiet"], needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.csv"]


def test_sweep_table_writes_with_word_and_number_columns_and_is_byte_identical(tmp_path):
    """Text, bool and number columns with gaps (empty cells keep the base value) write; the
    same sweep twice gives the same table bytes (wall times are in timings.csv)."""
    from mtbmj import sweep

    (tmp_path / "v.csv").write_text("fork.damper.model,fork.spring.preload,fork.spring.preload_N\n"
                                    "linear,true,\n,,250\nlinear,false,300\n")
    variants = sweep.from_csv(tmp_path / "v.csv")
    tables = []
    for name in ("a", "b"):
        result = sweep.run_sweep("S12", variants, tmp_path / name, duration=0.05, workers=1, csv=True)
        tables.append((tmp_path / name / "sweep.parquet").read_bytes())
        assert (tmp_path / name / "timings.csv").read_text().count("\n") == 4
        assert "wall_time_s" not in result.table.columns
    assert tables[0] == tables[1]
    table = pd.read_parquet(tmp_path / "a" / "sweep.parquet")
    assert table["fork.spring.preload_N"].dtype == float and np.isnan(table["fork.spring.preload_N"][0])
    model = table["fork.damper.model"]
    assert list(model.isna()) == [False, True, False] and model[0] == model[2] == "linear"
    assert list(table["fork.spring.preload"].isna()) == [False, True, False] and not table["fork.spring.preload"][2]


HOLDER = textwrap.dedent("""
    import fcntl, os, sys, time
    fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT)
    fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    os.write(fd, f"mtbmj sweep (process {os.getpid()})\\n".encode())  # what a running sweep writes there
    print("locked", flush=True)
    time.sleep(60)
""")


def test_one_sweep_per_out_folder(tmp_path, capsys):
    """Another process holds the folder's lock (as a running sweep does): refused at once; when
    that process is gone (even killed), the folder is free again."""
    out = tmp_path / "sw"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(out / ".lock")], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        one_line(capsys, ["sweep", "S12", "--vary", f"{PRESET_RATE}=150:300:2", "--duration", "0.05", "--out", out,
                          "--quiet"], "another mtbmj run (mtbmj sweep (process", "is writing to this folder")
        assert sorted(p.name for p in out.iterdir()) == [".lock"]
    finally:
        holder.kill()
        holder.wait()
        holder.stdout.close()
    assert main(["sweep", "S12", "--vary", f"{PRESET_RATE}=150:300:2", "--duration", "0.05", "--workers", "1",
                 "--out", str(out), "--quiet"]) == 0


# --- 5: unwritable --out ------------------------------------------------------------------------


@pytest.mark.parametrize("command", [
    ["sweep", "S12", "--vary", f"{PRESET_RATE}=150:300:3", "--quiet"],
    ["sensitivity", "S12", "--vary", f"{PRESET_RATE}=150:300", "--quiet"],
    ["drop", "S12", "--quiet"],
])
def test_an_out_that_is_a_file_is_refused_before_the_work(tmp_path, capsys, command):
    (tmp_path / "f").write_text("x\n")
    start = time.perf_counter()
    one_line(capsys, command + ["--out", tmp_path / "f"], "not a directory")
    assert (tmp_path / "f").read_text() == "x\n" and sorted(p.name for p in tmp_path.iterdir()) == ["f"]
    if command[0] != "drop":
        assert time.perf_counter() - start < 5.0  # refused before any variant ran


def test_a_full_disk_at_the_sweep_table_is_one_line_and_keeps_the_journal(tmp_path, capsys, monkeypatch):
    real = output.write_file

    def full(path, content):  # the disk fills while the result folder is staged (the table)
        if ".sw.new-" in str(path):
            raise OSError(28, "No space left on device")
        return real(path, content)

    monkeypatch.setattr(output, "write_file", full)
    out = tmp_path / "sw"
    one_line(capsys, ["sweep", "S12", "--vary", f"{PRESET_RATE}=150:300:2", "--duration", "0.05", "--workers", "1",
                      "--out", out, "--quiet"], "No space left on device")
    assert sorted(p.name for p in out.iterdir()) == [".lock", output.RECORD, "journal"]  # resumable
    assert output.read_record(out)["folders"] == ["journal"]
    assert [p.name for p in tmp_path.iterdir()] == ["sw"]


# --- 4: run lengths ------------------------------------------------------------------------------


@pytest.mark.parametrize("argv, needle", [
    (["drop", "S12", "--duration", "inf"], "--duration"),
    (["drop", "S12", "--duration", "1e9"], "memory"),
    (["drop", "S12", "--duration", "1e-9"], "shorter than one logger sample"),
    (["drop", "S12", "--engine", "ode", "--duration", "1e9"], "memory"),
    (["crosscheck", "S12", "--duration", "1e-9"], "shorter than one logger sample"),
    (["crosscheck", "S12", "--duration", "nan"], "--duration"),
    (["study", "--presets", "S1,S12", "--duration", "1e9", "--quiet"], "memory"),
    (["validate", "example", "S12", "--duration", "inf", "--quiet"], "--duration"),
    (["validate", "example", "S12", "--duration", "1e9", "--workers", "1", "--quiet"], "memory"),
    (["roll", "flat", "--speed", "3", "--duration", "1e9", "--quiet"], "memory"),
    (["roll", "flat", "--speed", "3", "--duration", "inf", "--quiet"], "--duration"),
])
def test_run_lengths_are_checked_before_allocating(tmp_path, capsys, argv, needle):
    one_line(capsys, argv + ([] if argv[0] == "crosscheck" else ["--out", tmp_path / "out"]), needle)
    assert not (tmp_path / "out").exists()


def test_a_tiny_timestep_is_refused_with_the_memory_it_would_need(tmp_path, capsys):
    (tmp_path / "t.toml").write_text('base = "S12"\n[solver]\ntimestep_s = 1e-13\n')
    err = one_line(capsys, ["drop", tmp_path / "t.toml", "--out", tmp_path / "out"], "memory", "available")
    assert "TiB" in err


# --- 6, 7: what is read --------------------------------------------------------------------------


def test_devices_fifos_and_far_away_bases_are_not_read(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "z.toml").write_text('base = "/dev/zero"\n')
    one_line(capsys, ["drop", "z.toml"], "z.toml", "must be a preset name or a .toml file")
    (tmp_path / "p.toml").write_text('base = "../../../etc/passwd"\n')
    one_line(capsys, ["drop", "p.toml"], "must be a preset name or a .toml file")
    far = tmp_path.parent / f"far-{os.getpid()}.toml"
    far.write_text("secret_key = 1\n")
    try:
        (tmp_path / "f.toml").write_text(f'base = "../{far.name}"\n')
        err = one_line(capsys, ["drop", "f.toml"], "lies outside the current directory")
        assert "secret_key" not in err
    finally:
        far.unlink()
    os.mkfifo(tmp_path / "fifo.toml")
    os.mkfifo(tmp_path / "fifo.csv")
    os.mkfifo(tmp_path / "fifo.SST")
    for argv in (["drop", "fifo.toml"], ["fit", "spring", "fifo.csv"], ["validate", "fifo.csv", "S12"],
                 ["telemetry", "fifo.SST"], ["sweep", "S12", "--from-csv", "fifo.csv"], ["drop", "/dev/zero"]):
        one_line(capsys, argv + ["--out", "out"], "not a regular file")
    assert not (tmp_path / "out").exists()


def test_a_base_is_found_beside_the_file_that_names_it(tmp_path, capsys, monkeypatch):
    """Relative to the including file (not the current directory), inside the allowed places."""
    (tmp_path / "configs" / "variants").mkdir(parents=True)
    (tmp_path / "configs" / "base.toml").write_text('base = "S12"\n[fork.spring]\npreload_N = 210.0\n')
    (tmp_path / "configs" / "variants" / "v.toml").write_text('base = "../base.toml"\n')
    monkeypatch.chdir(tmp_path)  # the project folder: configs/base.toml lies inside it
    from mtbmj.config import load

    assert load("configs/variants/v.toml")["fork.spring.preload_N"] == 210.0
    monkeypatch.chdir(tmp_path / "configs" / "variants")  # now base.toml is outside both places
    one_line(capsys, ["drop", "v.toml", "--out", tmp_path / "out"], "lies outside")


def test_files_over_the_size_limit_are_refused_unread(tmp_path, capsys, monkeypatch):
    from mtbmj import textfile

    monkeypatch.setitem(textfile.LIMITS, "config", 1000)
    (tmp_path / "big.toml").write_text("# " + "x" * 2000 + "\n")
    one_line(capsys, ["drop", tmp_path / "big.toml", "--out", tmp_path / "out"], "too large", "limit")


@pytest.mark.parametrize("text, needle", [
    ("a = " + "[" * 600 + "]" * 600 + "\n", "nested too deeply"),
    (".".join(["a"] * 1000) + " = 1\n", "nested deeper than"),
    ("sled.wheel_mass_kg = 1" + "0" * 400 + "\n", "sled.wheel_mass_kg"),
])
def test_deep_nesting_and_huge_numbers_are_one_line(tmp_path, capsys, text, needle):
    (tmp_path / "c.toml").write_text(text)
    one_line(capsys, ["drop", tmp_path / "c.toml", "--out", tmp_path / "out"], needle)


# --- 8, 9, 10, 13: single reproducers -----------------------------------------------------------


@pytest.mark.parametrize("argv", [["drop", "S12", "--set", "a\nb"], ["drop", "x\ny.toml"],
                                  ["drop", "S12", "--set", "fork.spring.model=li\r\nnear"]])
def test_a_line_break_in_user_input_keeps_the_report_one_line(tmp_path, capsys, argv):
    one_line(capsys, argv + ["--out", tmp_path / "out"], "\\n")


def test_fit_damper_on_an_all_zero_force_column(tmp_path, capsys):
    from mtbmj.identify import dyno_synthetic as dyno

    dyno.write_damper_record(tmp_path / "d.csv", peaks=True)
    lines = (tmp_path / "d.csv").read_text().splitlines()
    data = [line for line in lines if line and not line.startswith("#")]
    column = data[0].split(",").index("force_N")
    zeroed = [data[0]] + [",".join("0" if j == column else c for j, c in enumerate(r.split(","))) for r in data[1:]]
    (tmp_path / "z.csv").write_text("\n".join(zeroed) + "\n")
    one_line(capsys, ["fit", "damper", tmp_path / "z.csv", "--out", tmp_path / "out"], "force column is 0 N everywhere")


def test_telemetry_compare_with_a_broken_run_config(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["drop", "S12", "--duration", "0.3", "--quiet", "--out", str(run)]) == 0
    (run / "config.toml").write_text("fork = 'x'\n")
    one_line(capsys, ["telemetry", "example", "--compare", run, "--out", tmp_path / "t"], "fork.travel_mm")


def test_an_absurd_mass_is_refused_before_mujoco_prints(tmp_path, capfd):
    capfd.readouterr()
    assert main(["drop", "S12", "--set", "sled.wheel_mass_kg=1e200", "--out", str(tmp_path / "o")]) == 2
    err = capfd.readouterr().err  # file-descriptor level: MuJoCo's own prints would show here
    assert err.count("\n") == 1 and "sled.wheel_mass_kg" in err, err


def test_csv_cells_of_user_text_cannot_be_spreadsheet_formulas(tmp_path):
    assert output.spreadsheet_text("=cmd|' -C calc'!A0") == "'=cmd|' -C calc'!A0"
    assert output.spreadsheet_text("-1.5") == "-1.5" and output.spreadsheet_text("S12") == "S12"
    assert output.spreadsheet_text("@SUM(A1)") == "'@SUM(A1)" and output.spreadsheet_text(3.0) == 3.0
    name = "=cmd|' -C calc'!A0"
    (tmp_path / f"{name}.toml").write_text('base = "S12"\n')
    assert main(["validate", "example", str(tmp_path / f"{name}.toml"), "--duration", "0.3", "--workers", "1",
                 "--quiet", "--out", str(tmp_path / "v")]) == 0
    rows = (tmp_path / "v" / "validation_metrics.csv").read_text().splitlines()[1:]
    assert rows and all(row.startswith("'=cmd") for row in rows)


def test_presets_into_a_closed_pipe_is_quiet(tmp_path):
    code = "import sys; from mtbmj.cli import main; sys.exit(main(['presets']))"
    proc = subprocess.run(f"{sys.executable} -c \"{code}\" | head -1", shell=True, capture_output=True, text=True,
                          timeout=120)
    assert proc.stdout.startswith("configurations (") and proc.stderr == "", proc.stderr


# --- 3, 12: output folders ------------------------------------------------------------------------


def test_overwriting_a_result_leaves_only_the_new_one(tmp_path):
    out = tmp_path / "run"
    assert main(["drop", "S1", "--duration", "0.2", "--quiet", "--out", str(out)]) == 0
    (out / "results").mkdir()
    (out / "results" / "stray.txt").write_text("a file of the user's, put into the result\n")
    assert main(["drop", "S12", "--duration", "0.2", "--quiet", "--out", str(out)]) == 2  # never removed
    assert (out / "results" / "stray.txt").exists() and '"name": "S1"' in (out / "manifest.json").read_text()
    shutil.rmtree(out / "results")
    assert main(["drop", "S12", "--duration", "0.2", "--quiet", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [".lock", output.RECORD, "config.toml", "manifest.json",
                                                     "quicklook.png", "summary.json", "timeseries.csv",
                                                     "timeseries_raw.csv"]
    assert '"name": "S12"' in (out / "manifest.json").read_text()
    assert output.read_record(out)["command"] == "drop"
    assert [p.name for p in tmp_path.iterdir()] == ["run"]


def test_a_folder_of_other_files_or_the_current_directory_is_not_replaced(tmp_path, capsys, monkeypatch):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("years of work\n")
    one_line(capsys, ["drop", "S12", "--duration", "0.05", "--out", mine], "thesis.tex", "mtbmj did not write")
    one_line(capsys, ["sweep", "S12", "--vary", f"{PRESET_RATE}=150:300:2", "--out", mine, "--quiet"],
             "thesis.tex", "mtbmj did not write")
    assert [p.name for p in mine.iterdir()] == ["thesis.tex"]
    monkeypatch.chdir(mine)
    one_line(capsys, ["drop", "S12", "--duration", "0.05", "--out", "."], "current directory")
    one_line(capsys, ["drop", "S12", "--duration", "0.05", "--out", ".."], "current directory")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["drop", "S12", "--duration", "0.05", "--quiet", "--out", str(empty)]) == 0


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_modes_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        written = output.write_atomically(tmp_path / "o", {"a.csv": b"1\n", "sub/b.json": b"{}\n"})
        single = output.write_file_atomically(tmp_path / "single.csv", b"2\n")
    finally:
        os.umask(old)
    for path in written + [single]:
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask, path
    assert stat.S_IMODE((tmp_path / "o").stat().st_mode) == 0o777 & ~umask


def test_a_failed_write_keeps_the_old_folder_whole(tmp_path, monkeypatch):
    out = tmp_path / "o"
    output.write_atomically(out, {"a": b"old a\n", "manifest.json": b"old b\n"})
    real, calls = output.write_file, []

    def failing(path, content):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        return real(path, content)

    monkeypatch.setattr(output, "write_file", failing)
    record = (out / output.RECORD).read_bytes()
    with pytest.raises(MtbmjError, match="No space left"):
        output.write_atomically(out, {"a": b"new a\n", "c": b"new c\n"})
    assert {p.name: p.read_text() for p in out.iterdir() if p.name != ".lock"} == \
        {"a": "old a\n", "manifest.json": "old b\n", output.RECORD: record.decode()}
    assert [p.name for p in tmp_path.iterdir()] == ["o"]


WRITER = textwrap.dedent("""
    import sys
    from mtbmj import output
    out = sys.argv[1]
    for version in range(10 ** 6):
        tag = str(version).encode()
        files = {f"part{i}.bin": tag + b"|" + bytes(200_000) for i in range(6)}
        files["sub/last.txt"] = tag
        files["manifest.json"] = tag
        output.write_atomically(out, files)
        print(version, flush=True)
""")


def test_sigkill_mid_write_leaves_the_old_folder_or_the_new_one(tmp_path):
    """A writer replacing a 7-file folder over and over is killed at seeded random moments: the
    folder is always one whole version, and the next write clears the staging folder left behind."""
    rng = np.random.default_rng(13)
    out = tmp_path / "o"
    seen = set()
    for _ in range(6):
        proc = subprocess.Popen([sys.executable, "-c", WRITER, str(out)], stdout=subprocess.PIPE, text=True)
        proc.stdout.readline()  # one version complete
        time.sleep(rng.uniform(0.0, 0.3))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        proc.stdout.close()
        names = sorted(p.name for p in out.iterdir())
        assert names == [".lock", output.RECORD, "manifest.json"] + [f"part{i}.bin" for i in range(6)] + ["sub"], names
        tags = {(out / f"part{i}.bin").read_bytes().split(b"|")[0] for i in range(6)}
        tags |= {(out / "sub" / "last.txt").read_bytes(), (out / "manifest.json").read_bytes()}
        assert len(tags) == 1, tags  # never a mix of two versions
        seen |= tags
    output.write_atomically(out, {"x": b"1"})
    assert [p.name for p in tmp_path.iterdir()] == ["o"]  # staging folders of killed writers removed
    assert len(seen) > 1


@pytest.mark.parametrize("kind", ["new", "old", "probe"])
def test_leftovers_of_a_dead_writer_are_removed_and_a_live_ones_kept(tmp_path, kind):
    """A writer killed between making and removing its staging, old-version or probe folder
    leaves it behind; the next write removes it when that process is gone and keeps it while
    the process lives (it may still be writing)."""
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(done.stdout)
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        dead = tmp_path / f".o.{kind}-{dead_pid}-0badc0de"
        alive = tmp_path / f".o.{kind}-{live.pid}-0badc0de"
        for path in (dead, alive):
            path.mkdir()
        (dead / "part.bin").write_bytes(b"half")
        output.write_atomically(tmp_path / "o", {"x": b"1"})
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["o", alive.name])
    finally:
        live.kill()
        live.wait()


# --- 2: workers die with their parent --------------------------------------------------------------

POOL = textwrap.dedent("""
    import os, sys, time
    from mtbmj.workers import process_pool

    def pid(_):
        return os.getpid()

    def sleep(_):
        time.sleep(120)

    if __name__ == "__main__":
        pool = process_pool(2)
        pids = set()
        while len(pids) < 2:
            pids |= set(pool.map(pid, range(8)))
        for _ in range(2):
            pool.submit(sleep, 0)
        print(" ".join(map(str, sorted(pids))), flush=True)
        time.sleep(120)
""")


def test_pool_workers_die_when_the_parent_is_killed(tmp_path):
    script = tmp_path / "pool.py"
    script.write_text(POOL)
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    pids = [int(p) for p in proc.stdout.readline().split()]
    assert len(pids) == 2
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    proc.stdout.close()
    assert gone(pids), f"workers {pids} outlived their parent"


@pytest.mark.parametrize("command", [
    ["study", "--presets", "S1,S2", "--workers", "2"],
    ["validate", "example", "S1", "S2", "--workers", "2", "--quiet"],
    ["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:8", "--workers", "2", "--batch-size", "1", "--quiet"],
])
def test_workers_die_with_a_killed_command(tmp_path, command):
    """A command killed with SIGKILL mid-run: its workers exit too, and its pipes close."""
    code = "import sys; from mtbmj.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen([sys.executable, "-c", code, *command, "--out", str(tmp_path / "st")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    children: list[int] = []
    end = time.monotonic() + 60
    while len(children) < 2 and time.monotonic() < end:
        try:
            children = [int(p) for p in Path(f"/proc/{proc.pid}/task/{proc.pid}/children").read_text().split()]
        except FileNotFoundError:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert len(children) >= 2, f"{command[0]} did not start its workers"
    assert gone(children), f"workers {children} outlived {command[0]}"
    proc.stdout.read()  # returns: no orphan holds the pipe open
    proc.stdout.close()
    proc.stderr.close()
    if command[0] != "sweep":  # (a sweep keeps its journal for --resume)
        # the folder claimed before the work holds nothing but its lock: no result, no part of one
        assert not (tmp_path / "st").exists() or [p.name for p in (tmp_path / "st").iterdir()] == [".lock"]

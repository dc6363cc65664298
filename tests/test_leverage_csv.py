"""A leverage curve read from the CSV a linkage tool or a telemetry app exports (``leverage.csv``):
the same bike as the curve typed into the file, header lines skipped, commas, semicolons or tabs,
a path relative to the bike file; a bad row refused naming the file and the line."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.bike import spec as spec_mod
from mtbmj.cli import main

# the SST preset's curve at every tenth millimetre (its own table, written here as the tools do)
W = list(range(0, 171, 10)) + [174]


def curve():
    lev = spec_mod.load("sst").leverage
    return [float(np.interp(w * 1e-3, lev.travel, lev.ratio)) for w in W]


def bike(tmp_path, leverage: str, name="bike.toml"):
    path = tmp_path / name
    path.write_text(f'base = "sst"\n[leverage]\n{leverage}\n')
    return path


@pytest.mark.parametrize("text", [
    "{w},{r}",                                     # Sufni's export: no header, commas
    "Travel (mm);Leverage ratio\n{w};{r}",        # a header line and semicolons
    "wheel_travel_mm\tratio\n\n{w}\t{r}",         # tabs and a blank line
])
def test_a_csv_curve_is_the_typed_curve(tmp_path, text):
    r = curve()
    head, _, row = text.rpartition("\n") if "\n" in text else ("", "", text)
    rows = "\n".join(row.format(w=w, r=x) for w, x in zip(W, r))
    (tmp_path / "curves").mkdir()
    (tmp_path / "curves" / "lr.csv").write_text((head + "\n" if head else "") + rows + "\n")
    from_csv = spec_mod.load(str(bike(tmp_path, 'csv = "curves/lr.csv"')))
    typed = spec_mod.load(str(bike(tmp_path, f"wheel_travel_mm = {W}\nratio = {r}", "typed.toml")))
    assert from_csv.leverage == typed.leverage
    assert from_csv.leverage.full_stroke == pytest.approx(typed.leverage.full_stroke, abs=1e-15)


@pytest.mark.parametrize("rows, said", [
    ("0,3.1\n10,3.0\n20,x\n", "lr.csv, line 3: not two numbers ('20,x')"),
    ("0,3.1\n10,3.0,7\n", "lr.csv, line 2: expected wheel travel and leverage ratio"),
    ("0,3.1\n", "holds 1 row(s)"),
])
def test_a_bad_csv_is_refused_naming_the_line(tmp_path, capsys, rows, said):
    (tmp_path / "lr.csv").write_text(rows)
    path = bike(tmp_path, 'csv = "lr.csv"')
    assert main(["bike", str(path), "flat", "--speed", "4", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0], err
    assert not (tmp_path / "out").exists()


def test_a_csv_beside_the_lists_is_refused(tmp_path):
    (tmp_path / "lr.csv").write_text("0,3\n100,2.5\n")
    with pytest.raises(spec_mod.ConfigError, match="not both"):
        spec_mod.load(str(bike(tmp_path, 'csv = "lr.csv"\nwheel_travel_mm = [0, 100]\nratio = [3, 2.5]')))


def _refusal(tmp_path, csv_path):
    """``mtbmj bike`` on a bike whose [leverage] csv is ``csv_path``, in a child process with a
    timeout (a FIFO used to hang the reader): (exit status, stderr lines, whether out/ exists)."""
    import subprocess
    import sys

    path = tmp_path / "bike.toml"
    path.write_text(f'base = "sst"\n[leverage]\ncsv = "{csv_path}"\n')
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "mtbmj.cli", "bike", str(path), "flat", "--speed", "4", "--out",
                        str(out)], capture_output=True, text=True, timeout=120)
    return r.returncode, r.stderr.strip().splitlines(), out.exists()


@pytest.mark.parametrize("make, said", [
    ("fifo", "not a regular file (a pipe, device or socket is not read)"),
    ("/dev/zero", "not a regular file (a pipe, device or socket is not read)"),
    ("dir", "is a directory, not a file"),
    ("binary", "not a text file"),
])
def test_a_special_or_binary_file_as_the_csv_is_refused_in_one_line(tmp_path, make, said):
    """The CSV goes through the one reader of a user's files (mtbmj/textfile.py): a FIFO hung the
    run, /dev/zero ended in a MemoryError traceback."""
    import os

    if make == "fifo":
        target = tmp_path / "lr.csv"
        os.mkfifo(target)
    elif make == "dir":
        target = tmp_path / "lr.csv"
        target.mkdir()
    elif make == "binary":
        target = tmp_path / "lr.csv"
        target.write_bytes(b"0,3.1\n\xff\xfe\x00\x01\n")
    else:
        target = make
    code, err, wrote = _refusal(tmp_path, target)
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"mtbmj: error: leverage.csv: {target}") and said in err[0], err
    assert not wrote


def test_an_implausible_csv_curve_is_warned_of_as_the_same_curve_typed_in(tmp_path):
    """Ratios 1.2-1.0 (a wheel travel per stroke no bike has): the typed lists were warned of, the
    same curve as a CSV passed silently. One check for both, the CSV's naming the file."""
    import warnings

    w, r = [0.0, 30.0, 60.0], [1.2, 1.1, 1.0]  # needs 52.6 mm of stroke: the SST's 65 mm shock
    (tmp_path / "lr.csv").write_text("".join(f"{a},{b}\n" for a, b in zip(w, r)))

    def said(leverage):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            spec_mod.load(str(bike(tmp_path, leverage, f"b{len(leverage)}.toml")))
        return [str(x.message) for x in caught if "leverage" in str(x.message) and "1.2" in str(x.message)]

    typed = said(f"wheel_travel_mm = {w}\nratio = {r}")
    from_csv = said('csv = "lr.csv"')
    assert len(typed) == 1 and "leverage.ratio = 1.2 (of the list) is outside 1.5-4.5" in typed[0], typed
    assert len(from_csv) == 1, from_csv
    assert from_csv[0].startswith(f"leverage.csv ({tmp_path / 'lr.csv'}): ratio 1.2 (a row of the CSV) is outside "
                                  f"1.5-4.5"), from_csv


def test_a_csv_curve_not_from_zero_is_refused_naming_the_csv(tmp_path, capsys):
    (tmp_path / "lr.csv").write_text("5,3.1\n100,2.6\n")
    path = bike(tmp_path, 'csv = "lr.csv"')
    assert main(["bike", str(path), "flat", "--speed", "4", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mtbmj: error: leverage.csv ({tmp_path / 'lr.csv'}): wheel_travel_mm: must start at 0 mm, "
                   f"got 5"], err
    assert not (tmp_path / "out").exists()

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

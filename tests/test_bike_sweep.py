"""A bike sweep (issue 40: `mtbmj sweep sst ...` answered "sst: unknown preset"; a grid of fork and
rider settings over a rock garden had to be written in Python on an undocumented BikeSpec)."""
from __future__ import annotations

import csv
import json

import pytest

import mtbmj
from mtbmj.cli import main


def test_a_bike_grid_runs_each_variant_as_the_bike_command_would(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "trail", "--roll", "root:at_m=0.4", "--speed", "5", "--duration", "0.8",
                 "--vary", "rider.mass_kg=70:90:2", "--vary", "shock:fork.spring.rate_N_per_mm=70:90:2",
                 "--out", "sw", "--quiet"]) == 0
    line = capsys.readouterr().out
    assert line.startswith("sweep bike trail over root:at_m=0.4 at 5 m/s: 4 of 4 variants ran")
    rows = list(csv.DictReader((tmp_path / "sw" / "sweep.csv").open()))
    assert [(float(r["rider.mass_kg"]), float(r["shock:fork.spring.rate_N_per_mm"])) for r in rows] == [
        (70.0, 70.0), (70.0, 90.0), (90.0, 70.0), (90.0, 90.0)]
    # each row is that bike run: the heavier rider on the softer shock goes deepest at the rear
    heavy_soft = mtbmj.run_bike("trail", "root:at_m=0.4", 5.0, 0.8,
                                overrides={"rider.mass_kg": 90.0, "shock.set": {"fork.spring.rate_N_per_mm": 70.0}})
    assert float(rows[2]["max_rear_travel_mm"]) == pytest.approx(heavy_soft.summary["max_rear_travel_mm"], abs=1e-9)
    rear = {(float(r["rider.mass_kg"]), float(r["shock:fork.spring.rate_N_per_mm"])): float(r["max_rear_travel_mm"])
            for r in rows}
    assert rear[(90.0, 70.0)] > rear[(90.0, 90.0)] and rear[(90.0, 70.0)] > rear[(70.0, 70.0)]
    listing = json.loads((tmp_path / "sw" / "sweep.json").read_text())
    assert listing["variants"] == 4 and listing["failed"] == 0 and (tmp_path / "sw" / "sweep.png").is_file()


def test_the_heat_map_is_ticked_at_the_values_run(tmp_path):
    from mtbmj.sweep import bike as sweep
    from mtbmj.sweep.figure import sweep_figure

    table = sweep.run("trail", "root:at_m=0.4", 5.0, [{"rider.mass_kg": m, "fork:fork.spring.preload_N": p}
                                                       for m in (70.0, 90.0) for p in (80.0, 120.0)], 0.6)
    fig = sweep_figure(table, ["rider.mass_kg", "fork:fork.spring.preload_N"], "", sweep.OUTPUTS)
    ax = fig.axes[0]
    assert list(ax.get_xticks()) == [70.0, 90.0] and list(ax.get_yticks()) == [80.0, 120.0]


def test_bad_bike_sweeps_are_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "trail", "--speed", "5", "--vary", "rider.mass_kg=70:90:2", "--out", "a"]) == 2
    assert main(["sweep", "trail", "--roll", "root", "--speed", "5", "--vary", "rider.weight=70:90:2",
                 "--out", "b"]) == 2
    assert main(["sweep", "S12", "--roll", "root", "--vary", "fork.spring.preload_N=50:100:2", "--out", "c"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "Traceback" not in err and "--roll" in err and "rider.weight" in err
    assert list(tmp_path.iterdir()) == []


def test_a_bike_sweep_whose_every_variant_failed_says_why_and_exits_1(tmp_path, capsys):
    """A rider of -5 or -1 kg in every variant: "every variant failed (see sweep.csv)" with exit 0
    before; now the first reason on the line, exit 1, the table of reasons written."""
    from mtbmj.cli import main

    out = tmp_path / "sw"
    assert main(["sweep", "trail", "--roll", "flat", "--speed", "4", "--vary", "rider.mass_kg=-5:-1:2",
                 "--duration", "0.2", "--quiet", "--out", str(out)]) == 1
    line = capsys.readouterr().out
    assert "every variant failed (the first: rider.mass_kg: must be > 0, got -5.0; see sweep.csv)" in line, line
    assert (out / "sweep.csv").is_file()

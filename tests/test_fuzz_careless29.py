"""Careless input, round 29: what round 28 (``tests/test_fuzz_careless28.py``) left. A terrain edited by
hand with a cliff near its end: the front end's run stopped with the wheel still falling and its line gave
the peaks as if the run were whole. Terrains are written here."""
from __future__ import annotations

import json

import numpy as np

from helpers import command_said as _run


def _terrain(path, edge_m, fall_mm, length_m=60.0):
    x = np.arange(0.0, length_m + 1e-9, 0.1)
    z = np.where(x < edge_m, 0.0, -fall_mm)
    path.write_text("distance_m,height_mm\n" + "".join(f"{a:.2f},{b:.1f}\n" for a, b in zip(x, z)))
    return path



def test_a_roll_that_ends_in_the_air_says_so(tmp_path, capfd):
    """A 50 m cliff 5 m before the terrain's end: the run ends 1.2 s into the fall, the wheel about 5.6 m
    above the ground (free fall from the edge at 5 m/s: 1/2 g t^2 with t = (61 - 55) / 5 - the wheel's
    lead, less what the wheel had fallen when it started; bounded here, not fitted). The line says the
    landing is not in the run; the same terrain's cliff in mid-run with its landing on the ground
    afterwards, and a 0.3 m drop, do not."""
    cliff = _terrain(tmp_path / "cliff.csv", 55.0, 50000.0)
    status, err = _run(["roll", cliff, "--speed", "5", "--out", tmp_path / "cliff"], capfd)
    assert status == 0, err
    summary = json.loads((tmp_path / "cliff" / "summary.json").read_text())
    t_fall = (60.0 + 1.0 - 55.0) / 5.0  # the run's end less the edge's crossing, at most
    assert 1.0 < summary["in_air_at_end_mm"] / 1e3 < 0.5 * 9.81 * t_fall ** 2
    assert "the run ended with the wheel in the air" in err and "landing is not in the run" in err

    drop = _terrain(tmp_path / "drop.csv", 20.0, 300.0)
    status, err = _run(["roll", drop, "--speed", "5", "--out", tmp_path / "drop"], capfd)
    assert status == 0, err
    assert json.loads((tmp_path / "drop" / "summary.json").read_text())["in_air_at_end_mm"] is None
    assert "in the air" not in err


def test_a_passive_rider_s_crash_at_a_drop_names_the_active_rider(tmp_path, capfd):
    """A 1 m drop at 5 m/s: the passive rider (a rigid body on its limbs) goes over the bars in the air, and
    the line said only that, as if no rider could ride it; it now says the passive rider does not shift its
    weight and names --rider active, which lands it (no crash, checked here)."""
    status, said = _run(["bike", "sst", "drop:height_mm=1000", "--speed", "5", "--no-figure", "--quiet",
                         "--out", tmp_path / "passive"], capfd)
    assert status == 3, said  # a crash's exit status
    crash = json.loads((tmp_path / "passive" / "summary.json").read_text())["crash"]
    assert crash["kind"] == "over the bars"
    status, said = _run(["bike", "sst", "drop:height_mm=1000", "--speed", "5", "--no-figure",
                         "--out", tmp_path / "passive_said"], capfd)
    assert "with the passive rider" in said and "--rider active" in said
    status, said = _run(["bike", "sst", "drop:height_mm=1000", "--speed", "5", "--rider", "active", "--no-figure",
                         "--out", tmp_path / "active"], capfd)
    assert status == 0, said
    assert json.loads((tmp_path / "active" / "summary.json").read_text()).get("crash") is None
    line = said.split("; wrote")[0]  # the line, not the folder's name
    assert "crashed" not in line and "passive" not in line

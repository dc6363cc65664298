"""One result API for every rig (issue 50 item 2): ``to_csv`` writes what ``timeseries.csv`` holds,
``difference`` gives each compared column's largest |a - b| and when; written once in
``mtbmj.result.RunOutput`` for the drop, the rolling front end and the bike."""
from __future__ import annotations

import numpy as np
import pytest

import mtbmj


def _runs(rig):
    if rig == "drop":
        return mtbmj.run_drop("S1", duration=0.3), mtbmj.run_drop("S1", duration=0.3, overrides={"sled.drop_height_mm": 120})
    if rig == "roll":
        return (mtbmj.run_roll("root:at_m=0.6", 4.0, duration=0.3),
                mtbmj.run_roll("root:at_m=0.6,radius_mm=70", 4.0, duration=0.3))
    return (mtbmj.run_bike("sst", "root:at_m=0.6", 4.0, duration=0.3),
            mtbmj.run_bike("sst", "root:at_m=0.6,radius_mm=70", 4.0, duration=0.3))


@pytest.mark.parametrize("rig", ["drop", "roll", "bike"])
def test_every_rig_has_to_csv_and_difference(rig, tmp_path):
    a, b = _runs(rig)
    out = a.write(tmp_path / "run", figure=False)
    assert out
    written = a.to_csv(tmp_path / "alone.csv")
    assert written.read_bytes() == (tmp_path / "run" / "timeseries.csv").read_bytes()
    diff = a.difference(b)
    assert set(diff) == set(type(a).COMPARED) and diff
    # by hand, on the samples both share: the coarse grid's (the front end keeps finer rows where it
    # refines, at times the other run may not have)
    ra, rb = ({k: np.asarray(v) for k, v in r.raw.items()} for r in (a, b))
    ta, tb = np.round(ra["time_s"] * 1e9), np.round(rb["time_s"] * 1e9)
    grid = [np.flatnonzero(np.abs(t / 1e9 / a.info["timestep_s"] - np.round(t / 1e9 / a.info["timestep_s"])) < 1e-6)
            for t in (ta, tb)] if rig == "roll" else [np.arange(ta.size), np.arange(tb.size)]
    n = min(grid[0].size, grid[1].size)
    ia, ib = grid[0][:n], grid[1][:n]
    assert np.array_equal(ta[ia], tb[ib])
    key = type(a).DIFFERENCE_KEY
    for column, entry in diff.items():
        gap = np.abs(ra[column][ia] - rb[column][ib])
        assert entry[key] == pytest.approx(gap.max(), abs=0.0)
        assert entry["at_time_s"] == pytest.approx(ra["time_s"][ia][int(np.argmax(gap))])
    assert any(entry[key] > 0 for entry in diff.values())  # the two runs differ: the check can fail
    assert all(entry[key] == 0.0 for entry in a.difference(a).values())


def test_runs_on_different_grids_are_not_differenced():
    a = mtbmj.run_drop("S1", duration=0.2)
    b = mtbmj.run_drop("S1", duration=0.2, overrides={"solver.timestep_s": 5e-5})
    with pytest.raises(ValueError, match="same time grid"):
        a.difference(b)

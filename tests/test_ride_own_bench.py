"""benchmarks/ride_own.py (does the whole bike ride its own reconstruction, issue 51) and its rows in
docs/measured.md (benchmarks/report.py): what it reads at a crash, on terrains, records and results
written here (no ride is read, nothing simulated)."""
from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from helpers import bench_module





@pytest.fixture(scope="module")
def bench():
    yield bench_module("mtbmj_bench_ride_own", "ride_own.py")
    sys.modules.pop("mtbmj_bench_ride_own", None)


@pytest.fixture(scope="module")
def report():
    yield bench_module("mtbmj_bench_report_ride_own", "report.py")
    sys.modules.pop("mtbmj_bench_report_ride_own", None)


def step_terrain(at_m: float, rise_m: float, over_m: float = 0.05):
    """Level ground with one step of ``rise_m`` over ``over_m`` starting at ``at_m`` (1 cm points)."""
    x = np.arange(0.0, at_m + 20.0, 0.01)
    z = np.clip((x - at_m) / over_m, 0.0, 1.0) * rise_m
    return x, z


def test_a_step_before_the_crash_is_read_as_one_and_level_ground_as_none(bench):
    x, z = step_terrain(10.0, 0.3)
    there = bench.terrain_there(x, z, 10.8)
    assert there["step_m"] == pytest.approx(0.3, abs=1e-9)
    assert there["slope_max_deg"] == pytest.approx(math.degrees(math.atan(0.3 / 0.05)), abs=0.5)
    assert there["height_m"] == pytest.approx(0.3)
    # a drop reads as a fall, with its sign
    assert bench.terrain_there(x, -z, 10.8)["step_m"] == pytest.approx(-0.3, abs=1e-9)
    # the naive baseline: level ground has neither
    flat = bench.terrain_there(x, 0.0 * z, 10.8)
    assert flat["step_m"] == 0.0 and flat["slope_max_deg"] == 0.0
    # a step further back than the 2 m looked at is not there
    assert bench.terrain_there(x, z, 12.5)["step_m"] == pytest.approx(0.0, abs=1e-12)


def test_where_maps_the_ride_time_to_its_distance_and_reads_the_record_there(bench):
    t = np.arange(0.0, 20.0, 0.01)
    fork = np.where(np.abs(t - 8.0) < 0.2, 150.0, 40.0)  # the ride's fork deep at 8 s, the rear not
    series = {"time_s": t, "speed_m_per_s": np.full_like(t, 5.0), "fork_mm": fork, "rear_mm": np.full_like(t, 50.0)}
    x, z = step_terrain(43.0, 0.3)  # the terrain CSV starts 3 m before the ride: the step at the ride's 40 m
    rec = {"terrain_csv_lead_in_m": 3.0, "left_out": [{"start_s": 0.0, "end_s": 5.0}],
           "beyond_trail": [{"start_s": 7.0, "end_s": 7.5}, {"start_s": 15.0, "end_s": 16.0}]}
    got = bench.where(8.1, None, rec, series, {"distance_m": x, "height_mm": 1000.0 * z})
    assert got["ride_m"] == pytest.approx(40.5, abs=0.06)
    assert got["terrain"]["step_m"] == pytest.approx(0.3, abs=1e-9)
    assert got["record"]["fork_max_mm"] == 150.0 and got["record"]["rear_max_mm"] == 50.0
    assert got["record"]["record_runs_on_s"] == pytest.approx(19.99 - 8.1)
    assert got["speed_from"] == "a window's"
    assert got["beyond_trail"] == [{"start_s": 7.0, "end_s": 7.5}]  # the one within 3 s
    assert bench.where(4.0, None, rec, series, {"distance_m": x, "height_mm": 0 * x})["speed_from"].startswith("held")


def test_the_rows_say_where_each_crash_was_and_what_rode_through(report):
    there = {"terrain": {"height_m": 0.31, "slope_max_deg": 80.5, "step_m": 0.3},
             "record": {"fork_max_mm": 150.0, "rear_max_mm": 50.0, "record_runs_on_s": 11.9}}
    rides = [{"ride": "A.SST", "folder": "sst", "seconds": 100.0, "crash": None,
              "advise": [{"calibrated": False, "crash": "crashed: over the bars at 42.000 s (pitch -45.0 deg)",
                          "ride_s": 41.7, "ride_m": 232.0, "ridden_anyway": True, **there},
                         {"calibrated": True, "crash": None}]},
             {"ride": "B.SST", "folder": "sst_v2", "seconds": 60.0,
              "crash": {"kind": "looped out", "time_s": 9.0, "pitch_deg": 60.0, "part": None},
              "at": {"ride_s": 8.1, "ride_m": 40.5, "speed_m_per_s": 5.0, "speed_from": "a window's",
                     "beyond_trail": [{"start_s": 7.0, "end_s": 7.5}], **there}},
             {"ride": "C.SST", "folder": "sst_v2", "refused": "C.SST through sst: no speed: ..."}]
    d = {"command": "python benchmarks/ride_own.py --shared --out benchmarks/results/ride_own.json", "near_s": 3.0,
         "rides": rides}
    rows = report.ride_own_rows(d)["ride_own"]
    cells = {r.figure: r.measured for r in rows}
    assert cells["sst/A.SST (100 s): `mtbmj reconstruct`, then `mtbmj bike`"] == "rides it all"
    assert cells["sst/A.SST (100 s): as advise, the file's springs"].startswith(
        "**over the bars** at 41.7 s, 232 m (refused by its check; ridden); ground 0.310 m, steepest 80 deg, "
        "0.30 m in 0.2 m; its record: fork 150, rear 50.0 mm, 11.9 s more")
    assert cells["sst/A.SST (100 s): as advise, calibrated"] == "rides it all"
    assert cells["sst_v2/B.SST (60.0 s): `mtbmj reconstruct`, then `mtbmj bike`"] == (
        "**looped out** at 8.10 s, 40.5 m, 5.0 m/s (a window's); ground beyond trail within 3 s")
    assert "sst_v2/B.SST (60.0 s): there (the commands)" in cells
    assert cells["sst_v2/C.SST: reconstruct"] == "refused: no speed: ..."
    assert all(len(r.measured) <= 200 for r in rows)

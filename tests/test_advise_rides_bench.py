"""benchmarks/advise_rides.py (the shared rides' calibrations and advice, issue 52) and its rows in
docs/measured.md (benchmarks/report.py): whether the rides' intervals agree, and each ride's cells,
on results written here by hand (no ride is read, nothing simulated)."""
from __future__ import annotations

import sys

import pytest

from helpers import bench_module





@pytest.fixture(scope="module")
def bench():
    yield bench_module("mtbmj_bench_advise_rides", "advise_rides.py")
    sys.modules.pop("mtbmj_bench_advise_rides", None)


@pytest.fixture(scope="module")
def report():
    yield bench_module("mtbmj_bench_report_rides", "report.py")
    sys.modules.pop("mtbmj_bench_report_rides", None)


def spring(scale, low, high, file=6.5, unit="N/mm", key="fork:fork.spring.rate_N_per_mm"):
    return {"scale": scale, "low": low, "high": high, "file": file, "unit": unit, "key": key,
            "calibrated": file * scale, "calibrated_low": file * low, "calibrated_high": file * high}


def rear(scale, low, high):
    return spring(scale, low, high, 456.8, "lb/in", "shock.spring_rate_lb_per_in")


CALS = {  # three rides: the fronts A and B overlap, C apart from both; the rears all share 1.10-1.20
    "A.SST": {"springs": {"front": spring(0.60, 0.55, 0.69), "rear": rear(1.2, 1.05, 1.40)}},
    "B.SST": {"springs": {"front": spring(0.62, 0.56, 0.70), "rear": rear(1.1, 1.00, 1.20)}},
    "C.SST": {"springs": {"front": spring(0.80, 0.71, 0.92), "rear": rear(1.15, 1.10, 1.30)}},
}


def test_the_range_every_interval_holds_and_each_pair(bench):
    agree = bench.agreement(CALS)
    assert agree["front"]["common"] is None  # 0.71 (C's low) above 0.69 (A's high)
    assert agree["front"]["pairs"] == {"A.SST B.SST": True, "A.SST C.SST": False, "B.SST C.SST": False}
    assert agree["rear"]["common"] == [pytest.approx(1.10), pytest.approx(1.20)]
    assert all(agree["rear"]["pairs"].values())
    # one ride alone agrees with nothing: no end is compared
    assert bench.agreement({"A.SST": CALS["A.SST"]}) == {}


def test_each_ride_gives_its_calibration_and_its_advice_or_refusal(report, bench):
    rides = [{"ride": "A.SST", "version": 3, "seconds": 103.3, "calibration": CALS["A.SST"],
              "advice_refused": "A.SST: its reconstruction fails its own check (rear predicted within 21 % of the "
                                "travel used, 5 % of the ride checked; advice needs within 60 % over 10 %): ..."},
             {"ride": "B.SST", "version": 3, "seconds": 50.0, "calibration_refused": "B.SST: no fork spring rate ...",
              "advice": {"answer": "change", "recommendation": {"setting": {"adjuster": "rebound damping",
                                                                            "from": 700.0, "to": 560.0}}}}]
    d = {"command": "python benchmarks/advise_rides.py --out benchmarks/results/advise_rides.json", "rides": rides,
         "agreement": bench.agreement(CALS)}
    rows = report.advise_rides_rows(d)["advise"]
    cells = {r.figure: r.measured for r in rows}
    assert cells["A.SST (v3, 103 s): the springs calibrated, 95 %"] == (
        "fork 3.90 N/mm (3.58–4.48; x0.600 of the file's 6.50); shock 548 lb/in (480–640; x1.20 of the file's 457)")
    assert cells["A.SST (v3, 103 s): the advice"] == (
        "refused: its reconstruction's check (rear predicted within 21 % of the travel used, 5 % of the ride checked)")
    assert cells["B.SST (v3, 50.0 s): the springs calibrated, 95 %"].startswith("calibration refused: no fork spring")
    assert cells["B.SST (v3, 50.0 s): the advice"] == "rebound damping 700 -> 560"
    assert cells["the 3 rides' front spring scales: the range every interval holds"].startswith("none; ")
    assert all(len(r.measured) <= 200 for r in rows)

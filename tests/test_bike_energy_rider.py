"""The energy balance with the active rider's muscles (issue 54 item 5, mtbmj/bike/energy.py): off a
1 m drop at 5 m/s and over a rock garden (a profile written in tests/helpers.py, seven rocks
50-110 mm), the change of MuJoCo's kinetic and gravitational energy and of the rider's pins and end
stops equals the work of the muscles, the tissue's and the pins' damping, the saddle, the fork, the
shock, the tyres and the drive within 1 % of the work done; without the muscles' positive or negative
work it does not."""
from __future__ import annotations

import numpy as np
import pytest

from helpers import rock_garden
from mtbmj.bike import rider_control as rc
from mtbmj.bike.run import run_bike

TOLERANCE_PCT = 1.0  # the number


@pytest.fixture(scope="module", params=["drop", "rocks"])
def ridden(request, tmp_path_factory):
    if request.param == "drop":
        return run_bike("sst", "drop:height_mm=1000", 5.0, rider="active")
    path = rock_garden(tmp_path_factory.mktemp("rocks") / "rocks.csv")
    return run_bike("sst", str(path), 5.0, duration=1.5, rider="active")


def test_the_balance_closes_with_the_muscles_work(ridden):
    e = ridden.summary["energy"]
    assert ridden.summary["crash"] is None
    assert e["work_done_J"] > 500.0  # the feature was met: hundreds of joules through tyres, dampers and muscles
    # the muscles did work both ways: positive (pushing) and negative (absorbing)
    assert e["muscle_positive_J"] > 5.0 and e["muscle_negative_J"] < -5.0
    # no more positive work than the power limit gives over the run
    assert e["muscle_positive_J"] <= rc.POWER_W * e["duration_s"]
    # every applied generalised force is named by a term
    assert e["unsplit_W"] < 1e-6
    # the closure: what the energy changed by against the work of the forces
    assert abs(e["energy_change_J"] - e["work_total_J"]) <= TOLERANCE_PCT / 100.0 * e["work_done_J"]
    assert e["error_pct"] < TOLERANCE_PCT
    assert "muscle work" in ridden.headline() and "energy balance error" in ridden.headline()


def test_the_balance_misses_without_the_muscles(ridden):
    """The check can fail: leave the muscles' positive or their negative work out and the balance
    misses by more than 1 %. (Their net work is not the test: off the drop it is -13 J of 3532 J
    done, 801 J positive against -814 J negative, since the rider meets the bike's nose-up pitch
    after the drop's pose; it had been -101.5 J.)"""
    e = ridden.summary["energy"]
    for part in ("muscle_positive_J", "muscle_negative_J"):
        without = e["energy_change_J"] - (e["work_total_J"] - e[part])
        assert abs(without) > TOLERANCE_PCT / 100.0 * e["work_done_J"], part
    # and the muscles' two signs do not cancel into nothing
    assert abs(e["muscle_work_J"]) < e["muscle_positive_J"] - e["muscle_negative_J"]


def test_the_suspension_springs_stored_energy_is_their_forces_work(ridden):
    """The fork's and the shock's stored energy (the laws' own ``elastic_energy``, in the balance)
    against the work of their spring forces at rest along the run's travel and stroke, summed here
    by the trapezoid rule over the samples: within 1 % of that work's throughput."""
    e = ridden.summary["energy"]["stored_change_J"]
    p = ridden.prepared
    raw = ridden.raw
    for key, law, column in (("fork_spring", p.fork_law, "front_travel_mm"), ("shock_spring", p.shock_law, "stroke_mm")):
        x = np.asarray(raw[column]) / 1000.0
        f = np.array([law.spring.force(float(v), 0.0) for v in x])
        parts = 0.5 * (f[1:] + f[:-1]) * np.diff(x)
        assert np.sum(np.abs(parts)) > 50.0  # the spring worked
        assert abs(e[key] - np.sum(parts)) <= 0.01 * np.sum(np.abs(parts)), (key, e[key], np.sum(parts))


@pytest.mark.parametrize("how", ["seated", "pedalling"])
def test_the_balance_closes_seated_and_pedalling(how, tmp_path):
    """Seated, the saddle's one-sided push does work (left out, the balance misses by more than
    1 %); pedalling, the driving leg's muscles do the crank's work (mtbmj/bike/pedal_leg.py): both
    close, and pedalling without the driving leg's work the balance misses."""
    path = rock_garden(tmp_path / "rocks.csv")
    if how == "seated":
        res = run_bike("sst", str(path), 5.0, duration=1.5, rider="active", seated=True)
    else:
        res = run_bike("sst", str(path), None, duration=1.5, rider="active", pedal=(80, 250))
    e = res.summary["energy"]
    assert e["unsplit_W"] < 1e-6
    assert abs(e["energy_change_J"] - e["work_total_J"]) <= TOLERANCE_PCT / 100.0 * e["work_done_J"]
    if how == "seated":
        saddle = e["work_J"]["saddle"]
        assert saddle < 0.0  # the saddle's damping takes energy
        assert abs(e["energy_change_J"] - (e["work_total_J"] - saddle)) > TOLERANCE_PCT / 100.0 * e["work_done_J"]
    else:
        assert e["pedal_leg_J"] > 100.0  # the rider's legs put the pedalling's energy in
        assert e["muscle_positive_J"] >= e["crank_J"] > 100.0
        assert abs(e["energy_change_J"] - (e["work_total_J"] - e["pedal_leg_J"])) > TOLERANCE_PCT / 100.0 * e["work_done_J"]

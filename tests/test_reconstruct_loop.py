"""The reconstruct-then-ride loop on a ride the engine itself made: the terrain found from the ride's fork
record (``mtbmj.ride.reconstruct``) ridden again by the same MuJoCo bike at the same setting
(``mtbmj.ride.advise``'s recorded-setting run) should give back the ride's own metrics. It is the least a
model that advises from a ride owes: here nothing is unknown (the bike, its setting, the speed held, the
ground an ISO 8608 class C profile), so every miss is the loop's own.

What the loop shares with the ride: the engine that rides the terrain found (the same MuJoCo bike). What
it does not: the reconstruction's own whole bike (``reconstruct_bike``: point-contact tyres without
damping, vertical motion, the frame's pitch carrying the bike's masses fore and aft), through which the
terrain is found, and the record's integer counts.

Measured (2026-12-05, ``carried_inertia`` in the reconstruction's whole bike): the sags come back (front
23.7 % for 23.7, rear 28.8 for 28.8), and so do the velocities (p95 compression 180.7 mm/s for the ride's
181.0 at the fork, 158.4 for 160.0 at the rear; high-speed share 23.9 % for 24.8 at the fork) and the fork's
maximum (30.5 % for 29.4). Before it the loop doubled them (p95 378 mm/s for 181 at the fork, 340 for 160 at
the rear; high-speed share 57 % for 25 %; fork max 38 % for 29 %): the reconstruction's frame pitched about
its own body's inertia alone (3.2 kg m^2) where the engine's carries the rider fore and aft on it (12.0
more), so it answered the ground at 2-9 Hz with 0.4-0.6 times the engine's fork travel and the terrain it
found had 8.6 times the true power at 1-2 cycles/m (tests/test_reconstruct_pitch.py)."""
from __future__ import annotations

import json

import pytest

from mtbmj.cli import main
from mtbmj.rolling import terrain as terrain_mod

from helpers import engine_ride, reconstruction_passing


@pytest.fixture(scope="module")
def looped(tmp_path_factory):
    """(the ride's measured metrics, the loop's simulated ones) of a 37 s ride at 6 m/s over ISO 8608 class C."""
    folder = tmp_path_factory.mktemp("loop")
    file, sst, _ = engine_ride(folder, terrain_mod.make("iso8608:class=C,seed=5,length_m=400,at_m=15"))
    out = folder / "advice"
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(file), "--no-calibrate", "--workers", "1", "--out", str(out)]) == 0
    d = json.loads((out / "advice.json").read_text())
    return d["recorded_setting"]["measured"], d["recorded_setting"]["simulated"]


@pytest.mark.slow  # a 40 s engine run and one advice on 37 s of it: about a minute
def test_the_loop_gives_back_the_ride_s_sags(looped):
    rec, sim = looped
    for end in ("front", "rear"):
        assert sim[end]["dynamic_sag_percent"] == pytest.approx(rec[end]["dynamic_sag_percent"], abs=2.0), end


@pytest.mark.slow
def test_the_loop_gives_back_the_ride_s_speeds_and_depth(looped):
    rec, sim = looped
    for end in ("front", "rear"):
        assert sim[end]["p95_compression_mm_per_s"] == pytest.approx(rec[end]["p95_compression_mm_per_s"], rel=0.25), end
        assert sim[end]["max_travel_percent"] == pytest.approx(rec[end]["max_travel_percent"], abs=5.0), end


@pytest.fixture(scope="module")
def shipped():
    """(the shipped ride's measured metrics, the calibrated recorded setting's simulated ones over its
    reconstruction: what every advice compares its candidates with), the reconstruction's check set aside."""
    from argparse import Namespace

    import numpy as np

    from mtbmj.cli.telemetry import ride_record
    from mtbmj.ride import advise
    from mtbmj.ride.advice_rules import ride_metrics

    rec = ride_record("example", Namespace(bike="sst", fork_max_mm=None, shock_max_mm=None))
    with reconstruction_passing():
        ride = advise.prepare(rec, "sst", candidates=False)
    run = advise.simulate(ride.bike, ride.base_over, ride.terrain, ride.speed, ride.sim_s, "recorded", ride.lead_s,
                          ride.profile)
    t = ride.rec.t
    keep = t - t[0] <= ride.sim_s
    assert np.count_nonzero(keep) > 0.9 * t.size  # the whole ride, not a piece of it
    return (ride_metrics(t[keep], ride.rec.front[keep], ride.rec.rear[keep], run.metrics["front"]["travel_mm"],
                         run.metrics["rear"]["travel_mm"]), run.metrics)


@pytest.mark.slow  # the shipped ride's calibration, reconstruction and one 76 s run: about half a minute
def test_the_shipped_ride_s_speeds_come_back_at_its_recorded_setting(shipped):
    """A real ride, not made here: the shipped 00649 (SST bike, 76 s) at its recorded setting, calibrated.
    The same criteria as the engine's own ride above: the p95 compression speeds within 25 %, the sags
    within 2 points. Measured (2026-12-05): p95 420.6 mm/s at the fork and 429.2 at the rear for the
    ride's 435.7 and 497.5; dynamic sag 28.9 % and 25.6 for 27.5 and 25.7. Before the reconstruction's
    pitch carried the masses fore and aft (``reconstruct_bike.carried_inertia``): 739 and 573 mm/s."""
    rec, sim = shipped
    for end in ("front", "rear"):
        assert sim[end]["p95_compression_mm_per_s"] == pytest.approx(rec[end]["p95_compression_mm_per_s"], rel=0.25), end
        assert sim[end]["dynamic_sag_percent"] == pytest.approx(rec[end]["dynamic_sag_percent"], abs=2.0), end


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the shipped ride's depth does not come back at its recorded setting: the model's "
                                       "fork reaches 75.8 % of its travel for the ride's 66.4, the rear 67.3 for 79.1 (before "
                                       "carried_inertia: the fork 97.8)")
def test_the_shipped_ride_s_depth_comes_back_at_its_recorded_setting(shipped):
    rec, sim = shipped
    for end in ("front", "rear"):
        assert sim[end]["max_travel_percent"] == pytest.approx(rec[end]["max_travel_percent"], abs=5.0), end

"""The rider's slow load kept out of a flight (issue 51 item 2; ``reconstruct_inverse.slow_load`` with
``FLIGHTS_OUT_OF_SLOW_LOAD``, off by default: docs/rolling.md, "pit", says why): the fork's force beyond
its static load low-passed at 0.3 Hz with each flight, its take-off's push and its landing's impact
bridged from the ground either side, and nothing in the air (ballistic). Low-passed through them (the
default), a hard landing's kilonewtons leaked back into the flight before it: on 00100.SST 199-286 N in
the air.

The signal of the first test is written here (a slow load, a flight, a landing's blow); the ride of the
second is made by the independent whole bike of tests/helpers.py (``whole_bike_ride``: its own
equations and integrator; what it shares with the package is listed in
tests/test_reconstruct_whole_bike.py's module doc) over a course made here: a 1 m drop, a kicker 0.8 m
high (a jump back to the level it left) and a 0.6 m drop, on ISO 8608 class C roughness. Seed 7 and
the course were the second tried (seed 5 with a 0.5 m kicker, a 0.5 m drop and a tabletop first: there the
old filter left 33-38 N in the air and the grounds found were within 0.01 m RMS of each other).
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from helpers import SpeedProfile, whole_bike_ride

DT = 1e-3


def _written():
    """(t, the force beyond the static load N, the true slow load N, the airborne mask): 20 s of a
    slow load 60 + 40 sin(2 pi t / 9) N on the ground with a 12 Hz wobble of 150 N, a 0.47 s flight at
    10 s (the tyre carries nothing: the force beyond its static 450 N is -450 N), then a landing's blow
    (3.8 kN, the 00100 pit's, for 70 ms: the momentum its weight lost over the flight given back, so
    over the whole jump the force beyond the slow load adds to 5 N s)."""
    t = np.arange(0.0, 20.0, DT)
    slow = 60.0 + 40.0 * np.sin(2 * np.pi * t / 9.0)
    x = slow + 150.0 * np.sin(2 * np.pi * 12.0 * t)
    air = (t >= 10.0) & (t < 10.47)
    x[air] = -450.0
    x[(t >= 10.47) & (t < 10.54)] = 3800.0
    return t, x, slow, air


def test_a_landing_s_blow_stays_out_of_the_flight_and_the_ground_s_slow_load_is_kept(monkeypatch):
    """In the air the slow load is nothing (ballistic); on the ground from 0.5 to 3 s either side of
    the jump it is the written one within 15 N. Measured when written: the air 0 N, the ground off by
    at most 3.7 N. The plain low-pass (the code before) reads 54-110 N in the air (the ground's load
    about it, 86-94 N, and the blow's and the flight's wobble) and is off by up to 36 N on the ground."""
    from mtbmj.ride import reconstruct_inverse
    from mtbmj.ride.reconstruct_inverse import lowpass, slow_load

    t, x, slow, air = _written()
    assert np.array_equal(slow_load(x, air, DT), lowpass(x, DT))  # off by default: the plain low-pass
    monkeypatch.setattr(reconstruct_inverse, "FLIGHTS_OUT_OF_SLOW_LOAD", True)
    near = ((t >= 7.0) & (t < 9.5)) | ((t >= 11.5) & (t < 13.5))
    found = slow_load(x, air, DT)
    assert np.max(np.abs(found[air])) == 0.0
    assert np.max(np.abs(found - slow)[near]) <= 15.0, np.max(np.abs(found - slow)[near])
    plain = lowpass(x, DT)  # the naive baseline, the code before: it fails both
    assert np.min(plain[air]) > 50.0, plain[air].min()
    assert np.max(np.abs(plain - slow)[near]) > 15.0
    # without the flight the two are the same filter (nothing to keep out)
    assert np.array_equal(slow_load(x, np.zeros(t.size, bool), DT), plain)


PROFILE = SpeedProfile(6.0, 0.5, 20.0)
FEATURES = (("drop", 40.0, 1.0), ("kicker", 100.0, 0.8), ("drop", 150.0, 0.6))
DROPS = ("drop_1", "drop_0.6")
WITHIN_M = 0.1  # a drop's ground over its flight and landing within this RMS of the made one


def _reconstruct(ride):
    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(ride["sst"], **decoding(SimpleNamespace(bike=str(ride["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    return reconstruct.reconstruct(record, str(ride["bike"]))


def _errors(made, rec):
    """Per feature, the RMS (m) of the ground found less the made one over 0.3 s before the front wheel
    reaches it to 1.2 s after (its flight and landing), both from the window's start."""
    t = rec.t
    dt = t[1] - t[0]
    truth = made["h"](PROFILE.along(t))
    out = {}
    for name, at in made["features"].items():
        k = int(np.argmax(PROFILE.along(t) >= at))
        i, j = k - int(round(0.3 / dt)), k + int(round(1.2 / dt))
        e = (rec.ground[i:j] - rec.ground[i]) - (truth[i:j] - truth[i])
        out[name] = float(np.sqrt(np.mean(e * e)))
    return out


@pytest.mark.slow  # a 28 s made ride and two reconstructions: about 20 s
def test_a_hard_landing_s_force_kept_out_of_the_flight_finds_the_drop_s_ground(tmp_path, monkeypatch):
    """Over each drop's flight and landing the ground found is within ``WITHIN_M`` RMS of the made one,
    and the rear predicted no worse than with the slow load low-passed through the flights. Measured
    when written: the 1 m drop 0.051 m (the level read -1.02 and kept), the 0.6 m drop 0.032, the kicker
    0.197 (0.191 before: not better, not asserted); the rear predicted 5.21 mm RMS. With the slow load
    low-passed through the flights (the default, the naive baseline) the 1 m drop's ground is 0.757 m
    off (its flight, 6.30-6.70 s, not read as a drop's edge: the level above kept after it), the 0.6 m
    drop's 0.052, the rear 5.27 mm: it fails. Since a drop's edge is judged on the ground less the drift
    removal's own lift ahead of the fall (``reconstruct_flight.edge_flights``, drop51) the default finds the
    1 m drop too (0.064 m, the 0.6 m drop 0.058 when measured): the baseline that fails is now the default
    with the edge judged on the ground as found (the code before both), monkeypatched back."""
    from mtbmj.ride import reconstruct_flight, reconstruct_inverse
    from mtbmj.ride.reconstruct_inverse import edge, flights

    made = whole_bike_ride(tmp_path / "ride", seed=7, seconds=28.0, profile=PROFILE, features=FEATURES)
    assert set(made["features"]) == {"drop_1", "kicker", "drop_0.6"}
    before = _reconstruct(made)  # the default: the slow load low-passed through the flights
    with monkeypatch.context() as m:  # the code before both: the edge judged on the ground as found
        m.setattr(reconstruct_flight, "edge_flights",
                  lambda found, air, dt: [(p, q) for p, q in flights(air, dt) if edge(found, p, q, dt)])
        old = _errors(made, _reconstruct(made))
    monkeypatch.setattr(reconstruct_inverse, "FLIGHTS_OUT_OF_SLOW_LOAD", True)
    now = _reconstruct(made)
    errors = _errors(made, now)
    assert all(errors[name] <= WITHIN_M for name in DROPS), errors
    assert not all(old[name] <= WITHIN_M for name in DROPS), old  # the code before fails the check above
    assert now.checks()["rear_predicted_rms_mm"] <= before.checks()["rear_predicted_rms_mm"] + 0.1

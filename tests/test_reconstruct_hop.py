"""A hop found where the fork stays short of its top-out in the air (issue 51 item 2): take-off read
from the tyre's force falling toward zero for long enough (``reconstruct_inverse.unloaded``:
``LIGHT_SHARE`` of the static load for ``LIGHT_S``), not only from the fork at its top-out. The rule
is off by default (``LIGHT_S`` infinite: on the shared rides it moved crashes rather than clearing
them, docs/rolling.md); these tests turn it on at ``ON_S`` and show what it does, and a strict xfail
holds the default's miss.

The ride is made by the independent whole bike of tests/helpers.py (``whole_bike_ride``: its own
equations and integrator) over a course made here: a rock garden (rocks up to 0.1 m, ISO class C
roughness under it) and a kicker (0.3 m up over 1.5 m, the ground back at once: a flight of 0.33 s
to a landing at the level it left from). Its fork's record is written 6 mm deeper than the made
fork's travel (the sensor's zero 6 mm into the stroke): in the air the record stays 6 mm short of
full extension, as 00642.SST's and 00643.SST's forks did over their hops (6-7 mm), so the tyre's
force the inverse reads there is the law's at 6 mm (about 80 N of 425 at rest), never zero, and the
rule before (a flight only where the force reads zero or the fork hangs on its top-out) found none.
The seed and speed are the flight tests' (tests/test_reconstruct_flight.py), not tuned.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from helpers import RATIO, SpeedProfile, whole_bike_ride, write_v3

PROFILE = SpeedProfile(6.0, 0.5, 20.0)
FEATURES = (("rocks", 15.0, 0.1), ("kicker", 70.0, 0.3))
ON_S = 0.1  # the rule on: a flight of 0.1 s lifts a wheel g T^2 / 8 = 12 mm over its chord, its tyre's deflection
SHORT_MM = 6.0  # the record's fork this far short of full extension in the air
ENDS_S = 0.02  # the kicker's flight found within this of the made one's take-off and landing
UNDER_M = 0.1  # the ground found under it within this of the made one, on average (measured 0.080; the default 0.137)


def _flights(made):
    """(start s, end s) where the made front tyre carries nothing."""
    from mtbmj.ride.reconstruct_inverse import runs

    t, f = made["tyre_t"], made["front_tyre_N"]
    return [(float(t[a]), float(t[min(b, t.size - 1)])) for a, b in runs(f <= 0.0)]


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    from mtbmj.bike import spec as spec_mod

    path = tmp_path_factory.mktemp("hop")
    ride = whole_bike_ride(path, seed=5, seconds=20.0, profile=PROFILE, features=FEATURES)
    spec = spec_mod.load(str(ride["bike"]))
    ride["short_sst"] = write_v3(path / "short.SST", np.clip(ride["fork_mm"], 0, None) + SHORT_MM,
                                 np.clip(ride["rear_mm"], 0, None) / RATIO, spec.sensors, 1000)
    return ride


def _reconstruct(made):
    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(made["short_sst"], **decoding(SimpleNamespace(bike=str(made["bike"]), fork_max_mm=None,
                                                                               shock_max_mm=None)))
    return reconstruct.reconstruct(record, str(made["bike"]))


def _kicker_flight(made):
    """The made flight off the kicker: the first of 0.2 s or more after the front reaches its foot."""
    t = made["t"]
    at = float(t[int(np.argmax(PROFILE.along(t) >= made["features"]["kicker"]))])
    return next((a, b) for a, b in _flights(made) if b - a >= 0.2 and a >= at)


def _under(made, rec, a: float, b: float) -> float:
    """The ground found's mean distance (m) from the made one over the flight ``a``..``b`` (s), the two
    aligned on their median over the 1 s before the kicker's foot."""
    t = rec.t
    truth = made["h"](PROFILE.along(t))
    foot = int(np.argmax(PROFILE.along(t) >= made["features"]["kicker"]))
    dt = float(t[1] - t[0])
    before = slice(foot - int(round(1.0 / dt)), foot)
    off = float(np.median(rec.ground[before] - truth[before]))
    over = (t >= a) & (t <= b)
    return float(np.mean(np.abs(rec.ground[over] - off - truth[over])))


def test_a_hop_with_the_fork_short_of_top_out_is_found(made, monkeypatch):
    """With the rule on (``LIGHT_S`` = ``ON_S``) the kicker's flight (0.33 s, the record's fork 6 mm short
    in the air) is found within ``ENDS_S`` at both ends and the ground under it is within ``UNDER_M`` of
    the made one on average (the chord from the lip, the made ground level under it); the default (the
    rule off, the code before) finds no flight there and leaves the wheel's path as the ground (further
    off than ``UNDER_M``)."""
    from mtbmj.ride import reconstruct_inverse

    a, b = _kicker_flight(made)
    old = _reconstruct(made)
    under_old = _under(made, old, a, b)
    assert not [(p, q) for p, q in old.jumps if p < b and q > a]
    assert under_old > UNDER_M
    monkeypatch.setattr(reconstruct_inverse, "LIGHT_S", ON_S)
    rec = _reconstruct(made)
    found = [(p, q) for p, q in rec.jumps if p < b and q > a]
    assert len(found) == 1 and abs(found[0][0] - a) <= ENDS_S and abs(found[0][1] - b) <= ENDS_S, (a, b, found)
    assert _under(made, rec, a, b) <= UNDER_M


@pytest.mark.xfail(strict=True, reason="the light-tyre rule is off by default (LIGHT_S inf): measured, the default "
                                       "finds no flight over the made kicker (0.33 s, the fork 6 mm short) and "
                                       "the ground under it is 0.137 m off the made one on average (0.080 with "
                                       "the rule on); on, it moved the shared rides' crashes (docs/rolling.md)")
def test_the_default_finds_a_hop_with_the_fork_short_of_top_out(made):
    a, b = _kicker_flight(made)
    rec = _reconstruct(made)
    assert [(p, q) for p, q in rec.jumps if p < b and q > a]


def test_no_flight_is_found_on_the_rocks_where_the_wheel_stays_down(made, monkeypatch):
    """Every flight found of 50 ms or more lies within 50 ms of one the made front tyre flew (the rock
    garden throws it into several: each found is one); a deliberately loose rule (a tyre below 90 % of
    its static load for 20 ms a flight) finds flights where the made wheel stayed down."""
    from mtbmj.ride import reconstruct_inverse

    truth = _flights(made)
    monkeypatch.setattr(reconstruct_inverse, "LIGHT_S", ON_S)

    def false(rec):
        return [(p, q) for p, q in rec.jumps if q - p >= 0.05
                and not any(c - 0.05 <= q and p <= d + 0.05 for c, d in truth)]

    assert false(_reconstruct(made)) == []
    monkeypatch.setattr(reconstruct_inverse, "LIGHT_S", 0.02)
    monkeypatch.setattr(reconstruct_inverse, "LIGHT_SHARE", 0.9)
    assert false(_reconstruct(made))


def test_a_light_tyre_is_a_flight_only_long_enough_and_mid_record():
    """``unloaded`` on a force written here (1 kHz, 400 N at rest): a 20 ms dip to 100 N (a rock's
    back) is ground; 150 ms at 150 N (a hop, the fork short of its top-out) is a flight; 2 s at 100 N
    (the bike standing unweighted, longer than ``MAX_FLIGHT_S``) and 0.3 s at 100 N from the record's
    first sample are not (the rule on, ``LIGHT_S`` = ``ON_S``); off (the default) none is."""
    from mtbmj.ride import reconstruct_inverse as ri

    dt, static = 1e-3, 400.0
    f = np.full(10000, static)
    f[:300] = 100.0  # the record's start
    f[1000:1020] = 100.0  # a rock's back
    f[2000:2150] = 150.0  # a hop
    f[4000:6000] = 100.0  # standing
    assert ri.LIGHT_S == math.inf and not ri.unloaded(f, static, dt).any()
    before = ri.LIGHT_S
    try:
        ri.LIGHT_S = ON_S
        off = ri.unloaded(f, static, dt)
    finally:
        ri.LIGHT_S = before
    assert not off[:300].any() and not off[1000:1020].any() and not off[4000:6000].any()
    assert off[2000:2150].all() and off.sum() == 150

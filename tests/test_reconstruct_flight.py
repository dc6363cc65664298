"""A drop's level kept by the reconstruction (mtbmj/ride/reconstruct_flight.py, issue 51 item 2):
the level change across each drop's edge flight read by the whole bike and kept in its slow
reference where the flight's duration allows it.

The rides are made by the independent whole bike of tests/helpers.py (``whole_bike_ride``: its own
equations and integrator; what it shares with the package is listed in
tests/test_reconstruct_whole_bike.py's module doc) over a course made here: a 0.25 m drop, a kicker
(a straight ramp 0.3 m up over 1.5 m, the ground back at once to the level before it: a jump to a
landing at the level it started from) and a 0.5 m drop, on ISO 8608 class C roughness. The seed and
speeds were not tuned: seed 5 at 6 +- 0.5 m/s was the first tried (seed 9 at 5 m/s, tried after, reads
the drops -0.211 and -0.422 m for -0.241 and -0.496, the ground's levels -0.224 and -0.452, the rear
predicted 2.96 mm RMS where 3.59 with no level kept).
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from helpers import SpeedProfile, whole_bike_ride

PROFILE = SpeedProfile(6.0, 0.5, 20.0)
FEATURES = (("drop", 40.0, 0.25), ("kicker", 90.0, 0.3), ("drop", 140.0, 0.5))
TOLERANCE = 0.2  # a drop's level read within this share of the drop


def _reconstruct(ride):
    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(ride["sst"], **decoding(SimpleNamespace(bike=str(ride["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    return reconstruct.reconstruct(record, str(ride["bike"]))


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return whole_bike_ride(tmp_path_factory.mktemp("levels"), seed=5, seconds=30.0, profile=PROFILE, features=FEATURES)


@pytest.fixture(scope="module")
def rebuilt(made):
    return _reconstruct(made)


def across(made, rec, name):
    """(the made terrain's level change, the ground found's) from 1 s before the feature ``name`` to 2 s
    after it (m), and the sample where the front wheel reaches it."""
    t = rec.t
    dt = t[1] - t[0]
    truth = made["h"](PROFILE.along(t))
    k = int(np.argmax(PROFILE.along(t) >= made["features"][name]))
    i, j = k - int(round(1.0 / dt)), k + int(round(2.0 / dt))
    return float(truth[j] - truth[i]), float(rec.ground[j] - rec.ground[i]), k


def read_at(rec, k):
    """The level change read across the flight that starts within 50 ms of sample ``k``, or None."""
    t = rec.t
    rows = [r for r in rec.levels if abs(r["start_s"] - t[k]) <= 0.05]
    return rows[0] if rows else None


def assert_level_kept(made, rec, name: str, size: float) -> None:
    """The drop ``name`` (``size`` m, made) read and kept by ``rec``: its level change and the ground found
    past it within ``TOLERANCE`` of the drop as made."""
    truth, found, k = across(made, rec, name)
    assert truth == pytest.approx(-size, abs=0.02)  # the drop as made
    row = read_at(rec, k)
    assert row is not None and row["kept"], (name, rec.levels)
    assert row["level_change_m"] == pytest.approx(truth, abs=TOLERANCE * size), (name, row)
    assert found == pytest.approx(truth, abs=TOLERANCE * size), (name, found, truth)


def test_drops_levels_are_read_and_a_kicker_keeps_its_level(made, rebuilt, monkeypatch):
    """Each drop's level change is read across its flight within ``TOLERANCE`` of the drop and the
    ground found keeps it (2 s past the drop, from 1 s before it, within the same share), while the
    kicker (the wheel thrown up off its lip) reads no level change: its flight is not read, and the
    ground found 2 s past it is within 0.05 m of where it was. Measured when written: the 0.25 m drop
    (-0.247 as made) read -0.223, the ground -0.238; the 0.5 m (-0.494) -0.461 and -0.491; the kicker's
    ground +0.018 for +0.007. Beside the naive baseline, the reconstruction with no level kept (the
    drift's removal alone, the code before): each drop's ground found returns within 0.05 m of the level
    above it (+0.016 and +0.038 when written), which fails the checks above."""
    from mtbmj.ride import reconstruct_flight

    for name, size in (("drop_0.25", 0.25), ("drop_0.5", 0.5)):
        assert_level_kept(made, rebuilt, name, size)
    truth, found, k = across(made, rebuilt, "kicker")
    assert abs(truth) < 0.02 and abs(found - truth) <= 0.05, (truth, found)
    assert not any(r["kept"] and made["features"]["kicker"] <= PROFILE.along(r["start_s"])
                   <= made["features"]["kicker"] + 10.0 for r in rebuilt.levels), rebuilt.levels
    line = rebuilt.line()
    assert "2 drop level(s) kept, 0 left" in line, line
    # the naive baseline: no level kept, the ground found back at the level above each drop
    monkeypatch.setattr(reconstruct_flight, "edge_flights", lambda found, air, dt: [])
    none = _reconstruct(made)
    assert none.levels == []
    for name in ("drop_0.25", "drop_0.5"):
        _, found, _ = across(made, none, name)
        assert abs(found) <= 0.05, (name, found)


@pytest.mark.parametrize("scale", [1.3, 0.7])
def test_a_speed_30_percent_off_is_told_apart(made, rebuilt, monkeypatch, scale):
    """The ride read at a speed 30 % off (the two ends' lag's speed scaled, not found again from the rear
    predicted) fails the rear's check, where the speed found passes it: a level change is read in time
    (the fall across a flight), so the drops' levels barely move with the speed (when written, 1.3 times:
    -0.229 and -0.448 m read for -0.223 and -0.461; 0.7 times: the 0.25 m drop not read as an edge, the
    0.5 m -0.472), but the rear predicted over the terrain laid at the wrong speed misses the rear's
    record by more than twice its error at the speed found (8.43 and 8.74 mm RMS, the delayed fork
    7.60 and 9.65 at those speeds; 3.30 against 7.25 at the speed found; 3.65 since the rear meets the found
    ground's spectral share at once, mtbmj/ride/reconstruct_share.py)."""
    from mtbmj.ride import reconstruct

    assert rebuilt.checks()["passes"] is True
    tracked = reconstruct.tracked

    def off(*args, **kwargs):
        speed = tracked(*args, **kwargs)
        at = speed["speed_at"]
        speed["speed_at"] = lambda t: scale * at(t)
        return speed

    monkeypatch.setattr(reconstruct, "tracked", off)
    monkeypatch.setattr(reconstruct, "REFINE_PASSES", 0)
    wrong = _reconstruct(made)
    c = wrong.checks()
    assert c["passes"] is False, c
    assert c["rear_predicted_rms_mm"] > 2.0 * rebuilt.checks()["rear_predicted_rms_mm"], c
    assert "the model does not describe this ride" in c["verdict"]


def test_the_front_of_a_rod_pivoting_on_its_rear_end_falls_at_one_and_a_half_g():
    """``pivot_acceleration`` against the closed form: a uniform rod of length L pivoting about one end
    under its weight, from rest, accelerates its other end at g L / 2 * L / (L^2 / 3) = 1.5 g; a point
    mass at the front end alone falls at g; a push of the rider's limbs adds its moment."""
    from mtbmj.ride.reconstruct_flight import pivot_acceleration

    g, L, m = 9.81, 1.2, 20.0
    rod = SimpleNamespace(xF=L, xR=0.0, M=m, cx=L / 2, I=m * L * L / 12, mF=0.0, g=g, P_leg=0.0, P_arm=0.0,
                          leg_x=0.3, arm_x=0.9)
    assert pivot_acceleration(rod) == pytest.approx(1.5 * g, rel=1e-12)
    point = SimpleNamespace(**{**rod.__dict__, "M": 0.0, "I": 0.0, "mF": 5.0})
    assert pivot_acceleration(point) == pytest.approx(g, rel=1e-12)
    pushed = SimpleNamespace(**{**rod.__dict__, "P_arm": 100.0})
    assert pivot_acceleration(pushed) == pytest.approx(1.5 * g + 100.0 * 0.9 * L / (m * L * L / 3), rel=1e-12)


def test_a_hard_stop_s_impulse_is_read_from_the_ground_seen_after_the_hit():
    """``stop_kicks`` on a ground written here, two bottom-outs of 10 N s each (the quarter car's): after
    the first the ground sinks at 0.1 m/s for the next second on the wheel (the stop pushed too little:
    10 + 0.1 m/s x 40 kg = 14 N s); the second lands on a rock's top 20 ms before a 0.7 s flight whose
    chord falls 0.3 m (the ground after it not seen for 70 % of the window): kept at 10 N s. Read with
    the flight unknown (the rule before, a deliberately wrong input) the second is raised to level the
    chord (24.8 N s); a 0.4 s flight (60 % seen) is read (26.9 N s)."""
    from mtbmj.ride.reconstruct_flight import SEEN_SHARE, stop_kicks

    dt, mass, n = 1e-3, 40.0, 6000
    first, ground, air = np.zeros(n), np.zeros(n), np.zeros(n, bool)
    for a in (1000, 3000):
        first[a:a + 3] = 10.0 / (3 * dt)
    ground[1003:2003] = -0.1 * np.arange(1000) * dt
    ground[2003:] = ground[2002]

    def flight(long_s):
        g, off = ground.copy(), air.copy()
        m = int(round(long_s / dt))
        off[3023:3023 + m] = True
        g[3023:3023 + m] = g[3022] - 0.3 * np.arange(m) / m
        g[3023 + m:] = g[3022] - 0.3
        return g, off

    def impulses(out):
        return [float(out[a:a + 3].sum() * dt) for a in (1000, 3000)]

    g, off = flight(0.7)
    assert 1.0 - off[3003:4003].mean() < SEEN_SHARE
    assert impulses(stop_kicks(first, first, g, off, dt, mass)) == pytest.approx([14.0, 10.0], abs=1e-9)
    assert impulses(stop_kicks(first, first, g, np.zeros(n, bool), dt, mass))[1] > 15.0
    g, off = flight(0.4)
    assert impulses(stop_kicks(first, first, g, off, dt, mass))[1] > 15.0


def test_a_drop_deeper_than_its_flight_allows_is_left():
    """``read`` on a ground written here: three flights of 0.2 s, landing 0.1 m lower, 0.5 m lower and
    0.05 m higher, the front wheel's rise 20 mm at each take-off and 0 at each landing; at 2 g allowed,
    over the 0.201 s from the last sample on the ground to the first back on it, 0.5 * 2 g * 0.201^2 +
    0.02 = 0.4163 m: the first kept, the second (deeper) and the third (no drop) left, each with what
    it was allowed."""
    from mtbmj.ride.reconstruct_flight import read

    dt, g = 1e-3, 9.81
    n = 3000
    ground, air, rise = np.zeros(n), np.zeros(n, bool), np.zeros(n)
    starts, changes = (500, 1500, 2500), (-0.1, -0.5, 0.05)
    level = 0.0
    for a, d in zip(starts, changes):
        air[a:a + 200] = True
        rise[a - 1] = 0.02
        level += d
        ground[a + 200:] = level
        ground[a:a + 200] = level  # bridged at the landing's level from the take-off on
    chosen = [(a, a + 200) for a in starts]
    kept, left = read(ground, air, rise, chosen, dt, 2 * g)
    allowed = 0.5 * 2 * g * (201 * dt) ** 2 + 0.02  # from the last sample on the ground to the first back on it
    assert [(a, b) for a, b, _, _ in kept] == [(500, 700)]
    assert [(a, b) for a, b, _, _ in left] == [(1500, 1700), (2500, 2700)]
    for (_, _, change, most), d in zip(kept + left, changes):
        assert change == pytest.approx(d, abs=1e-12) and most == pytest.approx(allowed, rel=1e-12)
    assert math.isclose(allowed, 0.4163, abs_tol=1e-3)


def test_the_made_ride_s_ground_is_a_trail_and_a_hill_planted_in_it_is_not(made, rebuilt):
    """What a trail can be (mtbmj/ride/reconstruct_envelope.py): the ground found on this made ride (two
    drops and a kicker at 6 m/s) stays within what the bike could climb, so nothing is said and nothing
    left out for it (``beyond_trail`` empty); the same ground with a 3 m hill planted 1 s after its
    kicker (up over 1 s, down over 1.5 s, a deliberately wrong ground) is found, where it was planted."""
    import warnings

    from mtbmj.errors import ConfigWarning
    from mtbmj.ride import reconstruct_envelope as envelope

    assert rebuilt.beyond == [] and rebuilt.summary()["beyond_trail"] == []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        envelope.warn(rebuilt.name, rebuilt.beyond)
    assert not [w for w in caught if issubclass(w.category, ConfigWarning)]
    t = rebuilt.t
    k = int(np.argmax(PROFILE.along(t) >= made["features"]["kicker"]))
    t0 = float(t[k]) + 1.0
    hill = 3.0 * np.interp(t, [t0, t0 + 1.0, t0 + 2.5], [0.0, 1.0, 0.0])
    from mtbmj.bike.model import centre_of_mass
    from mtbmj.bike.spec import load

    total = centre_of_mass(load(str(made["bike"])))[0]  # the bike's mass with its rider: the bike file's
    speed = rebuilt.speed["speed_at"](t)
    found = envelope.beyond(t, rebuilt.distance, rebuilt.ground + hill, speed, total)
    assert len(found) == 1 and t0 - 0.3 <= found[0]["start_s"] <= t0 + 0.1 and found[0]["end_s"] >= t0 + 1.0, found


def _hp(x, dt):
    """A 2nd-order Butterworth high-pass at 0.3 Hz run forward and back (scipy, written here): what the
    drift's removal makes of a ground."""
    from scipy.signal import butter, sosfiltfilt

    return sosfiltfilt(butter(2, 0.3, btype="highpass", fs=1.0 / dt, output="sos"), x)


@pytest.mark.parametrize("size", [1.0, 1.5, 2.0])
def test_a_deep_drop_s_edge_is_read_though_the_drift_s_removal_lifts_the_ground_before_it(size):
    """``edge_flights`` on grounds written here, high-passed as the drift's removal does (``_hp``): a drop
    of ``size`` m left level at 6 s, its flight 0.5 s, the ground a chord across it, and a kicker (0.3 m up
    over 0.25 s, a 0.3 s flight, back on the level it started from; the ground a chord from its lip to the
    landing). The high-pass lifts the ground ahead of the drop's fall by about 0.07 m per metre fallen
    over the 0.1 s before the take-off (``EDGE_RISE_M`` is 0.05 m): read as a throw there, which left the
    made 1.0 and 1.5 m drops out before; the kicker's lip still reads as one. The deliberately wrong
    rule, the throw judged on the ground as found (the code before), leaves the drop out."""
    from mtbmj.ride.reconstruct_flight import edge_flights
    from mtbmj.ride.reconstruct_inverse import EDGE_RISE_M, edge, flights

    dt = 1e-3
    t = np.arange(0.0, 20.0, dt)
    a, b = 6000, 6500
    drop = np.where(t < t[a], 0.0, -size)
    drop[a:b] = np.linspace(0.0, -size, b - a)
    lip, c, d = 14000, 14250, 14550
    kick = np.interp(t, [t[lip], t[c]], [0.0, 0.3]) * (t < t[c])
    kick[c:d] = np.linspace(0.3, 0.0, d - c)
    found = _hp(drop + kick, dt)
    air = np.zeros(t.size, bool)
    air[a:b] = air[c:d] = True
    lifted = found[a - 1] - found[a - 1 - 100:a].min()
    assert lifted >= EDGE_RISE_M  # the high-pass's lift, enough to read as a throw
    assert edge_flights(found, air, dt) == [(a, b)]
    assert not any(edge(found, p, q, dt) for p, q in flights(air, dt))  # the rule before: neither read


def test_one_and_one_and_a_half_metre_drops_keep_their_levels(tmp_path):
    """A ride made by the independent whole bike (seed 5 at 6 +- 0.5 m/s, 25 s) off a 1.0 m and a 1.5 m
    drop (at 40 and 100 m; the made bike rides both, the fork to 127 of its 130 mm): each drop's level is
    read and kept, within ``TOLERANCE`` of the drop, and the ground found from 1 s before it to 2 s after
    within the same share. Measured when written: 1.0 m (-0.997 made) read -0.957, the ground -1.001;
    1.5 m (-1.487) read -1.624, the ground -1.644 (its take-off still about 0.18 m above the made level:
    what the drift's removal lifts ahead of the fall is not all taken off the reference). Beside the code
    before (the throw judged on the ground as found, monkeypatched back): no level kept, the ground found
    back above the level above each drop (+0.075 and +0.141 m when written). The rear predicted is not
    better for it (9.40 mm RMS, 7.28 before; neither passes the check): see docs/rolling.md."""
    from mtbmj.ride import reconstruct_flight
    from mtbmj.ride.reconstruct_inverse import edge, flights

    made = whole_bike_ride(tmp_path, seed=5, seconds=25.0, profile=PROFILE,
                           features=(("drop", 40.0, 1.0), ("drop", 100.0, 1.5)))
    rec = _reconstruct(made)
    for name, size in (("drop_1", 1.0), ("drop_1.5", 1.5)):
        assert_level_kept(made, rec, name, size)
    monkeypatch = pytest.MonkeyPatch()
    with monkeypatch.context() as m:
        m.setattr(reconstruct_flight, "edge_flights",
                  lambda found, air, dt: [(p, q) for p, q in flights(air, dt) if edge(found, p, q, dt)])
        before = _reconstruct(made)
    assert before.levels == []
    for name, size in (("drop_1", 1.0), ("drop_1.5", 1.5)):
        truth, found, _ = across(made, before, name)
        assert abs(found - truth) > TOLERANCE * size, (name, found, truth)

"""Issue 51 item 2 on the carried bike's point-contact ride at a fork far too soft (5 N/mm): the ground found
through its two wheelies.

The tests' whole bike (``helpers.whole_bike_ride``, scipy's solve_ivp on its own equations, the frame carrying
its masses fore and aft) rides the advice's course; at 17 m a 0.24 m rock's face bottoms its fork and throws
its front into a 0.8 s wheelie (2.55-3.36 s, the frame's front a metre up), it lands at 22.5 m on level ground,
bottoms out again, and a rock at 24.4 m throws it into a second of 0.93 s (3.64-4.57 s) over the 0.5 m drop at
30 m. The reconstruction finds the ground where the wheel is down between them 0.48 m low (a false dip at 23 m): the
quarter car's body (the whole bike's slow reference) high-passed through the wheelies sits 0.55 m below the
frame's front across both. Keeping the long flights' arcs out of the drift's removal (0.25 m low) and reading
a touch that never carries half the static load as no landing were tried and removed (docs/rolling.md,
"Wheelies' arcs", keeps what they measured).

What does not hold yet (strict xfails, the default reading): the ground between the wheelies; the second wheelie
is found as three flights, split by touches of 0.1 s and at most 160 N of 425 (the inverse's force about
nothing), whose landings make a face at 25-29 m 0.23 m above the made ground. The drop's level, inside a flight the rock threw, is not kept (a drop's edge is read
only where the ground did not throw the wheel, ``reconstruct_inverse.edge``)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from helpers import ADVISE_FEATURES, ADVISE_PROFILE, whole_bike_ride

pytestmark = pytest.mark.slow  # a 16 s made ride and its reconstruction

SECONDS = 16.0
LONG_S = 0.3  # the made bike's front flights this long are the wheelies


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return whole_bike_ride(tmp_path_factory.mktemp("wheelies"), fork_rate=5.0, seconds=SECONDS, profile=ADVISE_PROFILE,
                           features=ADVISE_FEATURES, carried=True, round_tyre=False)


def _reconstructed(made):
    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(made["sst"], **decoding(SimpleNamespace(bike=str(made["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    return reconstruct.reconstruct(record, str(made["bike"]))


@pytest.fixture(scope="module")
def rec(made):
    """The reconstruction of the made ride."""
    return _reconstructed(made)


def _wheelies(made):
    """The made bike's front flights of at least LONG_S before 5 s (before the drop's landing; the jump at
    105 m throws it into a third): (start s, end s)."""
    from mtbmj.ride.reconstruct_inverse import runs

    t, off = made["tyre_t"], made["front_tyre_N"] <= 0.0
    out = [(float(t[a]), float(t[min(b, t.size - 1)])) for a, b in runs(off)]
    return [(a, b) for a, b in out if b - a >= LONG_S and a < 5.0]


def _error(made, rec):
    """The ground found less the made one (m, both from the ride's start) on the reconstruction's samples."""
    truth = made["h"](ADVISE_PROFILE.along(rec.t))
    return (rec.ground - rec.ground[0]) - (truth - truth[0])


def _judged(made, rec) -> dict:
    flights = [(a, b) for a, b in rec.jumps if b - a >= 0.1]
    matched = all(any(abs(a - c) <= 0.1 and abs(b - d) <= 0.1 for c, d in flights) for a, b in _wheelies(made))
    e = _error(made, rec)
    (_, down), (up, _) = _wheelies(made)
    landing = float(np.mean(e[(rec.t >= down) & (rec.t < up)]))  # where the wheel is down between the wheelies
    x = ADVISE_PROFILE.along(rec.t)
    stretch = (x >= 10.0) & (x <= 30.0)
    return {"matched": matched, "landing_m": landing, "rms_m": float(np.sqrt(np.mean(e[stretch] ** 2)))}


def test_the_made_ride_has_its_two_wheelies(made):
    """The ride as the module doc tells it (a check of the reading): two front flights of 0.8-1 s."""
    w = _wheelies(made)
    assert len(w) == 2 and all(0.7 <= b - a <= 1.0 for a, b in w), w
    assert w[0][0] == pytest.approx(2.55, abs=0.05) and w[1][1] == pytest.approx(4.57, abs=0.05), w


@pytest.mark.xfail(strict=True, reason="measured: by default the ground between the wheelies is found 0.48 m low "
                                       "(0.25 with the arcs kept out of the drift's removal, tried and removed: "
                                       "see the module doc)")
def test_the_ground_between_the_wheelies_is_found_near_its_height(made, rec):
    assert _judged(made, rec)["landing_m"] > -0.35


@pytest.mark.xfail(strict=True, reason="measured: the second wheelie (3.64-4.57 s) is found as hops at "
                                       "3.64-3.76 s, 3.84-4.27 and 4.36-4.54 s, split by touches of 0.1 s and at most 160 N of "
                                       "425; the ground over 10-30 m 228 mm RMS (178 with those touches read as no "
                                       "landing and the arcs kept, both tried and removed: see the module doc)")
def test_the_wheelies_are_found_whole(made, rec):
    got = _judged(made, rec)
    assert got["matched"] and got["rms_m"] <= 0.2, got


@pytest.mark.xfail(strict=True, reason="measured: the ground found over 10-30 m is 228 mm RMS from the made one, "
                                       "a flat line 46 mm (the made ground there is level but for its rocks)")
def test_the_ground_through_the_wheelies_beats_a_flat_line(made, rec):
    e = _error(made, rec)
    x = ADVISE_PROFILE.along(rec.t)
    truth = made["h"](x) - made["h"](x[0])
    stretch = (x >= 10.0) & (x <= 30.0)
    assert np.sqrt(np.mean(e[stretch] ** 2)) <= np.sqrt(np.mean(truth[stretch] ** 2))


@pytest.mark.xfail(strict=True, reason="measured: 2 s past the drop the ground found lies 0.55 m above the made "
                                       "one (0.51 with the arcs kept) (the drop's 0.5 m level is read only off an edge the ground did not "
                                       "throw the wheel from; this flight began at a rock's face)")
def test_the_drop_inside_the_second_wheelie_keeps_its_level(made, rec):
    k = int(np.searchsorted(rec.t, _wheelies(made)[1][1] + 2.0))
    assert abs(_error(made, rec)[k]) <= 0.15

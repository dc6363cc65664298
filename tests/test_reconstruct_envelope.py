"""What a trail can be (mtbmj/ride/reconstruct_envelope.py, issue 51): the ground a reconstruction found
checked against what the bike could climb at its speed, g dh <= v^2/2 + P T / m. The grounds here are
written in the test (closed form); the shared ride 00100.SST, whose reconstruction found a 3 m hill
at 115-135 m while its whole bike took its quarter car's hard-stop impulse, finds none with its own
(reconstruct_flight.stop_kicks) and with the quarter car's is said in one line and left out of the
checks there."""
from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from mtbmj.cli import main
from mtbmj.errors import ConfigWarning

G = 9.81
MASS = 100.0


def _ramp(rise, seconds, v=6.0, dt=1e-3, start=5.0, total=12.0):
    """(t, distance, ground, speed): level, then a straight ramp up ``rise`` m over ``seconds`` s from
    ``start`` s, then level again, ridden at ``v`` m/s."""
    t = np.arange(0.0, total, dt)
    ground = rise * np.clip((t - start) / seconds, 0.0, 1.0)
    return t, v * t, ground, np.full(t.size, v)


def _bound(rise, seconds, v=6.0):
    from mtbmj.ride.reconstruct_envelope import PEDAL_POWER_W

    return v * v / (2 * G) + PEDAL_POWER_W * seconds / (MASS * G)


def test_a_rise_within_what_the_speed_climbs_is_a_trail_and_one_past_it_is_not():
    """At 6 m/s a 100 kg bike climbs v^2/2g = 1.83 m on its speed and 1.02 m more by pedalling 1 s at
    1000 W: a ramp of 95 % of that bound over 1 s is within it (no stretch), one of 105 % is not (one
    stretch, from the ramp's foot to its top and on: where, its rise and the bound said). A 0.3 m
    kicker's face and a 1.5 m drop (a fall) are within it. The bound follows the speed: the 105 % ramp
    ridden at 9 m/s is a trail."""
    from mtbmj.ride.reconstruct_envelope import beyond

    bound = _bound(None, 1.0)
    assert bound == pytest.approx(1.835 + 1.019, abs=1e-3)
    assert beyond(*_ramp(0.95 * bound, 1.0), MASS) == []
    found = beyond(*_ramp(1.05 * bound, 1.0), MASS)
    assert len(found) == 1, found
    s = found[0]
    assert s["start_s"] == pytest.approx(5.0, abs=0.02) and s["end_s"] >= 6.0, s
    assert s["start_m"] == pytest.approx(30.0, abs=0.2) and s["rise_m"] == pytest.approx(1.05 * bound, abs=0.01)
    assert s["allowed_m"] == pytest.approx(bound, abs=0.02) and s["speed_m_per_s"] == 6.0
    assert beyond(*_ramp(0.3, 0.2), MASS) == [] and beyond(*_ramp(-1.5, 0.3), MASS) == []
    t, x, z, _ = _ramp(1.05 * bound, 1.0)
    assert beyond(t, 1.5 * x, z, np.full(t.size, 9.0), MASS) == []


def test_a_long_climb_is_pedalled_and_a_wall_of_its_height_is_not():
    """A climb of 4 m over 10 s (a trail climbed at 6 m/s, 7 % grade) rises no more within the 2 s
    window than the bound allows; a 4 m wall (over 0.5 s) does not."""
    from mtbmj.ride.reconstruct_envelope import beyond

    assert beyond(*_ramp(4.0, 10.0, total=20.0), MASS) == []
    found = beyond(*_ramp(4.0, 0.5), MASS)
    assert len(found) == 1 and found[0]["rise_m"] == pytest.approx(4.0, abs=0.01), found
    assert found[0]["allowed_m"] == pytest.approx(_bound(None, 0.5), abs=0.02)


def test_the_stretch_is_masked_and_said_in_one_line():
    from mtbmj.ride.reconstruct_envelope import beyond, mask, warn

    t, x, z, v = _ramp(4.0, 0.5)
    found = beyond(t, x, z, v, MASS)
    m = mask(t, found)
    assert m[(t >= 5.0) & (t <= 5.5)].all() and not m[t < 4.99].any()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn("made.SST", found)
        warn("made.SST", [])
    said = [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)]
    assert len(said) == 1 and said[0].startswith("made.SST: the terrain found rises more than the bike at its "
                                                 "speed could climb at 30-"), said


@pytest.mark.slow  # two reconstructions through the whole bike: 10-40 s
@pytest.mark.shared_data("sst_v2", "00100.SST")
def test_the_shared_ride_s_hill_is_gone_and_with_the_quarter_car_s_impulse_said_and_left_out(tmp_path, capsys,
                                                                                            monkeypatch):
    """00100.SST: the fork hangs nearly fully out 15.3-15.8 s and lands on its stop at 15.83 s. The whole
    bike given the hard stop's impulse its quarter car found (316 N s, to stop its own body's free fall)
    was thrown up a 3.1 m hill at 115-135 m; with its own (``reconstruct_flight.stop_kicks``: what keeps
    its ground level after the hit, never pulling: none here) the ground there stays within 1 m of the
    level before it (0.87 m when written) and within what the bike could climb: nothing said. With the
    quarter car's impulse kept (the code before, a deliberately wrong input here), measured when written:
    4.3 m up from 15.8 to 16.8 s at 7.5 m/s, at most 3.8 m: one warning line naming 117-128 m and
    15.8-17.2 s (120-131 m and 4.4 m up since the rear meets the found ground's spectral share at once: the
    speed is then found again from the rear predicted, 7.40 m/s median where it was 7.54), the stretch in reconstruction.json's beyond_trail and not checked. series.csv's first
    rows print the fork at 0, not the subnormal -3.4e-317 its 5 kHz record's low-pass leaves there."""
    from conftest import SHARED_DATA

    from mtbmj.ride import reconstruct_flight

    ride = str(Path(SHARED_DATA) / "sst_v2" / "00100.SST")

    def hill(out):
        terrain = np.genfromtxt(out / "terrain.csv", delimiter=",", names=True)
        at = (terrain["distance_m"] >= 110.0) & (terrain["distance_m"] <= 145.0)
        before = terrain["height_mm"][np.argmin(np.abs(terrain["distance_m"] - 110.0))]
        return 1e-3 * float(terrain["height_mm"][at].max() - before)

    out = tmp_path / "fixed"
    assert main(["reconstruct", ride, "--bike", "sst", "--out", str(out)]) == 0
    assert "could climb" not in capsys.readouterr().err
    assert json.loads((out / "reconstruction.json").read_text())["beyond_trail"] == []
    assert hill(out) < 1.0, hill(out)

    monkeypatch.setattr(reconstruct_flight, "stop_kicks", lambda first, now, ground, air, dt, mass: now)
    out = tmp_path / "before"
    assert main(["reconstruct", ride, "--bike", "sst", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert hill(out) > 2.5, hill(out)
    said = [line for line in err.splitlines() if "could climb" in line]
    assert len(said) == 1 and said[0].startswith("mtbmj: warning: 00100.SST: the terrain found rises more than "
                                                 "the bike at its speed could climb at 120-131 m (15.8-17.2 s"), err
    summary = json.loads((out / "reconstruction.json").read_text())
    (s,) = summary["beyond_trail"]
    assert s["rise_m"] > s["allowed_m"] and 15.5 <= s["start_s"] <= 16.0 and 16.8 <= s["end_s"] <= 17.5, s
    series = np.genfromtxt(out / "series.csv", delimiter=",", names=True)
    inside = (series["time_s"] >= s["start_s"]) & (series["time_s"] <= s["end_s"])
    assert not series["checked"][inside].any()
    assert not (np.abs(series["fork_mm"]) < np.finfo(float).tiny)[series["fork_mm"] != 0.0].any()  # no subnormal
    assert math.isfinite(summary["checks"]["rear_predicted_rms_mm"])

def test_a_subnormal_or_minus_zero_is_written_0_and_a_small_normal_number_as_it_is():
    """Every CSV mtbmj writes (``output.csv_chunks``): a subnormal (round-off where 0 is meant: a filter's
    tail over a record's leading zeros) and -0 print as 0; the smallest normal number and 1e-300 print as
    they are, NaN as nan."""
    from mtbmj import output

    text = output.csv_bytes({"a": np.array([-3.4055945e-317, 1.67e-317, -0.0, np.finfo(float).tiny, 1e-300,
                                            float("nan"), 1.5])}).decode().split()
    assert text == ["a", "0", "0", "0", "2.22507386e-308", "1e-300", "nan", "1.5"], text

"""Careless input, round 30: a switch given both ways (``advise --calibrate --no-calibrate``: the last one won,
silently), a speed CSV whose ``speed_m_per_s`` holds km/h (read as a 20+ m/s ride), a speed CSV covering only
the part of the ride ``--duration`` asks for (refused without saying why the shorter run does not do), and
``run_bike(..., speed_profile=...)`` from Python (a profile off the terrain ran at one speed; a bad one was
refused only after the model was built). Every input is written here; the ride is the shipped example
(00649.SST, 0-76.398 s)."""
from __future__ import annotations

import argparse

import numpy as np
import pytest

from mtbmj.bike import run as bike_run
from mtbmj.cli.common import Parser
from mtbmj.errors import ConfigError, MtbmjError
from mtbmj.ride import reconstruct_given as G
from helpers import refused

RIDE_S = 76.398  # the shipped example's last sample (s), its first at 0
SECONDS = np.arange(0.0, 80.0, 1.0)  # a 1 Hz GPS track over the ride and past it


def _speed_csv(path, time, speed, header="time_s,speed_m_per_s"):
    path.write_text(header + "\n" + "".join(f"{t:g},{v:g}\n" for t, v in zip(time, speed)))
    return path


def test_a_switch_given_both_ways_is_refused(tmp_path, capfd):
    """``--calibrate --no-calibrate``: argparse took the last, silently (a 5 s --duration makes the code before
    refuse on the duration instead, so this fails fast there)."""
    out = tmp_path / "out"
    for pair in (["--calibrate", "--no-calibrate"], ["--no-calibrate", "--calibrate"]):
        line = refused(["advise", "example", "--bike", "sst", *pair, "--duration", "5", "--out", out], out, capfd,
                       f"{pair[0]} and {pair[1]} given both")
        assert "--duration" not in line
    # the other side: one way, even twice, is taken (and the run goes on to its own refusal of 5 s)
    line = refused(["advise", "example", "--bike", "sst", "--no-calibrate", "--no-calibrate", "--duration", "5",
                    "--out", out], out, capfd, "--duration: 5 s")
    assert "given both" not in line


def test_any_commands_switch_is_held_to_one_way():
    """The parser's rule, on a parser made here: both ways refused naming both; one way read."""
    p = Parser(prog="x")
    p.add_argument("--fast", action=argparse.BooleanOptionalAction, default=False)
    with pytest.raises(MtbmjError, match="--no-fast and --fast given both"):
        p.parse_args(["--no-fast", "--fast"])
    assert p.parse_args(["--fast"]).fast is True and p.parse_args(["--no-fast"]).fast is False


def test_a_speed_in_km_per_h_under_m_per_s_is_refused(tmp_path, capfd):
    """km/h 15-29 (a trail's) written under speed_m_per_s: before, read as a 22 m/s ride (reconstruct wrote
    1576 m of terrain and said the lag DISAGREES). Refused naming the column and km/h, with the m/s it would be;
    a row over 30 (km/h 15-35) was refused as "no bike is ridden so fast" and now names km/h too."""
    kmh = 22.0 + 7.0 * np.sin(SECONDS / 5.0)
    csv = _speed_csv(tmp_path / "kmh.csv", SECONDS, kmh)
    out = tmp_path / "out"
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", csv, "--out", out], out, capfd,
                   "km/h under speed_m_per_s?")
    median = float(np.median(np.interp(np.linspace(0.0, RIDE_S, 1001), SECONDS, kmh)))
    assert "kmh.csv" in line and "column speed_m_per_s" in line and f"{median:.3g} m/s" in line
    assert f"{median / 3.6:.3g} m/s if so" in line
    faster = _speed_csv(tmp_path / "kmh35.csv", SECONDS, 25.0 + 10.0 * np.sin(SECONDS / 5.0))
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", faster, "--out", out], out, capfd,
                   "row 4 (time 3 s): speed 30.6 m/s is outside 0-30 m/s")
    assert "km/h? 8.51 m/s if so" in line


def test_a_fast_ride_in_m_per_s_is_taken():
    """The refusal's other side: a downhill run at 15 m/s median (54 km/h) with bursts to 28 m/s is a ride;
    the same at a median just over 20 m/s is not."""
    fast = 15.0 + 13.0 * np.maximum(np.sin(SECONDS / 3.0), 0.0) ** 8
    assert np.median(fast) < 16.0 and fast.max() > 27.0
    G.checked(SECONDS, fast, "fast").check_covers(0.0, RIDE_S, "00649.SST")
    with pytest.raises(G.ConfigError, match="a median of 20.5 m/s"):
        G.checked(SECONDS, np.full(SECONDS.size, 20.5), "too fast").check_covers(0.0, RIDE_S, "00649.SST")


def test_a_speed_csv_shorter_than_the_ride_says_duration_does_not_help(tmp_path, capfd):
    """A GPS track of the ride's first 30 s with ``advise --duration 20``: refused as before (the ride is
    reconstructed whole, so its speed is needed over it all) and now says so; without --duration the line
    says nothing of it."""
    part = _speed_csv(tmp_path / "part.csv", np.arange(0.0, 31.0), np.full(31, 5.0))
    out = tmp_path / "out"
    line = refused(["advise", "example", "--bike", "sst", "--speed-csv", part, "--duration", "20", "--out", out], out,
                   capfd, "ends before the ride's end")
    assert "--duration 20 s limits the runs over the ride; the ride is reconstructed whole" in line
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", part, "--out", out], out, capfd,
                   "ends before the ride's end")
    assert "--duration" not in line


def test_a_speed_profile_off_the_terrain_is_refused_from_python():
    """``run_bike(speed_profile=...)`` with places in mm (0-20000 on a 20 m terrain): before, the run went on at
    the profile's nearest speed; now the CLI's refusal, from Python."""
    with pytest.raises(ConfigError, match="only place 1 of 3 lies along the terrain"):
        bike_run.run_bike("sst", "flat:length_m=20", duration=0.1, speed_profile=([0.0, 10000.0, 20000.0],
                                                                                   [4.0, 5.0, 6.0]))


@pytest.mark.parametrize("profile, said", [
    (([0.0, 10.0, 5.0], [5.0, 5.0, 5.0]), "the places must increase"),
    (([0.0, 10.0, 20.0], [5.0, np.nan, 5.0]), "not a number"),
    (([0.0, 10.0, 20.0], [5.0, -1.0, 5.0]), "a speed of -1 m/s is outside"),
])
def test_a_bad_speed_profile_is_refused_before_the_model_is_built(monkeypatch, profile, said):
    """Before, the profile was checked at the end of ``prepare``, after the bike's model was built (the run
    refused, the work done); now before. The model's builder made to fail shows which came first."""
    def built(*args, **kwargs):
        raise AssertionError("the model was built before the speed profile was checked")

    monkeypatch.setattr(bike_run, "build_bike", built)
    with pytest.raises(ConfigError, match=said):
        bike_run.run_bike("sst", "flat:length_m=20", duration=0.1, speed_profile=profile)

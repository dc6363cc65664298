"""Careless input, round 29b: the ride's speed given as a careless user writes it (``--speed-csv``: a column of
zeros, a time in ms under ``time_s``, a GPS clock of the day, a speed in km/h; a speed profile for the other
command; ``bike --speed-profile`` off the terrain), a terrain edited by hand into a wall (the front end went
backwards, or would start on top of it: said, refused), and an ``advise --try`` file's key for the other end.
Every input is written here; the ride is the shipped example (00649.SST, 0-76.398 s)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mtbmj.ride import reconstruct_given as G
from helpers import command_said as _run, refused

RIDE_S = 76.398  # the shipped example's last sample (s), its first at 0


def _speed_csv(path, time, speed, header="time_s,speed_m_per_s"):
    path.write_text(header + "\n" + "".join(f"{t:g},{v:g}\n" for t, v in zip(time, speed)))
    return path



SECONDS = np.arange(0.0, 80.0, 1.0)  # a 1 Hz GPS track over the ride and past it


@pytest.mark.parametrize("command", [["reconstruct", "example", "--bike", "sst"],
                                     ["advise", "example", "--bike", "sst"]])
def test_a_speed_column_of_zeros_is_refused(tmp_path, capfd, command):
    """A speed of 0 in every row: the bike never moves; before, taken as 0.3 m/s everywhere and the line said
    "speed given ..., 0.30 m/s median" (on the shared 14 s 00083.SST: 4 m of terrain, written)."""
    zeros = _speed_csv(tmp_path / "zeros.csv", SECONDS, 0.0 * SECONDS)
    out = tmp_path / "out"
    line = refused([*command, "--speed-csv", zeros, "--out", out], out, capfd, "below 0.3 m/s")
    assert "zeros.csv" in line and "never moves" in line


def test_a_ride_standing_part_of_the_time_is_not_refused():
    """The refusal's other side: a ride that stands for its first half (0 m/s) and rolls at 5 m/s after."""
    half = G.checked(SECONDS, np.where(SECONDS < 38.0, 0.0, 5.0), "half")
    half.check_covers(0.0, RIDE_S, "00649.SST")
    with pytest.raises(G.ConfigError, match="below 0.3 m/s"):
        G.checked(SECONDS, np.full(SECONDS.size, 0.29), "crawl").check_covers(0.0, RIDE_S, "00649.SST")


def test_a_time_in_ms_under_time_s_is_refused(tmp_path, capfd):
    """A GPS track at 1 Hz with its time in ms written under time_s: rows 0, 1000, 2000 ... s, only row 1 within
    the 76 s ride (it covers the ride, so the coverage check passed and the ride saw one straight line from row 1
    to row 2). The same file's header made time_ms is read and covers the ride."""
    ms = _speed_csv(tmp_path / "ms.csv", 1000.0 * SECONDS, 5.0 + np.sin(SECONDS))
    out = tmp_path / "out"
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", ms, "--out", out], out, capfd,
                   "a time in ms under time_s")
    assert "only row 1 of 80" in line and "1000 s apart" in line
    right = _speed_csv(tmp_path / "right.csv", 1000.0 * SECONDS, 5.0 + np.sin(SECONDS), "time_ms,speed_m_per_s")
    G.read_csv(right).check_covers(0.0, RIDE_S, "00649.SST")


def test_a_gps_clock_of_the_day_is_named(tmp_path, capfd):
    """Time of day (10:00:00, 36000 s on) in place of the ride's clock: refused as before, now naming the clock;
    a CSV starting 5 s late within the ride is refused without that word."""
    gps = _speed_csv(tmp_path / "gps.csv", 36000.0 + SECONDS, 5.0 + 0.0 * SECONDS)
    out = tmp_path / "out"
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", gps, "--out", out], out, capfd,
                   "a clock of the day?")
    assert "row 1 (time 36000 s)" in line
    late = _speed_csv(tmp_path / "late.csv", 5.0 + SECONDS, 5.0 + 0.0 * SECONDS)
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", late, "--out", out], out, capfd,
                   "starts after the ride's start")
    assert "clock of the day" not in line


@pytest.mark.parametrize("header, unit", [("time_s,speed_km_per_h", "km_per_h"), ("time_s,speed_mph", "mph"),
                                          ("time_s,speed_ft_per_s", "ft_per_s")])
def test_a_speed_in_another_unit_names_the_unit_whole(tmp_path, capfd, header, unit):
    """km/h typed as speed_km_per_h: the unit named is km_per_h (before: 'h', not the unit written)."""
    csv = _speed_csv(tmp_path / "s.csv", SECONDS, 18.0 + 0.0 * SECONDS, header)
    out = tmp_path / "out"
    refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", csv, "--out", out], out, capfd,
            f"unit '{unit}' is not one mtbmj reads")


def _terrain(path, x, z_mm):
    path.write_text("distance_m,height_mm\n" + "".join(f"{a:.2f},{b:.1f}\n" for a, b in zip(x, z_mm)))
    return path


@pytest.mark.parametrize("rows, back", [
    ([(0.0, 0.0), (20.0, 0.0), (20.0, 500.0), (40.0, 500.0)], True),   # a wall, its distance repeated
    ([(0.0, 0.0), (20.0, 0.0), (20.1, 500.0), (40.0, 500.0)], True),   # the same wall over one row
    ([(0.0, 0.0), (20.0, 0.0), (20.0, 60.0), (40.0, 60.0)], False),    # a 60 mm step, ridden over
    ([(0.0, 0.0), (40.0, 0.0)], False),                                # two rows of flat ground
])
def test_a_wall_edited_into_a_terrain_says_the_wheel_went_back(tmp_path, capfd, rows, back):
    """A 0.5 m wall (taller than the 0.37 m wheel's radius) at 20 m: the wheel meets it at 5 m/s and is thrown
    back (before: its peaks given as a ride over it, the only sign a negative lowest speed). Bounds, not fits:
    the axle turns back within a wheel's radius before the wall (19-20 m), no later than 0.5 s after 5 m/s
    would bring it there; ridden terrain (a 60 mm step, flat ground) says nothing of the kind."""
    x, z = zip(*rows)
    path = _terrain(tmp_path / "t.csv", x, z)
    status, err = _run(["roll", path, "--speed", "5", "--quiet", "--no-figure", "--out", tmp_path / "o"], capfd)
    assert status == 0, err
    went = json.loads((tmp_path / "o" / "summary.json").read_text())["went_back"]
    if not back:
        assert went is None and "backwards" not in err
        return
    assert 19.0 < went["x_m"] < 20.0 and went["time_s"] < 20.0 / 5.0 + 0.5 and went["speed_m_per_s"] < -0.5
    assert "the wheel went backwards" in err and "did not get over the terrain there" in err


def test_a_coasting_wheel_rolled_back_down_a_climb_is_said_too(tmp_path, capfd):
    """Coasting up a 40 % climb at 1 m/s: the wheel stops and rolls back, no impact (the axle's largest backward
    force some 60 N, not the wall's hundreds of kN); the line says it went backwards without calling it a
    wall. Bound: it stops no later than v / (g sin(atan 0.4)) = 0.27 s on the climb plus the 1.5 m lead-in
    and the climb's start (the run's own at_m) at 1 m/s, and backwards at most as fast as it came."""
    import math

    status, err = _run(["roll", "climb:grade_percent=40", "--speed", "1", "--drive", "coast", "--quiet",
                        "--no-figure", "--out", tmp_path / "o"], capfd)
    assert status == 0, err
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    went = s["went_back"]
    assert went is not None and -1.05 < went["speed_m_per_s"] < -0.5, went
    assert went["time_s"] < (1.5 + s["scenario"]["at_m"]) / 1.0 + 1.0 / (9.81 * math.sin(math.atan(0.4))) + 0.5
    assert "the wheel went backwards" in err and "a climb beyond the drive" in err


@pytest.mark.parametrize("table, said", [
    # the fork's progressive spring key in the coil shock's set table: its linear model does not read it
    ('[shock.set]\n"fork.spring.progressive_rate_N_per_mm" = 7.0\n', "fork.spring.progressive_rate_N_per_mm"),
    # the shock's linear rate in the progressive fork's set table
    ('[fork.set]\n"fork.spring.rate_N_per_mm" = 90.0\n', "fork.spring.rate_N_per_mm"),
    ('[shock.set]\n"fork.spring.rate_N_per_mm" = 90.0\n', None),  # a key the shock reads: a try, said nothing
])
def test_a_try_files_key_for_the_other_end_is_said(tmp_path, table, said):
    """advise --try FILE whose key is one the part's model does not read: the try predicts the recorded
    setting again. `mtbmj bike FILE` says so in a warning line; the try said nothing (its composition's
    warnings were caught and compared with the same file's)."""
    import warnings

    from mtbmj.config import ConfigWarning
    from mtbmj.ride import advise

    path = tmp_path / "try.toml"
    path.write_text('base = "sst"\n' + table)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        advise.trial("sst", None, str(path), [])
    lines = [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)]
    if said is None:
        assert lines == []
        return
    assert len(lines) == 1 and lines[0].startswith(f"--try {path}: ") and said in lines[0], lines
    assert "does not read it, so it changes nothing" in lines[0]


@pytest.mark.parametrize("places, said", [
    ([1000.0, 2000.0], "no place of 2 lies along the terrain"),                     # another terrain's profile
    ([0.0, 5000.0, 10000.0, 15000.0, 20000.0], "only place 1 of 5 lies along"),   # distances in mm
])
def test_a_speed_profile_off_the_terrain_is_refused(tmp_path, capfd, places, said):
    """``bike --speed-profile`` whose places miss the terrain (20 m of flat): before, held flat past its ends,
    the run rode one speed (the profile's nearest) and said "along a speed profile"."""
    prof = tmp_path / "speed.csv"
    prof.write_text("distance_m,speed_m_per_s\n" + "".join(f"{x:g},{4 + i}\n" for i, x in enumerate(places)))
    out = tmp_path / "out"
    line = refused(["bike", "sst", "flat:length_m=20", "--speed-profile", prof, "--duration", "1", "--out", out],
                   out, capfd, said)
    assert str(prof) in line and "distances in mm" in line


def test_a_speed_profile_along_the_terrain_is_taken():
    """The refusal's other side: the same places in metres (0-20 m) lie along a 20 m terrain."""
    from mtbmj.bike.schedule import SpeedProfile
    from mtbmj.rolling import terrain as T

    ter = T.make("flat:length_m=20")
    prof = SpeedProfile.checked(([0.0, 5.0, 10.0, 15.0, 20.0], [4.0, 5.0, 6.0, 7.0, 8.0]))
    assert prof.along(ter.start_x, ter.start_x + ter.length) is prof


def test_a_speed_over_time_and_a_speed_along_the_distance_name_each_other(tmp_path, capfd):
    """reconstruct's --speed-csv given a speed profile (distance_m, speed_m_per_s: the speed.csv reconstruct
    writes) and bike's --speed-profile given a speed over time: each refusal names the option that takes it;
    a file of neither (a typo) is refused without that word."""
    along = tmp_path / "along.csv"
    along.write_text("distance_m,speed_m_per_s\n0,5\n400,5\n")
    over = _speed_csv(tmp_path / "over.csv", SECONDS, 5.0 + 0.0 * SECONDS)
    typo = _speed_csv(tmp_path / "typo.csv", SECONDS, 5.0 + 0.0 * SECONDS, "time_s,sped_m_per_s")
    out = tmp_path / "out"
    refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", along, "--out", out], out, capfd,
            "what mtbmj bike --speed-profile takes")
    refused(["bike", "sst", "flat:length_m=20", "--speed-profile", over, "--duration", "1", "--out", out], out, capfd,
            "what reconstruct and advise --speed-csv take")
    line = refused(["reconstruct", "example", "--bike", "sst", "--speed-csv", typo, "--out", out], out, capfd,
                   "has time_s, sped_m_per_s")
    assert "--speed-profile" not in line


@pytest.mark.parametrize("rows, into", [
    ([(0.0, 0.0), (0.0, 500.0), (40.0, 500.0)], 500.0),     # a wall at the first distance: started on top of it
    ([(0.0, 0.0), (0.01, 500.0), (40.0, 500.0)], 500.0),    # the same wall leaning 1 cm
    ([(0.0, 0.0), (40.0, 8000.0)], None),                    # a 20 % climb from the first row
])
def test_a_roll_that_would_start_inside_the_terrain_is_refused(tmp_path, capfd, rows, into):
    """roll over a terrain CSV that rises at once: before, the wheel was put on top of the wall (its height at
    the start the wall's upper end) and rode flat ground, the wall never met ("fork peak 22.7 mm"), as
    mtbmj bike refuses ("does not start on level ground"). The tyre (0.37 m) at rest on the first row's level
    would hold the ground: for the wall all of it, for a 20 % grade s^2 r / 2 = 7.4 mm (at most, closed
    form), over the 5 mm a start allows."""
    x, z = zip(*rows)
    out = tmp_path / "o"
    line = refused(["roll", _terrain(tmp_path / "t.csv", x, z), "--speed", "5", "--out", out], out, capfd,
                   "would start")
    r_mm = 370.0
    expected = into if into is not None else 0.2 ** 2 * r_mm / 2
    got = float(line.split("would start ")[1].split(" mm")[0])
    assert abs(got - expected) <= 1.0, line


def test_a_gentle_climb_from_the_first_row_rolls(tmp_path, capfd):
    """The refusal's other side: a 10 % grade from the first row (1.85 mm into the tyre at most) rolls."""
    path = _terrain(tmp_path / "t.csv", [0.0, 40.0], [0.0, 4000.0])
    status, err = _run(["roll", path, "--speed", "5", "--duration", "0.5", "--quiet", "--no-figure", "--out",
                        tmp_path / "o"], capfd)
    assert status == 0, err


@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_a_spreadsheets_trailing_delimiter_is_no_column(tmp_path, delimiter):
    """A spreadsheet's export with a delimiter ending every line: before, refused as "line 2: '' is not a
    number". Read as the same record as without it; a header with a nameless column between two named
    ones is still refused, and so is a row with a value under the nameless trailing one."""
    from mtbmj.measured.records import RecordError, read_record

    d = delimiter
    rows = "".join(f"{t:g}{d}{5 + t / 10:g}{d}\n" for t in SECONDS)
    (tmp_path / "trail.csv").write_text(f"time_s{d}speed_m_per_s{d}\n" + rows)
    (tmp_path / "plain.csv").write_text(f"time_s{d}speed_m_per_s\n" + rows.replace(f"{d}\n", "\n"))
    got, want = read_record(tmp_path / "trail.csv"), read_record(tmp_path / "plain.csv")
    assert got.units == want.units == {"time": "s", "speed": "m_per_s"}
    assert np.array_equal(got["time"], want["time"]) and np.array_equal(got["speed"], want["speed"])
    G.read_csv(tmp_path / "trail.csv").check_covers(0.0, RIDE_S, "00649.SST")
    (tmp_path / "mid.csv").write_text(f"time_s{d}{d}speed_m_per_s\n" + "".join(f"{t:g}{d}{d}5\n" for t in SECONDS))
    (tmp_path / "more.csv").write_text(f"time_s{d}speed_m_per_s{d}\n" + "".join(f"{t:g}{d}5{d}7\n" for t in SECONDS))
    for bad in ("mid.csv", "more.csv"):
        with pytest.raises(RecordError, match="line 2"):
            read_record(tmp_path / bad)

"""The ride's speed given by the rider (issue 51 item 1; mtbmj/ride/reconstruct_given.py): ``mtbmj
reconstruct RIDE --speed M_PER_S`` or ``--speed-csv FILE``, ``reconstruct(record, bike, speed=)``, and the
same options on ``mtbmj advise``.

The rides are made here: two quarter cars (each end a sprung and an unsprung mass on a linear spring and
damper, point-contact tyres that leave the ground, scipy's DOP853, this file's own equations, as
tests/test_reconstruct.py's ride) ridden at a speed v(t) over a terrain h(s) written here, the rear a
wheelbase behind the front along the distance; both ends' travel written as a travel CSV at 1 kHz rounded
to 0.1 mm. One terrain is a washboard met at a steady cadence (bumps about 1.0 m apart): its two ends' records
align at every bump's lag, so the lag gives no speed and the ride is refused without a speed given. The other is
random bumps at 6 m/s (as tests/test_reconstruct.py's), where the lag gives one, to compare with. The truth
(the speed, the distance) is this file's; the package only reads the travel CSV and the speed given.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from mtbmj.cli import main

from helpers import quarter_car_ride

RATE = 1000.0
SECONDS = 20.0
V0, DV, PERIOD = 6.0, 1.0, 20.0  # the washboard ride's speed V0 + DV sin(2 pi t / PERIOD), m/s


def speed(t):
    return V0 + DV * np.sin(2 * np.pi * np.asarray(t, float) / PERIOD)


def along(t):
    t = np.asarray(t, float)
    return V0 * t - DV * PERIOD / (2 * np.pi) * (np.cos(2 * np.pi * t / PERIOD) - 1.0)


BUMP_S = 1.0 / 6.0  # s between the bumps as ridden (about 1.0 m apart at 6 m/s)


def _washboard():
    """Braking bumps 12 mm high and 0.5 m long, laid where the made ride's front meets one every
    ``BUMP_S`` seconds (from 1 s on, level before): 0.83-1.17 m apart as the speed swings. Both ends'
    records are then periodic in time, so every bump's lag aligns them as well as the wheelbase's: the
    lag cannot time this ride (a washboard ridden at a steady cadence). h(s) m, and the bumps' places."""
    centres = along(np.arange(1.0, SECONDS + 1.0, BUMP_S))
    grid = np.arange(-5.0, float(along(SECONDS)) + 5.0, 1e-3)
    table = np.zeros_like(grid)
    for c in centres:
        table += 0.012 * np.sin(np.pi * np.clip((grid - c) / 0.5 + 0.5, 0.0, 1.0)) ** 2
    return (lambda s: np.interp(s, grid, table)), centres


washboard, CENTRES = _washboard()


def made_ride(folder, h, place, seconds=SECONDS):
    """Both ends' travel (two quarter cars: ``helpers.quarter_car_ride``) over ``h`` (m at s m), the front at
    ``place(t)`` m, the rear a wheelbase behind; written as folder/ride.csv beside folder/bike.toml."""
    return quarter_car_ride(folder, h, place, seconds, RATE)


def gps_csv(path, times, speeds, header="time_s,speed_m_per_s"):
    path.write_text(header + "\n" + "\n".join(f"{a:g},{b:g}" for a, b in zip(times, speeds)) + "\n")
    return path


def one_line(err: str) -> str:
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("mtbmj: warning")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture(scope="module")
def board(tmp_path_factory):
    return made_ride(tmp_path_factory.mktemp("washboard"), washboard, along)


@pytest.fixture(scope="module")
def gps(board, tmp_path_factory):
    """The washboard ride's true speed at 1 Hz, as a GPS or a bike computer logs it."""
    times = np.arange(0.0, SECONDS + 1.0, 1.0)
    return gps_csv(tmp_path_factory.mktemp("gps") / "gps.csv", times, np.round(speed(times), 2))


def reconstructed(ride, tmp_path, name, *extra):
    out = tmp_path / name
    code = main(["reconstruct", str(ride["csv"]), "--bike", str(ride["bike"]), "--out", str(out), *extra])
    return code, out


def test_the_washboard_is_refused_without_a_speed_given(board, tmp_path, capsys):
    """The lag cannot time a washboard (every bump's lag aligns as well): no speed, one line, exit 2."""
    code, out = reconstructed(board, tmp_path, "none")
    assert code == 2 and not out.exists()
    line = one_line(capsys.readouterr().err)
    assert "do not align at any lag" in line and "no speed from this ride" in line, line


def test_the_washboard_with_its_gps_speed_lays_the_terrain_at_its_distances(board, gps, tmp_path, capsys):
    """With the true speed at 1 Hz (--speed-csv) the ride is reconstructed: its speed within 0.5 % of the
    made one at every sample (linear between 1 s rows), its distance axis within 0.5 % of the made
    distance, the terrain found where the made one is (see :func:`placed`), the lag's refusal reported
    beside the speed given."""
    code, out = reconstructed(board, tmp_path, "gps", "--speed-csv", str(gps))
    assert code == 0, capsys.readouterr().err
    s = json.loads((out / "reconstruction.json").read_text())
    g = s["speed_given"]
    assert g["used"] is True and "gps.csv" in g["given"]
    assert g["lag"]["windows_compared"] == 0 and "do not align" in g["lag"]["lag_gives_none"]
    line = capsys.readouterr().out
    assert "speed given (--speed-csv" in line and "the lag gives none" in line, line
    import csv as csv_mod

    with open(out / "series.csv") as f:
        rows = list(csv_mod.DictReader(f))
    ts = np.array([float(r["time_s"]) for r in rows])
    v = np.array([float(r["speed_m_per_s"]) for r in rows])
    assert np.max(np.abs(v / speed(ts) - 1.0)) < 0.005
    with open(out / "terrain.csv") as f:
        terr = [(float(r["distance_m"]), float(r["height_mm"])) for r in csv_mod.DictReader(f)]
    x = np.array([a for a, _ in terr]) - s["terrain_csv_lead_in_m"]
    assert x[-1] == pytest.approx(float(along(ts[-1])), rel=0.005)
    assert placed(out) > 0.8


def placed(out) -> float:
    """How well terrain.csv's ground lies where the made terrain is: their correlation over the distance
    from 10 m to 10 m before the end (each high-passed by its mean): near 1 only where each bump is found
    at its own distance (the bumps are 0.5 m long: a place 0.25 m off leaves none on its own)."""
    import csv as csv_mod

    s = json.loads((out / "reconstruction.json").read_text())
    with open(out / "terrain.csv") as f:
        terr = np.array([(float(r["distance_m"]), float(r["height_mm"])) for r in csv_mod.DictReader(f)])
    x = terr[:, 0] - s["terrain_csv_lead_in_m"]
    grid = np.arange(10.0, min(x[-1], float(along(SECONDS))) - 10.0, 0.005)
    found, truth = np.interp(grid, x, terr[:, 1]), washboard(grid)
    return float(np.corrcoef(found, truth)[0, 1])


def test_a_speed_one_and_a_half_times_too_high_is_worse_on_the_washboard(board, gps, tmp_path, capsys):
    """The same ride with the GPS's speeds 1.5 times too high (a wrong unit or wheel size): the distance
    stretched by half, the bumps not where they are (:func:`placed` below 0.5), and the rear predicted
    worse than with the true speed (its RMS error over 1.5 times the true speed's; measured 7.3 mm against
    2.7): with no lag to compare, the check is what tells it. The ride's mean speed as a constant (6 m/s)
    lies between: its distance at the end right (the ride is one whole period of the speed's swing; 3.5 %
    allowed), its bumps up to 3.2 m off on the way (not placed either), its rear worse than the true
    speed's (6.3 mm). :func:`placed` measured 0.90 with the true speed, -0.02 at 1.5 times, 0.02 steady."""
    code, out = reconstructed(board, tmp_path, "gps", "--speed-csv", str(gps))
    assert code == 0
    right = json.loads((out / "reconstruction.json").read_text())
    times = np.arange(0.0, SECONDS + 1.0, 1.0)
    fast_csv = gps_csv(tmp_path / "fast.csv", times, np.round(1.5 * speed(times), 2))
    code, out = reconstructed(board, tmp_path, "fast", "--speed-csv", str(fast_csv))
    assert code == 0
    fast = json.loads((out / "reconstruction.json").read_text())
    code, out = reconstructed(board, tmp_path, "six", "--speed", "6")
    assert code == 0
    steady = json.loads((out / "reconstruction.json").read_text())
    truth = float(along(SECONDS - 1.0 / RATE))
    assert right["terrain_length_m"] == pytest.approx(truth, rel=0.005)
    assert fast["terrain_length_m"] == pytest.approx(1.5 * truth, rel=0.01)
    assert steady["terrain_length_m"] == pytest.approx(truth, rel=0.035)
    rms = {k: r["checks"]["rear_predicted_rms_mm"] for k, r in (("gps", right), ("fast", fast), ("six", steady))}
    assert rms["fast"] > 1.5 * rms["gps"], rms
    assert rms["six"] > rms["gps"], rms
    assert placed(tmp_path / "gps") > 0.8
    assert placed(tmp_path / "fast") < 0.5 and placed(tmp_path / "six") < 0.5


@pytest.fixture(scope="module")
def bumps(tmp_path_factory):
    """Random bumps (40 bumps 5-25 mm high and 1.2-3 m long, as tests/test_reconstruct.py's) at 6 m/s: the
    lag gives a speed."""
    rng = np.random.default_rng(3)
    centres, heights, lengths = np.sort(rng.uniform(8.0, 92.0, 40)), rng.uniform(0.005, 0.025, 40), rng.uniform(1.2, 3.0, 40)
    grid = np.arange(-2.0, 97.0, 1e-3)
    table = np.zeros_like(grid)
    for c, a, L in zip(centres, heights, lengths):
        table += a * np.sin(np.pi * np.clip((grid - c) / L + 0.5, 0.0, 1.0)) ** 2
    return made_ride(tmp_path_factory.mktemp("bumps"), lambda x: np.interp(x, grid, table), lambda t: 6.0 * t,
                     seconds=16.0)


def test_a_speed_given_beside_the_lags_is_compared_with_it(bumps, tmp_path, capsys):
    """Where the lag gives a speed, both are reported and how far apart: the right speed (6 m/s) agrees
    (within 10 %, the lag's windows measured within 3 % of 6), 1.5 times it (9 m/s) is reported 1.5 times
    the lag's, every window over 10 % apart, and the line says they disagree; the given one is used."""
    code, out = reconstructed(bumps, tmp_path, "six", "--speed", "6")
    assert code == 0
    ok = json.loads((out / "reconstruction.json").read_text())["speed_given"]["lag"]
    assert ok["windows_compared"] >= 3 and ok["agree"] is True
    assert ok["given_over_lag_median"] == pytest.approx(1.0, abs=0.03)
    capsys.readouterr()
    code, out = reconstructed(bumps, tmp_path, "nine", "--speed", "9")
    assert code == 0
    s = json.loads((out / "reconstruction.json").read_text())
    bad = s["speed_given"]["lag"]
    assert bad["agree"] is False and bad["windows_apart_over"] == bad["windows_compared"] >= 3
    assert bad["given_over_lag_median"] == pytest.approx(1.5, abs=0.05)
    assert s["speed_m_per_s"] == 9.0 and s["terrain_length_m"] == pytest.approx(9.0 * 16.0, rel=0.01)
    assert "they DISAGREE by over 10 %" in capsys.readouterr().out


def test_the_python_api_takes_a_number_a_csv_or_arrays(bumps, tmp_path):
    """``reconstruct(record, bike, speed=)``: 6 (a number), a CSV's path and (time_s, speed_m_per_s) give the
    same distance axis where they give the same speed."""
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(bumps["csv"])
    times = np.array([0.0, 8.0, 16.0])
    path = gps_csv(tmp_path / "v.csv", times, [6.0, 6.0, 6.0])
    ends = [reconstruct.reconstruct(record, str(bumps["bike"]), speed=s).distance[-1]
            for s in (6, str(path), (times, np.full(3, 6.0)))]
    assert ends[0] == pytest.approx(6.0 * bumps["t"][-1], rel=1e-3)
    assert ends[1] == pytest.approx(ends[0], rel=1e-9) and ends[2] == pytest.approx(ends[0], rel=1e-9)


@pytest.mark.parametrize("rows, header, said", [
    ([(0, 6), (5, 6), (5, 6), (17, 6)], None, "row 3: time 5 s after 5 s in row 2: the time must increase"),
    ([(0, 6), (5, -1), (17, 6)], None, "row 2 (time 5 s): speed -1 m/s is outside 0-30 m/s (negative)"),
    ([(0, 6), (5, 45), (17, 6)], None, "row 2 (time 5 s): speed 45 m/s is outside 0-30 m/s (no bike"),
    ([(0, 6), (5, 6), (10, 6)], None, "row 3 (time 10 s), its last, ends before the ride's end"),
    ([(3, 6), (17, 6)], None, "row 1 (time 3 s) starts after the ride's start"),
    ([(0, 6), (17, 6)], "time_s,velocity_mm", "needs exactly the columns time_s and speed_m_per_s"),
    ([(0, 6)], None, "a speed over time needs at least two rows"),
])
def test_a_bad_speed_csv_is_refused_in_one_line_and_nothing_written(bumps, tmp_path, capsys, rows, header, said):
    """Each implausible row named (the data rows counted from 1), exit 2, no output folder."""
    path = gps_csv(tmp_path / "bad.csv", [a for a, _ in rows], [b for _, b in rows],
                   header or "time_s,speed_m_per_s")
    for command in ("reconstruct", "advise"):
        out = tmp_path / command
        code = main([command, str(bumps["csv"]), "--bike", str(bumps["bike"]), "--out", str(out),
                     "--speed-csv", str(path)])
        line = one_line(capsys.readouterr().err)
        assert code == 2 and not out.exists(), line
        assert str(path) in line and said in line, line


def test_speed_options_given_wrongly_are_refused(bumps, tmp_path, capsys):
    """--speed with --speed-csv; on advise, a count of --speed-csv other than the rides'; a constant beyond a
    ridden speed: one line each, exit 2, nothing written."""
    path = gps_csv(tmp_path / "v.csv", [0.0, 17.0], [6.0, 6.0])
    cases = [(["reconstruct", "--speed", "6", "--speed-csv", str(path)], "the ride's speed given twice"),
             (["advise", "--speed-csv", str(path), "--speed-csv", str(path)], "--speed-csv given 2 times for 1 rides"),
             (["reconstruct", "--speed", "45"], "a ride's speed given is a number above 0 and at most 30 m/s, the fastest a bike is ridden"),
             (["reconstruct", "--speed", "-2"], "--speed")]
    for args, said in cases:
        out = tmp_path / "out"
        code = main([args[0], str(bumps["csv"]), "--bike", str(bumps["bike"]), "--out", str(out), *args[1:]])
        line = one_line(capsys.readouterr().err)
        assert code == 2 and not out.exists() and said in line, (args, line)


@pytest.mark.slow  # a whole-bike ride made (12 s) and advised on (12 candidates, 35 s)
def test_advise_takes_the_speed_given_and_says_the_lags_beside_it(tmp_path, capsys):
    """``mtbmj advise RIDE --speed-csv FILE`` on a ride made by tests/helpers.py's independent whole bike
    (6.5 +- 1 m/s over 25 s, 40 s): the ride's true speed at 1 Hz reconstructs it at that speed, the
    reconstruction passes its check (measured: rear 3.5 mm RMS, 48 % below the delayed fork's 6.8), the
    lag's speed is reported beside it and agrees (ratio 0.99 over 15 windows), the terminal says the speed
    was given; the advice is given (the file's own bike: measured inconclusive)."""
    from helpers import SpeedProfile, whole_bike_ride

    profile = SpeedProfile(6.5, 1.0, 25.0)
    made = whole_bike_ride(tmp_path / "ride", seconds=40.0, profile=profile)
    times = np.arange(0.0, 41.0, 1.0)
    gps = gps_csv(tmp_path / "gps.csv", times, np.round(profile.at(times), 2))
    out = tmp_path / "adv"
    assert main(["advise", str(made["sst"]), "--bike", str(made["bike"]), "--speed-csv", str(gps), "--workers", "1",
                 "--out", str(out)]) == 0
    rec = json.loads((out / "advice.json").read_text())["reconstruction"]
    assert rec["speed_given"]["given"] == f"--speed-csv {gps}" and rec["checks"]["passes"] is True
    lag = rec["speed_given"]["lag"]
    assert lag["windows_compared"] >= 10 and lag["agree"] is True
    assert lag["given_over_lag_median"] == pytest.approx(1.0, abs=0.03)
    assert f"given (--speed-csv {gps})" in capsys.readouterr().out

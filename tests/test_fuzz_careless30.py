"""Careless input, round 30: a switch given both ways (``advise --calibrate --no-calibrate``: the last one won,
silently), a speed CSV whose ``speed_m_per_s`` holds km/h (read as a 20+ m/s ride), a speed CSV covering only
the part of the ride ``--duration`` asks for (refused without saying why the shorter run does not do), and
``run_bike(..., speed_profile=...)`` from Python (a profile off the terrain ran at one speed; a bad one was
refused only after the model was built). Every input is written here; the ride is the shipped example
(00649.SST, 0-76.398 s)."""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest

from mtbmj.bike import run as bike_run
from mtbmj.bike import spec
from mtbmj.cli.common import Parser
from mtbmj.errors import ConfigError, MtbmjError
from mtbmj.ride import reconstruct_given as G
from helpers import BIKE, SENSORS, bike_text, bumps_csv, command_said, refused, write_v3

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


@pytest.mark.parametrize("seconds", [5.0, 5.5])
def test_a_short_ride_at_a_speed_given_is_reconstructed(tmp_path, capfd, seconds):
    """A 5.5 s two-ended ride made here (bumps at the fork, the same 0.2 s later at the rear) with ``--speed 5``
    (and one of 5000 samples, exactly one window: refused as "5.0 s" under its 5 s when its length was read from
    its first sample's time to its last, 4.999 s; found in review):
    before, refused "a speed needs at least one 5 s window and the slowest lag searched ... 6.26 s: no speed
    estimate", though the speed was given; now reconstructed at it, the lag's refusal reported beside it. Without
    the speed it is refused as before."""
    csv, *_ = bumps_csv(tmp_path / "short.csv", seconds)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)
    out = tmp_path / "out"
    status, said = command_said(["reconstruct", csv, "--bike", bike, "--speed", "5", "--out", out], capfd)
    assert status == 0 and "Traceback" not in said, said
    assert "speed given (a constant 5 m/s, used)" in said and f"the lag gives none: the ride is {seconds:.1f} s" in said, said
    assert (out / "reconstruction.json").exists()
    refused(["reconstruct", csv, "--bike", bike, "--out", tmp_path / "lag"], tmp_path / "lag", capfd,
            "the slowest lag searched")


@pytest.mark.parametrize("seconds", [0.005, 1.0, 3.0])
def test_a_ride_shorter_than_a_window_at_a_speed_given_is_refused(tmp_path, capfd, seconds):
    """Shorter than one 5 s window, the speed given or not: one line naming the speed given (with the lag's
    minimum lifted, 5 samples gave a traceback from the derivative filter and 1 s a reason about windows
    'whose two ends aligned'), nothing written."""
    csv, *_ = bumps_csv(tmp_path / "short.csv", seconds)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)
    out = tmp_path / "out"
    line = refused(["reconstruct", csv, "--bike", bike, "--speed", "5", "--out", out], out, capfd,
                   "a reconstruction at the speed given (a constant 5 m/s) needs at least one 5 s window")
    assert "short.csv: the ride is" in line


@pytest.mark.parametrize("value", ["3", "-500", "80"])
def test_a_tried_spring_rate_outside_the_bike_keys_range_is_refused(tmp_path, capfd, value):
    """``--try-set shock.spring_rate_lb_per_in=3`` (a 3 lb/in spring; 80: N/mm typed under lb/in): before, set as
    the shock configuration's fork.spring.rate_N_per_mm (0.53 N/mm), whose range is not the bike key's, and
    taken (-500 was refused naming that internal key at -87.5634). Now the bike key's 150-1000 lb/in, named as
    typed; a 5 s --duration makes the code before refuse on the duration instead, so this fails fast there."""
    out = tmp_path / "out"
    line = refused(["advise", "example", "--bike", "sst", "--try-set", f"shock.spring_rate_lb_per_in={value}",
                    "--duration", "5", "--out", out], out, capfd,
                   f"shock.spring_rate_lb_per_in = {value} lb/in is outside 150-1000 lb/in")
    assert "fork.spring.rate_N_per_mm" not in line


def test_a_tried_spring_rate_within_the_range_is_taken():
    """The refusal's other side: 500 lb/in (the recorded 456.8 within 150-1000) is a try, set in N/mm."""
    from mtbmj.bike import spec
    from mtbmj.ride import advise

    tr = advise.trial(spec.resolve("sst"), None, None, [("shock.spring_rate_lb_per_in", 500.0)])
    assert tr.overrides["shock.set"]["fork.spring.rate_N_per_mm"] == pytest.approx(500.0 * 0.17512683524647638)


def test_an_sst_ride_through_a_bike_without_sensors_says_whose_arms_read_it(tmp_path, capfd):
    """An SST v3 ride (written here through this file's recorder's arms) with ``--bike`` a file without
    ``[sensors]``: before, decoded silently with the SST example's arms (another recorder's travel wrong by as
    much as they differ); now a warning line says so. The same ride through a bike file giving [sensors]: no
    such line."""
    t = np.arange(0.0, 20.0, 1e-3)
    sst = write_v3(tmp_path / "ride.SST", 60.0 + 30.0 * np.sin(2.0 * t), 15.0 + 8.0 * np.sin(2.0 * t - 0.3), SENSORS)
    bare, given = tmp_path / "bare.toml", tmp_path / "given.toml"
    from mtbmj.bike import presets

    sst_toml = (Path(presets.__file__).parent / "sst.toml").read_text()  # the SST preset without its [sensors]
    head, _, tail = sst_toml.partition("[sensors]")
    bare.write_text(head + tail[tail.index("\n["):] if "\n[" in tail else head)
    assert "[sensors]" not in bare.read_text() and spec.load(str(bare)).sensors == {}
    given.write_text(bike_text())
    status, said = command_said(["telemetry", sst, "--bike", bare, "--out", tmp_path / "a"], capfd)
    assert status == 0, said
    assert f"--bike {bare} gives no [sensors] for its front and rear sensor: decoded with the SST example's" in said
    status, said = command_said(["telemetry", sst, "--bike", given, "--out", tmp_path / "b"], capfd)
    assert status == 0 and "[sensors]" not in said, said


def _law(zeta_at_0, zeta_at_17):
    """A decay law made here (``bounce_predict.DecayLaw``'s face the answer reads): the shock's damping ratio
    linear between two records at 0 and 17 clicks, a 0.7 mm friction band."""
    from types import SimpleNamespace

    def zeta_d(k):
        return zeta_at_0 + (zeta_at_17 - zeta_at_0) * float(k) / 17.0, 0.7

    return SimpleNamespace(end="shock", clicks=[0.0, 17.0], zeta_d=zeta_d, fit=SimpleNamespace(names=("zeta0", "slope")))


def test_clicks_whose_damping_falls_get_no_answer_in_clicks():
    """``fit bounce 00083.SST 00085.SST --clicks 17,0`` (the shared slams' 0 and 8 clicks typed swapped): the
    law's zeta falls from 0.202 at 0 clicks to 0.142 at 17, and the answer said "more than 17 clicks: record a
    slam at more clicks", more of what the law says lowers damping. Now no answer, the clicks' order named. The
    same law rising (as rebound clicks do) answers as before."""
    from mtbmj.identify import bounce_clicks as bc

    ans = bc.answer(_law(0.202, 0.142), 18.0)
    assert ans.clicks is None and "the law's damping falls as the clicks rise" in ans.note
    assert "zeta 0.202 at 0 clicks, 0.142 at 17" in ans.note and "more than" not in ans.line()
    rising = bc.answer(_law(0.142, 0.202), 18.0)
    assert "falls" not in (rising.note or "") and "clicks" in rising.line()


def _slam_v2(path, rate=1000):
    """An SST v2 seat slam made here: the shock at 20 mm for 3 s, pressed to 45 mm in 0.1 s and let go, then
    ringing down about 20 mm at 1.5 Hz, damping ratio 0.15 (the fork still); counts through the v2 README's
    calibration (helpers.counts_of)."""
    import struct

    from helpers import SHOCK, counts_of

    t = np.arange(int(12.0 * rate)) / rate
    w = 2.0 * np.pi * 1.5
    after = np.clip(t - 3.1, 0.0, None)
    x = np.where(t < 3.0, 20.0, np.where(t < 3.1, 20.0 + 25.0 * (t - 3.0) / 0.1,
                                         20.0 + 25.0 * np.exp(-0.15 * w * after) * np.cos(w * np.sqrt(1 - 0.15 ** 2) * after)))
    shock = np.clip(np.rint(counts_of(x, *SHOCK)), 0, None).astype("<u2")
    fork = np.full_like(shock, 300)
    path.write_bytes(struct.pack("<3sBH", b"SST", 2, rate) + np.column_stack((fork, shock)).astype("<u2").tobytes())
    return path


@pytest.mark.parametrize("hit", ["500", "10"])
def test_a_hit_with_no_law_to_answer_is_refused(tmp_path, capfd, hit):
    """``fit bounce ONE.SST --clicks 0 --hit-mm 500``: one setting gives no law in clicks, so no answer, and the
    hit (past the 65 mm stroke, refused where there is a law) changed nothing, silently; fit.json written.
    Now refused naming why, nothing written. The slam alone (no --hit-mm) is fitted."""
    slam = _slam_v2(tmp_path / "slam.SST")
    out = tmp_path / "out"
    refused(["fit", "bounce", slam, "--clicks", "0", "--hit-mm", hit, "--out", out], out, capfd,
            f"--hit-mm {hit}: the hit of the answer in clicks, which needs a decay law across two or more")
    status, said = command_said(["fit", "bounce", slam, "--clicks", "0", "--out", out], capfd)
    assert status == 0 and "slam.SST at 0 clicks: shock zeta" in said, said


def test_one_speed_in_km_per_h_is_refused(tmp_path, capfd):
    """``--speed 25`` (km/h typed): before, a whole ride at 25 m/s reconstructed (within the 30 m/s top); now
    refused as the CSV's median is, with the m/s it would be. 19 m/s (68 km/h, a fast descent) is taken."""
    out = tmp_path / "out"
    refused(["reconstruct", "example", "--bike", "sst", "--speed", "25", "--out", out], out, capfd,
            "--speed 25: a whole ride at over 20 m/s (72 km/h) is no trail ridden: km/h? (6.94 m/s if so")
    assert G.constant(19.0).speed[0] == 19.0


def test_a_trail_s_profile_rides_a_short_section_of_it_and_a_stretched_segment_is_refused():
    """Fewer than two places along the terrain is not itself wrong: a trail's profile with a place every 5 m
    rides a 3 m section between two of them (the render test's run, refused by the check above when it asked
    for two places on the terrain). One segment stretched over it (places 0 and 10000 m about a 20 m
    terrain: a profile in mm) is still refused."""
    from mtbmj.bike.schedule import SpeedProfile

    trail = SpeedProfile.checked((np.arange(0.0, 105.0, 5.0), np.linspace(4.0, 6.0, 21)))
    assert trail.along(0.0, 3.0) is trail
    stretched = SpeedProfile.checked(([0.0, 10000.0], [4.0, 5.0]))
    with pytest.raises(ConfigError, match="only place 1 of 2 lies along the terrain"):
        stretched.along(0.0, 20.0)
    with pytest.raises(ConfigError, match="no place of 2 lies along the terrain"):
        SpeedProfile.checked(([500.0, 600.0], [4.0, 5.0])).along(0.0, 20.0)
    # a 1 km trail's profile, a place every 10 m, written in mm: its places about the terrain span 10000 "m", ten
    # terrain lengths; only the absolute cap tells it (found in review: the bracket alone took it at ~3 m/s throughout)
    x_m = np.arange(0.0, 1010.0, 10.0)
    with pytest.raises(ConfigError, match="only place 1 of 101 lies along the terrain"):
        SpeedProfile.checked((x_m * 1000.0, 3.0 + 2.0 * np.sin(x_m / 50.0))).along(0.0, 1001.0)


def test_a_passive_crash_along_a_speed_profile_names_what_the_active_rider_can_take(tmp_path, capfd):
    """A 1 m drop ridden along a speed profile (5 m/s held): the passive rider goes over the bars and the line
    says "--rider active does". The active rider holds a speed profile (``RiderCallback.set_speed``): along the
    same profile it lands the drop (exit 0, no crash)."""
    import json

    from helpers import command_said

    profile = tmp_path / "speed.csv"
    profile.write_text("distance_m,speed_m_per_s\n" + "".join(f"{x},5.0\n" for x in range(0, 210, 10)))
    status, said = command_said(["bike", "sst", "drop:height_mm=1000", "--speed-profile", profile, "--no-figure",
                                 "--out", tmp_path / "passive"], capfd)
    assert status == 3 and "over the bars" in said and "with the passive rider" in said, said
    assert "(--rider active does)" in said and "holds no speed profile" not in said, said
    status, said = command_said(["bike", "sst", "drop:height_mm=1000", "--speed-profile", profile, "--rider", "active",
                                 "--no-figure", "--out", tmp_path / "active"], capfd)
    assert status == 0 and "crashed" not in said.split("; wrote")[0], said
    s = json.loads((tmp_path / "active" / "summary.json").read_text())
    assert s["crash"] is None and s["rider"]["kind"] == "active" and s["speed_profile_m_per_s"] == [5.0, 5.0], s


@pytest.mark.parametrize("argv, refused_", [
    (["--fast", "--no-fa"], True), (["--fa", "--no-fast"], True),
    (["--name", "x", "--fast", "--", "--no-fast"], False), (["--fast"], False), (["--no-fast"], False)])
def test_a_switch_given_both_ways_is_refused_abbreviated_too(argv, refused_):
    """argparse takes a unique abbreviation (``--no-cal``) as the whole option, so a switch given both ways with
    one abbreviated still let the last win, silently; a ``--no-fast`` after ``--`` is a positional, not the
    switch (both found in review)."""
    p = Parser(prog="x")
    p.add_argument("--fast", action=argparse.BooleanOptionalAction)
    p.add_argument("--name")
    p.add_argument("pos", nargs="*")
    if refused_:
        with pytest.raises(MtbmjError, match="--fast and --no-fast given both"):
            p.parse_known_args(argv)
    else:
        assert p.parse_known_args(argv)[0].fast is (argv[-1] != "--no-fast" or "--" in argv)

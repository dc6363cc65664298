"""A bike run holding a set speed along the terrain (``run_bike(..., speed_profile=)``, ``mtbmj.bike.schedule``):
the speed profile a reconstructed ride gives its advice runs (``Reconstruction.speed_along``).

The check is the run's own speed against the profile written here, and the time it takes to ride a stretch
against the profile's integral (the closed form: the time of each metre is 1 / v). The drive's tracking lag
(a first-order speed loop, ``controllers.drive.drive_force``) is the tolerance's reason: where the profile's
speed changes the run follows it a fraction of a second later."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.bike.run import run_bike
from mtbmj.errors import ConfigError

X = np.array([-100.0, 10.0, 40.0, 80.0, 300.0])
V = np.array([4.0, 4.0, 7.0, 3.0, 3.0])


@pytest.fixture(scope="module", params=["compiled", "python"])
def ridden(request):
    return run_bike("sst", "flat:length_m=150", 4.0, duration=20.0, speed_profile=(X, V), callback=request.param)


def test_the_run_holds_the_profile_s_speed_where_the_front_axle_is(ridden):
    raw = ridden.raw
    x, v = raw["front_axle_x_m"], raw["speed_m_per_s"]
    for at in (5.0, 30.0, 40.0, 55.0, 70.0, 90.0):
        i = int(np.searchsorted(x, at))
        assert v[i] == pytest.approx(np.interp(at, X, V), rel=0.08), (at, v[i])
    # a metre takes 1 / v: the stretch 10-90 m in the profile's time, within the loop's lag
    t = raw["time_s"]
    ridden_s = float(np.interp(90.0, x, t) - np.interp(10.0, x, t))
    xs = np.linspace(10.0, 90.0, 2001)
    want = float(np.trapezoid(1.0 / np.interp(xs, X, V), xs))
    assert ridden_s == pytest.approx(want, rel=0.03), (ridden_s, want)
    held = run_bike("sst", "flat:length_m=150", 4.0, duration=26.0)  # the check can fail: one speed held (20 s)
    th = held.raw["time_s"]
    held_s = float(np.interp(90.0, held.raw["front_axle_x_m"], th) - np.interp(10.0, held.raw["front_axle_x_m"], th))
    assert abs(held_s - want) > 0.1 * want


@pytest.mark.parametrize("profile, why", [
    (([0.0, 1.0], [3.0]), "of one length"),
    (([0.0, 0.0], [3.0, 3.0]), "must increase"),
    (([0.0, 1.0], [3.0, 60.0]), "outside 0.3-30 m/s"),
    (([0.0, float("nan")], [3.0, 3.0]), "not a number"),
    ("fast", "two sequences"),
], ids=["lengths", "places", "speed", "nan", "words"])
def test_a_profile_that_cannot_be_is_refused_naming_why(profile, why):
    with pytest.raises(ConfigError, match=why):
        run_bike("sst", "flat:length_m=20", 4.0, duration=0.1, speed_profile=profile)


def test_a_profile_needs_the_rider_s_drive():
    with pytest.raises(ConfigError, match="coasting run has none"):
        run_bike("sst", "flat:length_m=20", 4.0, duration=0.1, drive="coast", speed_profile=(X, V))
    with pytest.raises(ConfigError, match="pedalling or coasting run has none"):  # the active rider's: not pedalling
        run_bike("sst", "flat:length_m=20", 4.0, duration=0.1, rider="active", pedal=(80, 250), speed_profile=(X, V))


@pytest.mark.parametrize("text, why", [
    ("distance_m,speed_m_per_s\n0,5\n0,6\n", "the places must increase"),
    ("distance_m,height_mm\n0,5\n1,6\n", "exactly the columns distance_m, speed_m_per_s"),
    ("distance_m,speed_m_per_s\n0,5\n1,90\n", "outside 0.3-30 m/s"),
], ids=["places", "columns", "speed"])
def test_a_bad_speed_profile_file_is_one_line_and_nothing_written(tmp_path, capsys, text, why):
    from mtbmj.cli import main

    bad = tmp_path / "speed.csv"
    bad.write_text(text)
    out = tmp_path / "out"
    assert main(["bike", "sst", "flat:length_m=20", "--speed-profile", str(bad), "--duration", "1", "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--speed-profile" in err[0] and str(bad) in err[0] and why in err[0], err
    assert not out.exists()


@pytest.mark.parametrize("options, why", [
    (["--pedal", "80"], "--pedal: a pedalling rider's speed is its own"),
    (["--pedal", "80", "--rider", "active"], "--pedal: a pedalling rider's speed is its own"),
    (["--drive", "coast"], "--drive coast: a coasting bike has no drive to hold it"),
])
def test_a_speed_profile_with_an_option_that_cannot_hold_it_names_the_option(tmp_path, capsys, options, why):
    """The refusal named run_bike's argument ("speed_profile: ..."), not the options the user set."""
    from helpers import one_line

    good = tmp_path / "speed.csv"
    good.write_text("distance_m,speed_m_per_s\n0,4\n10,5\n")
    out = tmp_path / "out"
    one_line(capsys, ["bike", "trail", "flat", "--speed-profile", good, *options, "--out", out],
             f"mtbmj: error: --speed-profile with {why}")
    assert not out.exists()


def test_the_command_rides_a_speed_profile_file(tmp_path):
    """``mtbmj bike ... --speed-profile CSV``: the start's speed the profile's first, the summary's set range
    the profile's, and the run at the profile's speeds (4 then 6 m/s)."""
    import json

    from mtbmj.cli import main

    prof = tmp_path / "speed.csv"
    prof.write_text("distance_m,speed_m_per_s\n0,4\n10,4\n20,6\n200,6\n")
    out = tmp_path / "out"
    assert main(["bike", "sst", "flat:length_m=80", "--speed-profile", str(prof), "--duration", "8", "--no-figure",
                 "--quiet", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["speed_m_per_s"] == 4.0 and s["speed_profile_m_per_s"] == [4.0, 6.0]
    assert s["min_speed_m_per_s"] == pytest.approx(4.0, abs=0.1) and s["max_speed_m_per_s"] == pytest.approx(6.0, abs=0.3)

"""Careless input, round 31: ``run_bike``'s bad speed profile not caught by ``except ValueError`` (the package's
ConfigError was no ValueError), a sweep grid of one value over a range (ran lo alone, the range dropped unsaid),
``presets --show`` of an empty file (printed nothing, exit 0), a bike file's geometry chart with a key misspelt
or a travel in metres (the line did not name the file; metres and radians unnamed), a version-2 ride read
through a bike file's [sensors] (set aside unsaid), and the Python entry points given a str or a list where a
mapping or a number goes (an AttributeError or a TypeError from deep inside, or a false reason). Every input is
written here."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

import mtbmj
from mtbmj.bike import run as bike_run
from mtbmj.errors import ConfigError, MtbmjError
from mtbmj.sweep import grid, parse_vary
from helpers import SENSORS_TOML, command_err, command_said, refused
from conftest import SHARED_DATA

V2_RIDE = Path(f"{SHARED_DATA}/sst_v2/00083.SST")
DROP = "sled.drop_height_mm"


def test_a_bad_speed_profile_is_a_value_error_from_python(monkeypatch):
    """Last round left alone: ``except ValueError`` around ``run_bike`` did not catch its refusal. ConfigError
    is a ValueError now (as MetricsError and EventsError were), and still the package's MtbmjError."""
    def built(*args, **kwargs):
        raise AssertionError("the model was built before the speed profile was checked")

    monkeypatch.setattr(bike_run, "build_bike", built)
    with pytest.raises(ValueError, match="the places must increase") as caught:
        bike_run.run_bike("sst", "flat:length_m=20", duration=0.1, speed_profile=([0.0, 10.0, 5.0], [5.0] * 3))
    assert isinstance(caught.value, MtbmjError) and isinstance(caught.value, ConfigError)
    assert issubclass(ConfigError, ValueError) and not issubclass(MtbmjError, ValueError)


def test_a_grid_of_one_value_over_a_range_is_refused(tmp_path, capfd):
    """``100:600:1`` ran the drop at 100 mm alone (linspace's one point), the 600 typed dropped unsaid."""
    out = tmp_path / "sweep"
    line = refused(["sweep", "S12", "--vary", f"{DROP}=100:600:1", "--engine", "fast", "--out", out], out, capfd,
                   "a grid of 1 value runs lo (100) alone, not the range to 600")
    assert f"--set {DROP}=100" in line
    # the other side: two values are the range's two ends
    assert grid([parse_vary(f"{DROP}=100:600:2")]) == [{DROP: 100.0}, {DROP: 600.0}]


def test_presets_show_of_an_empty_file_says_so(tmp_path, capfd):
    """An empty file (or comments only): ``presets --show`` printed nothing and exited 0."""
    for text in ("", "# my fork, to be filled in\n\n"):
        path = tmp_path / "mine.toml"
        path.write_text(text)
        status, err = command_err(["presets", "--show", path], capfd)
        assert status == 2 and err.count("\n") == 1 and "holds no keys (an empty file?)" in err, err
    # the other side: a file with a base and one key shows every key
    path.write_text(f'base = "S12"\n[sled]\ndrop_height_mm = 300\n')
    status, said = command_said(["presets", "--show", path], capfd)
    assert status == 0 and f"{DROP} = 300" in said and "holds no keys" not in said


@pytest.mark.parametrize("geometry, said", [
    ("head_angel_deg = 64.5", "chart.toml: geometry.head_angel_deg: unknown key"),
    ("fork_travel_mm = 0.16", "chart.toml: geometry.fork_travel_mm: 0.16 mm is outside 20-250 mm (metres typed "
                              "for mm? 0.16 m is 160 mm)"),
    ("head_angle_deg = 1.13", "chart.toml: geometry.head_angle_deg: 1.13 deg is outside 45-90 deg (radians? "
                              "1.13 rad is 64.7 deg)"),
])
def test_a_geometry_charts_bad_key_names_the_file_and_the_unit(tmp_path, capfd, monkeypatch, geometry, said):
    """The chart's own checks ran before the line was given the file's name: ``geometry.head_angel_deg: unknown
    key`` named no file; a travel in metres or an angle in radians was only "outside"."""
    monkeypatch.chdir(tmp_path)
    Path("chart.toml").write_text(f'base = "trail"\n[geometry]\n{geometry}\n')
    out = tmp_path / "out"
    for argv in (["presets", "--show", "chart.toml"], ["bike", "chart.toml", "root", "--speed", "4", "--out", out]):
        refused(argv, out, capfd, said)


@pytest.mark.parametrize("geometry, said", [("fork_travel_mm = 10", "10 mm is outside 20-250 mm"),
                                            ("head_angle_deg = 25", "25 deg is outside 45-90 deg")])
def test_a_value_out_of_range_that_is_no_unit_slip_names_none(tmp_path, capfd, geometry, said):
    path = tmp_path / "chart.toml"
    path.write_text(f'base = "trail"\n[geometry]\n{geometry}\n')
    line = refused(["presets", "--show", path], tmp_path / "out", capfd, said)
    assert "metres" not in line and "radians" not in line and "chart.toml" in line


@pytest.mark.skipif(not V2_RIDE.is_file(), reason="the shared v2 ride is not here")
def test_a_version_2_ride_through_a_bike_files_sensors_says_they_are_set_aside(tmp_path, capfd):
    """A v2 record is decoded with its time's calibration whatever [sensors] says: the file's arms were set
    aside without a word."""
    bike = tmp_path / "mine.toml"
    bike.write_text('base = "trail"\n' + SENSORS_TOML)
    said_line = "[sensors] (front and rear) are a version-3 recorder's arms: not used for this version-2 record"
    status, said = command_said(["telemetry", V2_RIDE, "--bike", bike, "--out", tmp_path / "v2"], capfd)
    assert status == 0 and said_line in said, said
    # the other side: a v3 ride (the shipped example) through the same file reads its arms, unsaid; the preset
    # sst's own arms with the v2 ride are not the user's, unsaid too
    for ride, with_bike in (("example", bike), (V2_RIDE, "sst")):
        status, said = command_said(["telemetry", ride, "--bike", with_bike, "--out", tmp_path / "other"], capfd)
        assert status == 0 and "not used for this version-2 record" not in said, said


@pytest.mark.parametrize("call, said", [
    (lambda: mtbmj.run_drop("S12", overrides=[f"{DROP}=300"]), "overrides: must be a mapping of key to value"),
    (lambda: mtbmj.run_drop("S12", overrides=f"{DROP}=300"), "got a str"),
    (lambda: mtbmj.run_drop("S12", duration="0.1"), "duration: must be a number of seconds, got '0.1'"),
    (lambda: mtbmj.run_drop("S12", duration=math.nan), "duration: must be a positive finite number of seconds"),
    (lambda: mtbmj.run_roll("washboard", 4.0, duration="0.1"), "duration: must be a number of seconds"),
    (lambda: mtbmj.run_roll("washboard", 4.0, overrides=["a=1"]), "overrides: must be a mapping"),
    (lambda: mtbmj.run_bike("sst", "drop", 5.0, duration="0.05"), "duration: must be a number of seconds"),
    (lambda: mtbmj.run_bike("sst", "drop", 5.0, overrides="rider.mass_kg=78"), "overrides: must be a mapping"),
    (lambda: mtbmj.run_bike("sst", "drop", 5.0, overrides=[("rider.mass_kg", 78)]), "got a list"),
    (lambda: mtbmj.run_study(presets="S12"), "presets: must be a list of names, e.g. ['S12']"),
    (lambda: mtbmj.run_study(presets=["S12"], engines="mujoco"), "engines: must be a list of names"),
])
def test_the_python_entry_points_given_the_wrong_type_say_so(call, said):
    """Before: AttributeError ('list' object has no attribute 'items'), TypeError ('>' not supported between str
    and int), ValueError (dictionary update sequence), "duration: must be positive, got '0.05'" (it may be),
    "S: unknown preset" (the str read letter by letter). Each is now one ConfigError naming the argument."""
    with pytest.raises(ConfigError) as caught:
        call()
    assert said in str(caught.value) and "\n" not in str(caught.value)


def test_the_python_entry_points_given_the_right_types_run():
    """The other side of the checks above: a mapping and a float are taken (a short drop and a short bike run)."""
    drop = mtbmj.run_drop("S12", overrides={DROP: 300.0}, duration=0.05)
    assert drop.raw["time_s"][-1] == pytest.approx(0.05, abs=2e-3)
    bike = mtbmj.run_bike("sst", "drop", 5.0, duration=0.05, overrides={"rider.mass_kg": 78})
    assert bike.raw["time_s"][-1] == pytest.approx(0.05, abs=2e-3)


def test_a_decimal_comma_in_a_number_option_is_named(tmp_path, capfd):
    """``--speed 4,5`` (a European keyboard's 4.5): "'4,5' is not a number", the comma unnamed."""
    out = tmp_path / "out"
    refused(["roll", "root", "--speed", "4,5", "--out", out], out, capfd,
            "'4,5' is not a number (a decimal comma? the decimal point is a dot: 4.5)")
    # the other side: a list or a word is not taken for a decimal comma
    for typed in ("4,5,6", "4.5,1", "fast"):
        line = refused(["roll", "root", "--speed", typed, "--out", out], out, capfd, "is not a number")
        assert "decimal comma" not in line


@pytest.mark.parametrize("section, typed, meant", [
    ("rider", "mass_kg = 180", "probably meant 180 lb = 81.65 kg"),  # 180 lb typed as kg
    ("rider", "mass_kg = 8", "probably meant 8 st = 50.8 kg"),  # stones
    ("shock", 'spring = "air"\npressure_psi = 14\npiston_diameter_mm = 40\npositive_volume_cm3 = 60\n'
              'negative_volume_cm3 = 50', "probably meant 14 bar = 203.1 psi"),  # bar under pressure_psi
])
def test_a_bike_keys_unit_slip_names_the_unit_meant(tmp_path, capfd, section, typed, meant):
    """A bike file's value outside what bikes have was warned as "(a unit mistake?)" without the unit, where
    a fork configuration's names it (1.8 psi: "probably meant 1.8 bar")."""
    path = tmp_path / "mine.toml"
    path.write_text(f'base = "trail"\n[{section}]\n{typed}\n')
    status, said = command_said(["presets", "--show", path], capfd)
    lines = [line for line in said.splitlines() if line.startswith("mtbmj: warning:")]
    assert status == 0 and len(lines) == 1 and f"(a unit mistake? {meant})" in lines[0], said
    # the other side: a mass no unit brings within 30-150 kg is only "a unit mistake?"
    path.write_text('base = "trail"\n[rider]\nmass_kg = 2000\n')
    status, said = command_said(["presets", "--show", path], capfd)
    assert status == 0 and "(a unit mistake?)" in said and "probably meant" not in said, said


@pytest.mark.parametrize("vary, said", [
    ("rider.mass_kg=70:nan:3", "lo and hi must be finite numbers, got 'nan'"),
    ("rider.mass_kg=-inf:90:3", "lo and hi must be finite numbers, got '-inf'"),
    ("fork:fork.spring.rate_N_per_mm=8:12:1", "or the one value with --fork-set fork.spring.rate_N_per_mm=8"),
    ("rider.mass_kg=70:90:1", "or the one value with --set rider.mass_kg=70"),
])
def test_a_bike_sweeps_range_with_no_end_or_one_value_says_so(tmp_path, capfd, vary, said):
    """``70:nan:3`` was refused as "expected key=lo:hi:n", the form it has; a bike sweep's one-value grid of a
    fork key names the option that sets one (--fork-set), not --set."""
    out = tmp_path / "out"
    refused(["sweep", "sst", "--roll", "root", "--speed", "4", "--vary", vary, "--out", out], out, capfd, said)
    # the other side: a form that is wrong is still said to be
    refused(["sweep", "sst", "--roll", "root", "--speed", "4", "--vary", "rider.mass_kg=70:90:3:4", "--out", out],
            out, capfd, "expected key=lo:hi:n")


@pytest.mark.parametrize("leverage, csv, said", [
    ("wheel_travel_mm = [0.0, 100.0, 80.0, 160.0]\nratio = [3.0, 2.9, 2.8, 2.6]", None, "value 3, 80 mm, follows 100 mm"),
    ('csv = "curve.csv"', "wheel_travel_mm,ratio\n0,3.0\n160,2.6\n100,2.8\n", "value 3, 100 mm, follows 160 mm"),
])
def test_a_leverage_table_going_back_names_the_value(tmp_path, capfd, leverage, csv, said):
    """A table not monotonic was refused as "must increase strictly" without the value at fault."""
    if csv:
        (tmp_path / "curve.csv").write_text(csv)
    path = tmp_path / "mine.toml"
    path.write_text(f'base = "trail"\n[leverage]\n{leverage}\n')
    refused(["presets", "--show", path], tmp_path / "out", capfd, f"must increase strictly (the shock stroke must "
                                                                  f"be monotonic in the wheel travel): {said}")


def test_one_ride_under_one_name_in_two_folders_is_told_by_its_paths(tmp_path, capfd, monkeypatch):
    """``advise example 00649.SST`` (the shipped ride and a copy of it): "00649.SST: the same ride as 00649.SST",
    the two told apart by nothing. Now the paths, where the names alone are one."""
    from mtbmj.measured.telemetry import ride_path

    shipped = Path(ride_path("example"))
    monkeypatch.chdir(tmp_path)
    Path(shipped.name).write_bytes(shipped.read_bytes())
    out = tmp_path / "advice"
    refused(["advise", "example", shipped.name, "--bike", "sst", "--out", out], out, capfd,
            f"{shipped.name}: the same ride as {shipped} (the same travels on the same clock)")
    # the other side: one path twice is named by its name, as before
    refused(["advise", shipped.name, shipped.name, "--bike", "sst", "--out", out], out, capfd,
            f"{shipped.name}: the same ride as {shipped.name} (the same")


def test_a_bike_sag_typed_as_a_fraction_says_so(tmp_path, capfd):
    """``--front-sag-percent 0.2``: "no setting ... gives 0.2 % front": true, but the cause unsaid (its
    plausibility warning is dropped from a refusal that does not name the option)."""
    out = tmp_path / "sag"
    refused(["sag", "trail", "--bike", "--front-sag-percent", "0.2", "--rear-sag-percent", "0.28", "--out", out],
            out, capfd, "gives 0.2 % front and 0.28 % rear sag (0.2 % front and 0.28 % rear: a fraction typed for a "
                        "percent? 0.2 is 20 %)")


def test_a_washboards_wavelength_in_metres_is_named():
    """``washboard:wavelength_mm=0.5`` (0.5 m typed in mm): the wheel rolled over 0.5 mm ripples it cannot feel,
    the run the same as a flat one, unsaid (only heights and radii were held to 3 mm)."""
    from mtbmj.rolling import terrain as T

    with pytest.warns(Warning, match=r"wavelength_mm = 0.5 mm is under 3 mm, smaller than any trail feature \(a unit "
                                     r"mistake\? 0.5 m is wavelength_mm=500\)"):
        T.make("washboard:wavelength_mm=0.5")
    with pytest.warns(Warning, match=r"width_mm = 0.1 mm is under 3 mm"):
        T.make("square_edge:width_mm=0.1")
    # the other side: a real wavelength, and the iso8608 road's sampling step (no feature), draw none
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        T.make("washboard:wavelength_mm=500")
        T.make("iso8608:sample_mm=1")

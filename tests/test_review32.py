"""What the review of round 32's careless-input fixes found (each failed before its fix): a name the file system
takes refused after the work for the staged copy's longer name, an empty record name read as the current folder,
a table given whole to ``--set`` told it was given a value. Inputs are written here."""
from __future__ import annotations

import csv

import pytest

from mtbmj import limits
from helpers import command_err, refused


def test_a_record_name_the_file_system_takes_is_written(tmp_path, capfd):
    """``synth spring S12 --out n3/bbb...(247).csv``: a 251-byte name, within the 255 a name may have, was refused
    after the work ("File name too long"): the record was staged as ``.NAME.partial.csv``, 9 bytes longer."""
    out = tmp_path / "n3" / f"{'b' * 247}.csv"
    status, err = command_err(["synth", "spring", "S12", "--out", out], capfd)
    assert status == 0 and err == "", err
    with open(out, newline="") as f:  # the record whole: a header and its rows, nothing staged left beside it
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    assert len(rows) > 100 and all(len(r) == len(rows[0]) for r in rows)
    assert [p.name for p in out.parent.iterdir()] == [out.name]


def test_an_empty_record_name_to_fit_is_named_empty(tmp_path, capfd):
    """``fit spring ''``: ".: is a directory, not a file" (Path('') is the current folder)."""
    refused(["fit", "spring", "", "--out", tmp_path / "fit.toml"], tmp_path / "fit.toml", capfd,
            "fit spring: an empty name among the records")


def test_a_table_given_whole_to_set_is_told_how_to_set_its_keys(tmp_path, capfd):
    """``--set 'sled={body_mass_kg=5}'``: "sled: is a table of keys (e.g. sled.body_mass_kg), not a value", where
    a table was given; its keys go one at a time. A value in its place keeps its own line."""
    refused(["drop", "S12", "--set", "sled={body_mass_kg=5}", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "sled: a table given whole; set its keys one at a time, e.g. --set sled.body_mass_kg=5")
    refused(["drop", "S12", "--set", "sled=5", "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "sled: is a table of keys (e.g. sled.body_mass_kg), not a value; got 5")


@pytest.mark.parametrize("typed, note", [
    # converted into the option's unit but outside its range: the range, not a number the option then refuses
    ("500km/h", "(the option is in m/s: 500 km/h = 138.9 m/s, outside the range allowed: above 0 and at most 100 m/s)"),
    ("-20km/h", "(the option is in m/s: -20 km/h = -5.556 m/s, outside the range allowed: above 0 and at most 100"),
    # the number alone as typed (":g" dropped digits: 160.123), and outside the range: said so
    ("160.1234567m/s", "(the unit is the option's, m/s: 160.1234567 is outside the range allowed: above 0 and at"),
    ("12.3456789m/s", "(the unit is the option's, m/s: give the number alone, 12.3456789)"),
    ("20km/h", f"(the option is in m/s: 20 km/h = {20 / 3.6:.4g} m/s, give {20 / 3.6:.4g})"),  # the other side
])
def test_a_unit_typed_in_a_value_names_a_number_the_option_takes(typed, note):
    """review32a: ``--speed=500km/h`` said "give 138.9", which the option refuses (at most 100 m/s)."""
    with pytest.raises(ValueError) as caught:
        limits.argument("--speed", typed)
    assert note in str(caught.value), str(caught.value)


@pytest.mark.parametrize("typed", ["4-6", "5/2", "3.2.1", "0x10", "1e"])
def test_a_value_with_no_unit_in_it_is_not_told_it_has_one(typed):
    """review32a: ``--speed 4-6`` (a range), ``5/2``, ``3.2.1``, ``0x10``, ``1e`` were each told "the option takes a
    number in m/s, without a unit": no unit was typed. The line is the value's alone."""
    with pytest.raises(ValueError) as caught:
        limits.argument("--speed", typed)
    assert str(caught.value) == f"{typed!r} is not a number"


# --- review32b: the Python API's plausibility warnings (careless32b) said where no one typed the value ----------

def _config_warnings(call):
    import warnings

    from mtbmj.errors import ConfigWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    return result, [w for w in caught if issubclass(w.category, ConfigWarning)]


def test_a_still_rig_and_a_saved_run_replayed_are_not_warned_of_a_speed_nobody_typed():
    """``fit bounce --replay`` builds the bike standing still (1 mm/s, ``bounce_replay.STILL_M_PER_S``) through
    ``bike.run.prepare``: it warned "--speed = 0.001 m/s is outside 0.3-30 m/s"; ``render`` of a saved roll run at
    head angle 50 warned "--head-angle = 50 deg" (render has no such option). Warned where a caller gives them:
    ``run_roll`` and ``run_bike``, at the caller's own line (not a line inside the package)."""
    from mtbmj.bike import run as bike_run
    from mtbmj.rolling import frontend

    _, said = _config_warnings(lambda: bike_run.prepare("sst", "flat", 1e-3, drive="coast", seated=True))
    assert said == []
    _, said = _config_warnings(lambda: frontend.roll_trajectory("flat", 4.0, head_angle_deg=50.0, duration=0.02))
    assert said == []
    _, said = _config_warnings(lambda: frontend.run_roll("flat", 4.0, head_angle_deg=50.0, duration=0.02))
    assert [w.filename for w in said] == [__file__] and "--head-angle = 50 deg is outside 55-80 deg" in str(said[0].message)


def test_a_config_file_named_like_a_unit_is_read_by_validate(tmp_path, capfd, monkeypatch):
    """``validate example --duration 0.5 s`` with a configuration file named ``s`` was refused as "'0.5 s' is a
    number and its unit": validate's parse goes in two passes whose first leaves its positionals over."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s").write_text('base = "S12"\n')
    status, err = command_err(["validate", "example", "--duration", "0.5", "s", "--out", tmp_path / "out", "--quiet"],
                              capfd)
    assert status == 0 and "is a number and its unit" not in err, err
    assert (tmp_path / "out" / "validation_report.html").exists()
    status, err = command_err(["roll", "flat", "--speed", "20", "km/h", "--out", tmp_path / "r"], capfd)  # the other side
    assert status == 2 and "'20 km/h' is a number and its unit" in err, err

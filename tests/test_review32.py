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

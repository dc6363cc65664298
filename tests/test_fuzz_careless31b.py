"""Careless input, round 31b: what round 31 left alone. A bad terrain spec, record or ride file not caught by
``except ValueError`` (TerrainError, RecordError, TelemetryError were no ValueErrors, while ConfigError was), a
command-line option's range warning naming no unit (``--fork-max-mm 0.16``: "(a unit mistake?)" only), a sag
load of 180 (lb typed as kg) run unsaid, a 5 m square edge rolled into unsaid, and usage.md's Python example
showing ``plot()`` where the README shows ``quicklook()``. Every input is written here."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

from mtbmj import limits
from mtbmj.errors import ConfigError, MtbmjError, RunError
from mtbmj.measured import records, telemetry
from mtbmj.rolling import terrain as T
from helpers import command_err, command_said

DOCS = Path(__file__).resolve().parent.parent


def test_the_input_errors_are_value_errors(tmp_path):
    """``except ValueError`` caught a bad configuration but not a bad terrain spec, record or ride file."""
    with pytest.raises(ValueError, match="unknown scenario"):
        T.make("drop_off:height_mm=300")  # no such scenario
    record = tmp_path / "dyno.csv"
    record.write_text("time_s,force_N\n0.0,10\n0.1,ten\n")
    with pytest.raises(ValueError, match="line 3"):
        records.read_csv(record)
    ride = tmp_path / "ride.csv"
    ride.write_text("time_s,fork_mm\n0.0,1\n0.01\n")
    with pytest.raises(ValueError, match="line 3"):
        telemetry.read_travel_csv(ride)
    for error in (T.TerrainError, records.RecordError, telemetry.TelemetryError, ConfigError):
        assert issubclass(error, ValueError) and issubclass(error, MtbmjError), error
    # the other side: a run that left the model's envelope is no input error
    assert not issubclass(RunError, ValueError) and not issubclass(MtbmjError, ValueError)


@pytest.mark.parametrize("option, typed, said", [
    ("--fork-max-mm", "0.16", "probably meant 0.16 m = 160 mm"),
    ("--shock-max-mm", "2.5", "probably meant 2.5 in = 63.5 mm"),
    ("--load-kg", "180", "probably meant 180 lb = 81.65 kg"),
    ("--sag-percent", "0.25", "probably meant 0.25 as a fraction = 25 %"),
])
def test_an_options_unit_slip_is_named(option, typed, said):
    """An option's range warning ended in "(a unit mistake?)" alone; now it names the slip that brings it in."""
    with pytest.warns(Warning, match=re.escape(f"(a unit mistake? {said})")):
        limits.argument(option, typed)


def test_an_option_out_of_range_that_is_no_slip_names_none():
    with pytest.warns(Warning, match=re.escape("(a unit mistake?)")):
        limits.argument("--fork-max-mm", "900")  # neither 900 m, in nor cm is a fork's travel
    with warnings.catch_warnings():  # the other side: a fork's travel draws no warning
        warnings.simplefilter("error")
        assert limits.argument("--fork-max-mm", "160") == 160.0


def test_a_telemetry_travel_in_metres_names_metres(capfd):
    """``--fork-max-mm 0.16`` (the fork's 160 mm in metres): the refusal's note names metres."""
    status, err = command_err(["telemetry", "example", "--fork-max-mm", "0.16", "--out", "unused"], capfd)
    assert status == 2 and err.count("\n") == 1 and "probably meant 0.16 m = 160 mm" in err, err


def test_a_sag_load_in_pounds_is_named(tmp_path, capfd):
    """``mtbmj sag air120 --load-kg 180``: 180 kg on a fork (a 300 kg rider and bike) ran unsaid; the load a
    fork carries at sag is part of the rider's mass, at most the heaviest rider's 150 kg."""
    status, said = command_said(["sag", "air120", "--load-kg", "180", "--sag-percent", "20", "--out",
                                 tmp_path / "a"], capfd)
    assert status == 0 and said.count("mtbmj: warning:") == 1, said
    assert "--load-kg = 180 kg is outside 5-150 kg" in said and "probably meant 180 lb = 81.65 kg" in said, said
    # the other side: a rider's front load draws none
    status, said = command_said(["sag", "air120", "--load-kg", "80", "--sag-percent", "20", "--out",
                                 tmp_path / "b"], capfd)
    assert status == 0 and "warning" not in said, said


@pytest.mark.parametrize("spec, said", [
    ("square_edge:height_mm=5000", "terrain square_edge: height_mm = 5000 mm is over 1000 mm, taller than any trail "
                                   "feature a wheel rolls over"),
    ("step_up:height_mm=1500", "terrain step_up: height_mm = 1500 mm is over 1000 mm"),
    ("root:radius_mm=2000", "terrain root: radius_mm = 2000 mm is over 1000 mm"),
    ("drum:cleat_height_mm=1200", "terrain drum: cleat_height_mm = 1200 mm is over 1000 mm"),
    ("drop:height_mm=8000", "terrain drop: height_mm = 8000 mm is over 5000 mm, taller than any trail feature a "
                            "wheel drops off"),
])
def test_a_feature_taller_than_a_trail_holds_is_named(spec, said):
    """``mtbmj roll square_edge:height_mm=5000`` ran, told only that the wheel went back."""
    with pytest.warns(Warning, match=re.escape(said)) as caught:
        T.make(spec)
    assert len([w for w in caught if "taller than any" in str(w.message)]) == 1


def test_a_trail_sized_feature_draws_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for spec in ("square_edge:height_mm=300", "drop:height_mm=1500", "step_up:height_mm=1000",
                     "drum:radius_mm=2000", "rock:length_mm=3000"):
            T.make(spec)


def test_usage_shows_the_figure_the_readme_and_every_result_have():
    """usage.md showed ``r.plot().savefig`` where the README shows ``r.quicklook().savefig``."""
    usage = (DOCS / "docs" / "usage.md").read_text(encoding="utf-8")
    readme = (DOCS / "README.md").read_text(encoding="utf-8")
    line = 'r.quicklook().savefig("s12.png")'
    assert line in readme and line in usage
    assert "r.plot().savefig" not in usage and "`plot(axes=None" in usage


@pytest.mark.parametrize("argv, said", [
    (["S12", "--presets", "S12"], "S12: given twice (in --presets and as CONFIG); give each configuration once"),
    (["S12", "S12"], "S12: given twice (as CONFIG)"),
])
def test_validate_given_a_configuration_twice_refuses(tmp_path, capfd, argv, said):
    """``mtbmj validate example S12 --presets S12`` ran S12 twice (as S12 and S12-2), unsaid."""
    from helpers import refused

    out = tmp_path / "v"
    refused(["validate", "example", *argv, "--out", out, "--quiet"], out, capfd, said)


def test_a_sensitivity_that_fails_for_a_range_in_metres_names_it(tmp_path, capfd):
    """``--vary sled.drop_height_mm=0.1:0.5`` (metres for mm): refused as "fork_peak1_mm is undefined in 6 of 6
    runs", the range's warning, the cause, dropped from the line (only a key the line named was added)."""
    out = tmp_path / "s"
    status, err = command_err(["sensitivity", "S12", "--vary", "sled.drop_height_mm=0.1:0.5", "--samples", "2",
                               "--engine", "fast", "--duration", "0.2", "--workers", "1", "--quiet", "--out", out],
                              capfd)
    lines = err.splitlines()
    assert status == 2 and len(lines) == 1 and "fork_peak1_mm is undefined in 6 of 6 runs" in lines[0], err
    assert "probably meant 0.1 m = 100 mm" in lines[0], err


def test_study_takes_a_range_of_presets_as_validate_does(tmp_path, capfd):
    """``mtbmj study --presets S1..S2`` (validate's syntax): "S1..S2: unknown preset"."""
    out = tmp_path / "st"
    status, said = command_said(["study", "--presets", "S1..S2", "--engines", "fast", "--duration", "0.3",
                                 "--quiet", "--out", out], capfd)
    assert status == 0 and "study: 2 configurations x 1 engines" in said, said
    # the other side: a name that is no range nor preset is still refused naming it
    from helpers import refused

    refused(["study", "--presets", "S1..S2x", "--engines", "fast", "--out", tmp_path / "st2"], tmp_path / "st2",
            capfd, "S1..S2x: unknown preset")

"""What the review of round 33's merges (depth33, careless33) found, each mended at its cause; inputs made here."""
from __future__ import annotations

import numpy as np
import pytest

from helpers import command_err


def test_identify_takes_numpys_numbers_for_the_tyre_mass():
    """``identify("tire", ..., mass_kg=np.int64(5))`` ran before round 33 and was then refused ("mass_kg: must be a
    number of kg, got np.int64(5)"): a number from numpy is a number (a config key's from Python too)."""
    from mtbmj.identify import identify
    from mtbmj.identify.examples import example_paths
    from mtbmj.limits import number

    assert number("k", np.int64(5)) == 5.0 and number("k", np.float32(0.5)) == 0.5
    with pytest.raises(ValueError, match="k: must be a number"):
        number("k", np.bool_(True))
    assert identify("tire", example_paths("tire"), mass_kg=np.int64(5)).kind == "tire"


def test_a_generator_given_as_a_list_of_names_is_read_once_and_kept():
    """``check_outputs(o for o in [...])`` and identify's ``free``/``clicks`` checked a generator by reading it and
    went on with the spent one: "--output: name at least one output", and a fit with no free key (identify's
    check read here alone: a fit takes minutes)."""
    from mtbmj.identify.run import _check_arguments
    from mtbmj.sweep.sensitivity import check_outputs

    assert check_outputs(o for o in ["fork_peak1_mm"]) == ["fork_peak1_mm"]
    free, clicks = _check_arguments("mujoco", 1, (k for k in ["fork.spring.rate_N_per_mm"]), None, None, None,
                                    (c for c in [0, 8]))
    assert free == ["fork.spring.rate_N_per_mm"] and clicks == [0, 8]


def test_sobols_design_has_no_levels_to_refuse():
    """``samples(prob, 8, "sobol", 0, 1)`` returned its design before round 33 and was then refused for --levels,
    which sobol does not use; morris still holds --levels to at least 2."""
    from mtbmj.errors import ConfigError
    from mtbmj.sweep.sensitivity import samples

    prob = {"num_vars": 1, "names": ["a"], "bounds": [[0.0, 1.0]]}
    assert samples(prob, 8, "sobol", 0, 1).shape == (24, 1)
    assert samples(prob, 8, "sobol", 0, None).shape == (24, 1)
    with pytest.raises(ConfigError, match="--levels"):
        samples(prob, 8, "morris", 0, 1)


@pytest.mark.parametrize("argv, option", [
    (["roll", "flat", "--spee", "5", "km/h"], "--speed"),
    (["roll", "flat", "--spee=5", "km/h"], "--speed"),
    (["roll", "flat", "--speed", "5", "--dur", "0.2", "s"], "--duration"),
])
def test_a_unit_typed_apart_after_an_abbreviated_option_is_named(tmp_path, capfd, argv, option):
    """argparse takes a long option's unique prefix (``--spee`` for ``--speed``): the unit typed apart after it was
    "unrecognized arguments: km/h" (or the scenario "s", or ``bob --pow 250 W REC``'s "W: cannot read"), where
    the full option's is named; now the same line, naming the option in full."""
    status, err = command_err([*argv, "--out", str(tmp_path / "out")], capfd)
    assert status == 2 and f"argument {option}: '" in err and "is a number and its unit" in err, err
    assert not (tmp_path / "out").exists()


def test_a_start_far_before_the_terrain_is_refused_naming_its_ends(tmp_path, capfd):
    """review33b: with --start-m's range widened to 100 km, ``--start-m -99999`` rode 100 km of level ground before
    the terrain, silently (a sign or mm-for-m slip); a start more than 100 m before it begins is refused naming its
    ends, one 50 m before still runs."""
    status, err = command_err(["bike", "sst", "flat", "--speed", "5", "--duration", "0.2", "--start-m", "-5000",
                               "--out", tmp_path / "far", "--quiet", "--no-figure"], capfd)
    assert status == 2 and "start: the front axle's start (--start-m) -5000 m is 5000 m before the terrain flat " \
        "begins (0 to 10 m): start within 100 m of its beginning" in err, err
    assert not (tmp_path / "far").exists()
    status, err = command_err(["bike", "sst", "flat", "--speed", "5", "--duration", "0.2", "--start-m", "-50",
                               "--out", tmp_path / "near", "--quiet", "--no-figure"], capfd)
    assert status == 0, err


def test_numpys_times_are_no_numbers_and_a_long_double_past_the_float_range_is_too_large():
    """review33b: taking numpy's numbers let np.timedelta64(5) through as 5.0 (identify then met a TypeError);
    np.longdouble('1e400') was "must be finite ... got inf" for a finite number."""
    from mtbmj.limits import number

    for value in (np.timedelta64(5), np.timedelta64(5, "s"), np.datetime64("2020-01-01")):
        with pytest.raises(ValueError, match="k: must be a number, got "):
            number("k", value)
    with pytest.raises(ValueError, match="is too large for any number the model holds"):
        number("k", np.longdouble("1e400"))
    with pytest.raises(ValueError, match="must be finite"):
        number("k", np.float64("inf"))

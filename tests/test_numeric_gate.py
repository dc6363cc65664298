"""The one numeric-input gate (issue 49) and RuntimeWarnings as errors only where a run steps.

Every number a user gives (a configuration's or a bike file's key, a ``--set``, a command's
numeric argument) passes ``mtbmj.limits`` before any work: NaN, infinity, an integer too large for
a float and a value beyond what the model holds are refused in one line naming the key or the
option; a value outside its plausible range is warned about. numpy's RuntimeWarnings are errors
(a diverged run) only inside a run's stepping (``mtbmj.errors.diverging``), never around a fit or
a reader. Every record and bike file here is made in the test.
"""
from __future__ import annotations

import argparse
import math
import warnings

import numpy as np
import pytest

from mtbmj import cli, limits
from mtbmj.errors import ConfigError, ConfigWarning, RunError, diverging

HUGE = int("1" + "0" * 400)  # what TOML reads for 1 followed by 400 zeros: an int no float holds
HUGE_TEXT = "1" + "0" * 400


def _one_line_refusal(capsys, argv, needle, tmp_path):
    before = sorted(p.name for p in tmp_path.iterdir())
    code = cli.main(argv)
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("mtbmj: error: ") and needle in lines[0], err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
    return lines[0]


# --- the key gate ------------------------------------------------------------------------------

@pytest.mark.parametrize("value", [HUGE, -HUGE, math.inf, -math.inf, math.nan, 1e300, -1e300, 10 ** 31])
def test_a_key_value_no_model_holds_is_refused_naming_the_key(value):
    with pytest.raises(ConfigError) as err:
        limits.number("shock.stroke_mm", value)
    text = str(err.value)
    assert text.startswith("shock.stroke_mm: ") and "\n" not in text and len(text) < 200, text


@pytest.mark.parametrize("value", [True, "12", None, [1.0]])
def test_a_key_value_that_is_not_a_number_is_refused(value):
    with pytest.raises(ConfigError, match=r"^rider\.mass_kg: must be a number"):
        limits.number("rider.mass_kg", value)


def test_a_plain_number_passes_the_gate_unchanged():
    assert limits.number("k", 7) == 7.0 and limits.number("k", -2.5) == -2.5
    # whole numbers that fit stay whole (teeth, spacers), nested lists and tables are walked
    assert limits.numbers_in("t", {"a": [1, 2.5], "b": {"c": 3}, "d": "text"}) == {"a": [1, 2.5], "b": {"c": 3},
                                                                                    "d": "text"}
    with pytest.raises(ConfigError, match=r"^t\.b\.c: "):
        limits.numbers_in("t", {"b": {"c": HUGE}})


# A bike file made here: the SST preset with one key changed, written as TOML text.
def _bike_file(tmp_path, section, key, literal):
    path = tmp_path / "hostile.toml"
    path.write_text(f'base = "sst"\n[{section}]\n{key} = {literal}\n')
    return path


HOSTILE_LITERALS = [HUGE_TEXT, "-" + HUGE_TEXT, "inf", "-inf", "nan", "1e300", "-1e300"]
BIKE_KEYS = [("geometry", "head_angle_deg"), ("shock", "spring_rate_lb_per_in"), ("sensors", "fork_arm_mm"),
             ("shock", "stroke_mm"), ("rider", "leg_stiffness_N_per_mm"), ("bike", "frame_mass_kg"),
             ("rider", "mass_kg"), ("geometry", "wheel_diameter_mm"), ("geometry", "fork_travel_mm"),
             ("drive", "push_N"), ("shock", "pressure_psi")]


@pytest.mark.parametrize("section,key", BIKE_KEYS)
@pytest.mark.parametrize("literal", HOSTILE_LITERALS)
def test_fuzz_hostile_numbers_in_a_bike_file_are_refused_in_one_line(tmp_path, capsys, monkeypatch, section, key,
                                                                     literal):
    """The reproductions (10**400 head angle, rate, sensor arm, stroke: OverflowError tracebacks;
    a 1e300 leg stiffness: IndexError) and their kin, across keys of every section."""
    monkeypatch.chdir(tmp_path)
    path = _bike_file(tmp_path, section, key, literal)
    line = _one_line_refusal(capsys, ["bike", path.name, "flat", "--speed", "3", "--duration", "0.05",
                                      "--out", "out"], f"{section}.{key}", tmp_path)
    assert "hostile.toml" in line  # the file is named with the key


@pytest.mark.parametrize("section,key", BIKE_KEYS[:6])
@pytest.mark.parametrize("literal", [HUGE_TEXT, "nan", "-inf", "1e300"])
def test_fuzz_hostile_numbers_set_on_the_command_line_are_refused_in_one_line(tmp_path, capsys, monkeypatch, section,
                                                                              key, literal):
    monkeypatch.chdir(tmp_path)
    _one_line_refusal(capsys, ["bike", "sst", "root", "--speed", "5", "--duration", "0.05", "--out", "out",
                               "--set", f"{section}.{key}={literal}"], f"{section}.{key}", tmp_path)


@pytest.mark.parametrize("literal", [HUGE_TEXT, "nan", "1e300"])
def test_a_hostile_number_in_a_bikes_shock_configuration_is_refused(tmp_path, capsys, monkeypatch, literal):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.toml").write_text(f'base = "sst"\n[shock.set]\n"fork.spring.rate_N_per_mm" = {literal}\n')
    _one_line_refusal(capsys, ["bike", "b.toml", "flat", "--speed", "3", "--duration", "0.05", "--out", "out"],
                      "fork.spring.rate_N_per_mm", tmp_path)


@pytest.mark.parametrize("key", ["fork.spring.rate_N_per_mm", "sled.drop_height_mm", "tire.radius_mm",
                                 "solver.timestep_s", "fork.damper.force_N"])
@pytest.mark.parametrize("literal", [HUGE_TEXT, "inf", "nan", "-1e300"])
def test_fuzz_hostile_numbers_in_a_configuration_are_refused_in_one_line(tmp_path, capsys, monkeypatch, key,
                                                                         literal):
    monkeypatch.chdir(tmp_path)
    value = f"[0.0, {literal}]" if key.endswith("force_N") else literal
    _one_line_refusal(capsys, ["drop", "S1", "--set", f"{key}={value}", "--duration", "0.05", "--out", "out"],
                      key, tmp_path)


# --- the argument gate -------------------------------------------------------------------------

def _numeric_options():
    """(the command's words, option) of every numeric argument of every command, found in the
    parser itself (a new argument is fuzzed without this list being edited)."""
    found = []
    parser = cli.build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in subs.choices.items():
        for action in sub._actions:
            if getattr(action.type, "__name__", "") == "number":
                words = [name, "spring"] if name == "fit" else [name]
                found.append((tuple(words), action.option_strings[-1]))
    return found


NUMERIC_OPTIONS = _numeric_options()


def test_every_numeric_argument_goes_through_the_gate_with_a_stated_range():
    assert len(NUMERIC_OPTIONS) > 40  # every command's --speed, --duration, --workers, ...
    lacking = sorted({option for _, option in NUMERIC_OPTIONS if option not in limits.ARGUMENTS})
    assert lacking == []
    parser = cli.build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    plain = [(name, a.option_strings) for name, sub in subs.choices.items() for a in sub._actions
             if a.type in (float, int)]
    assert plain == []  # no numeric argument is parsed by a bare float or int


@pytest.mark.parametrize("words,option", NUMERIC_OPTIONS, ids=[f"{' '.join(w)} {o}" for w, o in NUMERIC_OPTIONS])
def test_fuzz_hostile_numbers_given_to_any_argument_are_refused_in_one_line(tmp_path, capsys, monkeypatch, words,
                                                                            option):
    monkeypatch.chdir(tmp_path)
    for value in ("nan", "inf", "-inf", "1e400", HUGE_TEXT, "-" + HUGE_TEXT, "9" * 5000, "twelve"):
        line = _one_line_refusal(capsys, [*words, option, value, "--out", "out"], option, tmp_path)
        assert len(line) < 300, line


@pytest.mark.parametrize("words,option", NUMERIC_OPTIONS, ids=[f"{' '.join(w)} {o}" for w, o in NUMERIC_OPTIONS])
def test_a_value_starting_like_a_negative_number_is_judged_as_a_value(tmp_path, capsys, monkeypatch, words, option):
    """``--speed -1e3`` or ``--static-sag-mm -40,20`` was "expected one argument" (argparse takes only
    ``-40`` and ``-0.5`` for values): the value's own check now says what is wrong with it."""
    monkeypatch.chdir(tmp_path)
    for value in ("-1e400", "-4,5"):  # (an integer's gate: "is not a whole number")
        line = _one_line_refusal(capsys, [*words, option, value, "--out", "out"], option, tmp_path)
        assert "expected one argument" not in line and repr(value) in line, line


def test_a_threshold_of_infinity_is_refused_by_the_parser(tmp_path, capsys, monkeypatch):
    """``telemetry example --threshold-mm-per-s inf`` ended "run diverged (invalid value
    encountered in multiply)"; it is refused before any work."""
    monkeypatch.chdir(tmp_path)
    _one_line_refusal(capsys, ["telemetry", "example", "--threshold-mm-per-s", "inf", "--out", "out"],
                      "argument --threshold-mm-per-s: must be a finite number", tmp_path)


@pytest.mark.parametrize("argv", [
    ["bike", "sst", "drop", "--speed", "1000", "--out", "out"],
    ["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:2", "--speed", "1e9", "--out", "out"],
    ["roll", "flat", "--speed", "150", "--out", "out"],
])
def test_a_speed_beyond_the_model_is_refused(tmp_path, capsys, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    line = _one_line_refusal(capsys, argv, "argument --speed:", tmp_path)
    assert "at most 100 m/s" in line


def test_a_speed_beyond_any_ridden_is_warned_about_and_the_run_proceeds(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = cli.main(["bike", "sst", "drop", "--speed", "45", "--duration", "0.02", "--out", "out"])
    err = capsys.readouterr().err
    assert code == 0, err
    warned = [line for line in err.splitlines() if line.startswith("mtbmj: warning: --speed = 45 m/s")]
    assert len(warned) == 1 and "0.3-30 m/s" in warned[0], err
    assert "Traceback" not in err


def test_the_argument_type_warns_once_per_value_outside_the_plausible_range():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert limits.argument("--speed", "12") == 12.0
        assert limits.argument("--speed", "31") == 31.0
    assert [str(w.message).split(" is ")[0] for w in caught if issubclass(w.category, ConfigWarning)] == [
        "--speed = 31 m/s"]
    assert limits.argument("--workers", "3") == 3 and isinstance(limits.argument("--workers", "3"), int)
    for text in ("0", "-1", "101", "nan", "inf", "1e400"):
        with pytest.raises(ValueError):
            limits.argument("--speed", text)


# --- RuntimeWarnings: errors only where a run steps ---------------------------------------------

def _bilinear_dyno(path, rate_below=8.0, rate_above=16.0, knee_mm=60.0, preload_N=150.0, top_out_N_per_mm=60.0,
                   friction_N=25.0, cycles=3, rate_Hz=100.0, period_s=2.0):
    """A spring dyno record made here: a bilinear coil (knee at ``knee_mm``) on its preload, a
    top-out spring past full extension, Coulomb hysteresis; three cycles at 100 Hz, comma-
    separated, mm and N."""
    t = np.arange(0.0, cycles * period_s, 1.0 / rate_Hz)
    x = 45.0 - 50.0 * np.cos(2.0 * np.pi * t / period_s)  # -5 .. 95 mm
    f = np.where(x < knee_mm, preload_N + rate_below * x, preload_N + rate_below * knee_mm + rate_above * (x - knee_mm))
    f = np.where(x < 0.0, preload_N + top_out_N_per_mm * x, f) + friction_N * np.sign(np.gradient(x, t))
    path.write_text("time_s,displacement_mm,force_N\n" + "".join(f"{a:.6f},{b:.6f},{c:.6f}\n" for a, b, c in zip(t, x, f)))
    return path


def test_a_warning_a_library_raises_and_handles_inside_a_fit_is_not_a_divergence(tmp_path, capsys, monkeypatch):
    """``fit spring`` on a valid bilinear dyno record ended "run diverged (invalid value
    encountered in multiply)": scipy's ``lsq_linear`` met such a value and handled it, and the
    command line made every RuntimeWarning fatal. Here the bounded solver meets one on every call
    (as scipy's did) and the fit still answers."""
    from mtbmj.identify import spring as spring_mod

    real = spring_mod.lsq_linear
    calls = []

    def meets_an_invalid_value(*args, **kwargs):
        calls.append(1)
        _ = np.float64(0.0) * np.float64(np.inf)  # RuntimeWarning: invalid value encountered in multiply
        return real(*args, **kwargs)

    monkeypatch.setattr(spring_mod, "lsq_linear", meets_an_invalid_value)
    monkeypatch.chdir(tmp_path)
    _bilinear_dyno(tmp_path / "dyno.csv")
    code = cli.main(["fit", "spring", "dyno.csv", "--out", "out"])
    err = capsys.readouterr().err
    assert calls, "the fit did not reach the bounded solver"
    assert code in (0, 3), err  # an answer (3: it says its model misses the record), not a refusal
    assert "diverged" not in err and "invalid value" not in err and "Traceback" not in err
    assert (tmp_path / "out" / "fit.toml").is_file()


def test_an_overflow_while_stepping_is_a_divergence_and_only_there():
    with pytest.raises(RunError, match=r"^drop run diverged \(overflow encountered"):
        with diverging("drop"):
            np.float64(1e300) * np.float64(1e300)
    with pytest.raises(RunError, match=r"^bike run diverged before t = 0\.2500 s: a numerical overflow"):
        with diverging("bike", lambda: 0.25):
            np.array([-1.0]) ** 0.5 + np.log(np.array([0.0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        assert np.isinf(np.float64(1e300) * np.float64(1e300))  # outside the block: numpy's own rule again


def test_a_drop_whose_ode_overflows_is_still_refused_in_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    line = _one_line_refusal(capsys, ["drop", "S1", "--engine", "ode", "--set", "sled.drop_height_mm=1e29",
                                      "--out", "out"], "diverged", tmp_path)
    assert "sled.drop_height_mm" in line  # the implausible value named as the likely cause

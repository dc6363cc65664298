"""One cross-check result for every rig (issue 38 item 3): ``mtbmj.runpath.crosscheck``'s
``CrosscheckResult`` holds the drop's, the rolling front end's and the bike's checks against their
ODE references: per signal the largest difference over the series, its unit, the peaks in both
runs, the tolerance and the verdict, and both wall times, in one line and one dict. The series
here are made in the test, so the verdicts at the tolerance's edge are known exactly."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mtbmj.runpath.crosscheck import CrosscheckResult, SignalCheck, compare_series

TIMES = np.arange(5) * 0.01


def made(fork_gap: float = 0.0, load_gap: float = 0.0, tolerance_mm: float = 0.1) -> CrosscheckResult:
    """A check built from series made here: the fork off by ``fork_gap`` mm at t = 0.02 s, the
    tire load off by ``load_gap`` N at t = 0.03 s (its reference peak 1000 N), a pitch reported."""
    fork_ref = np.array([0.0, 10.0, 20.0, 15.0, 12.0])
    fork = fork_ref.copy()
    fork[2] += fork_gap
    load_ref = np.array([400.0, 600.0, 800.0, 1000.0, 900.0])
    load = load_ref.copy()
    load[3] += load_gap
    signals = [compare_series("fork", "mm", TIMES, fork, fork_ref, tolerance_mm),
               compare_series("pitch", "deg", TIMES, [0.0, 0.1, 0.2, 0.1, 0.0], [0.0, 0.1, 0.2, 0.1, 0.05]),
               compare_series("tire_load", "N", TIMES, load, load_ref, 0.01, relative=True,
                              judged=("peak", "series"))]
    return CrosscheckResult("test", "made series", "mujoco", "made reference", signals, 0.25, 1.5,
                            {"note": "made in the test"})


def test_a_check_within_its_tolerances_passes():
    check = made(fork_gap=0.06, load_gap=5.0)
    fork, pitch, load = check["fork"], check["pitch"], check["tire_load"]
    assert check.passed and fork.passed and load.passed and pitch.passed is None  # pitch: reported only
    assert fork.max_abs == pytest.approx(0.06) and fork.at_time_s == pytest.approx(0.02) and fork.unit == "mm"
    assert fork.engine_peak == pytest.approx(20.06) and fork.reference_peak == 20.0
    assert load.max_abs == 5.0 and load.engine_peak == 1005.0 and load.reference_peak == 1000.0
    assert load.series_difference == pytest.approx(0.005) and load.peak_difference == pytest.approx(0.005)
    assert pitch.max_abs == pytest.approx(0.05) and pitch.at_time_s == pytest.approx(0.04)
    assert check.worst is fork  # 0.06 of 0.1 mm is nearer its tolerance than 0.5 % of 1 %
    assert fork.ratio == pytest.approx(0.6) and load.ratio == pytest.approx(0.5) and pitch.ratio is None
    assert (check.engine_wall_s, check.reference_wall_s) == (0.25, 1.5)


def test_equal_to_the_tolerance_passes_and_just_beyond_it_fails():
    tolerance = 0.1
    at_edge = made(fork_gap=tolerance, tolerance_mm=tolerance)
    # the gap as computed (20 + 0.1 - 20) is the tolerance in floating point, or a hair off it:
    # the verdict follows the number the check holds, compared with <=
    assert at_edge["fork"].passed == (at_edge["fork"].max_abs <= tolerance)
    edge = SignalCheck("fork", "mm", tolerance, 0.02, 20.1, 20.0, tolerance, judged=("series",))
    beyond = SignalCheck("fork", "mm", math.nextafter(tolerance, math.inf), 0.02, 20.1, 20.0, tolerance,
                         judged=("series",))
    assert edge.passed is True and beyond.passed is False
    # the tire load's series judged at 1 % of the reference's 1000 N peak: 10 N passes, a little more fails
    assert made(load_gap=10.0)["tire_load"].passed and made(load_gap=10.0).passed
    failing = made(load_gap=10.001)
    assert not failing["tire_load"].passed and not failing.passed and failing.worst.name == "tire_load"
    assert failing["fork"].passed  # the fork is still within: the verdict is the tire load's
    assert "tire load peak 1.00 % (EXCEEDS 1 %) and series 1.00 % of the peak (EXCEEDS 1 %)" in failing.line()
    assert "NOT within the tolerances" in failing.line()


def test_a_difference_that_is_not_finite_fails():
    for bad in (math.nan, math.inf):
        fork_ref = np.array([0.0, 10.0, 20.0, 15.0, 12.0])
        engine = fork_ref.copy()
        engine[3] = bad
        signal = compare_series("fork", "mm", TIMES, engine, fork_ref, 0.1)
        assert not math.isfinite(signal.max_abs) and signal.passed is False and signal.ratio == math.inf
        check = CrosscheckResult("test", "diverged", "mujoco", "made reference", [signal], 0.1, 0.2)
        assert not check.passed and "NOT within" in check.line()
        d = check.to_dict()
        json.dumps(d, allow_nan=False)  # valid JSON: a value that is not finite is written as null
        assert d["signals"]["fork"]["max_abs"] is None and d["passed"] is False
        assert CrosscheckResult.from_dict(d).passed is False
    # a relative signal whose reference peak is zero: a force's difference is over the 1 N floor
    zero = SignalCheck("load", "N", 1.0, 0.0, 1.0, 0.0, 0.01, relative=True, judged=("peak",))
    assert zero.peak_difference == 1.0 and zero.passed is False
    # and one with no floor (a unit that has none): any difference is infinitely large
    bare = SignalCheck("ratio", "-", 1.0, 0.0, 1.0, 0.0, 0.01, relative=True, judged=("peak",))
    assert bare.peak_difference == math.inf and bare.passed is False


def test_the_line_and_the_dict_agree():
    for check in (made(fork_gap=0.05, load_gap=5.0), made(fork_gap=0.2, load_gap=20.0)):
        d = check.to_dict()
        assert json.loads(json.dumps(d)) == d  # plain JSON
        assert CrosscheckResult.from_dict(d) == check and CrosscheckResult.from_dict(d).line() == check.line()
        line = check.line()
        assert line.startswith(f"{d['rig']} {d['case']}: MuJoCo vs the {d['reference']}, ")
        assert ("NOT within the tolerances" in line) == (not d["passed"])
        assert f"(worst {d['worst'].replace('_', ' ')}, its largest difference at " \
               f"t = {d['signals'][d['worst']]['at_time_s']:.4f} s; " in line
        assert f"engine {d['engine_wall_s']:.2f} s, reference {d['reference_wall_s']:.2f} s)" in line
        fork = d["signals"]["fork"]
        assert f"fork {fork['max_abs']:.4f} mm ({'tol.' if fork['passed'] else 'EXCEEDS'} 0.1 mm)" in line
        assert f"pitch {d['signals']['pitch']['max_abs']:.4f} deg," in line
        load = d["signals"]["tire_load"]
        assert (f"tire load peak {100 * load['peak_difference']:.2f} % ({'tol.' if load['passed'] else 'EXCEEDS'} 1 %) "
                f"and series {100 * load['series_difference']:.2f} % of the peak") in line
        # every signal the dict holds is in the line, in order
        labels = [name.replace("_", " ") for name in d["signals"]]
        positions = [line.index(f" {label} ") for label in labels]
        assert positions == sorted(positions)


def test_a_result_is_refused_when_it_judges_nothing_or_names_a_signal_twice():
    reported = compare_series("pitch", "deg", TIMES, np.zeros(5), np.zeros(5))
    with pytest.raises(ValueError, match="judges at least one"):
        CrosscheckResult("test", "nothing judged", "mujoco", "made reference", [reported], 0.1, 0.1)
    judged = compare_series("fork", "mm", TIMES, np.zeros(5), np.zeros(5), 0.1)
    with pytest.raises(ValueError, match="repeat"):
        CrosscheckResult("test", "twice", "mujoco", "made reference", [judged, judged], 0.1, 0.1)
    with pytest.raises(ValueError, match="tolerance"):
        SignalCheck("fork", "mm", 0.0, 0.0, 0.0, 0.0, -0.1, judged=("series",))
    with pytest.raises(ValueError, match="share one"):
        compare_series("fork", "mm", TIMES, np.zeros(4), np.zeros(5), 0.1)


def test_every_rig_returns_the_one_result():
    """The drop (on both engines), the rolling front end and the bike: short runs, one type."""
    from mtbmj.bike.crosscheck import crosscheck as bike_crosscheck
    from mtbmj.rolling.reference import crosscheck as roll_crosscheck
    from mtbmj.validation import crosscheck_all

    drops = crosscheck_all("S1", ("mujoco", "fast"), duration=0.3)
    roll = roll_crosscheck("square_edge:at_m=0.2", 3.0, duration=0.2)  # a backward force to compare
    bike = bike_crosscheck("sst", "flat", 4.0, duration=0.2)
    for check in [*drops, roll, bike]:
        assert type(check) is CrosscheckResult, type(check)
        assert check.passed, check.line()
        assert check.engine_wall_s > 0.0 and check.reference_wall_s > 0.0
        d = check.to_dict()
        json.dumps(d, allow_nan=False)
        assert CrosscheckResult.from_dict(d).line() == check.line()
        assert "\n" not in check.line() and check.line().startswith(f"{check.rig} ")
    assert [c.engine for c in drops] == ["mujoco", "fast"] and [c.rig for c in drops] == ["drop", "drop"]
    assert drops[0].names == ("sled", "fork", "tire") and all(s.tolerance == 0.1 for s in drops[0].signals)
    assert roll.rig == "roll" and roll.names == ("fork", "body_height", "axle_height", "tire", "axle_force_up",
                                                  "axle_force_back")
    assert [s.name for s in roll.judged] == ["fork", "axle_force_up", "axle_force_back"]
    assert bike.rig == "bike" and bike.names == ("front_travel", "rear_travel", "shock_stroke", "pitch",
                                                  "front_tire_load", "rear_tire_load")
    assert bike["front_tire_load"].judged == ("peak", "series") and bike["pitch"].unit == "deg"
    assert bike.context["scenario"] == "flat" and bike.context["speed_m_per_s"] == 4.0


def test_a_round_off_against_a_zero_force_peak_is_no_difference():
    """The rolling front end's backward force on flat ground: 3.4e-14 N against a reference peak of
    exactly 0 was an infinite relative difference (exit 1); a relative measure is over at least 1 N."""
    from mtbmj.runpath.crosscheck import compare_series

    t = np.linspace(0.0, 1.0, 11)
    check = compare_series("axle force back", "N", t, np.full(11, -3.4e-14), np.zeros(11), tolerance=0.01,
                           relative=True)
    assert check.passed and check.peak_difference < 1e-13
    loaded = compare_series("load", "N", t, np.full(11, 5.0), np.full(11, 4.0), tolerance=0.01, relative=True)
    assert not loaded.passed and loaded.peak_difference == pytest.approx(0.25)  # 1 N over the 4 N peak

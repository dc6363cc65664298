"""The ridden bike calibrated on the ride before advice (issue 52 item 1; mtbmj/ride/calibrate.py).

The rides are made by the independent whole bike of tests/helpers.py (``advise_ride``: scipy's
solve_ivp on its own equations, its frame body the frame and the rider's on-bike segments half at
the pedals and half at the bars, written as SST v3 through the bike file's sensors). The bike file
the advice is given is written here: the same bike with the fork's spring as the file *says*,
which is not always what was ridden. The calibration reads only the record and that file."""
from __future__ import annotations

import json
from argparse import Namespace

import pytest

from mtbmj.cli import main
from mtbmj.cli.telemetry import ride_record
from mtbmj.ride import calibrate

from helpers import RATIO, advise_ride, bike_text, outside_well_set_ranges, reconstruction_passing

FILE_RATE = 12.0  # N/mm, the fork's spring as the bike file says


def _ride(folder, ridden_rate, **settings):
    """A ride of the whole bike with the fork at ``ridden_rate`` N/mm, and a bike file saying 12: (the SST
    file, the bike file, the static sag a rider measures on this bike standing in the file's place on level
    ground: the fork's stroke and the shock's, mm: the made bike at rest, in place, at that rate)."""
    _, sst, *_ = advise_ride(folder, fork_rate=ridden_rate, **settings)
    file = folder / "said.toml"
    file.write_text(bike_text(FILE_RATE))
    _, _, fork_mm, rear_mm, _ = advise_ride(folder / "at_rest", seconds=0.01, fork_rate=ridden_rate)
    return sst, file, (float(fork_mm[0]), float(rear_mm[0]) / RATIO)


@pytest.fixture(scope="module")
def softer(tmp_path_factory):
    return _ride(tmp_path_factory.mktemp("cal") / "softer", 0.7 * FILE_RATE)  # 30 % softer than it says


@pytest.fixture(scope="module")
def right(tmp_path_factory):
    return _ride(tmp_path_factory.mktemp("cal") / "right", FILE_RATE)


def _calibrated(sst, file, sag=None, measured=False):
    """The calibration of the ride ``sst`` on the bike file ``file``: on the ride's balances, or on the
    static sag ``sag`` (fork, shock mm) where ``measured``."""
    record = ride_record(sst, Namespace(bike=str(file), fork_max_mm=None, shock_max_mm=None))
    return calibrate.calibrate(record, str(file), static_sag_mm=sag if measured else None)


def test_a_fork_30_percent_softer_than_its_file_is_found(softer):
    """Ridden at 8.4 N/mm, the file saying 12: the fork's scale's interval holds 0.7 and is no wider
    than +-0.1; the shock's (as the file says) holds 1."""
    cal = _calibrated(*softer)
    fork, shock = cal.scales["front"], cal.scales["rear"]
    assert fork.low <= 0.7 <= fork.high, fork
    assert fork.high - fork.low < 0.2 and fork.value < 0.8
    assert shock.low <= 1.0 <= shock.high, shock
    d = cal.to_dict()["springs"]["front"]
    assert d["file"] == 12.0 and d["unit"] == "N/mm" and d["calibrated_low"] <= 8.4 <= d["calibrated_high"]
    # the calibrated bike: the fork's rate the file's times the scale, over the recorded keys
    assert cal.overrides["fork.set"]["fork.spring.rate_N_per_mm"] == pytest.approx(12.0 * fork.value)


def test_a_bike_as_its_file_says_calibrates_to_one(right):
    cal = _calibrated(*right)
    for end, sc in cal.scales.items():
        assert sc.low <= 1.0 <= sc.high, (end, sc)
        assert sc.high - sc.low < 0.2, (end, sc)


RIDER_FORWARD_M = 0.15  # the forward ride's rider, ahead of where the bike file puts them


@pytest.fixture(scope="module")
def forward(tmp_path_factory):
    """The bike as its file says (12 N/mm), ridden with the rider's centre of mass 150 mm ahead of the
    file's place the whole ride (as on a descent, or a rider who rides over the bars)."""
    return _ride(tmp_path_factory.mktemp("cal") / "forward", FILE_RATE, rider_forward_m=RIDER_FORWARD_M)


def _moved_forward_N(file) -> float:
    """The load the forward ride's rider moves onto the front wheel (N): their weight times the move over
    the wheelbase (moments about the rear axle), from the test bike's own numbers."""
    from mtbmj.bike import spec as spec_mod

    spec = spec_mod.load(str(file))
    return spec.rider.mass * 9.81 * RIDER_FORWARD_M / (spec.front_axle[0] - spec.rear_axle[0])


def test_a_rider_carried_forward_reads_as_a_soft_fork_and_the_other_reading_finds_it(forward, right, softer):
    """The same two balances read two ways, and a test that each is needed: the right bike ridden with the
    rider 150 mm forward is read per end as a fork ~20 % soft and a shock ~20 % stiff (what the shared rides
    show: x0.61 and x1.23 on 00642), and the other reading (``Calibration.split``) finds both springs as the
    file says (x1 within 3 %) and the load the rider moved (their weight x 0.15 m / wheelbase, against the
    same ride with the rider in place, within 15 %). The fork 30 % softer than its file is read the other
    way round: per end right (x0.7 held), the other reading a forward load it does not have. The travel
    alone cannot tell the two apart: that is why the advice judges a static-sag change on both readings."""
    fwd, base, soft = _calibrated(*forward), _calibrated(*right), _calibrated(*softer)
    assert fwd.scales["front"].high < 0.9 and fwd.scales["rear"].low > 1.1, fwd.line()  # per end: wrong here
    assert fwd.split.common == pytest.approx(1.0, abs=0.03), fwd.split
    moved = fwd.split.shift_N - base.split.shift_N
    assert moved == pytest.approx(_moved_forward_N(forward[1]), rel=0.15), (moved, fwd.split, base.split)
    assert abs(base.split.shift_N) < 0.2 * moved and base.split.common == pytest.approx(1.0, abs=0.03)
    # the soft fork: the per-end reading right, the other reading a forward load the ride did not have
    assert soft.scales["front"].low <= 0.7 <= soft.scales["front"].high
    assert soft.split.common < 0.9 and soft.split.shift_N > 0.5 * moved, soft.split
    # each reading's static sags: the forward ride's other reading is the right bike's statics
    for end in ("front", "rear"):
        assert fwd.split.static_sag[end][1] == pytest.approx(base.split.static_sag[end][0], abs=1.0), end
    assert fwd.split.static_sag["front"][0] > fwd.split.static_sag["front"][1] + 3.0
    d = fwd.to_dict()["or"]
    assert d["common_scale"] == fwd.split.common and d["load_forward_N"] > 0 and "cannot tell" in fwd.line()


def test_the_static_sag_measured_tells_a_soft_fork_from_a_rider_forward(forward, softer, right):
    """The two rides the travel alone reads alike (above), each with the static sag its rider would
    measure on level ground (``--static-sag-mm``: the made bike at rest in the file's place): the forward
    ride's springs are found as the file says (x1 within 5 %, intervals holding the right bike's own sag
    reading) and the load its rider carried forward (their weight x 0.15 m / wheelbase over what the right
    ride carries, within 15 %); the soft fork's ride is found soft (x0.7 held, the shock x1) with no such
    load (under a fifth of it). The sags are the test bike's, solved by its own statics."""
    fwd = _calibrated(*forward, measured=True)
    soft = _calibrated(*softer, measured=True)
    base = _calibrated(*right, measured=True)
    moved = _moved_forward_N(forward[1])
    for end in ("front", "rear"):
        assert fwd.scales[end].value == pytest.approx(base.scales[end].value, rel=0.005), end  # the same bike, sag
        assert fwd.scales[end].value == pytest.approx(1.0, abs=0.05), (end, fwd.scales[end])
    assert fwd.carried["load_forward_N"] - base.carried["load_forward_N"] == pytest.approx(moved, rel=0.15), fwd.carried
    assert soft.scales["front"].low <= 0.7 <= soft.scales["front"].high and soft.scales["front"].high < 0.8
    assert soft.scales["rear"].low <= 1.0 <= soft.scales["rear"].high
    assert abs(soft.carried["load_forward_N"] - base.carried["load_forward_N"]) < 0.2 * moved, soft.carried
    assert fwd.split is None and "calibrated on the static sag" in fwd.line() and "carried" in fwd.line()
    assert fwd.to_dict()["carried"]["rider_place_forward_mm"] > 100.0


@pytest.mark.parametrize("given, why", [
    (["--static-sag-mm", "40"], "is not two sags in mm"),
    (["--static-sag-mm", "40,-3"], "is not two sags in mm"),
    (["--static-sag-mm", "-40,20"], "is not two sags in mm"),
    (["--static-sag-mm", "forty,15"], "is not two sags in mm"),
    (["--static-sag-mm", "40,15", "--no-calibrate"], "cannot go with --no-calibrate"),
    (["--static-sag-mm", "400,15"], "the fork's 400 mm is not a static sag any fork spring rate"),
    (["--static-sag-mm", "15,13.9"], "would ride 457 mm from the pedals, past the bars"),
    (["--carried-as", "descent"], "--carried-as says how the runs carry the load a measured static sag leaves: it "
                                  "needs --static-sag-mm"),
], ids=["one", "negative", "leading-minus", "words", "uncalibrated", "past-any-spring", "load-past-the-bars", "carried-without-sag"])
def test_a_static_sag_that_cannot_be_is_refused_in_one_line(right, tmp_path, capsys, given, why):
    """A careless --static-sag-mm: one line naming the option and the cause, exit status 2, nothing written
    (a fork sag half the bike's own, 15 mm for 30.7: the stiff fork it gives leaves 220 N of the ride's front
    load to be carried forward, the rider past the bars, 457 mm from the pedals for the bars' 455 (458 on the
    point-contact ride): the ride is not described with that sag)."""
    sst, file, _ = right
    out = tmp_path / "advice"
    assert main(["advise", str(sst), "--bike", str(file), *given, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--static-sag-mm" in err[0] and why in err[0], err
    assert not out.exists()


def test_a_ride_no_spring_can_carry_is_not_described(right, tmp_path):
    """The same ride against a file whose fork is 5x stiffer (60 N/mm): no scale within x0.3-x3 of it
    balances the front's mean force; refused naming the fork and the range."""
    from mtbmj.ride.advice_rules import RideNotDescribed

    sst, *_ = right
    stiff = tmp_path / "stiff.toml"
    stiff.write_text(bike_text(60.0))
    with pytest.raises(RideNotDescribed, match=r"no fork spring rate within x0.3-x3 of the bike file's"):
        _calibrated(sst, stiff)


def test_a_recorded_setting_that_crashes_on_the_terrain_found_is_a_refusal():
    """The refusal the uncalibrated soft-fork ride below reached by a loop-out until the rider eased off
    the push as the front lifts (controllers.drive.eased; now it rides, 0 of 12 candidates crash,
    inconclusive), reached here by a run written here that crashed: ``Prepared.assemble`` says the recorded setting crashed and that the model cannot ride
    the ride as reconstructed; a run that did not crash is not refused at that point."""
    from types import SimpleNamespace

    from mtbmj.ride.advice_rules import RideNotDescribed
    from mtbmj.ride.advise import Prepared

    ride = SimpleNamespace(record=SimpleNamespace(name="made.SST"))
    line = "crashed: looped out at 4.460 s (pitch 60.1 deg)"
    with pytest.raises(RideNotDescribed, match=r"made.SST: the recorded setting crashed: looped out at 4.460 s.*"
                                               r"cannot ride this ride as reconstructed"):
        Prepared.assemble(ride, [SimpleNamespace(crash=line)])
    with pytest.raises(AttributeError):  # not refused: it goes on to the candidates (absent from this stand-in)
        Prepared.assemble(ride, [SimpleNamespace(crash=None)])


@pytest.mark.slow
def test_advice_on_a_softer_fork_than_the_file_says_rides_the_calibrated_bike(softer, tmp_path, capsys):
    """Calibrated (the default), this ride is ridden, the report carries the calibration, and a change of
    the fork's spring is read in the file's units (from 12)."""
    sst, file, _ = softer
    out = tmp_path / "advice"
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(file), "--out", str(out)]) == 0  # calibrated: the default
    printed = capsys.readouterr().out
    assert "calibrated on the ride: fork spring rate" in printed
    d = json.loads((out / "advice.json").read_text())
    front = d["calibration"]["springs"]["front"]
    assert front["calibrated_low"] <= 8.4 <= front["calibrated_high"]
    for c in d["candidates"]:
        if c["key"] == "fork:fork.spring.rate_N_per_mm":
            assert c["setting"]["from"] == 12.0 and c["from"] == pytest.approx(12.0 * front["scale"])
    assert 'id="calibration"' in (out / "advice.html").read_text()


def test_the_well_set_ranges_catch_a_change_too_far():
    """The check below can fail: a fork spring raised 25 % or a rebound lowered 36 % is outside."""
    spring = {"key": "fork:fork.spring.rate_N_per_mm", "setting": {"from": 12.0, "to": 15.0}}
    rebound = {"key": "fork:fork.damper.rebound_N_s_per_m", "setting": {"from": 700.0, "to": 448.0}}
    assert outside_well_set_ranges(spring) == [("fork:fork.spring.rate_N_per_mm", 12.0, 15.0)]
    assert outside_well_set_ranges({**spring, "setting": {"from": 12.0, "to": 13.2}, "then": [rebound]}) == [
        ("fork:fork.damper.rebound_N_s_per_m", 700.0, 448.0)]
    assert outside_well_set_ranges({**rebound, "setting": {"from": 700.0, "to": 560.0}}) == []


@pytest.mark.slow  # one advice on a 30 s made ride, every candidate searched: 2-4 min on two busy cores
def test_a_well_set_bike_is_left_about_where_it_is(tmp_path):
    """The made ride of the bike exactly as its file says (the fork 12 N/mm, its rebound 700 N s/m,
    the shock's 3500), advised calibrated (the default): the calibration holds 1 at both ends, and
    the answer is inconclusive, keep, or a change within the issue's ranges for a well-set bike
    (fork spring within +-20 %, rebound within +-30 %; every change after the first too). Measured:
    inconclusive (the rules scored on the ride: no rule outside its window at the recorded setting).
    Before, with the rules on the model's own values: the fork's rebound 700 -> 560 N s/m, driven by
    the front bottom-outs the model has and the ride has not (4 against 0: the model's fork reaches
    101 % of travel where the ride's reached 90 %)."""
    folder = tmp_path / "well"
    bike, sst, *_ = advise_ride(folder)  # the helpers' bike at its own file's setting
    out = folder / "advice"
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(bike), "--out", str(out)]) == 0
    advice = json.loads((out / "advice.json").read_text())
    for end, sc in advice["calibration"]["springs"].items():
        assert sc["low"] <= 1.0 <= sc["high"], (end, sc)
    answer = advice["verdict"]["answer"]
    assert answer in ("change", "inconclusive", "keep"), advice["verdict"]
    if answer == "change":
        assert outside_well_set_ranges(advice["recommendation"]) == [], advice["recommendation"]


@pytest.mark.slow  # one advice on a 30 s made ride, every candidate searched: 2-4 min on two busy cores
def test_a_well_set_bike_ridden_forward_is_not_given_a_stiffer_fork(forward, tmp_path):
    """The file's bike ridden with the rider 150 mm forward: per end the fork reads x0.81, its static sag
    out of the guides' window, and a stiffer fork lowers the penalty on that reading (12 -> 14.52 N/mm,
    measured, the advice before it judged the other reading too); on the other reading (both springs as
    the file says, the load carried forward) it raises it. The advice is not that change: inconclusive,
    naming the other reading, with the fork's spring the candidate it could not confirm."""
    sst, file, _ = forward
    out = tmp_path / "advice"
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(file), "--out", str(out)]) == 0
    advice = json.loads((out / "advice.json").read_text())
    other = advice["calibration"]["or"]
    assert other["common_scale"] == pytest.approx(1.0, abs=0.03) and other["load_forward_N"] > 50.0, other
    verdict = advice["verdict"]
    if verdict["answer"] == "change":
        assert outside_well_set_ranges(advice["recommendation"]) == [], advice["recommendation"]
    else:
        assert verdict["answer"] == "inconclusive" and "other reading" in verdict["why"], verdict
        best = verdict["best_candidate"]
        assert best["config_key"] == "fork.spring.rate_N_per_mm" and best["direction"] == "up", best
    assert 'id="other-reading"' in (out / "advice.html").read_text()


@pytest.mark.slow  # one advice on a 30 s made ride, every candidate searched: 1-3 min on two busy cores
def test_advice_on_the_forward_ride_with_its_static_sag_rides_it_as_carried(forward, tmp_path):
    """The forward ride advised with the static sag its rider measures (``--static-sag-mm``, the made bike
    at rest in the file's place): the springs as the file says, the rider moved to where the ride carried
    the load (so the whole bike rides the reconstruction: without the move it loops out at 5.9 s, at 21 s on
    the point-contact ride), the
    model's fork sitting where the ride's sat (its mean travel within 3 points of the record's), the static
    sag the rules judge the one measured (within 2 points of the test bike's own at rest), and no stiffer
    fork advised (the per-end reading raised it 12 -> 14.52 N/mm)."""
    sst, file, sag = forward
    out = tmp_path / "advice"
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(file), "--static-sag-mm", f"{sag[0]:.3f},{sag[1]:.3f}",
                     "--out", str(out)]) == 0
    advice = json.loads((out / "advice.json").read_text())
    cal = advice["calibration"]
    for end, sc in cal["springs"].items():
        assert sc["scale"] == pytest.approx(1.0, abs=0.05), (end, sc)
    assert cal["carried"]["rider_place_forward_mm"] == pytest.approx(1e3 * RIDER_FORWARD_M, abs=25.0), cal["carried"]
    rec, sim = advice["recorded_setting"]["measured"], advice["recorded_setting"]["simulated"]
    assert abs(sim["front"]["dynamic_sag_percent"] - rec["front"]["dynamic_sag_percent"]) < 3.0, (sim["front"], rec["front"])
    assert sim["front"]["static_sag_percent"] == pytest.approx(100 * sag[0] / rec["front"]["travel_mm"], abs=2.0)
    verdict = advice["verdict"]
    if verdict["answer"] == "change":
        assert outside_well_set_ranges(advice["recommendation"]) == [], advice["recommendation"]
    assert 'id="carried"' in (out / "advice.html").read_text()


@pytest.mark.slow  # a 40 s engine run and one advice on 35 s of it: about a minute on two busy cores
def test_a_ride_down_a_steady_descent_is_ridden_on_its_descent(tmp_path):
    """A ride down a 10 % grade (5.71 deg) over ISO 8608 class C roughness at 6 m/s, made by the package's own
    whole bike (MuJoCo: no independent whole bike here rides along a slope with its brakes) and written as SST
    version-3 counts; the static sag its rider measures the bike at rest on level ground. What this shares
    with the engine: everything that made the ride, so it checks the reading, not the physics (the engine on
    a descent is checked against a moment balance in tests/test_bike_descent.py): advised with the sag and
    ``--carried-as descent``, the springs read as the file's (x1 within each interval), the load carried
    forward read as the grade ridden (within 0.5 deg), every run on that grade sitting where the ride sat
    (mean travel within 3 points at both ends), the static sag judged the one measured, and the bike riding
    the whole ride. (On the made ride of a rider 150 mm forward on the flat, the descent is the wrong reading:
    on its point-contact ride, ridden so at the ride's own speed the bike looped out at its 0.4 m tabletop, and
    ``rider`` is right; on its round-tyre ride both ride through.)"""
    from mtbmj.rolling import terrain as terrain_mod

    from helpers import engine_ride

    ground = terrain_mod.on_grade(terrain_mod.make("iso8608:class=C,seed=5,length_m=400,at_m=15"), -10.0, 2.0, 5.0)
    file, sst, made = engine_ride(tmp_path, ground, from_s=5.0)  # from 5 s: on the grade (the front axle past 25 m)
    sag = (made.summary["static_front_travel_mm"], made.summary["static_rear_travel_mm"] / RATIO)
    out = tmp_path / "advice"
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(file), "--static-sag-mm", f"{sag[0]:.3f},{sag[1]:.3f}",
                     "--carried-as", "descent", "--out", str(out)]) == 0
    advice = json.loads((out / "advice.json").read_text())
    cal = advice["calibration"]
    for end, sc in cal["springs"].items():
        assert sc["low"] <= 1.0 <= sc["high"], (end, sc)
    carried = cal["carried"]
    assert carried["as"] == "descent" and carried["ridden_descent_deg"] == pytest.approx(5.71, abs=0.5), carried
    rec, sim = advice["recorded_setting"]["measured"], advice["recorded_setting"]["simulated"]
    for end in ("front", "rear"):
        assert abs(sim[end]["dynamic_sag_percent"] - rec[end]["dynamic_sag_percent"]) < 3.0, (end, sim[end], rec[end])
    assert sim["front"]["static_sag_percent"] == pytest.approx(100 * sag[0] / rec["front"]["travel_mm"], abs=2.0)
    assert advice["recorded_setting"].get("crash") is None


def test_the_descent_that_carries_a_load_is_found_as_the_moment_balance_says(right):
    """``calibrate.descent_for`` (``calibrate_descent.grade_for``) on the test bike: the descent whose steady run the calibration reads as
    85 N carried forward is the one a moment balance gives, m g sin(theta) h / L = 85 N, h and L the bike's
    centre of mass height and wheelbase from MuJoCo's model at rest (within 0.7 deg: the brakes' dive and
    the frame's pitch on the grade are in the run, not in the balance); a load no trail's steady descent
    carries (400 N: 29 deg) is refused naming the load."""
    import math

    import mujoco

    from mtbmj.bike.run import run_bike
    from mtbmj.ride import calibrate_descent
    from mtbmj.ride.advice_rules import RideNotDescribed

    sst, file, sag = right
    cal = _calibrated(sst, file, sag, measured=True)
    level = run_bike(str(file), "flat:length_m=5", 5.0, duration=0.01, overrides=cal.overrides)
    p = level.prepared
    m, d = p.bike.model, mujoco.MjData(p.bike.model)
    d.qpos[:] = p.initial_qpos
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    h = float(d.subtree_com[0][2])
    wheelbase = float(d.xpos[m.body("front_wheel").id][0] - d.xpos[m.body("rear_wheel").id][0])
    want = math.degrees(math.asin(85.0 * wheelbase / (float(m.body_subtreemass[0]) * 9.81 * h)))
    found = calibrate.descent_for(str(file), None, cal.scales, 85.0, 3.0)  # from a poor first guess
    assert found["descent_deg"] == pytest.approx(want, abs=0.7), (found, want)
    assert abs(found["read_N"] - 85.0) <= calibrate_descent.TOLERANCE_N and found["runs"] <= 5, found
    with pytest.raises(RideNotDescribed, match="400 N.*steeper than 20 deg"):
        calibrate.descent_for(str(file), None, cal.scales, 400.0, 29.0)


def _reference_scale(t, travel_mm, bike, end):
    return _reference_pooled_scale([(t, travel_mm)], bike, end)


def _reference_pooled_scale(parts, bike, end):
    """The scale of ``end``'s spring whose mean force at the wheel over ``travel_mm`` is the end's
    static load, per sample as the module doc states it (the law at the stroke and speed, over
    sin(head angle) or the leverage ratio), each sample's force in a plain loop: the calibration
    before its speed mend (the leverage once per ride, the spring not apart), for the answer's sameness.
    ``parts``: [(t, travel_mm)] of one ride or several, each one's speed on its own time, the mean over
    all their samples."""
    import numpy as np
    from scipy.optimize import brentq

    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod
    from mtbmj.measured import metrics
    from mtbmj.ride import reconstruct_bike

    def whole(over):
        spec = spec_mod.load(bike, over)
        return spec, reconstruct_bike.whole_bike(spec, *bike_run.setups(spec))

    spec, w0 = whole(None)
    adj = calibrate.spring_adjuster(spec, end)
    x = np.concatenate([np.clip(travel_mm, 0.0, None) for _, travel_mm in parts]) * 1e-3
    v = np.concatenate([metrics.velocity(t, travel_mm) for t, travel_mm in parts]) * 1e-3

    def mean_force(s):
        _, w = whole(calibrate.merged({}, adj.overrides(adj.value * s)))
        law = w.fork if end == "front" else w.shock
        f = []
        for xi, vi in zip(x, v):
            if end == "front":
                f.append((law.force(xi, vi, 0.0) if law.has_state else law.force(xi, vi)) / w.sin_a)
            else:
                r = w.lev.ratio_at(xi)
                st = float(w.lev.strokes(np.array([xi]))[0])
                f.append((law.force(st, vi / r, 0.0) if law.has_state else law.force(st, vi / r)) / r)
        return float(np.mean(f))

    load = w0.fF0 if end == "front" else w0.fR0
    return brentq(lambda q: mean_force(q) - load, *calibrate.SCALE_RANGE, xtol=1e-4)


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_the_mended_calibration_gives_the_same_scales(softer, compiled, monkeypatch):
    """The calibration's speed mends (the whole force's mean without its spring apart, the rear's
    leverage once per ride, the laws through the compiled kernel where numba is present) give each
    end's scale as the plain per-sample loop does, on the first 6 s of the softer fork's ride (the
    same bisection: the same scale to rounding); without numba too (the Python laws per sample)."""
    import numpy as np

    from mtbmj.controllers import compiled as kernels_face

    if compiled and kernels_face.numba is None:
        pytest.skip("numba not installed")
    if not compiled:  # the compiled kernels' face says it cannot run: the Python laws per sample
        monkeypatch.setattr(kernels_face, "numba", None)

    from mtbmj.ride.reconstruct import RATE_HZ

    sst, file, _ = softer
    record = ride_record(sst, Namespace(bike=str(file), fork_max_mm=None, shock_max_mm=None)).decimated(RATE_HZ)
    t = np.asarray(record.time_s, float)
    k = t - t[0] <= 6.0
    front, rear = np.asarray(record.fork_mm, float)[k], np.asarray(record.rear_mm, float)[k]
    cal = calibrate.spring_scales(t[k], front, rear, str(file))
    for end, travel in (("front", front), ("rear", rear)):
        assert cal.scales[end].value == pytest.approx(_reference_scale(t[k], travel, str(file), end), rel=1e-9), end
    assert cal.scales["front"].value < 0.8  # the softer fork is found on these 6 s too: the check is not idle


@pytest.mark.shared_data("sst_v2", "00088.SST", "00089.SST", "00090.SST", "00091.SST")
def test_the_shared_pedalling_runs_standing_carry_load_forward_of_seated():
    """The shared pedalling runs of one bike and setting (the recording's own labels): standing up (00088,
    00089) the rider's weight is over the pedals and bars, seated (00090, 00091) on the saddle, behind.
    The calibration's other reading (one spring scale, the rest a load carried fore-aft) must put every
    standing run's load forward of every seated run's: measured 50 and 135 N forward standing, 60 and 45 N
    rearward seated. Version-2 amplitudes are approximate (a placeholder decoding), the same for all four,
    so the order is what is read, not the newtons; the per-end reading says the same thing in its own
    terms (the fork read softer than the shock standing, stiffer seated), and a reading with the labels
    swapped fails."""
    import os

    from conftest import SHARED_DATA
    from mtbmj.measured.telemetry import read_ride

    def read(n):
        return calibrate.calibrate(read_ride(os.path.join(SHARED_DATA, "sst_v2", f"{n}.SST")), "sst")

    standing, seated = [read(n) for n in ("00088", "00089")], [read(n) for n in ("00090", "00091")]
    assert min(c.split.shift_N for c in standing) > max(c.split.shift_N for c in seated) + 50.0, \
        ([c.split for c in standing], [c.split for c in seated])
    assert all(c.split.shift_N < 0 for c in seated) and all(c.split.shift_N > 0 for c in standing)
    ratio = [c.scales["front"].value / c.scales["rear"].value for c in standing + seated]
    assert max(ratio[:2]) < 1.0 < min(ratio[2:]), ratio


def _first(sst, file, seconds):
    """(record, t, fork mm, rear mm) of the ride ``sst``'s first ``seconds`` as the calibration reads it."""
    import numpy as np

    from mtbmj.ride.reconstruct import RATE_HZ

    record = ride_record(sst, Namespace(bike=str(file), fork_max_mm=None, shock_max_mm=None))
    rec = record.decimated(RATE_HZ)
    t = np.asarray(rec.time_s, float)
    k = t - t[0] <= seconds
    return record, t[k], np.asarray(rec.fork_mm, float)[k], np.asarray(rec.rear_mm, float)[k]


def test_rides_pooled_calibrate_as_one_ride_of_all_their_samples(softer, right):
    """Two rides' pooled calibration (``advise RIDE RIDE``'s one bike) is each end's scale whose mean force
    over every sample of both is the end's load, each ride's speed on its own time: the plain per-sample
    reference above on the first 6 s of the softer fork's ride and of the right one's. The pooled fork
    lies between the two rides' own (a mix of two settings is not told apart: that the rides share one is
    the rider's word), and a ride pooled with itself reads as alone, its interval no wider."""
    rec_s, ts, fs, rs = _first(*softer[:2], 6.0)
    rec_r, tr, fr, rr = _first(*right[:2], 6.0)
    file = str(softer[1])  # the two bike files are the same text: 12 N/mm
    cal = calibrate.calibrate_pooled([rec_s, rec_r], file, duration=6.0)
    assert cal.scales["front"].value == pytest.approx(_reference_pooled_scale([(ts, fs), (tr, fr)], file, "front"),
                                                      rel=1e-6)
    assert cal.scales["rear"].value == pytest.approx(_reference_pooled_scale([(ts, rs), (tr, rr)], file, "rear"),
                                                     rel=1e-6)
    alone_s = calibrate.calibrate(rec_s, file, duration=6.0).scales["front"]
    alone_r = calibrate.calibrate(rec_r, file, duration=6.0).scales["front"]
    assert alone_s.value < cal.scales["front"].value < alone_r.value, (alone_s, cal.scales["front"], alone_r)
    twice = calibrate.calibrate_pooled([rec_s, rec_s], file, duration=6.0).scales["front"]
    assert twice.value == pytest.approx(alone_s.value, rel=1e-6)
    assert twice.high - twice.low <= alone_s.high - alone_s.low + 1e-9
    assert "2 rides pooled" in cal.method and cal.line().startswith("calibrated on 2 rides pooled: fork spring rate")
    assert cal.to_dict()["rides"] == 2 and calibrate.calibrate(rec_s, file, duration=6.0).to_dict()["rides"] == 1

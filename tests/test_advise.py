"""``mtbmj advise``: setup advice from a ride (mtbmj/ride/advise.py), against rides made here.

The rides the advice is judged on are made by an independent whole bike integrated in
tests/helpers.py (``advise_ride``: ``whole_bike_ride`` over a hard course; scipy's solve_ivp, its own
equations, not the package's engines or laws' code): a frame that heaves and pitches, a rider on legs
and arms who shifts a slow load fore and aft, the fork's spring, bumper, hard stop and two-rate damper
acting along the steering axis, the shock's through a constant leverage ratio, tyres that meet the
ground as round wheels do and leave it (``helpers.ADVISE_ROUND_TYRE``), at a speed that varies along the ride, over rock gardens, drops, a G-out and a
tabletop (the frame pitching about its own body's inertia, the masses it carries fore and aft left out:
``helpers.ADVISE_CARRIED`` says why, tests/test_advise_carried.py what the carried bike gives); both
ends' travel written as an SST version-3 file in integer counts through the
[sensors] calibration of the bike file (the law of cosines inverted in tests/helpers.py, not by the
reader). One ride is made with the fork far too soft (5 N/mm: it bottoms several times), one with
the fork's rebound four times too slow (it packs down). The advice must move the right setting the
right way, and what it predicts at the new setting must agree with that bike ridden again at that
setting.

Shared with the package, and so not tested here: the laws' forms and values (read from the same
bike file: inputs, not results), the masses and geometry, the metrics' definitions
(``advise.ride_metrics``: written out in its module doc). The quarter-car rides of
``helpers.ride`` (two decoupled ends) remain for what does not simulate the ride to its end (the
refusals, a crash or a refused candidate stood in)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mtbmj.cli import main
from mtbmj.ride import advise

import helpers
from helpers import (advise_ride, air_shock_bike, clicks_bike, generated_metrics, reconstruction_passing, ride,
                     write_sst)


def advice_of(folder, **settings):
    """The independent whole bike ridden with ``settings`` (``helpers.advise_ride``), its ride written
    as SST v3, and ``mtbmj advise`` run on it through the command line: (bike, advice.json, (fork,
    rear, t), out folder)."""
    bike, sst, fork_mm, rear_mm, t = advise_ride(folder, **settings)
    out = folder / "advice"
    # the verdict set to pass: on these hard courses the rear predicted misses the 40 % margin (the soft
    # fork's: 15.9 mm RMS where 10.5 passes, the delayed fork 17.5; on point contacts 11.4 where 11.1
    # passed); the advice's logic is tested here
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(bike), "--out", str(out)]) == 0
    return bike, json.loads((out / "advice.json").read_text()), (fork_mm, rear_mm, t), out


@pytest.fixture(scope="module")
def soft(tmp_path_factory):
    return advice_of(tmp_path_factory.mktemp("advise") / "soft", fork_rate=5.0)


@pytest.mark.slow
def test_a_fork_far_too_soft_gets_a_stiffer_spring(soft, tmp_path):
    bike, advice, (fork_mm, rear_mm, t), out = soft
    made = generated_metrics(bike, fork_mm, rear_mm, t)
    assert made["front"]["bottom_outs"] >= 3  # the ride made here bottoms several times
    rec = advice["recommendation"]
    assert rec is not None, advice["candidates"]
    assert rec["config_key"] == "fork.spring.rate_N_per_mm" and rec["section"] == "fork.set"
    assert rec["direction"] == "up" and rec["setting"]["to"] > rec["setting"]["from"] == 5.0  # the file's units
    # the search reaches the answer (issue 52's "how we will know": raised by 20-150 %), for bottoming
    assert 1.2 <= rec["setting"]["to"] / rec["setting"]["from"] <= 2.5, rec["search"]
    # scored on the ride (its 3 bottom-outs, not the model's 12), the static sag (62.9 % for 20-25) falls most
    assert rec["driven_by"] == "front_static_sag" and len(rec["search"]) >= 1
    # one fault: nothing follows the spring once raised (the others searched again from it: the compression
    # and rebound the recorded setting advised, 500 -> 1221 and 700 -> 286.7, raise the penalty 0.34 -> 0.38
    # and 0.39 at 11.79 N/mm, measured; mtbmj.ride.advice_combined)
    comb = rec["combined"]
    assert comb["joined"] == [] and comb["runs"] >= 1 and "penalty_to" not in comb, comb["changes"]
    assert "Then nothing more" in (out / "advice.html").read_text()
    assert rec["changes"]["front.bottom_outs_per_minute"]["expected"] < made["front"]["bottom_outs_per_minute"]
    # this file's bike at the recommended rate (as the rider sets it): what the advice expects agrees
    bike2, _, *again = advise_ride(tmp_path, fork_rate=rec["setting"]["to"])
    made2 = generated_metrics(bike2, *again)
    for metric in ("front.bottom_outs_per_minute", "front.max_travel_percent", "front.dynamic_sag_percent"):
        c = rec["changes"][metric]
        end, key = metric.split(".")
        assert abs(c["expected"] - made2[end][key]) <= c["uncertainty"] + 0.1 * abs(made2[end][key]) + 1.0, (
            metric, c, made2[end][key])
    assert made2["front"]["bottom_outs"] < made["front"]["bottom_outs"]
    assert rec["changes"]["front.bottom_outs_per_minute"]["change"] < 0


@pytest.mark.slow
def test_a_rebound_far_too_slow_gets_less_rebound_damping(tmp_path):
    """The fork's rebound four times too slow (2800 N s/m, the bike's own 700): the made ride packs
    down, and the advice is a change, the fork's rebound damping lowered by 30-90 % (the search goes
    on from the one-step candidate: 1147 N s/m, the rules scored on the ride, driven by the front's
    packing against the rear's; 917.5 on the point-contact rides), packing predicted to ease beyond its uncertainty; the bike ridden again at the advised damping packs less, as the advice expects, within
    its uncertainty. Advised with calibration (the default), which reads the file's springs (about x0.97
    and x1.02: each end's interval holds 1), the advice (every candidate searched before the verdict) is
    the rebound, not the spring the one-step screen once preferred (issue 52's "how we will know"; the
    same ride and command were advised again in tests/test_advise_calibrate.py for that, now here)."""
    bike, advice, (fork_mm, rear_mm, t), out = advice_of(tmp_path / "slow", fork_reb=2800.0)
    for end, sc in advice["calibration"]["springs"].items():
        assert sc["low"] <= 1.0 <= sc["high"], (end, sc)
    made = generated_metrics(bike, fork_mm, rear_mm, t)
    # the ride made here packs: its fork rebounds below the packing rule's share of its rear's
    assert made["front"]["rebound_over_compression"] < advise.PACKING_SHARE * made["rear"]["rebound_over_compression"]
    assert advice["verdict"]["answer"] == "change", advice["verdict"]
    rec = advice["recommendation"]
    # the reason: the rule whose penalty fell most on the way (the search says which), and packing
    # itself predicted to ease beyond its uncertainty (below)
    assert rec is not None and "driven by the front" in advice["verdict"]["why"]
    packing = rec["changes"]["front.rebound_over_compression"]
    assert packing["change"] > (packing["uncertainty"] or 0.0)
    assert rec["config_key"] == "fork.damper.rebound_N_s_per_m" and rec["section"] == "fork.set"
    assert rec["direction"] == "down" and rec["setting"]["to"] < rec["setting"]["from"] == 2800.0
    assert 0.1 <= rec["setting"]["to"] / rec["setting"]["from"] <= 0.7, rec["search"]  # lowered by 30-90 %
    _, _, *again = advise_ride(tmp_path / "again", fork_reb=rec["setting"]["to"])
    made2 = generated_metrics(bike, *again)
    c = rec["changes"]["front.rebound_over_compression"]
    assert c["change"] > 0 and made2["front"]["rebound_over_compression"] > made["front"]["rebound_over_compression"]
    assert abs(c["expected"] - made2["front"]["rebound_over_compression"]) <= c["uncertainty"] + 0.05


@pytest.mark.slow
def test_the_report_opens_in_headless_chromium(soft, tmp_path):
    from helpers import CHROMIUM, rendered

    if not CHROMIUM.exists():
        pytest.skip("headless Chromium not installed (/usr/bin/chromium)")
    _, advice, _, out = soft
    result, dom = rendered(out / "advice.html", tmp_path)
    (image,) = result["imgs"]
    assert image["id"] == "histograms" and image["inline"] and image["width"] > 500 and image["height"] > 200
    assert result["resources"] == []
    assert result["tables"]["candidates"]["rows"] == 1 + len(advice["candidates"])
    assert result["tables"]["changes"]["visible"] and result["tables"]["changes"]["rows"] > 5
    assert f"raise the fork spring rate from 5 to {advice['recommendation']['setting']['to']:g}" in dom


def test_the_figure_shows_both_ends_before_and_after():
    """The figure of an Advice made here by hand (no simulation): both ends' histograms over 0-100 %
    of travel, the record, the recorded setting and the recommended one, labelled."""
    t = np.linspace(0, 20, 2001)
    wave = 40 + 20 * np.sin(t)
    metrics = advise.ride_metrics(t, wave, wave * 0.8, 130.0, 125.0, static=(30.0, 35.0))
    base = advise.Run("recorded setting", {}, metrics, advise.penalties(metrics), wave, wave * 0.8)
    better = advise.Run("fork spring rate 5.5", {}, metrics, advise.penalties(metrics), wave * 0.9, wave * 0.8)
    adj = advise.Adjuster("front", "fork.set", "fork.spring.rate_N_per_mm", 5.0, 4.5, 5.5, "fork spring rate")
    a = advise.Advice("ride", "bike", {}, metrics, base, [(adj, "up", 5.5, better)],
                      {"key": adj.name, "label": adj.label, "direction": "up", "from": 5.0, "to": 5.5},
                      wave, wave * 0.8)
    fig = a.figure()
    front, rear = fig.axes
    for ax, what in ((front, "fork travel"), (rear, "rear wheel travel")):
        assert ax.get_xlim() == (0.0, 100.0) and what in ax.get_xlabel() and ax.get_ylabel() == "time (%)"
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert labels == ["recorded ride", "simulated, recorded setting", "simulated, fork spring rate 5 -> 5.5"]
    assert "recommended: fork spring rate 5 -> 5.5" in fig._suptitle.get_text()
    for ax in (front, rear):  # the legend (upper right, three lines) sits above the tallest bar
        tallest = max(float(np.max(p.get_data().values)) for p in ax.patches)
        assert ax.get_ylim()[1] == pytest.approx(advise.LEGEND_ROOM * tallest) and advise.LEGEND_ROOM >= 1.4


def test_a_ride_too_short_is_refused_in_one_line(tmp_path, capsys):
    bike, fork_mm, rear_mm, t = ride(tmp_path, seconds=10.0)
    sst = write_sst(tmp_path / "short.SST", fork_mm, rear_mm)
    out = tmp_path / "advice"
    assert main(["advise", str(sst), "--bike", str(bike), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert [line for line in err if line.startswith("mtbmj: error")] == [
        "mtbmj: error: short.SST: 10.0 s of ride cannot support advice (at least 15 s)"]
    assert not out.exists()


def test_a_ride_of_one_end_is_refused_in_one_line(tmp_path, capsys):
    """A travel CSV of the fork alone (a logger with one sensor): the calibration read the rear that is
    not there (an IndexError's traceback); refused as reconstruct refuses it, nothing written."""
    t = np.arange(0.0, 40.0, 0.005)
    fork = 40.0 + 25.0 * np.sin(2 * np.pi * 1.1 * t)
    (tmp_path / "fork_only.csv").write_text("time_s,fork_mm\n" + "".join(f"{a:.3f},{b:.3f}\n" for a, b in zip(t, fork)))
    out = tmp_path / "advice"
    helpers.one_line(capsys, ["advise", tmp_path / "fork_only.csv", "--bike", "trail", "--out", out],
                     "fork_only.csv", "needs both ends")
    assert not out.exists()


def test_the_riders_mass_given_two_ways_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """--rider-kg 80 beside --set rider.mass_kg=85: --rider-kg won without a word (the advice was
    for an 80 kg rider where the user also said 85). Refused in one line before a ride is read; the
    same mass twice, or either alone, is not refused for it."""
    from mtbmj.cli import telemetry as cli_telemetry

    read = []
    monkeypatch.setattr(cli_telemetry, "ride_record", lambda *a, **k: read.append(a) or (_ for _ in ()).throw(
        advise.AdviseError("reached the ride")))
    out = tmp_path / "advice"
    helpers.one_line(capsys, ["advise", "example", "--bike", "sst", "--rider-kg", "80", "--set", "rider.mass_kg=85",
                              "--out", out], "--rider-kg 80 and --set rider.mass_kg=85", "given twice")
    assert not read and not out.exists()
    for given in (["--rider-kg", "80", "--set", "rider.mass_kg=80"], ["--rider-kg", "80"], ["--set", "rider.mass_kg=85"]):
        helpers.one_line(capsys, ["advise", "example", "--bike", "sst", *given, "--out", out], "reached the ride")
    assert len(read) == 3


def test_no_candidate_leaves_what_the_part_allows(tmp_path):
    """Candidates stay within the part: clicks within the measured range (none past the last), a
    value within what any part has (``mtbmj.config.PLAUSIBLE``), no negative volume spacer."""
    from mtbmj.bike import spec as spec_mod
    from mtbmj.config import PLAUSIBLE

    bike = tmp_path / "edge.toml"
    bike.write_text('''base = "trail"
[fork]
[fork.set]
"fork.spring.model" = "air"
"fork.spring.air_pressure_psi" = 390.0
"fork.spring.tokens" = 0
[shock]
[shock.set]
"fork.damper.model" = "clicks"
"fork.damper.velocity_mm_per_s" = [0.0, 100.0, 500.0]
"fork.damper.compression_clicks_measured" = [0, 10]
"fork.damper.compression_force_N" = [[0.0, 300.0, 900.0], [0.0, 600.0, 1500.0]]
"fork.damper.rebound_clicks_measured" = [0, 10]
"fork.damper.rebound_force_N" = [[0.0, 300.0, 900.0], [0.0, 600.0, 1500.0]]
"fork.damper.compression_clicks" = 10
"fork.damper.rebound_clicks" = 1
''')
    found = {a.key: a for a in advise.adjusters(spec_mod.load(str(bike)))}
    pressure = found["fork.spring.air_pressure_psi"]
    assert pressure.up is None and pressure.down == pytest.approx(351.0)  # 429 psi is past 400, what forks hold
    assert PLAUSIBLE["fork.spring.air_pressure_psi"][1] == 400.0
    assert found["fork.spring.tokens"].down is None and found["fork.spring.tokens"].up == 1.0
    comp, reb = found["fork.damper.compression_clicks"], found["fork.damper.rebound_clicks"]
    assert comp.up is None and comp.down == 8.0  # at the last measured click: no more
    assert reb.down == 0.0 and reb.up == 3.0  # one click from the end: to the end, not past it


def test_a_recorded_setting_that_crashes_on_the_terrain_is_refused(tmp_path, monkeypatch, capsys):
    """The rider came home; a model that crashes their own setting on the terrain it found cannot
    predict a change: one line, exit 2, nothing written."""
    real = advise.simulate

    def crashing(bike, overrides, terrain, speed, duration, label, lead_s, profile=None):
        run = real(bike, overrides, terrain, speed, min(duration, 0.3), label, lead_s, profile)
        run.crash = "crashed: over the bars at 0.250 s (pitch -45.1 deg)"
        return run

    monkeypatch.setattr(advise, "simulate", crashing)
    # the crash path alone: this packing ride's rear predicted does not beat the naive baselines (issue 51:
    # 23.8 mm RMS against the delayed fork's 7.3), which advise refuses first; that refusal is passed here
    from mtbmj.ride import reconstruct as rc

    checks = rc.Reconstruction.checks
    monkeypatch.setattr(rc.Reconstruction, "checks", lambda self: {**checks(self), "passes": True})
    bike, fork_mm, rear_mm, t = ride(tmp_path, fork_reb=2500.0)  # the packing ride
    sst = write_sst(tmp_path / "ride.SST", fork_mm, rear_mm)
    out = tmp_path / "advice"
    assert main(["advise", str(sst), "--bike", str(bike), "--workers", "1", "--out", str(out)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("mtbmj: error")]
    assert len(err) == 1 and "the recorded setting crashed: over the bars at 0.250 s" in err[0], err
    assert not out.exists()


@pytest.mark.slow  # a reconstruction through the whole bike: 0.5-2 min
def test_a_rider_no_bike_carries_is_refused_naming_the_key(tmp_path, capsys):
    """A careless --rider-kg 500 on the shipped ride: no fork spring within x0.3-x3 of the file's
    carries such a rider (the calibration, before anything is reconstructed), and the refusal names
    the implausible key; uncalibrated, the bike sinks onto its stops, the reconstruction cannot
    reproduce the rear, and that refusal names the key too."""
    out = tmp_path / "advice"
    assert main(["advise", "example", "--bike", "sst", "--rider-kg", "500", "--duration", "30", "--out", str(out)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("mtbmj: error")]
    assert len(err) == 1 and "carries the front end's static load" in err[0], err
    assert "rider.mass_kg = 500 kg is outside 30-150 kg" in err[0]
    assert not out.exists()
    assert main(["advise", "example", "--bike", "sst", "--rider-kg", "500", "--duration", "30", "--no-calibrate",
                 "--out", str(out)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("mtbmj: error")]
    assert len(err) == 1 and "fails its own check" in err[0] and "rider.mass_kg = 500 kg is outside 30-150 kg" in err[0]
    assert not out.exists()


def test_a_stretch_too_short_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """A 16 s ride is long enough, but --duration 14.9 asks for advice on 14.9 s of it: the minimum
    holds for the stretch analysed (one line naming --duration, exit 2, nothing written, nothing
    reconstructed); --duration 15 is let through to the reconstruction."""
    from helpers import BIKE, bumps_csv, reconstruction_stand_in

    reached = reconstruction_stand_in(monkeypatch)
    csv, *_ = bumps_csv(tmp_path / "ride.csv", 16.0)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)
    out = tmp_path / "advice"
    for duration in ("14.9", "0.5"):
        assert main(["advise", str(csv), "--bike", str(bike), "--duration", duration, "--out", str(out)]) == 2
        err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("mtbmj: warning")]
        assert err == [f"mtbmj: error: --duration: {duration} s of ride.csv cannot support advice (at least 15 s; "
                       f"the ride is 16.0 s)"], err
        assert not out.exists() and not reached
    assert main(["advise", str(csv), "--bike", str(bike), "--duration", "15", "--out", str(out)]) == 2
    assert reached and "reached the reconstruction" in capsys.readouterr().err


def test_the_ride_is_decoded_through_the_bike_as_set_on_the_command_line(tmp_path, monkeypatch):
    """--set sensors.* (the recorder's calibration) decodes the ride as the same keys in the bike file do
    (it was left to the runs: the ride was read through the file's sensors, 20.5 mm against 21.1 mm of
    the rear's RMS on the shipped ride); without the --set the ride reads otherwise (the check can fail)."""
    from helpers import FORK_ARM, FORK_MAX, bike_text, write_sst
    from mtbmj.ride import advise as advise_mod
    from mtbmj.errors import MtbmjError

    wave = np.sin(np.arange(16000) / 1000 * 2 * np.pi)
    sst = write_sst(tmp_path / "ride.SST", 60.0 + 40.0 * wave, 40.0 + 30.0 * wave)
    text = bike_text()
    plain = tmp_path / "plain.toml"  # the recorder's fork sensor 10 % longer in the arm and base than written
    plain.write_text(text)
    other = text.replace(f"fork_arm_mm = {FORK_ARM}", f"fork_arm_mm = {FORK_ARM * 1.1}").replace(
        f"fork_max_mm = {FORK_MAX}", f"fork_max_mm = {FORK_MAX * 1.1}")
    assert other != text
    (tmp_path / "other.toml").write_text(other)
    read = []

    def caught(record, *a, **k):
        read.append(record.fork_mm.copy())
        raise MtbmjError("caught the ride")

    monkeypatch.setattr(advise_mod, "advise", caught)
    sets = ["--set", f"sensors.fork_arm_mm={FORK_ARM * 1.1}", "--set", f"sensors.fork_max_mm={FORK_MAX * 1.1}"]
    for bike, extra in ((plain, sets), (tmp_path / "other.toml", []), (plain, [])):
        assert main(["advise", str(sst), "--bike", str(bike), *extra, "--out", str(tmp_path / "o")]) == 2
    by_set, by_file, as_written = read
    assert np.array_equal(by_set, by_file)
    assert np.max(np.abs(by_set - as_written)) > 5.0


def test_an_expected_value_keeps_the_metric_s_bounds():
    """What the advice expects on the ride: the model's change mapped through (bound, bound) and
    (simulated now, recorded). Closed forms: the trail bike's case (the model's 5 bottom-outs become
    4 where the ride had none: 0, not -1; its deep-travel share 1.62 -> 1.13 % where the ride had
    0.63 %: scaled, 0.44 %, not -0.49 + 0.63 ...); a share rising towards 100 % scaled by the room
    left; a count rising added; the balance (either sign) added."""
    e = advise.expected
    assert e("front.bottom_outs", 0.0, 5.0, 4.0) == 0.0
    assert e("front.bottom_outs_per_minute", 2.0, 4.0, 1.0) == pytest.approx(0.5)
    assert e("front.deep_travel_percent", 0.63, 1.62, 1.13) == pytest.approx(0.63 * 1.13 / 1.62)
    assert e("rear.high_speed_percent", 99.0, 98.0, 99.5) == pytest.approx(100.0 - 1.0 * 0.5 / 2.0)
    assert e("rear.low_speed_percent", 1.0, 2.0, 0.5) == pytest.approx(0.25)  # the same share, seen from below
    assert e("rear.bottom_outs", 2.0, 1.0, 3.0) == pytest.approx(4.0)
    assert e("balance_points", 3.0, 1.0, -4.0) == pytest.approx(-2.0)
    assert e("front.max_travel_percent", 70.0, 80.0, 80.0) == 70.0
    rng = np.random.default_rng(11)
    for metric, (lo, hi) in (("front.bottom_outs", (0.0, 30.0)), ("rear.deep_travel_percent", (0.0, 100.0)),
                             ("front.p95_rebound_mm_per_s", (0.0, 3000.0)), ("rear.rebound_over_compression", (0, 2))):
        for _ in range(300):
            rec, a, b = rng.uniform(lo, hi, 3) * rng.choice([0.0, 1.0], 3, p=[0.2, 0.8])
            x = e(metric, rec, a, b)
            assert 0.0 <= x and (hi != 100.0 or x <= 100.0), (metric, rec, a, b, x)
            assert e(metric, rec, a, a) == rec
            assert (x - rec) * (b - a) >= 0.0  # it moves the way the model's value moves
            assert e(metric, rec, a, b + abs(b - a) + 1.0) >= x  # more in the model, no less expected


def test_clicks_step_within_the_measured_range_from_its_own_first_position(tmp_path):
    """Clicks measured at 4-20 and set at 5: two clicks down is 3, outside; the candidate is 4 (the
    range's own end, not 0); set at 4, none down."""
    from mtbmj.bike import spec as spec_mod

    bike = tmp_path / "clicks.toml"
    for setting, down in ((5, 4.0), (4, None), (12, 10.0)):
        bike.write_text(clicks_bike(setting))
        found = {a.key: a for a in advise.adjusters(spec_mod.load(str(bike)))}
        comp = found["fork.damper.compression_clicks"]
        assert comp.down == down and comp.up == setting + 2.0, (setting, comp)
        ok, skipped = advise.allowed(str(bike), [(comp, "down", comp.down)] if down is not None else [], lambda x: x)
        assert not skipped  # the candidate the part allows, composed without a refusal


def test_a_candidate_the_part_does_not_allow_is_skipped_naming_why(tmp_path):
    """An air shock with 5 spacers where a sixth leaves less air than the stroke sweeps: the sixth
    spacer is skipped (naming the chamber), the fourth kept; nothing else skipped."""
    from mtbmj.bike import spec as spec_mod

    bike = tmp_path / "air.toml"
    bike.write_text(air_shock_bike(5))
    spec = spec_mod.load(str(bike))
    cands = [(a, d, v) for a in advise.adjusters(spec) for d, v in (("down", a.down), ("up", a.up)) if v is not None]
    tokens = [(a, d, v) for a, d, v in cands if a.key == "fork.spring.tokens" and a.section == "shock.set"]
    assert sorted(v for _, _, v in tokens) == [4.0, 6.0]
    ok, skipped = advise.allowed(str(bike), cands, lambda extra: extra)
    assert [(s["key"], s["to"]) for s in skipped] == [("shock:fork.spring.tokens", 6.0)], skipped
    assert "air chamber" in skipped[0]["why"] and skipped[0]["why"].startswith("fork.spring.air_volume_cm3")
    assert len(ok) == len(cands) - 1


@pytest.mark.slow
def test_a_candidate_refused_only_when_run_is_skipped_and_reported(tmp_path, monkeypatch, capsys):
    """A candidate whose run the part refuses (a ConfigError from the worker) is skipped, not fatal:
    the advice is written, its report names the candidate and why (advice.json 'skipped', the
    line, the HTML), and no expected count or share is negative."""
    real = advise.simulate

    def refusing(bike, overrides, terrain, speed, duration, label, lead_s, profile=None):
        if label.startswith("shock rebound damping"):
            from mtbmj.errors import ConfigError

            raise ConfigError("fork.damper.rebound_N_s_per_m: refused here (the test's part)")
        return real(bike, overrides, terrain, speed, min(duration, 0.3), label, lead_s, profile)

    monkeypatch.setattr(advise, "simulate", refusing)
    bike, fork_mm, rear_mm, t = ride(tmp_path, fork_reb=2500.0)  # the packing ride, whose reconstruction checks
    sst = write_sst(tmp_path / "ride.SST", fork_mm, rear_mm)
    out = tmp_path / "advice"
    with reconstruction_passing():  # refused otherwise: the model does not describe the made ride (issue 51)
        assert main(["advise", str(sst), "--bike", str(bike), "--workers", "1", "--duration", "1000",
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    # a --duration past the ride's end is the whole ride, and said (it was silent)
    said = [line for line in printed.splitlines() if line.startswith("--duration 1000 s is longer than ride.SST (")]
    assert len(said) == 1 and said[0].endswith(" s): the whole ride was advised on"), printed
    advice = json.loads((out / "advice.json").read_text())
    assert sorted((s["label"], s["direction"]) for s in advice["skipped"]) == [
        ("shock rebound damping", "down"), ("shock rebound damping", "up")]
    assert all("refused here" in s["why"] for s in advice["skipped"])
    assert "skipped, not allowed by the part: shock rebound damping 3500 -> 2800" in printed
    assert 'id="skipped"' in (out / "advice.html").read_text()
    assert not any(c["label"] == "shock rebound damping" for c in advice["candidates"])
    rec = advice["recommendation"]
    for k, c in (rec or {}).get("changes", {}).items():
        assert k == "balance_points" or c["expected"] >= 0.0, (k, c)

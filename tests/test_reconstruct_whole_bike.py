"""A ride reconstructed (mtbmj/ride/reconstruct.py, issue 51 item 5) against a ride made by a whole
bike integrated in tests/helpers.py (``whole_bike_ride``: scipy's solve_ivp, its own equations, not the
package's engines or laws' code): a frame that heaves and pitches, a rider on legs and arms (vertical
springs and dampers at the pedals and the bars) who heaves and pitches on it and shifts a slow load
fore and aft (a force pair at the bars and pedals, 80 N, 7 s period), the fork's lower and wheel
sliding along the steering axis, the rear wheel on a constant leverage ratio, point-contact tyres
that leave the ground, at a speed that varies along the ride (6.5 +- 1 m/s over 25 s), over terrain
made there: ISO 8608 class C roughness (sum of sines, 0.05-8 cycles/m), a rock garden, a G-out,
drops of 0.3 and 0.5 m and a tabletop jump of 0.4 m, written as SST version 3 integer counts through
the bike file's [sensors] (tests/helpers.write_v3: the law of cosines inverted).

Shared with the package, and so not tested here: the laws' form and values (helpers.law: a linear
spring, a bumper, stiff stops and a damper of one rate each way, the values the bike file gives),
the masses and geometry read from the same bike file (inputs), point-contact tyres of the bike file's
rate without damping, vertical-only motion of the axles (the wheelbase fixed at its sag), the frame's
pitch carrying the rider (rigid fore and aft on his limbs) and the wheels fore and aft with the bike's
horizontal momentum free (here an explicit fore-aft coordinate solved with the pitch, there
``reconstruct_bike.carried_inertia``'s closed form; the MuJoCo bike has it too), the rear unsprung mass
lumped at the axle (the wheel and half the swingarm). Not shared:
the pitch coupling between the ends, the rider on his limbs (the package's inverse takes each end's
sprung mass as rigid, its static share of bike and rider), the rider's slow load (the inverse takes
the slow part of the fork's force as the rider's and gives the rear none), the split of the rider's
on-bike mass (half at the pedals, half at the bars here).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.signal import butter, sosfiltfilt

from mtbmj.cli import main

from helpers import WHOLE_RATE as RATE, SpeedProfile, bike_text, whole_bike_ride

SECONDS = 40.0
PROFILE = SpeedProfile(6.5, 1.0, 25.0)  # m/s: the speed V0 + DV sin(2 pi t / PERIOD)
V0 = PROFILE.v0
speed, along = PROFILE.at, PROFILE.along


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return whole_bike_ride(tmp_path_factory.mktemp("whole_bike"), seconds=SECONDS, profile=PROFILE)


@pytest.fixture(scope="module")
def rebuilt(made, tmp_path_factory):
    out = tmp_path_factory.mktemp("rebuilt") / "rec"
    assert main(["reconstruct", str(made["sst"]), "--bike", str(made["bike"]), "--out", str(out)]) == 0
    return out


def test_the_made_ride_has_what_it_must(made):
    """The ride made here leaves the ground (the jump, the drops) and uses the travel."""
    assert made["airborne_front"] > 0.005
    assert np.ptp(made["fork_mm"]) > 60.0 and np.ptp(made["rear_mm"]) > 50.0


def test_the_speed_along_the_ride_comes_back(made, rebuilt):
    """Issue 51 item 1: every window's speed within 3 % of the made ride's mean speed over that window
    (what a window's lag measures: its span's mean) and within 5 % of the made speed at its centre;
    measured 1.7 % and 1.6 % at most (a strict xfail at 3.7 % and 3.9 % until the rear's flights were
    left out of the lag found again, ``reconstruct_speed.refine``'s ``flights``);
    the profile (linear between the windows' centres) within 3 % RMS over the samples checked; the
    wheelbase it is found with (the ride's sag) within 0.5 % of the made ride's median; the distance
    axis (terrain.csv's, past its lead-in) within 3 % of the made distance at the end."""
    import csv as csv_mod

    s = json.loads((rebuilt / "reconstruction.json").read_text())
    accepted = [w for w in s["windows"] if w["speed_m_per_s"] is not None]
    assert len(accepted) >= 0.6 * len(s["windows"])
    t = made["t"]
    for w in accepted:
        assert w["speed_m_per_s"] == pytest.approx(float(speed(0.5 * (w["start_s"] + w["end_s"]))), rel=0.05), w
        inside = (t >= w["start_s"]) & (t < w["end_s"])
        assert w["speed_m_per_s"] == pytest.approx(float(np.mean(speed(t[inside]))), rel=0.03), w
        assert 0.0 < w["speed_sd_m_per_s"] < 0.1 * w["speed_m_per_s"], w
    assert s["wheelbase_at_sag_m"] == pytest.approx(float(np.median(made["wb"])), rel=0.005)
    with open(rebuilt / "series.csv") as f:
        rows = list(csv_mod.DictReader(f))
    ts = np.array([float(r["time_s"]) for r in rows])
    v = np.array([float(r["speed_m_per_s"]) for r in rows])
    checked = np.array([r["checked"] == "1" for r in rows])
    assert np.sqrt(np.mean((v[checked] / speed(ts[checked]) - 1.0) ** 2)) < 0.03
    with open(rebuilt / "terrain.csv") as f:  # its distance axis, past the level lead-in
        end_m = float(list(csv_mod.DictReader(f))[-1]["distance_m"]) - s["terrain_csv_lead_in_m"]
    assert end_m == pytest.approx(float(along(ts[-1])), rel=0.03)  # the speed's 3 %, integrated (1.5 % today)


def terrain_error_mm(made, rec) -> float:
    """The terrain found under the front wheel against the made one, both high-passed at 5 m (at the
    mean speed: V0 / 5 Hz in time), RMS over the samples the checks count (mm)."""
    sos = butter(2, V0 / 5.0, btype="highpass", fs=RATE, output="sos")
    truth = made["h"](along(made["t"]))
    e = sosfiltfilt(sos, rec.ground) - sosfiltfilt(sos, truth)
    return 1e3 * float(np.sqrt(np.mean(e[rec.valid] ** 2)))


@pytest.fixture(scope="module")
def reconstruction(made):
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(made["sst"], **decoding(SimpleNamespace(bike=str(made["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    return reconstruct.reconstruct(record, str(made["bike"]))


def test_the_right_bike_describes_the_ride(rebuilt, reconstruction):
    """The rear predicted from the fork's record alone beats both naive baselines by the stated margin
    (40 %: the checks' pass), at a correlation above 0.8, and the headline says so in words."""
    d = json.loads((rebuilt / "reconstruction.json").read_text())
    c = d["checks"]
    assert c["passes"] is True, c
    assert d["at_once_spectral"]["band_Hz"] == [0.3, 3.0]  # the check's rear met the found ground's share at once
    assert c["beat_margin_percent"] == 40.0
    assert c["rear_predicted_rms_mm"] <= 0.6 * min(c["baseline_delayed_fork_rms_mm"], c["baseline_rear_mean_rms_mm"])
    assert c["verdict"].startswith("the model describes this ride")
    v = reconstruction.valid
    assert np.corrcoef(reconstruction.rear_predicted[v], reconstruction.rear[v])[0, 1] > 0.8


def test_a_drops_level_is_kept(made, reconstruction):
    """Issue 51 (the terrain under the wheels): the ground found 2 s past the made ride's 0.5 m drop lies
    at least half the drop below where it was 1 s before it, and the ground found from its start is off
    the made one by at most 0.6 of what a ground with no level below 0.3 Hz is off (the made terrain
    high-passed here at 0.3 Hz, forward and back, as the body's drift is removed). Measured: -0.505 m
    across the drop, 57 mm RMS from the start where the high-passed terrain is 388 mm off (the drop read
    -0.46 m across its flight, the 0.3 m drop -0.26: mtbmj/ride/reconstruct_flight.py); before each
    drop's edge flight's level was kept +0.02 m and 388 mm. The drops' levels are read so on rides made
    here of their own in tests/test_reconstruct_flight.py."""
    t, dt = made["t"], made["t"][1] - made["t"][0]
    truth = made["h"](along(t))
    truth = truth - truth[0]
    found = reconstruction.ground - reconstruction.ground[0]
    k = int(np.argmax(along(t) >= made["features"]["drop_0.5"]))
    i, j = k - int(round(1.0 / dt)), k + int(round(2.0 / dt))
    assert truth[j] - truth[i] == pytest.approx(-0.5, abs=0.05)  # the drop as made
    lost = truth - sosfiltfilt(butter(2, 0.3, btype="highpass", fs=1 / dt, output="sos"), truth)
    v = reconstruction.valid
    err, baseline = (1e3 * float(np.sqrt(np.mean(e[v] ** 2))) for e in (found - truth, lost))
    assert err <= 0.6 * baseline, (err, baseline)
    assert found[j] - found[i] < -0.25, found[j] - found[i]


TOO_LITTLE = "the fork's record holds too little about this ride's rear to check the model"


def test_the_verdict_does_not_say_the_front_holds_too_little(reconstruction):
    """Issue 51 item 3, the bound beside the baselines (mtbmj/ride/reconstruct_bound.py): on this ride
    the rear meets the terrain a wheelbase after the front (its rider only shifts a slow load), so in
    0.5-2 Hz the fork's record correlates with the rear's more a wheelbase later than at once, and the
    verdict never blames the ride (tests/test_reconstruct_bound.py makes a ride where it does)."""
    c = reconstruction.checks()
    body = next(b["timing"] for b in c["bands"] if b["band_Hz"] == [0.5, 2.0])
    assert body["fork_at_lag_correlation"] > body["fork_now_correlation"] + 0.2, body
    assert c["front_holds_too_little"] is False and TOO_LITTLE not in c["verdict"]
    assert c["bound_fork_filter_rms_mm"] < c["baseline_delayed_fork_rms_mm"]  # the fork carries the rear


@pytest.mark.xfail(strict=True, reason="a linear filter from the fork's record cannot follow the whole bike's flights "
                                       "and stops: fitted on the rear itself it reaches 4.70 mm RMS where it was not "
                                       "fitted, the pass mark is 4.07 mm and the model 3.43 mm (3.73 before the "
                                       "rear met the found ground's spectral share at once; 3.77 before the "
                                       "drops' levels were kept; before the rear's flights were left out of the speed found again 4.81, 4.14 and 3.63: 5.74 and "
                                       "3.74 per fold; with a fixed ridge in-sample on the whole ride 3.76)")
def test_the_fork_filter_meets_the_pass_mark_where_the_front_carries_the_rear(reconstruction):
    """The bound below the pass mark on a ride whose rear the front's record carries (the model passes
    here)."""
    c = reconstruction.checks()
    assert c["bound_fork_filter_rms_mm"] <= c["pass_mark_rms_mm"], c


@pytest.mark.xfail(strict=True, reason="since the made bike and the reconstruction's carry the masses fore and aft in "
                                       "pitch (reconstruct_bike.carried_inertia): the rear predicted 3.43 mm RMS where "
                                       "the delayed fork gives 6.78 (0.51 of it, the target 0.5, at a correlation of "
                                       "0.938; 3.73, 0.55, 0.925 before the rear met the found ground's spectral "
                                       "share at once; 3.77, 0.56, before the drops' levels were kept; 3.63 and 6.90, 0.53, "
                                       "before the rear's flights were left out of the speed found again). Where: "
                                       "53 % of the squared error in the rock garden (6-10 s), 16 % at the tabletop's "
                                       "landing, 15 % at the 0.5 m drop's; the rear is thrown off faces found too low "
                                       "(a rock's 123 mm for 147, the ramp 290 mm for 396), lowered by the loop holding "
                                       "the frame's front near the quarter car's high-passed body: without it 2.51 mm "
                                       "(0.37) here, but worse on ten of the twelve shared rides (docs/rolling.md, "
                                       "'Where the made ride's rear misses'); no rule from the fork's side "
                                       "chooses the looser loop per ride without costing the shared rides "
                                       "('Can the ride choose the loop's setting?'); the loop's damping pushes the "
                                       "frame at once at the faces (81 of its 81.4 N RMS at the rock): its slow "
                                       "load fed forward instead passes here (2.71 mm, 0.40) and breaks three "
                                       "of the advice's answers ('The rider's slow load fed forward'); the faces "
                                       "are low by the frame's front path alone, its reference the quarter car's "
                                       "body at every frequency: that reference above 2 Hz taken from the whole "
                                       "bike's own frame passes here (3.23 mm, 0.477) and broke five guard tests "
                                       "('Why the faces are found low')")
def test_the_rear_is_predicted_within_half_the_delayed_forks_error(reconstruction):
    """Issue 51's rear target: the rear predicted from the fork's record within half the RMS error of
    the delayed-fork baseline, at a correlation of at least 0.9 with the record (0.44 of it at 0.914
    since a long flight's take-off is put where the tyre's force fell toward zero and one that lands
    lower is bridged from a drop's edge; 0.52 at 0.88 with the chord from a late take-off)."""
    c = reconstruction.checks()
    v = reconstruction.valid
    assert c["rear_predicted_rms_mm"] <= 0.5 * c["baseline_delayed_fork_rms_mm"]
    assert np.corrcoef(reconstruction.rear_predicted[v], reconstruction.rear[v])[0, 1] >= 0.9


def test_the_terrain_is_found_within_15_mm(made, reconstruction):
    """Issue 51's terrain target on this ride: within 15 mm RMS after a 5 m high-pass (10.2 mm when
    written; 20.2 with the chord from a late take-off, most of it at the 0.5 m drop's edge)."""
    assert terrain_error_mm(made, reconstruction) < 15.0


def test_issue_51_speed_target(reconstruction):
    """Issue 51's speed target: every window that gives a speed within 3 % of the made speed at its
    centre (1.6 % at most now; 3.9 % since the bikes carry their masses in pitch until the rear's
    flights were left out of the lag found again; 1.8 % at most when written, with the speed found
    again from the rear predicted: 2.5 s
    windows; 3.4 % with the two ends' lag alone, 5 s windows, whose lag is their span's mean); and the
    speed was found again (the first pass's rear beats the naive baselines on this ride)."""
    sp = reconstruction.speed
    assert "first" in sp and sp["window_s"] < sp["first"]["window_s"]
    found = [(start, v) for start, v, _ in sp["windows"] if v is not None]
    assert len(found) >= 0.6 * len(sp["windows"])
    for start, v in found:
        assert v == pytest.approx(float(speed(start + 0.5 * sp["window_s"])), rel=0.03), start


def test_the_terrain_is_found_under_the_jumps_and_drops(made, reconstruction):
    """The terrain within 25 mm RMS after a 5 m high-pass (the made one spans 1.2 m: drops of 0.3 and
    0.5 m, a 0.4 m tabletop, a 0.25 m G-out), the flights found: one starts within the first 0.5 m past
    each drop's edge and one over the tabletop (its 7.5 m), and none is longer than 0.5 s (no flight
    runs on past a landing)."""
    assert terrain_error_mm(made, reconstruction) < 25.0
    rec = reconstruction
    where = lambda m: float(np.interp(m, along(made["t"]), made["t"]))  # noqa: E731 (s at m along the ride)
    for name, span in (("jump", 7.5), ("drop_0.3", 0.5), ("drop_0.5", 0.5)):
        a, b = where(made["features"][name]), where(made["features"][name] + span)
        assert any(a <= start <= b for start, _ in rec.jumps), (name, a, b, rec.jumps)
    assert max(end - start for start, end in rec.jumps) < 0.5


@pytest.mark.slow  # a reconstruction through the whole bike: 0.5-2 min
@pytest.mark.parametrize("wrong", ["fork_spring_x1.5", "rider_25kg_heavier"])
def test_a_wrong_bike_fails_the_checks_and_says_why(made, tmp_path, capsys, wrong):
    """The same ride read through a bike that did not make it: its fork spring 1.5 times the made one,
    or its rider 25 kg heavier. The rear predicted from the fork's record must lose to a naive
    baseline by the stated margin, and the line says so in words, without saying the ride cannot be
    checked."""
    text = bike_text(18.0 if wrong == "fork_spring_x1.5" else 12.0)
    if wrong == "rider_25kg_heavier":
        from mtbmj.bike import spec as spec_mod

        text += f"[rider]\nmass_kg = {spec_mod.load(str(made['bike'])).rider.mass + 25.0:g}\n"
    bike = tmp_path / "wrong.toml"
    bike.write_text(text)
    assert main(["reconstruct", str(made["sst"]), "--bike", str(bike), "--out", str(tmp_path / "rec")]) == 0
    line = capsys.readouterr().out
    c = json.loads((tmp_path / "rec" / "reconstruction.json").read_text())["checks"]
    assert c["passes"] is False, c
    assert "the model does not describe this ride: it does not beat " in line
    # the fault is the bike's: the verdict does not say the fork's record cannot check this ride's rear
    assert c["front_holds_too_little"] is False and TOO_LITTLE not in line


def test_the_whole_bike_rides_its_reconstruction(made, rebuilt, tmp_path, capsys):
    """`mtbmj bike` at the recorded setting rides the reconstructed terrain.csv as written, from its
    level lead-in over the G-out, the drops and the tabletop, without a crash (exit 0, no 'crashed')."""
    s = json.loads((rebuilt / "reconstruction.json").read_text())
    length = s["terrain_length_m"] + s["terrain_csv_lead_in_m"]
    code = main(["bike", str(made["bike"]), str(rebuilt / "terrain.csv"), "--speed", f"{V0:g}",
                 "--duration", f"{0.9 * length / V0:.1f}", "--no-figure", "--quiet", "--out", str(tmp_path / "bike")])
    out = capsys.readouterr()
    assert code == 0 and "crashed" not in out.out + out.err, out


@pytest.mark.slow
def test_a_drops_edge_beats_the_chord_on_a_ride_of_its_own(tmp_path, monkeypatch):
    """A long flight's take-off where the tyre's force fell toward zero and, where it lands more than
    0.15 m lower, the ground bridged from the edge the wheel left (reconstruct_inverse.unloaded and
    bridge), against the chord under every flight from where the force read zero, on a ride made here
    with its own seed, features and speed (5 +- 0.8 m/s over rocks, a 0.4 m drop, a G-out and a 0.5 m
    tabletop; nothing was tuned on it): the terrain's error after a 5 m high-pass at most 0.8 of the
    chord's (10.5 against 17.3 mm when written), and the rear predicted closer with the edge (4.4
    against 5.2 mm RMS, the delayed fork 6.9). Before the speed was found again from the rear
    predicted, the rear was worse with the edge (5.9 against 4.9 mm): one window's speed 10.5 % off
    put the 0.4 m drop's step 0.27 m deep. Issue 51's speed target holds on this ride too: every
    window found again within 3 % of the made speed at its centre (1.9 % at most when written, 2.5 %
    later, 1.7 % since the rear's flights are left out of the speed found again; with them left out the
    terrain is 9.0 mm against the chord's 16.9, the rear 4.4 against 5.7)."""
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct, reconstruct_inverse

    profile = SpeedProfile(5.0, 0.8, 15.0)
    features = (("rocks", 20.0, 0.08), ("drop", 50.0, 0.4), ("g_out", 80.0, 0.3), ("jump", 110.0, 0.5))
    ride = whole_bike_ride(tmp_path, seed=11, seconds=30.0, profile=profile, features=features)
    record = telemetry.read_ride(ride["sst"], **decoding(SimpleNamespace(bike=str(ride["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    sos = butter(2, profile.v0 / 5.0, btype="highpass", fs=RATE, output="sos")
    truth = sosfiltfilt(sos, ride["h"](profile.along(ride["t"])))

    def error_mm():
        rec = reconstruct.reconstruct(record, str(ride["bike"]))
        e = sosfiltfilt(sos, rec.ground) - truth
        return 1e3 * float(np.sqrt(np.mean(e[rec.valid] ** 2))), rec

    edge, rec = error_mm()
    sp = rec.speed
    assert "first" in sp
    for start, v, _ in sp["windows"]:
        assert v is None or v == pytest.approx(float(profile.at(start + 0.5 * sp["window_s"])), rel=0.03), start
    monkeypatch.setattr(reconstruct_inverse, "EDGE_FLIGHT_S", math.inf)  # the chord under every flight
    chord, by_chord = error_mm()
    assert edge <= 0.8 * chord, (edge, chord)
    assert rec.checks()["rear_predicted_rms_mm"] < by_chord.checks()["rear_predicted_rms_mm"]


@pytest.mark.slow
def test_a_drop_whose_tyre_force_flickers_is_found_on_a_ride_of_its_own(tmp_path):
    """Issue 51's made-ride targets on a ride made here with a seed, features and speed of its own
    (5.5 +- 0.6 m/s over a 0.35 m drop, rocks, a G-out and a 0.4 m tabletop): the terrain within 15 mm
    RMS after a 5 m high-pass, the rear predicted within half the delayed fork's RMS error and with a
    correlation of at least 0.9, every window's speed within 3 % of the made speed at its centre.
    Written after the drop was found bridged, not before: read stretch by stretch, its 0.19 s fall
    was two 0.09 s hops (the inverse's force flickering at 0-56 N between), the ground followed the
    wheel down, and the ride gave 14.3 mm, 0.68 and 0.77; one flight (reconstruct_inverse.unloaded)
    gave 6.5 mm, 0.44 and 0.915 when written."""
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    profile = SpeedProfile(5.5, 0.6, 30.0)
    features = (("rocks", 30.0, 0.05), ("drop", 70.0, 0.35), ("g_out", 110.0, 0.2), ("jump", 150.0, 0.4))
    ride = whole_bike_ride(tmp_path, seed=7, seconds=35.0, profile=profile, features=features)
    record = telemetry.read_ride(ride["sst"], **decoding(SimpleNamespace(bike=str(ride["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    rec = reconstruct.reconstruct(record, str(ride["bike"]))
    sos = butter(2, profile.v0 / 5.0, btype="highpass", fs=RATE, output="sos")
    e = sosfiltfilt(sos, rec.ground) - sosfiltfilt(sos, ride["h"](profile.along(ride["t"])))
    assert 1e3 * float(np.sqrt(np.mean(e[rec.valid] ** 2))) <= 15.0
    c = rec.checks()
    assert c["rear_predicted_rms_mm"] <= 0.5 * c["baseline_delayed_fork_rms_mm"], c
    v = rec.valid
    assert np.corrcoef(rec.rear_predicted[v], rec.rear[v])[0, 1] >= 0.9
    sp = rec.speed
    for start, s, _ in sp["windows"]:
        assert s is None or s == pytest.approx(float(profile.at(start + 0.5 * sp["window_s"])), rel=0.03), start


@pytest.mark.slow  # the reconstruction again with two or three more runs of the whole bike: 0.5-1 min
def test_the_share_met_at_once_is_none_on_a_ride_whose_rear_meets_the_terrain_a_wheelbase_later(made, reconstruction):
    """reconstruct(at_once=True) on the made ride, whose rear meets what the front met a wheelbase later
    (no load on both ends at once beyond the rider's slow one): the share fitted on the rear's record is
    0, its rear is the judged one's, and the judged checks are those of the plain reconstruction (the
    fit is reported beside, never judged)."""
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(made["sst"], **decoding(SimpleNamespace(bike=str(made["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    rec = reconstruct.reconstruct(record, str(made["bike"]), at_once=True)
    fit, c, plain = rec.at_once_fit, rec.checks(), reconstruction.checks()
    assert fit["share"] == 0.0 and fit["judged"] is False
    assert abs(fit["rear_predicted_rms_mm"] - c["rear_predicted_rms_mm"]) < 1e-9
    assert c["rear_predicted_rms_mm"] == plain["rear_predicted_rms_mm"] and c["passes"] == plain["passes"]
    assert "met at the front's moment" not in reconstruction.line() and rec.summary()["at_once_fit"] == fit


@pytest.fixture(scope="module")
def pumped_record(tmp_path_factory):
    """The made ride again with its rider pumping and absorbing: his limbs push both ends down at once
    with a force of 0.5-2 Hz of at most 300 N (``whole_bike_ride(pump_N=300)``): (its bike file, its record)."""
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry

    made = whole_bike_ride(tmp_path_factory.mktemp("pumped"), seconds=SECONDS, profile=PROFILE, pump_N=300.0)
    return str(made["bike"]), telemetry.read_ride(made["sst"], **decoding(SimpleNamespace(
        bike=str(made["bike"]), fork_max_mm=None, shock_max_mm=None)))


@pytest.fixture(scope="module")
def pumped(pumped_record):
    """The pumped ride reconstructed (the check's default: the found ground's spectral share met at once)."""
    from mtbmj.ride import reconstruct

    bike, record = pumped_record
    return reconstruct.reconstruct(record, bike)


@pytest.mark.slow  # a ride made and reconstructed: 0.5 min
def test_a_rider_pumping_at_300_n_fails_the_check_without_blaming_the_ride(pumped):
    """What the check says on the pumped ride: the model fails (5.3 mm against the mark 4.7), the
    fork's filter misses the mark too (6.0), but in 0.5-2 Hz the rear still follows the fork a
    wheelbase later more than at once (0.71 against 0.58), so the verdict does not say the fork's
    record holds too little: 300 N of pumping is not the shared rides' load on both ends."""
    c = pumped.checks()
    body = next(b["timing"] for b in c["bands"] if b["band_Hz"] == [0.5, 2.0])
    assert c["passes"] is False and c["bound_misses_mark"] is True, c
    assert body["fork_at_lag_correlation"] > body["fork_now_correlation"], body
    assert c["front_holds_too_little"] is False and TOO_LITTLE not in c["verdict"]


@pytest.mark.slow  # a ride made and reconstructed: 0.5 min
@pytest.mark.xfail(strict=True, reason="the rider's pumping is not estimated: on the made ride with 0.5-2 Hz of at most "
                                       "300 N at both ends the rear predicted is 5.26 mm RMS, the mark 4.67 (6.51 "
                                       "before the rear met the found ground's spectral share at once; the delayed "
                                       "fork 7.79; 3.43 against 4.07 without the pumping)")
def test_the_model_describes_a_ride_whose_rider_pumps(pumped):
    """Issue 51 item 2: the rider's loads (pumping among them) are an estimated input, bounded by what a
    rider can do, so a ride with them is described as one without."""
    assert pumped.checks()["passes"] is True


@pytest.mark.slow  # the pumped ride reconstructed again the way before: 0.5 min
def test_the_spectral_share_brings_the_pumped_rear_nearer_its_record(pumped_record, pumped):
    """Issue 51 item 2 (mtbmj/ride/reconstruct_share.py): on the pumped ride the rear meeting at the front's
    moment the found ground's share above the ISO 8608 law is nearer the rear's record than all of it a
    wheelbase later (the code before: ``spectral=False``). Measured: 5.26 mm RMS against 6.51; the
    reconstruction says the share it used (0.3-3 Hz, 18.8 mm RMS met at once)."""
    from mtbmj.ride import reconstruct

    bike, record = pumped_record
    before = reconstruct.reconstruct(record, bike, spectral=False)
    now, then = pumped.checks()["rear_predicted_rms_mm"], before.checks()["rear_predicted_rms_mm"]
    assert now < then - 0.2, (now, then)
    used = pumped.summary()["at_once_spectral"]
    assert used["band_Hz"] == [0.3, 3.0] and used["fit_Hz"] == [3.0, 10.0] and used["at_once_rms_mm"] > 1.0, used
    assert before.spectral is None and "at_once_spectral" not in before.summary()
    assert "of the ground found at the front's moment" in pumped.line()

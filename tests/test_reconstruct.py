"""A ride reconstructed through the bike (mtbmj/ride/reconstruct.py) against a ride made here: a
hidden bumpy profile ridden at a known speed by a bike integrated in this file (scipy's DOP853, its
own equations: each end a sprung and an unsprung mass on a linear spring and damper, the fork's
acting along the steering axis, a constant leverage ratio at the rear, point-contact tyres that leave
the ground), both ends' travel written as a travel CSV at 1 kHz rounded to 0.1 mm (a sensor's
resolution).

Shared with the package, and so not tested here: the laws and masses read from the same bike file
(inputs, not results). Not shared: the package reconstructs through the bike file's whole bike (its
frame pitching, its rider on legs and arms; mtbmj/ride/reconstruct_bike.py), this generator's ends
move independently with rigid masses (dynamic index 1: two quarter cars). So this ride is not the
bike file's bike: its checks must say the model does not describe it; the package's quarter-car
inverse (the whole bike's first guess) must find its terrain. The whole bike's accuracy is tested on
a ride made by a whole bike in tests/test_reconstruct_whole_bike.py."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import pytest

from mtbmj.cli import main

from helpers import BIKE, RATIO, bumps_csv, quarter_car_masses, quarter_car_ride

SPEED = 6.0
RATE = 1000.0
SECONDS = 16.0


def hidden_profile(seed=3):
    """Bumps 5-25 mm high and 1.2-3 m long, at random places, on flat ground: h(s) m."""
    rng = np.random.default_rng(seed)
    centres = np.sort(rng.uniform(8.0, SPEED * SECONDS - 4.0, 40))
    heights = rng.uniform(0.005, 0.025, centres.size)
    lengths = rng.uniform(1.2, 3.0, centres.size)

    grid = np.arange(-2.0, SPEED * SECONDS + 1.0, 1e-3)
    table = np.zeros_like(grid)
    for c, a, L in zip(centres, heights, lengths):
        u = np.clip((grid - c) / L + 0.5, 0.0, 1.0)
        table += a * np.sin(np.pi * u) ** 2
    return lambda s: np.interp(s, grid, table)  # on a 1 mm grid: the bumps' chords sag < 0.01 mm


def ride(tmp_path):
    """The made ride (``helpers.quarter_car_ride``) over the hidden profile at ``SPEED``."""
    h = hidden_profile()
    m = quarter_car_ride(tmp_path, h, lambda t: SPEED * t, SECONDS, RATE)
    assert max(m["airborne"]) < 0.02 * m["t"].size, m["airborne"]  # the tyres leave the ground only briefly, at a few crests
    return m["bike"], m["csv"], m["t"], m["fork_mm"], m["rear_mm"], h, m["wb"]


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return ride(tmp_path_factory.mktemp("reconstruct"))


def test_the_speed_the_terrain_and_the_rear_come_back(made, tmp_path):
    import json

    bike, csv, t, fork_mm, rear_mm, h, wb = made
    out = tmp_path / "rec"
    assert main(["reconstruct", str(csv), "--bike", str(bike), "--out", str(out)]) == 0
    summary = json.loads((out / "reconstruction.json").read_text())
    assert summary["speed_m_per_s"] == pytest.approx(SPEED, rel=0.03)
    # the first pass's rear does not beat the delayed fork here, so its timing is not trusted to find the
    # speed again (it would: the rear predicted's phase is the whole bike's, not these quarter cars')
    assert "first_estimate" not in summary["speed_profile"]
    assert summary["speed_profile"]["found_from"] == "the lag between the two ends"
    c = summary["checks"]
    # two independent quarter cars are not the bike file's whole bike: the checks tell them apart
    assert c["passes"] is False and c["verdict"].startswith("the model does not describe this ride")
    assert c["samples_checked_percent"] > 50.0
    assert (out / "terrain.csv").read_text().splitlines()[0] == "distance_m,height_mm"


def test_the_ground_under_the_front_is_the_hidden_one(made):
    """The quarter car's inverse (reconstruct_inverse.ground_under, the whole bike's first guess; this
    ride is two quarter cars) against the hidden profile under the front wheel, sample by sample in
    time (the speed is checked above), both without their slow part (a slope is not in a
    suspension's record): RMS within 3 mm where the bumps are 5-25 mm, over the samples the checks
    count."""
    from scipy.signal import butter, sosfiltfilt

    from mtbmj.ride import reconstruct
    from mtbmj.measured import telemetry

    bike, csv, t, fork_mm, rear_mm, h, wb = made
    from mtbmj.bike import run, spec as spec_mod
    from mtbmj.ride.reconstruct_inverse import QuarterCar, ground_under

    rec = reconstruct.reconstruct(telemetry.read_travel_csv(csv), str(bike))
    spec = spec_mod.load(str(bike))
    fork_setup, _ = run.setups(spec)
    Mf, mf, _, _ = quarter_car_masses(spec)
    car = QuarterCar(Mf, mf, fork_setup.fork, fork_setup.tire.values(1).rate, fork_setup.tire_radius,
                     fork_setup.gravity, fork_setup.travel)
    sa = math.sin(spec.head_angle)
    ground = ground_under(t, fork_mm * 1e-3 * sa, fork_mm * 1e-3, car, lambda w: sa)[0]
    sos = butter(2, 0.3, btype="highpass", fs=RATE, output="sos")
    found, hidden = sosfiltfilt(sos, ground), sosfiltfilt(sos, h(SPEED * t))
    keep = rec.valid & (t > 3.0) & (t < t[-1] - 2.0)
    assert keep.mean() > 0.5
    assert np.sqrt(np.mean((found[keep] - hidden[keep]) ** 2)) < 3e-3
    assert np.ptp(hidden[keep]) > 0.02  # there were bumps to find


def test_the_figure_marks_what_was_left_out(made, tmp_path):
    from mtbmj.ride import reconstruct
    from mtbmj.measured import telemetry

    bike, csv, *_ = made
    rec = reconstruct.reconstruct(telemetry.read_travel_csv(csv), str(bike))
    fig = rec.figure()
    titles = [a.get_title() for a in fig.axes]
    assert titles[1] == "Front: the record reproduced (the check)"
    assert titles[2].startswith("Rear: predicted from the front's terrain, beside the naive baseline")
    assert fig.axes[2].get_xlim() == pytest.approx((0.0, SECONDS - 1.0 / RATE))
    c = rec.checks()
    assert [ln.get_label() for ln in fig.axes[2].get_lines()] == [
        "rear wheel, measured", f"rear wheel, predicted ({c['rear_predicted_rms_mm']:.1f} mm RMS)",
        f"baseline: the fork delayed, scaled ({c['baseline_delayed_fork_rms_mm']:.1f} mm RMS)"]
    # the baseline drawn is the one checked against: its RMS over the checked samples, by hand here
    drawn = fig.axes[2].get_lines()[2].get_ydata()
    v = rec.valid
    assert np.sqrt(np.mean((drawn[v] - rec.rear[v]) ** 2)) == pytest.approx(c["baseline_delayed_fork_rms_mm"])
    # the verdict in the title, in the checks' own words
    assert fig.get_suptitle().splitlines()[0].endswith(
        "the model describes this ride" if c["passes"] else "the model does not describe this ride")
    assert "red, the front wheel off the ground (bridged, checked); grey, no speed (left out)" in fig.get_suptitle()
    shaded = [p for p in fig.axes[2].patches]
    assert len(shaded) == len(rec.jumps) + len(rec.unaligned) + len(rec.beyond)  # each stretch left out is drawn
    # the speed along the ride: the profile the distance is integrated from, each window's speed
    speed = fig.axes[3]
    assert speed.get_title().startswith(f"Speed along the ride: median {rec.speed['speed_m_per_s']:.2f} m/s")
    assert speed.get_ylabel() == "speed (m/s)" and speed.get_xlim() == pytest.approx((0.0, SECONDS - 1.0 / RATE))
    profile = speed.get_lines()[0]
    assert np.allclose(profile.get_ydata(), rec.speed["speed_at"](rec.t))
    accepted = [v for _, v, _ in rec.speed["windows"] if v is not None]
    labels = [t.get_text() for t in speed.get_legend().get_texts()]
    assert any(f"({len(accepted)}, +-2 standard errors)" in x for x in labels), labels
    assert SPEED * 0.97 < np.median(profile.get_ydata()) < SPEED * 1.03


def test_the_figure_shades_the_stretches_beyond_what_the_bike_could_climb(made):
    """``reconstruction.png`` (``Reconstruction.figure``): a stretch of ``beyond_trail`` written here
    (5.0-6.5 s and its metres on the ride's distance) is shaded in each panel over its x-range, the
    terrain's in metres and the others in seconds, one hatched artist per panel labelled in its legend;
    the made ride's own reconstruction has none (nothing beyond), and then no such artist and no legend
    on the terrain's panel."""
    import dataclasses

    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct
    from mtbmj.ride.reconstruct_envelope import LABEL

    bike, csv, *_ = made
    rec = reconstruct.reconstruct(telemetry.read_travel_csv(csv), str(bike))

    def spans(fig):
        out = []
        for ax in fig.axes:
            mine = [p for p in ax.patches if p.get_label() == LABEL]
            xs = [p.get_patch_transform().transform(p.get_path().vertices)[:, 0] for p in mine]
            legend = ax.get_legend()
            out.append(([(float(x.min()), float(x.max())) for x in xs],
                        [t.get_text() for t in legend.get_texts()] if legend else None))
        return out

    assert rec.beyond == []
    plain = spans(rec.figure())
    assert all(found == [] for found, _ in plain) and plain[0][1] is None
    terrain = rec.figure().axes[0]
    a, b = 5.0, 6.5
    xa, xb = (float(np.interp(s, rec.t, rec.distance)) for s in (a, b))
    stretch = {"start_s": a, "end_s": b, "start_m": round(xa, 2), "end_m": round(xb, 2), "rise_m": 4.0,
               "allowed_m": 3.0, "speed_m_per_s": SPEED}
    fig = dataclasses.replace(rec, beyond=[stretch]).figure()
    got = spans(fig)
    # the terrain's panel keeps its metres: its range and its flights as without the stretch, and one more patch
    assert fig.axes[0].get_xlim() == pytest.approx(terrain.get_xlim()) and terrain.get_xlim()[1] > 2.0 * rec.t[-1]
    assert len(fig.axes[0].patches) == len(terrain.patches) + 1
    assert xb - xa > 5.0  # metres and seconds told apart
    assert got[0][0] == [pytest.approx((round(xa, 2), round(xb, 2)), abs=1e-9)] and LABEL in got[0][1]
    for found, legend in got[1:]:
        assert found == [pytest.approx((a, b), abs=1e-9)] and legend.count(LABEL) == 1


def test_one_end_alone_or_no_alignment_is_refused_in_one_line(made, tmp_path, capsys):
    bike, csv, t, fork_mm, rear_mm, h, wb = made
    alone = tmp_path / "fork.csv"
    alone.write_text("time_s,fork_mm\n" + "\n".join(f"{a:.4f},{b:.1f}" for a, b in zip(t, fork_mm)))
    assert main(["reconstruct", str(alone), "--bike", str(bike), "--out", str(tmp_path / "o")]) == 2
    assert "needs both ends' records" in capsys.readouterr().err
    noise = tmp_path / "noise.csv"
    rng = np.random.default_rng(0)
    noise.write_text("time_s,fork_mm,rear_mm\n" + "\n".join(
        f"{a:.4f},{40 + rng.normal():.1f},{40 + rng.normal():.1f}" for a in t[:8000]))
    assert main(["reconstruct", str(noise), "--bike", str(bike), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "do not align at any lag" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_a_ride_shorter_than_a_window_or_periodic_gives_no_speed(tmp_path):
    """Too short for one window: refused naming the length. A pure sine at both ends (no
    quantisation to break the tie) aligns at every period: no window gives a speed."""
    from mtbmj.ride import reconstruct

    t = np.arange(2000) / RATE
    with pytest.raises(reconstruct.ReconstructError, match="the ride is 2.0 s: a speed needs at least one 5 s window"):
        reconstruct.speed_from_lag(t, np.sin(9 * t), np.sin(9 * t - 1), 1.255)
    t = np.arange(20000) / RATE
    wave = lambda x: np.sin(2 * np.pi * 6.0 * x) + 0.5 * np.sin(2 * np.pi * 12.0 * x)  # noqa: E731 (period 1/6 s)
    with pytest.raises(reconstruct.ReconstructError, match="do not align at any lag"):
        reconstruct.speed_from_lag(t, wave(t), wave(t - 0.2), 1.255)


def first_seconds(record, seconds):
    """``record`` cut to its first ``seconds`` (every per-sample array)."""
    import dataclasses

    n = int(np.searchsorted(record.time_s, record.time_s[0] + seconds))
    cut = {f.name: getattr(record, f.name)[:n] for f in dataclasses.fields(record)
           if isinstance(getattr(record, f.name), np.ndarray) and getattr(record, f.name).shape[:1] == record.time_s.shape}
    return dataclasses.replace(record, **cut)


@pytest.mark.slow
def test_the_compiled_forward_quarter_cars_are_the_python_ones(made, monkeypatch):
    """The forward quarter car (reconstruct_inverse.forward) compiled (mtbmj/ride/quartercar_compiled.py)
    gives the Python loop's numbers within 1e-9 mm (the law's sum in another order): over the ground
    the quarter car's inverse finds on the ride made here (a linear law, a constant leverage ratio) and
    on the shipped ride (a friction state, the SST leverage curve)."""
    from types import SimpleNamespace

    from mtbmj.bike import run, spec as spec_mod
    from mtbmj.cli.telemetry import decoding
    from mtbmj.ride import quartercar_compiled
    from mtbmj.ride.reconstruct_inverse import QuarterCar, forward, ground_under
    from mtbmj.measured import telemetry

    bike, csv, *_ = made
    rides = [(telemetry.read_ride(csv, **decoding(SimpleNamespace(bike=str(bike), fork_max_mm=None, shock_max_mm=None))),
              str(bike)),
             (first_seconds(telemetry.read_ride(telemetry.example_path(), **decoding(SimpleNamespace(
                 bike="sst", fork_max_mm=None, shock_max_mm=None))), 25.0), "sst")]
    for record, name in rides:
        spec = spec_mod.load(name)
        fork_setup, shock_setup = run.setups(spec)
        Mf, mf, Mr, mr = quarter_car_masses(spec)
        tyre = (fork_setup.tire.values(1).rate, fork_setup.tire_radius, fork_setup.gravity)
        front = QuarterCar(Mf, mf, fork_setup.fork, *tyre, fork_setup.travel)
        rear = QuarterCar(Mr, mr, shock_setup.fork, *tyre, shock_setup.travel)
        t, fork = np.asarray(record.time_s, float), np.asarray(record.fork_mm, float) * 1e-3
        sa, lev = math.sin(spec.head_angle), spec.leverage
        ground = ground_under(t, fork * sa, fork, front, lambda w: sa)[0]
        runs = []
        for native in (True, False):
            if not native:
                monkeypatch.setattr(quartercar_compiled, "run", lambda *a, **k: None)
            runs.append((forward(t, ground, front, lambda w: w / sa, lambda w: sa, float(fork[0] * sa), None,
                                 native=(quartercar_compiled.FORK, sa, None)),
                         forward(t, np.interp(t - 0.2, t, ground), rear, lev.stroke, lev.ratio_at, 0.03, None,
                                 native=(quartercar_compiled.LEVERAGE, 0.0, lev))))
            monkeypatch.undo()
        (cf, cr), (pf, pr) = runs
        assert np.max(np.abs(cf - pf)) * 1e3 < 1e-9 and np.max(np.abs(cr - pr)) * 1e3 < 1e-9
        assert np.ptp(cf) > 1e-3 and np.ptp(cr) > 1e-3  # both moved


def test_the_same_ride_as_sst_counts_comes_back(made, tmp_path):
    """The made ride written as a recorder writes it: SST version 3, integer AS5600 counts through the bike
    file's [sensors] calibration (the fork's isosceles triangle, the shock's general one, inverted
    by the law of cosines in tests/test_telemetry_sensors.py, not by the reader): the speed within 3
    % and the rear within 10 % of its travel used, as from the travel CSV."""
    import json

    from mtbmj.bike import spec as spec_mod
    from helpers import write_v3

    bike, csv, t, fork_mm, rear_mm, h, wb = made
    sst = write_v3(tmp_path / "ride.SST", np.clip(fork_mm, 0, None), np.clip(rear_mm, 0, None) / RATIO,
                   spec_mod.load(str(bike)).sensors, RATE)
    out = tmp_path / "rec"
    assert main(["reconstruct", str(sst), "--bike", str(bike), "--out", str(out)]) == 0
    summary = json.loads((out / "reconstruction.json").read_text())
    assert summary["speed_m_per_s"] == pytest.approx(SPEED, rel=0.03)
    assert summary["checks"]["rear_predicted_rms_percent_of_used"] < 10.0


def one_error_line(err):
    lines = [line for line in err.splitlines() if not line.startswith("mtbmj: warning")]
    assert len(lines) == 1 and lines[0].startswith("mtbmj: error: ") and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("seconds", [0.005, 3.0, 6.0])
def test_a_record_too_short_for_a_speed_is_refused_before_any_work(tmp_path, capsys, seconds):
    """Five samples (a traceback from the derivative filter before), 3 s and 6 s (under one 5 s window
    and the slowest lag searched, 1.26 s on this bike): one line naming the file, 'no speed
    estimate', nothing written."""
    csv, *_ = bumps_csv(tmp_path / "short.csv", seconds)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)
    out = tmp_path / "o"
    assert main(["reconstruct", str(csv), "--bike", str(bike), "--out", str(out)]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert line.startswith("mtbmj: error: short.csv: the ride is ") and line.endswith("no speed estimate"), line
    assert not out.exists()


def test_a_lag_at_the_end_of_the_search_gives_no_speed():
    """The rear the front's copy 50 ms later: 25 m/s on a 1.255 m wheelbase, outside the 1-15 m/s
    searched. The best lag searched is the shortest, at the search's end, not a peak: no speed (it
    gave 15.0 m/s, the search's edge, before)."""
    from mtbmj.ride import reconstruct

    t = np.arange(20000) / RATE
    rng = np.random.default_rng(1)
    x = np.convolve(rng.normal(size=t.size + 100), np.hanning(30), mode="same")
    front = x[100:]
    rear = np.interp(t - 0.05, t, front)
    with pytest.raises(reconstruct.ReconstructError, match="do not align at any lag"):
        reconstruct.speed_from_lag(t, front, rear, 1.255)
    # the same record 0.2 s apart (6.3 m/s): found, so the refusal above is the edge's, not the record's
    rear = np.interp(t - 0.2, t, front)
    assert reconstruct.speed_from_lag(t, front, rear, 1.255)["speed_m_per_s"] == pytest.approx(1.255 / 0.2, rel=0.01)


def test_a_standing_window_gives_no_speed():
    """Both ends moving less than 1 mm (a bike standing; their filtered series hold the filters'
    tails) align perfectly at 0.2 s, but that is not the terrain: with the travel given, no speed;
    the same window scaled to 10 mm gives one."""
    from mtbmj.ride import reconstruct

    t = np.arange(12000) / RATE
    rng = np.random.default_rng(2)
    x = np.convolve(rng.normal(size=t.size), np.hanning(40), mode="same")
    x = 0.4 * x / np.ptp(x)  # 0.4 mm of motion
    front, rear = x, np.interp(t - 0.2, t, x)
    assert reconstruct.speed_from_lag(t, front, rear, 1.255)["speed_m_per_s"] == pytest.approx(6.275, rel=0.01)
    with pytest.raises(reconstruct.ReconstructError, match=r"of (\d+) windows: \1 standing"):
        reconstruct.speed_from_lag(t, front, rear, 1.255, travel=(front, rear))
    big = reconstruct.speed_from_lag(t, 25 * front, 25 * rear, 1.255, travel=(25 * front, 25 * rear))
    assert big["speed_m_per_s"] == pytest.approx(6.275, rel=0.01)


@pytest.mark.shared_data("sst_v2", "00098.SST")
def test_a_v2_trail_ride_without_a_speed_is_refused_in_one_line(tmp_path, capsys):
    """00098.SST of the shared version-2 rides (a trail section): no 5 s window whose two ends align
    at any lag the search allows, and a stretch where the bike stood: one line, 'no speed',
    nothing written."""
    from conftest import SHARED_DATA

    sst = Path(SHARED_DATA) / "sst_v2" / "00098.SST"
    out = tmp_path / "o"
    assert main(["reconstruct", str(sst), "--bike", "sst", "--out", str(out)]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert line.startswith("mtbmj: error: 00098.SST: ") and "no speed" in line and "empty" not in line, line
    assert not out.exists()


@pytest.mark.slow  # a reconstruction through the whole bike: 0.5-2 min
@pytest.mark.shared_data("sst_v2", "00094.SST")
def test_a_v2_trail_ride_with_standing_stretches_is_read_and_judged(tmp_path, capsys):
    """00094.SST of the shared version-2 rides (a trail section, 5 kHz): stretches where the bike
    stood. It ended in 'run diverged (Mean of empty slice)' after minutes, then in 'no speed' (no
    window aligned while its coarse 5 kHz steps were differentiated raw). Low-passed first (issue
    51), a few windows align, and the checks say in words that the model does not describe this ride
    (its rear predicted worse than a naive baseline). Its bike stood unweighted mid-ride, 31.2-54.7 s
    (both ends fully out: the rider off it), which the whole bike with its rider on cannot ride (it
    diverged at 57.7-59.7 s, after the stand, as soon as the terrain changed a little): the longest part
    ridden (54.7 s to the end) is reconstructed, and the line and the summary say so."""
    import json

    from conftest import SHARED_DATA

    sst = Path(SHARED_DATA) / "sst_v2" / "00094.SST"
    out = tmp_path / "o"
    assert main(["reconstruct", str(sst), "--bike", "sst", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "the model does not describe this ride" in captured.out and "empty" not in captured.err + captured.out
    summary = json.loads((out / "reconstruction.json").read_text())
    assert summary["checks"]["passes"] is False
    assert summary["whole_bike"]["diverged_s"] is None
    assert summary["record_part_s"] == pytest.approx([54.7, 121.7], abs=0.1)
    assert [pytest.approx(a, abs=0.1) for a in summary["stood_unweighted_s"][0]] == [31.2, 54.7]
    assert captured.out.startswith("00094.SST (the record's 54.7-121.7 s, its times from there: the bike stood "
                                   "unweighted at 31.2-54.7 s) through sst: "), captured.out
    assert summary["duration_s"] == pytest.approx(67.0, abs=0.1)


def _record(t, fork, rear):
    from mtbmj.measured.telemetry import TelemetryRecord

    return TelemetryRecord("made.SST", 3, 1000.0, 0, t, fork, None, rear)


def test_a_bike_standing_unweighted_mid_ride_is_cut_out():
    """reconstruct.ridden_part on records written here (1 kHz): riding 0-20 s, standing unweighted
    (both ends at 0.0-0.3 mm) 20-35 s, riding 35-80 s, standing again to the end: the longer part
    ridden, 35 s to the end, its times from 0, the stand named (the end's stand is the rider getting
    off, kept); riding with only the ends standing, or a 1 s flight (both ends fully out) mid-ride, or a
    stand of the fork alone: the record itself."""
    from mtbmj.ride.reconstruct import ridden_part

    t = np.arange(0.0, 90.0, 1e-3)
    rng = np.random.default_rng(5)
    ride = lambda: 30.0 + 10.0 * rng.standard_normal(t.size)  # noqa: E731
    fork, rear = ride(), ride()
    stand = ((t >= 20.0) & (t < 35.0)) | (t >= 80.0)
    fork[stand], rear[stand] = 0.3 * rng.random(int(stand.sum())), 0.0
    part, span, stands = ridden_part(_record(t, fork, rear))
    assert span == pytest.approx((35.0, 90.0 - 1e-3), abs=2e-3)
    assert stands == [pytest.approx((20.0, 35.0), abs=2e-3)]
    assert part.time_s[0] == 0.0 and part.time_s.size == np.count_nonzero(t >= 35.0)
    assert np.array_equal(part.fork_mm, fork[t >= 35.0]) and np.array_equal(part.rear_mm, rear[t >= 35.0])
    fork, rear = ride(), ride()
    ends = (t < 2.0) | (t > 88.0)
    fork[ends], rear[ends] = 0.0, 0.0
    flight = (t >= 40.0) & (t < 41.0)
    fork[flight], rear[flight] = 0.0, 0.0
    fork_only = (t >= 50.0) & (t < 60.0)
    fork[fork_only] = 0.0
    record = _record(t, fork, rear)
    assert ridden_part(record) == (record, None, [])


def test_speed_windows_that_leave_nothing_to_check_are_refused(tmp_path, capsys, monkeypatch):
    """A speed search whose windows leave no sample to check (here one that returns a speed but
    marks every window as without one, so every stretch is left out): no speed estimate that can be
    checked, one line, nothing written, and no mean taken of no samples (numpy's warnings are errors
    here; it ended as 'run diverged (Mean of empty slice)')."""
    import warnings

    from mtbmj.ride import reconstruct

    csv, t, *_ = bumps_csv(tmp_path / "ride.csv", 12.0)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)

    def nothing_checkable(t, first, second, wheelbase, **kw):
        windows = [(0.0, None, 0.1), (5.0, None, 0.1), (10.0, None, 0.1)]
        return {"speed_m_per_s": 6.0, "lag_s": wheelbase / 6.0, "windows": windows, "sources": [None] * 3,
                "speed_at": lambda time: np.full(np.shape(time), 6.0)}

    monkeypatch.setattr(reconstruct, "speed_from_either", nothing_checkable)
    out = tmp_path / "o"
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        code = main(["reconstruct", str(csv), "--bike", str(bike), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    line = one_error_line(err)
    assert "ride.csv: no speed estimate that can be checked" in line, line
    assert not out.exists()
    # and a Reconstruction with no sample checked reports its checks without a mean of nothing
    rec = reconstruct.Reconstruction("r", "b", t, {}, t, t, np.zeros(t.size, bool), t, t, t, t, 125.0, [])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert rec.checks()["samples_checked_percent"] == 0.0


def test_a_flight_is_bridged_from_a_drops_edge_or_by_the_chord():
    """reconstruct_inverse.bridge on grounds written here (1 kHz): a 0.2 s flight off a 0.3 m drop
    (the wheel's path a parabola from the edge down to the landing) gets the landing's level from the
    take-off on; a 0.2 s flight that lands 0.1 m higher, one that lands 0.1 m lower (a rock's back,
    within EDGE_DROP_M) and a 0.05 s hop that lands 0.3 m lower get the chord; nothing is put above
    the path the wheel flew."""
    from mtbmj.ride.reconstruct_inverse import EDGE_DROP_M, EDGE_FLIGHT_S, bridge

    dt = 1e-3
    n = 1000

    def flight(a, b, before, after):
        """The ground found: level ``before`` up to ``a``, the wheel's path (a parabola through both
        ends, 0.05 m above the chord at its middle) over ``a..b``, level ``after`` past it."""
        g = np.full(n, float(before))
        g[b:] = after
        s = np.linspace(0.0, 1.0, b - a + 2)  # from the last sample on the ground to the first back on it
        g[a - 1:b + 1] = before + (after - before) * s + 0.2 * s * (1.0 - s)
        off = np.zeros(n, bool)
        off[a:b] = True
        return g, off

    assert EDGE_FLIGHT_S <= 0.2 and 0.1 < EDGE_DROP_M < 0.3
    g, off = flight(300, 500, 0.0, -0.3)  # a drop's flight: the landing's level from the edge on
    out, air = bridge(g, off, dt)
    assert np.all(out <= g + 1e-12) and air[300:500].all() and not air[:300].any() and not air[500:].any()
    assert out[299] == 0.0 and np.all(out[300:] == -0.3)
    out, _ = bridge(g, off, dt, edges=False)  # the quarter car's: the chord
    assert np.allclose(out[299:501], np.linspace(0.0, -0.3, 202))
    for after, (a, b) in ((0.1, (300, 500)), (-0.1, (300, 500)), (-0.3, (300, 350))):
        g, off = flight(a, b, 0.0, after)  # landing higher, a little lower, or a short hop: the chord
        out, _ = bridge(g, off, dt)
        assert np.allclose(out[a - 1:b + 1], np.linspace(0.0, after, b - a + 2)) and np.all(out <= g + 1e-12)


def test_a_flight_whose_force_only_flickers_back_is_one_flight():
    """reconstruct_inverse.unloaded on tyre forces written here (1 kHz, 400 N at rest): a wheel off a
    drop whose computed force reads zero for 10 ms, then flickers at 0-56 N (mean about 20 N, below 10 %
    of the static load) for 90 ms, then reads zero again for 90 ms is one flight of 0.19 s, from where
    the force first fell below 40 N; two zero stretches with a real contact between (300 N for 90 ms)
    stay two hops of their own, each keeping its start."""
    from mtbmj.ride.reconstruct_inverse import unloaded

    dt, static = 1e-3, 400.0
    rng = np.random.default_rng(3)
    tyre = np.full(3000, static)
    tyre[795:800] = 30.0  # the last of the load as the wheel leaves the edge
    tyre[800:810] = -20.0
    tyre[810:900] = rng.uniform(0.0, 56.0, 90)  # the inverse's noise about nothing
    tyre[900:990] = -5.0
    tyre[990:1010] = 1500.0  # the landing
    tyre[2000:2010] = -20.0
    tyre[2010:2100] = 300.0  # on the ground between
    tyre[2100:2190] = -5.0
    off = unloaded(tyre, static, dt)
    assert off[795:990].all() and not off[:795].any() and not off[990:2000].any()
    assert off[2000:2010].all() and not off[2010:2100].any() and off[2100:2190].all() and not off[2190:].any()


def test_a_long_flights_take_off_is_where_the_tyre_unloaded():
    """reconstruct_inverse.unloaded on tyre forces written here (1 kHz, 400 N at rest): a 0.2 s flight
    whose force had hovered at 20-35 N (below 10 % of the static load) for 80 ms before it read zero
    starts where it first fell below 40 N; a 0.05 s hop after the same hovering keeps its start (its
    ground gets the chord, whose start a hop does not need moved); a force that hovers low but never
    reads zero is no flight; the end of each flight is where the force returns."""
    from mtbmj.ride.reconstruct_inverse import TAKE_OFF_SHARE, unloaded

    dt, static = 1e-3, 400.0
    assert TAKE_OFF_SHARE == pytest.approx(0.1)
    tyre = np.full(2000, static)
    tyre[220:300] = 20.0 + 15.0 * np.sin(np.arange(80) / 5.0) ** 2  # 20-35 N: the wheel following down
    tyre[300:500] = -1.0  # the long flight
    tyre[500:520] = 900.0  # its landing
    tyre[1120:1200] = 30.0
    tyre[1200:1250] = 0.0  # the short hop
    tyre[1600:1700] = 25.0  # low, never zero
    off = unloaded(tyre, static, dt)
    assert off[220:500].all() and not off[:220].any() and not off[500:1200].any()
    assert off[1200:1250].all() and not off[1250:].any()


def test_the_rear_is_checked_band_by_band_against_series_written_here():
    """Reconstruction.checks()["bands"] on series written here (200 Hz, 200 s), each band's part of the
    rear made by hand: a 0.2 Hz swing (the rider's slow load), a 1.2 Hz one (the body) and noise
    between 3 and 8 Hz (the wheels). A prediction that has the slow and body parts right and the wheels'
    noise of another draw is described in those two bands and not in the wheels' (its correlation
    there near zero); the same prediction with the body's part reversed is not described in the body's
    band (correlation about -1); the line names each band's verdict."""
    from scipy.signal import butter, sosfiltfilt

    from mtbmj.ride import reconstruct

    rng = np.random.default_rng(5)
    fs, n = 200.0, 40000
    t = np.arange(n) / fs
    slow, body = 8.0 * np.sin(2 * math.pi * 0.2 * t), 6.0 * np.sin(2 * math.pi * 1.2 * t + 0.4)
    sos = butter(4, (3.0, 8.0), btype="bandpass", fs=fs, output="sos")
    wheels = lambda: 40.0 * sosfiltfilt(sos, rng.standard_normal(n))  # noqa: E731
    rear = 50.0 + slow + body + wheels()
    fork_delayed = 60.0 + wheels()  # a baseline that shares nothing with the rear but its mean
    valid = np.ones(n, bool)
    valid[:2000] = valid[-2000:] = False  # the filters' ends are not what is checked

    def bands(predicted):
        rec = reconstruct.Reconstruction("r", "b", t, {"windows": []}, t, t, valid, rear, rear, rear, predicted, 150.0,
                                         [], fork_delayed=fork_delayed)
        return {tuple(b["band_Hz"]): b for b in rec.checks()["bands"]}

    right = bands(50.0 + slow + body + wheels())
    assert set(right) == {(0.05, 0.5), (0.5, 2.0), (2.0, 10.0)}
    assert right[(0.05, 0.5)]["described"] and right[(0.5, 2.0)]["described"]
    assert right[(0.5, 2.0)]["predicted_correlation"] > 0.99
    assert not right[(2.0, 10.0)]["described"]
    assert abs(right[(2.0, 10.0)]["predicted_correlation"]) < 0.1
    # the wheels' band holds the noise the rear has there (its RMS about 40 * the filter's share)
    assert right[(2.0, 10.0)]["record_rms_mm"] > 3.0 * right[(0.5, 2.0)]["predicted_error_rms_mm"]
    wrong = bands(50.0 + slow - body + wheels())
    assert not wrong[(0.5, 2.0)]["described"] and wrong[(0.5, 2.0)]["predicted_correlation"] < -0.95
    assert wrong[(0.05, 0.5)]["described"]
    rec = reconstruct.Reconstruction("r", "b", t, {"windows": [(0.0, 5.0, 0.9)], "speed_m_per_s": 5.0, "lag_s": 0.24},
                                     t, t, valid, rear, rear, rear, 50.0 + slow + body + wheels(), 150.0, [],
                                     fork_delayed=fork_delayed)
    assert "the rear by band (correlation, described): 0.05-0.5 Hz 1.00 yes, 0.5-2 Hz 1.00 yes, 2-10 Hz" in rec.line()


def _reconstructed_with(record, bike, past_m=None, monkeypatch=None, spectral=True):
    """(the reconstruction, its warnings' texts), the stops' allowance ``past_m`` (m) where given
    (``spectral``: ``reconstruct``'s)."""
    import warnings

    from mtbmj.ride import reconstruct, reconstruct_inverse

    if past_m is not None:
        monkeypatch.setattr(reconstruct_inverse, "PAST_TRAVEL_M", past_m)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = reconstruct.reconstruct(record, bike, spectral=spectral)
    return result, [str(w.message) for w in caught if "passes its travel" in str(w.message)]


def test_a_fork_record_past_its_travel_is_read_within_its_stops(made, monkeypatch):
    """The made ride with the fork's record scaled (a calibration's error) so it reads 141 mm of its
    130: the whole ride is found, the fork read at most 2 mm into its stop (controllers/stops: a hard
    landing passes the travel by about 2 mm), said in one warning and in the summary; the ride as made
    (58 mm at most) is read as it is, no warning, nothing cut."""
    import dataclasses

    from mtbmj.measured import telemetry

    path, csv, t, fork, rear, h, wb = made
    record = telemetry.read_ride(csv)
    result, said = _reconstructed_with(record, str(path))
    assert said == [] and result.cut == [] and "read_within_stops" not in result.summary()
    scaled = dataclasses.replace(record, fork_mm=record.fork_mm * 141.0 / float(np.max(record.fork_mm)))
    result, said = _reconstructed_with(scaled, str(path))
    assert result.diverged_s is None
    [cut] = result.summary()["read_within_stops"]
    assert cut["end"] == "fork" and cut["deepest_mm"] == pytest.approx(141.0, abs=0.05)
    assert cut["read_at_most_mm"] == pytest.approx(132.0) and 0.0 < cut["seconds"] < 1.0
    assert float(np.max(result.front)) == pytest.approx(132.0)
    assert len(said) == 1 and said[0].startswith("ride.csv: the fork's record passes its travel (130 mm) by 11.0 mm")


@pytest.mark.shared_data("sst_v2", "00100.SST")
def test_a_shared_ride_past_its_fork_s_travel_is_ridden_to_its_end(monkeypatch):
    """00100.SST (a version-2 trail section, its placeholder calibration): the fork reads 191 mm of
    180 for 18 ms at 15.84 s. Read so, the terrain found there asks the whole bike to press its fork
    11 mm into the stop's stiffening, and the free ride over it diverged at 15.88 s (what
    docs/measured.md showed); read at most 2 mm past its travel it rides the whole ride. (Read so with
    each drop's level kept, mtbmj/ride/reconstruct_flight.py, it rides through as well: the unread
    record is checked with no level kept and the quarter car's hard-stop impulse given to the whole bike,
    as the divergence was found, the rear meeting all the ground a wheelbase later; with the whole bike's
    own, reconstruct_flight.stop_kicks, it diverges at 16.03 s; with the found ground's spectral share met
    at once, mtbmj/ride/reconstruct_share.py, at 19.16 s.)"""
    from conftest import SHARED_DATA

    from mtbmj.bike.spec import load, ride_decoding
    from mtbmj.measured import telemetry

    record = telemetry.read_ride(Path(SHARED_DATA) / "sst_v2" / "00100.SST", **ride_decoding(load("sst")))
    result, said = _reconstructed_with(record, "sst")
    assert result.diverged_s is None and len(said) == 1 and "read at 182 mm" in said[0]
    assert result.valid.mean() > 0.1  # the checks count samples past 15.9 s
    from mtbmj.ride import reconstruct_flight

    monkeypatch.setattr(reconstruct_flight, "edge_flights", lambda found, air, dt: [])
    monkeypatch.setattr(reconstruct_flight, "stop_kicks", lambda first, now, ground, air, dt, mass: now)
    unread, said = _reconstructed_with(record, "sst", past_m=1.0, monkeypatch=monkeypatch, spectral=False)
    assert said == [] and unread.diverged_s == pytest.approx(15.88, abs=0.05)

"""Real ride telemetry (SST files) and the rider's metrics: decoding the shipped recording against
the format's own numbers, the metrics on signals with closed-form answers, malformed files as one
line with exit status 2, and the measured-vs-simulated comparison."""
import json
import struct
from pathlib import Path

import numpy as np
import pytest

from mtbmj import cli
from mtbmj.cli import telemetry as cli_telemetry
from mtbmj.measured import metrics as ride_metrics
from mtbmj.measured import telemetry
from mtbmj.errors import MtbmjError

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "sst"
SHIPPED = telemetry.example_path()


def run_cli(argv):
    """``mtbmj`` main, with the telemetry sub-command added if cli.py does not wire it yet."""
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    if "telemetry" in sub.choices:
        return cli.main(argv)
    original = cli.build_parser

    def build():
        p = original()
        cli_telemetry.add_parser(next(a for a in p._actions if a.__class__.__name__ == "_SubParsersAction"))
        return p

    cli.build_parser = build
    try:
        return cli.main(argv)
    finally:
        cli.build_parser = original


@pytest.fixture(scope="module")
def record():
    return telemetry.read_sst(SHIPPED)


# --- decoding ---------------------------------------------------------------------------------

def test_shipped_file_decodes(record):
    samples = (SHIPPED.stat().st_size - 16) // 4
    assert record.version == 3 and record.sample_rate_Hz == 1000
    assert record.time_s.size == samples == 76399
    assert record.duration_s == pytest.approx(samples / 1000)
    assert record.time_s[1] - record.time_s[0] == pytest.approx(1e-3)
    assert 0 <= record.fork_mm.min() and record.fork_mm.max() <= 180
    assert record.fork_mm.max() > 100  # a real ride uses the travel
    assert 0 <= record.shock_mm.min() and record.shock_mm.max() <= 65
    assert 0 <= record.rear_mm.min() and record.rear_mm.max() <= record.rear_max_mm
    assert record.timestamp > 1.6e9  # 2023
    assert (SHIPPED.parent / "LICENSE").read_text().startswith("MIT License")


@pytest.mark.skipif(not (SHARED / "00642.SST").exists(), reason="../shared/data/sst not present")
def test_readme_check_00642():
    """The data README: 00642.SST decodes to 103.3 s at 1 kHz, front travel 0 .. 155 mm."""
    r = telemetry.read_sst(SHARED / "00642.SST")
    assert r.duration_s == pytest.approx(103.3, abs=0.05)
    assert r.fork_mm.min() == pytest.approx(0, abs=0.01)
    assert r.fork_mm.max() == pytest.approx(155, abs=0.5)


def test_calibrations():
    front, rear = telemetry.IsoscelesTriangle(), telemetry.Triangle()
    assert front.travel_mm([0])[0] == pytest.approx(0, abs=1e-9)
    assert front.travel_mm([4090])[0] == pytest.approx(0, abs=1e-9)  # wrapped just below zero
    assert np.all(np.diff(front.travel_mm(np.arange(0, 800))) > 0)
    assert rear.stroke_mm([0])[0] == pytest.approx(0, abs=1e-9)
    lev = telemetry.LeverageCurve()
    w = np.linspace(0, 170, 50)
    assert lev.wheel_travel_mm(lev.stroke_mm(w)) == pytest.approx(w, abs=1e-9)
    # The bike: about 174 mm of rear wheel travel for the 65 mm stroke (leverage 3.18 .. 2.37).
    assert lev.wheel_travel_mm(65.0) == pytest.approx(174.5, abs=1.0)
    assert lev.stroke_mm(1.0) == pytest.approx(1 / 3.18, rel=0.01)


# --- metrics with known answers ---------------------------------------------------------------

def sine(amplitude=60.0, mean=90.0, freq=2.0, seconds=10.0, rate=1000.0):
    t = np.arange(int(seconds * rate)) / rate
    return t, mean + amplitude * np.sin(2 * np.pi * freq * t)


def test_travel_histogram_of_a_sine():
    """Time share in a band of a sine is the arcsine law: (asin(b) - asin(a)) / pi."""
    t, x = sine(amplitude=60, mean=90, rate=20000)  # fine sampling: a crossing is off by < 1/20000 s
    h = ride_metrics.travel_histogram(x, 180, bin_percent=5)
    assert h.edges_percent[0] == 0 and h.edges_percent[-1] == 100 and h.time_percent.size == 20
    assert h.time_percent.sum() == pytest.approx(100)
    lo, hi = h.edges_percent[:-1] * 1.8, h.edges_percent[1:] * 1.8
    u = lambda mm: np.arcsin(np.clip((mm - 90) / 60, -1, 1))
    expected = (u(hi) - u(lo)) / np.pi * 100
    assert h.time_percent == pytest.approx(expected, abs=0.05)
    assert h.time_percent[:3].sum() == 0 and h.time_percent[-3:].sum() == 0  # 30..150 mm = 17..83 % only
    assert h.peak_bin_percent in ((15.0, 20.0), (80.0, 85.0))  # the sine lingers at its extremes


def test_velocity_of_a_sine_and_the_split():
    amplitude, freq = 60.0, 2.0
    t, x = sine(amplitude, 90, freq)
    v = ride_metrics.velocity(t, x)
    peak = amplitude * 2 * np.pi * freq  # 754 mm/s
    assert v == pytest.approx(peak * np.cos(2 * np.pi * freq * t), abs=0.005 * peak)
    h = ride_metrics.velocity_histogram(v, threshold_mm_per_s=100)
    high = 2 / np.pi * np.arccos(100 / peak) * 100  # % of time with |v| > 100
    assert h.high_speed_percent == pytest.approx(high, abs=0.3)
    assert h.split_percent["high_speed_compression"] == pytest.approx(high / 2, abs=0.3)
    assert h.split_percent["high_speed_rebound"] == pytest.approx(high / 2, abs=0.3)
    assert sum(h.split_percent.values()) == pytest.approx(100)
    assert h.time_percent.sum() == pytest.approx(100)
    assert h.compression["max_mm_per_s"] == pytest.approx(peak, rel=0.01)
    assert h.compression["mean_mm_per_s"] == pytest.approx(2 / np.pi * peak, rel=0.01)
    assert h.rebound["max_mm_per_s"] == pytest.approx(-peak, rel=0.01)


def test_velocity_smooths_encoder_steps():
    """One encoder count (~0.2 mm) per sample would read as 200 mm/s by differences."""
    t, x = sine(amplitude=20, mean=60, freq=1.0)
    quantised = np.round(x / 0.2) * 0.2
    v = ride_metrics.velocity(t, quantised)
    exact = 20 * 2 * np.pi * np.cos(2 * np.pi * t)
    assert np.max(np.abs(np.diff(quantised) * 1000 - exact[1:])) > 100
    assert np.max(np.abs(v - exact)) < 10


def test_bottom_outs_counts_distinct_events():
    t = np.arange(20000) / 1000.0
    x = np.full(t.size, 50.0)
    for k, centre in enumerate((2, 6, 10, 14)):  # four hits, each with chatter at the end stop
        hit = np.abs(t - centre) < 0.3
        x[hit] = 180 - 130 * np.abs(t[hit] - centre) / 0.3
        chatter = np.abs(t - centre) < 0.02
        x[chatter] = 179 - 3.0 * (np.arange(chatter.sum()) % 2)  # 179, 176, 179 ...
    near = np.abs(t - 18) < 0.3
    x[near] = 170 - 120 * np.abs(t[near] - 18) / 0.3  # 10 mm short of the end: not a bottom-out
    assert ride_metrics.bottom_outs(x, 180, margin_mm=3) == 4
    assert ride_metrics.bottom_outs(x, 180, margin_mm=11) == 5
    assert ride_metrics.bottom_outs(x, 180, margin_mm=3, release_mm=0) > 4  # without hysteresis: chatter


def test_airtime_rule():
    rate = 1000
    t = np.arange(10 * rate) / rate
    x = np.full(t.size, 50.0)  # riding at 28 % sag
    x[: rate] = 0.0  # parked at the start: fully extended, not airtime
    x[3000:3400] = 0.0  # a 0.4 s jump ...
    x[3400:3500] = np.linspace(0, 120, 100)  # ... and its landing
    x[6000:6020] = 0.0  # a 20 ms top-out on rebound: not airtime
    x[8000:8300] = 0.0  # extended 0.3 s but no landing follows (a gentle unweighting)
    air = ride_metrics.airtime(x, 180, t)
    assert air.count == 1
    assert air.periods_s[0] == pytest.approx((3.0, 3.4), abs=0.01)  # until the landing passes 3 % of travel
    assert air.total_s == pytest.approx(0.4, abs=0.01)
    # With a rear sensor the bike is airborne only while both ends are extended.
    rear = np.full(t.size, 40.0)
    rear[3000:3200] = 0.0
    rear[3200:3400] = 40.0
    both = ride_metrics.airtime(x, 180, t, rear, 150)
    assert both.count == 0  # rear loaded for the last 0.2 s: no landing after the shared 0.2 s
    summary = ride_metrics.summarize(t, x, 180)
    json.dumps(summary)
    assert summary["airtime"]["count"] == 1 and summary["bottom_outs"]["count"] == 0
    assert summary["histograms_exclude_airtime"] is True


def test_metrics_reject_bad_signals():
    with pytest.raises(MtbmjError, match="uniformly"):
        ride_metrics.velocity([0, 1, 3, 4, 5, 6, 7, 8], np.zeros(8))
    with pytest.raises(MtbmjError, match="not finite"):
        ride_metrics.travel_histogram([1.0, np.nan], 180)
    with pytest.raises(MtbmjError, match="travel_max_mm"):
        ride_metrics.travel_histogram([1.0], 0)


def test_shipped_metrics(record):
    m = record.metrics()
    json.dumps(m)
    fork = m["fork"]
    assert fork["travel_histogram"]["peak_bin_percent"] == [25.0, 30.0]
    assert 20 < fork["velocity"]["high_speed_percent"] < 45
    assert fork["bottom_outs"]["count"] == 0  # 120 mm used of 180
    assert fork["airtime"]["count"] == 3
    assert fork["airtime"]["total_s"] == pytest.approx(0.852, abs=0.01)
    assert m["rear"]["travel_histogram"]["peak_bin_percent"] == [25.0, 30.0]


# --- malformed files --------------------------------------------------------------------------

def sst_bytes(magic=b"SST", version=3, rate=1000, records=((100, 50),) * 10, tail=b""):
    head = struct.pack("<3sBHHq", magic, version, rate, 0, 1_690_000_000)
    return head + b"".join(struct.pack("<HH", a, b) for a, b in records) + tail


@pytest.mark.parametrize("content, cause", [
    (sst_bytes(magic=b"PNG"), "not an SST file"),
    (b"SST\x03\xe8\x03", "truncated header (6 of 16 bytes)"),
    (sst_bytes(version=4), "unknown SST version 4"),
    (sst_bytes(records=((0xFFFF, 0xFFFF),) * 5), "both sensors are marked absent"),
    (sst_bytes(records=((1, 1),)), "truncated"),
    (sst_bytes(rate=0), "sample rate is 0"),
    (sst_bytes(records=((1, 1), (5000, 1), (1, 1))), "fork count 5000 at sample 1"),
])
def test_malformed_files_are_one_line(tmp_path, capsys, content, cause):
    path = tmp_path / "ride.SST"
    path.write_bytes(content)
    with pytest.raises(telemetry.TelemetryError) as info:
        telemetry.read_sst(path)
    assert str(path) in str(info.value) and cause in str(info.value)
    assert run_cli(["telemetry", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and cause in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_absent_sensor_and_partial_record(tmp_path):
    rows = [(0xFFFF, 20)] + [(0xFFFF, 20 + i % 7) for i in range(2000)]
    path = tmp_path / "rear_only.SST"
    path.write_bytes(sst_bytes(records=rows, tail=b"\x01\x02"))  # a partial record is ignored
    r = telemetry.read_sst(path)
    assert r.fork_mm is None and r.rear_mm is not None and r.time_s.size == 2001
    m = r.metrics()
    assert "fork" not in m and "rear" in m
    assert run_cli(["telemetry", str(path), "--out", str(tmp_path / "out")]) == 0
    assert run_cli(["telemetry", str(tmp_path / "missing.SST"), "--out", str(tmp_path / "o2")]) == 2


# --- the comparison -------------------------------------------------------------------------------

def test_compare_with_a_drop_run(tmp_path, capsys):
    import mtbmj

    run_dir = tmp_path / "s1"
    mtbmj.run_drop("S1", duration=0.4).write(run_dir)
    out = tmp_path / "tel"
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(run_dir), "--out", str(out)]) == 0
    line = capsys.readouterr().out
    assert "00649.SST" in line and "compared 1 run" in line
    png = (out / "telemetry.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 20000
    summary = json.loads((out / "telemetry.json").read_text())
    measured, (sim,) = summary["measured"], summary["simulated"]
    assert measured["file"] == "00649.SST" and sim["name"].startswith("S1")
    # Same axes: the same travel bins in % and the same velocity bins for measured and simulated.
    assert sim["fork"]["travel_histogram"]["bin_edges_percent"] == measured["fork"]["travel_histogram"]["bin_edges_percent"]
    assert sim["fork"]["velocity"]["bin_edges_mm_per_s"] == measured["fork"]["velocity"]["bin_edges_mm_per_s"]
    assert sum(sim["fork"]["travel_histogram"]["time_percent"]) == pytest.approx(100)
    assert sim["fork"]["travel_max_mm"] == 120.0  # from the run's config.toml
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(tmp_path / "nothing"), "--out", str(tmp_path / "x")]) == 2
    assert "not a run directory" in capsys.readouterr().err


def test_compare_given_a_file_or_another_command_s_folder_says_what_it_takes(tmp_path, capsys):
    """--compare RUN/timeseries.csv names the run's folder to give; --compare a folder another
    command wrote (a telemetry, a fit) names that command (it said "no timeseries.csv (write one
    with ... --out TEL)", which would have overwritten it); a run's folder is still taken."""
    import mtbmj

    run_dir = tmp_path / "s1"
    mtbmj.run_drop("S1", duration=0.4).write(run_dir)
    capsys.readouterr()  # the drop's "compiling ..." notice where numba's cache is cold (a fresh clone) is not the CLI's
    out = tmp_path / "tel"
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(run_dir / "timeseries.csv"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"a file, not a run directory (give the folder that holds it: --compare {run_dir})" \
        in err and not out.exists()
    stray = tmp_path / "notes.csv"
    stray.write_text("time_s,fork_mm\n0,1\n")
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(stray), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "a file, not a run directory" in err and "give the folder" not in err
    assert run_cli(["telemetry", str(SHIPPED), "--out", str(tmp_path / "ride")]) == 0
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(tmp_path / "ride"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a folder of mtbmj telemetry, not a run" in err and not out.exists()
    empty = tmp_path / "empty"
    empty.mkdir()
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(empty), "--out", str(out)]) == 2
    assert "no timeseries.csv" in capsys.readouterr().err
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(run_dir), "--out", str(out)]) == 0
    capsys.readouterr()
    # one run twice (by two names of one folder): refused as mtbmj compare refuses it; it was drawn twice
    again = f"{run_dir}/../s1"
    assert run_cli(["telemetry", str(SHIPPED), "--compare", str(run_dir), str(again), "--out", str(tmp_path / "t2")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--compare {again}: given twice (as {run_dir})" in err
    assert not (tmp_path / "t2").exists()


def test_comparison_figure_labels_each_travel_and_shows_every_tail(record):
    """A simulated run faster than the ride (a 120 mm fork, random amplitude) against the shipped
    ride (a 180 mm fork): each histogram is in % of its own travel and says so, the velocity axis
    reaches the simulated tails, and the split's abbreviations are defined."""
    from mtbmj.ride import comparison

    rng = np.random.default_rng(12)
    amplitude, freq = rng.uniform(30, 50), rng.uniform(5, 8)
    t = np.arange(0, 4, 0.001)
    fork = 50 + amplitude * np.sin(2 * np.pi * freq * t)
    peak_v = 2 * np.pi * freq * amplitude
    run = {"name": "fast", "dir": "fast", "time_s": t, "fork_mm": fork,
           "velocity_mm_per_s": np.gradient(fork, t), "travel_max_mm": 120.0}
    summary = comparison.compare(record, [run]).summary
    assert summary["simulated"][0]["fork"]["travel_max_mm"] == 120.0
    assert set(summary["abbreviations"]) == {"HSC", "LSC", "LSR", "HSR"}
    fig = comparison.figure(summary)
    ax_t, ax_v = fig.axes[0], fig.axes[1]
    labels = [text.get_text() for text in ax_t.get_legend().get_texts()]
    assert any("% of 120 mm" in s for s in labels)
    assert any(f"% of {record.fork_max_mm:.0f} mm" in s for s in labels)
    assert "own travel" in ax_t.get_xlabel()
    low, high = ax_v.get_xlim()
    assert high >= peak_v * 0.98 and low <= -peak_v * 0.98
    assert "HSC" in ax_v.get_legend().get_title().get_text()


def test_defaults_match_the_shipped_setup_notes():
    """The reader's calibrations, strokes and leverage curve are those of the recording's own setup
    notes (``mtbmj/data/sst/notes.txt``, shipped with the ride), parsed here from its JSON lines."""
    notes = SHIPPED.parent / "notes.txt"
    records = [json.loads(line) for line in notes.read_text().splitlines() if line.startswith(("{", "[{"))]
    calibrations = {r["id"]: r for r in records if "inputs" in r}
    linkage = next(r for r in records if "front_stroke" in r)
    front, rear = telemetry.IsoscelesTriangle(), telemetry.Triangle()
    assert (front.arm_mm, front.max_mm) == (calibrations[1]["inputs"]["arm"], calibrations[1]["inputs"]["max"])
    assert (rear.arm1_mm, rear.arm2_mm, rear.max_mm) == tuple(calibrations[2]["inputs"][k] for k in ("arm1", "arm2", "max"))
    assert telemetry.FORK_TRAVEL_MAX_MM == linkage["front_stroke"]
    assert telemetry.SHOCK_STROKE_MAX_MM == linkage["rear_stroke"]
    assert telemetry.HEAD_ANGLE_DEG == linkage["head_angle"]
    rows = [line.split(",") for line in linkage["data"].splitlines()]
    curve = telemetry.LeverageCurve()
    assert len(rows) == len(curve.ratio)
    for (wheel, ratio), ours_wheel, ours_ratio in zip(rows, curve.wheel_mm, curve.ratio):
        assert float(wheel) == ours_wheel
        try:
            assert float(ratio) == ours_ratio
        except ValueError:  # the one garbled row: digits around the inserted file name
            assert ratio.startswith("3.") and ratio.endswith("008") and ours_ratio == 3.008
    assert (SHIPPED.parent / "LICENSE").read_text().startswith("MIT License")


def test_the_comparison_is_the_python_api_s_as_the_command_s(tmp_path, capsys):
    """``mtbmj.ride.comparison.compare`` is what ``mtbmj telemetry`` runs: its result writes the same
    telemetry.json byte for byte and gives the line the command prints (the shipped ride, read with
    the example bike's defaults as the command reads it without --bike)."""
    from mtbmj.cli import main
    from mtbmj.ride import comparison

    assert main(["telemetry", "example", "--out", str(tmp_path / "cli")]) == 0
    printed = capsys.readouterr().out.strip()
    result = comparison.compare(telemetry.read_sst(telemetry.example_path()), [])
    assert isinstance(result, comparison.RideComparison) and result.runs == 0
    written = result.write(tmp_path / "api")
    assert sorted(p.name for p in written) == ["telemetry.json", "telemetry.png"]
    assert (tmp_path / "api" / "telemetry.json").read_bytes() == (tmp_path / "cli" / "telemetry.json").read_bytes()
    assert printed == f"{result.line()}; wrote telemetry.json, telemetry.png to {tmp_path / 'cli'}"
    assert "compared 0 run(s)" in result.line() and result.summary["simulated"] == []
    # "EXAMPLE" typed as --bike SST is typed: the shipped ride, where no file of that name is there
    assert main(["telemetry", "EXAMPLE", "--out", str(tmp_path / "upper")]) == 0
    assert (tmp_path / "upper" / "telemetry.json").read_bytes() == (tmp_path / "cli" / "telemetry.json").read_bytes()


def test_a_file_cut_inside_a_sample_is_read_with_a_warning(tmp_path, capsys):
    """A recorder writes whole 4-byte samples (every real file here: the header and a whole number of
    them); a file cut short in copying ends inside one. It was read without a word: now one warning
    line says so, and the whole samples are read as before."""
    from helpers import write_v3

    t = np.arange(0.0, 40.0, 0.001)
    whole = write_v3(tmp_path / "whole.SST", 60.0 + 40.0 * np.sin(2 * np.pi * 1.3 * t), 20.0 + 10.0 * np.sin(t))
    cut = tmp_path / "cut.SST"
    cut.write_bytes(whole.read_bytes() + b"\x07\x01\x00")  # three bytes of a 40 001st sample
    assert cli.main(["telemetry", str(whole), "--bike", "sst", "--out", str(tmp_path / "a")]) == 0
    said = capsys.readouterr()
    assert "ends inside a sample" not in said.err
    assert cli.main(["telemetry", str(cut), "--bike", "sst", "--out", str(tmp_path / "b")]) == 0
    cut_said = capsys.readouterr()
    warned = [line for line in cut_said.err.splitlines() if "ends inside a sample" in line]
    assert warned == ["mtbmj: warning: cut.SST: ends inside a sample (3 of its 4 bytes): a truncated file? its "
                      "40000 whole samples (40.0 s) are read"]
    assert cut_said.out.replace("cut.SST", "whole.SST").replace(str(tmp_path / "b"), str(tmp_path / "a")) == said.out

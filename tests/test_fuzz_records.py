"""Ride records a careless logger or a hostile hand makes (issue 49): SST v2/v3 files and travel CSVs
written here — a ride longer than the bike's travel, a stuck, metric or sign-flipped travel column,
time in milliseconds, a header's implausible sample rate, cut and garbage bytes — read by
``telemetry``, ``bob``, ``reconstruct`` and ``advise``: one line and exit 2 naming the cause (or one
named warning where the record can still be read), no traceback, nothing written. And every figure
of the package draws a file name with ``$`` in it as written.

The counts are made here by inverting the sensors' geometry as the shared README gives it (the
isosceles fork and triangle shock of version 3; the half-turn isosceles of version 2 and its
placeholder values), not by the reader."""
from __future__ import annotations

import math
import re
import shutil
import struct
from pathlib import Path

import numpy as np
import pytest

from mtbmj.cli import main

COUNTS = 4096
# version 3 (the shared data/sst/README.md): fork arm and max, shock arms and max
V3_FORK = (134.9375, 234.15625)
V3_SHOCK = (98.9, 202.8, 230.0)
# version 2: both ends an isosceles pair at pi/4096 rad per count; fork arm 120, max 218
V2_FORK = (120.0, 218.0)
V2_SHOCK = (88.0, 138.0)
ROOT = Path(__file__).resolve().parents[1]


def v3_fork_counts(travel):
    arm, top = V3_FORK
    start = math.acos(top / (2 * arm))
    return (np.arccos((top - travel) / (2 * arm)) - start) * COUNTS / (2 * np.pi)


def v3_shock_counts(stroke):
    a, b, top = V3_SHOCK
    g0 = math.acos((a * a + b * b - top ** 2) / (2 * a * b))
    c = top - stroke
    return (g0 - np.arccos((a * a + b * b - c * c) / (2 * a * b))) * COUNTS / (2 * np.pi)


def v3_fork_travel(counts):
    """The README's decoding of fork counts: what the written (whole) counts stand for."""
    arm, top = V3_FORK
    return top - 2 * arm * np.cos(2 * np.pi / COUNTS * np.asarray(counts, float) + math.acos(top / (2 * arm)))


def v2_counts(travel, arm, top):
    start = math.acos(top / (2 * arm))
    return (np.arccos((top - travel) / (2 * arm)) - start) * COUNTS / np.pi


def sst(path, fork_mm, shock_mm, rate=1000, version=3):
    if version == 3:
        counts = np.column_stack((v3_fork_counts(fork_mm), v3_shock_counts(shock_mm)))
        head = struct.pack("<3sBHHq", b"SST", 3, rate, 0, 1_700_000_000)
    else:
        counts = np.column_stack((v2_counts(fork_mm, *V2_FORK), v2_counts(shock_mm, *V2_SHOCK)))
        head = struct.pack("<3sBH", b"SST", 2, rate)
    path.write_bytes(head + np.rint(counts).astype("<u2").tobytes())
    return path


def sines(seconds=40.0, rate=1000.0, fork=(60.0, 50.0), shock=(20.0, 15.0)):
    """(time s, fork travel mm, shock stroke mm): a mean and an amplitude each, at 1.3 and 1.1 Hz."""
    t = np.arange(int(round(seconds * rate))) / rate
    return t, fork[0] + fork[1] * np.sin(2 * np.pi * 1.3 * t), shock[0] + shock[1] * np.sin(2 * np.pi * 1.1 * t)


def travel_csv(path, columns: dict, t, time_scale=1.0):
    data = {"time_s": t * time_scale, **columns}
    lines = [",".join(data)] + [",".join(f"{data[k][i]:.6f}" for k in data) for i in range(t.size)]
    path.write_text("\n".join(lines) + "\n")
    return path


def run(argv, capfd):
    """(status, stderr lines) of ``mtbmj argv``."""
    capfd.readouterr()
    status = main([str(a) for a in argv])
    err = capfd.readouterr().err
    assert "Traceback" not in err, err
    return status, err.splitlines()


def refused(argv, out, capfd, *said):
    """``argv`` refused in one line naming each of ``said``, exit 2, ``out`` not written."""
    status, lines = run(list(argv) + ["--out", out], capfd)
    assert status == 2 and len(lines) == 1 and lines[0].startswith("mtbmj: error: "), (status, lines)
    for word in said:
        assert word in lines[0], (word, lines[0])
    assert not Path(out).exists()
    assert not [p for p in Path(out).parent.iterdir() if p.name.startswith(f".{Path(out).name}.")]
    return lines[0]


# --- a ride longer than the bike's travel ---------------------------------------------------------


@pytest.fixture(scope="module")
def long_fork(tmp_path_factory):
    """A 180 mm fork's ride (20-155 mm) with the shock well inside 50 mm (5-35 mm)."""
    t, fork, shock = sines(fork=(87.5, 67.5))
    path = sst(tmp_path_factory.mktemp("long") / "long.SST", fork, shock)
    deepest = float(v3_fork_travel(np.max(np.rint(v3_fork_counts(fork)))))  # 155 mm to the nearest count
    assert abs(deepest - 155.0) < 0.3
    return path, deepest


@pytest.mark.parametrize("command", [["telemetry"], ["reconstruct"], ["advise"]])
def test_a_ride_longer_than_the_bikes_fork_is_refused(long_fork, tmp_path, capfd, command):
    # the trail bike's fork has 130 mm: 155 mm is 19 % beyond
    path, deepest = long_fork
    line = refused(command + [path, "--bike", "trail"], tmp_path / "out", capfd,
                   "long.SST", f"{deepest:.1f} mm", "130 mm", "geometry.fork_travel_mm of --bike trail")
    assert f"{100 * (deepest / 130 - 1):.1f} % beyond" in line


def test_the_refusal_names_the_option_that_set_the_travel_and_keeps_a_margin(long_fork, tmp_path, capfd):
    long_fork, deepest = long_fork
    refused(["telemetry", long_fork, "--fork-max-mm", "140"], tmp_path / "a", capfd, "--fork-max-mm",
            f"{100 * (deepest / 140 - 1):.1f} % beyond")
    # 155 mm on a 150 mm fork (3.3 % beyond: a calibration's tolerance) is read, and says 103 %
    status, lines = run(["telemetry", long_fork, "--fork-max-mm", "150", "--out", tmp_path / "b"], capfd)
    assert status == 0 and (tmp_path / "b" / "telemetry.json").is_file()
    # the SST example's bike (180 mm) reads it without a word about its travel
    status, lines = run(["telemetry", long_fork, "--out", tmp_path / "c"], capfd)
    assert status == 0 and not [x for x in lines if "beyond" in x]


def test_a_shock_stroking_past_the_bikes_is_refused_naming_its_key(tmp_path, capfd):
    t, fork, _ = sines()
    path = travel_csv(tmp_path / "ride.csv", {"fork_mm": fork, "shock_mm": 30.0 + 25.0 * np.sin(2 * np.pi * t)}, t)
    refused(["telemetry", path, "--bike", "trail"], tmp_path / "out", capfd,
            "shock strokes 55.0 mm", "50 mm", "shock.stroke_mm of --bike trail")


def test_a_version_2_ride_within_its_calibrations_uncertainty_is_warned(tmp_path, capfd):
    t, fork, shock = sines(seconds=31.0, fork=(100.0, 90.0), rate=5000.0)  # 190 mm: 5.6 % past 180 mm
    path = sst(tmp_path / "v2.SST", fork, shock, rate=5000, version=2)
    status, lines = run(["telemetry", path, "--out", tmp_path / "out"], capfd)
    warned = [x for x in lines if "beyond 180 mm" in x]
    assert status == 0 and len(warned) == 1 and warned[0].startswith("mtbmj: warning: v2.SST: the fork travels")
    # the same ride read as a 150 mm fork (27 % beyond) is refused
    refused(["telemetry", path, "--fork-max-mm", "150"], tmp_path / "o2", capfd, "--fork-max-mm", "beyond 150 mm")


# --- travel CSVs that are not what they say ---------------------------------------------------------


def test_a_stuck_travel_csv(tmp_path, capfd):
    t, fork, _ = sines()
    both = travel_csv(tmp_path / "stuck.csv", {"fork_mm": np.full(t.size, 42.0), "rear_mm": np.full(t.size, 30.0)}, t)
    refused(["telemetry", both], tmp_path / "a", capfd, "stuck.csv", "fork_mm 42", "rear_mm 30", "stuck")
    # one end stuck, the other moving: read, the stuck column named in one warning
    one = travel_csv(tmp_path / "one.csv", {"fork_mm": fork, "rear_mm": np.full(t.size, 30.0)}, t)
    status, lines = run(["telemetry", one, "--out", tmp_path / "b"], capfd)
    stuck = [x for x in lines if "stuck" in x]
    assert status == 0 and stuck == ["mtbmj: warning: one.csv: rear_mm is constant at 30 mm over all 40000 samples: "
                                     "a missing or stuck sensor; its end's metrics say nothing"]


@pytest.mark.parametrize("command", [["telemetry"], ["reconstruct", "--bike", "sst"]])
def test_a_travel_csv_in_metres(tmp_path, capfd, command):
    t, fork, shock = sines()
    path = travel_csv(tmp_path / "m.csv", {"fork_mm": fork / 1000.0, "shock_mm": shock}, t)
    refused(command[:1] + [path] + command[1:], tmp_path / "out", capfd, "m.csv", "fork_mm", "0.11", "metres")


@pytest.mark.parametrize("column", ["fork_mm", "rear_mm"])
def test_a_sign_flipped_travel_csv(tmp_path, capfd, column):
    t, fork, shock = sines()
    columns = {"fork_mm": fork, "rear_mm": 2.8 * shock}
    columns[column] = -columns[column]
    path = travel_csv(tmp_path / "f.csv", columns, t)
    refused(["telemetry", path], tmp_path / "out", capfd, f"{column} is below", "100 % of the samples", "sign-flipped")


def test_a_small_negative_offset_is_not_a_flip(tmp_path, capfd):
    """A sensor zeroed a few mm off at full extension reads a little below zero: still a ride."""
    t, fork, shock = sines(fork=(8.0, 14.0))  # -6 .. 22 mm: 36 % of the time below zero, never below -9 mm
    path = travel_csv(tmp_path / "o.csv", {"fork_mm": fork, "shock_mm": shock}, t)
    status, lines = run(["telemetry", path, "--out", tmp_path / "out"], capfd)
    assert status == 0 and (tmp_path / "out" / "telemetry.json").is_file()


@pytest.mark.parametrize("command", [["telemetry"], ["reconstruct", "--bike", "sst"]])
def test_time_in_milliseconds(tmp_path, capfd, command):
    t, fork, shock = sines(seconds=30.0)
    path = travel_csv(tmp_path / "ms.csv", {"fork_mm": fork, "shock_mm": shock}, t, time_scale=1000.0)
    refused(command[:1] + [path] + command[1:], tmp_path / "out", capfd,
            "ms.csv: time_s steps 1 s", "1 Hz", "milliseconds", "1000 Hz if so")


# --- headers and bytes ------------------------------------------------------------------------------


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("rate", [1, 50, 65535])
@pytest.mark.parametrize("command", [["telemetry"], ["bob"], ["reconstruct", "--bike", "sst"]])
def test_an_implausible_header_rate(tmp_path, capfd, version, rate, command):
    t, fork, shock = sines(seconds=4.0)
    path = sst(tmp_path / "r.SST", fork, shock, rate=rate, version=version)
    refused(command[:1] + [path] + command[1:], tmp_path / "out", capfd,
            f"r.SST: the header gives a sample rate of {rate} Hz", "100-20000 Hz")


def _cuts():
    t, fork, shock = sines(seconds=1.0)
    for version in (2, 3):
        head = 16 if version == 3 else 6
        for cut in (0, 2, 3, head - 1, head, head + 4, head + 5):
            yield version, cut


@pytest.mark.parametrize("version, cut", list(_cuts()))
@pytest.mark.parametrize("command", [["telemetry"], ["bob"]])
def test_a_truncated_record(tmp_path, capfd, version, cut, command):
    t, fork, shock = sines(seconds=1.0)
    blob = sst(tmp_path / "whole.SST", fork, shock, version=version).read_bytes()
    path = tmp_path / "cut.SST"
    path.write_bytes(blob[:cut])
    refused(command + [path], tmp_path / "out", capfd, "cut.SST")


def garbage(seed):
    """Random bytes, half of them behind a plausible SST header (a version, a rate, a timestamp)."""
    rng = np.random.default_rng(seed)
    body = rng.integers(0, 256, int(rng.integers(0, 4000)), dtype=np.uint8).tobytes()
    if seed % 2:
        return body
    version = int(rng.choice([2, 3, 3, 7]))
    rate = int(rng.choice([0, 1, 99, 100, 1000, 5000, 20001, 65535]))
    head = struct.pack("<3sBHHq", b"SST", version, rate, 0, int(rng.integers(-2 ** 62, 2 ** 62))) if version != 2 \
        else struct.pack("<3sBH", b"SST", 2, rate)
    return head + body


@pytest.mark.parametrize("seed", range(24))
def test_garbage_bytes_are_one_line_or_a_reading(tmp_path, capfd, seed):
    path = tmp_path / "g.SST"
    path.write_bytes(garbage(seed))
    for command in (["telemetry"], ["bob"]):
        out = tmp_path / f"out_{command[0]}"
        status, lines = run(command + [path, "--out", out], capfd)
        if status == 2:
            assert len(lines) == 1 and lines[0].startswith("mtbmj: error: ") and "g.SST" in lines[0], lines
            assert not out.exists()
        else:  # random counts can make a valid file; then it is read, never half-written
            assert status == 0 and command == ["telemetry"] and (out / "telemetry.json").is_file(), (status, lines)
            return


def test_the_readers_refuse_the_same_without_the_command_line(tmp_path):
    """The rate and the sensors are checked where the header and the columns are read (every
    command that reads a ride: telemetry, reconstruct, advise, bob, bounce, bike --ride)."""
    from mtbmj.measured import telemetry

    t, fork, shock = sines(seconds=4.0)
    with pytest.raises(telemetry.TelemetryError, match="sample rate of 1 Hz"):
        telemetry.read_sst(sst(tmp_path / "a.SST", fork, shock, rate=1))
    still = np.full(t.size, 1000.0)  # counts 1000 and 1000 on both ends, all the ride long
    held = tmp_path / "b.SST"
    held.write_bytes(struct.pack("<3sBHHq", b"SST", 3, 1000, 0, 0) + np.column_stack((still, still)).astype("<u2").tobytes())
    with pytest.raises(telemetry.TelemetryError, match="no sensor moved .fork count 1000, shock count 1000"):
        telemetry.read_sst(held)
    with pytest.raises(telemetry.TelemetryError, match="milliseconds"):
        telemetry.read_travel_csv(travel_csv(tmp_path / "c.csv", {"fork_mm": fork}, t, time_scale=1000.0))


# --- what the analyses themselves say of a slow record -----------------------------------------------


def test_velocity_names_the_sampling_not_the_length():
    from mtbmj.measured import metrics

    t = np.arange(3000) / 50.0  # 50 Hz: 3 samples in the 51 ms window
    with pytest.raises(metrics.MetricsError) as info:
        metrics.velocity(t, 50.0 + 40.0 * np.sin(2 * np.pi * 1.3 * t))
    assert "time_s: a sample every 0.02 s (50 Hz)" in str(info.value) and "too few" not in str(info.value)


def test_bob_of_a_slow_record_is_one_line():
    from mtbmj.measured import bob

    t = np.arange(600) / 10.0  # 10 Hz
    with pytest.raises(bob.BobError, match="sample rate of 10 Hz is too slow"):
        bob.bob(t, 30.0 + 5.0 * np.sin(2 * np.pi * 2.0 * t))


# --- a file name with "$" in every figure --------------------------------------------------------------


def test_every_figure_is_written_by_the_one_figure_writer():
    """A figure saved anywhere but through ``readout/quicklook.py`` (``png``, which draws every text
    as written) parses a file or bike name with ``$`` as mathtext (a traceback for an unbalanced
    one): no ``savefig`` anywhere else in the package (issue 50 item 5)."""
    bare = []
    for folder in ("mtbmj", "controllers", "validation"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path.relative_to(ROOT).as_posix() == "mtbmj/readout/quicklook.py":
                continue
            for number, line in enumerate(path.read_text().splitlines(), 1):
                if re.search(r"\.(savefig|print_png|print_figure)\(", line):
                    bare.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not bare, bare


@pytest.mark.slow  # a reconstruction through the whole bike: 0.5-2 min
def test_reconstruct_a_ride_whose_name_is_mathtext(tmp_path, capfd):
    ride = tmp_path / "a$\\frac{b$.SST"
    shutil.copyfile(ROOT / "mtbmj" / "data" / "sst" / "00649.SST", ride)
    status, lines = run(["reconstruct", ride, "--bike", "sst", "--out", tmp_path / "out"], capfd)
    assert status == 0, lines
    png = (tmp_path / "out" / "reconstruction.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"

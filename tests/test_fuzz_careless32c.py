"""Careless input, round 32c: the ride commands (telemetry, reconstruct, advise, bob, bike --ride, fit bounce,
sag --bike) and ``mtbmj.ride``'s readers given the shared records damaged as a rider damages them. Each case
failed before its fix. Records are written here from the formats of /work/shared/data/sst/README.md and
/work/shared/data/sst_v2/README.md (header and 4-byte samples), never by the code under test."""
from __future__ import annotations

import re
import struct

import numpy as np
import pytest

from helpers import refused
from mtbmj.measured.telemetry import TelemetryError
from mtbmj.ride import read_sst
from conftest import SHARED_DATA


def v3_record(seconds: float, rate: int = 1000, phase: float = 0.0) -> bytes:
    """An SST v3 file: the 16-byte header (magic, version 3, rate, padding, Unix time) and counts of both
    sensors moving (by the README's formulas the fork 23-159 mm of 180, the shock 14-43 mm of 65)."""
    t = np.arange(int(seconds * rate)) / rate
    fork = 300 + 200 * np.sin(2 * np.pi * 1.3 * t + phase)
    shock = 200 + 100 * np.sin(2 * np.pi * 0.9 * t + phase)
    body = np.column_stack((fork, shock)).round().astype("<u2").tobytes()
    return struct.pack("<3sBHHq", b"SST", 3, rate, 0, 1_650_000_000) + body


def v2_record(seconds: float, rate: int = 5000) -> bytes:
    """An SST v2 file: the 6-byte header (magic, version 2, rate) and counts within the v2 fork's and shock's
    range (0..1485 and 0..1071 by the README's placeholder arms)."""
    t = np.arange(int(seconds * rate)) / rate
    fork = 300 + 200 * np.sin(2 * np.pi * 1.3 * t)
    shock = 400 + 150 * np.sin(2 * np.pi * 0.9 * t)
    return struct.pack("<3sBH", b"SST", 2, rate) + np.column_stack((fork, shock)).round().astype("<u2").tobytes()


# --- 1. two recordings joined into one file (cat a.SST b.SST > ride.SST) ------------------------------------

@pytest.mark.parametrize("first, second, cut, said", [
    # was "fork count 21331 at sample 40000 is outside 0..4095": true, but a rider reads a sensor gone wild
    (v3_record(40.0), v3_record(35.0, phase=1.0), 0, "a second SST header (version 3) at byte 160016, after 40000 "
                                                     "samples (40.0 s): two recordings joined into one file?"),
    (v2_record(8.0), v2_record(6.0), 0, "a second SST header (version 2) at byte 160006, after 40000 samples "
                                        "(8.0 s): two recordings joined into one file?"),
    (v3_record(40.0), v2_record(6.0), 0, "a second SST header (version 2) at byte 160016"),
    # the first cut inside a sample (head -c): the second header falls across two samples
    (v3_record(40.0), v3_record(35.0), 3, "a second SST header (version 3) at byte 160013, after 39999 samples"),
])
def test_two_recordings_joined_name_the_second_header(tmp_path, capfd, first, second, cut, said):
    ride = tmp_path / "joined.SST"
    ride.write_bytes(first[:len(first) - cut] + second)
    mtime = ride.stat().st_mtime_ns
    out = tmp_path / "out"
    for argv in (["telemetry", ride, "--out", out], ["reconstruct", ride, "--bike", "sst", "--out", out]):
        line = refused(argv, out, capfd, said)
        assert "read each on its own" in line
    with pytest.raises(TelemetryError, match="two recordings joined into one file"):
        read_sst(ride)
    assert ride.stat().st_mtime_ns == mtime


def test_a_count_out_of_range_that_is_no_header_is_named_as_before(tmp_path, capfd):
    """The baseline: a sensor's count past the encoder's 4095 with no second header in the file keeps its line."""
    blob = bytearray(v3_record(5.0))
    struct.pack_into("<H", blob, 16 + 4 * 1234, 5000)  # the fork's count of sample 1234
    ride = tmp_path / "wild.SST"
    ride.write_bytes(bytes(blob))
    refused(["telemetry", ride, "--out", tmp_path / "out"], tmp_path / "out", capfd,
            "wild.SST: fork count 5000 at sample 1234 is outside 0..4095")


def test_one_recording_whole_is_read(tmp_path):
    """The two records of the joined cases, each on its own, are read: the line is for the joint only."""
    for k, blob in enumerate((v3_record(40.0), v2_record(8.0))):
        ride = tmp_path / f"{k}.SST"
        ride.write_bytes(blob)
        record = read_sst(ride)
        assert record.time_s.size == 40000 and record.version == (3 if k == 0 else 2)


# --- 2. a sensor unplugged, stuck or saturated all the ride: reconstruct and advise -------------------------

def still(column: int, count: int) -> bytes:
    """``v3_record(40 s)`` with one sensor's count held all the ride (0: unplugged or at full extension;
    4095: saturated, which the v3 fork's calibration reads as 0 mm too)."""
    blob = bytearray(v3_record(40.0))
    counts = np.frombuffer(bytes(blob[16:]), dtype="<u2").reshape(-1, 2).copy()
    counts[:, column] = count
    return bytes(blob[:16]) + counts.tobytes()


@pytest.mark.parametrize("column, count, said", [
    (0, 0, "the fork's travel never moves (0 mm, count 0 over all 40000 samples): its sensor unplugged"),
    (0, 4095, "the fork's travel never moves (0 mm, count 4095 over all 40000 samples)"),
    (1, 0, "the rear's travel never moves (0 mm, count 0 over all 40000 samples)"),
])
def test_an_end_that_never_moves_is_refused_by_reconstruct_and_advise(tmp_path, capfd, column, count, said):
    """Was: with a speed given, reconstructed from a fork that never moved (no terrain at all); without one,
    "the two ends' records do not align at any lag ... a speed given is used in its place": a false lead."""
    from mtbmj.ride.reconstruct import reconstruct
    from mtbmj.ride.reconstruct_speed import ReconstructError

    ride = tmp_path / "unplugged.SST"
    ride.write_bytes(still(column, count))
    mtime = ride.stat().st_mtime_ns
    out = tmp_path / "out"
    for argv in (["reconstruct", ride, "--bike", "sst", "--speed", "5", "--out", out],
                 ["reconstruct", ride, "--bike", "sst", "--out", out],
                 ["advise", ride, "--bike", "sst", "--out", out]):
        refused(argv, out, capfd, said)
    with pytest.raises(ReconstructError, match="never moves"):
        reconstruct(read_sst(ride), "sst", speed=5.0)
    assert ride.stat().st_mtime_ns == mtime


def test_an_end_that_never_moves_is_still_read_by_telemetry_and_a_moving_one_passes(tmp_path, capfd):
    """telemetry reads the other end and says the still one in a warning (as before); a record whose two ends
    move passes the check reconstruct and advise make."""
    from helpers import command_err
    from mtbmj.measured.telemetry import both_ends

    ride = tmp_path / "unplugged.SST"
    ride.write_bytes(still(0, 0))
    status, err = command_err(["telemetry", ride, "--out", tmp_path / "out"], capfd)
    assert status == 0 and "the fork sensor never moved: missing or stuck" in err, err
    moving = tmp_path / "moving.SST"
    moving.write_bytes(v3_record(40.0))
    assert both_ends(read_sst(moving)) is None
    assert "never moves" in both_ends(read_sst(ride))


# --- 3. bob given a record too short for its stretch ---------------------------------------------------------

def test_bob_of_a_short_record_names_it_before_any_run(tmp_path, capfd, monkeypatch):
    """Was "bob: the pedalling stretch 2.0--1.5 s is shorter than 4 s": no file named (of two records, which?),
    a span read as a minus, and said after the first record's runs (10 s of work for nothing)."""
    import mtbmj.bike.run
    from mtbmj.measured.bob import BobError
    from mtbmj.ride.pedalling import against

    good, short = tmp_path / "pedalling.SST", tmp_path / "short.SST"
    good.write_bytes(v2_record(8.0))
    short.write_bytes(v2_record(0.5))
    out = tmp_path / "out"
    line = refused(["bob", short, "--out", out], out, capfd, f"{short}: 0.5 s of record; the rear's pedalling "
                   "stretch (2 s after the travel first rises above 2 mm, at 0.0 s, to 2 s before it last does, at "
                   "0.5 s) is empty: shorter than 4 s")
    assert "--" not in line

    def no_run(*args, **kwargs):
        raise AssertionError("a run before every record was read")

    monkeypatch.setattr(mtbmj.bike.run, "run_bike", no_run)
    with pytest.raises(BobError, match=f"{short}: 0.5 s of record"):
        against([good, short])


# --- 4. fit bounce's hit typed in metres --------------------------------------------------------------------

SLAMS = [f"{SHARED_DATA}/sst_v2/00083.SST", f"{SHARED_DATA}/sst_v2/00085.SST"]  # 0 and 8 rebound clicks


def test_a_hit_typed_in_metres_is_named(tmp_path, capfd):
    """``fit bounce ... --hit-mm 0.03`` (30 mm typed in metres): answered for a 0.03 mm hit, within the
    friction band the decay law fits (0.28-1.23 mm on these two slams), unsaid. Now one warning naming 30 mm,
    from the command line and from Python alike; a 5 mm hit draws none."""
    from helpers import command_said
    from mtbmj.errors import ConfigWarning
    from mtbmj.identify.bounce_fit import fit_bounce

    status, said = command_said(["fit", "bounce", *SLAMS, "--clicks", "0,8", "--hit-mm", "0.03",
                                 "--out", tmp_path / "metres"], capfd)
    note = "--hit-mm = 0.03 mm is outside 1-1000 mm, what bikes, riders and records have (a unit mistake? " \
           "probably meant 0.03 m = 30 mm)"
    assert status == 0 and said.count(note) == 1, said
    status, said = command_said(["fit", "bounce", *SLAMS, "--clicks", "0,8", "--hit-mm", "5",
                                 "--out", tmp_path / "mm"], capfd)
    assert status == 0 and "warning" not in said and "after a 5.0 mm hit" in said, said
    with pytest.warns(ConfigWarning, match=r"probably meant 0\.03 m = 30 mm"):
        fit_bounce(SLAMS, [0.0, 8.0], hit_mm=0.03)


# --- 5. mtbmj.ride.summarize given a travel in metres, a clock going back ----------------------------------

def fork_ride(seconds: float = 20.0, rate: int = 1000):
    """A fork's travel written here: 60 mm of sag, a 1.3 Hz stroke of 40 mm, a 180 mm fork."""
    t = np.arange(int(seconds * rate)) / rate
    return t, 60.0 + 40.0 * np.sin(2 * np.pi * 1.3 * t)


@pytest.mark.parametrize("scale, top, said", [
    # was answered: max 55.6 % with both in metres (its velocities in m/s split at 100 "mm/s"), 55556 % with the
    # travel in mm and its top in metres
    (1e-3, 0.18, "travel_max_mm: 0.18 mm: no suspension end travels under 10 mm; metres? (180 mm if so"),
    (1.0, 0.18, "travel_max_mm: 0.18 mm: no suspension end travels under 10 mm"),
    (1.0, 40.0, "travel_mm reaches 100 mm, 2.5 times travel_max_mm (40 mm): the two in different units, or another "
                "end's travel"),
])
def test_summarize_of_a_travel_in_another_unit_says_so(scale, top, said):
    from mtbmj.ride import summarize

    t, x = fork_ride()
    with pytest.raises(ValueError, match=re.escape(said)):
        summarize(t, x * scale, top)
    assert summarize(t, x, 180.0)["travel"]["max_percent"] == pytest.approx(100.0 * 100.0 / 180.0, abs=0.01)
    assert summarize(t, x, 60.0)["travel"]["max_percent"] > 100.0  # past its travel, within a bottom-out: read


def test_summarize_of_a_clock_going_back_names_the_sample():
    """Was "time_s: samples are not uniformly spaced (resample first)": a clock that goes back is not resampled."""
    from mtbmj.ride import summarize

    t, x = fork_ride()
    t[500] = t[499]
    with pytest.raises(ValueError, match=re.escape("time_s: sample 500 (0.499 s) does not come after sample 499 "
                                                   "(0.499 s): the time must increase")):
        summarize(t, x, 180.0)
    with pytest.raises(ValueError, match="time_s: sample 1 .* does not come after sample 0"):
        summarize(t[::-1], x, 180.0)

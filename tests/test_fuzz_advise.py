"""Fuzzing the arguments of ``mtbmj reconstruct`` and ``mtbmj advise`` (issue 49): every case is
generated here (records made in this file or by tests/helpers.py's bike, argument combinations
drawn from a seeded generator). Each run must end in one of two ways: exit 2 with one ``mtbmj:
error:`` line and nothing written, or exit 0 with a report that holds what it claims (strict JSON, a
speed inside the range searched, samples checked; advice with no negative count or share and no
candidate outside what its part allows). Never a traceback, never a confident answer from a record
that cannot support one."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mtbmj.cli import main


def strict_json(path):
    def bad(token):
        raise AssertionError(f"{path.name}: {token} is not JSON")

    return json.loads(path.read_text(), parse_constant=bad)


def outcome(code, err, out):
    """Exit 2: one error line, nothing written; exit 0: the report is there. The error line."""
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if not ln.startswith("mtbmj: warning")]
    if code == 2:
        assert len(lines) == 1 and lines[0].startswith("mtbmj: error: "), err
        assert not out.exists()
        return lines[0]
    assert code == 0 and not lines, (code, err)
    return None


def made_record(path, rng, kind, seconds, speed=None):
    """A two-ended travel CSV of a drawn kind: bumps at the fork and the same bumps a lag later at the
    rear (a speed of 2-25 m/s on the 1.255 m wheelbase: inside and outside the 1-15 m/s searched),
    sub-millimetre motion (a bike standing), one end still, or two unrelated ends; a drawn length
    (under and over the 6.3 s a speed needs) and rate."""
    rate = int(rng.choice([500, 1000]))
    speed = float(rng.uniform(2.0, 25.0)) if speed is None else speed
    t = np.arange(max(int(seconds * rate), 3)) / rate
    grid = np.arange(-3.0, seconds + 3.0, 1.0 / rate)
    n = max(int(4 * seconds), 2)

    def bumps():
        kicks = np.zeros_like(grid)
        kicks[rng.integers(0, grid.size, n)] = rng.uniform(5, 40, n)
        kernel = np.hanning(max(int(0.12 * rate), 3))
        return np.convolve(kicks, kernel / kernel.max(), mode="same")

    shape = bumps()
    drift = np.linspace(0.0, 1.5, t.size)
    fork = 20.0 + drift + np.interp(t, grid, shape)
    rear = 25.0 + drift + np.interp(t - 1.255 / speed, grid, shape)
    if kind == "standing":
        fork, rear = 20.0 + 0.02 * (fork - 20.0), 25.0 + 0.02 * (rear - 25.0)
    elif kind == "one_still":
        rear = 25.0 + 0.3 * np.sin(2 * np.pi * 0.1 * t)
    elif kind == "unrelated":
        rear = 25.0 + drift + np.interp(t, grid, bumps())
    path.write_text("time_s,fork_mm,rear_mm\n" + "\n".join(
        f"{a:.5f},{b:.1f},{c:.1f}" for a, b, c in zip(t, fork, rear)))
    return seconds, speed


# each kind at two lengths (under and over the 6.3 s a speed needs, or both over), the rest drawn;
# one lagged record at 20 m/s, whose lag is shorter than any searched
RECORD_CASES = [(kind, seconds, int(seed), None) for (kind, lengths), seed in zip(
    (("lagged", (9.0, 12.0)), ("standing", (7.0, 12.0)), ("one_still", (9.0, 0.01)), ("unrelated", (12.0, 2.0))),
    np.random.default_rng(49).integers(0, 10**6, 4)) for seconds in lengths] + [("lagged", 9.0, 5, 20.0)]


@pytest.mark.parametrize("kind,seconds,seed,speed", RECORD_CASES)
def test_reconstruct_on_made_records(tmp_path, capsys, kind, seconds, seed, speed):
    from helpers import BIKE

    rng = np.random.default_rng(seed)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)
    csv = tmp_path / "ride.csv"
    seconds, speed = made_record(csv, rng, kind, seconds, speed)
    out = tmp_path / "out"
    code = main(["reconstruct", str(csv), "--bike", str(bike), "--out", str(out)])
    line = outcome(code, capsys.readouterr().err, out)
    if kind == "one_still" and seconds < 0.1:  # 10 samples of the rear at 0.1 mm: written 25.0 all through
        assert line is not None and "the rear's travel never moves (25 mm over all 10 samples)" in line, line
    elif seconds < 6.3 or kind in ("standing", "one_still"):  # too short, or an end still: no speed
        assert line is not None and "no speed" in line, (kind, seconds, line)
    if line is None:
        summary = strict_json(out / "reconstruction.json")
        assert 1.0 <= summary["speed_m_per_s"] <= 15.0
        assert summary["checks"]["samples_checked_percent"] > 0.0
        if kind == "lagged" and speed > 16.0:  # the true lag is outside the search: never the search's edge
            assert summary["speed_m_per_s"] < 14.9, (speed, summary["window_speeds_m_per_s"])


ADVISE_ARGUMENTS = [["--duration", "-1"], ["--duration", "0"], ["--duration", "nan"], ["--duration", "inf"],
                    ["--duration", "1e400"], ["--duration", "0.5"], ["--duration", "14.99"], ["--duration", "abc"],
                    ["--workers", "0"], ["--workers", "-3"], ["--rider-kg", "nan"], ["--bike", "no-such-bike"],
                    ["--shock-set", "fork.damper.compression_clicks"], ["--duration", "15.5"], ["--duration", "100"]]


def test_advise_arguments_are_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """Drawn combinations of bad and good arguments on a 16 s record made here: a bad one is
    refused in one line before the ride is reconstructed; good ones reach the reconstruction
    (stood in for here by a refusal of its own)."""
    from helpers import BIKE, bumps_csv, reconstruction_stand_in

    reached = reconstruction_stand_in(monkeypatch)
    csv, *_ = bumps_csv(tmp_path / "ride.csv", 16.0)
    bike = tmp_path / "bike.toml"
    bike.write_text(BIKE)
    rng = np.random.default_rng(4949)
    good = {"--duration": {"15.5", "100"}}
    for _ in range(12):
        picks = [ADVISE_ARGUMENTS[i] for i in rng.choice(len(ADVISE_ARGUMENTS), int(rng.integers(1, 3)), replace=False)]
        args = ["advise", str(csv), "--bike", str(bike)] + [x for p in picks for x in p] + ["--out", str(tmp_path / "o")]
        reached.clear()
        try:
            code = main(args)
        except SystemExit as exc:  # argparse's own refusal (a value of the wrong type)
            code = exc.code
        line = outcome(code, capsys.readouterr().err, tmp_path / "o")
        assert line is not None, args
        all_good = all(p[1] in good.get(p[0], ()) for p in picks)
        assert bool(reached) == all_good, (args, line)
        if not all_good:
            assert "reached the reconstruction" not in line


def advise_cases():
    """(name, bike text) of tests/test_advise.py's bike with parts whose ranges are tight: clicks
    measured over a short range around the setting or with it at an end, an air shock whose next
    spacer fills its chamber."""
    from helpers import air_shock_bike, clicks_bike

    rng = np.random.default_rng(7)
    setting = int(rng.integers(5, 10))
    return [("clicks at the range's first", clicks_bike(setting, (setting, setting + 1))),
            ("clicks one above the range's first", clicks_bike(setting, (setting - 1, setting + 10))),
            ("air shock, the next spacer impossible", air_shock_bike(5))]


@pytest.fixture(scope="module")
def made_ride(tmp_path_factory):
    from helpers import ride, write_sst

    # tests/test_advise.py's packing ride, 16 s (its reconstruction checks); the bike files here are
    # its bike with other shocks: what is fuzzed is the advice's handling of their parts
    folder = tmp_path_factory.mktemp("fuzz_advise")
    bike, fork_mm, rear_mm, t = ride(folder, fork_reb=2500.0, seconds=16.0)
    return write_sst(folder / "ride.SST", fork_mm, rear_mm)


@pytest.mark.slow
@pytest.mark.parametrize("case", range(3))
def test_advise_with_tight_parts_answers_or_refuses_the_ride(made_ride, tmp_path, capsys, case):
    """A part whose range leaves a candidate outside it never ends the advice: it answers (the
    candidate skipped, named, or stepped to the range's end) or refuses the ride itself (its
    reconstruction's check) in one line; an answer expects no negative count or share. --duration
    just above the 15 s minimum."""
    from mtbmj.bike import spec as spec_mod
    from mtbmj.ride import advise

    name, text = advise_cases()[case]
    bike = tmp_path / "bike.toml"
    bike.write_text(text)
    out = tmp_path / "advice"
    code = main(["advise", str(made_ride), "--bike", str(bike), "--duration", "15.2", "--out", str(out)])
    line = outcome(code, capsys.readouterr().err, out)
    if line is not None:  # the ride's own refusal, never a candidate's
        assert ("fails its own check" in line or "on the ride's reconstructed terrain" in line), (name, line)
        return
    advice = strict_json(out / "advice.json")
    found = {(a.section, a.key): a for a in advise.adjusters(spec_mod.load(str(bike)))}
    values = spec_mod.load(str(bike)).shock_overrides
    for c in advice["candidates"]:
        section, key = ("shock.set" if c["key"].startswith("shock:") else "fork.set"), c["key"].split(":", 1)[1]
        if key.endswith("_clicks"):
            measured = values[f"{key}_measured"]
            assert min(measured) <= c["to"] <= max(measured), (name, c)
        assert (section, key) in found
    for s in advice["skipped"]:
        assert s["why"] and s["to"] is not None
    rec = advice["recommendation"]
    for k, c in (rec or {}).get("changes", {}).items():
        assert c["expected"] is None or math.isfinite(c["expected"])
        if k != "balance_points":
            assert c["expected"] >= 0.0, (name, k, c)
        if k.endswith(("deep_travel_percent", "speed_percent")):
            assert c["expected"] <= 100.0, (name, k, c)

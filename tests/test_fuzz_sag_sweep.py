"""Fuzzing the arguments of `mtbmj sag --bike` and of `mtbmj sweep` over a bike (issue 49): hostile
--set / --fork-set / --shock-set values, --vary ranges and sag percents (0, 100, -5, nan, inf, huge
integers, words, lists, unknown keys, special files). Every case either answers (exit 0; sag --bike
then wrote one bike file that sags as printed, sweep a table) or is refused in one line on stderr with
exit status 2, no traceback and nothing written. The cases are drawn here, seeded, from lists written
here; the sweeps are tiny (2 variants, 0.2 s)."""
from __future__ import annotations

import random
import re
import tomllib

import pytest

from mtbmj.cli import main

HUGE = str(10 ** 400)
VALUES = ["0", "-5", "nan", "inf", "-inf", "1e400", HUGE, "1e300", "-1e-300", "abc", '"text"', "[1, 2]", "true",
          "{a = 1}", "", "1e9", "0.0001"]
BIKE_KEYS = ["rider.mass_kg", "rider.com_mm", "rider.leg_stiffness_N_per_mm", "rider.limbs_share_percent",
             "geometry.head_angle_deg", "geometry.wheelbase_mm", "geometry.fork_travel_mm", "bike.frame_mass_kg",
             "bike.pivot_mm", "shock.spring_rate_lb_per_in", "shock.spring_rate_N_per_mm", "shock.stroke_mm",
             "shock.pressure_psi", "shock.volume_spacers", "shock.preload_mm", "leverage.ratio", "leverage.csv",
             "fork.config", "sensors.fork_arm_mm", "drive.push_N", "nosuch.key", "rider.nosuch", "rider"]
CONFIG_KEYS = ["fork.spring.rate_N_per_mm", "fork.spring.progressive_rate_N_per_mm", "fork.spring.preload_N",
               "fork.spring.model", "fork.travel_mm", "tire.radius_mm", "fork.damper.compression_N_s_per_m",
               "fork.nosuch", "sled.rider_mass_kg"]
PERCENTS = ["0", "100", "-5", "nan", "inf", "1e400", HUGE, "28", "20", "99.99", "0.001", "abc"]
FILES = ["/dev/zero", "/dev/null", "fifo", "folder", "missing.csv", "empty.csv"]


def _special_files(folder) -> None:
    import os

    if hasattr(os, "mkfifo"):
        os.mkfifo(folder / "fifo")
    (folder / "folder").mkdir()
    (folder / "empty.csv").write_text("")


# values a rider might give: half of the changes are drawn from these, so that many cases answer
FAIR = [("--set", "rider.mass_kg", ["62", "78.5", "104"]), ("--set", "shock.spring_rate_lb_per_in", ["350", "420", "500"]),
        ("--set", "shock.spring_rate_N_per_mm", ["60", "75.5"]), ("--set", "geometry.head_angle_deg", ["63", "64.5", "66"]),
        ("--set", "geometry.wheelbase_mm", ["1210", "1250"]), ("--set", "geometry.fork_travel_mm", ["120", "140"]),
        ("--set", "bike.frame_mass_kg", ["6.5", "8"]), ("--set", "rider.com_mm", ["[60.0, 940.0]"]),
        ("--fork-set", "fork.spring.preload_N", ["50", "150"]), ("--shock-set", "fork.spring.rate_N_per_mm", ["70", "95"]),
        ("--shock-set", "fork.damper.compression_N_s_per_m", ["1500", "3000"])]


def _set(rng: random.Random) -> list[str]:
    kind = rng.random()
    if kind < 0.5:
        option, key, values = rng.choice(FAIR)
        return [option, f"{key}={rng.choice(values)}"]
    if kind < 0.8:
        key = rng.choice(BIKE_KEYS)
        value = rng.choice(FILES) if key in ("leverage.csv", "fork.config") and rng.random() < 0.7 else rng.choice(VALUES)
        return ["--set", f"{key}={value}"]
    option = rng.choice(["--fork-set", "--shock-set"])
    return [option, f"{rng.choice(CONFIG_KEYS)}={rng.choice(VALUES)}"]


def _check(status: int, err: str, out_dir, out: str = "") -> None:
    assert "Traceback" not in err, err
    if status == 0:
        return
    if status == 1:  # a sweep whose every variant failed: the table of their reasons is written
        assert (out_dir / "sweep.csv").is_file() and "every variant failed (the first: " in out, (out, err)
        return
    assert status == 2, (status, err)
    lines = [line for line in err.splitlines() if not line.startswith("mtbmj: warning:")]
    assert len(lines) == 1 and lines[0].startswith("mtbmj: error: "), err
    assert not out_dir.exists(), "a refused command wrote its folder"


SAG = re.compile(r"gives [\d.]+ % front sag \(([\d.]+) of ([\d.]+) mm\).*gives [\d.]+ % rear \(([\d.]+) of ([\d.]+) mm")


def _sag_cases(n: int) -> list[list[str]]:
    rng = random.Random(49)
    cases = [["--front-sag-percent", p, "--rear-sag-percent", "28"] for p in ("0", "100", "-5", "nan")]
    cases += [["--front-sag-percent", "20", "--rear-sag-percent", p] for p in ("0", "100", "-5", "nan", HUGE)]
    while len(cases) < n:
        args = ["--front-sag-percent", rng.choice(PERCENTS) if rng.random() < 0.15 else rng.choice(["18", "20", "25"]),
                "--rear-sag-percent", rng.choice(PERCENTS) if rng.random() < 0.15 else rng.choice(["25", "28", "32"])]
        for _ in range(rng.randint(1, 3)):
            args += _set(rng)
        cases.append(args)
    return cases


@pytest.mark.parametrize("index", range(32))
def test_fuzz_sag_bike(index, tmp_path, monkeypatch, capsys):
    args = _sag_cases(32)[index]
    monkeypatch.chdir(tmp_path)
    _special_files(tmp_path)
    status = main(["sag", "trail", "--bike", *args, "--out", "set"])
    captured = capsys.readouterr()
    _check(status, captured.err, tmp_path / "set")
    if status == 0:  # it answered: the file it wrote runs from another folder at the sag it printed
        from mtbmj.bike import run

        got = SAG.search(captured.out)
        assert got, captured.out
        front, front_travel, rear, rear_travel = (float(got.group(i)) for i in range(1, 5))
        written = list((tmp_path / "set").glob("*.toml"))
        assert len(written) == 1 and "base" not in tomllib.loads(written[0].read_text())
        (tmp_path / "away").mkdir()
        monkeypatch.chdir(tmp_path / "away")
        p = run.prepare(str(written[0]), "flat", 4.0, callback="python")
        summary_front = float(p.data.qpos[p.bike.qpos_index("fork")]) * 1e3
        assert abs(summary_front - front) < 0.01 * front_travel


def _sweep_cases(n: int) -> list[list[str]]:
    rng = random.Random(4949)
    numbers = ["70", "90", "-5", "0", "nan", "inf", "1e400", HUGE, "abc", "", "1e-300", "5"]
    counts = ["2", "0", "-1", "1.5", "abc", "", "99999999999", HUGE]
    keys = ["rider.mass_kg", "rider.com_mm", "geometry.head_angle_deg", "bike.head_angle_deg", "nosuch.key",
            "fork:fork.spring.progressive_rate_N_per_mm", "shock:fork.spring.rate_N_per_mm", "fork:fork.spring.model",
            "shock:fork.nosuch", "rider", "fork:", ":x", "=", "rider.mass_kg=70:90:2"]
    terrains = ["root:at_m=0.4", "root:at_m=nan", "nosuch", "/dev/zero", "fifo", "folder", "missing.csv", "empty.csv",
                "root:radius_mm=" + HUGE, "flat:length_m=1e9"]
    cases = []
    while len(cases) < n:
        if rng.random() < 0.5:  # a fair range
            key, lo, hi = rng.choice([("rider.mass_kg", "65", "95"), ("geometry.head_angle_deg", "63", "66"),
                                      ("fork:fork.spring.progressive_rate_N_per_mm", "7", "10"),
                                      ("shock:fork.spring.rate_N_per_mm", "70", "90")])
        else:
            key = rng.choice(keys)
            lo, hi = (rng.choice(numbers), rng.choice(numbers)) if rng.random() < 0.6 else ("70", "90")
        vary = f"{key}={lo}:{hi}:{rng.choice(counts) if rng.random() < 0.4 else '2'}"
        args = ["--roll", rng.choice(terrains) if rng.random() < 0.25 else "root:at_m=0.4",
                "--speed", rng.choice(["5", "0", "-1", "nan", "1e9", HUGE]) if rng.random() < 0.15 else "5",
                "--vary", vary]
        if rng.random() < 0.4:
            args += _set(rng)
        cases.append(args)
    return cases


@pytest.mark.parametrize("index", range(24))
def test_fuzz_bike_sweep(index, tmp_path, monkeypatch, capsys):
    args = _sweep_cases(24)[index]
    monkeypatch.chdir(tmp_path)
    _special_files(tmp_path)
    status = main(["sweep", "trail", *args, "--duration", "0.2", "--quiet", "--out", "sw"])
    captured = capsys.readouterr()
    _check(status, captured.err, tmp_path / "sw", captured.out)
    if status == 0:
        assert (tmp_path / "sw" / "sweep.csv").is_file()


# the cases that answered "every variant failed" (exit 0) or ran out of memory before issue 49, named
REFUSED = {
    "a grid of 1e11 variants": ["--roll", "root:at_m=0.4", "--vary", "rider.mass_kg=70:90:99999999999"],
    "an unknown terrain": ["--roll", "nosuch", "--vary", "rider.mass_kg=70:90:2"],
    "a terrain parameter nan": ["--roll", "root:at_m=nan", "--vary", "rider.mass_kg=70:90:2"],
    "a missing terrain CSV": ["--roll", "missing.csv", "--vary", "rider.mass_kg=70:90:2"],
    "an empty terrain CSV": ["--roll", "empty.csv", "--vary", "rider.mass_kg=70:90:2"],
    "a FIFO as the terrain": ["--roll", "fifo", "--vary", "rider.mass_kg=70:90:2"],
    "a device as the terrain": ["--roll", "/dev/zero", "--vary", "rider.mass_kg=70:90:2"],
    "a common --set nan": ["--roll", "root:at_m=0.4", "--vary", "rider.mass_kg=70:90:2", "--set", "bike.frame_mass_kg=nan"],
    "a point varied as a number": ["--roll", "root:at_m=0.4", "--vary", "rider.com_mm=60:80:2"],
    "a word varied as a number": ["--roll", "root:at_m=0.4", "--vary", "fork:fork.spring.model=1:2:2"],
    "a frame key of a chart bike": ["--roll", "root:at_m=0.4", "--vary", "bike.head_angle_deg=63:66:2"],
}


@pytest.mark.parametrize("case", list(REFUSED))
def test_a_sweep_whose_common_part_is_bad_is_refused_before_any_work(case, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    _special_files(tmp_path)
    status = main(["sweep", "trail", *REFUSED[case], "--speed", "5", "--duration", "0.2", "--quiet", "--out", "sw"])
    err = capsys.readouterr().err
    assert status == 2, (case, err)
    _check(status, err, tmp_path / "sw")

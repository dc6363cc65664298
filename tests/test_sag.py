"""``mtbmj sag`` / ``mtbmj.solve_sag``: the pressure or preload found gives the asked sag, in the
static balance (against the air and coil formulas written out here), the band its Coulomb friction
lets the fork rest in (|F(x) - m g| <= F_c, solved here on those formulas), the load taken from
the rider inputs (the front share of rider and bike less the wheel, written out here), and a drop
of the written file, run as the command says, comes to rest inside the band."""
import json
import math
import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

import mtbmj
from mtbmj import cli
from mtbmj.config import load
from mtbmj.errors import ConfigError

PSI = 6894.757293168
P_ATM = 101325.0
G = 9.81


def air_force(c, psi, x):
    """The air spring at compression x (m) > 0 with its transfer port at full extension: both
    chambers sealed from p + p_atm there, A (p + p_atm) [(V_p / (V_p - A x))^n - (V_m / (V_m + A x))^n];
    without a negative chamber A [(p + p_atm) (V_p / (V_p - A x))^n - p_atm]."""
    a = math.pi * (c["fork.spring.piston_diameter_mm"] * 1e-3) ** 2 / 4
    vp = (c["fork.spring.air_volume_cm3"] - c["fork.spring.tokens"] * c["fork.spring.token_volume_cm3"]) * 1e-6
    vm = c["fork.spring.negative_volume_cm3"] * 1e-6
    n, p = c["fork.spring.polytropic_index"], psi * PSI
    assert c["fork.spring.transfer_port_mm"] == 0.0
    if vm == 0.0:
        return a * ((p + P_ATM) * (vp / (vp - a * x)) ** n - P_ATM)
    return a * (p + P_ATM) * ((vp / (vp - a * x)) ** n - (vm / (vm + a * x)) ** n)


def progressive_force(c, preload, x):
    """A preloaded coil past the top-out spring's reach: P + k x + c x^3 (x in m)."""
    return preload + c["fork.spring.progressive_rate_N_per_mm"] * 1e3 * x + \
        c["fork.spring.progressive_cubic_N_per_mm3"] * 1e9 * x ** 3


def band(force, weight, coulomb, sag):
    """(x_low, x_high) in mm: where force(x) = weight -/+ coulomb, either side of the sag (m)."""
    return (brentq(lambda x: force(x) - (weight - coulomb), 1e-9, sag, xtol=1e-14) * 1e3,
            brentq(lambda x: force(x) - (weight + coulomb), sag, 0.110, xtol=1e-14) * 1e3)


def front_load(rider, bike, share, wheel):
    return share / 100 * (rider + bike) - wheel


def printed_band(line):
    found = re.search(r"anywhere from ([\d.]+) to ([\d.]+) mm", line)
    return found.group(1), found.group(2)


def run_printed_drop(printed, tmp_path, monkeypatch, capsys):
    """Run the ``mtbmj drop ...`` the sag line tells the user to run, from where sag ran; its summary."""
    command = printed.split("run it with: ", 1)[1].strip()
    argv = shlex.split(command)
    assert argv[:2] == ["mtbmj", "drop"]
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv[1:] + ["--out", "dropped"]) == 0, capsys.readouterr().err
    capsys.readouterr()
    return json.loads((tmp_path / "dropped" / "summary.json").read_text())


def test_air_pressure_balances_the_load_on_the_formula():
    """Negative chamber off: A [(p + p_atm) (V / (V - A x))^n - p_atm] = m g at the sag, for random
    loads and sags (the top-out spring is free there)."""
    rng = np.random.default_rng(160)
    for load_kg, sag_percent in zip(rng.uniform(45, 95, 5), rng.uniform(15, 35, 5)):
        setting = mtbmj.solve_sag("air120", float(load_kg), float(sag_percent),
                                  {"fork.spring.negative_volume_cm3": 0.0})
        c = setting.config
        a = math.pi * (c["fork.spring.piston_diameter_mm"] * 1e-3) ** 2 / 4
        x = sag_percent / 100 * c["fork.travel_mm"] * 1e-3
        p = setting.value * PSI
        assert air_force(c, setting.value, x) == pytest.approx(load_kg * G, rel=1e-9)
        assert x > a * p / (c["fork.spring.top_out_rate_N_per_mm"] * 1e3)  # top-out free at the sag
        assert c["sled.body_mass_kg"] == pytest.approx(load_kg)


def test_linear_coil_preload_and_band_in_closed_form():
    """A linear coil with preload P and rate k: P = m g - k x_sag; with Coulomb friction F_c the
    fork rests anywhere in x_sag -/+ F_c / k; without friction the band is the sag itself."""
    rng = np.random.default_rng(37)
    for _ in range(4):
        load_kg, sag_percent = float(rng.uniform(50, 90)), float(rng.uniform(18, 30))
        rate, coulomb = float(rng.uniform(6, 12)), float(rng.uniform(15, 45))
        sets = {"fork.spring.model": "linear", "fork.spring.rate_N_per_mm": rate,
                "fork.friction.coulomb_N": coulomb}
        setting = mtbmj.solve_sag("S12", load_kg, sag_percent, sets)
        sag_mm = sag_percent / 100 * 120.0
        preload = load_kg * G - rate * sag_mm
        assert setting.value == pytest.approx(preload, rel=1e-9)
        assert preload / 35.3 < sag_mm - coulomb / rate  # the top-out spring is free over the band
        assert setting.holding_N == coulomb
        assert setting.rest_low_mm == pytest.approx(sag_mm - coulomb / rate, abs=1e-7)
        assert setting.rest_high_mm == pytest.approx(sag_mm + coulomb / rate, abs=1e-7)
        line = setting.line()
        assert printed_band(line) == (f"{sag_mm - coulomb / rate:.1f}", f"{sag_mm + coulomb / rate:.1f}")
        assert f"{coulomb / rate:.1f} mm less to {coulomb / rate:.1f} mm more than the sag" in line
        bare = mtbmj.solve_sag("S12", load_kg, sag_percent, {**sets, "fork.friction.model": "none"})
        assert bare.value == pytest.approx(preload, rel=1e-9)
        assert bare.holding_N == 0.0 and bare.rest_low_mm == bare.rest_high_mm == pytest.approx(sag_mm)
        assert "friction" not in bare.line()


def test_air_band_on_the_formula():
    """air120 (negative chamber on, Coulomb 34.2 N): the band's ends are where the air formula
    carries m g -/+ F_c."""
    rng = np.random.default_rng(6)
    for load_kg, sag_percent in zip(rng.uniform(35, 90, 4), rng.uniform(15, 30, 4)):
        setting = mtbmj.solve_sag("air120", float(load_kg), float(sag_percent))
        c = setting.config
        sag = sag_percent / 100 * 0.120
        assert air_force(c, setting.value, sag) == pytest.approx(load_kg * G, rel=1e-9)
        assert c["fork.friction.model"] == "coulomb" and setting.holding_N == c["fork.friction.coulomb_N"]
        low, high = band(lambda x: air_force(c, setting.value, x), load_kg * G, c["fork.friction.coulomb_N"], sag)
        assert (setting.rest_low_mm, setting.rest_high_mm) == (pytest.approx(low, abs=1e-7),
                                                               pytest.approx(high, abs=1e-7))


def test_the_bands_docs_air_quotes():
    """docs/air.md: air120 at 20 % under 35 and 70 kg, the pressure and the band."""
    said = " ".join((Path(__file__).parents[1] / "docs" / "air.md").read_text().split())
    for load_kg in (35.0, 70.0):
        setting = mtbmj.solve_sag("air120", load_kg, 20.0)
        c = setting.config
        assert air_force(c, setting.value, 0.024) == pytest.approx(load_kg * G, rel=1e-9)
        low, high = band(lambda x: air_force(c, setting.value, x), load_kg * G, c["fork.friction.coulomb_N"], 0.024)
        assert f"under {load_kg:g} kg ({setting.value:.1f} psi)" in said
        assert f"{low:.1f} to {high:.1f} mm" in said


@pytest.mark.parametrize("preset,key", [("air120", "fork.spring.air_pressure_psi"), ("S12", "fork.spring.preload_N")])
def test_written_config_rests_inside_the_band(tmp_path, capsys, monkeypatch, preset, key):
    rng = np.random.default_rng(16 if preset == "air120" else 61)
    load_kg, sag_percent = float(rng.uniform(50, 80)), float(rng.uniform(18, 28))
    out = tmp_path / "sag"
    assert cli.main(["sag", preset, "--load-kg", f"{load_kg}", "--sag-percent", f"{sag_percent}",
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    written = load(out / "config.toml")
    assert key in written.values and f"{written[key]:.1f}" in printed
    assert written["sled.body_mass_kg"] == load_kg
    sag = sag_percent / 100 * 0.120
    if preset == "air120":
        def force(x):
            return air_force(written, written[key], x)
    else:
        def force(x):
            return progressive_force(written, written[key], x)
    assert force(sag) == pytest.approx(load_kg * G, rel=1e-9)
    low, high = band(force, load_kg * G, written["fork.friction.coulomb_N"], sag)
    if preset == "S12":
        assert written[key] / written["fork.spring.top_out_rate_N_per_mm"] < low  # the top-out spring is free
    assert printed_band(printed) == (f"{low:.1f}", f"{high:.1f}")
    summary = run_printed_drop(printed, tmp_path, monkeypatch, capsys)
    assert summary["at_rest"]
    assert low <= summary["rest_mm"]["fork"] <= high


RIDER = ["--set", "sled.rider_mass_kg=78", "--set", "sled.bike_mass_kg=15", "--set", "sled.front_share_percent=60"]


def test_the_issues_mix_is_refused_in_one_line(tmp_path, capsys):
    """Issue 37 item 6: --load-kg beside the rider inputs was solved for the --load-kg and written
    with both, which the drop refused."""
    out = tmp_path / "s"
    assert cli.main(["sag", "air120", "--load-kg", "35", "--sag-percent", "20", *RIDER, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--load-kg" in err[0] and "sled.rider_mass_kg" in err[0] and "two ways" in err[0]
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_the_rider_inputs_set_the_load_and_the_drop_runs_it(tmp_path, capsys, monkeypatch):
    """The load the rider inputs give, 0.60 x (78 + 15) - 2.3 = 53.5 kg, is the one solved for,
    written as the rider inputs, run by the command the line names, and rested inside the band;
    docs/air.md quotes this run."""
    out = tmp_path / "s"
    assert cli.main(["sag", "air120", "--sag-percent", "20", *RIDER, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    load_kg = front_load(78.0, 15.0, 60.0, 2.3)
    written = load(out / "config.toml")
    assert written["sled.body_mass_kg"] == pytest.approx(load_kg, rel=1e-12)
    assert (written["sled.rider_mass_kg"], written["sled.bike_mass_kg"], written["sled.front_share_percent"]) == \
        (78.0, 15.0, 60.0)
    psi = written["fork.spring.air_pressure_psi"]
    assert air_force(written, psi, 0.024) == pytest.approx(load_kg * G, rel=1e-9)
    low, high = band(lambda x: air_force(written, psi, x), load_kg * G, written["fork.friction.coulomb_N"], 0.024)
    assert printed_band(printed) == (f"{low:.1f}", f"{high:.1f}")
    assert f"under {load_kg:g} kg (60 % of the 78 kg rider and 15 kg bike" in printed
    summary = run_printed_drop(printed, tmp_path, monkeypatch, capsys)
    rest = summary["rest_mm"]["fork"]
    assert summary["at_rest"] and low <= rest <= high
    ran = load(tmp_path / "dropped" / "config.toml")
    assert ran["sled.body_mass_kg"] == pytest.approx(load_kg, rel=1e-12)
    doc = (Path(__file__).parents[1] / "docs" / "air.md").read_text()
    said = " ".join(doc.split())
    assert f"{psi:.1f} psi" in said and f"{low:.1f} to {high:.1f} mm" in said and f"at {rest:.1f} mm" in said


def test_other_ways_to_give_the_load(tmp_path):
    """--set sled.body_mass_kg alone is the load; beside --load-kg it is refused; a file's rider
    inputs are the load without --load-kg (written as the inputs, the body mass derived again),
    and --load-kg replaces them as --set sled.body_mass_kg would."""
    by_set = mtbmj.solve_sag("air120", None, 20.0, {"sled.body_mass_kg": 61.0})
    assert by_set.load_kg == 61.0 and by_set.written["sled.body_mass_kg"] == 61.0
    with pytest.raises(ConfigError, match="--load-kg and --set sled.body_mass_kg: the load given two ways"):
        mtbmj.solve_sag("air120", 61.0, 20.0, {"sled.body_mass_kg": 61.0})
    with pytest.raises(ConfigError, match="--load-kg: missing"):
        mtbmj.solve_sag("air120", None, 20.0)
    source = tmp_path / "rider.toml"
    source.write_text('base = "air120"\n[sled]\nrider_mass_kg = 70.0\nbike_mass_kg = 14.0\n'
                      'front_share_percent = 55.0\nwheel_mass_kg = 2.0\n')
    setting = mtbmj.solve_sag(str(source), None, 22.0)
    assert setting.load_kg == pytest.approx(front_load(70.0, 14.0, 55.0, 2.0), rel=1e-12)
    setting.write(tmp_path / "from-file")
    again = load(tmp_path / "from-file" / "config.toml")
    assert again["sled.body_mass_kg"] == pytest.approx(front_load(70.0, 14.0, 55.0, 2.0), rel=1e-12)
    assert again["sled.rider_mass_kg"] == 70.0
    replaced = mtbmj.solve_sag(str(source), 40.0, 22.0)
    assert "in place of the rider inputs of rider" in replaced.line()
    replaced.write(tmp_path / "replaced")
    again = load(tmp_path / "replaced" / "config.toml")
    assert again["sled.body_mass_kg"] == 40.0 and "sled.rider_mass_kg" not in again.values


def test_a_file_config_is_written_whole(tmp_path):
    source = tmp_path / "mine.toml"
    source.write_text('base = "air120"\n[fork.spring]\ntokens = 2.0\n')
    setting = mtbmj.solve_sag(str(source), 75.0, 20.0)
    setting.write(tmp_path / "out")
    again = load(tmp_path / "out" / "config.toml")
    assert again["fork.spring.tokens"] == 2.0
    assert again["fork.spring.air_pressure_psi"] == pytest.approx(setting.value)


@pytest.mark.parametrize("args,needle", [
    (["air120", "--load-kg", "-5", "--sag-percent", "20"], "--load-kg"),
    (["air120", "--load-kg", "70", "--sag-percent", "120"], "--sag-percent"),
    (["air120", "--load-kg", "70", "--sag-percent", "0.5"], "--sag-percent"),
    (["S12", "--load-kg", "60", "--sag-percent", "80"], "--sag-percent"),
    (["S1", "--load-kg", "60", "--sag-percent", "25"], "fork.spring.preload"),  # no top-out spring
    (["air120", "--load-kg", "70", "--sag-percent", "20", "--set", "fork.spring.tokens=30"], "fork.spring.tokens"),
    (["air120", "--sag-percent", "20"], "--load-kg: missing"),
    (["air120", "--sag-percent", "20", "--set", "sled.rider_mass_kg=78"], "sled.bike_mass_kg"),
    (["air120", "--load-kg", "70", "--sag-percent", "20", "--set", "sled.front_share_percent=60"],
     "--load-kg and --set sled.front_share_percent"),
    (["air120", "--load-kg", "70", "--sag-percent", "20", "--set", "sled.body_mass_kg=70"],
     "--load-kg and --set sled.body_mass_kg"),
    # a bike without --bike was "trail: unknown preset (known: S1, ...)", a preset it is
    (["trail", "--load-kg", "70", "--sag-percent", "25"],
     "trail: is a bike: give --bike with --front-sag-percent and --rear-sag-percent"),
    (["trail", "--front-sag-percent", "20", "--rear-sag-percent", "30"], "trail: is a bike: give --bike"),
    # --bike with the fork's one sag named what to give, not what was given wrongly
    (["trail", "--bike", "--sag-percent", "30"], "--sag-percent: not with --bike"),
])
def test_bad_sag_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, args, needle):
    out = tmp_path / "sag"
    assert cli.main(["sag", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]
    assert not out.exists()


def test_python_refusal_is_a_config_error():
    with pytest.raises(ConfigError, match="--load-kg"):
        mtbmj.solve_sag("air120", float("nan"), 20.0)

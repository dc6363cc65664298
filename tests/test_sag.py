"""``mtbmj sag`` / ``mtbmj.solve_sag``: the pressure or preload found gives the asked sag, in the
static balance (against the air formula written out here) and in a drop run to rest."""
import math

import numpy as np
import pytest

import mtbmj
from mtbmj import cli
from mtbmj.config import load
from mtbmj.errors import ConfigError

PSI = 6894.757293168
P_ATM = 101325.0


def test_air_pressure_balances_the_load_on_the_formula():
    """Negative chamber off: A [(p + p_atm) (V / (V - A x))^n - p_atm] = m g at the sag, for random
    loads and sags (the top-out spring is free there)."""
    rng = np.random.default_rng(160)
    for load_kg, sag_percent in zip(rng.uniform(45, 95, 5), rng.uniform(15, 35, 5)):
        setting = mtbmj.solve_sag("air120", float(load_kg), float(sag_percent),
                                  {"fork.spring.negative_volume_cm3": 0.0})
        c = setting.config
        a = math.pi * (c["fork.spring.piston_diameter_mm"] * 1e-3) ** 2 / 4
        v = (c["fork.spring.air_volume_cm3"] - c["fork.spring.tokens"] * c["fork.spring.token_volume_cm3"]) * 1e-6
        x = sag_percent / 100 * c["fork.travel_mm"] * 1e-3
        p = setting.value * PSI
        force = a * ((p + P_ATM) * (v / (v - a * x)) ** c["fork.spring.polytropic_index"] - P_ATM)
        assert force == pytest.approx(load_kg * 9.81, rel=1e-9)
        assert x > a * p / (c["fork.spring.top_out_rate_N_per_mm"] * 1e3)  # top-out free at the sag
        assert c["sled.body_mass_kg"] == pytest.approx(load_kg)


@pytest.mark.parametrize("preset,key", [("air120", "fork.spring.air_pressure_psi"), ("S12", "fork.spring.preload_N")])
def test_written_config_rests_at_the_asked_sag(tmp_path, capsys, preset, key):
    rng = np.random.default_rng(16 if preset == "air120" else 61)
    load_kg, sag_percent = float(rng.uniform(50, 80)), float(rng.uniform(18, 28))
    out = tmp_path / "sag"
    assert cli.main(["sag", preset, "--load-kg", f"{load_kg}", "--sag-percent", f"{sag_percent}",
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    written = load(out / "config.toml")
    assert key in written.values and f"{written[key]:.1f}" in printed
    result = mtbmj.run_drop(str(out / "config.toml"), duration=3.0)
    assert result.summary["at_rest"]
    travel = written["fork.travel_mm"]
    assert result.summary["rest_mm"]["fork"] == pytest.approx(sag_percent / 100 * travel, abs=1.0)


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

"""``tire.pressure_psi``: the tire's rates from its inflation pressure (pressure over the contact
patch, anchored at 62 N/mm and 25 psi) and the sourced dynamic/static ratios, in both engines."""
import numpy as np
import pytest

import mtbmj
from mtbmj import cli, compose
from mtbmj.config import load
from mtbmj.errors import ConfigError


def test_rates_scale_with_the_gauge_pressure_and_keep_the_sourced_ratios():
    rng = np.random.default_rng(1603)
    for psi in rng.uniform(15.0, 25.0, 20):
        setup = compose.setup(load("S12", {"tire.pressure_psi": float(psi)}))
        static = 62.0 * psi / 25.0  # N/mm: k(p) = k_ref p / p_ref
        assert setup.tire.impact.rate == pytest.approx(1.38 * static * 1e3, rel=1e-12)
        assert setup.tire.in_contact.rate == pytest.approx(1.19 * static * 1e3, rel=1e-12)
        assert setup.tire.impact.damping == load("S12")["tire.impact_damping_N_s_per_m"]
    s14 = compose.setup(load("S14", {"tire.pressure_psi": 20.0}))
    assert s14.tire.impact.rate == pytest.approx(62.0 * 20.0 / 25.0 * 1e3, rel=1e-12)  # static values


@pytest.mark.parametrize("engine", ["mujoco", "ode"])
def test_resting_tire_deflection_is_the_weight_over_the_pressure_rate(engine):
    rng = np.random.default_rng(16 if engine == "mujoco" else 61)
    psi = float(rng.uniform(15.0, 25.0))
    cfg = load("air120", {"tire.pressure_psi": psi, "tire.model": "impact"})
    result = mtbmj.run_drop(cfg, engine, duration=2.0)
    weight = (cfg["sled.body_mass_kg"] + cfg["sled.wheel_mass_kg"]) * cfg["sled.gravity_m_per_s2"]
    rate = 1.38 * 62.0 * psi / 25.0  # N/mm
    assert result.summary["at_rest"]
    assert result.summary["rest_mm"]["tire"] == pytest.approx(weight / rate, abs=0.05)


def test_softer_tire_deflects_more_on_the_drop():
    peaks = [mtbmj.run_drop("air120", overrides={"tire.pressure_psi": p}, duration=0.25).summary["max_tire_mm"]
             for p in (16.0, 20.0, 24.0)]
    assert peaks[0] > peaks[1] > peaks[2], peaks


@pytest.mark.parametrize("psi", [0.0, -3.0, -0.0])
def test_a_tire_without_air_is_refused(psi, tmp_path, capsys):
    with pytest.raises(ConfigError, match=r"tire\.pressure_psi"):
        compose.setup(load("S12", {"tire.pressure_psi": psi}))
    out = tmp_path / "out"
    assert cli.main(["drop", "S12", "--set", f"tire.pressure_psi={psi}", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "tire.pressure_psi" in err[0]
    assert not out.exists()


@pytest.mark.parametrize("psi", [14.9, 25.5, 26.0, 30.0, 35.0])
def test_pressures_riders_run_outside_the_measured_range_run_with_a_warning(psi, tmp_path, capsys):
    """Riders run about 15-35 psi; the relation was measured at 15-25 psi (issue 23): outside it the
    rates are extrapolated by the same proportionality, and the run says so on one line."""
    with pytest.warns(UserWarning, match=r"tire\.pressure_psi = .* outside 15-25 psi"):
        setup = compose.setup(load("S12", {"tire.pressure_psi": psi}))
    assert setup.tire.impact.rate == pytest.approx(1.38 * 62.0 * psi / 25.0 * 1e3, rel=1e-12)
    out = tmp_path / "out"
    assert cli.main(["drop", "S12", "--engine", "fast", "--quiet", "--duration", "0.05", "--set",
                     f"tire.pressure_psi={psi}", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mtbmj: warning: tire.pressure_psi = ") and "extrapolated" in err[0]
    assert (out / "summary.json").is_file()

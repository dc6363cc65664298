"""The air spring (``fork.spring.model = "air"``): its law against the polytropic formula computed
here, its compiled form, static sag on both engines, the effect of volume spacers, the engines
against each other, and the configurations it refuses."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mtbmj.controllers import AirSpring, TopOutSpring
from mtbmj.validation import crosscheck
from scipy.integrate import quad
from scipy.optimize import brentq

import mtbmj
from mtbmj import compose
from mtbmj.config import load, preset_names
from mtbmj.errors import ConfigError

PSI = 6894.757293168
P_ATM = 101325.0
G = 9.81


def formula(x, gauge_psi, diameter_mm, volume_cm3, n):
    """F(x) = A [(p + p_atm) (V / (V - A x))^n - p_atm], written out from the issue, SI."""
    a = math.pi * (diameter_mm * 1e-3) ** 2 / 4
    v = volume_cm3 * 1e-6
    return a * ((gauge_psi * PSI + P_ATM) * (v / (v - a * x)) ** n - P_ATM)


air_params = st.fixed_dictionaries({
    "gauge_psi": st.floats(20.0, 200.0),
    "diameter_mm": st.floats(25.0, 36.0),
    "volume_cm3": st.floats(130.0, 250.0),
    "n": st.floats(1.0, 1.4),
    "negative_cm3": st.floats(2.0, 80.0),
    "port_mm": st.floats(0.0, 8.0),
})


def _law(p, negative=True, limit=0.1):
    a = math.pi * (p["diameter_mm"] * 1e-3) ** 2 / 4
    return AirSpring(a, p["gauge_psi"] * PSI, p["volume_cm3"] * 1e-6, p["n"],
                     p["negative_cm3"] * 1e-6 if negative else 0.0, p["port_mm"] * 1e-3, limit)


# ------------------------------------------------------------------------------------------ law
@settings(max_examples=60, deadline=None)
@given(air_params, st.floats(-0.02, 0.099))
def test_positive_chamber_is_the_polytropic_formula(p, x):
    law = _law(p, negative=False)
    expected = formula(x, p["gauge_psi"], p["diameter_mm"], p["volume_cm3"], p["n"])
    assert law.force(x, 0.3) == pytest.approx(expected, rel=1e-12)


@settings(max_examples=60, deadline=None)
@given(air_params, st.floats(0.0, 0.099))
def test_negative_chamber_cancels_above_the_port_and_subtracts_below(p, x):
    """Both chambers at p + p_atm at the port; each polytropic from there (Boyle-Mariotte with n)."""
    law = _law(p)
    a, port = law.area, p["port_mm"] * 1e-3
    p0 = p["gauge_psi"] * PSI + P_ATM
    if x <= port:
        assert law.force(x, 0.0) == 0.0 or x == port
        return
    vp = p["volume_cm3"] * 1e-6 - a * port  # positive chamber when the port closes
    vm = p["negative_cm3"] * 1e-6 + a * port
    positive = p0 * (vp / (vp - a * (x - port))) ** p["n"]
    negative = p0 * (vm / (vm + a * (x - port))) ** p["n"]
    assert law.force(x, 0.0) == pytest.approx(a * (positive - negative), rel=1e-10, abs=1e-9)


@settings(max_examples=30, deadline=None)
@given(air_params)
def test_force_is_continuous_at_the_port_and_the_limit(p):
    law = _law(p)
    for at in (p["port_mm"] * 1e-3, law.limit):
        below, above = law.force(at - 1e-9, 0.0), law.force(at + 1e-9, 0.0)
        assert abs(above - below) <= 2.5e-9 * law.air_rate(at) + 1e-9  # no jump: only the slope times 2 nm
    # past the limit the curve is its tangent: slope equal, still finite far beyond
    h = 1e-6
    slope = (law.force(law.limit + 2 * h, 0.0) - law.force(law.limit + h, 0.0)) / h
    assert slope == pytest.approx(law.air_rate(law.limit), rel=1e-5)
    assert math.isfinite(law.force(1.0, 0.0))


@settings(max_examples=30, deadline=None)
@given(air_params, st.floats(-0.02, 0.13), st.booleans())
def test_energy_is_the_integral_of_the_force(p, x, negative):
    law = _law(p, negative)
    points = [q for q in (law.port, law.limit) if min(0.0, x) < q < max(0.0, x)]
    work, _ = quad(lambda s: law.force(s, 0.0), 0.0, x, points=points or None, epsabs=1e-10, epsrel=1e-10)
    assert law.energy(x) == pytest.approx(work, rel=1e-7, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(air_params, st.integers(0, 3), st.floats(10.0, 40.0), st.booleans())
def test_compiled_air_law_equals_the_python_law(p, tokens, top_rate, negative):
    compiled = pytest.importorskip("mtbmj.controllers.compiled")
    if not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    from mtbmj.controllers import ForkLaw, LinearDamper, NoFriction

    air = _law(p, negative)
    preload = max(0.0, air.force(0.0, 0.0))
    spring = TopOutSpring(AirSpring(air.area, air.pressure, air.volume, air.index, air.negative_volume, air.port,
                                    air.limit, preload), top_rate * 1e3, preload) if tokens % 2 else air
    law = ForkLaw(spring, LinearDamper(200.0), NoFriction())
    ints, floats = compiled.flatten(law)
    P = np.zeros(compiled.FLOAT_WIDTH)
    P[: len(floats)] = floats
    I = np.asarray(ints, dtype=np.int64)
    rng = np.random.default_rng(tokens)
    for x in np.concatenate([rng.uniform(-0.03, 0.14, 40), [0.0, air.port, air.limit]]):
        v = float(rng.uniform(-2, 2))
        assert compiled.fork_force(I, P, x, v, 0.0) == pytest.approx(law.force(x, v), rel=1e-13, abs=1e-10)


# ------------------------------------------------------------------------------------ configuration
def _sag_config(gauge_psi, tokens, **more):
    values = {"fork.spring.air_pressure_psi": gauge_psi, "fork.spring.tokens": tokens,
              "fork.spring.negative_volume_cm3": 0.0, "fork.friction.model": "none",
              "fork.damper.model": "linear", "fork.damper.coefficient_N_s_per_m": 2500.0}
    values.update(more)
    return load("air120", values)


def test_air_preset_is_listed_and_every_air_value_says_where_it_comes_from():
    assert "air120" in preset_names()
    from importlib import resources

    text = (resources.files("mtbmj.presets") / "air120.toml").read_text()
    keys = [k for k in load("air120").values if k.startswith("fork.spring.") and k in text]
    lines = {line.split("=")[0].strip(): line for line in text.splitlines() if "=" in line}
    for key in keys:
        leaf = key.rsplit(".", 1)[1]
        if leaf in lines and leaf not in ("model",):
            assert any(w in lines[leaf] for w in ("sourced", "assumed", "reference value", "preload", "top-out")), leaf


def test_static_force_function_is_finite_over_the_sampled_range():
    """The timestep rule samples the spring from -20 mm to 1.2 x travel: every value finite."""
    for tokens in (0, 3, 6):
        setup = compose.setup(load("air120", {"fork.spring.tokens": tokens}))
        xs = np.linspace(-0.02, 1.2 * setup.travel + 1e-4, 2001)
        assert all(math.isfinite(setup.fork.spring.force(x, 0.0)) for x in xs)


@pytest.mark.parametrize("engine", ["mujoco", "ode"])
def test_static_sag_is_the_root_of_the_air_formula(engine):
    """Negative chamber off, no friction: at rest F(x) = m_b g with F from the formula above.

    Without the negative chamber the air pushes with A p at full extension, which the top-out
    spring holds (engaged below A p / k_top); the pressures drawn keep the sag beyond that."""
    rng = np.random.default_rng(16)
    for gauge, tokens in zip(rng.uniform(50.0, 80.0, 2), rng.integers(0, 4, 2)):
        cfg = _sag_config(float(gauge), float(tokens))
        volume = cfg["fork.spring.air_volume_cm3"] - tokens * cfg["fork.spring.token_volume_cm3"]
        load_n = cfg["sled.body_mass_kg"] * cfg["sled.gravity_m_per_s2"]
        closed = brentq(lambda x: formula(x, gauge, cfg["fork.spring.piston_diameter_mm"], volume,
                                          cfg["fork.spring.polytropic_index"]) - load_n, 0.0, 0.12)
        at_full_extension = formula(0.0, gauge, cfg["fork.spring.piston_diameter_mm"], volume, 1.0)
        assert closed > at_full_extension / (cfg["fork.spring.top_out_rate_N_per_mm"] * 1e3)
        result = mtbmj.run_drop(cfg, engine, duration=2.5)
        assert result.summary["at_rest"]
        assert result.summary["rest_mm"]["fork"] == pytest.approx(closed * 1e3, abs=0.1)


def test_more_spacers_give_a_shallower_peak_1_on_a_hard_drop():
    peaks = []
    for tokens in (0, 1, 2, 3):
        result = mtbmj.run_drop("air120", overrides={"fork.spring.tokens": tokens, "sled.drop_height_mm": 250.0},
                                duration=0.3)
        peaks.append(result.summary["max_fork_mm"])
    assert all(b < a - 0.5 for a, b in zip(peaks, peaks[1:])), peaks


@pytest.mark.parametrize("gauge,tokens", [(70.0, 0), (100.0, 3), (85.0, 1)])
def test_mujoco_matches_the_reference_across_pressures_and_spacers(gauge, tokens):
    check = crosscheck("air120", 0.1, {"fork.spring.air_pressure_psi": gauge, "fork.spring.tokens": tokens},
                       duration=1.0)
    assert check.passed, check.line()


# ------------------------------------------------------------------------------------- refusals
@pytest.mark.parametrize("overrides,key", [
    ({"fork.spring.air_pressure_psi": -14.7}, "fork.spring.air_pressure_psi"),  # at vacuum (-14.696 psi)
    ({"fork.spring.air_pressure_psi": -14.6}, "fork.spring.air_pressure_psi"),  # a near-vacuum, not a fork setting
    ({"fork.spring.air_pressure_psi": -0.5}, "fork.spring.air_pressure_psi"),
    ({"fork.spring.air_pressure_psi": -30.0}, "fork.spring.air_pressure_psi"),
    ({"fork.spring.tokens": 19.0}, "fork.spring.tokens"),  # 19 x 8 cm3 > 150 cm3
    ({"fork.spring.tokens": 1.5}, "fork.spring.tokens"),
    ({"fork.spring.tokens": 7.0}, "fork.spring.air_volume_cm3"),  # 94 cm3 left, the piston sweeps 96.5
    ({"fork.spring.air_volume_cm3": 90.0, "fork.spring.tokens": 0.0}, "fork.spring.air_volume_cm3"),
    ({"fork.spring.polytropic_index": 1.6}, "fork.spring.polytropic_index"),
    ({"fork.spring.transfer_port_mm": 130.0}, "fork.spring.transfer_port_mm"),
    ({"fork.spring.preload": True}, "fork.spring.preload"),
    ({"fork.spring.top_out": False, "fork.spring.negative_volume_cm3": 0.0}, "fork.spring.top_out"),
])
def test_bad_air_input_names_the_key(overrides, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        compose.setup(load("air120", overrides))


def test_bad_air_input_from_the_command_line_exits_2_and_writes_nothing(tmp_path, capsys):
    from mtbmj import cli

    for setting, key in (("fork.spring.air_pressure_psi=-20", "fork.spring.air_pressure_psi"),
                         ("fork.spring.tokens=30", "fork.spring.tokens"),
                         ("fork.spring.tokens=7", "fork.spring.air_volume_cm3")):
        out = tmp_path / key
        assert cli.main(["drop", "air120", "--set", setting, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and key in err[0]
        assert not out.exists()


# ------------------------------------------------------------------------ sweeps and rolling
def test_a_batched_sweep_varies_pressure_and_spacers_like_single_runs(tmp_path):
    from mtbmj.sweep import read_table, run_sweep

    rng = np.random.default_rng(1606)
    variants = [{"fork.spring.air_pressure_psi": float(p), "fork.spring.tokens": float(t)}
                for p, t in zip(rng.uniform(70, 100, 3), rng.integers(0, 4, 3))]
    run_sweep("air120", variants, tmp_path / "sweep", duration=0.4)
    table = read_table(tmp_path / "sweep")
    assert list(table["status"]) == ["ok"] * 3
    for v in variants:
        row = table[np.isclose(table["fork.spring.air_pressure_psi"], v["fork.spring.air_pressure_psi"])].iloc[0]
        single = mtbmj.run_drop("air120", overrides=v, duration=0.4)
        assert row["fork_peak1_mm"] == pytest.approx(single.summary["events"]["fork"]["peak1"]["value_mm"], abs=1e-6)


def test_rolling_front_end_runs_the_air_law_compiled_as_in_python():
    from mtbmj.rolling.frontend import run_roll

    compiled = run_roll("square_edge", 4.0, "air120", duration=0.6, callback="auto")
    python = run_roll("square_edge", 4.0, "air120", duration=0.6, callback="python")
    assert np.max(np.abs(np.asarray(compiled.signals["fork_mm"]) - np.asarray(python.signals["fork_mm"]))) < 1e-6
    assert np.max(compiled.signals["fork_mm"]) > 10.0  # the edge compresses the fork


@pytest.mark.parametrize("config, setting, key", [
    ("S12", "fork.travel_mm=0.12", "fork.travel_mm"),  # metres typed into a mm key: blamed on the preload before
    ("air120", "fork.spring.air_volume_cm3=1", "fork.spring.air_volume_cm3"),  # blamed on tokens before
    ("air120", "fork.spring.air_pressure_psi=-14.6", "fork.spring.air_pressure_psi"),  # a near-vacuum ran before
])
def test_a_refusal_names_the_key_the_user_set(tmp_path, capsys, config, setting, key):
    from mtbmj import cli

    out = tmp_path / "o"
    assert cli.main(["drop", config, "--set", setting, "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and key in err, err
    assert not out.exists()

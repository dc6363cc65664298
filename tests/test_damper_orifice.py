"""The orifice damper (``fork.damper.model = "orifice"``), the law that landed after the law
library was reorganised (issue 24) and the worked example of docs/laws.md: F = b v + c v |v|, c by
direction. Its values against the closed form written here, its compiled twin, both engines against
the ODE reference, and the configuration keys a user types."""
from __future__ import annotations

import numpy as np
import pytest

import mtbmj
from mtbmj import cli, compose
from mtbmj.controllers import ForkLaw, NoFriction, LinearSpring, OrificeDamper
from mtbmj.drop.crosscheck import crosscheck_all

KEYS = {"fork.damper.model": "orifice", "fork.damper.bleed_N_s_per_m": 300.0,
        "fork.damper.compression_orifice_N_s2_per_m2": 400.0, "fork.damper.rebound_orifice_N_s2_per_m2": 900.0}


def test_the_force_is_the_bleed_plus_the_orifice_by_direction():
    law = OrificeDamper(300.0, 400.0, 900.0)
    assert law.force(2.0) == 300.0 * 2.0 + 400.0 * 2.0 ** 2
    assert law.force(-1.5) == 300.0 * -1.5 - 900.0 * 1.5 ** 2
    assert law.force(0.0) == 0.0
    # continuous with its slope at rest: (F(h) - F(-h)) / 2h -> b, one-sided slopes agree
    h = 1e-7
    assert (law.force(h) - law.force(-h)) / (2 * h) == pytest.approx(300.0, rel=1e-6)
    v = np.linspace(-5.0, 5.0, 1001)
    assert all(law.force(x) * x >= 0.0 for x in v)  # it only dissipates


def test_the_configuration_builds_it_and_the_curve_shows_it(tmp_path):
    setup = compose.setup(mtbmj.load_config("S12", overrides=KEYS))
    assert setup.fork.damper == OrificeDamper(300.0, 400.0, 900.0)
    argv = ["curve", "S12", "--out", str(tmp_path / "curve")]
    for key, value in KEYS.items():
        argv += ["--set", f"{key}={value}"]
    assert cli.main(argv) == 0
    rows = np.genfromtxt(tmp_path / "curve" / "damper_curve.csv", delimiter=",", names=True, skip_header=1)
    v = rows["velocity_mm_per_s"] * 1e-3  # mm/s -> m/s
    assert v.min() < -1.0 and v.max() > 1.0
    assert np.allclose(rows["damper_N"], 300.0 * v + np.where(v >= 0, 400.0, 900.0) * v * np.abs(v))


def test_the_compiled_twin_gives_the_same_forces():
    pytest.importorskip("numba")
    from mtbmj.controllers import compiled

    law = ForkLaw(LinearSpring(8e4), OrificeDamper(300.0, 400.0, 900.0), NoFriction())
    rng = np.random.default_rng(3)
    x, v = rng.uniform(-0.01, 0.15, 500), rng.uniform(-6.0, 6.0, 500)
    compiled_forces = compiled.fork_forces_along(law, x, v, np.zeros(500))
    assert np.array_equal(compiled_forces, [law.force(a, b) for a, b in zip(x, v)])


def test_both_engines_agree_with_the_ode_reference():
    checks = crosscheck_all("S12", ("mujoco", "fast"), overrides=KEYS, duration=0.6)
    for check in checks:
        assert check.passed, check


@pytest.mark.parametrize("key, value", [("fork.damper.rebound_orifice_N_s2_per_m2", "-5"),
                                        ("fork.damper.bleed_N_s_per_m", "nan")])
def test_a_bad_value_is_one_line_naming_the_key(tmp_path, capsys, key, value):
    argv = ["drop", "S12", "--quiet", "--out", str(tmp_path / "out")]
    for k, v in {**KEYS, key: value}.items():
        argv += ["--set", f"{k}={v}"]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0]
    assert not (tmp_path / "out").exists()


def test_a_missing_key_names_the_model_that_needs_it(tmp_path, capsys):
    argv = ["drop", "S12", "--quiet", "--out", str(tmp_path / "out"), "--set", "fork.damper.model=orifice"]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert "fork.damper.bleed_N_s_per_m" in err and "orifice" in err

"""Damper laws that real dampers follow (issue 22): the two-stage (digressive) law, and a damper
fit that says when the friction cannot be told from the hydraulic law instead of inventing it.

The dyno records are peak force against speed made here from closed forms outside the law
library (a log-digressive shim stack, a power law, a blow-off valve, a bilinear damper), each with
30 N of Coulomb friction and 1.5 N of noise, 9 speeds per direction from 25 to 2000 mm/s."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mtbmj import cli

SPEEDS_MM_S = np.array([25, 50, 100, 200, 400, 700, 1000, 1500, 2000.0])
FRICTION_N = 30.0

SHAPES = {  # hydraulic force (N) at speed v (m/s) > 0: (compression, rebound)
    "log_digressive": (lambda v: 2200.0 * 0.12 * np.log1p(v / 0.12), lambda v: 3500.0 * 0.15 * np.log1p(v / 0.15)),
    "power_law": (lambda v: 700.0 * v**0.6, lambda v: 1200.0 * v**0.6),
    "blow_off": (lambda v: np.where(v < 0.3, 1500.0 * v, 450.0 + 300.0 * (v - 0.3)),
                 lambda v: np.where(v < 0.25, 2500.0 * v, 625.0 + 500.0 * (v - 0.25))),
    "bilinear": (lambda v: 600.0 * v, lambda v: 1100.0 * v),
}


def dyno_csv(path, shape, seed=0):
    rng = np.random.default_rng(seed)
    comp, reb = SHAPES[shape]
    rows = []
    for sign, law in ((1, comp), (-1, reb)):
        for speed in SPEEDS_MM_S:
            force = sign * (float(law(speed / 1e3)) + FRICTION_N) + rng.normal(0.0, 1.5)
            rows.append(f"{sign * speed:g},{force:.3f}")
    path.write_text("velocity_mm_per_s,force_N\n" + "\n".join(rows) + "\n")
    return path


def fit(tmp_path, shape, capsys):
    out = tmp_path / shape
    assert cli.main(["fit", "damper", str(dyno_csv(tmp_path / f"{shape}.csv", shape)), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "fit.json").read_text())
    return out, printed, summary


@pytest.mark.parametrize("shape", ["blow_off", "bilinear"])
def test_friction_is_recovered_where_the_record_can_tell_it(tmp_path, capsys, shape):
    out, printed, summary = fit(tmp_path, shape, capsys)
    coulomb = summary["parameter_set"]["fork.friction.coulomb_N"]
    assert coulomb == pytest.approx(FRICTION_N, rel=0.2)
    assert "NOT told" not in printed and summary["warnings"] == []
    assert summary["models"]["digressive"]["friction_check"]["told"] is True
    assert not (out / "fit.toml").read_text().startswith('description = "NOT A CLEAN RESULT')


def test_the_blow_off_damper_is_fitted_by_the_two_stage_law(tmp_path, capsys):
    out, printed, summary = fit(tmp_path, "blow_off", capsys)
    assert summary["chosen"][0] == "digressive"
    values = summary["parameter_set"]
    for key, truth in (("compression_low_N_s_per_m", 1500.0), ("compression_high_N_s_per_m", 300.0),
                       ("compression_knee_mm_per_s", 300.0), ("rebound_low_N_s_per_m", 2500.0),
                       ("rebound_high_N_s_per_m", 500.0), ("rebound_knee_mm_per_s", 250.0)):
        assert values[f"fork.damper.{key}"] == pytest.approx(truth, rel=0.05), key
    assert "95 % interval" in printed


@pytest.mark.parametrize("shape", ["log_digressive", "power_law"])
def test_friction_is_right_or_said_to_be_unknown(tmp_path, capsys, shape):
    """Ordinary digressive dampers: the fit no longer prints 174 N of friction as a fact. Either
    the friction comes out within 20 % of the truth, or the fit says it cannot tell it."""
    out, printed, summary = fit(tmp_path, shape, capsys)
    coulomb = summary["parameter_set"]["fork.friction.coulomb_N"]
    check = summary["models"]["digressive"]["friction_check"]
    if abs(coulomb / FRICTION_N - 1.0) > 0.2:
        assert check["told"] is False
        assert "warning: friction NOT told from the hydraulic law" in printed
        assert (out / "fit.toml").read_text().startswith('description = "NOT A CLEAN RESULT: friction NOT told')
    assert summary["models"]["bilinear"]["rms"] > 2 * summary["models"]["digressive"]["rms"]


def test_the_log_digressive_damper_is_not_given_a_friction_it_cannot_show(tmp_path, capsys):
    _, printed, summary = fit(tmp_path, "log_digressive", capsys)
    assert summary["models"]["digressive"]["friction_check"]["told"] is False  # (97 N sharp, 70 N smooth)


def test_a_fitted_digressive_damper_runs_on_both_engines_alike(tmp_path, capsys):
    out, _, _ = fit(tmp_path, "blow_off", capsys)
    assert cli.main(["crosscheck", str(out / "fit.toml"), "--engines", "mujoco,fast", "--duration", "1.0"]) == 0
    printed = capsys.readouterr().out
    assert printed.count("within the tolerances") == 2 and printed.count("(tol. 0.1 mm)") == 6


def test_a_digressive_configuration_names_its_missing_keys(tmp_path, capsys):
    from helpers import one_line

    one_line(capsys, ["drop", "S12", "--set", "fork.damper.model=digressive", "--out", tmp_path / "o"],
             "fork.damper.compression_low_N_s_per_m", "digressive")


# --- issue 49: the two-stage law reproduces a digressive record with 5 N of noise ----------------------

TRUTH = {"compression_low_N_s_per_m": 3000.0, "compression_high_N_s_per_m": 600.0, "compression_knee_mm_per_s": 150.0,
         "rebound_low_N_s_per_m": 5000.0, "rebound_high_N_s_per_m": 900.0, "rebound_knee_mm_per_s": 120.0}
NOISE_N = 5.0


def two_stage(v_m_s, low, high, knee_m_s):
    """The two-stage force magnitude at speed |v| (written here, not the library's law)."""
    speed = np.abs(v_m_s)
    return np.where(speed < knee_m_s, low * speed, low * knee_m_s + high * (speed - knee_m_s))


def digressive_force(v_m_s, values, coulomb_N):
    comp = two_stage(v_m_s, values["compression_low_N_s_per_m"], values["compression_high_N_s_per_m"],
                     values["compression_knee_mm_per_s"] / 1e3)
    reb = two_stage(v_m_s, values["rebound_low_N_s_per_m"], values["rebound_high_N_s_per_m"],
                    values["rebound_knee_mm_per_s"] / 1e3)
    return np.where(v_m_s > 0, comp, -reb) + coulomb_N * np.sign(v_m_s)


@pytest.mark.slow
def test_a_digressive_record_is_reproduced_within_its_noise(tmp_path, capsys):
    """Records of a two-stage damper with 30 N of Coulomb friction and 5 N of noise, 11 speeds per
    direction from 25 to 2000 mm/s and 4 repeats each, on 5 seeds: the law `fit damper --model
    digressive` writes (read back from fit.json and evaluated by the formula above) misses each
    record by at most 1.2 x the noise RMS, and its 95 % intervals hold the true values: at most 5 of
    the 35 miss (2 expected; more than 5 has a chance below 1 % when the intervals are right)."""
    speeds = np.array([25, 50, 100, 150, 200, 300, 400, 600, 1000, 1500, 2000.0]) / 1e3
    v = np.concatenate([np.repeat(speeds, 4), -np.repeat(speeds, 4)])
    truth = {**{f"fork.damper.{k}": x for k, x in TRUTH.items()}, "fork.friction.coulomb_N": FRICTION_N}
    misses = 0
    for seed in range(5):
        force = digressive_force(v, TRUTH, FRICTION_N) + np.random.default_rng(seed).normal(0.0, NOISE_N, v.size)
        path = tmp_path / f"digressive_{seed}.csv"
        path.write_text("velocity_mm_per_s,force_N\n" + "".join(f"{a * 1e3:g},{b:.4f}\n" for a, b in zip(v, force)))
        out = tmp_path / f"fit_{seed}"
        assert cli.main(["fit", "damper", str(path), "--model", "digressive", "--friction", "coulomb",
                         "--out", str(out)]) == 0
        capsys.readouterr()
        summary = json.loads((out / "fit.json").read_text())
        written = summary["parameter_set"]
        assert written["fork.damper.model"] == "digressive" and written["fork.friction.model"] == "coulomb"
        law = {k: written[f"fork.damper.{k}"] for k in TRUTH}
        rms = float(np.sqrt(np.mean((digressive_force(v, law, written["fork.friction.coulomb_N"]) - force) ** 2)))
        assert rms <= 1.2 * NOISE_N, (seed, rms)
        ci = summary["models"][summary["chosen"][0]]["ci95"]
        misses += sum(not ci[k][0] <= truth[k] <= ci[k][1] for k in truth)
    assert misses <= 5, misses


@pytest.mark.slow
def test_a_friction_law_that_cannot_be_fitted_is_left_out_not_fatal(tmp_path, capsys):
    """Five speeds per direction, one point each (a closed form and the noise draws written out): the
    stiction law, which the fit tries with the two-stage law among the others, ran out of solver
    evaluations, and `fit damper --model digressive --friction coulomb` refused the record ("the
    stiction damper fit did not converge"). A fit that runs out of evaluations is now let finish
    from its best point, and a friction law that still cannot be fitted is left out of the
    comparison instead of ending the fit."""
    speeds = np.array([27.85, 34.92, 53.95, 414.88, 515.86]) / 1e3
    noise = np.array([-5.59, -11.21, -2.92, 7.6, -0.22, 2.04, -1.35, -0.42, 6.33, 3.98])
    values = {"compression_low_N_s_per_m": 11535.27, "compression_high_N_s_per_m": 1551.90,
              "compression_knee_mm_per_s": 54.776, "rebound_low_N_s_per_m": 6135.80,
              "rebound_high_N_s_per_m": 5451.32, "rebound_knee_mm_per_s": 30.815}
    v = np.concatenate([speeds, -speeds])
    force = digressive_force(v, values, 30.0) + noise
    path = tmp_path / "five_speeds.csv"
    path.write_text("velocity_mm_per_s,force_N\n" + "".join(f"{a * 1e3:.2f},{b:.3f}\n" for a, b in zip(v, force)))
    out = tmp_path / "fit"
    assert cli.main(["fit", "damper", str(path), "--model", "digressive", "--friction", "coulomb",
                     "--out", str(out)]) == 0, capsys.readouterr().err
    capsys.readouterr()
    summary = json.loads((out / "fit.json").read_text())
    written = summary["parameter_set"]
    assert written["fork.damper.model"] == "digressive" and written["fork.friction.model"] == "coulomb"
    law = {k: written[f"fork.damper.{k}"] for k in TRUTH}
    rms = float(np.sqrt(np.mean((digressive_force(v, law, written["fork.friction.coulomb_N"]) - force) ** 2)))
    assert rms == pytest.approx(summary["models"][summary["chosen"][0]]["rms"], rel=1e-3)  # the law written
    assert rms < 1.2 * float(np.sqrt(np.mean(noise ** 2)))

"""Model choice that cannot overfit, intervals that cover, and the shipped examples of every fit
kind (`mtbmj fit KIND example`)."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from mtbmj.identify.fitresult import FitResult, hac_covariance, covariance_stderr
from mtbmj.measured.records import write_csv_text
from mtbmj.identify.run import identify


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "mtbmj.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def dyno_points(tmp_path, seed, noise_N, speeds=(50, 100, 150, 250, 400, 600, 800, 1000, 1250, 1500)):
    """The usual dyno output: one peak force per speed and side of a bilinear + Coulomb damper
    with random plausible coefficients."""
    rng = np.random.default_rng(seed)
    c, r, fc = rng.uniform(80, 200), rng.uniform(180, 350), rng.uniform(10, 60)
    v = np.concatenate([np.array(speeds, float), -np.array(speeds, float)])
    f = np.where(v > 0, c, r) * v * 1e-3 + fc * np.sign(v) + rng.normal(0.0, noise_N, v.size)
    path = tmp_path / f"dyno_{seed}.csv"
    path.write_text(write_csv_text({"velocity_mm_per_s": v, "force_N": f}, ["synthetic peak points"]))
    return path


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("noise_N", [5.0, 0.0])
def test_a_table_through_every_point_is_never_chosen(tmp_path, seed, noise_N):
    ident = identify("damper", [dyno_points(tmp_path, seed, noise_N)])
    table = ident.results["table"]
    assert table.saturated and table.n_params >= table.n_points / 2
    assert ident.chosen == ["bilinear"]
    assert any("not compared" in n and "table" in n for n in ident.notes)
    assert all(np.isfinite(r.bic) for r in ident.results.values())


def test_models_the_data_cannot_tell_apart_are_named(tmp_path):
    ident = identify("damper", [dyno_points(tmp_path, 4, 5.0)])
    assert any(n.startswith("the data cannot distinguish") for n in ident.notes)


def test_zero_force_column_is_refused_in_one_line(tmp_path):
    path = tmp_path / "zero.csv"
    v = np.array([50, 100, 200, 400, -50, -100, -200, -400.0])
    path.write_text(write_csv_text({"velocity_mm_per_s": v, "force_N": 0 * v}))
    done = run_cli("fit", "damper", path, "--out", tmp_path / "out")
    assert done.returncode == 2 and "force column is 0 N everywhere" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()


def test_bic_is_finite_for_a_zero_residual():
    r = FitResult("damper", "exact", {}, {}, 0.0, "N", 20, 3)
    assert np.isfinite(r.bic) and np.isfinite(r.aic)
    assert r.bic_with_floor(1e-3) > r.bic


def test_newey_west_covers_a_regression_with_coloured_noise():
    """A straight line fitted through AR(1) noise (rho 0.9): the white-noise standard error is
    far too small, the Newey-West one matches the spread of the slope over many records."""
    rng = np.random.default_rng(0)
    n, rho = 600, 0.9
    x = np.linspace(0, 1, n)
    jac = np.column_stack([np.ones(n), x])
    slopes, se_white, se_hac = [], [], []
    for _ in range(300):
        e = np.empty(n)
        e[0] = rng.normal()
        for i in range(1, n):
            e[i] = rho * e[i - 1] + np.sqrt(1 - rho**2) * rng.normal()
        coef, *_ = np.linalg.lstsq(jac, 2.0 + 3.0 * x + e, rcond=None)
        resid = jac @ coef - (2.0 + 3.0 * x + e)
        slopes.append(coef[1])
        se_white.append(covariance_stderr(jac, resid, 2)[0][1])
        se_hac.append(np.sqrt(hac_covariance(jac, resid, 2)[0][1, 1]))
    spread = float(np.std(slopes))
    assert np.median(se_white) < 0.5 * spread
    assert np.median(se_hac) == pytest.approx(spread, rel=0.25)


@pytest.mark.parametrize("kind", ["spring", "damper", "tire", "drop"])
def test_every_fit_kind_runs_on_its_shipped_example(tmp_path, kind):
    out = tmp_path / kind
    done = run_cli("fit", kind, "example", "--out", out)
    summary = json.loads((out / "fit.json").read_text())
    assert summary["synthetic_data"] is True
    # every example passes its own check (tests/test_shipped_examples.py checks what each finds)
    assert done.returncode == 0, done.stderr
    assert summary["model_check_passed"] is True


def test_shipped_examples_are_what_the_documented_call_writes(tmp_path):
    from mtbmj.identify.examples import FILES, data_dir, write_examples

    written = write_examples(tmp_path)
    assert {p.name for p in written} == {n for k in ("spring", "damper", "tire") for n in FILES[k]}
    for path in written:
        assert path.read_text() == (data_dir() / path.name).read_text(), path.name

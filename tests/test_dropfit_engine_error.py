"""The fast engine's own error in a drop fit: measured by the same equations stepped finer
(``engine_fast.run(refine=...)``, ``dropfit.OTHER_ENGINE["fast"]``), checked against the scipy ODE
reference, which integrates those equations with an implicit adaptive solver and shares no
stepping code with the fast engine."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")

from mtbmj.drop import chain, engine_fast  # noqa: E402
from mtbmj.drop.chain import resolve  # noqa: E402
from mtbmj.drop.run import run_drop  # noqa: E402
from mtbmj.identify import dropfit  # noqa: E402
from mtbmj.identify.drop_synthetic import make_drop_record  # noqa: E402

# S12 away from its defaults (a fit's optimum is seldom the preset)
VALUES = {"fork.spring.preload_N": 0.88, "fork.spring.top_out_rate_N_per_mm": 1.2, "fork.friction.coulomb_N": 1.1,
          "tire.impact_rate_N_per_mm": 0.93}


def overrides():
    cfg = resolve("S12")
    return cfg, {k: cfg[k] * f for k, f in VALUES.items()}


def test_refined_run_bounds_the_error_the_reference_sees():
    """The fast run's error as the fit estimates it (the refined run's difference, scaled) covers
    its difference from the ODE reference without overstating it more than threefold: the fast
    run's discretisation is all that separates it from the reference's equations."""
    cfg, over = overrides()
    _, setup = chain.prepare(cfg, over, 1.0, warn=False)
    fast = engine_fast.run(setup, 1.0)
    refined = engine_fast.run(setup, 1.0, refine=dropfit.REFINE_FAST)
    ode = run_drop(cfg, "ode", overrides=over, duration=1.0).trace
    assert np.array_equal(engine_fast.run(setup, 1.0).fork, fast.fork)  # refine=1 is the engine as it is
    for name in ("sled", "fork"):
        f, r, o = (getattr(t, name) for t in (fast, refined, ode))
        seen_by_reference = np.max(np.abs(o - f))
        estimated = dropfit.ERROR_SCALE["fast"] * np.max(np.abs(r - f))
        assert seen_by_reference > 1e-7  # there is an error to measure (m)
        assert 0.9 * seen_by_reference <= estimated <= 3.0 * seen_by_reference, name


@pytest.fixture(scope="module")
def record():
    cfg = resolve("S12")
    truth = {k: round(cfg[k] * f, 4) for k, f in VALUES.items()}
    return truth, make_drop_record("S12", truth, duration=0.8, engine="ode", seed=5)


def test_fast_fit_intervals_as_with_the_reference_run(record, monkeypatch):
    """The fast fit with its refined run at the optimum gives the intervals the same fit gives with
    the ODE reference's run there (its former, 5-10x dearer measure), up to the estimate's margin
    and never narrower, and engine shifts of the reference's sign and size."""
    truth, rec = record
    fit = dropfit.fit_drop(rec, "S12", free=list(truth), engine="fast", workers=1)
    assert fit.extra["engine_error_run"] == "fast_refined"
    assert dropfit.error_note(fit.extra) == "against the fast engine stepped twice as finely at the optimum, its difference doubled"
    monkeypatch.setitem(dropfit.OTHER_ENGINE, "fast", "ode")
    monkeypatch.setitem(dropfit.ERROR_SCALE, "fast", 1.0)
    with_ode = dropfit.fit_drop(rec, "S12", free=list(truth), engine="fast", workers=1)
    for key in truth:
        assert fit.values[key] == with_ode.values[key]  # the engine error moves the intervals only
        lo, hi = fit.extra["ci95"][key]
        lo_ode, hi_ode = with_ode.extra["ci95"][key]
        # never narrower than with the reference's run, and at most 5 % wider (the estimate's margin)
        assert hi_ode - lo_ode <= hi - lo <= 1.05 * (hi_ode - lo_ode), key
        assert lo <= truth[key] <= hi, key
    shift = np.array([fit.extra["engine_error_shift"][k] for k in truth])
    shift_ode = np.array([with_ode.extra["engine_error_shift"][k] for k in truth])
    assert np.all(shift != 0.0)
    # per parameter, relative to its value: those within a tenth of the largest have the reference's
    # sign and between 0.8 and 3 times its size (the reference carries its own tolerance, which
    # shows on the smallest)
    scale = np.abs(np.array(list(truth.values())))
    big = np.abs(shift_ode) / scale >= 0.1 * np.max(np.abs(shift_ode) / scale)
    assert big.any()
    ratio = shift[big] / shift_ode[big]
    assert np.all((ratio >= 0.8) & (ratio <= 3.0)), ratio


def test_mujoco_fit_intervals_as_with_the_reference_run(record, monkeypatch):
    """The MuJoCo fit's own error measured against the refined fast run gives the intervals it
    gives measured against the ODE reference's run, within 1 %; and without numba, the fit
    measures it against the reference's run."""
    truth, rec = record
    engine_fast.kernel()  # loaded in this process: the refined run is taken whatever numba's disk cache holds
    fit = dropfit.fit_drop(rec, "S12", free=list(truth), engine="mujoco", workers=1)
    assert dropfit.error_note(fit.extra) == "against the fast engine stepped twice as finely at the optimum"
    monkeypatch.setitem(dropfit.OTHER_ENGINE, "mujoco", "ode")
    with_ode = dropfit.fit_drop(rec, "S12", free=list(truth), engine="mujoco", workers=1)
    assert dropfit.error_note(with_ode.extra) == "against the ODE reference at the optimum"
    for key in truth:
        assert fit.values[key] == with_ode.values[key]
        lo, hi = fit.extra["ci95"][key]
        lo_ode, hi_ode = with_ode.extra["ci95"][key]
        assert hi - lo == pytest.approx(hi_ode - lo_ode, rel=0.01), key
    shift = np.array([fit.extra["engine_error_shift"][k] for k in truth])
    shift_ode = np.array([with_ode.extra["engine_error_shift"][k] for k in truth])
    scale = np.abs(np.array(list(truth.values())))
    big = np.abs(shift_ode) / scale >= 0.1 * np.max(np.abs(shift_ode) / scale)
    ratio = shift[big] / shift_ode[big]
    assert np.all((ratio >= 0.5) & (ratio <= 1.5)), ratio


def test_without_numba_the_reference_measures_the_error(monkeypatch):
    """No numba: the fast refined run is not there, and the fit asks the ODE reference."""
    asked = []
    real = dropfit._model

    def spy(values, keys, config=None, engine=None, *args, **kwargs):
        asked.append(engine)
        return real(values, keys, config, engine, *args, **kwargs)

    monkeypatch.setattr(dropfit._jit, "numba", None)
    monkeypatch.setattr(dropfit, "_model", spy)
    cfg = resolve("S12")
    truth = {"fork.spring.preload_N": cfg["fork.spring.preload_N"] * 1.1}
    rec = make_drop_record("S12", truth, duration=0.3, engine="ode", seed=2)
    fit = dropfit.fit_drop(rec, "S12", free=list(truth), engine="mujoco", workers=1)
    assert asked[-1] == "ode" and fit.extra["engine_error_run"] == "ode"
    assert "fast_refined" not in asked


def test_an_unmeasured_engine_error_is_said():
    assert dropfit.error_note({"engine": "fast", "engine_error_run": None}).startswith("not measured")


def test_a_mujoco_fit_does_not_compile_the_fast_engine_to_measure_its_error(monkeypatch):
    """Where the fast engine's compiled code is neither loaded nor cached, a MuJoCo fit measures its
    error against the ODE reference (a compile would cost more); where it is, against the refined run."""
    from mtbmj.controllers import jit
    from mtbmj.drop import engine_fast

    monkeypatch.setattr(engine_fast, "_WARM", False)
    monkeypatch.setattr(jit, "cold", lambda dispatcher: True)
    assert dropfit.error_engine("mujoco") == "ode"
    assert dropfit.error_engine("fast") == "fast_refined"  # its own kernel is what the fit ran
    monkeypatch.setattr(jit, "CACHE", False)  # no disk cache: every process would compile
    monkeypatch.setattr(jit, "cold", lambda dispatcher: False)
    assert dropfit.error_engine("mujoco") == "ode"
    monkeypatch.setattr(engine_fast, "_WARM", True)  # loaded in this process
    assert dropfit.error_engine("mujoco") == "fast_refined"
    assert dropfit.error_engine("ode") == "mujoco"

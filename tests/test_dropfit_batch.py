"""The drop fit on the batched path (``mtbmj.drop.engine_batch.drop_traces``): the same engine runs as
``run_drop``, so the same Jacobians and fit; multi-start."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.drop.engine_batch import drop_traces
from mtbmj.controllers import compiled
from mtbmj.drop.chain import resolve
from mtbmj.drop.run import run_drop
from mtbmj.identify.drop_synthetic import make_drop_record
from mtbmj.identify.dropfit import fit_drop

pytestmark = pytest.mark.skipif(not compiled.available(), reason="compiled force laws unavailable")

TRUTH = {"fork.spring.preload_N": 232.0, "fork.friction.coulomb_N": 31.0, "tire.contact_rate_N_per_mm": 78.5}


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    return make_drop_record("S12", TRUTH, duration=0.6, engine="mujoco", seed=7,
                            path=tmp_path_factory.mktemp("dropfit") / "drop.csv")


def test_drop_traces_equal_run_drop():
    cfg = resolve("S12")
    sets = [{}, {"fork.spring.preload_N": 250.0, "tire.contact_rate_N_per_mm": 70.0},
            {"fork.friction.coulomb_N": 20.0}]
    for over, tr in zip(sets, drop_traces(cfg, sets, 0.4, threads=2)):
        signals = run_drop(cfg, "mujoco", overrides=over, duration=0.4).signals
        # RK4 stages use the contact solver, whose warm start is reset where a rollout restarts; the
        # batched rounds restart at other steps than the engine's chunks: equal to ~1e-11 mm
        assert np.array_equal(tr["time_s"], signals["time_s"])
        for name in ("sled_mm", "fork_mm", "tire_mm"):
            assert np.max(np.abs(tr[name] - signals[name])) <= 1e-9, (over, name)


def test_batched_fit_equals_the_process_pool_fit(record):
    free = list(TRUTH)
    old = fit_drop(record, "S12", free=free, batched=False, workers=2)
    new = fit_drop(record, "S12", free=free, batched=True, workers=2)
    assert new.extra["batched"] and not old.extra["batched"]
    for key in free:  # runs equal to ~1e-11 mm (see above): the same fit to far below its error
        assert new.values[key] == pytest.approx(old.values[key], rel=1e-7), key
        assert new.stderr[key] == pytest.approx(old.stderr[key], rel=1e-4), key


def test_multi_start_recovers_the_truth(record):
    res = fit_drop(record, "S12", free=list(TRUTH), starts=2)
    assert len(res.extra["starts"]) == 2 and res.extra["best_start"] in (0, 1)
    costs = [s["cost"] for s in res.extra["starts"] if s["failed"] is None]
    assert 0.5 * res.rms**2 * res.n_points == pytest.approx(min(costs), rel=1e-9)
    for key, true in TRUTH.items():
        assert res.values[key] == pytest.approx(true, rel=0.03), key
        low, high = res.extra["ci95"][key]
        assert low < res.values[key] < high, key
        # One record at a fixed seed: its 95 % intervals miss the truth of one of three parameters
        # about one time in seven, so this checks the 3-sigma interval (the intervals' coverage is
        # measured on 20 records by benchmarks/interval_coverage.py).
        assert abs(res.values[key] - true) <= 3.0 * res.stderr[key], key


def test_fine_steps_of_several_drops_stepped_together_equal_run_drop(monkeypatch):
    """With threads, drops at their fine steps go through one rollout call together
    (``engine_batch._fine_together``), each for its own plan's steps at its own fine step, some
    padded to the longest: every drop still equals its ``run_drop``."""
    from mtbmj.drop import engine_batch

    calls = []
    real = engine_batch._fine_together

    def spy(runs, datas, pool):
        calls.append([(r.plan.size(r.steps - r.done), r.plan.substeps) for r in runs])
        return real(runs, datas, pool)

    monkeypatch.setattr(engine_batch, "_fine_together", spy)
    cfg = resolve("S12")
    sets = [{}, {"sled.drop_height_mm": 70.0}, {"sled.drop_height_mm": 130.0, "fork.friction.coulomb_N": 20.0},
            {"fork.spring.preload_N": 150.0, "tire.impact_rate_N_per_mm": 95.0}]
    traces = drop_traces(cfg, sets, 0.5, threads=2)
    assert calls, "no two drops were at their fine steps together"
    assert any(len({n * k for n, k in c}) > 1 for c in calls), "no call padded a shorter drop"
    for over, tr in zip(sets, traces):
        signals = run_drop(cfg, "mujoco", overrides=over, duration=0.5).signals
        assert np.array_equal(tr["time_s"], signals["time_s"])
        for name in ("sled_mm", "fork_mm", "tire_mm"):
            assert np.max(np.abs(tr[name] - signals[name])) <= 1e-9, (over, name)

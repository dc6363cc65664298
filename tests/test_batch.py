"""The batched sweep runner (``mtbmj.sweep.batch`` on ``mtbmj.drop.engine_batch``): the same records as ``run_drop`` per variant, failing
variants recorded while the others go on, and the journal/resume contract kept."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import mtbmj
from mtbmj.drop import chain, engine_batch
from mtbmj.sweep import batch
from mtbmj import sweep
from mtbmj.controllers import compiled

pytestmark = pytest.mark.skipif(not compiled.available(), reason="compiled force laws unavailable")

DURATION = 0.6  # long enough for S12's tire-law switch (~0.28 s) and the second peak

# ~8 variants over S12 (tire-law switch), S10 and S1 (no switch)
CASES = {
    "S12": [{}, {"sled.drop_height_mm": 130.0},
            {"fork.spring.preload_N": 150.0, "tire.impact_rate_N_per_mm": 80.0},
            {"fork.spring.progressive_rate_N_per_mm": 9.5, "sled.drop_height_mm": 70.0}],
    "S10": [{}, {"sled.drop_height_mm": 70.0}],
    "S1": [{}, {"sled.drop_height_mm": 90.0}],
}


def _numbers_equal(a: dict, b: dict) -> None:
    assert set(a) == set(b)
    for key in a:
        x, y = a[key], b[key]
        if isinstance(x, float) and isinstance(y, float):
            assert abs(x - y) <= 1e-9 * max(abs(x), abs(y), 1e-12), (key, x, y)
        else:
            assert x == y, (key, x, y)


def _by_id(records):
    return {r["id"]: r for r in records}


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("threads", [1, 2])
def test_batch_equals_run_drop_summaries(name, threads):
    cfg = mtbmj.load_config(name)
    variants = sweep.plan(cfg, CASES[name], duration=DURATION)
    job = sweep.BatchJob(cfg, "mujoco", DURATION, variants, traces=True, threads=threads)
    single = _by_id(sweep.run_batch(job))
    batched = _by_id(batch.run_batch_rollout(job))
    assert set(single) == set(batched) == {v.id for v in variants}
    for v in variants:
        a, b = single[v.id], batched[v.id]
        assert a["status"] == b["status"] == "ok"
        _numbers_equal(a["outputs"], b["outputs"])
        for key in ("time_s", "sled_mm", "fork_mm", "tire_mm"):
            np.testing.assert_allclose(b["traces"][key], a["traces"][key], rtol=0, atol=1e-9)
    if name == "S12":  # the tire law switched in these runs
        assert sum(batched[v.id]["outputs"]["fork_tops_out"] for v in variants) >= 3


def test_equal_to_run_drop_directly():
    cfg = mtbmj.load_config("S12")
    variants = sweep.plan(cfg, [{"sled.drop_height_mm": 110.0}], duration=DURATION)
    record = batch.run_batch_rollout(sweep.BatchJob(cfg, "mujoco", DURATION, variants))[0]
    expected = sweep.flatten_summary(mtbmj.run_drop(cfg, "mujoco", variants[0].overrides, DURATION).summary)
    _numbers_equal(record["outputs"], expected)


def test_failing_variant_is_recorded_and_the_others_go_on():
    cfg = mtbmj.load_config("S12")
    overrides = [{}, {"sled.body_mass_kg": -1.0}, {"solver.timestep_s": 0.01}, {"sled.drop_height_mm": 120.0}]
    variants = sweep.plan(cfg, overrides, duration=DURATION)
    job = sweep.BatchJob(cfg, "mujoco", DURATION, variants)
    batched = _by_id(batch.run_batch_rollout(job))
    single = _by_id(sweep.run_batch(job))
    status = [batched[v.id]["status"] for v in variants]
    assert status == ["ok", "failed", "failed", "ok"]
    assert "sled.body_mass_kg: must be positive" in batched[variants[1].id]["reason"]
    assert "solver.timestep_s" in batched[variants[2].id]["reason"]
    for v in variants:
        assert batched[v.id]["reason"] == single[v.id]["reason"]
        _numbers_equal(batched[v.id]["outputs"], single[v.id]["outputs"])


def test_variant_flagged_during_stepping_goes_to_the_single_path(monkeypatch):
    """A variant that looks diverged in the batch (here: a lowered runaway limit) is run again
    alone by the single-variant path and recorded as it records it; the others are unaffected."""
    cfg = mtbmj.load_config("S12")
    variants = sweep.plan(cfg, [{"sled.drop_height_mm": 60.0}, {"sled.drop_height_mm": 130.0}], duration=DURATION)
    job = sweep.BatchJob(cfg, "mujoco", DURATION, variants)
    single = _by_id(sweep.run_batch(job))
    ran_alone = []
    original = batch.run_variant
    monkeypatch.setattr(engine_batch, "MAX_DISPLACEMENT_M", 0.125)  # only the 130 mm drop goes beyond 125 mm
    monkeypatch.setattr(batch, "run_variant", lambda j, v: ran_alone.append(v.id) or original(j, v))
    batched = _by_id(batch.run_batch_rollout(job))
    assert ran_alone == [variants[1].id]
    for v in variants:
        assert batched[v.id]["status"] == "ok"
        _numbers_equal(batched[v.id]["outputs"], single[v.id]["outputs"])


def test_fast_timestep_check_is_never_more_lenient():
    cfg = mtbmj.load_config("S12")
    from mtbmj import compose

    base = compose.setup(cfg)
    assert chain.prepare(cfg)[1].fork.spring == base.fork.spring
    with pytest.raises(mtbmj.ConfigError, match="solver.timestep_s"):
        chain.prepare(cfg.with_overrides({"solver.timestep_s": 0.01}))


def test_sweep_default_runner_is_batched_and_resume_works(tmp_path, monkeypatch):
    cfg = "S12"
    ranges = [sweep.parse_vary("fork.spring.preload_N=150:300", count=False),
              sweep.parse_vary("sled.drop_height_mm=60:130", count=False)]
    variants = sweep.sample(ranges, 6, "lhs", seed=1)
    reference = sweep.run_sweep(cfg, variants, tmp_path / "single", duration=DURATION, workers=2, batch_size=2,
                                runner="single")
    out = tmp_path / "batched"
    full = sweep.run_sweep(cfg, variants, out, duration=DURATION, workers=2, batch_size=2)
    cols = [c for c in reference.table.columns if c != "wall_time_s"]
    pd.testing.assert_frame_equal(full.table[cols], reference.table[cols], rtol=1e-9)
    # lose two of the three journaled batches; --resume computes exactly their variants
    parts = sorted((out / "journal").glob("part-*.json"))
    assert len(parts) == 3
    for part in parts[:2]:
        part.unlink()
    (out / sweep.TABLE).unlink()
    again = sweep.run_sweep(cfg, variants, out, duration=DURATION, workers=2, batch_size=2, resume=True)
    assert again.computed == 4 and again.reused == 2
    pd.testing.assert_frame_equal(again.table[cols], reference.table[cols], rtol=1e-9)
    with pytest.raises(mtbmj.ConfigError, match="--runner"):
        sweep.run_sweep(cfg, variants, tmp_path / "x", duration=DURATION, runner="nope")


@pytest.mark.parametrize("name,overrides", [("S12", {}), ("S4", {"sled.drop_height_mm": 250.0})])
def test_batch_counts_the_steps_it_makes_as_the_engine_does(name, overrides):
    """One variant alone makes the engine's stepping decisions: the same MuJoCo steps (fine ones
    each counted, at both fine levels), refined output steps and discarded ones."""
    import mujoco

    from mtbmj import compose
    from mtbmj.controllers import installed
    from mtbmj.drop import engine_mujoco

    cfg = mtbmj.load_config(name, overrides)
    variants = sweep.plan(cfg, [{}], duration=DURATION)
    job = sweep.BatchJob(cfg, "mujoco", DURATION, variants)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    run = engine_batch.prepare(job.config, variants[0].overrides, job.duration, 0, spec)
    with installed(run.callback):
        engine_batch.step_group([run], [mujoco.MjData(run.scene.model)], None, spec)
    ours = engine_batch.trace_of(run).info
    engine = engine_mujoco.run(compose.setup(cfg), DURATION, callback="compiled").info
    keys = ("steps_computed", "steps_refined", "steps_discarded", "substeps", "contact_substeps")
    assert {k: ours[k] for k in keys} == {k: engine[k] for k in keys}
    assert ours["steps_computed"] > ours["steps"] and ours["steps_refined"] > 0

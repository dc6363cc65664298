"""The fast engine's integrator specialised to one fork law's structure (issue 27, item 2): its
generated force is the shared kernel's, bit for bit, for every law code; its traces equal the
shared kernel's; a sweep batch and a fit reach it once it pays, with the same records; without a
cache folder to write in, the shared kernel runs."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj import compose, config
from mtbmj import controllers as law
from mtbmj.controllers import compiled

pytestmark = pytest.mark.skipif(not compiled.available(), reason="numba not installed")

TABLE = law.TableDamper([-1.5, -0.8, -0.4, -0.15, -0.05, 0.0, 0.05, 0.15, 0.4, 0.8, 1.5],
                        [-391.4, -225.2, -128.0, -58.1, -21.9, 0.0, 6.7, 20.0, 53.3, 106.6, 199.8])
STOPS = dict(travel=0.12, bumper_length=0.008, bumper_force=3000.0, stop_rate=2e7, stop_damping=2000.0,
             extension=0.005)
LAWS = {
    "linear": law.ForkLaw(law.LinearSpring(16470.0), law.LinearDamper(201.3), law.NoFriction()),
    "bilinear_coulomb": law.ForkLaw(law.BilinearSpring(17380.0, 14310.0, 0.067), law.BilinearDamper(133.2, 269.4),
                                    law.Coulomb(34.2, 0.005)),
    "directional_digressive_viscous": law.ForkLaw(
        law.DirectionalSpring(law.TopOutSpring(law.LinearSpring(17000.0), 35300.0, 150.0),
                              law.DirectionalSpring(law.LinearSpring(15000.0),
                                                    law.ProgressiveSpring(11000.0, 3e5), 0.01), 0.02),
        law.DigressiveDamper(1500.0, 300.0, 0.3, 2500.0, 500.0, 0.25), law.CoulombViscous(34.2, 40.0, 0.005)),
    "stops_orifice_stiction": law.ForkLaw(law.EndStops(law.ProgressiveSpring(11370.0, 326000.0), **STOPS),
                                          law.OrificeDamper(50.0, 300.0, 500.0),
                                          law.Stiction(34.2, 45.0, 10.0, 0.02, 0.005)),
    "stops_table_stribeck": law.ForkLaw(law.EndStops(law.TopOutSpring(law.LinearSpring(16470.0), 35300.0), **STOPS),
                                        TABLE, law.Stribeck(34.2, 45.0, 10.0, 0.02, 2.0, 0.005)),
    "lugre": law.ForkLaw(law.LinearSpring(16470.0), TABLE, law.LuGre(20.0, 30.0, 0.02, 1e5, 300.0, 15.0)),
}
for _inner in (law.Coulomb(34.2, 0.005), law.CoulombViscous(34.2, 40.0, 0.005),
               law.Stiction(34.2, 45.0, 10.0, 0.02, 0.005), law.Stribeck(34.2, 45.0, 10.0, 0.02, 1.5, 0.005)):
    LAWS[f"sticking_{type(_inner).__name__}"] = law.ForkLaw(
        law.TopOutSpring(law.ProgressiveSpring(11370.0, 326000.0), 35300.0, 211.1), TABLE,
        law.Sticking(_inner, 3e4, 2500.0, 0.05, 0.5))


def _setup_law(name):
    return compose.setup(config.load(name)).fork


def _generated(I):
    """The generated fork_force_rate, run as Python on the compiled law functions."""
    from mtbmj.controllers import kernels
    from mtbmj.drop import engine_fast

    namespace = {name: getattr(kernels, name) for name in engine_fast.LAW_FUNCTIONS}
    exec(engine_fast.force_source(I), namespace)
    return namespace["fork_force_rate"]


@pytest.mark.parametrize("name", list(LAWS) + ["S12", "S9", "air120"])
def test_the_generated_force_is_the_shared_kernels_bit_for_bit(name):
    from mtbmj.controllers import kernels
    from mtbmj.controllers.lawcodes import law_arrays

    fork = LAWS[name] if name in LAWS else _setup_law(name)
    I, P = law_arrays(fork)
    force = _generated(I)
    rng = np.random.default_rng(27)
    xs = np.concatenate([rng.uniform(-0.03, 0.14, 200), [0.0, 0.067, 0.12, 0.128, -0.006]])
    vs = np.concatenate([rng.uniform(-3.0, 3.0, 200), [0.0, 0.02, -0.05, 1.5, -1.5]])
    zs = rng.uniform(-4e-4, 4e-4, xs.size)
    for x, v, z in zip(xs, vs, zs):
        assert force(I, P, x, v, z) == kernels.fork_force_rate(I, P, x, v, z)


@pytest.mark.parametrize("preset", ["S12", "S1"])
def test_the_specialised_integrator_gives_the_shared_kernels_trace(preset):
    from mtbmj.drop import engine_fast

    setup = compose.setup(config.load(preset))
    shared = engine_fast.run(setup, 1.0)
    I, _ = engine_fast.law_arrays(setup)
    assert engine_fast.specialised(I, force=True) is not None
    own = engine_fast.run(setup, 1.0, specialise=True)
    for name in ("sled", "fork", "sled_velocity", "fork_velocity", "friction_state", "tire_phase", "time"):
        assert np.array_equal(getattr(own, name), getattr(shared, name)), name
    assert own.info == shared.info


def _fresh(monkeypatch, engine_fast, after):
    for name, value in (("_SPECIAL", {}), ("_MODULES", {}), ("_RUNS", {}), ("_LOOKED", set()), ("_TEXTS", {})):
        monkeypatch.setattr(engine_fast, name, value)
    monkeypatch.setattr(engine_fast, "SPECIALISE_AFTER", after)


def test_a_sweep_batch_reaches_it_once_due_with_the_same_records(monkeypatch, tmp_path):
    import os

    from mtbmj.drop import engine_fast
    from mtbmj.sweep.fast import run_batch_fast
    from mtbmj.sweep.variants import BatchJob, Variant

    cfg = config.load("S12")
    variants = [Variant(i, f"v{i}", {"sled.drop_height_mm": h, "fork.spring.preload_N": p})
                for i, (h, p) in enumerate([(70.0, 180.0), (100.0, 250.0), (125.0, 290.0)])]
    job = BatchJob(cfg, "fast", 0.8, variants, True)
    home = os.environ.get("XDG_CACHE_HOME")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))  # an empty cache: the shared kernel runs
    _fresh(monkeypatch, engine_fast, 10**9)
    shared = run_batch_fast(job)
    assert not any(engine_fast._SPECIAL.values())
    if home is None:
        monkeypatch.delenv("XDG_CACHE_HOME")
    else:
        monkeypatch.setenv("XDG_CACHE_HOME", home)
    _fresh(monkeypatch, engine_fast, 1)
    own = run_batch_fast(job)
    assert any(engine_fast._SPECIAL.values())
    for a, b in zip(own, shared):
        assert a["status"] == b["status"] == "ok"
        assert a["outputs"] == b["outputs"] or all(
            x == y or (x != x and y != y) for x, y in zip(a["outputs"].values(), b["outputs"].values()))
        for name in a["traces"]:
            assert np.array_equal(a["traces"][name], b["traces"][name])


def test_without_a_cache_folder_the_shared_kernel_runs(monkeypatch, tmp_path):
    from mtbmj.drop import engine_fast

    blocked = tmp_path / "not-a-folder"
    blocked.write_text("a file where the cache folder would go\n")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocked))
    _fresh(monkeypatch, engine_fast, 0)
    setup = compose.setup(config.load("S9"))
    I, _ = engine_fast.law_arrays(setup)
    assert engine_fast.specialised(I) is None
    trace = engine_fast.run(setup, 0.3, specialise=True)
    assert np.array_equal(trace.sled, engine_fast.run(setup, 0.3).sled)


def test_a_process_below_the_threshold_writes_nothing(monkeypatch, tmp_path):
    from mtbmj.drop import engine_fast

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    _fresh(monkeypatch, engine_fast, 10**9)
    setup = compose.setup(config.load("S9"))
    for _ in range(3):
        engine_fast.run(setup, 0.2, specialise=True)
    assert not any(tmp_path.iterdir())

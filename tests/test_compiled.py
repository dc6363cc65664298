"""Compiled force laws (controllers.compiled) against the Python laws, their specification."""
import ctypes
import gc
import os
import subprocess
import sys
import warnings

import mujoco
import numpy as np
import pytest
from mujoco import rollout

import mtbmj
from mtbmj.errors import FallbackWarning
from mtbmj import compose
from mtbmj.drop import engine_mujoco, scene
from mtbmj.runpath import steprule
from mtbmj import controllers as law
from mtbmj.controllers import ForkCallback, installed, native

compiled = pytest.importorskip("mtbmj.controllers.compiled")
CALLS_PER_STEP = {"rk4": 4, "euler": 1, "implicit": 1, "implicitfast": 1}  # control callback calls per step
if not compiled.available():
    pytest.skip(f"compiled path unavailable: {compiled.unavailable_reason()}", allow_module_level=True)

TOL_M = 1e-9
DURATION = 0.6
INTEGRATORS = ["euler", "implicitfast", "implicit", "rk4"]
PRESETS = [f"S{i}" for i in range(1, 15)]

SPRINGS = {
    "linear": law.LinearSpring(16470.0),
    "bilinear": law.BilinearSpring(17380.0, 14310.0, 0.067),
    "progressive": law.ProgressiveSpring(11370.0, 326000.0),
    "directional": law.DirectionalSpring(law.LinearSpring(17000.0), law.LinearSpring(15930.0), 0.02),
    "directional_bilinear": law.DirectionalSpring(law.BilinearSpring(17380.0, 14310.0, 0.067),
                                                  law.LinearSpring(15930.0), 0.02),
    "topout": law.TopOutSpring(law.ProgressiveSpring(11370.0, 326000.0), 35300.0, 211.1),
    "topout_no_preload": law.TopOutSpring(law.LinearSpring(16470.0), 35300.0),
    "topout_directional": law.TopOutSpring(
        law.DirectionalSpring(law.BilinearSpring(17380.0, 14310.0, 0.067), law.LinearSpring(15930.0), 0.02),
        35300.0, 211.1),
    "nested": law.DirectionalSpring(law.TopOutSpring(law.LinearSpring(17000.0), 35300.0, 150.0),
                                    law.DirectionalSpring(law.LinearSpring(15000.0), law.ProgressiveSpring(
                                        11000.0, 3e5), 0.01), 0.02),
}
TABLE = law.TableDamper([-1.5, -0.8, -0.4, -0.15, -0.05, 0.0, 0.05, 0.15, 0.4, 0.8, 1.5],
                        [-391.4, -225.2, -128.0, -58.1, -21.9, 0.0, 6.7, 20.0, 53.3, 106.6, 199.8])
DAMPERS = {
    "linear": law.LinearDamper(201.3),
    "bilinear": law.BilinearDamper(133.2, 269.4),
    "digressive": law.DigressiveDamper(1500.0, 300.0, 0.3, 2500.0, 500.0, 0.25),
    "table": TABLE,
    "table_no_zero": law.TableDamper([-1.0, -0.3, 0.2, 1.0], [-250.0, -60.0, 30.0, 150.0]),
}
FRICTIONS = {
    "none": law.NoFriction(),
    "coulomb": law.Coulomb(34.2, 0.005),
    "coulomb_viscous": law.CoulombViscous(34.2, 40.0, 0.005),
    "stiction": law.Stiction(34.2, 45.0, 10.0, 0.02, 0.005),
    "stribeck": law.Stribeck(34.2, 45.0, 10.0, 0.02, 2.0, 0.005),
    "stribeck_1.5": law.Stribeck(34.2, 45.0, 10.0, 0.02, 1.5, 0.005),
    "lugre": law.LuGre(20.0, 30.0, 0.02, 1e5, 300.0, 0.0),
    "lugre_viscous": law.LuGre(20.0, 30.0, 0.02, 1e5, 300.0, 15.0),
}


def _rows(fork_law):
    ints, floats = compiled.flatten(fork_law)
    P = np.zeros(compiled.FLOAT_WIDTH)
    P[: len(floats)] = floats
    return np.asarray(ints, dtype=np.int64), P


def _samples():
    rng = np.random.default_rng(6)
    x = np.concatenate([rng.uniform(-0.03, 0.14, 300), [0.0, 0.067, 0.0059802, -1e-12, 0.12]])
    v = np.concatenate([rng.uniform(-3.0, 3.0, 300), [0.0, 0.02, -0.02, 0.05, -1e-9]])
    z = rng.uniform(-4e-4, 4e-4, x.size)
    return x, v, z


# ---------------------------------------------------------------------------------------------
# The laws themselves: compiled kernel == Python law, every type and composition
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("spring", SPRINGS)
def test_every_spring_law_is_bit_identical(spring):
    fork_law = law.ForkLaw(SPRINGS[spring], DAMPERS["linear"], FRICTIONS["none"])
    I, P = _rows(fork_law)
    for x, v, z in zip(*_samples()):
        assert compiled.fork_force(I, P, x, v, 0.0) == fork_law.force(x, v)


@pytest.mark.parametrize("damper", DAMPERS)
def test_every_damper_law_is_bit_identical(damper):
    fork_law = law.ForkLaw(SPRINGS["linear"], DAMPERS[damper], FRICTIONS["none"])
    I, P = _rows(fork_law)
    d = DAMPERS[damper]
    breakpoints = list(getattr(d, "velocity", ()))
    xs, vs, _ = _samples()
    for x, v in zip(np.append(xs, [0.01] * len(breakpoints)), np.append(vs, breakpoints)):
        assert compiled.fork_force(I, P, x, v, 0.0) == fork_law.force(x, v)


@pytest.mark.parametrize("friction", FRICTIONS)
def test_every_friction_law_is_bit_identical(friction):
    f = FRICTIONS[friction]
    fork_law = law.ForkLaw(SPRINGS["topout"], TABLE, f)
    I, P = _rows(fork_law)
    for x, v, z in zip(*_samples()):
        z = z if f.has_state else 0.0
        assert compiled.fork_force(I, P, x, v, z) == fork_law.force(x, v, z)
        assert compiled.state_rate(I, P, v, z) == fork_law.state_rate(v, z)


def test_unsupported_laws_are_refused_and_fall_back():
    class MySpring(law.LinearSpring):  # a subclass may change force(): never compiled
        def force(self, x, v, sides=None):
            return 2.0 * self.rate * x

    fork_law = law.ForkLaw(MySpring(1e4), DAMPERS["linear"], FRICTIONS["none"])
    with pytest.raises(compiled.UnsupportedLaw):
        compiled.flatten(fork_law)
    setup = compose.setup(mtbmj.load_config("S1"))
    sc = scene.build(setup)
    compiled._WARNED.clear()
    with pytest.warns(FallbackWarning, match="MySpring has no compiled form"):
        callback = engine_mujoco.fork_callback(sc.model, fork_law)
    assert isinstance(callback, ForkCallback)


# ---------------------------------------------------------------------------------------------
# Whole drops: compiled path == Python path, every preset and law, every integrator
# ---------------------------------------------------------------------------------------------
def _compare(setup, duration=DURATION):
    fast = engine_mujoco.run(setup, callback="compiled", duration=duration)
    slow = engine_mujoco.run(setup, callback="python", duration=duration)
    for name in ("sled", "fork", "sled_velocity", "fork_velocity", "friction_state"):
        worst = np.max(np.abs(getattr(fast, name) - getattr(slow, name)))
        assert worst <= (TOL_M if name in ("sled", "fork") else 1e3 * TOL_M), (name, worst)
    assert np.array_equal(fast.tire_phase, slow.tire_phase)
    for key in ("steps", "steps_discarded", "callback_calls"):
        assert fast.info[key] == slow.info[key], key
    return fast, slow


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("preset", PRESETS)
def test_every_preset_agrees_on_every_integrator(preset, integrator):
    setup = compose.setup(mtbmj.load_config(preset, {"solver.integrator": integrator}))
    fast, _ = _compare(setup)
    if preset == "S12":  # the tire law switched mid-chunk: a chunk was cut and resumed
        assert fast.info["steps_discarded"] > 0 and fast.tire_phase[-1] == 1


LAW_OVERRIDES = {
    "spring_linear": {"fork.spring.model": "linear", "fork.spring.top_out": False, "fork.spring.preload": False},
    "spring_bilinear_topout": {"fork.spring.model": "bilinear", "fork.spring.preload": False},
    "spring_directional": {"fork.spring.model": "compression_rebound"},
    "spring_bilinear_rebound_curve": {"fork.spring.model": "bilinear", "fork.spring.rebound_curve": True},
    "damper_linear": {"fork.damper.model": "linear"},
    "damper_bilinear": {"fork.damper.model": "bilinear"},
    "friction_none": {"fork.friction.model": "none"},
    "friction_coulomb_viscous": {"fork.friction.model": "coulomb_viscous", "fork.friction.viscous_N_s_per_m": 30.0},
    "friction_stiction": {"fork.friction.model": "stiction"},
    "friction_stribeck": {"fork.friction.model": "stribeck"},
    "friction_stribeck_exponent": {"fork.friction.model": "stribeck", "fork.friction.stribeck_exponent": 1.3},
}
LUGRE = {"fork.friction.model": "lugre", "fork.friction.coulomb_N": 20.0, "fork.friction.breakaway_N": 30.0}


@pytest.mark.parametrize("variant", LAW_OVERRIDES)
def test_every_law_type_agrees_over_a_drop(variant):
    setup = compose.setup(mtbmj.load_config("S12", LAW_OVERRIDES[variant]))
    _compare(setup)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_lugre_state_and_tire_switch_agree_on_every_integrator(integrator):
    setup = compose.setup(mtbmj.load_config("S12", {**LUGRE, "solver.integrator": integrator}))
    fast, _ = _compare(setup)
    assert np.max(np.abs(fast.friction_state)) > 1e-5  # the bristle state really moved
    assert fast.tire_phase[-1] == 1


def test_a_whole_default_drop_agrees():
    setup = compose.setup(mtbmj.load_config("S12"))
    _compare(setup, duration=None)


# ---------------------------------------------------------------------------------------------
# Hygiene: the layout, other models, threads, the registry, the fallback
# ---------------------------------------------------------------------------------------------
def test_mjdata_layout_comes_from_mujoco_and_matches_live_arrays():
    layout = compiled.mjdata_layout()
    setup = compose.setup(mtbmj.load_config("S12"))
    model = scene.build(setup).model
    compiled.check_layout(model)
    data = mujoco.MjData(model)
    for name in compiled.MJDATA_FIELDS:
        assert ctypes.c_void_p.from_address(data._address + layout[name]).value == getattr(data, name).ctypes.data
    bad = dict(layout, qvel=layout["qpos"])
    with pytest.raises(RuntimeError, match="qvel"):
        compiled.check_layout(model, bad)


def test_callback_is_a_c_function_pointer_installed_and_restored():
    setup = compose.setup(mtbmj.load_config("S12"))
    sc = scene.build(setup)
    callback = compiled.CompiledForkCallback(sc.model, setup.fork)
    assert isinstance(callback, ctypes._CFuncPtr) and callback.address == compiled.dispatcher().address
    previous = lambda m, d: None  # noqa: E731
    mujoco.set_mjcb_control(previous)
    try:
        with installed(callback):
            assert mujoco.get_mjcb_control() is callback
        assert mujoco.get_mjcb_control() is previous
    finally:
        mujoco.set_mjcb_control(None)


def test_callback_never_touches_another_model():
    setup = compose.setup(mtbmj.load_config("S12"))
    ours, other = scene.build(setup), scene.build(setup)
    data = mujoco.MjData(other.model)
    data.qvel[other.sled_dof] = 1.0
    callback = compiled.CompiledForkCallback(ours.model, setup.fork)
    with installed(callback):
        mujoco.mj_step(other.model, data, nstep=200)
    assert callback.calls == 0
    assert np.all(data.qfrc_applied == 0.0)
    alone = mujoco.MjData(other.model)
    alone.qvel[other.sled_dof] = 1.0
    mujoco.mj_step(other.model, alone, nstep=200)
    assert np.array_equal(alone.qpos, data.qpos)


def test_a_collected_callback_frees_its_slot():
    setup = compose.setup(mtbmj.load_config("S1"))
    sc = scene.build(setup)
    callback = compiled.CompiledForkCallback(sc.model, setup.fork)
    slot = callback.slot
    assert compiled.REGISTRY.tables["ints"][slot, 0] == sc.model._address
    pointer = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)(callback.address)
    del callback
    gc.collect()
    assert compiled.REGISTRY.tables["ints"][slot, 0] == 0
    data = mujoco.MjData(sc.model)
    data.qpos[sc.fork_qpos] = 0.05
    with installed(pointer):  # the dispatcher itself, with no live slot for this model
        mujoco.mj_step(sc.model, data)
    assert np.all(data.qfrc_applied == 0.0)


def test_the_newest_callback_of_a_model_defines_its_law():
    setup = compose.setup(mtbmj.load_config("S1"))
    sc = scene.build(setup)
    soft = law.ForkLaw(law.LinearSpring(1e4), law.LinearDamper(0.0), law.NoFriction())
    hard = law.ForkLaw(law.LinearSpring(2e4), law.LinearDamper(0.0), law.NoFriction())
    old = compiled.CompiledForkCallback(sc.model, soft)
    new = compiled.CompiledForkCallback(sc.model, hard)
    assert new.active and not old.active
    data = mujoco.MjData(sc.model)
    data.qpos[sc.fork_qpos] = 0.01
    old(sc.model, data)  # the shared dispatcher, called from Python: the newest law acts
    assert data.qfrc_applied[sc.fork_dof] == -200.0
    assert (old.calls, new.calls) == (0, 1)
    new.close()
    assert new.calls == 1 and not new.active
    data.qfrc_applied[:] = 0.0
    old(sc.model, data)  # retired and the newest closed: the model is left alone
    assert data.qfrc_applied[sc.fork_dof] == 0.0


def _batch(setup, n=6):
    """n initial states of S12 (different impact speeds), one MjData each."""
    sc = scene.build(setup)
    model = sc.model
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    states = []
    for k in range(n):
        d = mujoco.MjData(model)
        d.qvel[sc.sled_dof] = setup.impact_speed * (0.7 + 0.1 * k)
        d.qvel[sc.fork_dof] = 0.0
        mujoco.mj_forward(model, d)
        s = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, d, s, spec)
        states.append(s)
    return sc, np.array(states)


@pytest.mark.parametrize("overrides", [{}, LUGRE], ids=["S12", "S12_lugre"])
def test_rollout_on_two_threads_is_identical_to_serial_and_to_python(overrides):
    setup = steprule.at_fine_step(compose.setup(mtbmj.load_config("S12", overrides)))  # a raw rollout
    sc, states = _batch(setup)
    model, nstep = sc.model, 3000
    callback = compiled.CompiledForkCallback(model, setup.fork)
    datas = [mujoco.MjData(model) for _ in range(2)]
    with installed(callback):
        serial, _ = rollout.rollout(model, datas[0], states, nstep=nstep)
        calls = callback.calls
        threaded, _ = rollout.rollout([model] * len(states), datas, states, nstep=nstep)
    assert calls == len(states) * nstep * CALLS_PER_STEP[setup.integrator]
    assert callback.calls == 2 * calls  # the atomic counter lost no call across threads
    assert np.array_equal(serial, threaded)
    python = ForkCallback(model, setup.fork)
    with installed(python):
        reference, _ = rollout.rollout(model, mujoco.MjData(model), states, nstep=nstep)
    assert np.max(np.abs(reference - serial)) <= TOL_M


def test_two_models_with_two_laws_in_one_rollout():
    """One rollout over two models, each with its own law: each follows its own Python run."""
    a = steprule.at_fine_step(compose.setup(mtbmj.load_config("S12")))  # raw rollouts
    b = steprule.at_fine_step(compose.setup(mtbmj.load_config("S12", LUGRE)))
    sa, xa = _batch(a, 2)
    sb, xb = _batch(b, 2)
    ca = compiled.CompiledForkCallback(sa.model, a.fork)
    cb = compiled.CompiledForkCallback(sb.model, b.fork)
    models = [sa.model, sa.model, sb.model, sb.model]
    datas = [mujoco.MjData(sa.model), mujoco.MjData(sb.model)]
    with installed(ca):
        together, _ = rollout.rollout(models, datas, np.concatenate([xa, xb]), nstep=2000)
    for sc, setup, x, rows in ((sa, a, xa, together[:2]), (sb, b, xb, together[2:])):
        with installed(ForkCallback(sc.model, setup.fork)):
            alone, _ = rollout.rollout(sc.model, mujoco.MjData(sc.model), x, nstep=2000)
        assert np.max(np.abs(alone - rows)) <= TOL_M
    assert ca.calls == cb.calls == 2 * 2000 * CALLS_PER_STEP[a.integrator]


def test_fallback_warns_once_when_numba_is_unavailable(monkeypatch):
    setup = compose.setup(mtbmj.load_config("S1"))
    sc = scene.build(setup)
    monkeypatch.setattr(compiled, "numba", None)
    monkeypatch.setattr(compiled, "_WARNED", set())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = engine_mujoco.fork_callback(sc.model, setup.fork)
        second = engine_mujoco.fork_callback(sc.model, setup.fork)
    assert isinstance(first, ForkCallback) and isinstance(second, ForkCallback)
    assert [str(w.message) for w in caught] == [compiled.FALLBACK_MESSAGE]
    assert not compiled.available()
    assert isinstance(engine_mujoco.fork_callback(sc.model, setup.fork, "python"), ForkCallback)


def test_without_numba_installed_mtbmj_runs_on_the_python_path():
    """A fresh interpreter in which ``import numba`` fails."""
    code = """
import sys, warnings
sys.modules["numba"] = None
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    import mtbmj
    from mtbmj import compose
    from mtbmj.drop import engine_mujoco, scene
    from mtbmj.controllers import compiled, ForkCallback
    setup = compose.setup(mtbmj.load_config("S1"))
    model = scene.build(setup).model
    assert not compiled.available()
    assert all(isinstance(engine_mujoco.fork_callback(model, setup.fork), ForkCallback) for _ in range(3))
    trace = engine_mujoco.run(setup, callback="auto", duration=0.05)
    assert trace.fork.size == round(0.05 / setup.timestep) + 1
messages = [str(w.message) for w in caught if "numba" in str(w.message)]
assert messages == [compiled.FALLBACK_MESSAGE], messages
print("ok", trace.fork.size)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("ok ")


def test_without_numba_the_command_line_runs_and_says_so_once(tmp_path):
    """``mtbmj drop`` and ``mtbmj sweep`` in an interpreter where ``import numba`` fails: the runs
    complete on the Python laws (the command line used to read the fallback notice as a divergence
    and exit 2), the same numbers as with numba, and a notice is one line on stderr."""
    code = ("import sys; sys.modules['numba'] = None\n"
            "from mtbmj.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    run = subprocess.run([sys.executable, "-c", code, "drop", "S1", "--duration", "0.3", "--out", str(tmp_path / "a")],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    notes = [line for line in run.stderr.splitlines() if "numba" in line]
    # a short drop does not reach for numba at all (controllers.native); a notice is one line
    assert notes in ([], [f"mtbmj: note: {compiled.FALLBACK_MESSAGE}"]), run.stderr
    from mtbmj.cli import main

    assert main(["drop", "S1", "--duration", "0.3", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "a" / "timeseries.csv").read_text() == (tmp_path / "b" / "timeseries.csv").read_text()
    sweep = subprocess.run([sys.executable, "-c", code, "sweep", "S1", "--duration", "0.2", "--vary",
                            "fork.spring.preload_N=100:200:2", "--out", str(tmp_path / "s")],
                           capture_output=True, text=True, timeout=300)
    assert sweep.returncode == 0, sweep.stderr
    assert "2 variants (2 computed" in sweep.stdout and "failed" not in sweep.stdout, sweep.stdout
    from mtbmj.sweep import read_table

    table = read_table(tmp_path / "s")
    assert len(table) == 2 and np.all(np.isfinite(table["sled_peak1_mm"].to_numpy(dtype=float)))


def test_a_short_drop_in_a_fresh_process_does_not_load_numba():
    """``controllers.native``: a default drop in a process without numba loaded runs on the Python
    laws (loading numba would cost more than the run), with the compiled run's trajectory and
    forces bit for bit and its logged signals within 1e-9 mm; a run long enough to repay loading
    numba loads it, and so does a caller that announces many runs. (With the background load of
    a loop of drops turned off: tests/test_native_background.py tests that one.)"""
    code = """
import sys, json
import numpy as np
import mtbmj
from mtbmj.controllers import native
short = mtbmj.run_drop("S12", duration=0.5)
out = {"after_short": "numba" in sys.modules}
np.save(sys.argv[1], np.vstack([short.trace.sled, short.trace.fork, short.raw["fork_force_N"], short.raw["tire_force_N"],
                               short.signals["fork_mm"]]))
native.COMPILED_FROM_STEPS = 400
mtbmj.run_drop("S1", duration=0.5)
out["after_long"] = "numba" in sys.modules
print(json.dumps(out))
"""
    import json
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = f"{tmp}/short.npy"
        run = subprocess.run([sys.executable, "-c", code, path], capture_output=True, text=True, timeout=300,
                             env={**os.environ, "MTBMJ_BACKGROUND_LOAD": "0"})
        assert run.returncode == 0, run.stderr
        flags = json.loads(run.stdout.strip().splitlines()[-1])
        python = np.load(path)
    assert flags == {"after_short": False, "after_long": True}
    native.expect_many()  # this process: numba loaded, the compiled laws taken
    compiled_run = mtbmj.run_drop("S12", duration=0.5)
    assert compiled_run.trace.info["callback_calls"] > 0
    assert np.array_equal(python[0], compiled_run.trace.sled) and np.array_equal(python[1], compiled_run.trace.fork)
    assert np.array_equal(python[2], compiled_run.raw["fork_force_N"])
    assert np.array_equal(python[3], compiled_run.raw["tire_force_N"])
    assert np.max(np.abs(python[4] - compiled_run.signals["fork_mm"])) < 1e-9


def test_a_callback_collected_during_a_registry_operation_does_not_deadlock():
    """The garbage collector may free a dead callback (its finalizer takes the registry lock)
    while this thread is inside a registry operation, holding that lock: a `mtbmj fit drop` in
    CI hung for good on it. In a fresh process, with a timeout. (The rolling registry takes the
    same re-entrant lock.)"""
    script = """
import gc
import mtbmj
from mtbmj import compose
from mtbmj.controllers import compiled
from mtbmj.drop import scene
setup = compose.setup(mtbmj.load_config("S1"))
model = scene.build(setup).model
dead = compiled.CompiledForkCallback(model, setup.fork)
slot = dead.slot
cycle = [dead]
cycle.append(cycle)  # only the cycle collector frees it
del dead, cycle
with compiled.REGISTRY.lock:  # as inside a callback's construction
    gc.collect()  # runs the dead callback's finalizer, which takes the lock
assert not compiled.REGISTRY.owned[slot]
print("done")
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and "done" in done.stdout, done.stderr

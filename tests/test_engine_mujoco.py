"""The MuJoCo side: the control callback's hygiene, integrators, scenes and dm_control."""
import mujoco
import numpy as np
import pytest

import mtbmj
from mtbmj import compose, mjcf as scenes
from mtbmj.drop import engine_mujoco
from mtbmj.drop import scene
from mtbmj.controllers import ForkCallback, installed
from mtbmj.errors import RunError


def test_callback_is_removed_after_a_run_and_previous_one_restored():
    calls = []
    previous = lambda m, d: calls.append(1)  # noqa: E731
    mujoco.set_mjcb_control(previous)
    try:
        mtbmj.run_drop("S1", duration=0.05)
        assert mujoco.get_mjcb_control() is previous
    finally:
        mujoco.set_mjcb_control(None)


def test_callback_is_removed_when_the_run_fails(monkeypatch):
    def explode(*args, **kwargs):
        raise RunError("boom")

    monkeypatch.setattr(engine_mujoco.loop.guard, "check", explode)
    with pytest.raises(RunError):
        mtbmj.run_drop("S1", duration=0.05)
    assert mujoco.get_mjcb_control() is None


def test_callback_never_touches_another_model():
    setup = compose.setup(mtbmj.load_config("S12"))
    ours = scene.build(setup)
    other = scene.build(setup)
    data = mujoco.MjData(other.model)
    data.qvel[other.sled_dof] = 1.0
    callback = ForkCallback(ours.model, setup.fork)
    with installed(callback):
        mujoco.mj_step(other.model, data, nstep=200)
    assert callback.calls == 0
    assert np.all(data.qfrc_applied == 0.0)
    # the other model moves exactly as it does with no callback at all
    alone = mujoco.MjData(other.model)
    alone.qvel[other.sled_dof] = 1.0
    mujoco.mj_step(other.model, alone, nstep=200)
    assert np.array_equal(alone.qpos, data.qpos)


@pytest.mark.parametrize("integrator, calls_per_step", [("euler", 1), ("implicitfast", 1), ("implicit", 1), ("rk4", 4)])
def test_every_integrator_agrees_with_the_reference(integrator, calls_per_step):
    """The callback is evaluated at every stage (4 per RK4 step) and each integrator follows the ODE."""
    overrides = {"solver.integrator": integrator}
    result = mtbmj.run_drop("S12", overrides=overrides, duration=0.5)
    reference = mtbmj.run_drop("S12", engine="ode", overrides=overrides, duration=0.5)
    info = result.trace.info
    assert info["steps_discarded"] > 0  # S12 switches its tire law: a chunk was cut and resumed
    assert info["steps_computed"] >= info["steps"] + info["steps_discarded"]
    if info["substeps"] == 1:
        assert info["steps_computed"] == info["steps"] + info["steps_discarded"]
    assert info["callback_calls"] == calls_per_step * info["steps_computed"]
    worst = max(d["max_abs_mm"] for d in result.difference(reference).values())
    assert worst < 0.1


def test_rk4_is_more_accurate_than_euler_on_the_smooth_linear_model():
    ref = mtbmj.run_drop("S1", engine="ode", duration=0.6)
    step = {"solver.timestep_s": 2e-5}  # the same grid for both (and within euler's limit)
    ref = mtbmj.run_drop("S1", engine="ode", overrides=step, duration=0.6)
    euler = mtbmj.run_drop("S1", overrides={**step, "solver.integrator": "euler"}, duration=0.6)
    rk4 = mtbmj.run_drop("S1", overrides={**step, "solver.integrator": "rk4"}, duration=0.6)
    e_euler = euler.difference(ref)["fork_mm"]["max_abs_mm"]
    e_rk4 = rk4.difference(ref)["fork_mm"]["max_abs_mm"]
    assert e_rk4 < 0.01 and e_rk4 < 0.1 * e_euler  # fourth order against first, on the same grid


def test_lugre_state_is_integrated_by_mujoco():
    """LuGre's bristle state lives in an actuator activation that MuJoCo integrates with the rest of
    the state: at default settings the displacements follow the reference within 0.1 mm; with RK4
    the bristle state itself follows it within 1 % and the displacements within 0.01 mm."""
    overrides = {"fork.friction.model": "lugre", "fork.friction.coulomb_N": 20.0, "fork.friction.breakaway_N": 30.0}
    mj = mtbmj.run_drop("S12", overrides=overrides, duration=0.6)
    ode = mtbmj.run_drop("S12", engine="ode", overrides=overrides, duration=0.6)
    assert max(d["max_abs_mm"] for d in mj.difference(ode).values()) < 0.1
    rk4 = {**overrides, "solver.integrator": "rk4"}
    mj = mtbmj.run_drop("S12", overrides=rk4, duration=0.6)
    ode = mtbmj.run_drop("S12", engine="ode", overrides=rk4, duration=0.6)
    z_ref = ode.trace.friction_state
    assert np.max(np.abs(z_ref)) > 1e-4  # the bristles deflect (about F_C / sigma0)
    assert np.max(np.abs(mj.trace.friction_state - z_ref)) < 0.01 * np.max(np.abs(z_ref))
    assert max(d["max_abs_mm"] for d in mj.difference(ode).values()) < 0.01


@pytest.mark.parametrize("path", scenes.scenes(), ids=lambda p: p.name)
def test_every_scene_compiles_and_steps_without_warnings(path):
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(500):
        data.qfrc_applied[:] = rng.normal(0.0, 20.0, model.nv)
        mujoco.mj_step(model, data)
    assert all(w.number == 0 for w in data.warning)
    for kind, count in (("body", model.nbody), ("joint", model.njnt), ("geom", model.ngeom)):
        for i in range(1 if kind == "body" else 0, count):
            assert getattr(model, kind)(i).name, f"unnamed {kind} {i} in {path.name}"


@pytest.mark.rl
def test_dm_control_physics_steps_the_drop_scene_like_the_engine():
    """The bundled scene through dm_control.mjcf and a dm_control Physics, with our callback,
    reproduces the engine's trace."""
    mjcf = pytest.importorskip("dm_control.mjcf", reason="dm_control is the [rl] extra")
    setup = compose.setup(mtbmj.load_config("S6", {"solver.integrator": "implicitfast", "solver.timestep_s": 2e-5}))
    ours = scene.build(setup)
    root = mjcf.from_path(str(scenes.path("drop_scene.xml")))
    root.option.integrator = "implicitfast"
    root.option.timestep = setup.timestep
    physics = mjcf.Physics.from_mjcf_model(root)
    model = physics.model.ptr
    np.copyto(model.geom_solref, ours.model.geom_solref)
    # the same masses and geometry as the engine's compiled scene (defaults of the preset)
    assert np.allclose(model.body_mass, ours.model.body_mass)
    physics.named.data.qvel["sled"] = setup.impact_speed
    physics.named.data.qpos["sled"] = engine_mujoco.TOUCH_DEPTH_M  # the engine's start at tread touch
    steps = 3000
    callback = ForkCallback(model, setup.fork, floor=ours.floor())  # as the engine's: the contact-floor correction
    fork = np.empty(steps)
    with installed(callback):
        physics.forward()  # dm_control steps as mj_step2 + mj_step1: refresh after setting the state
        for i in range(steps):
            physics.step()
            fork[i] = physics.named.data.qpos["fork"][0]
    engine = engine_mujoco.run(setup, duration=steps * setup.timestep)
    assert callback.calls == steps + 1  # one forward to start, one per step
    assert np.max(np.abs(fork - engine.fork[1:])) < 1e-9

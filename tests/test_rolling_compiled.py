"""The compiled rolling callback (mtbmj.rolling.callback_compiled) against RollCallback, its specification."""
import os
import subprocess
import sys
import warnings

os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco
import numpy as np
import pytest

import mtbmj
from mtbmj.errors import FallbackWarning
from mtbmj import compose
from mtbmj.drop import scene
from mtbmj.rolling import frontend as R
from mtbmj.rolling import terrain as T
from mtbmj.controllers import installed

from helpers import SETTLE_CASES, settle

compiled = pytest.importorskip("mtbmj.controllers.compiled")
CR = pytest.importorskip("mtbmj.rolling.callback_compiled")
if not CR.available():
    pytest.skip(f"compiled path unavailable: {compiled.unavailable_reason()}", allow_module_level=True)

TOL_M = 1e-9  # positions and deflections
TOL_N = 1e-6  # forces (1e-9 m of tire deflection is 7e-5 N; in practice both paths are bit-identical)
FORCES = ("fork_force_N", "axle_force_x_N", "axle_force_z_N", "tire_force_N", "drive_force_N")
LENGTHS = ("fork_mm", "tire_mm", "axle_z_mm", "body_z_mm", "x_m")

SCENARIOS = {
    "washboard": ("washboard", 5.0, 1.5),
    "root": ("root:radius_mm=60,at_m=0.4", 4.0, 1.0),
    "square_edge": ("square_edge:height_mm=50,at_m=0.4", 4.0, 1.0),
    "drum": ("drum:radius_mm=400,cleat_height_mm=20,cleat_at_deg=20", 3.0, 1.0),
    "drop": ("drop:height_mm=200,at_m=0.3", 6.0, 1.0),  # airborne, distance-triggered refreshes
}


def both(scenario, speed, duration, **kwargs):
    py = R.run_roll(scenario, speed, duration=duration, callback="python", **kwargs)
    cc = R.run_roll(scenario, speed, duration=duration, callback="compiled", **kwargs)
    assert py.info["callback"] == "python" and cc.info["callback"] == "compiled"
    return py, cc


def assert_agree(py, cc):
    for name in FORCES:
        diff = np.max(np.abs(py.raw[name] - cc.raw[name]))
        assert diff <= TOL_N, (name, diff)
    for name in LENGTHS:
        scale = 1.0 if name == "x_m" else 1e-3  # to metres
        diff = np.max(np.abs(py.raw[name] - cc.raw[name])) * scale
        assert diff <= TOL_M, (name, diff)
    assert py.info["callback_calls"] == cc.info["callback_calls"]
    assert py.info["geometry_refreshes"] == cc.info["geometry_refreshes"]


@pytest.mark.parametrize("case", list(SCENARIOS))
def test_compiled_and_python_rolling_agree(case):
    scenario, speed, duration = SCENARIOS[case]
    py, cc = both(scenario, speed, duration)
    assert_agree(py, cc)
    assert py.raw["tire_force_N"].max() > 500.0  # the tire was loaded: a real comparison


@pytest.mark.parametrize("overrides", [
    {"fork.friction.model": "lugre", "fork.friction.coulomb_N": 20.0, "fork.friction.breakaway_N": 30.0},
    {"solver.integrator": "rk4"},  # several callback calls per step, at intermediate times
    {"solver.integrator": "euler"},
], ids=["lugre", "rk4", "euler"])
def test_agree_with_stateful_friction_and_other_integrators(overrides):
    py, cc = both("root:radius_mm=60,at_m=0.3", 4.0, 0.5, overrides=overrides)
    assert_agree(py, cc)


def test_agree_on_a_sampled_profile_and_at_another_head_angle():
    ter = T.iso8608("D", seed=2, length_m=20, sample_mm=10)
    py, cc = both(ter, 6.0, 1.0, head_angle_deg=70)
    assert_agree(py, cc)


def test_patch_search_matches_radial_tire():
    """The compiled patch search (polyline, pieces, runs) against RadialTire.patches directly."""
    rng = np.random.default_rng(3)
    cases = [
        (T.step_up(50, at_m=0.19), [(0.0, 0.362)]),
        (T.Terrain("gap", np.array([-2.0, 0.0, 0.0, 0.1, 0.1, 3.0]), np.array([0, 0, -0.2, -0.2, 0, 0.0]), 0.0, 1.0),
         [(0.05, 0.36)]),
        (T.make("washboard"), [(x, 0.36 + 0.02 * rng.random()) for x in rng.uniform(1.0, 5.0, 40)]),
        (T.make("root:radius_mm=50,at_m=1"), [(x, 0.38 + 0.04 * rng.random()) for x in rng.uniform(0.7, 1.4, 40)]),
        (T.iso8608("D", seed=1, length_m=30, sample_mm=10), [(x, 0.35 + 0.05 * rng.random()) for x in
                                                              rng.uniform(0.0, 30.0, 40)]),
        (T.make("drum:radius_mm=500,cleat_height_mm=20,cleat_at_deg=10").with_speed(3.0),
         [(x, 0.36 + 0.01 * rng.random()) for x in rng.uniform(-0.05, 0.05, 40)]),
        (T.make("drum:radius_mm=300,cleat_height_mm=30,cleat_at_deg=-520").with_speed(5.0),  # cleat angle > 2 pi
         [(x, 0.36 + 0.01 * rng.random()) for x in rng.uniform(-0.05, 0.05, 80)]),
    ]
    for ter, points in cases:
        p = R.prepare(ter, 3.0, callback="compiled")
        cb, tire = p.callback, p.tire
        I, F = CR._INTS[cb.slot], CR._FLOATS[cb.slot]
        for k, (cx, cz) in enumerate(points):
            t = 0.013 * k
            CR.refresh_patches(I, F, cx, cz, t)
            expected = tire.patches(cx, cz, t)
            assert len(cb.patches) == len(expected), (ter.name, cx, cz)
            for got, want in zip(cb.patches, expected):
                assert np.max(np.abs(np.subtract(got[:6], want[:6]))) <= 1e-12, (ter.name, cx, cz, got, want)
                assert got[6] == want[6] or abs(got[6] - want[6]) <= 1e-12, (ter.name, cx, cz, got, want)  # the cap
        assert any(len(tire.patches(cx, cz, 0.013 * k)) for k, (cx, cz) in enumerate(points))


def test_static_deflection_on_the_compiled_path(monkeypatch):
    """settle() (tests/helpers.py, as tests/test_rolling.py runs it): static deflection = F / K within
    2 %, on the compiled path."""
    original = R.prepare
    kinds = []

    def prepare(*args, **kwargs):
        p = original(*args, **{**kwargs, "callback": "compiled"})
        kinds.append(R.callback_kind(p.callback))
        return p

    monkeypatch.setattr(R, "prepare", prepare)
    for case, (ter, x) in SETTLE_CASES.items():
        deflection, force, applied, rate = settle(ter, x)
        assert abs(deflection - force / rate) / (force / rate) < 0.02, (case, deflection, force / rate)
        assert abs(applied - force) / force < 0.02, case
    assert kinds == ["compiled"] * len(SETTLE_CASES)


def test_default_path_is_compiled_and_settable_fields_reach_the_slot():
    p = R.prepare("washboard", 5.0, drive="servo")
    cb = p.callback
    assert isinstance(cb, CR.CompiledRollCallback) and cb.active
    assert cb.refreshes == 1 and cb.calls == 1 and len(cb.patches) == 1  # mj_forward at t = 0
    cb.speed, cb.x_ref0 = 2.5, 0.125
    model, data = p.front.model, p.data
    cb(model, data)
    assert data.ctrl[cb.a_dv] == 2.5 and data.ctrl[cb.a_dp] == 0.125 + 2.5 * data.time
    cb.reset()
    assert cb.patches == [] and cb.next_refresh == -np.inf
    cb(model, data)
    assert cb.refreshes == 2 and len(cb.patches) == 1
    cb.damper_scale = 0.5
    assert cb.damper_scale == 0.5


def test_the_rider_drive_writes_its_force_through_the_servo_actuators():
    """The rider's drive reaches MuJoCo through the servo's two actuators: the position one's
    reference is the chassis' own x (force 0), the velocity one's v + F / kv (force F)."""
    p = R.prepare("washboard", 5.0)
    cb, model, data = p.callback, p.front.model, p.data
    assert cb.drive.mode == "rider"
    data.qvel[cb.xv] = 4.9  # 0.1 m/s slow: the rider pushes kv x 0.1, within the limits
    cb(model, data)
    assert data.ctrl[cb.a_dp] == data.qpos[cb.xq]
    force = (data.ctrl[cb.a_dv] - data.qvel[cb.xv]) * cb.drive.kv
    assert force == pytest.approx(min(cb.drive.kv * 0.1, cb.drive.power / 4.9), rel=1e-9)
    cb.damper_scale = None
    assert cb.damper_scale is None


def test_scaled_damper_agrees():
    """The semi-active damper scale (mtbmj.rolling.env's command) on both paths."""
    out = {}
    for kind in ("python", "compiled"):
        p = R.prepare("root:radius_mm=60,at_m=0.3", 4.0, callback=kind)
        p.callback.damper_scale = 0.4
        out[kind] = R.simulate(p, 0.4)
    assert np.max(np.abs(out["python"][0] - out["compiled"][0])) <= TOL_M
    assert np.max(np.abs(out["python"][1] - out["compiled"][1])) <= TOL_N


def test_the_callback_never_touches_another_model():
    p = R.prepare("washboard", 5.0)
    setup = compose.setup(mtbmj.load_config("S1"))
    other = scene.build(setup).model
    d = mujoco.MjData(other)
    calls = p.callback.calls
    with installed(p.callback):
        for _ in range(20):
            mujoco.mj_step(other, d)
    assert not d.ctrl.any() and not d.qfrc_applied.any()
    assert p.callback.calls == calls


def test_fork_dispatcher_leaves_rolling_models_alone():
    """The drop's compiled fork callback (its own registry) does not act on a rolling model."""
    p = R.prepare("washboard", 5.0)
    setup = compose.setup(mtbmj.load_config("S1"))
    fork_cb = compiled.CompiledForkCallback(scene.build(setup).model, setup.fork)
    d = mujoco.MjData(p.front.model)
    with installed(fork_cb):
        mujoco.mj_step(p.front.model, d)
    assert not d.ctrl.any() and not d.qfrc_applied.any()


def test_a_collected_callback_frees_its_slot():
    import gc

    p = R.prepare("washboard", 5.0)
    slot = p.callback.slot
    assert CR.REGISTRY.owned[slot]
    del p
    gc.collect()
    assert not CR.REGISTRY.owned[slot] and CR._INTS[slot, CR.R_MODEL] == 0


def test_too_many_patches_reruns_on_the_python_path():
    # a comb: 1 mm teeth every 3 mm, 150 mm deep slots: ~80 patches under the tire at once
    pitch, tooth, depth = 0.003, 0.001, 0.15
    xs, zs = [-2.0, 0.0], [0.0, 0.0]
    for k in range(400):
        a = 0.2 + k * pitch
        xs += [a, a, a + pitch - tooth, a + pitch - tooth]
        zs += [0.0, -depth, -depth, 0.0]
    xs += [0.2 + 400 * pitch + 3.0]
    zs += [0.0]
    ter = T.Terrain("comb", np.array(xs), np.array(zs), 0.5, 1.0)
    assert len(R.prepare(ter, 1.0, callback="python").tire.patches(0.5, 0.365)) > CR.MAX_PATCHES
    p = R.prepare(ter, 1.0, callback="compiled")
    assert p.callback.overflowed
    with pytest.warns(FallbackWarning, match="too many contact patches"):
        states, sensors = R.simulate(p, 0.05)
    assert R.callback_kind(p.callback) == "python"
    q = R.prepare(ter, 1.0, callback="python")
    ref_states, ref_sensors = R.simulate(q, 0.05)
    assert np.max(np.abs(states - ref_states)) <= TOL_M and np.max(np.abs(sensors - ref_sensors)) <= TOL_N


def test_fallback_without_numba(monkeypatch):
    monkeypatch.setattr(compiled, "numba", None)
    monkeypatch.setattr(compiled, "_WARNED", set())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = R.run_roll("root:at_m=0.3", 4.0, duration=0.2)
        again = R.run_roll("root:at_m=0.3", 4.0, duration=0.2)
    assert r.info["callback"] == again.info["callback"] == "python"
    assert [str(w.message) for w in caught] == [compiled.FALLBACK_MESSAGE]
    assert isinstance(R.prepare("flat", 2.0).callback, R.RollCallback)
    monkeypatch.undo()
    c = R.run_roll("root:at_m=0.3", 4.0, duration=0.2)
    assert c.info["callback"] == "compiled"
    assert_agree(r, c)


def test_unsupported_terrain_falls_back(monkeypatch):
    class Wavy(T.Terrain):  # a subclass may override polyline(): the Python path runs it
        pass

    base = T.make("root:at_m=0.3")
    ter = Wavy(base.name, base.x, base.z, base.start_x, base.length, base.params)
    monkeypatch.setattr(compiled, "_WARNED", set())
    with pytest.warns(FallbackWarning, match="no compiled form"):
        p = R.prepare(ter, 4.0)
    assert isinstance(p.callback, R.RollCallback)
    with pytest.raises(CR.UnsupportedRolling):
        R.prepare(ter, 4.0, callback="compiled")


def test_bad_callback_choice_is_a_config_error():
    with pytest.raises(mtbmj.ConfigError, match="callback"):
        R.prepare("flat", 2.0, callback="fast")


def test_without_numba_installed_rolling_runs_on_the_python_path():
    """A fresh interpreter in which ``import numba`` fails."""
    code = """
import sys, warnings
sys.modules["numba"] = None
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    from mtbmj.rolling import frontend as rolling
    from mtbmj.rolling import callback_compiled as compiled_rolling
    assert not compiled_rolling.available()
    r = rolling.run_roll("washboard", 5.0, duration=0.05)
messages = [str(w.message) for w in caught if "numba" in str(w.message)]
assert messages == ["numba not installed: using the Python force laws"], messages
print("ok", r.info["callback"], r.info["steps"])
"""
    env = {**os.environ, "MUJOCO_GL": "disable"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=180, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("ok python 100")  # 0.05 s at the 0.5 ms coarse step

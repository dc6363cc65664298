"""Physics checks: the engines against closed forms, each other and conservation laws."""
import math

import mujoco
import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

import mtbmj
from mtbmj import compose
from mtbmj.drop import scene

G = 9.81


def test_tire_static_deflection_is_load_over_rate():
    """Resting on the floor, the tire carries the whole weight: deflection = (m_b + m_w) g / k."""
    cfg = mtbmj.load_config("S1", {"fork.damper.coefficient_N_s_per_m": 4000.0, "tire.impact_damping_N_s_per_m": 800.0})
    result = mtbmj.run_drop(cfg, duration=2.5)
    k = cfg["tire.impact_rate_N_per_mm"] * 1e3
    expected_mm = (cfg["sled.body_mass_kg"] + cfg["sled.wheel_mass_kg"]) * G / k * 1e3
    assert result.raw["tire_mm"][-1] == pytest.approx(expected_mm, rel=0.01)
    # and the tire force balances the weight
    assert result.raw["tire_force_N"][-1] == pytest.approx((cfg["sled.body_mass_kg"] + cfg["sled.wheel_mass_kg"]) * G, rel=0.01)


@pytest.mark.parametrize("rate, damping", [(80e3, 150.0), (58e3, 0.0), (120e3, 400.0)])
def test_mujoco_contact_force_is_the_configured_spring_and_damper(rate, damping):
    """mj_contactForce during an impact equals max(0, k d + b dd/dt): N/m and N s/m, not solref units."""
    setup = compose.setup(mtbmj.load_config("S1"))
    sc = scene.build(setup)
    sc.set_tire(rate, damping)
    m = sc.model
    d = mujoco.MjData(m)
    d.qvel[sc.sled_dof] = setup.impact_speed
    force = np.zeros(6)
    worst, peak, pulls = 0.0, 0.0, 0
    for _ in range(3000):
        mujoco.mj_step(m, d)
        mujoco.mj_forward(m, d)
        deflection = d.qpos[sc.sled_qpos] - d.qpos[sc.fork_qpos]
        rate_of = d.qvel[sc.sled_dof] - d.qvel[sc.fork_dof]
        expected = max(0.0, rate * deflection + damping * rate_of) if deflection > 0 else 0.0
        actual = 0.0
        for i in range(d.ncon):
            mujoco.mj_contactForce(m, d, i, force)
            actual += force[0]
            pulls += force[0] < -1e-9
        worst = max(worst, abs(actual - expected))
        peak = max(peak, expected)
    assert peak > 500.0
    assert pulls == 0
    assert worst < 1e-3 * peak


def test_tire_pushes_never_pulls_and_wheel_lands_again():
    result = mtbmj.run_drop("S12")
    s = result.summary
    assert s["lifts_off"] and s["landing_s"] is not None and s["landing_s"] > s["lift_off_s"]
    assert np.all(result.raw["tire_force_N"] >= 0.0)
    air = (result.raw["time_s"] > s["lift_off_s"] + 0.01) & (result.raw["time_s"] < s["landing_s"] - 0.01)
    assert np.all(result.raw["tire_mm"][air] < 0.0)  # tread off the ground
    assert np.all(result.raw["tire_force_N"][air] == 0.0)


def test_impact_speed_from_free_fall_matches_sqrt_2gh():
    """Released h0 above the touch point, MuJoCo's sled reaches the floor at sqrt(2 g h0)."""
    setup = compose.setup(mtbmj.load_config("S1"))
    sc = scene.build(setup)
    m = sc.model
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    d = mujoco.MjData(m)
    d.qpos[sc.sled_qpos] = -setup.drop_height
    while d.qpos[sc.sled_qpos] - d.qpos[sc.fork_qpos] < 0.0:
        mujoco.mj_step(m, d)
    # interpolate back to the touch instant within the last step
    speed = d.qvel[sc.sled_dof]
    overshoot = d.qpos[sc.sled_qpos] - d.qpos[sc.fork_qpos]
    speed_at_touch = math.sqrt(max(speed**2 - 2 * G * overshoot, 0.0))
    assert speed_at_touch == pytest.approx(math.sqrt(2 * G * setup.drop_height), rel=1e-3)
    assert setup.impact_speed == pytest.approx(1.3652, abs=1e-4)  # paper: h0 = 95 mm


def _linear_state_matrix(setup):
    mb, mw = setup.body_mass, setup.wheel_mass
    k, c = setup.fork.spring.main.rate, setup.fork.damper.coefficient
    kt, bt = setup.tire.impact.rate, setup.tire.impact.damping
    # y = [s, x, sd, xd, 1]; w = s - x; F_f = k x + c xd; F_t = kt w + bt wd
    a = np.zeros((5, 5))
    a[0, 2] = a[1, 3] = 1.0
    # s'' = g - F_f / mb
    a[2, 1], a[2, 3], a[2, 4] = -k / mb, -c / mb, G
    # w'' = g + (F_f - F_t)/mw ; x'' = s'' - w''
    wdd = np.zeros(5)
    wdd[1], wdd[3], wdd[4] = k / mw, c / mw, G
    wdd[0] += -kt / mw
    wdd[1] += kt / mw
    wdd[2] += -bt / mw
    wdd[3] += bt / mw
    a[3] = a[2] - wdd
    return a


def test_linear_model_in_contact_matches_matrix_exponential():
    """S1 while the tire pushes: the ODE reference equals expm(A t) y0 to 1e-6 m."""
    cfg = mtbmj.load_config("S1")
    setup = compose.setup(cfg)
    ode = mtbmj.run_drop(cfg, engine="ode", duration=0.6)
    a = _linear_state_matrix(setup)
    y0 = np.array([0.0, 0.0, setup.impact_speed, 0.0, 1.0])
    t = ode.raw["time_s"]
    pushing = ode.raw["tire_force_N"] > 0.0
    first_gap = np.argmin(pushing[1:]) + 1 if not pushing[1:].all() else len(t)
    span = slice(1, first_gap)
    assert t[span][-1] > 0.1  # a real stretch of contact is compared
    exact = np.array([expm(a * ti) @ y0 for ti in t[span]])
    assert np.max(np.abs(exact[:, 0] - ode.trace.sled[span])) < 1e-6
    assert np.max(np.abs(exact[:, 1] - ode.trace.fork[span])) < 1e-6
    mj = mtbmj.run_drop(cfg, duration=0.6)
    assert np.max(np.abs(exact[:, 1] - mj.trace.fork[span])) < 1e-5  # MuJoCo: RK4 at the chosen step


def test_undamped_system_conserves_energy():
    """No fork damping, no friction, an undamped tire, undamped end stops: the ODE reference
    dissipates nothing (the stops' and the rim's springs store what they take)."""
    cfg = mtbmj.load_config("S1", {"fork.damper.coefficient_N_s_per_m": 0.0, "tire.model": "undamped",
                                   "fork.stops.stop_damping_N_s_per_m": 0.0, "tire.rim_damping_N_s_per_m": 0.0})
    ode = mtbmj.run_drop(cfg, engine="ode", duration=1.0)
    energy = ode.summary["energy"]
    assert abs(energy["dissipated_J"]) < 1e-4 * energy["input_J"]
    mj = mtbmj.run_drop(cfg, duration=1.0)
    assert abs(mj.summary["energy"]["dissipated_J"]) < 0.01 * energy["input_J"]


def test_dissipated_energy_equals_damper_work():
    """With only the fork damper dissipating, E_in - E_end equals the integral of c v^2."""
    c = 400.0
    cfg = mtbmj.load_config("S1", {"fork.damper.coefficient_N_s_per_m": c, "tire.model": "undamped"})
    ode = mtbmj.run_drop(cfg, engine="ode", duration=1.0)
    v = ode.trace.fork_velocity
    work = np.trapezoid(c * v * v, ode.trace.time)
    assert ode.summary["energy"]["dissipated_J"] == pytest.approx(work, rel=1e-3)


def test_static_sag_matches_closed_form():
    """At rest the fork carries the body: P + k x + c x^3 = m_b g (progressive + preload, S7)."""
    cfg = mtbmj.load_config("S7", {"fork.damper.coefficient_N_s_per_m": 3000.0})
    setup = compose.setup(cfg)
    result = mtbmj.run_drop(cfg, duration=3.0)
    load = setup.body_mass * G
    sag = brentq(lambda x: setup.fork.spring.force(x, 0.0) - load, 0.0, setup.travel)
    top_out = setup.fork.spring.main  # inside the end stops
    spring = top_out.main
    closed = brentq(lambda x: top_out.preload + spring.rate * x + spring.cubic * x**3 - load, 0.0, 0.2)
    assert sag == pytest.approx(closed, rel=1e-9)
    assert result.raw["fork_mm"][-1] == pytest.approx(closed * 1e3, rel=0.005)


@pytest.mark.parametrize("preset", ["S1", "S6", "S12"])
def test_runs_are_deterministic_and_finite(preset):
    a = mtbmj.run_drop(preset, duration=0.4)
    b = mtbmj.run_drop(preset, duration=0.4)
    for column in ("sled_mm", "fork_mm", "tire_mm", "fork_force_N", "tire_force_N"):
        assert np.all(np.isfinite(a.raw[column]))
        assert np.array_equal(a.raw[column], b.raw[column])


@pytest.mark.parametrize("kind", ["python", "compiled"])
def test_mujoco_accelerations_are_the_reference_equations_in_contact(kind):
    """At random in-contact states of random plausible forks, MuJoCo's accelerations (contact,
    callback and gravity together) are the reference's eqs. 2-3 written out here: the soft
    contact's impedance floor (a relative 1e-4 of the other forces on the wheel) is cancelled by
    the callback, before and after the tire switch."""
    from mtbmj.drop.engine_mujoco import fork_callback
    from mtbmj.drop.envelope import draws
    from mtbmj.controllers import installed

    rng = np.random.default_rng(515)
    table = list(mtbmj.load_config("reference").require("fork.damper.force_N"))
    worst = 0.0
    for preset, overrides in draws(6, 515, table):
        setup = compose.setup(mtbmj.load_config(preset, overrides))
        sc = scene.build(setup)
        m, d = sc.model, mujoco.MjData(sc.model)
        callback = fork_callback(m, setup.fork, kind, setup.tire.rim, sc.floor())
        mb, mw, g = setup.body_mass, setup.wheel_mass, setup.gravity
        for phase in (0, 1):
            tire = setup.tire.values(phase)
            sc.set_tire(tire.rate, tire.damping, callback)
            for _ in range(20):
                x = rng.uniform(-0.005, setup.travel)
                deflection = rng.uniform(1e-4, 0.03)
                v, w = rng.uniform(-3.0, 3.0, 2)
                d.qpos[sc.sled_qpos], d.qpos[sc.fork_qpos] = x + deflection, x
                d.qvel[sc.sled_dof], d.qvel[sc.fork_dof] = v + w, v
                d.act[:] = rng.uniform(-1e-4, 1e-4, m.na)
                with installed(callback):
                    mujoco.mj_forward(m, d)
                z = d.act[0] if m.na else 0.0
                fork = setup.fork.force(x, v, z)
                tire_force = setup.tire.force(deflection, w, phase)
                sled_acc = g - fork / mb
                wheel_acc = g + (fork - tire_force) / mw  # descent of the wheel
                scale = (abs(fork) + abs(tire_force)) / mw + g
                worst = max(worst, abs(d.qacc[sc.sled_dof] - sled_acc) / scale,
                            abs(d.qacc[sc.fork_dof] - (sled_acc - wheel_acc)) / scale)
    assert worst < 1e-8

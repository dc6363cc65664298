"""The compiled bike callback (mtbmj.bike.callback_compiled) against BikeCallback, its specification:
the same run state by state on several terrains, the fallbacks, the overflow rerun."""
from __future__ import annotations

import dataclasses
import os
import warnings

os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco
import numpy as np
import pytest

import mtbmj
from mtbmj.bike import run as B
from mtbmj.bike import spec as S
from mtbmj.errors import FallbackWarning
from mtbmj.rolling import terrain as T

from helpers import rock_garden

compiled = pytest.importorskip("mtbmj.controllers.compiled")
CB = pytest.importorskip("mtbmj.bike.callback_compiled")
if not CB.available():
    pytest.skip(f"compiled path unavailable: {compiled.unavailable_reason()}", allow_module_level=True)

TOL = 1e-9  # each state variable (m, rad, m/s, rad/s, friction states); in practice ~1e-13
TOL_N = 1e-6  # each sensor (forces N, deflections m, accelerations m/s2)


def _rock_garden(tmp_path):
    return str(rock_garden(tmp_path / "rocks.csv"))


def both(bike, scenario, speed, duration, **kwargs):
    runs = []
    for kind in ("python", "compiled"):
        p = B.prepare(bike, scenario, speed, callback=kind, **kwargs)
        assert B.callback_kind(p.callback) == kind
        states, sensors = B.simulate(p, duration)
        runs.append((p, states, sensors))
    return runs


def assert_agree(runs):
    (pp, sp, ep), (pc, sc, ec) = runs
    # the prepared states (static equilibrium, mj_forward with each callback) and every step after
    assert np.max(np.abs(sp - sc)) <= TOL, np.unravel_index(np.argmax(np.abs(sp - sc)), sp.shape)
    assert np.max(np.abs(ep - ec)) <= TOL_N
    assert pp.callback.calls == pc.callback.calls
    assert pp.callback.refreshes == pc.callback.refreshes
    for k in (0, 1):  # each tire's contact patches at the end
        assert len(pp.callback.patches[k]) == len(pc.callback.patches(k))
        for want, got in zip(pp.callback.patches[k], pc.callback.patches(k)):
            assert np.all(np.isclose(want, got, rtol=0.0, atol=TOL))  # (a lone contact's prominence: inf)
    return float(np.max(np.abs(sp - sc)))


CASES = {  # scenario, speed, duration, front axle's start: each feature met by the front tire (the root by both)
    "root": ("root:at_m=0.4", 5.0, 0.45, None),
    "square_edge": ("square_edge:at_m=0.4,height_mm=40", 5.0, 0.2, None),
    "drop": ("drop:at_m=0.4,height_mm=150", 6.0, 0.3, None),
    "rough": ("iso8608:class=D,length_m=10,seed=3", 5.0, 0.25, 1.1),  # sampled every 10 mm from 1.5 m
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_and_python_bike_agree_state_by_state(case):
    scenario, speed, duration, start = CASES[case]
    runs = both("sst", scenario, speed, duration, start_x=start)
    assert_agree(runs)
    _, _, sensors = runs[1]
    model = runs[1][0].bike.model
    front = sensors[:, model.sensor_adr[model.sensor("front_tire_z").id]]
    assert front.max() > (1.05 if case == "rough" else 1.3) * front[0]  # the front tire met the feature


def test_agree_on_the_rock_garden_coasting_with_the_trail_bike(tmp_path):
    assert_agree(both("trail", _rock_garden(tmp_path), 5.0, 0.25, drive="coast"))


def test_agree_with_stateful_friction_at_both_ends():
    lugre = {"fork.friction.model": "lugre", "fork.friction.coulomb_N": 20.0, "fork.friction.breakaway_N": 30.0}
    base = S.load("sst")
    bike = dataclasses.replace(base, fork_overrides={**base.fork_overrides, **lugre},
                               shock_overrides={**base.shock_overrides, **lugre})
    runs = both(bike, "root:at_m=0.4", 5.0, 0.2)
    assert runs[0][0].fork_law.has_state and runs[0][0].shock_law.has_state
    assert_agree(runs)


def test_the_leverage_lookups_are_the_spec_functions_compiled():
    lev = S.load("sst").leverage
    w_tab, r, s = (np.array(v) for v in lev.table)
    for w in np.concatenate((np.linspace(-0.01, w_tab[-1] + 0.01, 301), w_tab)):
        i = CB.piece_index(w_tab, w_tab.size, w)
        assert CB._leverage_ratio(w_tab, r, i, w) == lev.ratio_at(w)
        assert CB._leverage_stroke(w_tab, r, s, i, w) == lev.stroke(w)


def test_kinematics_offsets_are_mujocos():
    from mtbmj.controllers.native_data import _struct

    p = B.prepare("sst", "flat", 4.0)
    layout = CB.kinematics_layout(p.bike.model)
    assert layout == {name: getattr(_struct("mjData"), name).offset for name in CB.KINEMATICS}


def test_default_is_compiled_and_the_run_says_so():
    r = B.run_bike("sst", "flat", 4.0, duration=0.05)
    assert r.info["callback"] == "compiled"
    assert r.info["timestep_s"] == 5e-4 and r.info["refined_fraction"] == 0.0  # flat: the coarse step throughout
    assert r.info["callback_calls"] == 4 * 100 + 1  # RK4, and the mj_forward of prepare


def test_too_many_patches_reruns_on_the_python_path():
    # a comb: 0.7 mm teeth every 2 mm, 150 mm deep slots: ~85 patches under the tire at once
    pitch, tooth, depth = 0.002, 0.0007, 0.15
    xs, zs = [-3.0, 0.0], [0.0, 0.0]
    for k in range(400):
        a = 0.2 + k * pitch
        xs += [a, a, a + pitch - tooth, a + pitch - tooth]
        zs += [0.0, -depth, -depth, 0.0]
    xs += [0.2 + 400 * pitch + 3.0]
    zs += [0.0]
    ter = T.Terrain("comb", np.array(xs), np.array(zs), -0.2, 1.0)
    p = B.prepare("sst", ter, 8.0, callback="compiled")
    with pytest.warns(FallbackWarning, match="too many contact patches"):
        states, sensors = B.simulate(p, 0.07)
    assert B.callback_kind(p.callback) == "python"
    q = B.prepare("sst", ter, 8.0, callback="python")
    assert len(q.front_tire.patches(0.6, q.front_tire.radius)) > CB.MAX_PATCHES
    ref_states, ref_sensors = B.simulate(q, 0.07)
    assert np.max(np.abs(states - ref_states)) <= TOL and np.max(np.abs(sensors - ref_sensors)) <= TOL_N


def test_fallback_without_numba(monkeypatch):
    monkeypatch.setattr(compiled, "numba", None)
    monkeypatch.setattr(compiled, "_WARNED", set())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = B.run_bike("sst", "flat", 4.0, duration=0.02)
        again = B.run_bike("sst", "flat", 4.0, duration=0.02)
    assert r.info["callback"] == again.info["callback"] == "python"
    assert [str(w.message) for w in caught] == [compiled.FALLBACK_MESSAGE]


def test_unsupported_terrain_falls_back(monkeypatch):
    class Wavy(T.Terrain):  # a subclass may override polyline(): the Python path runs it
        pass

    base = T.make("root:at_m=0.4")
    ter = Wavy(base.name, base.x, base.z, base.start_x, base.length, base.params)
    monkeypatch.setattr(compiled, "_WARNED", set())
    with pytest.warns(FallbackWarning, match="no compiled form"):
        p = B.prepare("sst", ter, 4.0)
    assert B.callback_kind(p.callback) == "python"
    with pytest.raises(CB.UnsupportedRolling):
        B.prepare("sst", ter, 4.0, callback="compiled")


def test_bad_callback_choice_is_a_config_error():
    with pytest.raises(mtbmj.ConfigError, match="callback"):
        B.prepare("sst", "flat", 4.0, callback="fast")


def test_the_compiled_callback_leaves_other_models_alone():
    p = B.prepare("sst", "flat", 4.0)
    other = B.prepare("sst", "flat", 4.0, callback="python")
    d = mujoco.MjData(other.bike.model)
    calls = p.callback.calls
    p.callback(other.bike.model, d)
    assert p.callback.calls == calls and not np.any(d.ctrl)

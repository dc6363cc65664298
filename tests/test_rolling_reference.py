"""The rolling front end's ODE reference (issue 25): the same model as ``mtbmj roll`` integrated
by scipy with the terrain's exact closest points at every evaluation, and the cross-check of
MuJoCo against it. Its mass matrix is MuJoCo's own (written out in closed form), it holds a
settled front end exactly, it converges with its step, and MuJoCo's runs agree with it within
0.02 mm and 1 % of the axle force peaks at default settings."""
from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from mtbmj import cli
from mtbmj.rolling.frontend import prepare, run_roll
from mtbmj.rolling.reference import FORCE_TOLERANCE, TOLERANCE_MM, Reference, crosscheck, mass_matrix


@pytest.mark.parametrize("head_angle", [65.0, 90.0, 50.0])
def test_the_mass_matrix_is_mujocos(head_angle):
    p = prepare("washboard", 5.0, head_angle_deg=head_angle, callback="python")
    model, data = p.front.model, p.data
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, full, data.qM) if hasattr(data, "qM") else mujoco.mj_fullM(model, data, full)
    cb = p.callback
    dofs = [cb.xv, cb.zv, cb.fv]
    ours = mass_matrix(p.setup.body_mass, p.setup.wheel_mass, np.radians(head_angle))
    assert np.max(np.abs(full[np.ix_(dofs, dofs)] - ours)) < 1e-12


def test_a_settled_front_end_on_flat_ground_stays_exactly_where_mujoco_holds_it():
    engine = run_roll("flat", 4.0, duration=0.3, callback="python")
    ref = Reference(prepare("flat", 4.0, callback="python")).run(engine.raw["time_s"], max_step=1e-3)
    for column in ("fork_mm", "body_z_mm", "tire_mm", "axle_force_z_N"):
        assert np.max(np.abs(engine.raw[column] - ref[column])) < 1e-8, column


def test_the_reference_converges_with_its_step():
    times = np.arange(3000) * 1e-4
    a = Reference(prepare("root", 4.0, callback="python")).run(times, max_step=1e-3)
    b = Reference(prepare("root", 4.0, callback="python")).run(times, max_step=2.5e-4)
    assert np.max(np.abs(a["fork_mm"] - b["fork_mm"])) < 1e-4


# every fixed terrain of the library, its feature 0.4 m ahead so that 0.5 s covers it, at 2 or 5 m/s
# in turn (benchmarks/rolling_crosscheck.py runs each at both speeds)
LIBRARY = [("step_up:at_m=0.4", 2.0, None), ("step_down:at_m=0.4", 5.0, None), ("square_edge:at_m=0.4", 2.0, None),
           ("root:at_m=0.4", 5.0, None), ("rock:at_m=0.4", 2.0, None), ("drop:at_m=0.4", 5.0, None),
           ("washboard:at_m=0.4", 2.0, 90.0), ("iso8608:at_m=0.4,length_m=1", 5.0, None),
           ("rock_garden:at_m=0.4", 5.0, None)]


@pytest.mark.parametrize("scenario, speed, head_angle", LIBRARY)
def test_mujoco_agrees_with_the_rolling_reference(scenario, speed, head_angle):
    check = crosscheck(scenario, speed, head_angle_deg=head_angle, duration=0.5)
    assert check.passed, check.line()
    # the body, the axle and the tire in contact are as close as the fork
    assert all(check[name].max_abs <= TOLERANCE_MM for name in ("fork", "body_height", "axle_height", "tire")), \
        check.line()
    assert all(check[name].peak_difference <= FORCE_TOLERANCE for name in ("axle_force_up", "axle_force_back"))


def test_the_old_geometry_refresh_fails_the_crosscheck(monkeypatch):
    """The check can fail: with the contact patches refreshed every 1 ms / 5 mm (the old default)
    the fork on the 50 mm root is 0.1 mm off the reference."""
    import mtbmj.rolling.frontend as frontend
    import mtbmj.rolling.tire as tire

    for module in (frontend, tire):  # the Python callback reads the one, the compiled callback the other
        monkeypatch.setattr(module, "REFRESH_S", 1e-3)
        monkeypatch.setattr(module, "REFRESH_DISTANCE_M", 5e-3)
    check = crosscheck("root:at_m=0.4", 4.0, duration=0.3, drive="servo")
    assert not check.passed and check["fork"].max_abs > 0.05


def test_the_crosscheck_command(capsys):
    assert cli.main(["crosscheck", "S12", "--roll", "square_edge:at_m=0.3", "--speed", "2", "--duration", "0.4"]) == 0
    out = capsys.readouterr().out
    assert "MuJoCo vs the rolling ODE reference" in out and "within the tolerances" in out
    assert "fork " in out and "(tol. 0.02 mm)" in out and "axle force up peak" in out and "(tol. 1 %)" in out
    assert cli.main(["crosscheck", "S12", "--roll", "root"]) == 2
    assert "--speed" in capsys.readouterr().err
    assert cli.main(["crosscheck", "S12", "--roll", "drum", "--speed", "3", "--duration", "0.2"]) == 2
    assert "drum" in capsys.readouterr().err

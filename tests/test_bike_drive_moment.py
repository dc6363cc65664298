"""Drive and brake with their moments (issue 39 item 1): the ground's force on a tyre acts at its
contact patch. On a steady climb and a steady braked descent the tyre loads are checked against a
moment balance written here, from the run's geometry alone (where the centre of mass and the two
contact patches are): about the rear patch, only the front tyre's normal force and the weight
have a moment (the ground's tangential forces lie along the slope through both patches), so
N_front = (the weight's moment about the rear patch) / (the front patch's lever). Before, the
drive acted at the rear axle with no couple: 298 N on the front tyre of the climb, 235-241 N from
the contact patch; and a rear-only brake ran away on a 40 % descent."""
from __future__ import annotations

import math

import numpy as np
import pytest

import mtbmj

from helpers import last_pose, slope_profile

G = 9.81


def _balance(result, grade: float) -> tuple[float, float]:
    """(the front tyre's normal force by the moment balance, the weight) at the run's last sample."""
    p = result.prepared
    model, data = last_pose(result)
    frame = model.body("frame").id
    com = data.subtree_com[frame][[0, 2]]
    mass = float(model.body_subtreemass[frame])
    a = math.atan(grade)
    normal = np.array([-math.sin(a), math.cos(a)])  # the slope's normal, out of the ground
    raw = result.raw
    patches = []
    for end in ("front", "rear"):
        axle = data.site_xpos[model.site(f"{end}_axle").id][[0, 2]]
        depth = max(raw[f"{end}_tire_mm"][-1], 0.0) * 1e-3
        patches.append(axle - (p.front_tire.radius - depth) * normal)
    cross = lambda r, f: r[1] * f[0] - r[0] * f[1]  # noqa: E731 - the y component of r x f (x, z)
    weight = np.array([0.0, -mass * G])
    lever = cross(patches[0] - patches[1], normal)
    return -cross(com - patches[1], weight) / lever, mass * G


@pytest.mark.parametrize("grade,what", [(0.2, "climb"), (-0.4, "descent")])
def test_steady_tyre_loads_match_the_moment_balance(tmp_path, grade, what):
    r = mtbmj.run_bike("trail", slope_profile(tmp_path, grade, what), speed_m_per_s=4.0, duration=10.0)
    raw = r.raw
    assert r.summary["crash"] is None
    assert abs(raw["speed_m_per_s"][-1] - 4.0) < 0.05  # held at the set speed: steady
    assert np.ptp(raw["front_tire_N"][-200:]) < 0.01 * raw["front_tire_N"][-1]  # and settled
    front, weight = _balance(r, grade)
    assert raw["front_tire_N"][-1] == pytest.approx(front, rel=0.01)
    # both tyres together carry the weight's normal component
    a = math.atan(grade)
    assert raw["front_tire_N"][-1] + raw["rear_tire_N"][-1] == pytest.approx(weight * math.cos(a), rel=0.01)
    # the drive holds the weight's component along the slope (pushing up, braking down)
    assert raw["drive_force_N"][-1] == pytest.approx(weight * math.sin(a), rel=0.02)

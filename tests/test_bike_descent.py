"""The whole bike on a steady descent, which ``mtbmj advise --static-sag-mm ... --carried-as descent`` rides:
the terrain laid on a grade (``mtbmj.rolling.terrain.on_grade``), and the engine's loads there against a
moment balance written here.

What the balance shares with the engine: the bike's masses and the rider's place (read from MuJoCo's own
model at the start, ``subtree_com``, not from the package's statics), and rigid bodies on a straight
slope. What it does not: it knows nothing of the tyres, the suspension, the rider's limbs or the drive's
law; a rider who slid forward on their limbs under the slope's pull, or a drive that did not hold the
speed, would show as a miss."""
from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from mtbmj.bike.run import run_bike
from mtbmj.rolling import terrain as terrain_mod

GRADE = -15.0  # percent: a descent of 8.5 deg, as the shared rides' loads read
SPEED = 5.0


def _steady(r, x_lo, x_hi):
    """The run's means over the front axle's stretch [x_lo, x_hi] (m): (front tyre N, rear tyre N, drive N)."""
    raw = r.raw
    k = (raw["front_axle_x_m"] >= x_lo) & (raw["front_axle_x_m"] <= x_hi)
    assert k.sum() > 100, "the stretch was not ridden"
    return tuple(float(np.mean(raw[c][k])) for c in ("front_tire_N", "rear_tire_N", "drive_force_N"))


def _balance(r, theta, x_lo, x_hi, radius):
    """The front tyre's load a moment balance about the rear tyre's patch gives, over the run's states on the
    stretch (MuJoCo's centre of mass and wheel centres per sampled state, in the slope's frame, averaged):
    N_f = m g (cos(theta) a + sin(theta) h) / L, with a the centre of mass along the slope from the rear
    patch, h its height above the slope's line, L the patches' distance; and h, L themselves."""
    p = r.prepared
    m, d = p.bike.model, mujoco.MjData(p.bike.model)
    u, n = np.array([math.cos(theta), -math.sin(theta)]), np.array([math.sin(theta), math.cos(theta)])
    t, rows = r.motion
    geo = []
    for q in rows:
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        wf, wr = d.xpos[m.body("front_wheel").id][[0, 2]], d.xpos[m.body("rear_wheel").id][[0, 2]]
        if not x_lo <= wf[0] <= x_hi:
            continue
        patch = wr - radius * n
        c = d.subtree_com[0][[0, 2]] - patch
        geo.append((c @ u, c @ n, (wf - wr) @ u))
    assert len(geo) > 50, "the stretch was not ridden"
    a, h, wheelbase = np.mean(geo, axis=0)
    mass = float(m.body_subtreemass[0])
    return mass * 9.81 * (math.cos(theta) * a + math.sin(theta) * h) / wheelbase, h, wheelbase, mass


def test_the_whole_bike_on_a_steady_descent_carries_load_forward_as_a_moment_balance_says():
    """At a steady speed down a grade theta the ground's brake (at the tyres' patches) balances the weight's
    component along the slope, and about the rear patch the front tyre carries m g (cos(theta) a +
    sin(theta) h) / L (the brake's forces lie on the ground's line). So the descent moves about
    m g sin(theta) h / L onto the front, and the drive brakes with m g sin(theta). Measured with the
    engine's own geometry per state (the fork sinks, the rider leans on his arms): 138 N onto the front,
    of which the plain m g sin(theta) h / L of the bike at rest on level ground is 122 N."""
    at = 3.0
    descent = run_bike("sst", f"climb:grade_percent={GRADE:g},length_m=60,at_m={at:g}", SPEED, duration=11.0)
    level = run_bike("sst", "flat:length_m=60", SPEED, duration=11.0)
    theta = math.atan(-GRADE / 100.0)
    radius = level.prepared.fork_setup.tire_radius
    # the steady stretch: 15 m into the grade (its 3 m transition and the bike's settling behind) to 45 m
    # (x is horizontal: the slope's metres are x / cos(theta))
    stretch = (at + 15.0, at + 45.0)
    f, r_, drive = _steady(descent, *stretch)
    f0, r0, drive0 = _steady(level, *stretch)
    want, h, wheelbase, mass = _balance(descent, theta, *stretch, radius)
    want0, *_ = _balance(level, 0.0, *stretch, radius)
    assert f0 == pytest.approx(want0, rel=0.02), (f0, want0)
    assert f == pytest.approx(want, rel=0.02), (f, want)
    assert f + r_ == pytest.approx(mass * 9.81 * math.cos(theta), rel=0.01), (f, r_)
    shift = mass * 9.81 * math.sin(theta) * h / wheelbase  # about 120 N: the check is not idle
    assert 100.0 < shift < 140.0 and f - math.cos(theta) * f0 > 0.9 * shift, (f, f0, shift)
    assert drive - drive0 == pytest.approx(-mass * 9.81 * math.sin(theta), rel=0.05), (drive, drive0)
    assert descent.summary.get("crash") is None


def test_a_profile_on_a_grade_keeps_its_bumps_and_enters_the_grade_without_a_kink():
    """``on_grade``: before ``at_m`` the profile as it was; after the transition the grade's straight line plus
    the profile; the added height's slope grows linearly along the transition (no kink at either end)."""
    x = np.linspace(-20.0, 100.0, 1201)
    z = 0.02 * np.sin(2 * np.pi * x / 3.0)
    ter = terrain_mod.Terrain("bumps", x, z, -5.0, 100.0)
    out = terrain_mod.on_grade(ter, -10.0, 2.0, 5.0)
    added = out.z - np.interp(out.x, x, z)
    assert np.all(added[out.x <= 2.0] == 0.0)
    after = out.x >= 7.0
    assert np.allclose(added[after], -0.1 * (out.x[after] - 2.0 - 2.5), atol=1e-12)
    slope = np.gradient(added, out.x)
    inside = (out.x > 2.2) & (out.x < 6.8)
    assert np.allclose(slope[inside], -0.1 * (out.x[inside] - 2.0) / 5.0, atol=2e-3)
    assert out.start_x == ter.start_x and out.params["grade_percent"] == -10.0
    with pytest.raises(terrain_mod.TerrainError, match="outside -40 to 40"):
        terrain_mod.on_grade(ter, -55.0, 2.0)

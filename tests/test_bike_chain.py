"""The drive through the chain (``drive.chainring_teeth``, ``drive.cog_teeth``; issue 40 item 3):
the chain's pull on the rear axle along its upper run, its reaction on the frame at the chainring.

On a steady climb the swingarm is in equilibrium, checked here by virtual work on the swingarm and
rear wheel about the main pivot (the frame held): the ground's force at the rear tyre, the chain's
pull and the weights, each through its point's displacement per unit of swingarm rotation, balance
the shock's force through ds/dphi. The chain's tension is the drive force's couple about the axle
over the cog's radius (the wheel spins freely: its moments balance), and its line is found here by
solving for the two tangent points (a root finder on their angles), not by the package's formula.
The same balance without the chain's term does not close: the chain acts (anti-squat). Also: the
compiled callback is the Python one's twin on a chain bike, and a chain needs both sprockets."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import fsolve

import mtbmj
from mtbmj.bike import spec as spec_mod
from helpers import last_pose, slope_profile

CHAIN = 'base = "sst"\n[drive]\nchainring_teeth = 32\ncog_teeth = 24\n'
PITCH = 0.0127  # a 1/2 in chain


def sprocket(teeth):
    return PITCH / (2 * math.sin(math.pi / teeth))


def upper_run(c1, r1, c2, r2):
    """The unit vector from the cog's tangent point to the chainring's along the upper run: the two
    points P = c + r (cos b, sin b) whose joining line is perpendicular to both radii, above."""
    def eqs(b):
        p1 = c1 + r1 * np.array([math.cos(b[0]), math.sin(b[0])])
        p2 = c2 + r2 * np.array([math.cos(b[1]), math.sin(b[1])])
        d = p1 - p2
        return [d @ (p1 - c1), d @ (p2 - c2)]
    b = fsolve(eqs, [math.pi / 2, math.pi / 2], xtol=1e-14)
    assert max(abs(e) for e in eqs(b)) < 1e-12
    p1 = c1 + r1 * np.array([math.cos(b[0]), math.sin(b[0])])
    p2 = c2 + r2 * np.array([math.cos(b[1]), math.sin(b[1])])
    assert p1[1] > c1[1] and p2[1] > c2[1]  # the upper run
    return (p1 - p2) / np.linalg.norm(p1 - p2)


@pytest.fixture(scope="module")
def climb(tmp_path_factory):
    folder = tmp_path_factory.mktemp("chain")
    bike = folder / "chain.toml"
    bike.write_text(CHAIN)
    path = slope_profile(folder, 0.2, "climb")
    return {cb: mtbmj.run_bike(str(bike), path, 4.0, duration=6.0, callback=cb) for cb in ("compiled", "python")}, \
        mtbmj.run_bike("sst", path, 4.0, duration=6.0, overrides={"drive.chain": False})  # a hub drive


def test_the_swingarm_balances_by_virtual_work_with_the_chain(climb):
    runs, hub = climb
    r = runs["compiled"]
    p = r.prepared
    model, data = last_pose(r)
    xz = lambda v: np.asarray(v)[[0, 2]]  # noqa: E731
    frame = model.body("frame").id
    bb, axle, pivot = xz(data.xpos[frame]), xz(data.site_xpos[model.site("rear_axle").id]), \
        xz(data.site_xpos[model.site("main_pivot").id])
    up = xz(data.xmat[frame].reshape(3, 3)[:, 2])  # the frame's z axis in the world
    d_dphi = lambda point: np.array([point[1] - pivot[1], -(point[0] - pivot[0])])  # noqa: E731 - rear wheel up
    raw = {k: v[-1] for k, v in r.raw.items() if isinstance(v, np.ndarray)}
    a = math.atan(0.2)
    normal, tangent = np.array([-math.sin(a), math.cos(a)]), np.array([math.cos(a), math.sin(a)])
    drive = raw["drive_force_N"]
    assert drive > 100.0  # climbing: the rider pushes
    ground = raw["rear_tire_N"] * normal + drive * tangent
    reach = p.rear_tire.radius - max(raw["rear_tire_mm"], 0.0) * 1e-3  # axle to contact patch
    tension = drive * reach / sprocket(24)
    chain = tension * upper_run(bb, sprocket(32), axle, sprocket(24))
    g = np.array([0.0, -9.81])
    arm = model.body("swingarm").id
    weights = (model.body_mass[model.body("rear_wheel").id] * g) @ d_dphi(axle) \
        + (model.body_mass[arm] * g) @ d_dphi(xz(data.xipos[arm]))
    spec = spec_mod.load("sst")
    w = raw["rear_travel_mm"] * 1e-3
    ds_dphi = (d_dphi(axle) @ up) / spec.leverage.ratio_at(w)
    shock = raw["shock_force_N"] * ds_dphi
    chain_term = chain @ d_dphi(axle)
    residual = ground @ d_dphi(axle) + chain_term + weights - shock
    assert abs(chain_term) > 0.05 * abs(shock)  # the chain's term is not a rounding
    assert abs(residual) < 0.01 * abs(chain_term), (residual, chain_term, shock)
    # without the chain's pull (a hub drive's couple on the swingarm instead) the same balance is off
    assert abs(residual - chain_term) > 0.5 * abs(chain_term)
    # anti-squat acts: the chain holds the rear up against the hub drive on the same climb
    assert r.raw["rear_travel_mm"][-1] < hub.raw["rear_travel_mm"][-1] - 1.0


def test_the_compiled_callback_is_the_python_one_with_a_chain(climb):
    runs, _ = climb
    a, b = runs["compiled"].raw, runs["python"].raw
    for key in ("rear_travel_mm", "front_travel_mm", "rear_tire_N", "pitch_deg"):
        assert np.max(np.abs(a[key] - b[key])) < 1e-9, key


def test_a_chain_needs_both_sprockets(tmp_path):
    from pathlib import Path

    # the SST preset without its sprockets, as a bike file of its own
    preset = (Path(spec_mod.__file__).parent / "presets" / "sst.toml").read_text().splitlines()
    (tmp_path / "bare.toml").write_text("\n".join(line for line in preset
                                                 if not line.startswith(("chainring_teeth", "cog_teeth"))) + "\n")
    bike = tmp_path / "half.toml"
    bike.write_text('base = "bare.toml"\n[drive]\nchainring_teeth = 32\n')
    with pytest.raises(spec_mod.ConfigError, match="drive.cog_teeth: needed with drive.chainring_teeth"):
        spec_mod.load(str(bike))
    bike.write_text('base = "sst"\n[drive]\nchainring_teeth = 32\ncog_teeth = 8\n')
    with pytest.raises(spec_mod.ConfigError, match="drive.cog_teeth: must be a whole number of teeth within 9-60"):
        spec_mod.load(str(bike))

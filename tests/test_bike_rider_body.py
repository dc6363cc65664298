"""The articulated rider (``--rider active``): its segments, its statics, its torque limits and its
drops (mtbmj/bike/rider_body.py, mtbmj/bike/rider_control.py)."""
import math

import mujoco
import numpy as np
import pytest

from mtbmj.bike import rider_body as rb
from mtbmj.bike import rider_control as rc
from mtbmj.bike import run
from mtbmj.bike.run import LOCK_ARMATURE, run_bike
from mtbmj.controllers import installed
from mtbmj.errors import ConfigError

G = 9.81


def test_de_leva_table_is_a_whole_body():
    # de Leva's mass shares: head and trunk once, the six limb segments twice, 100 % in all
    total = sum(pct * (2 if name in rb.SIDES else 1) for name, (pct, *_rest) in rb.DE_LEVA.items())
    assert total == pytest.approx(100.0, abs=1e-9)


@pytest.mark.parametrize("mass, height", [(85.0, 1.78), (62.5, 1.62), (104.0, 1.95)])
def test_segment_masses_sum_to_the_riders_mass(mass, height):
    body = rb.body(mass, height)
    assert sum(body.segment_masses.values()) == pytest.approx(mass, rel=1e-12)
    # the thighs: 2 x 14.16 % of the body (de Leva, male), the lengths scaled by the stature
    assert body.thigh.mass == pytest.approx(2 * 0.1416 * mass)
    assert body.thigh.length == pytest.approx(0.4222 * height / 1.741)


def test_the_models_masses_are_the_riders():
    p = run.prepare("sst", "flat", 4.0, rider="active", overrides={"rider.mass_kg": 72.0, "rider.height_m": 1.70})
    m = p.bike.model
    articulated = sum(float(m.body_mass[m.body(n).id]) for n in ("rider", "thigh", "shank", "upper_arm", "forearm"))
    body = p.articulated[0]
    assert articulated + body.feet_mass == pytest.approx(72.0, rel=1e-12)
    # the frame body: the frame and the feet, nothing else of the rider
    assert float(m.body_mass[m.body("frame").id]) == pytest.approx(p.spec.frame_mass + body.feet_mass)
    assert float(m.body_subtreemass[m.body("frame").id]) == pytest.approx(p.spec.total_mass)


def test_height_is_refused_outside_what_riders_have():
    with pytest.raises(ConfigError, match="rider.height_m: must be within 1.2-2.3 m"):
        run.prepare("sst", "flat", 4.0, overrides={"rider.height_m": 178.0})


def test_the_pose_puts_feet_and_hands_where_they_belong():
    body = rb.body(85.0, 1.78)
    pedal, grip = (0.0, 0.0), (0.45, 0.67)
    hip, trunk = (-0.2, 0.88), math.radians(32.0)
    pose = rb.pose(body, pedal, grip, hip, trunk)
    assert math.dist(pose.ankle, pose.knee) == pytest.approx(body.shank.length)
    assert math.dist(pose.knee, pose.hip) == pytest.approx(body.thigh.length)
    assert math.dist(pose.shoulder, pose.elbow) == pytest.approx(body.upper_arm.length)
    assert math.dist(pose.elbow, pose.grip) == pytest.approx(body.forearm.length)
    assert pose.knee[0] > pose.ankle[0]  # the knee ahead of the ankle
    # knee flexion: 180 deg less the angle at the knee (law of cosines), written here
    a, b, c = body.thigh.length, body.shank.length, math.dist(pose.hip, pose.ankle)
    assert pose.angles["knee"] == pytest.approx(math.pi - math.acos((a * a + b * b - c * c) / (2 * a * b)))


def _held_still(seated: bool, seconds: float = 1.5):
    """The active rider on the SST bike with every joint of the bike held (the frame fixed level):
    the body settles on its muscles; returns the prepared run and its rider callback."""
    p = run.prepare("sst", "flat", 4.0, rider="active", seated=seated)
    b, d = p.bike, p.data
    for name in ("bike_x", "bike_z", "pitch", "fork", "swingarm", "front_spin", "rear_spin"):
        b.model.dof_armature[b.dof_index(name)] = LOCK_ARMATURE
    d.qpos[b.qpos_index("pitch")] = 0.0
    d.qvel[:] = 0.0
    with installed(p.callback):
        for _ in range(int(seconds / p.timestep)):
            mujoco.mj_step(b.model, d)
        mujoco.mj_forward(b.model, d)
    return p, p.callback


def _loads(p):
    """World (x, z) force of the frame on the body at each pin, written from the pin's spring law
    (the body is at rest: no damping term), and the pins' world points."""
    m, d = p.bike.model, p.data
    out = {}
    for end, anchor in (("ankle_end", "ankle_anchor"), ("grip_end", "bars")):
        pe, pa = d.site_xpos[m.site(end).id], d.site_xpos[m.site(anchor).id]
        f = -rc.PIN_N_PER_M * (pe - pa)
        out[anchor] = (np.array([f[0], f[2]]), np.array([pa[0], pa[2]]))
    return out


def _articulated_weight(p):
    m, d = p.bike.model, p.data
    names = ("rider", "thigh", "shank", "upper_arm", "forearm")
    masses = np.array([m.body_mass[m.body(n).id] for n in names])
    points = np.array([[d.xipos[m.body(n).id][0], d.xipos[m.body(n).id][2]] for n in names])
    return masses.sum(), masses @ points / masses.sum()


def test_standing_statics_balance_on_pedals_and_bars():
    p, cb = _held_still(seated=False)
    assert max(abs(v) for v in p.data.qvel) < 1e-3  # at rest
    loads = _loads(p)
    (f_foot, at_foot), (f_bars, at_bars) = loads["ankle_anchor"], loads["bars"]
    mass, com = _articulated_weight(p)
    weight = np.array([0.0, -mass * G])
    # forces: the pins carry the weight of everything above the feet
    assert f_foot + f_bars + weight == pytest.approx(np.zeros(2), abs=0.5)
    # moments about the ankle's pin (nose-up positive): the bars' force, the weight at the centre of
    # mass, and the ankle's torque, which the foot (on the frame) puts on the shank
    def moment(r, f):
        return r[0] * f[1] - r[1] * f[0]

    ankle = cb.last["applied"]["ankle"]  # dorsiflexion positive: it turns the shank nose-down on the frame
    total = moment(at_bars - at_foot, f_bars) + moment(com - at_foot, weight) - ankle
    assert abs(total) < 0.5
    # the legs carry most of the weight, the bars the rest, both push up on the rider
    assert f_foot[1] > 0.5 * mass * G and f_bars[1] > 0.0


def test_seated_statics_the_saddle_carries_the_body():
    p, cb = _held_still(seated=True)
    m, d = p.bike.model, p.data
    loads = _loads(p)
    mass, com = _articulated_weight(p)
    # the saddle's push, written from its spring law: the sitting bones below the saddle's top
    frame = d.xpos[m.body("frame").id]
    saddle = np.array(rc.saddle_point(p.spec))
    bone_z = d.site_xpos[m.site("hips").id][2] - rc.ISCHIAL_BELOW_HIP_M
    depth = (frame[2] + saddle[1]) - bone_z
    push = rc.SADDLE_N_PER_M * max(depth, 0.0)
    vertical = loads["ankle_anchor"][0][1] + loads["bars"][0][1] + push
    assert vertical == pytest.approx(mass * G, abs=1.0)
    assert push > 0.5 * mass * G  # seated: the saddle carries most of the body


@pytest.fixture(scope="module")
def drop_1m():
    return run_bike("sst", "drop:height_mm=1000", 5.0, rider="active")


def test_active_rider_lands_a_1m_drop_at_5_m_per_s(drop_1m):
    s = drop_1m.summary
    assert s["crash"] is None
    assert s["rider"]["kind"] == "active"
    assert s["pitch_deg"]["min"] > -45.0
    assert "active rider: joint torques within their limits" in drop_1m.headline()


def test_active_riders_torques_stay_within_their_limits(drop_1m):
    r = drop_1m.summary["rider"]
    assert r["within_limits"]
    for name, joint in r["joints"].items():
        flex, ext = rc.STRENGTH_N_M[name]
        assert joint["peak_N_m"] <= max(flex, ext) + 1e-9
        assert joint["peak_of_limit"] <= 1.0 + 1e-9
    # the landing asks the muscles for much: some joint works near its limit
    assert max(j["peak_of_limit"] for j in r["joints"].values()) > 0.5
    assert r["peak_power_W"] <= rc.POWER_W + 1e-6


def test_an_active_riders_folder_replays_with_the_active_rider(drop_1m, tmp_path):
    """``render`` re-simulates a bike folder: an active rider's run is replayed with the active rider
    (it was replayed passive, which crashed, and the folder was refused as not reproduced)."""
    from mtbmj.bike import replay

    folder = tmp_path / "act"
    drop_1m.write(folder, figure=False)
    again = replay.rerun(folder)
    assert again.summary["rider"]["kind"] == "active" and again.summary["crash"] is None
    assert np.max(np.abs(again.raw["front_travel_mm"] - drop_1m.raw["front_travel_mm"])) < 1e-6


def test_passive_rider_still_goes_over_the_bars():
    res = run_bike("sst", "drop:height_mm=1000", 5.0)
    assert res.summary["crash"]["kind"] == "over the bars"
    assert res.summary["rider"] == {"kind": "passive"}
    assert res.headline().startswith("crashed: over the bars")


def test_active_rider_refuses_locks_in_one_line():
    with pytest.raises(ConfigError, match="rider: the active rider rides the whole bike"):
        run.prepare("sst", "flat", 4.0, rider="active", lock="rear")
    with pytest.raises(ConfigError, match="rider: must be one of passive, active"):
        run.prepare("sst", "flat", 4.0, rider="puppet")


@pytest.mark.parametrize("option", [["--lock", "rear"], ["--lock", "pitch", "--lift-rear"], ["--lift-rear"]])
def test_the_command_names_the_option_the_active_rider_refuses(tmp_path, capsys, option):
    """On the command line the refusal named run_bike's "rider: ... (no lock, no lifted rear)"; it names
    the option the user set, in one line, nothing written."""
    from helpers import one_line

    out = tmp_path / "out"
    one_line(capsys, ["bike", "sst", "flat", "--speed", "4", "--rider", "active", *option, "--out", out],
             f"mtbmj: error: {option[0]}: the active rider rides the whole bike (no --lock, no --lift-rear")
    assert not out.exists()

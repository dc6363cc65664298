"""The driving leg of a pedalling active rider (mtbmj/bike/pedal_leg.py, issue 54 item 4): its joint
torques against J^T F of a leg written here (finite differences of its foot's place), its joints'
speeds against finite differences of its angles, the power they make against the crank's and the
body's, the foot's tip at the stroke's bottom, the push along the crank against a search here, and
in the engine: the reaction on the trunk, the crank's work against power x time, the balance."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mtbmj.bike import pedal_leg as pl
from mtbmj.bike import rider_body as rb
from mtbmj.bike import rider_control as rc


def u(a):
    return np.array([math.cos(a), math.sin(a)])


def leg_points(hip, l1, l2, offset, a_thigh, a_shank, a_foot):
    """A leg written here: the thigh and the shank at absolute angles (rad, nose-up from the frame's
    x), the foot turned a_foot from its rest attitude; the pedal's spindle ``offset`` (the ankle's
    place from the spindle, at rest) back from the ankle. (knee, ankle, pedal)."""
    knee = np.asarray(hip, float) + l1 * u(a_thigh)
    ankle = knee + l2 * u(a_shank)
    c, s = math.cos(a_foot), math.sin(a_foot)
    o = np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
    return knee, ankle, ankle - o


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_joint_torques_are_the_transposed_jacobian_times_the_pedal_force(seed):
    """A massless leg pushing its pedal with F: by virtual work F . dP = tau_h da_t + tau_k (da_s -
    da_t) + tau_a (da_f - da_s) for the absolute angles' variations, so with Q = J^T F (J the pedal's
    place over (a_t, a_s, a_f), by central differences here) tau_a = Q_f, tau_k = Q_s + Q_f, tau_h =
    Q_t + Q_s + Q_f; anatomically hip flexion tau_h, knee flexion -tau_k, ankle dorsiflexion tau_a."""
    rng = np.random.default_rng(seed)
    hip = rng.uniform(-0.3, 0.0, 2) + np.array([0.0, 0.8])
    l1, l2 = rng.uniform(0.38, 0.46, 2)
    offset = (-0.13, 0.09)
    angles = np.array([rng.uniform(-1.6, -0.6), rng.uniform(-2.2, -1.5), rng.uniform(-0.4, 0.2)])
    force = rng.uniform(-400.0, 400.0, 2)
    h = 1e-6
    jac = np.zeros((2, 3))
    for j in range(3):
        dp, dm = angles.copy(), angles.copy()
        dp[j] += h
        dm[j] -= h
        jac[:, j] = (leg_points(hip, l1, l2, offset, *dp)[2] - leg_points(hip, l1, l2, offset, *dm)[2]) / (2 * h)
    q = jac.T @ force
    want = {"hip": q[0] + q[1] + q[2], "knee": -(q[1] + q[2]), "ankle": q[2]}
    knee, ankle, pedal = leg_points(hip, l1, l2, offset, *angles)
    got = pl.leg_torques(hip, knee, ankle, pedal, force)
    for k in pl.LEG_JOINTS:
        assert got[k] == pytest.approx(want[k], rel=1e-6, abs=1e-6), k
    # and the whole leg's moment balance about the hip: the pedal's push back and the hip's torque
    assert got["hip"] + pl.cross(pedal - hip, -force) == pytest.approx(0.0, abs=1e-9)


def test_joint_speeds_and_the_power_they_make():
    """A leg moved here (its angles and the hips and the trunk along made-up paths): leg_rates
    against the angles' differences, and the joints' power sum tau w against F . (v_pedal -
    v_trunk(P)), the crank's power less what the reaction does on the trunk (the point of the trunk
    at the pedal moves with the hips and the trunk's turn)."""
    l1, l2, offset = 0.42, 0.43, (-0.13, 0.09)
    force = np.array([120.0, -350.0])

    def at(t):
        hip = np.array([-0.2 + 0.03 * math.sin(3 * t), 0.78 + 0.02 * math.cos(5 * t)])
        ang = (-1.2 + 0.3 * math.sin(2 * t), -1.9 + 0.2 * math.cos(3 * t), 0.1 * math.sin(4 * t))
        return hip, ang, 0.8 + 0.05 * math.sin(t)  # trunk angle

    t, h = 0.37, 1e-6
    hip, ang, trunk = at(t)
    knee, ankle, pedal = leg_points(hip, l1, l2, offset, *ang)
    vel = {}
    for name, f in (("hip", lambda s: at(s)[0]), ("ankle", lambda s: leg_points(*[at(s)[0], l1, l2, offset],
                                                                                 *at(s)[1])[1]),
                    ("pedal", lambda s: leg_points(at(s)[0], l1, l2, offset, *at(s)[1])[2])):
        vel[name] = (f(t + h) - f(t - h)) / (2 * h)
    da = (np.array(at(t + h)[1]) - np.array(at(t - h)[1])) / (2 * h)
    w_trunk = (at(t + h)[2] - at(t - h)[2]) / (2 * h)
    got = pl.leg_rates(hip, knee, ankle, vel["hip"], vel["ankle"], w_trunk, da[2])
    assert got["hip"] == pytest.approx(da[0] - w_trunk, rel=1e-6)
    assert got["knee"] == pytest.approx(da[0] - da[1], rel=1e-6)
    assert got["ankle"] == pytest.approx(da[2] - da[1], rel=1e-6)
    taus = pl.leg_torques(hip, knee, ankle, pedal, force)
    power = sum(taus[k] * got[k] for k in pl.LEG_JOINTS)
    v_trunk_at_p = vel["hip"] + w_trunk * np.array([-(pedal - hip)[1], (pedal - hip)[0]])
    assert power == pytest.approx(float(force @ (vel["pedal"] - v_trunk_at_p)), rel=1e-6)


def test_the_foot_tips_heel_up_where_the_hips_are_far():
    """Within reach the foot keeps its attitude; further, it turns about the spindle until the ankle
    is ``longest`` from the hips, by the smaller turn, heel up (nose-down) below the hips; its rate
    against the difference of the turn along a made-up motion; past any turn it says so."""
    offset, longest = (-0.13, 0.09), 0.85
    near = pl.foot_tip((-0.2, 0.6), (0.0, 0.0), (0.1, -0.1), (0.0, 0.0), offset, longest)
    assert near == (0.0, 0.0, True)

    def path(t):
        return np.array([-0.2, 0.78 + 0.02 * t]), np.array([0.05 * math.sin(t), -0.17 * math.cos(0.3 * t)])

    t, h = 0.4, 1e-6
    hip, pedal = path(t)
    v_hip = (path(t + h)[0] - path(t - h)[0]) / (2 * h)
    v_ped = (path(t + h)[1] - path(t - h)[1]) / (2 * h)
    phi, rate, ok = pl.foot_tip(hip, v_hip, pedal, v_ped, offset, longest)
    assert ok and phi < 0.0  # heel up
    c, s = math.cos(phi), math.sin(phi)
    ankle = pedal + np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
    assert math.hypot(*(hip - ankle)) == pytest.approx(longest, abs=1e-9)
    turn = lambda s_: pl.foot_tip(path(s_)[0], v_hip, path(s_)[1], v_ped, offset, longest)[0]
    assert rate == pytest.approx((turn(t + h) - turn(t - h)) / (2 * h), rel=1e-5)
    far = pl.foot_tip((0.0, 1.5), (0.0, 0.0), (0.0, -0.17), (0.0, 0.0), offset, longest)
    assert far[2] is False


def test_the_push_along_the_crank_is_the_least_effort_and_makes_no_torque():
    """The foot's push along the crank (``PedalLeg.radial``) makes no moment about the bottom bracket
    (it is along the crank) and, among pushes along it, makes sum (tau_j / S_j)^2 least, S_j one
    side's strength in the direction the stroke's force alone turns the joint: a search here."""
    body = rb.body(85.0, 1.78)
    leg = pl.PedalLeg(body, (0.45, 0.67), 1.0, rc.STRENGTH_ONE_SIDE_N_M)
    hip = (-0.23, 0.77)
    for theta in (0.5, 1.2, 1.9, 2.6):
        pedal = pl.CRANK_LENGTH_M * np.array([math.sin(theta), math.cos(theta)])
        force = 300.0 * math.sin(theta) * np.array([math.cos(theta), -math.sin(theta)])
        pose = rb.pose(body, tuple(pedal), (0.45, 0.67), hip, 0.8)
        r = leg.radial(pose.hip, pose.knee, pose.ankle, pedal, force)
        assert pl.cross(pedal, r) == pytest.approx(0.0, abs=1e-9)  # no crank torque
        n = pedal / np.hypot(*pedal)
        a = pl.leg_torques(pose.hip, pose.knee, pose.ankle, pedal, force)

        def effort(lam):
            t = pl.leg_torques(pose.hip, pose.knee, pose.ankle, pedal, force + lam * n)
            return sum((t[k] / rc.STRENGTH_ONE_SIDE_N_M[k][0 if a[k] > 0 else 1]) ** 2 for k in pl.LEG_JOINTS)

        lams = np.linspace(-1500.0, 1500.0, 30001)
        best = lams[np.argmin([effort(v) for v in lams])]
        assert float(r @ n) == pytest.approx(best, abs=0.2)
        assert effort(float(r @ n)) < effort(0.0)


def test_pedalling_hips_reach_the_stroke_bottom():
    """Standing, the attack position's hips (knees 45 deg over the pedals' mean) are further from the
    stroke's bottom than the leg reaches; pedalling, they come down until the driving leg reaches it
    with the knee ``BOTTOM_KNEE_DEG`` bent, at the same fore-aft place."""
    from mtbmj.bike.spec import load

    spec = load("sst")
    body = rb.body(spec.rider.mass + spec.rider.on_bike_mass, spec.rider.height)
    attack, _ = rc.stance(spec, body)
    hip, _ = rc.stance(spec, body, pedalling=True)
    bottom = np.array([body.ankle_from_pedal[0], body.ankle_from_pedal[1] - pl.CRANK_LENGTH_M])
    leg = body.thigh.length + body.shank.length
    assert math.hypot(*(np.array(attack) - bottom)) > leg
    l1, l2 = body.thigh.length, body.shank.length
    knee = math.pi - math.acos((l1 * l1 + l2 * l2 - math.hypot(*(np.array(hip) - bottom)) ** 2) / (2 * l1 * l2))
    assert math.degrees(knee) == pytest.approx(pl.BOTTOM_KNEE_DEG, abs=1e-6)
    assert hip[0] == pytest.approx(attack[0]) and hip[1] < attack[1]


def test_the_reaction_is_on_the_trunk():
    """In the engine the bike's callback puts the stroke's reaction on the ``rider`` body (the trunk);
    the rider's callback adds the push along the crank: the frame gets it at the pedal, the trunk its
    reaction on the same line; the shank nothing. The force on the trunk is the driving leg's whole
    push, reversed, and its moment about the world's origin that of a force at the pedal."""
    import mujoco

    from mtbmj.bike import run

    p = run.prepare("sst", "climb:grade_percent=10,length_m=20,at_m=0.5", None, pedal=(70.0, 250.0),
                    rider="active", legs_swing=True)
    m, d, cb = p.bike.model, p.data, p.callback
    rider, shank, frame = m.body("rider").id, m.body("shank").id, m.body("frame").id
    found = 0
    for x in np.linspace(0.05, 0.4, 8):
        d.qpos[p.bike.qpos_index("bike_x")] = p.initial_qpos[p.bike.qpos_index("bike_x")] + x
        mujoco.mj_forward(m, d)
        d.xfrc_applied[:] = 0.0
        cb(m, d)
        leg = cb.last["leg"]
        if not leg["force"].any():
            continue
        found += 1
        rot = d.xmat[frame].reshape(3, 3)
        f = rot @ np.array([leg["force"][0], 0.0, leg["force"][1]])
        at = d.xpos[frame] + rot @ np.array([leg["pedal"][0], 0.0, leg["pedal"][1]])
        # the legs' swing (PedalLeg.swing, legs_swing) on the trunk besides: its force at the hips and its moment
        g = rot.T @ m.opt.gravity
        sf, sm = cb.leg.swing(d.qpos[p.bike.qpos_index("bike_x")], d.qvel[p.bike.dof_index("bike_x")], (g[0], g[2]))
        sw = rot @ np.array([sf[0], 0.0, sf[1]])
        hips = d.site_xpos[m.site("hips").id]
        w = d.xfrc_applied[rider] - np.concatenate((sw, np.cross(hips - d.xipos[rider], sw) + [0.0, -sm, 0.0]))
        assert w[:3] == pytest.approx(-f, rel=1e-9, abs=1e-9)
        assert w[3:] + np.cross(d.xipos[rider], w[:3]) == pytest.approx(np.cross(at, -f), rel=1e-9, abs=1e-6)
        assert not d.xfrc_applied[shank].any()
        assert abs(leg["radial"] @ leg["pedal"]) > 0.0  # a push along the crank was added
        assert np.hypot(*sw[[0, 2]]) > 5.0  # and the legs swung
    assert found >= 4


@pytest.fixture(scope="module", params=[pytest.param("standing", marks=pytest.mark.slow),  # 20-25 s of setup each
                                        pytest.param("seated", marks=pytest.mark.slow)])
def climbing(request):
    from mtbmj.bike.run import run_bike

    return run_bike("sst", "climb:grade_percent=8,length_m=40,at_m=0.5", None, duration=3.0, rider="active",
                    pedal=(70.0, 250.0), seated=request.param == "seated")


def test_the_muscles_do_the_pedalling_work(climbing):
    """3 s of pedalling at 250 W, standing and seated: the foot's work on the crank is 250 W x 3 s
    within 3 %, and the muscles' positive work holds it (the driving leg's alone at least the crank's
    less 5 %; before, with the stroke prescribed, the muscles' positive work standing was 44 J of
    it); the balance closes within 1 % of the work done, and misses without the driving leg's work."""
    e = climbing.summary["energy"]
    assert climbing.summary["crash"] is None
    assert e["crank_J"] == pytest.approx(250.0 * e["duration_s"], rel=0.03)
    assert e["pedal_leg_positive_J"] >= 0.95 * e["crank_J"]
    assert e["muscle_positive_J"] >= e["crank_J"]
    assert abs(e["work_J"]["drive"]) < 0.05 * e["crank_J"]  # what the chain and the ground leave besides
    assert e["unsplit_W"] < 1e-6
    assert e["error_pct"] < 1.0
    without = e["energy_change_J"] - (e["work_total_J"] - e["pedal_leg_J"])
    assert abs(without) > 0.01 * e["work_done_J"]
    leg = climbing.summary["rider"]["pedal_leg"]
    assert leg["out_of_reach_s"] == 0.0
    # the headline says whether the driving leg's side stayed within one side's strength
    said = "the driving leg within" if leg["within_limits"] else "the driving leg PAST"
    assert said in climbing.headline()
    # 250 W standing: the stroke within strength, or all but (the ankle's dorsiflexion, 0.3 % of the
    # stroke's time); seated the common leg holds larger torques and the cut takes 2.2 % of the work
    seated = climbing.prepared.callback.controller.seated
    assert leg["delivered_of_asked"] >= (0.95 if seated else 0.99)
    assert leg["within_limits"] and max(leg["side_peak_of_limit"].values()) <= 1.0


# the stroke cut by the leg's strength and power (PedalLeg.limit): J^T F of the leg solved here


def _torques_here(pose, pedal, force):
    """The anatomical torques (hip, knee flexion, ankle dorsiflexion) with which the leg of ``pose`` pushes
    its pedal with ``force``: J^T F, J the pedal's place over the leg's absolute angles by central
    differences of ``leg_points`` (the test's leg), as in the first test of this file."""
    hip, knee, ankle = (np.asarray(v, float) for v in (pose.hip, pose.knee, pose.ankle))
    l1, l2 = float(np.hypot(*(knee - hip))), float(np.hypot(*(ankle - knee)))
    angles = np.array([math.atan2(*(knee - hip)[::-1]), math.atan2(*(ankle - knee)[::-1]), 0.0])
    offset = tuple(ankle - np.asarray(pedal, float))
    assert leg_points(hip, l1, l2, offset, *angles)[2] == pytest.approx(pedal, abs=1e-12)
    h, jac = 1e-6, np.zeros((2, 3))
    for j in range(3):
        dp, dm = angles.copy(), angles.copy()
        dp[j] += h
        dm[j] -= h
        jac[:, j] = (leg_points(hip, l1, l2, offset, *dp)[2] - leg_points(hip, l1, l2, offset, *dm)[2]) / (2 * h)
    q = jac.T @ np.asarray(force, float)
    return {"hip": q[0] + q[1] + q[2], "knee": -(q[1] + q[2]), "ankle": q[2]}


def _stroke_here(theta):
    """The stroke's force per N m of peak crank torque and the pedal's place at crank angle ``theta``
    (0 < theta < pi: the right foot drives, along the crank circle's tangent, |F| = sin theta / L)."""
    L = pl.CRANK_LENGTH_M
    return math.sin(theta) / L * np.array([math.cos(theta), -math.sin(theta)]), L * np.array([math.sin(theta), math.cos(theta)])


CUT_HIP, CUT_TRUNK = (-0.23, 0.77), 0.8
COMMON = {"hip": 120.0, "knee": -300.0, "ankle": 40.0}  # both legs' muscle torques (N m), made up


@pytest.mark.parametrize("theta", [0.6, 1.5, 2.4])
def test_a_stroke_past_strength_is_cut_to_the_limit(theta):
    """A stroke asked for far past one side's strength (900 W at 40 rpm): the share ``limit`` gives is
    the closed form min_j (limit_j - common_j / 2) / (peak |a_j|), a_j the joint's torque per N m of
    peak from J^T F here (F the stroke's force and the push along the crank), the limit the side's
    strength in the direction a_j turns; the cut stroke puts the binding joint at (not past) its limit
    and every other within; without the cut it was past."""
    body = rb.body(85.0, 1.78)
    leg = pl.PedalLeg(body, (0.45, 0.67), 1.0, rc.STRENGTH_ONE_SIDE_N_M, 1500.0)
    omega = 40.0 * math.pi / 30.0
    peak = math.pi * 900.0 / (2.0 * omega)  # the stroke's peak crank torque at 900 W, 40 rpm
    g = leg.geometry(CUT_HIP, (0.0, 0.0), CUT_TRUNK, 0.0, theta, 0.0)  # gear 1: the crank's angle is x; at rest
    f1, pedal = _stroke_here(theta)
    assert g["pedal"] == pytest.approx(pedal, abs=1e-12)
    pose = g["pose"]
    whole = f1 + leg.radial(pose.hip, pose.knee, pose.ankle, pedal, f1)
    a = _torques_here(pose, pedal, whole)
    room = {}
    for k in pl.LEG_JOINTS:
        flex, ext = rc.STRENGTH_ONE_SIDE_N_M[k]
        room[k] = (flex - COMMON[k] / 2) / a[k] if a[k] > 0 else (ext + COMMON[k] / 2) / -a[k]
    by = min(room, key=room.get)
    share = room[by] / peak
    assert share < 0.7  # asked past strength
    cut = leg.limit(g, theta, omega, 900.0, COMMON, math.inf)
    assert cut["share"] == pytest.approx(share, rel=1e-6)
    assert cut["by"] == by
    assert cut["asked_W"] == 0.0  # the pedal at rest: no crank power asked
    for s, at_limit in ((cut["share"], True), (1.0, False)):
        st = leg.state(CUT_HIP, (0.0, 0.0), CUT_TRUNK, 0.0, theta, 0.0, s * peak * f1)
        side = {k: st["taus"][k] + COMMON[k] / 2 for k in pl.LEG_JOINTS}
        of = {k: side[k] / rc.STRENGTH_ONE_SIDE_N_M[k][0] if side[k] > 0 else -side[k] / rc.STRENGTH_ONE_SIDE_N_M[k][1]
              for k in pl.LEG_JOINTS}
        if at_limit:
            assert of[by] == pytest.approx(1.0, abs=1e-9)
            assert max(of.values()) <= 1.0 + 1e-9
        else:
            assert of[by] > 1.2  # uncut, past the limit
    # the common leg's half counted: without it the share is another
    alone = leg.limit(g, theta, omega, 900.0, dict.fromkeys(pl.LEG_JOINTS, 0.0), math.inf)
    assert alone["share"] != pytest.approx(share, rel=1e-3)


def test_a_stroke_within_strength_is_untouched():
    """50 W at 90 rpm: every joint within one side's strength with the common leg's half: share 1,
    nothing named, and the state's torques those of the uncut stroke."""
    leg = pl.PedalLeg(rb.body(85.0, 1.78), (0.45, 0.67), 1.0, rc.STRENGTH_ONE_SIDE_N_M, 1500.0)
    for theta in (0.3, 1.5, 2.8):
        g = leg.geometry(CUT_HIP, (0.0, 0.0), CUT_TRUNK, 0.0, theta, 0.0)
        cut = leg.limit(g, theta, 9.42, 50.0, COMMON, 1000.0)
        assert cut["share"] == 1.0 and cut["by"] is None


def test_the_stroke_is_cut_by_the_power_left():
    """The leg moving (the crank at 60 rpm, the hips and the trunk moving on the frame): where the
    rider's muscles leave the leg 40 W, the stroke's share is 40 W over its power per N m of peak,
    F . (v_pedal - v_trunk(P)) computed here (the crank's tangent speed, the trunk's point at the pedal
    moving with the hips and the trunk's turn), and the cut names the power."""
    leg = pl.PedalLeg(rb.body(85.0, 1.78), (0.45, 0.67), 1.0, rc.STRENGTH_ONE_SIDE_N_M, 1500.0)
    theta, omega, v_hip, w_trunk = 1.4, 2.0 * math.pi, np.array([0.1, -0.05]), 0.3
    g = leg.geometry(CUT_HIP, tuple(v_hip), CUT_TRUNK, w_trunk, theta, omega)
    f1, pedal = _stroke_here(theta)
    pose = g["pose"]
    whole = f1 + leg.radial(pose.hip, pose.knee, pose.ankle, pedal, f1)
    v_pedal = omega * pl.CRANK_LENGTH_M * np.array([math.cos(theta), -math.sin(theta)])
    arm = pedal - np.asarray(CUT_HIP)
    per_peak = float(whole @ (v_pedal - v_hip - w_trunk * np.array([-arm[1], arm[0]])))
    assert per_peak > 0.0
    peak = math.pi * 200.0 / (2.0 * omega)
    cut = leg.limit(g, theta, omega, 200.0, COMMON, 40.0)
    assert cut["by"] == "power"
    assert cut["share"] == pytest.approx(40.0 / (peak * per_peak), rel=1e-6)
    assert cut["asked_W"] == pytest.approx(peak * float(f1 @ v_pedal), rel=1e-9)
    # with the power to spare, strength alone
    assert leg.limit(g, theta, omega, 200.0, COMMON, 1e6)["by"] != "power"


@pytest.fixture(scope="module")
def straining():
    from mtbmj.bike.run import run_bike

    return run_bike("sst", "climb:grade_percent=8,length_m=40,at_m=0.5", None, duration=3.0, rider="active",
                    pedal=(50.0, 700.0))


@pytest.mark.slow  # a pedalling active rider's bike run: 20-30 s of setup
def test_a_stroke_past_strength_is_cut_in_the_engine(straining):
    """700 W at 50 rpm standing asks the driving leg past one side's strength: the stroke is cut so
    the side's torques reach their limits and never pass them; the crank gets less work than asked
    (the balance's crank work, the foot's force times the pedal's speed, is what the summary says
    was delivered); the cut's shares are shares; the balance still closes within 1 % of the work."""
    s = straining.summary
    assert s["crash"] is None
    leg = s["rider"]["pedal_leg"]
    assert leg["within_limits"]
    assert 0.999 <= max(leg["side_peak_of_limit"].values()) <= 1.0
    assert 0.5 < leg["delivered_of_asked"] < 0.97
    assert leg["delivered_crank_J"] < leg["asked_crank_J"]
    e = s["energy"]
    assert e["crank_J"] == pytest.approx(leg["delivered_crank_J"], rel=0.02)
    shares = leg["cut_of_stroke_time"]
    assert all(0.0 <= v <= 1.0 for v in shares.values()) and 0.0 < sum(shares.values()) <= 1.0
    assert e["error_pct"] < 1.0
    head = straining.headline()
    assert "the driving leg within one side's strength" in head and "crank work delivered (cut by" in head
    # the headline says "within" only when so
    leg["within_limits"] = False
    try:
        assert "the driving leg PAST one side's strength" in straining.headline()
    finally:
        leg["within_limits"] = True


def test_the_legs_swing_against_their_centres_moved_here():
    """The two legs' swing (``PedalLeg.swung``, ``swing``) at the standing pedalling stance: its force
    on the trunk is -(d^2/dt^2) of the legs' first moment about the hips, and its moment that of the
    legs' d'Alembert forces about the hips plus their weight's moved from the lumped leg's place,
    the legs' centres put here (each leg half the lumped thigh's and shank's mass, on its own pedal,
    half a turn apart; the lumped leg on the pedals' mean), their accelerations by central
    differences over the crank's angle at a steady cadence. Within 2 % of the swing's peak (the
    series keeps 16 harmonics: with 8 it missed by 3 %); it scales with the cadence squared; and it is no small thing: some
    60 N at 70 rpm."""
    from mtbmj.bike.spec import load

    spec = load("sst")
    r = spec.rider
    body = rb.body(r.mass + r.on_bike_mass, r.height)
    hip, trunk = rc.stance(spec, body, pedalling=True)
    grip = (r.arm_x, r.arm_z)
    leg = pl.PedalLeg(body, grip, 1.0, rc.STRENGTH_ONE_SIDE_N_M).swung(hip, trunk)
    h0 = np.asarray(hip)

    def centres(pedal, share):  # [(mass, centre less the hips)] of thigh and shank
        pose = rb.pose(body, tuple(pedal), grip, hip, trunk)
        out = []
        for seg, a, e in ((body.thigh, pose.hip, pose.knee), (body.shank, pose.knee, pose.ankle)):
            a, e = np.asarray(a), np.asarray(e)
            out.append((share * seg.mass, a + seg.com / np.hypot(*(e - a)) * (e - a) - h0))
        return out

    def legs(theta):
        crank = pl.CRANK_LENGTH_M * np.array([math.sin(theta), math.cos(theta)])
        return centres(crank, 0.5) + centres(-crank, 0.5)

    lumped = centres(np.zeros(2), 1.0)
    g = np.array([0.0, -9.81])
    w = 70.0 * math.pi / 30.0
    h = 1e-3
    peak = 0.0
    rows = []
    for theta in np.linspace(0.1, 2 * math.pi, 13):
        now, ahead, back = legs(theta), legs(theta + h), legs(theta - h)
        force, moment = np.zeros(2), 0.0
        for (mass, c), (_, c1), (_, c0) in zip(now, ahead, back):
            acc = (c1 - 2 * c + c0) / (h * h) * w * w
            force += -mass * acc
            moment += pl.cross(c, mass * (g - acc))
        moment -= sum(pl.cross(c, mass * g) for mass, c in lumped)
        got_f, got_m = leg.swing(theta, w, tuple(g))
        rows.append((got_f, got_m, force, moment))
        peak = max(peak, float(np.hypot(*force)))
    assert peak > 40.0
    for got_f, got_m, force, moment in rows:
        assert got_f == pytest.approx(force, abs=0.02 * peak)
        assert got_m == pytest.approx(moment, abs=0.02 * peak * 0.3)
    # twice the cadence: four times the d'Alembert force (the weight's moment unchanged)
    f1, _ = leg.swing(1.0, w, (0.0, 0.0))
    f2, _ = leg.swing(1.0, 2 * w, (0.0, 0.0))
    assert f2 == pytest.approx(4.0 * f1, rel=1e-12)
    # without swung, no swing
    assert not pl.PedalLeg(body, grip, 1.0, rc.STRENGTH_ONE_SIDE_N_M).swing(1.0, w, tuple(g))[0].any()


def test_the_legs_swing_only_for_a_pedalling_active_rider():
    from mtbmj.bike.run import prepare
    from mtbmj.errors import ConfigError

    with pytest.raises(ConfigError, match="legs_swing: the legs swing only for a pedalling active rider"):
        prepare("sst", "flat", 4.0, rider="active", legs_swing=True)
    with pytest.raises(ConfigError, match="legs_swing"):
        prepare("sst", "flat", None, pedal=(70.0, 250.0), legs_swing=True)


@pytest.mark.slow  # a pedalling active rider's bike run: 15-20 s
def test_the_legs_swing_from_the_command_line(tmp_path, capsys):
    """`mtbmj bike ... --legs-swing`: without a pedalling active rider one line naming the option, exit
    2, nothing written; with one, the run goes and its summary says the legs swung (off: they did not)."""
    import json

    from mtbmj.cli import main

    out = tmp_path / "no"
    assert main(["bike", "sst", "flat", "--speed", "4", "--rider", "active", "--legs-swing", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mtbmj: error: --legs-swing: ") and "--pedal RPM --rider active" in err[0]
    assert not out.exists()
    for swing in (True, False):
        out = tmp_path / f"swing_{swing}"
        args = ["bike", "sst", "climb:grade_percent=8,length_m=40,at_m=0.5", "--pedal", "70", "--rider", "active",
                "--duration", "0.6", "--no-figure", "--quiet", "--out", str(out)] + (["--legs-swing"] if swing else [])
        assert main(args) == 0
        s = json.loads((out / "summary.json").read_text())
        assert s["rider"]["pedal_leg"]["legs_swing"] is swing

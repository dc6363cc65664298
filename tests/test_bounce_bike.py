"""``fit bounce --bike``: a seat slam's ring-down read through the bike's seated model
(``mtbmj.identify.bounce_bike``): the shock's spring rate and damper coefficient.

The ring-downs here are made by the MuJoCo bike (another engine: MuJoCo's integrator stepping the
full model, not the linearisation and eigenvalues the identification solves), with the seated
rider held rigid on the frame, no friction, a linear damper of a chosen coefficient and a spring
whose rate differs from the bike file's; the identification must give both back. What the two
share (the masses, the geometry, the rigid seated rider) is checked here against physics: the
seated statics against the weight and its moment, and the linearisation's stiffness against the
symmetry a conservative system's has."""
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mtbmj import cli
from mtbmj.bike import run as bike_run
from mtbmj.bike import spec as spec_mod
from mtbmj.identify import bounce
from mtbmj.identify.bounce_bike import SeatedBike

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "sst_v2"
PRESET = Path(spec_mod.__file__).resolve().parent / "presets" / "sst.toml"


@pytest.fixture(scope="module")
def seated():
    return SeatedBike("sst")


def test_seated_statics_carry_the_weight_and_its_moment(seated):
    """At the seated equilibrium the two tyres carry bike and rider, and their loads balance the
    moment of the weights about the rear contact (summed here point by point from the spec)."""
    ref, q = seated.ref, np.concatenate((seated.q, [0.0, 0.0]))
    y = np.concatenate((q, [2.0, 0, 0, 0, 0, 0, 0], np.zeros(ref.nf + ref.ns)))
    _, out = ref.forces(0.0, y)
    g = seated.prepared.gravity
    s = seated.spec
    total = s.total_mass
    front_z, rear_z = out["front"][1], out["rear"][1]
    assert front_z + rear_z == pytest.approx(total * g, rel=1e-6)
    # the moment about the rear axle's world x: every mass at its world x (frame pitch q[2])
    th = q[2]
    c, sn = math.cos(th), math.sin(th)
    world_x = lambda p: c * p[0] - sn * p[1]
    rear_x = world_x(spec_mod.rear_axle_in_frame(s, q[4]))
    front_axle = np.array(s.front_axle) + q[3] * np.array([-math.cos(s.head_angle), math.sin(s.head_angle)])
    r = s.rider
    # the swingarm at its mid-point, the limbs where the model puts them (part of the frame body)
    from mtbmj.bike.model import frame_body

    m_f, c_f, _ = frame_body(seated.prepared.spec)
    masses = [(m_f, c_f), (r.mass, r.seated_com), (s.fork_lower_mass + s.front_wheel_mass, front_axle),
              (s.rear_wheel_mass, spec_mod.rear_axle_in_frame(s, q[4])),
              (s.swingarm_mass, (np.array(s.pivot) + np.array(spec_mod.rear_axle_in_frame(s, q[4]))) / 2)]
    moment = sum(m * g * (world_x(p) - rear_x) for m, p in masses)
    assert front_z * (world_x(front_axle) - rear_x) == pytest.approx(moment, rel=2e-3)
    assert sum(m for m, _ in masses) == pytest.approx(total, rel=1e-9)


def test_linearised_stiffness_is_symmetric_and_mass_positive(seated):
    """Gravity and radial springs are conservative: at an equilibrium the stiffness is a potential's
    Hessian (symmetric); the mass matrix is symmetric positive definite."""
    K, M = seated.K, seated.M
    assert np.allclose(K, K.T, rtol=0, atol=1e-4 * np.abs(K).max())
    assert np.allclose(M, M.T) and np.all(np.linalg.eigvalsh(M) > 0)
    modes = seated.modes("shock")
    assert len(modes) == 4  # bounce, pitch and the two wheels' hop
    assert modes[0]["frequency_hz"] < 4.0 < modes[2]["frequency_hz"]


def ring_down_by_mujoco(rate_N_per_mm, damper_N_s_per_m, preload_N, seconds=4.0):
    """The MuJoCo bike, seated and held rigid, coasting on flat ground at 2 m/s, its frame given a
    slam's end (pitching nose up, the rear dropping onto its shock, the rear wheel rising less): the
    shock's stroke, mm, against time."""
    base = spec_mod.load("sst")
    shock = {**base.shock_overrides, "fork.friction.coulomb_N": 0.0, "fork.spring.rate_N_per_mm": rate_N_per_mm,
             "fork.spring.preload_N": preload_N, "fork.damper.compression_N_s_per_m": damper_N_s_per_m,
             "fork.damper.rebound_N_s_per_m": damper_N_s_per_m}
    gen = dataclasses.replace(base, shock_overrides=shock,
                              fork_overrides={**base.fork_overrides, "fork.friction.coulomb_N": 0.0})
    p = bike_run.prepare(gen, "flat", 2.0, drive="coast", seated=True)
    b = p.bike
    for dof, speed in (("pitch", 0.3), ("bike_z", -0.2), ("swingarm", 0.3)):  # rad/s, m/s, rad/s
        p.data.qvel[b.dof_index(dof)] = speed
    states, _ = bike_run.simulate(p, seconds)
    phi = states[:-1, 1 + p.bike.qpos_index("swingarm")]
    _, z = spec_mod.rear_axle_in_frame(gen, phi)
    stroke = gen.leverage.strokes(z - gen.rear_axle[1])
    return states[:-1, 0], stroke * 1e3


@pytest.mark.parametrize("rate, damper", [(80.0, 2000.0), (60.0, 3500.0), (90.0, 1200.0)])
def test_mujoco_ring_down_gives_back_its_spring_and_damper(seated, rate, damper):
    # the generator's preload keeps the seated static stroke the bike file's (so both linearise at
    # one point): preload + rate x stroke equal to the file's 250 N + 80 N/mm x stroke
    preload = 250.0 + (80.0 - rate) * seated.stroke * 1e3
    t, x = ring_down_by_mujoco(rate, damper, preload)
    rd = bounce.ring_down(t, x, "shock", slam_index=int(np.argmax(x)))
    assert rd.fitted, rd.note
    got = seated.identify("shock", rd.zeta, rd.zeta_sd, rd.fd_Hz, rd.fd_sd)
    assert got["spring_rate_N_per_mm"] == pytest.approx(rate, rel=0.01)
    assert got["damper_N_s_per_m"] == pytest.approx(damper, rel=0.01)
    assert got["wheel_rate_N_per_mm"] == pytest.approx(rate / got["leverage_ratio_at_sag"] ** 2, rel=0.02)
    lo, hi = got["damper_N_s_per_m_ci95"]
    assert lo < got["damper_N_s_per_m"] < hi


@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
@pytest.mark.slow
def test_shared_slams_through_the_bike(tmp_path, capsys):
    """The three shared slams through the SST bike: the damper's coefficient rises with clicks, and
    its law fitted on 0 and 17 clicks puts 8 clicks inside the 8-click record's own interval."""
    recs = [str(SHARED / f) for f in ("00083.SST", "00085.SST", "00087.SST")]
    assert cli.main(["fit", "bounce", *recs, "--clicks", "0,8,17", "--bike", "sst", "--predict-clicks", "4",
                     "--out", str(tmp_path / "all")]) == 0
    out = capsys.readouterr().out
    assert "through the bike: spring" in out and "damper law" in out
    fit = json.loads((tmp_path / "all" / "fit.json").read_text())
    c = [r["shock"]["bike"]["damper_N_s_per_m"] for r in fit["records"]]
    assert c[0] < c[1] < c[2]
    assert fit["predicted"][0]["shock"]["bike"]["damper_N_s_per_m"] == pytest.approx(
        c[0] + 4 / 8 * (c[1] - c[0]), rel=0.15)
    assert cli.main(["fit", "bounce", recs[0], recs[2], "--clicks", "0,17", "--bike", "sst",
                     "--out", str(tmp_path / "ends")]) == 0
    law = json.loads((tmp_path / "ends" / "fit.json").read_text())["law"]["shock"]["bike"]
    at8 = law["damper0_N_s_per_m"] + 8 * law["slope_N_s_per_m_per_click"]
    lo, hi = fit["records"][1]["shock"]["bike"]["damper_N_s_per_m_ci95"]
    assert lo < at8 < hi


@pytest.mark.shared_data("sst_v2", "00083.SST")
def test_bike_without_a_seated_rider_is_refused(tmp_path, capsys):
    text = "\n".join(line for line in PRESET.read_text().splitlines() if not line.startswith(("seated_com", "seat_tube_angle_deg", "saddle_height_mm")))
    bike = tmp_path / "standing.toml"
    bike.write_text(text)
    out = tmp_path / "out"
    code = cli.main(["fit", "bounce", str(SHARED / "00083.SST"), "--clicks", "0", "--bike", str(bike),
                     "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert "rider.seated_com_mm" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()

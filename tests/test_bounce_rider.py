"""The seated rider compliant on the saddle when a ring-down is read through the bike
(``mtbmj.identify.bounce_bike.SeatedBike(rider_hz=)``, ``fit bounce --bike --rider-hz``).

The checks are written here: the seated bike's statics against a force and a moment balance
(the wheels' loads against the weight and its moment about the rear contact, from MuJoCo's own
masses and centre of mass), the linear ring-down's energy balance integrated by solve_ivp, the
rigid rider as the stiff limit, and the strain energy's shares from this file's own eigen-solve."""
import math

import numpy as np
import pytest

from mtbmj import cli
from mtbmj.identify.bounce_bike import HELD, N, SeatedBike

G = 9.81


@pytest.fixture(scope="module")
def soft():
    return SeatedBike("sst", rider_hz=5.0)


@pytest.fixture(scope="module")
def rigid():
    return SeatedBike("sst")


def test_seated_statics_balance_forces_and_moments(soft):
    """At the seated static state the wheels carry the weight, and their loads' moment about the rear
    contact is the weight's (flat ground, at rest: the contact right below each axle)."""
    p = soft.prepared
    m, d = p.bike.model, p.data
    y = np.concatenate((soft.q, np.zeros(soft.q.size), np.zeros(soft.ref.nf + soft.ref.ns)))
    _, out = soft.ref.forces(0.0, y)
    fz_f, fz_r = out["front"][1], out["rear"][1]
    weight = float(np.sum(m.body_mass)) * p.gravity
    assert fz_f + fz_r == pytest.approx(weight, rel=1e-6)  # measured: to 1e-15
    x_f = d.xpos[m.body("front_wheel").id][0]
    x_r = d.xpos[m.body("rear_wheel").id][0]
    x_com = d.subtree_com[0][0]
    assert fz_f * (x_f - x_r) == pytest.approx(weight * (x_com - x_r), rel=1e-6)


def test_the_rider_rings_at_4_to_6_hz_on_the_held_frame(soft):
    s = soft.saddle
    lo, hi = s["frame_held_rider_hz"]
    assert 4.0 <= lo < hi <= 6.0  # 4.36 and 5.56 Hz: the legs and arms couple height and pitch
    for i in (N, N + 1):  # each coordinate alone: the stated damping ratio
        assert soft.C[i, i] / (2 * math.sqrt(soft.K[i, i] * soft.M[i, i])) == pytest.approx(0.475, rel=1e-9)
    assert s["saddle_vertical_rate"] > 0  # the legs and arms alone ring lower: the saddle carries the rest


def test_a_stiff_rider_reads_as_the_rigid_one_and_a_soft_one_needs_a_stiffer_spring(rigid, soft):
    """The rigid rider is the stiff limit (a 60 Hz body); at 5 Hz the body's compliance lowers the mode,
    so the same ring-down asks for a stiffer spring (measured: 0.503 -> 0.560 x the preset's)."""
    a_rigid, c_rigid = rigid.solve("shock", 0.176, 1.50)
    a_stiff, c_stiff = SeatedBike("sst", rider_hz=60.0).solve("shock", 0.176, 1.50)
    assert a_stiff == pytest.approx(a_rigid, rel=0.01) and c_stiff == pytest.approx(c_rigid, rel=0.02)
    a_soft, _ = soft.solve("shock", 0.176, 1.50)
    assert a_soft > a_rigid * 1.05


def test_the_mode_energy_shares_from_an_eigen_solve_written_here(soft):
    a, c = soft.solve("shock", 0.176, 1.50)
    shares = soft.energy_shares("shock", a, c)
    M, _, K = soft.matrices("shock", a, c)
    Ks = 0.5 * (K + K.T)
    from scipy.linalg import eigh

    w2, vec = eigh(Ks, M)  # symmetric: M-orthonormal modes
    f = np.sqrt(np.clip(w2, 0, None)) / (2 * math.pi)
    target = soft.mode_of("shock", a, c)["frequency_hz"]
    v = vec[:, int(np.argmin(np.abs(f - target)))]
    pe = v @ Ks @ v
    k_spring = a * soft.rate["shock"] * soft.d_end["shock"] ** 2
    assert shares["spring"] == pytest.approx(k_spring * v[4] ** 2 / pe, rel=1e-6)
    rider = v[N:] @ Ks[N:, N:] @ v[N:]
    assert shares["rider"] == pytest.approx(rider / pe, rel=1e-6)
    assert 0.05 < shares["rider"] < 0.15 and shares["spring"] > 0.6


def test_the_linear_ring_down_balances_its_energy(soft):
    """M q'' + C q' + K q = 0 from the shock's mode displaced (10 mm of the rear wheel), integrated
    here: the energy lost equals what the dampers and the non-symmetric stiffness take."""
    from scipy.integrate import solve_ivp

    a, c = soft.solve("shock", 0.176, 1.50)
    M, C, K = soft.matrices("shock", a, c)
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    Ks, Ka = 0.5 * (K + K.T), 0.5 * (K - K.T)
    q0 = np.zeros(n)
    q0[4] = 0.010 / abs(soft.dw_dphi)  # 10 mm of wheel travel on the swingarm
    q0[1] = -0.005  # and the frame 5 mm down

    def rhs(_, y):
        q, v = y[:n], y[n:2 * n]
        return np.concatenate((v, -Minv @ (K @ q + C @ v), [v @ C @ v + v @ Ka @ q]))

    sol = solve_ivp(rhs, (0, 3.0), np.concatenate((q0, np.zeros(n), [0.0])), rtol=1e-10, atol=1e-13)
    q, v, lost = sol.y[:n, -1], sol.y[n:2 * n, -1], sol.y[-1, -1]
    e0 = 0.5 * q0 @ Ks @ q0
    e1 = 0.5 * v @ M @ v + 0.5 * q @ Ks @ q
    assert e0 - e1 == pytest.approx(lost, rel=1e-6)
    assert e1 < 0.05 * e0  # and it rings down


def test_rider_hz_needs_a_bike_and_a_positive_number(tmp_path, capsys):
    rc = cli.main(["fit", "bounce", str(tmp_path / "a.SST"), "--clicks", "0", "--rider-hz", "5",
                   "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--rider-hz" in err[0] and "--bike" in err[0]
    rc = cli.main(["fit", "bounce", str(tmp_path / "a.SST"), "--clicks", "0", "--bike", "sst", "--rider-hz", "-1",
                   "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--rider-hz" in err[0]
    assert not (tmp_path / "o").exists()


def test_a_rider_resonance_outside_4_to_6_hz_warns_once_and_proceeds():
    from mtbmj.errors import ConfigWarning
    from mtbmj.identify.bounce_fit import _check_rider_hz

    with pytest.warns(ConfigWarning, match="4-6 Hz") as got:
        _check_rider_hz(9.0)
    assert len(got) == 1

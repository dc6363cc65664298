"""Each force law on its own: the physics and maths of the formula, not just that it runs.

Units are SI throughout (m, m/s, N), with values close to the reference preset. The friction laws
follow Olsson, Astrom, Canudas de Wit, Gafvert & Lischinsky (1998) and the LuGre model of
Canudas de Wit et al. (1995).
"""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from mtbmj.controllers import (
    BilinearDamper, BilinearSpring, Coulomb, DigressiveDamper, CoulombViscous, DirectionalSpring, ForkLaw, KelvinVoigt,
    LinearDamper, LinearSpring, LuGre, NoFriction, ProgressiveSpring, Stiction, Stribeck, TableDamper,
    TireLaw, TopOutSpring, smooth_sign,
)

MM = 1e-3
K_TOP = 40e3
PRELOAD = 250.0

LINEAR = LinearSpring(10e3)
BILINEAR = BilinearSpring(8e3, 30e3, 67 * MM)
PROGRESSIVE = ProgressiveSpring(8e3, 0.0007 * 1e3 / MM**2)  # 0.0007 N/mm^3
DIRECTIONAL = DirectionalSpring(LinearSpring(11e3), LinearSpring(9e3), 20 * MM)
DIRECTIONAL_BILINEAR = DirectionalSpring(BILINEAR, LinearSpring(9e3), 20 * MM)

MAINS = {
    "linear": LINEAR,
    "bilinear": BILINEAR,
    "progressive": PROGRESSIVE,
    "directional": DIRECTIONAL,
    "directional_bilinear": DIRECTIONAL_BILINEAR,
}

SPRINGS = dict(MAINS)
for _name, _main in MAINS.items():
    SPRINGS[f"topout_{_name}"] = TopOutSpring(_main, K_TOP, 0.0)
    SPRINGS[f"topout_preload_{_name}"] = TopOutSpring(_main, K_TOP, PRELOAD)

TABLE_V = (-1.5, -0.8, -0.4, -0.15, -0.05, 0.0, 0.05, 0.15, 0.4, 0.8, 1.5)
TABLE_F = (-300.0, -175.0, -95.0, -40.0, -12.0, 0.0, 14.0, 45.0, 115.0, 225.0, 420.0)


def _slope(f, x, h=1e-7):
    return (f(x + h) - f(x - h)) / (2 * h)


# --------------------------------------------------------------------------------------- springs


@pytest.mark.parametrize("x", [-0.02, 0.0, 0.001, 0.05, 0.12])
@pytest.mark.parametrize("v", [-1.0, 0.0, 2.0])
def test_linear_spring_is_hooke(x, v):
    assert LINEAR.force(x, v) == pytest.approx(10e3 * x, abs=1e-12)
    assert LINEAR.energy(x) == pytest.approx(0.5 * 10e3 * x * x, abs=1e-15)


def test_bilinear_spring_is_continuous_at_the_knee_with_its_two_slopes():
    s = BILINEAR
    knee = s.knee
    eps = 1e-9
    # continuous: the force at the knee from both sides is k1 * knee
    assert s.force(knee - eps, 0.0) == pytest.approx(8e3 * knee, abs=1e-4)
    assert s.force(knee, 0.0) == pytest.approx(8e3 * knee, abs=1e-9)
    assert s.force(knee + eps, 0.0) == pytest.approx(8e3 * knee, abs=1e-4)
    # slope k1 below the knee, k2 beyond it
    for x in (0.0, 0.01, 0.03, knee - 1e-3):
        assert _slope(lambda u: s.force(u, 0.0), x, 1e-5) == pytest.approx(8e3, rel=1e-6)
    for x in (knee + 1e-3, 0.09, 0.12, 0.2):
        assert _slope(lambda u: s.force(u, 0.0), x, 1e-5) == pytest.approx(30e3, rel=1e-6)
    # explicit values on both sides
    assert s.force(0.1, 0.0) == pytest.approx(8e3 * knee + 30e3 * (0.1 - knee))
    assert s.force(0.03, 0.0) == pytest.approx(8e3 * 0.03)


@pytest.mark.parametrize("x", [-0.02, 0.0, 0.01, 0.08, 0.12])
def test_progressive_spring_is_cubic(x):
    k, c = 8e3, 7e5
    assert PROGRESSIVE.force(x, 0.3) == pytest.approx(k * x + c * x**3, abs=1e-10)
    # odd, and the rate rises as k + 3 c x^2
    assert PROGRESSIVE.force(-x, 0.0) == pytest.approx(-PROGRESSIVE.force(x, 0.0), abs=1e-10)
    assert _slope(lambda u: PROGRESSIVE.force(u, 0.0), x, 1e-5) == pytest.approx(k + 3 * c * x * x, rel=1e-6)


@pytest.mark.parametrize("x", [0.0, 0.02, 0.06, 0.1])
def test_directional_spring_picks_the_curve_by_stroke_direction(x):
    s = DIRECTIONAL_BILINEAR
    band = s.band
    compression = s.compression.force(x, 0.0)
    rebound = s.rebound.force(x, 0.0)
    if x > 0:
        assert compression != pytest.approx(rebound)  # the two curves differ, so the test can tell
    for v in (20 * band, 50 * band, 3.0):
        assert s.force(x, v) == pytest.approx(compression, rel=1e-12, abs=1e-9)
    for v in (-20 * band, -50 * band, -3.0):
        assert s.force(x, v) == pytest.approx(rebound, rel=1e-12, abs=1e-9)
    assert s.force(x, 0.0) == pytest.approx(0.5 * (compression + rebound), abs=1e-12)
    # the blend is smooth and monotone between the two curves
    vs = np.linspace(-5 * band, 5 * band, 201)
    f = np.array([s.force(x, v) for v in vs])
    lo, hi = min(compression, rebound), max(compression, rebound)
    assert np.all(f >= lo - 1e-9) and np.all(f <= hi + 1e-9)
    d = np.diff(f) * np.sign(compression - rebound)
    assert np.all(d >= -1e-12)


TOP_OUT_V = [-2.0, -0.01, 0.0, 0.01, 2.0]


@pytest.mark.parametrize("main_name", list(MAINS))
@pytest.mark.parametrize("preload", [0.0, PRELOAD])
@pytest.mark.parametrize("v", TOP_OUT_V)
def test_top_out_spring_is_continuous_everywhere(main_name, preload, v):
    s = TopOutSpring(MAINS[main_name], K_TOP, preload)
    h = 0.05 * MM
    xs = np.arange(-20 * MM, 120 * MM + h / 2, h)
    f = np.array([s.force(x, v) for x in xs])
    jumps = np.abs(np.diff(f))
    # local slope: one-sided derivatives at both ends of every interval
    d = 1e-8
    right = np.abs(np.array([(s.force(x + d, v) - s.force(x, v)) / d for x in xs[:-1]]))
    left = np.abs(np.array([(s.force(x, v) - s.force(x - d, v)) / d for x in xs[1:]]))
    bound = 1.05 * h * np.maximum(right, left) + 1e-6
    worst = int(np.argmax(jumps - bound))
    assert np.all(jumps <= bound), (
        f"force jumps by {jumps[worst]:.3g} N between x = {xs[worst] * 1e3:.3f} and {xs[worst + 1] * 1e3:.3f} mm "
        f"(local slope allows {bound[worst]:.3g} N)"
    )
    # the bound is tight enough to catch a preload-sized step: 250 N >> 40 N/mm * 0.05 mm
    assert np.max(bound) < 5.0


@pytest.mark.parametrize("main_name", list(MAINS))
@pytest.mark.parametrize("preload", [0.0, PRELOAD])
def test_top_out_spring_zero_at_full_extension_and_both_springs_beyond(main_name, preload):
    """Pulled past full extension the fork's rate is the top-out rate plus the main rate."""
    main = MAINS[main_name]
    s = TopOutSpring(main, K_TOP, preload)
    for v in TOP_OUT_V:
        assert s.force(0.0, v) == pytest.approx(0.0, abs=1e-9)
        for x in np.linspace(-20 * MM, -0.1 * MM, 12):
            assert s.force(x, v) == pytest.approx(main.force(x, v) + K_TOP * x, rel=1e-12)
            main_slope = _slope(lambda u: main.force(u, v), x, 1e-6)
            assert _slope(lambda u: s.force(u, v), x, 1e-6) == pytest.approx(K_TOP + main_slope, rel=1e-6)


@pytest.mark.parametrize("main_name", list(MAINS))
@pytest.mark.parametrize("preload", [0.0, PRELOAD])
def test_top_out_spring_is_preload_plus_main_once_compressed(main_name, preload):
    main = MAINS[main_name]
    s = TopOutSpring(main, K_TOP, preload)
    # the top-out spring comes free at x_e = P / k_top: 6.25 mm here
    assert s.engagement == pytest.approx(preload / K_TOP)
    for v in TOP_OUT_V:
        for x in np.linspace(10 * MM, 120 * MM, 23):
            assert s.force(x, v) == pytest.approx(preload + main.force(x, v), rel=1e-12, abs=1e-9)
    if preload:
        # between 0 and x_e the top-out spring holds the preload back
        x = 2 * MM
        expected = preload + main.force(x, 0.0) - K_TOP * (preload / K_TOP - x)
        assert s.force(x, 0.0) == pytest.approx(expected)
        assert 0.0 < s.force(x, 0.0) < preload


def test_top_out_spring_does_not_take_over_again_at_deep_compression():
    """Past its engagement the top-out spring is free for good: a progressive main curve never
    hands the force back to it, however deep the compression (the model has no bottom-out stop,
    so compressions beyond the 120 mm travel are reachable on big drops)."""
    s = TopOutSpring(PROGRESSIVE, K_TOP, PRELOAD)
    bad = [x for x in np.linspace(10 * MM, 300 * MM, 59)
           if s.force(x, 0.0) != pytest.approx(PRELOAD + PROGRESSIVE.force(x, 0.0), rel=1e-12)]
    assert not bad, f"top-out line governs again from x = {bad[0] * 1e3:.0f} mm"


@pytest.mark.parametrize("name", list(SPRINGS))
@pytest.mark.parametrize("x", [-20 * MM, -3 * MM, 2 * MM, 8 * MM, 40 * MM, 67 * MM, 90 * MM, 120 * MM])
def test_spring_energy_is_the_integral_of_the_force(name, x):
    s = SPRINGS[name]
    points = [p for p in (67 * MM, 7.8 * MM, 8.0 * MM) if min(0, x) < p < max(0, x)]
    exact, err = quad(lambda u: s.force(u, 0.0), 0.0, x, points=points or None, limit=200, epsabs=1e-12, epsrel=1e-12)
    assert s.energy(x) == pytest.approx(exact, rel=1e-10, abs=1e-12)
    assert s.energy(x) >= 0.0


# --------------------------------------------------------------------------------------- dampers


@pytest.mark.parametrize("v", [-2.0, -0.1, 0.0, 0.3, 1.5])
def test_linear_damper(v):
    d = LinearDamper(225.0)
    assert d.force(v) == pytest.approx(225.0 * v, abs=1e-12)
    assert d.force(-v) == pytest.approx(-d.force(v), abs=1e-12)


def test_bilinear_damper_slopes_and_continuity():
    d = BilinearDamper(300.0, 150.0)
    assert d.force(0.0) == 0.0
    for v in (1e-6, 0.1, 1.0, 3.0):
        assert d.force(v) == pytest.approx(300.0 * v)
        assert d.force(-v) == pytest.approx(-150.0 * v)
    assert _slope(d.force, 0.5, 1e-4) == pytest.approx(300.0)
    assert _slope(d.force, -0.5, 1e-4) == pytest.approx(150.0)
    assert abs(d.force(1e-9) - d.force(-1e-9)) < 1e-6


def test_table_damper_reproduces_the_table_and_interpolates_linearly():
    d = TableDamper(TABLE_V, TABLE_F)
    for v, f in zip(TABLE_V, TABLE_F):
        assert d.force(v) == pytest.approx(f, abs=1e-12)
    for (v0, f0), (v1, f1) in zip(zip(TABLE_V, TABLE_F), zip(TABLE_V[1:], TABLE_F[1:])):
        for t in (0.1, 0.5, 0.9):
            v = v0 + t * (v1 - v0)
            assert d.force(v) == pytest.approx(f0 + t * (f1 - f0), rel=1e-12, abs=1e-12)
    assert d.force(0.0) == 0.0


def test_table_damper_extrapolates_with_the_end_slopes():
    d = TableDamper(TABLE_V, TABLE_F)
    hi = (TABLE_F[-1] - TABLE_F[-2]) / (TABLE_V[-1] - TABLE_V[-2])
    lo = (TABLE_F[1] - TABLE_F[0]) / (TABLE_V[1] - TABLE_V[0])
    for v in (1.6, 2.5, 5.0):
        assert d.force(v) == pytest.approx(TABLE_F[-1] + hi * (v - TABLE_V[-1]))
    for v in (-1.6, -2.5, -5.0):
        assert d.force(v) == pytest.approx(TABLE_F[0] + lo * (v - TABLE_V[0]))


def test_table_damper_without_a_zero_point_passes_through_zero():
    d = TableDamper([-1.0, -0.2, 0.1, 1.0], [-100.0, -30.0, 20.0, 150.0])
    assert d.force(0.0) == 0.0
    assert d.velocity == (-1.0, -0.2, 0.0, 0.1, 1.0)
    assert d.n_guards == 3 == len(d.guards(0.0, 0.0))
    assert d.force(0.05) == pytest.approx(10.0)  # on the line (0, 0)-(0.1, 20)
    assert d.force(-0.1) == pytest.approx(-15.0)  # on the line (-0.2, -30)-(0, 0)
    for v, f in [(-1.0, -100.0), (-0.2, -30.0), (0.1, 20.0), (1.0, 150.0)]:
        assert d.force(v) == pytest.approx(f)


# -------------------------------------------------------------------------------------- friction

F_C, F_S, F_V = 20.0, 30.0, 50.0


def test_smooth_sign():
    assert smooth_sign(0.0, 0.005) == 0.0
    assert smooth_sign(0.1, 0.005) == pytest.approx(1.0, abs=1e-15)
    assert smooth_sign(-0.1, 0.005) == pytest.approx(-1.0, abs=1e-15)
    assert smooth_sign(1e-6, 0.005) == pytest.approx(1e-6 / 0.005, rel=1e-6)


def test_no_friction():
    f = NoFriction()
    assert f.force(0.3) == 0.0 and f.force(-2.0, 0.1) == 0.0
    assert not f.has_state and f.n_guards == 0


def test_coulomb_is_odd_and_saturates_at_f_c():
    band = 5 * MM
    f = Coulomb(F_C, band)
    for v in (20 * band, 0.5, 3.0):
        assert f.force(v) == pytest.approx(F_C, rel=1e-12)
        assert f.force(-v) == pytest.approx(-F_C, rel=1e-12)
    for v in np.linspace(0, 0.05, 51):
        assert f.force(-v) == -f.force(v)
        assert abs(f.force(v)) <= F_C
    assert f.force(0.0) == 0.0
    # slope F_C / band through zero: a regularised sgn, not a step
    assert _slope(f.force, 0.0, 1e-7) == pytest.approx(F_C / band, rel=1e-6)


def test_coulomb_viscous():
    band = 5 * MM
    f = CoulombViscous(F_C, F_V, band)
    for v in (20 * band, 0.5, 3.0):
        assert f.force(v) == pytest.approx(F_C + F_V * v, rel=1e-12)
        assert f.force(-v) == pytest.approx(-(F_C + F_V * v), rel=1e-12)
    for v in np.linspace(0, 0.05, 51):
        assert f.force(-v) == pytest.approx(-f.force(v), abs=1e-12)
    assert f.force(0.0) == 0.0


def _stiction(band=1e-5, dv=10 * MM):
    return Stiction(F_C, F_S, F_V, dv, band)


def test_stiction_reaches_breakaway_near_zero_and_coulomb_viscous_outside_the_band():
    dv, band = 10 * MM, 1e-5
    f = _stiction(band, dv)
    v0 = 20 * band  # sgn is saturated, still deep inside the stiction band
    expected = F_C + (F_S - F_C) * (1 - v0 / dv) + F_V * v0
    assert f.force(v0) == pytest.approx(expected, rel=1e-9)
    assert f.force(v0) == pytest.approx(F_S, rel=0.01)
    assert f.force(-v0) == pytest.approx(-f.force(v0), abs=1e-12)
    vs = np.linspace(0, dv, 2001)
    assert max(f.force(v) for v in vs) == pytest.approx(F_S, rel=0.01)
    for v in (dv, 1.5 * dv, 0.3, 2.0):
        assert f.force(v) == pytest.approx(F_C + F_V * v, rel=1e-12)
        assert f.force(-v) == pytest.approx(-(F_C + F_V * v), rel=1e-12)
    # the level falls linearly from F_S to F_C across the band
    for t in (0.25, 0.5, 0.75):
        v = t * dv
        assert f.force(v) == pytest.approx(F_C + (F_S - F_C) * (1 - t) + F_V * v, rel=1e-9)


def test_stiction_is_continuous_at_its_guards():
    dv = 10 * MM
    f = _stiction(1e-5, dv)
    for edge in (dv, -dv):
        for eps in (1e-6, 1e-9):
            jump = abs(f.force(edge + eps) - f.force(edge - eps))
            assert jump <= 2.1 * eps * ((F_S - F_C) / dv + F_V) + 1e-12
    vs = np.linspace(-3 * dv, 3 * dv, 6001)
    jumps = np.abs(np.diff([f.force(v) for v in vs]))
    away_from_zero = np.abs(vs[:-1]) > 0.001
    # steps of 0.01 mm/s: at most (F_S - F_C)/dv + F_V = 1050 N s/m -> 0.0105 N, no steps
    assert np.max(jumps[away_from_zero]) < 0.011


def test_stribeck_curve():
    band, vs_ = 1e-5, 20 * MM
    f = Stribeck(F_C, F_S, F_V, vs_, 2.0, band)
    # near zero (sgn saturated, v << v_S): the breakaway force
    assert f.force(20 * band) == pytest.approx(F_S, rel=1e-3)
    # at v_S: F_C + (F_S - F_C) / e
    assert f.force(vs_) == pytest.approx(F_C + (F_S - F_C) / math.e + F_V * vs_, rel=1e-12)
    # far beyond v_S: Coulomb + viscous
    for v in (10 * vs_, 1.0, 3.0):
        assert f.force(v) == pytest.approx(F_C + F_V * v, rel=1e-9)
    # odd
    for v in (1e-4, 0.01, 0.5):
        assert f.force(-v) == pytest.approx(-f.force(v), abs=1e-12)
    # without viscous friction the level falls monotonically from F_S to F_C
    g = Stribeck(F_C, F_S, 0.0, vs_, 2.0, band)
    levels = [g.force(v) for v in np.linspace(20 * band, 5 * vs_, 200)]
    assert np.all(np.diff(levels) <= 1e-12)
    assert levels[0] == pytest.approx(F_S, rel=1e-3) and levels[-1] == pytest.approx(F_C, rel=1e-6)
    # the exponent shapes the fall: exp(-|v/v_S|^delta)
    h = Stribeck(F_C, F_S, 0.0, vs_, 1.0, band)
    assert h.force(vs_ / 2) == pytest.approx(F_C + (F_S - F_C) * math.exp(-0.5), rel=1e-9)
    assert g.force(vs_ / 2) == pytest.approx(F_C + (F_S - F_C) * math.exp(-0.25), rel=1e-9)


LUGRE = LuGre(F_C, F_S, 20 * MM, 100e3, 300.0, 40.0)


@pytest.mark.parametrize("v", [-2.0, -0.1, -0.02, -1e-4, 1e-4, 0.005, 0.02, 0.3, 1.5])
def test_lugre_steady_state(v):
    f = LUGRE
    g = F_C + (F_S - F_C) * math.exp(-((v / (20 * MM)) ** 2))
    assert f.g(v) == pytest.approx(g, rel=1e-12)
    z_ss = g / f.stiffness * math.copysign(1.0, v)
    assert f.state_rate(v, z_ss) == pytest.approx(0.0, abs=1e-12 * max(1.0, abs(v)))
    assert f.force(v, z_ss) == pytest.approx(g * math.copysign(1.0, v) + f.viscous * v, rel=1e-12)
    # off the steady state the bristles relax towards it: dz/dt has the sign of z_ss - z
    for dz in (-0.3, 0.3):
        z = z_ss * (1 + dz)
        assert math.copysign(1.0, f.state_rate(v, z)) == math.copysign(1.0, z_ss - z)


def test_lugre_at_rest_is_a_bristle_spring():
    f = LUGRE
    assert f.has_state and f.n_guards == 1
    for z in (-1e-4, 0.0, 5e-5):
        assert f.state_rate(0.0, z) == 0.0
        assert f.force(0.0, z) == pytest.approx(f.stiffness * z)
    # dz/dt = v - sigma0 |v| z / g(v), F = sigma0 z + sigma1 dz/dt + sigma2 v
    v, z = 0.01, 1e-4
    rate = v - f.stiffness * abs(v) * z / f.g(v)
    assert f.state_rate(v, z) == pytest.approx(rate)
    assert f.force(v, z) == pytest.approx(f.stiffness * z + f.damping * rate + f.viscous * v)


# ------------------------------------------------------------------------------------------ tire


def test_kelvin_voigt_pushes_but_never_pulls():
    t = KelvinVoigt(80e3, 150.0)
    assert t.force(0.01, 0.0) == pytest.approx(800.0)
    assert t.force(0.01, 1.0) == pytest.approx(950.0)
    assert t.force(0.01, -2.0) == pytest.approx(500.0)
    # no contact: nothing, whatever the rate
    for d in (0.0, -1e-9, -0.05):
        for r in (-3.0, 0.0, 3.0):
            assert t.force(d, r) == 0.0
    # in contact but separating faster than the spring pushes: k d + b dd/dt < 0 -> 0, not a pull
    assert 80e3 * 0.001 + 150.0 * -1.0 < 0
    assert t.force(0.001, -1.0) == 0.0
    for d in np.linspace(-0.01, 0.05, 31):
        for r in np.linspace(-5, 5, 21):
            f = t.force(d, r)
            assert f >= 0.0
            if d > 0 and 80e3 * d + 150.0 * r > 0:
                assert f == pytest.approx(80e3 * d + 150.0 * r)


def test_tire_law_switch_semantics():
    impact, contact = KelvinVoigt(80e3, 150.0), KelvinVoigt(70e3, 120.0)
    fixed = TireLaw(impact)
    assert not fixed.switches
    assert fixed.values(0) is impact and fixed.values(1) is impact
    assert fixed.force(0.01, 0.1, phase=1) == impact.force(0.01, 0.1)
    switching = TireLaw(impact, contact)
    assert switching.switches
    assert switching.values(0) is impact and switching.values(1) is contact
    assert switching.force(0.01, 0.1) == pytest.approx(800.0 + 15.0)
    assert switching.force(0.01, 0.1, phase=1) == pytest.approx(700.0 + 12.0)
    # the event (controllers.tire.SWITCH_RULE, found by stepping.switch_index, which the MuJoCo
    # engine and the batched runner use): the tire leaves the ground, or the fork turns from
    # extension into compression. A state row here is (sled, fork, fork velocity).
    from mtbmj.drop.stepping import switch_index

    def switches(d0, d1, v0, v1):
        return switch_index(np.array([d0, 0.0, v0]), np.array([[d1, 0.0, v1]]), (0, 1, 2)) == 0

    assert switches(0.001, 0.0, 0.5, 0.4)  # deflection falls to zero
    assert switches(0.001, -0.001, -0.5, -0.4)
    assert switches(0.01, 0.01, -0.01, 0.0)  # rebound stroke ends on the ground
    assert not switches(0.0, -0.001, 0.1, 0.2)  # already in the air
    assert not switches(0.01, 0.011, 0.0, 0.1)  # compressing from rest (the impact itself)
    assert not switches(0.01, 0.009, 0.1, -0.1)  # Peak 1: compression turns into extension


# ------------------------------------------------------------------------ sides / guards mechanism

FRICTION_STATIC = Stiction(F_C, F_S, F_V, 10 * MM, 1e-3)


def _spring_case(law):
    return law, (lambda x, v, sides=None: law.force(x, v, sides))


def _damper_case(law):
    return law, (lambda x, v, sides=None: law.force(v, sides))


def _friction_case(law, z=0.0):
    return law, (lambda x, v, sides=None: law.force(v, z, sides))


def _fork_case(law, z=0.0):
    return law, (lambda x, v, sides=None: law.force(x, v, z, sides))


PIECEWISE = {
    "bilinear_spring": _spring_case(BILINEAR),
    "directional_bilinear": _spring_case(DIRECTIONAL_BILINEAR),
    "topout_linear": _spring_case(TopOutSpring(LINEAR, K_TOP, PRELOAD)),
    "topout_progressive": _spring_case(TopOutSpring(PROGRESSIVE, K_TOP, PRELOAD)),
    "topout_directional_bilinear": _spring_case(TopOutSpring(DIRECTIONAL_BILINEAR, K_TOP, PRELOAD)),
    "bilinear_damper": _damper_case(BilinearDamper(300.0, 150.0)),
    "digressive_damper": _damper_case(DigressiveDamper(1500.0, 300.0, 0.3, 2500.0, 500.0, 0.25)),
    "table_damper": _damper_case(TableDamper(TABLE_V, TABLE_F)),
    "stiction": _friction_case(FRICTION_STATIC),
    "lugre": _friction_case(LUGRE, 1e-4),
    "fork_s6_like": _fork_case(ForkLaw(TopOutSpring(DIRECTIONAL_BILINEAR, K_TOP, PRELOAD),
                                       TableDamper(TABLE_V, TABLE_F), FRICTION_STATIC)),
    "fork_lugre": _fork_case(ForkLaw(TopOutSpring(BILINEAR, K_TOP, 0.0), BilinearDamper(300.0, 150.0), LUGRE), -5e-5),
}

GRID_X = sorted({-0.02, -0.001, 0.0, 0.002, 6.25 * MM, 0.03, 0.067, 0.08, 0.12} | {k * 0.013 for k in range(-1, 11)})
GRID_V = sorted(set(TABLE_V) | {-3.0, -0.6, -0.01, -1e-4, 1e-4, 0.01, 0.6, 3.0, 0.02, -0.02})


@pytest.mark.parametrize("name", list(PIECEWISE))
def test_live_sides_reproduce_the_law(name):
    law, force = PIECEWISE[name]
    assert law.n_guards > 0
    for x in GRID_X:
        for v in GRID_V:
            guards = law.guards(x, v)
            assert len(guards) == law.n_guards
            sides = tuple(g >= 0.0 for g in guards)
            assert force(x, v, sides) == force(x, v), (x, v, sides)


def _second_difference(f, a, b):
    """f(a) - 2 f(mid) + f(b): zero for a straight line, ~ slope change x half-width at a kink."""
    return f(a) - 2.0 * f(0.5 * (a + b)) + f(b)


# (name, law, force(x, v, sides), point p0 on one side, point p1 across exactly one guard,
#  the branch's own formula at p1)
K1, K2, KNEE = 8e3, 30e3, 67 * MM
_table = TableDamper(TABLE_V, TABLE_F)
_bilinear_damper = BilinearDamper(300.0, 150.0)
_topout = TopOutSpring(LINEAR, K_TOP, PRELOAD)
_x_cross = PRELOAD / K_TOP  # where the top-out spring comes free

FROZEN = [
    ("bilinear below knee, continued past it", BILINEAR, lambda x, v, s: BILINEAR.force(x, v, s),
     (KNEE - 5 * MM, 0.0), (KNEE + 5 * MM, 0.0), lambda x, v: K1 * x),
    ("bilinear above knee, continued below it", BILINEAR, lambda x, v, s: BILINEAR.force(x, v, s),
     (KNEE + 5 * MM, 0.0), (KNEE - 5 * MM, 0.0), lambda x, v: K1 * KNEE + K2 * (x - KNEE)),
    ("bilinear damper compression, continued into rebound", _bilinear_damper,
     lambda x, v, s: _bilinear_damper.force(v, s), (0.0, 0.2), (0.0, -0.2), lambda x, v: 300.0 * v),
    ("bilinear damper rebound, continued into compression", _bilinear_damper,
     lambda x, v, s: _bilinear_damper.force(v, s), (0.0, -0.2), (0.0, 0.2), lambda x, v: 150.0 * v),
    ("table segment 0.15-0.4, continued past 0.4", _table, lambda x, v, s: _table.force(v, s),
     (0.0, 0.3), (0.0, 0.5), lambda x, v: 45.0 + (115.0 - 45.0) / 0.25 * (v - 0.15)),
    ("table segment 0-0.05, continued below 0", _table, lambda x, v, s: _table.force(v, s),
     (0.0, 0.03), (0.0, -0.03), lambda x, v: 14.0 / 0.05 * v),
    ("stiction inside, continued past +dv", FRICTION_STATIC, lambda x, v, s: FRICTION_STATIC.force(v, 0.0, s),
     (0.0, 8 * MM), (0.0, 14 * MM),
     lambda x, v: (F_C + (F_S - F_C) * (1 - abs(v) / (10 * MM))) * math.tanh(v / 1e-3) + F_V * v),
    ("stiction outside, continued into the band", FRICTION_STATIC, lambda x, v, s: FRICTION_STATIC.force(v, 0.0, s),
     (0.0, -14 * MM), (0.0, -8 * MM), lambda x, v: F_C * math.tanh(v / 1e-3) + F_V * v),
    ("top-out engaged, continued past its free point", _topout, lambda x, v, s: _topout.force(x, v, s),
     (_x_cross - 2 * MM, 0.0), (_x_cross + 2 * MM, 0.0), lambda x, v: PRELOAD + 10e3 * x - K_TOP * (_x_cross - x)),
    ("preloaded main, continued into extension", _topout, lambda x, v, s: _topout.force(x, v, s),
     (_x_cross + 2 * MM, 0.0), (-5 * MM, 0.0), lambda x, v: PRELOAD + 10e3 * x),
    ("lugre sliding forward, continued into reverse", LUGRE, lambda x, v, s: LUGRE.state_rate(v, 1e-4, s),
     (0.0, 0.01), (0.0, -0.01), lambda x, v: v - LUGRE.stiffness * v * 1e-4 / LUGRE.g(v)),
]


@pytest.mark.parametrize("case", FROZEN, ids=[c[0] for c in FROZEN])
def test_frozen_side_is_the_branch_formula_across_the_guard(case):
    _, law, force, p0, p1, formula = case
    frozen = tuple(g >= 0.0 for g in law.guards(*p0))
    crossed = tuple(g >= 0.0 for g in law.guards(*p1))
    assert sum(a != b for a, b in zip(frozen, crossed)) == 1, "p0 -> p1 must cross exactly one guard"
    # the frozen branch is the branch's own formula on both sides of the guard
    for t in np.linspace(0.0, 1.0, 11):
        x = p0[0] + t * (p1[0] - p0[0])
        v = p0[1] + t * (p1[1] - p0[1])
        assert force(x, v, frozen) == pytest.approx(formula(x, v), rel=1e-12, abs=1e-12)
    # ... so it is smooth across the guard, where the live law switches branch (a kink)
    along = lambda t: (p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1]))
    frozen_curve = lambda t: force(*along(t), frozen)
    live_curve = lambda t: force(*along(t), None)
    kink = abs(_second_difference(live_curve, 0.0, 1.0))
    smooth = abs(_second_difference(frozen_curve, 0.0, 1.0))
    assert kink > 1e-3 * max(abs(live_curve(0.0)), abs(live_curve(1.0)), 1e-9)
    assert smooth < 0.1 * kink

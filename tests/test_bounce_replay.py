"""The seat slam replayed through the MuJoCo bike with a compliant seated rider
(``mtbmj.identify.bounce_replay``, ``fit bounce --replay``).

(a) A slam made here by a model of this file's own (``slam`` below: its own fixed-step integrator,
three masses on one line in the shock's stroke: the seated rider on a saddle spring-damper, the body
on the shock, the wheel on a tyre spring in series under it; a coil with preload on the preset's
top-out spring, a stiffness beside the coil, a linear damper, Coulomb friction with a stick condition,
started at rest, pushed by a known lift and slam): the replay gives back the spring scale and the
damper. What the two models share: the seated body's 5 Hz and 0.475 (Fairley and Griffin 1989), the
linear damper both ways, Coulomb friction, the preset's top-out spring (300 N/mm carrying the coil's
preload, ``TopOutSpring``), the rest level matched by preload, and four lumped values in the stroke:
the sprung mass (529 kg), the stiffness beside the coil (9.2 kN/m), the wheel's mass (34 kg: 3.5 kg
times the leverage ratio squared, 3.1^2; the fit does not depend on it, 34-120 kg fit alike) and the
spring in series (680 kN/m: the tyre and what flexes with it), solved by least squares on the
linearised model's lowest mode so that it rings as sixteen free ring-downs of the MuJoCo bike at its
10 mm rest were measured (spring 0.45-1.0 x, damper 100-7500 N s/m: damped frequency and damping
ratio; ``test_generator_rings_as_the_bike`` holds six of them, lightly and heavily damped, within 1 %
and 5 %). Not shared: the integrator, the bike's pitch and fork, the leverage curve (the bike
stiffens with stroke, the generator does not), the tyres' law, the friction law (a stick condition
here, the shock law's friction state there), the push's shape (half sines here, sin^2 lobes there)
and where it acts (the stiffening is small: the two ring within 0.2 % about the slam's 14 mm rest,
2.1 % apart about 30 mm). The stated tolerance is 15 % on the spring and 30 % on the damper. It holds
lightly (2500 N s/m) and heavily (5000 N s/m) damped; the spring's interval holds the generator's
heavily damped, not lightly (a strict xfail with the numbers).

Two earlier forms of this generator were not the bike. The first took the mass from the preset's
rear mode at its own spring alone (522 kg, no stiffness beside the coil) and a top-out stop 100 x
stiffer than the preset's: at 0.55 x it rang as the bike does at 0.47 x, and the replay read it
0.45 and 0.40 x. The second, one mode (665 kg, 17.8 kN/m beside the coil) rang as the bike lightly
damped, but its damped frequency fell with the damper as one mass on a spring does while the bike's
falls less (the tyre in series): heavily damped (5000 N s/m) the replay read it 0.461 x.

(b) Wrong input: the record's travel scaled x2 (it leaves the shock's stroke) is refused in one
line; a slam the bike cannot follow (a ring-down at 6 Hz, three times faster than any spring scale
in bounds gives) is refused.

(c) The shared slams (00083, 00085, 00087 at 0, 8, 17 clicks): see ``test_shared_slams``.

(d) The rebound damper read from the first rebound (``bounce_rebound``): on two slams of the generator
at two rebound settings (its damper ``rebound`` in extension, ``c`` in compression) and on the shared
slams, where it rises with the clicks while the whole-trace replay's damper does not.
"""
from __future__ import annotations

import functools
import math
import os

import numpy as np
import pytest

from mtbmj.identify.bounce import BounceError

from helpers import (SLAM_K_OTHER as K_OTHER, SLAM_K_TYRE as K_TYRE, SLAM_TOP_OUT as TOP_OUT,  # noqa: E402
                     SLAM_W_SHOCK as W_SHOCK, slam_parts)

FS = 5000.0
STILL_M_PER_S = 1e-4  # the stroke's speed under which the friction may hold it


def slam(scale=0.55, c=2500.0, fc=30.0, rest_mm=14.0, lift=0.6, push=1.0, noise=0.05, seed=1, dt=2e-5,
         quiet=2.0, after=1.6, rebound=None):
    """(time_s, stroke_mm) of a seat slam: at rest for ``quiet`` s, a lift (``lift`` x the static force,
    a half sine over 0.35 s) and a slam (``push`` x, a half sine over 0.2 s) on the rider, then free.
    Three masses on one line (down positive): the rider on the saddle, the body (frame) on the shock,
    the wheel on the tyre; the stroke is the body's travel less the wheel's. The coil's preload P
    rests the shock at ``rest_mm``; near full extension the top-out spring takes it up,
    P + k x - k_t max(0, P / k_t - x), so the force is 0 at full extension (x = 0). The tyre pushes
    only while it touches (its force not below 0). The friction holds the stroke while its speed is
    under STILL_M_PER_S and the force it needs (the body's and wheel's forces apart, their reduced
    mass) is within ``fc``; then body and wheel move as one. The damper is ``c`` both ways, or ``c`` in
    compression and ``rebound`` in extension when given."""
    c_reb = c if rebound is None else rebound
    k, m_r, m_b, m_w, k_r, c_r, g_r, g_b, x_rest, preload = slam_parts(scale, rest_mm)
    t_lift, T_lift = quiet - 0.55, 0.35
    t_slam, T_slam = quiet - 0.2, 0.2
    zb, vb = x_rest, 0.0  # the body (so the stroke is zb - zw)
    zw, vw = 0.0, 0.0  # the wheel: the tyre's deflection past its static one
    y, vy = g_r / k_r, 0.0  # the saddle's deflection (the rider down on the bike)
    every = int(round(1 / (FS * dt)))
    out = []
    for i in range(int(round((quiet + after) / dt))):
        t = i * dt
        f = 0.0  # on the rider, down positive
        if t_lift < t < t_lift + T_lift:
            f -= lift * W_SHOCK * math.sin(math.pi * (t - t_lift) / T_lift)
        if t_slam < t < t_slam + T_slam:
            f += push * W_SHOCK * math.sin(math.pi * (t - t_slam) / T_slam)
        x, v = zb - zw, vb - vw
        saddle = k_r * y + c_r * vy
        spring = preload + k * x + K_OTHER * (x - x_rest) - TOP_OUT * max(0.0, preload / TOP_OUT - x)
        tyre = max(0.0, W_SHOCK + K_TYRE * zw)
        damper = (c if v > 0.0 else c_reb) * v
        on_body = g_b + saddle - spring - damper
        on_wheel = spring + damper - tyre
        hold = (m_w * on_body - m_b * on_wheel) / (m_b + m_w)  # the friction that keeps the stroke still
        if abs(v) < STILL_M_PER_S and abs(hold) <= fc:  # stuck: body and wheel as one
            ab = aw = (on_body + on_wheel) / (m_b + m_w)
            vb = vw = (m_b * vb + m_w * vw) / (m_b + m_w)
        else:
            friction = fc * math.copysign(1.0, v if abs(v) >= STILL_M_PER_S else hold)
            ab, aw = (on_body - friction) / m_b, (on_wheel + friction) / m_w
        ay = (g_r + f - saddle) / m_r - ab
        vb += ab * dt
        vw += aw * dt
        vy += ay * dt
        zb += vb * dt
        zw += vw * dt
        y += vy * dt
        if i % every == 0:
            out.append(zb - zw)
    x = np.array(out) * 1e3
    return np.arange(x.size) / FS, x + noise * np.random.default_rng(seed).standard_normal(x.size)


def ring(t, x) -> tuple[float, float]:
    """(damped frequency in Hz, damping ratio) of a free ring-down about a level near 0: a damped
    sinusoid A exp(-a t) cos(w t + phase) + level fitted by least squares."""
    from scipy.optimize import curve_fit

    def model(tt, amp, a, w, phase, level):
        return amp * np.exp(-a * tt) * np.cos(w * tt + phase) + level

    tt = t - t[0]
    i = np.nonzero(np.diff(np.sign(x)) != 0)[0]
    f0 = 1.0 / (2.0 * np.mean(np.diff(tt[i]))) if i.size > 1 else 1.5
    p, _ = curve_fit(model, tt, x, p0=[float(np.max(np.abs(x))), 1.0, 2 * math.pi * f0, 0.0, 0.0], maxfev=20000)
    a, w = float(p[1]), abs(float(p[2]))
    return w / (2 * math.pi), a / math.hypot(a, w)


def test_generator_is_a_slam():
    """The test's own slam: at rest at 14 mm before, a slam deep into the stroke, a ring-down that tops
    out (reaches the top-out spring, P / k_t = 4 mm) and stays within the bike's stroke."""
    t, x = slam()
    before = x[t < 1.4]
    assert abs(np.median(before) - 14.0) < 0.05
    assert 40.0 < x.max() < 65.0
    after = x[t > t[np.argmax(x)]]
    assert -1.3 < after.min() < 1.0


@pytest.fixture(scope="module")
def seated():
    from mtbmj.identify.bounce_replay import SeatedReplay

    return SeatedReplay("sst")


def test_starts_at_rest_and_holds_still(seated):
    """The compliant seated bike at the record's rest level: no acceleration, and with no push it stays
    (the saddle's preload is the seated rider's weight share, the shock's the rest level's)."""
    from mtbmj.identify.bounce_replay import NAMES

    seated.set_rest(12.0, None)
    seated.set_shock(0.5, 2000.0, 30.0)
    assert seated.rest_acceleration() < 1e-6
    p = dict.fromkeys(NAMES, 0.1)
    p.update(lift_N=0.0, slam_N=0.0, spring_scale=0.5, damper_N_s_per_m=2000.0, friction_N=30.0)
    out = seated.run(p)
    assert abs(out["stroke_mm"][0] - 12.0) < 1e-3
    assert np.max(np.abs(out["stroke_mm"] - 12.0)) < 1e-3
    assert np.max(np.abs(out["rider_mm"])) < 1e-3


def test_saddle_rings_at_rider_hz(seated):
    """The saddle's vertical rate with the legs' and arms' on the rider's height gives rider_hz on the
    rider's own mass (the frame held): k / m = (2 pi 5)^2, m the rider's body mass from MuJoCo."""
    import mujoco

    seated.set_rest(12.0, None)
    seated.set_shock(0.5, 2000.0, 30.0)
    seated.start()
    m, d = seated.model, seated.p.data
    mujoco.mj_forward(m, d)
    mass = float(m.body_mass[seated.rider_body])
    # the rider's height stiffness: the MuJoCo generalised force's slope at the seated position, the frame held
    from mtbmj.controllers import installed

    def force(dz):
        seated.start()
        d.qpos[seated.qadr[0]] = dz
        with installed(seated.p.callback):
            mujoco.mj_forward(m, d)
        return float(d.qfrc_passive[seated.dofs[0]] + d.qfrc_applied[seated.dofs[0]] + d.qfrc_actuator[seated.dofs[0]]
                     - d.qfrc_bias[seated.dofs[0]])

    k = -(force(1e-5) - force(-1e-5)) / 2e-5
    assert math.sqrt(k / mass) / (2 * math.pi) == pytest.approx(5.0, rel=0.05)


# the MuJoCo bike's free ring-downs at a 10 mm rest (damped frequency Hz, damping ratio), measured
BIKE_RINGS = {(0.55, 100.0): (1.4886, 0.0191), (1.0, 100.0): (1.8412, 0.0273), (0.55, 2500.0): (1.4613, 0.2014),
              (0.55, 5000.0): (1.4217, 0.3950), (0.45, 5000.0): (1.3019, 0.4448), (1.0, 5000.0): (1.7996, 0.2727)}


@pytest.mark.parametrize("scale,c", list(BIKE_RINGS))
def test_generator_rings_as_the_bike(seated, scale, c):
    """The generator's lumped values (M_SHOCK, K_OTHER, M_WHEEL, K_TYRE) hold: a small free ring-down of
    this file's model (no friction, its rest at 10 mm) and of the MuJoCo bike (the same) have the same
    damped frequency within 1 % and, damped (2500 N s/m and more), the same damping ratio within 5 %,
    lightly and heavily damped: the bike's frequency falls with the damper less than one mass on a
    spring does (at 0.55 x, 1.489 Hz at 100 N s/m, 1.422 at 5000 where one mode would give 1.368),
    as the tyre in series makes it. Lightly damped (100 N s/m) the bike's damping ratio is 0.019-0.027
    against the generator's 0.016-0.022 (the bike's own losses beside the damper), not compared."""
    t, x = slam(scale=scale, c=c, fc=0.0, rest_mm=10.0, lift=0.0, push=0.15, noise=0.0, dt=1e-4, after=3.0)
    free = (t > 2.05) & (t < 3.6)
    f_test, z_test = ring(t[free], x[free] - 10.0)
    seated.set_rest(10.0, None)
    out = seated.run({"lift_N": 0.0, "lift_start_s": -0.5, "lift_s": 0.1, "slam_N": 300.0, "slam_end_s": 0.0,
                      "slam_s": 0.1, "spring_scale": scale, "damper_N_s_per_m": c, "friction_N": 0.0},
                     before_s=0.2, after_s=3.0)
    tb, xb = out["time_s"], out["stroke_mm"] - out["stroke_mm"][0]
    free = (tb > 0.05) & (tb < 1.6)
    f_bike, z_bike = ring(tb[free], xb[free])
    hz, zeta = BIKE_RINGS[(scale, c)]
    assert f_bike == pytest.approx(hz, rel=0.01) and z_bike == pytest.approx(zeta, rel=0.05)
    assert f_test == pytest.approx(f_bike, rel=0.01)
    if c >= 2500.0:
        assert z_test == pytest.approx(z_bike, rel=0.05)


def test_generator_and_bike_along_the_stroke(seated):
    """Where the generator (linear in the stroke) and the bike (its leverage falling with travel) part: a
    small free ring-down of each at 0.55 x and 2500 N s/m about the slam's 14 mm rest and about 30 mm.
    At 14 mm they ring within 1 % (measured 1.467 and 1.470 Hz); at 30 mm the bike rings 1-4 % faster
    (measured 2.1 %: 1.498 Hz), the generator not at all. The leverage alone, as this test interpolates
    the bike file's table (sst: stroke the integral of 1 / ratio over wheel travel), would raise the
    frequency from 10 to 30 mm by at least its ratio's fall, 2.97 / 2.68 = 11 % (a sprung mass fixed at the wheel):
    the MuJoCo bike's rear mode stiffens a fifth of that, so a generator stiffened by the leverage alone
    would part from the bike more than this linear one does, and the stiffening is not what reads the
    generator's spring low (docs/identification.md, "The spring from the ring-down's period")."""
    import tomllib
    from pathlib import Path

    import mtbmj

    table = tomllib.loads((Path(mtbmj.__file__).parent / "bike" / "presets" / "sst.toml").read_text())["leverage"]
    w, lr = np.array(table["wheel_travel_mm"], float), np.array(table["ratio"], float)
    stroke = np.concatenate(([0.0], np.cumsum(np.diff(w) * 0.5 * (1 / lr[1:] + 1 / lr[:-1]))))
    ratio_at = lambda s_mm: float(np.interp(np.interp(s_mm, stroke, w), w, lr))  # noqa: E731
    assert ratio_at(10.0) / ratio_at(30.0) > 1.10

    hz = {}
    for rest in (14.0, 30.0):
        t, x = slam(scale=0.55, c=2500.0, fc=0.0, rest_mm=rest, lift=0.0, push=0.15, noise=0.0, dt=1e-4, after=3.0)
        free = (t > 2.05) & (t < 3.6)
        seated.set_rest(rest, None)
        out = seated.run({"lift_N": 0.0, "lift_start_s": -0.5, "lift_s": 0.1, "slam_N": 300.0, "slam_end_s": 0.0,
                          "slam_s": 0.1, "spring_scale": 0.55, "damper_N_s_per_m": 2500.0, "friction_N": 0.0},
                         before_s=0.2, after_s=3.0)
        tb, xb = out["time_s"], out["stroke_mm"] - out["stroke_mm"][0]
        fb = (tb > 0.05) & (tb < 1.6)
        hz[rest] = (ring(t[free], x[free] - rest)[0], ring(tb[fb], xb[fb])[0])
    assert hz[14.0][1] == pytest.approx(hz[14.0][0], rel=0.01)
    assert hz[30.0][0] == pytest.approx(hz[14.0][0], rel=1e-3)
    assert 1.01 < hz[30.0][1] / hz[30.0][0] < 1.04


@pytest.fixture(scope="module")
def generated():
    """The replays of two slams of this file's generator: spring 0.55 x the preset's, damper 2500 and
    5000 N s/m, friction 30 N; each on a bike of its own (a replay's start values and its static
    solution's guess carry over on one SeatedReplay, so a shared one made the result depend on the
    tests run before it: the light case's spring interval reached 0.56 or 0.544)."""
    from mtbmj.identify.bounce_replay import SeatedReplay, replay

    out = {}
    for c in (2500.0, 5000.0):
        t, x = slam(scale=0.55, c=c, fc=30.0)
        out[c] = replay(t, x, None, name=f"generated {c:g}", seated=SeatedReplay("sst"))
    return out


@pytest.mark.slow
def test_follows_an_independent_slam(generated):
    """(a) The replay follows the generator's slam and ring-down within 5 % of the slam's rise (RMS)
    and reads the doubled damper as the larger."""
    for rp in generated.values():
        assert rp.rms_mm < 0.05 * rp.rise_mm
    assert generated[5000.0].values["damper_N_s_per_m"] > 1.2 * generated[2500.0].values["damper_N_s_per_m"]


@pytest.mark.slow
def test_recovers_spring_and_damper(generated):
    """(a) Within the stated tolerance (module docstring), lightly damped (2500 N s/m, a damping ratio
    of about 0.20): the spring scale within 15 %, the damper within 30 % and inside its interval."""
    rp = generated[2500.0]
    s = rp.summary()
    assert rp.values["spring_scale"] == pytest.approx(0.55, rel=0.15)
    assert rp.values["damper_N_s_per_m"] == pytest.approx(2500.0, rel=0.30)
    assert s["damper_N_s_per_m_ci95"][0] <= 2500.0 <= s["damper_N_s_per_m_ci95"][1]


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the spring is read 11 % low lightly damped, 0.490 x [0.437, 0.544] for 0.55 "
                                       "(9 % heavily damped, 0.50 [0.43, 0.56], which holds it). The bike stiffens "
                                       "with stroke and the generator does not, but by little: at 0.55 x and 2500 N s/m "
                                       "they ring within 0.2 % about the slam's 14 mm rest, the bike 2.1 % faster about "
                                       "30 mm (test_generator_and_bike_along_the_stroke): a spring about 0.4-4 % apart, "
                                       "not 11 %; "
                                       "the replay's friction, read 64 N for the generator's 30 on the same model's "
                                       "slam (seed 2500), trades with the spring as in the period reading (below); "
                                       "not shown to be the whole of it")
def test_spring_interval_holds_lightly_damped(generated):
    s = generated[2500.0].summary()
    assert s["spring_scale_ci95"][0] <= 0.55 <= s["spring_scale_ci95"][1]


@pytest.mark.slow
def test_recovers_spring_heavily_damped(generated):
    """(a) The same heavily damped (5000 N s/m, a damping ratio of about 0.40): the spring scale within
    15 %, the damper within 30 %, each inside its interval (with the tyre in series in the generator;
    its one-mode form, whose frequency fell with the damper faster than the bike's, read 0.461 x)."""
    rp = generated[5000.0]
    s = rp.summary()
    assert rp.values["spring_scale"] == pytest.approx(0.55, rel=0.15)
    assert rp.values["damper_N_s_per_m"] == pytest.approx(5000.0, rel=0.30)
    assert s["spring_scale_ci95"][0] <= 0.55 <= s["spring_scale_ci95"][1]
    assert s["damper_N_s_per_m_ci95"][0] <= 5000.0 <= s["damper_N_s_per_m_ci95"][1]


def _path_noise(rest_tol_mm):
    """(the largest change of the replay's residual at one set of values when another run came between,
    the largest change one finite-difference step of the fit, 1e-3 of the friction's scale, makes), mm."""
    from mtbmj.identify.bounce_replay import NAMES, SeatedReplay, prepare_slam

    t, x = slam(scale=0.55, c=2500.0, fc=30.0)
    sl = prepare_slam(t, x, None, "generated", SeatedReplay("sst", rest_tol_mm=rest_tol_mm))
    v, f = sl.x0.copy(), NAMES.index("friction_N")
    first = sl.residual(v)
    far = v.copy()
    far[NAMES.index("spring_scale")] *= 1.2
    far[f] *= 2.0
    sl.residual(far)
    again = sl.residual(v)
    step = v.copy()
    step[f] += 1e-3 * sl.base[f]
    return float(np.max(np.abs(again - first))), float(np.max(np.abs(sl.residual(step) - again)))


TIGHT_REST_MM = 1e-7  # the rest solved to this leaves the residual a function of its values alone


def test_rest_solved_tightly_leaves_no_path_noise():
    """Issue 53, why the whole-trace replay lands differently from start to start: at the default
    ``REST_TOL_MM`` (5e-4 mm) each run solves the rest from the preload the last run left, and the same
    values replayed after a run far from them give a stroke 6.7e-4 mm apart, 29 % of what the fit's own
    finite-difference step in friction changes (more than 10 % here). With the rest solved to 1e-7 mm
    the same values give the same stroke within 1e-3 of that step (measured 1.7e-8 mm)."""
    from mtbmj.identify.bounce_replay import REST_TOL_MM

    noise, step = _path_noise(TIGHT_REST_MM)
    assert noise < 1e-3 * step
    loose, step = _path_noise(REST_TOL_MM)
    assert loose > 0.1 * step


AGREE = 0.01  # landings from starts the fit cannot tell apart agree within this share of their 95 % intervals


@pytest.fixture(scope="module")
def moved_starts():
    return landings_from_moved_starts()


def landings_from_moved_starts():
    """The replay of this file's lightly damped slam (0.55 x, 2500 N s/m, 30 N) from two starts moved
    as ``bounce_rebound.restarted`` moves them (a normal draw of its ``RESTART_STEP``, 1e-3 of each value's
    scale, seeded), with the rest solved to ``TIGHT_REST_MM`` and to the default ``REST_TOL_MM``:
    {tolerance: [summary per start]}. Two, not the three it once took: two starts that agree or land apart
    are what the tests below read (the third was two whole replays more, about 2 min on a busy machine)."""
    from mtbmj.identify.bounce_rebound import RESTART_STEP
    from mtbmj.identify.bounce_replay import NAMES, REST_TOL_MM, SeatedReplay, prepare_slam, replay

    t, x = slam(scale=0.55, c=2500.0, fc=30.0)
    out = {}
    for tol in (TIGHT_REST_MM, REST_TOL_MM):
        sr = SeatedReplay("sst", rest_tol_mm=tol)
        sl = prepare_slam(t, x, None, "generated", sr)
        rng = np.random.default_rng(0)
        out[tol] = [replay(t, x, None, name="generated", seated=sr, start=dict(zip(NAMES, map(
            float, sl.x0 + RESTART_STEP * sl.base * rng.standard_normal(sl.x0.size))))).summary() for _ in range(2)]
    return out


def _spread(summaries) -> dict:
    """Per shock value, its landings' range over the mean width of their 95 % intervals."""
    from mtbmj.identify.bounce_replay import SHOCK_NAMES

    return {k: float(np.ptp([s[k] for s in summaries]) / np.mean([np.diff(s[k + "_ci95"])[0] for s in summaries]))
            for k in SHOCK_NAMES}


@pytest.mark.slow
def test_landings_agree_with_the_rest_solved_tightly(moved_starts):
    """From two starts the fit cannot tell apart, the rest solved to 1e-7 mm, the replay lands on one
    spring, damper and friction within AGREE of their intervals (measured 3e-4 of each)."""
    got = _spread(moved_starts[TIGHT_REST_MM])
    assert all(v <= AGREE for v in got.values()), got


@pytest.mark.slow
def test_landings_spread_at_the_default_rest(moved_starts):
    """The same starts at the default ``REST_TOL_MM`` (5e-4 mm) land apart by more than AGREE of the
    intervals (measured 0.073 of the spring's, 0.100 of the damper's, 0.136 of the friction's on
    2026-12-07's machine; 0.027, 0.046 and 0.083 over three starts on another: the scatter is the path's
    rounding, which moves with the machine): the scatter ``bounce_rebound.restarted`` measures, which the
    tight rest removes."""
    from mtbmj.identify.bounce_replay import REST_TOL_MM

    got = _spread(moved_starts[REST_TOL_MM])
    assert max(got.values()) > AGREE, got


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the reproducible landing reads the generator worse than the default's: with the "
                                       "rest solved to 1e-7 mm both starts land at 0.467 x [0.384, 0.550] (15.1 % "
                                       "low), 1692 N s/m (32 % low) and 89 N of friction for 30, where the default "
                                       "(5e-4 mm) lands at 0.476-0.489 x, 1815-2054 N s/m, 41-73 N: the whole-trace "
                                       "least squares, converging further, trades the damper for friction, and the "
                                       "default's noise stops it nearer its start (2000 N s/m, 40 N): the objective's "
                                       "own minimum, its cost 45.0 with the friction held at 30 N, 31.7 at 89 N; so "
                                       "the default stays 5e-4 mm")
def test_reproducible_landing_recovers_the_generator(moved_starts):
    for s in moved_starts[TIGHT_REST_MM]:
        assert s["spring_scale"] == pytest.approx(0.55, rel=0.15)
        assert s["damper_N_s_per_m"] == pytest.approx(2500.0, rel=0.30)


def test_travel_doubled_is_refused(seated):
    """(b) The record's travel x2 leaves the shock's 65 mm stroke: refused in one line naming the file."""
    from mtbmj.identify.bounce_replay import replay

    t, x = slam()
    with pytest.raises(BounceError, match=r"doubled.*outside the bike's 65 mm stroke"):
        replay(t, 2 * x, None, name="doubled", seated=seated)


@pytest.mark.slow
def test_a_ring_down_no_spring_in_bounds_gives_is_refused(seated):
    """(b) A slam whose ring-down is too fast for the bike (the generator's spring 9 x 0.55 of the
    preset's, past the fit's bound of 3 x) cannot be followed: refused in one line, never answered."""
    from mtbmj.identify.bounce_replay import replay

    t, x = slam(scale=0.55 * 9, c=2500.0, fc=30.0, rest_mm=20.0, lift=0.0, push=4.0)
    with pytest.raises(BounceError, match=r"^fast: the replay through the bike cannot follow the record"):
        replay(t, x, None, name="fast", seated=seated)


@pytest.fixture(scope="module")
def shared_replays():
    from conftest import SHARED_DATA

    from mtbmj.identify.bounce_replay import replay_records
    from mtbmj.measured.telemetry import read_sst

    records = [read_sst(os.path.join(SHARED_DATA, "sst_v2", f)) for f in ("00083.SST", "00085.SST", "00087.SST")]
    return replay_records(records, [0, 8, 17], "sst")


@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_slams(shared_replays):
    """(c) The shared slams through the sst preset with the rider compliant at 5 Hz: the 0- and 8-click
    slams are followed (RMS under 12 % of the slam) with one spring within both intervals, about half
    the preset's 80 N/mm, the rider's body taking 5-10 % of the mode's strain energy; the 17-click
    slam, which sticks after two half cycles (friction-dominated: the decay law refuses it too), is
    refused with the reason."""
    done = {s["clicks"]: s for s in shared_replays["summary"]}
    assert "refused" in done[17] and "cannot follow" in done[17]["refused"]
    a, b = done[0], done[8]
    for s in (a, b):
        assert s["rms_mm"] < 0.12 * s["slam_rise_mm"]
        assert 0.3 < s["spring_scale"] < 0.7
        assert 0.05 < s["mode_strain_energy_share"]["rider"] < 0.10
        assert s["rest_offset_mm"] == pytest.approx(0.0, abs=0.01)
    (alo, ahi), (blo, bhi) = a["spring_scale_ci95"], b["spring_scale_ci95"]
    assert alo <= b["spring_scale"] <= ahi and blo <= a["spring_scale"] <= bhi
    # the model-free reading beside each: every record's own first rebound, the replayed ones' replay's;
    # the records slow with the clicks (their first rebounds: tests/test_bounce_rebound.py)
    assert all("record_rebound" in s for s in done.values()) and "replay_rebound" not in done[17]
    assert all("replay_rebound" in done[k] for k in (0, 8))
    assert shared_replays["check"]["records_order"] is True
    assert shared_replays["lines"][-1].startswith("replay check: the records' first rebounds slow")



@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_files_show_the_replay_beside_the_record(shared_replays):
    """replay_<file>.csv holds the record's and the replay's stroke on one time axis whose misfit is the
    stated RMS, for the replayed records only; replay.png is a PNG of one panel per replayed record."""
    from mtbmj.identify.bounce_replay import figure_png

    assert sorted(shared_replays["csv"]) == ["replay_00083.csv", "replay_00085.csv"]
    for rp in shared_replays["replays"]:
        cols = rp.csv_columns()
        assert len({len(v) for v in cols.values()}) == 1
        miss = cols["stroke_mm"] - cols["record_stroke_mm"]
        assert math.sqrt(float(np.mean(miss ** 2))) == pytest.approx(rp.rms_mm, rel=0.05)
        assert cols["time_s"][0] < -0.5 and cols["time_s"][-1] > 1.2  # from the rest before to the ring-down
    png = figure_png(shared_replays["replays"])
    assert png[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
@pytest.mark.xfail(strict=True, reason="the replay reads the damper lower at 8 clicks than at 0 (1794 [0, 6875] against "
                                       "1450 [0, 5631] N s/m on one machine, 2012 and 1364 on another: "
                                       "the values move with the machine, the order did not) while the records' own "
                                       "first rebounds slow with the clicks (mid-rebound speed 352, 291, 227 mm/s at 0, "
                                       "8, 17, model-free): the replay's slam peaks late and high (51.6 and 47.3 mm above "
                                       "rest against the records' 44.0 and 45.0; its first rebound 411 and 325 mm/s "
                                       "against 352 and 291), and the whole-trace fit spends the damper on that and on "
                                       "the rest moving 6-8 mm after the slam; fitted jointly with one spring and "
                                       "friction still lowest at 8 (2069, 1602, 2497 in an earlier run)")
def test_shared_damper_rises_with_clicks(shared_replays):
    done = {s["clicks"]: s for s in shared_replays["summary"]}
    assert done[8]["damper_N_s_per_m"] > done[0]["damper_N_s_per_m"]


def test_replay_needs_a_bike(tmp_path, capsys):
    """--replay without --bike: one line naming both, exit status 2, nothing written."""
    from mtbmj import cli

    rc = cli.main(["fit", "bounce", str(tmp_path / "a.SST"), "--clicks", "0", "--replay", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--replay" in err[0] and "--bike" in err[0]
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_pooled_replay_of_two_clicks(seated):
    """Two slams of this file's generator at two rebound settings (2500 and 3500 N s/m, one spring
    0.55 x and one friction 30 N) replayed jointly (``bounce_pooled``: one spring and one friction, a
    damper each): the spring within 15 %, each damper within 30 % and the larger read as the larger."""
    from mtbmj.identify.bounce_pooled import replay_pooled
    from mtbmj.identify.bounce_replay import SeatedReplay, prepare_slam

    slams = []
    for c in (2500.0, 3500.0):
        t, x = slam(scale=0.55, c=c, fc=30.0, seed=int(c))
        sr = seated if not slams else SeatedReplay("sst")
        slams.append(prepare_slam(t, x, None, f"generated {c:g}", sr))
    replays, refused, pooled = replay_pooled(slams)
    assert not refused and len(replays) == 2
    assert pooled["spring_scale"] == pytest.approx(0.55, rel=0.15)
    (a, b) = (rp.values["damper_N_s_per_m"] for rp in replays)
    assert a == pytest.approx(2500.0, rel=0.30) and b == pytest.approx(3500.0, rel=0.30) and b > a
    assert replays[0].values["spring_scale"] == replays[1].values["spring_scale"] == pooled["spring_scale"]


def test_push_settles_after_the_slam():
    """The pooled replay's settling force: none before the slam lobe's end, half of it SETTLE_S / 2
    after (sin^2 of pi/4 = 1/2), all of it from SETTLE_S on; without settle_N the push is the two lobes."""
    from mtbmj.identify.bounce_replay import SETTLE_S, push

    p = {"lift_N": 0.0, "lift_start_s": -0.5, "lift_s": 0.2, "slam_N": 0.0, "slam_end_s": 0.02, "slam_s": 0.1}
    t = np.array([0.0, 0.02 + SETTLE_S / 2, 0.02 + SETTLE_S, 1.0])
    assert np.allclose(push(t, {**p, "settle_N": 400.0}), [0.0, -200.0, -400.0, -400.0])
    assert np.allclose(push(t, p), 0.0)


def test_compression_set_apart_from_rebound(seated):
    """set_shock's compression coefficient (the pooled replay's shared one) reaches the shock's law
    apart from the rebound's; without it both are the damper's."""
    from mtbmj.identify.bounce_replay import SHOCK_KEYS

    seated.set_rest(12.0, None)
    seated.set_shock(0.5, 2000.0, 30.0, 900.0)
    cfg = seated.p.shock_setup.config
    assert cfg.get(SHOCK_KEYS["compression"]) == 900.0 and cfg.get(SHOCK_KEYS["rebound"]) == 2000.0
    seated.set_shock(0.5, 2000.0, 30.0)
    assert seated.p.shock_setup.config.get(SHOCK_KEYS["compression"]) == 2000.0


@pytest.fixture(scope="module")
def two_rebounds():
    """Two slams of this file's generator at two rebound settings (2500 and 5000 N s/m in extension,
    2500 in compression both; spring 0.55 x, friction 30 N), made ready for the replay on one bike."""
    from mtbmj.identify.bounce_replay import SeatedReplay, prepare_slam

    sr = SeatedReplay("sst")
    out = []
    for reb in (2500.0, 5000.0):
        t, x = slam(scale=0.55, c=2500.0, rebound=reb, fc=30.0, seed=int(reb))
        out.append(prepare_slam(t, x, None, f"rebound {reb:g}", sr))
    return out


@pytest.mark.slow
def test_rebound_damper_from_the_first_rebound(two_rebounds):
    """``bounce_rebound``: the spring (0.55 x), friction (30 N) and compression (2500 N s/m) given, each
    slam's rebound coefficient solved so the replay's first rebound has the record's middle speed per
    mm of height: within 30 % of the generator's (2500, 5000) and the larger read as the larger."""
    from mtbmj.identify.bounce_rebound import rebound_dampers, rises

    got = rebound_dampers(two_rebounds, [0, 10], 0.55, 30.0, 2500.0)
    assert [e.get("refused") for e in got] == [None, None]
    assert got[0]["rebound_N_s_per_m"] == pytest.approx(2500.0, rel=0.30)
    assert got[1]["rebound_N_s_per_m"] == pytest.approx(5000.0, rel=0.30)
    assert rises(got) is True
    assert got[0]["record_mid_rebound_per_s"] > got[1]["record_mid_rebound_per_s"]


@pytest.mark.slow
def test_rebound_no_coefficient_gives_is_refused(two_rebounds):
    """With a spring far too soft given (0.2 x for the generator's 0.55) the bike rebounds slower than
    the record even undamped: refused for that record with the reason, no value."""
    from mtbmj.identify.bounce_rebound import rebound_dampers, rises

    got = rebound_dampers(two_rebounds[:1], [0], 0.2, 30.0, 2500.0)
    assert "rebound_N_s_per_m" not in got[0]
    assert "slower than the record even undamped" in got[0]["refused"]
    assert rises(got) is None


@pytest.fixture(scope="module")
def shared_first_rebounds(shared_replays):
    """The shared slams' slams and first rebounds read once, as ``fit bounce --replay`` reads them: fitted
    together (``bounce_slam_rebound.read_records``, "slam_rebound", the spring from their ring-down period,
    then the ring-down fit, "ring_fit"), then each record's rebound damper (``bounce_rebound.read_records``,
    "rebound_dampers") with the ring-down fit's spring, friction and compression where it is read (on these
    slams it is refused: the best whole-trace replay's)."""
    from conftest import SHARED_DATA

    from mtbmj.identify import bounce_rebound, bounce_slam_rebound
    from mtbmj.measured.telemetry import read_sst

    records = [read_sst(os.path.join(SHARED_DATA, "sst_v2", f)) for f in ("00083.SST", "00085.SST", "00087.SST")]
    pooled = bounce_slam_rebound.read_records(records, [0, 8, 17], shared_replays["summary"], "sst")
    dampers = bounce_rebound.read_records(records, [0, 8, 17], shared_replays["summary"], "sst",
                                          ring=pooled["ring_fit"])
    return {"slam_rebound": pooled, "rebound_dampers": dampers}


@pytest.fixture(scope="module")
def shared_rebound(shared_first_rebounds):
    return shared_first_rebounds["rebound_dampers"]


@pytest.fixture(scope="module")
def shared_slam_rebound(shared_first_rebounds):
    return shared_first_rebounds["slam_rebound"]


@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_rebound_dampers_rise_with_clicks(shared_rebound):
    """The shared slams' rebound coefficients read from their first rebounds (``bounce_rebound``, the
    spring, friction and compression of the best-determined whole-trace replay, as ``fit bounce`` reads them:
    the ring-down fit is refused on these slams, the bike not following their free ring-downs after the
    top-out, and the ring-down period's spring, 0.46 x, refuses the 0-click slam, docs/identification.md): all three read (the
    17-click slam too, which the whole-trace replay refuses) and rising with the clicks, as the
    records' own rebounds slow; at the spring interval's upper end they rise too. The 0- and 8-click
    intervals open below (the 0-click one at the friction's and compression's together axis' upper end,
    the 8-click one at the spring interval's lower end, read at 0.20 x, where no coefficient gives its
    rate); the 17-click one closed below at the spring's lower end, where its replay's first rebound has no
    middle at 30000 N s/m and ``solve_on`` reads it below that stall (measured: 1778 N s/m, at_spring
    1778.2, its noise and the friction's and compression's ends all above 5337: before the mend it was
    refused as "faster" there and the interval open below, issue 53), the law's slope above 0, each record held out (within its 2 sd, the sd carrying the replay's
    friction, compression and spring: the next test), and the answer for 7 /s holding the clicks where the records' own rates reach it."""
    got = shared_rebound
    assert got["spring_from"].startswith("the whole-trace replay of")
    assert "the ring-down fit refused: the bike does not follow the records' free ring-downs" in got["spring_from"]
    assert [e["clicks"] for e in got["records"]] == [0, 8, 17]
    assert all("rebound_N_s_per_m" in e for e in got["records"]) and got["rises"] is True
    upper = [e["at_spring_ci95"][1] for e in got["records"]]
    assert None not in upper and upper[0] < upper[1] < upper[2]
    assert got["line"].endswith("they rise with the clicks")
    # the intervals (bounce_rebound.combine): 0 and 8 clicks open below, said so; 17 clicks closed below at
    # its reading at the spring's lower end (the other parts move it little below); the noise interval
    # holds the value
    for e in got["records"]:
        lo, hi = e["rebound_N_s_per_m_ci95"]
        if e["clicks"] == 17:
            spring_lo = e["at_spring_ci95"][0]
            assert spring_lo is not None and not any(w.startswith("open below") for w in e["interval_open"])
            assert 1000.0 < lo <= spring_lo < e["rebound_N_s_per_m"] and lo == pytest.approx(spring_lo, rel=0.02)
        else:
            assert lo is None and e["interval_open"][0].startswith("open below")
        if e["clicks"] == 8:
            assert e["at_spring_ci95"][0] is None and "the spring interval's lower end" in e["interval_open"][0]
        if e["clicks"] == 0:  # at the friction's and compression's joint upper end (together) it reads none
            assert hi is None and "friction_compression_together interval" in e["interval_open"][1]
        else:
            assert hi >= e["at_spring_ci95"][1]
        n_lo, n_hi = e["rebound_noise_ci95"]
        assert n_lo < e["rebound_N_s_per_m"] < n_hi
    # the law in clicks, each record held out (issue 53: within its own 2 sd), and an answer for 7 /s
    # whose range holds the records' own rates joined in clicks (model-free)
    from mtbmj.identify.bounce_rebound import law_in_clicks

    assert got["law"]["slope_ci95"][0] > 0
    assert len(got["held_out"]) == 3
    ans = law_in_clicks(got["records"], 7.0)["answer"]
    assert ans["set_clicks"] is not None and ans["records_clicks"] is not None
    assert ans["clicks_range95"][0] <= ans["records_clicks"] <= ans["clicks_range95"][1]


@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_rebound_dampers_each_held_out_within_2_sd(shared_rebound):
    """Issue 53: each shared slam held out (the law on the other two) within 2 combined sd, the sd
    carrying the values given (``bounce_rebound.at_nuisance_ends``, ``at_spring_ends``: every record
    read again at the ends of the two axes of the friction's and compression's joint 95 % interval, their
    correlation -0.92 from the replay's Jacobian, and of the spring's; at the spring's lower end only the
    17-click record reads (1778 N s/m), so no law and no residual there, the 0-click record none at the
    together axis' upper end). Measured (00083's replay given, 0.494 x,
    46 N, 1764 N s/m): +0.4, -0.3, +0.4 sd, the values' part 0.205, 0.107, 0.216 /s (each value's own ends,
    before: +0.4, -0.4, +0.4 sd, 0.199, 0.101, 0.197); with 00085's tight-rest landing (0.465 x,
    23 N, 1418 N s/m) +0.5, -0.8, +0.9. With the record's noise and the law alone the same reading misses
    (+3.6, -3.5, +3.5 sd; +8.8, -12.9, +12.9 at the other landing): the residual is the law's bend, which the values given,
    barely determined by the whole-trace replay, move through zero (at the compression's upper end and
    the spring's its sign turns), so the check holds because it cannot tell the law's bend from theirs,
    and says so by its sd. No restarts (``RESTARTS`` 0): the readings' rest is solved tightly."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    got = shared_rebound
    assert got["restarts"] == []
    assert len(got["held_out"]) == 3
    for r in got["held_out"]:
        ends = r["nuisance_residuals_per_s"]
        assert None not in ends["friction_compression_traded"] and ends["friction_compression_together"][0] is not None
        assert ends["spring_scale"][1] is not None
        assert r["nuisance_sd_per_s"] > 3 * math.hypot(r["predicted_rate_sd_per_s"], r["record_rate_sd_per_s"])
    assert all(r["holds"] for r in got["held_out"]), [round(r["z"], 2) for r in got["held_out"]]
    assert got["friction_compression_correlation"] < -0.5  # they trade
    assert "friction and compression (jointly) and spring given at their 95 % ends" in got["lines"][1]
    naive = held_out(got["records"])
    assert not all(r["holds"] for r in naive), [round(r["z"], 2) for r in naive]


# (e) the slams and first rebounds fitted together (``bounce_slam_rebound``)
def test_slam_rebound_window_ends_where_the_record_first_returns_to_rest():
    """The fitted window's end on a made rebound, x = 40 exp(-2 t) cos(2 pi 1.5 t) mm after the peak at t = 0:
    the first grid time at or below the rest, within one 5 ms step after the closed form's zero, 1 / (4 x
    1.5) s; the whole cycle's end is the next peak, 1 / 1.5 s; a record that never returns is refused."""
    from types import SimpleNamespace

    from mtbmj.identify.bounce_slam_rebound import window_end

    g = np.arange(-0.6, 1.3, 0.005)
    x = np.where(g < 0, 40.0 * np.exp(-((g / 0.08) ** 2)), 40.0 * np.exp(-2.0 * g) * np.cos(2 * math.pi * 1.5 * g))
    sl = SimpleNamespace(grid=g, rec_g=x, name="made")
    end = window_end(sl)
    assert 1 / 6 <= end < 1 / 6 + 0.005 + 1e-9
    # the whole cycle: the peak of exp(-2 t) cos(w t) is where tan(w t) = -2 / w, after one period
    w = 2 * math.pi * 1.5
    peak2 = (2 * math.pi + math.atan(-2.0 / w)) / w
    assert window_end(sl, cycle=True) == pytest.approx(peak2, abs=0.005)
    with pytest.raises(BounceError, match="never reaches the rest"):
        window_end(SimpleNamespace(grid=g, rec_g=np.abs(x) + 1.0, name="stays"))


def test_slam_rebound_verdict_needs_the_order_and_intervals_clear_of_0():
    """``rises``: rising values with every interval above 0 is True; the same values with the clicks
    swapped, or with one interval down to 0, is False; one record read is None."""
    from mtbmj.identify.bounce_slam_rebound import rises

    recs = [{"clicks": 0, "rebound_N_s_per_m": 1000.0, "rebound_N_s_per_m_ci95": [400.0, 1600.0]},
            {"clicks": 8, "rebound_N_s_per_m": 3000.0, "rebound_N_s_per_m_ci95": [2000.0, 4000.0]}]
    assert rises(recs) is True
    assert rises(recs[::-1]) is False
    assert rises([recs[0] | {"rebound_N_s_per_m_ci95": [0.0, 1600.0]}, recs[1]]) is False
    assert rises(recs[:1]) is None


@pytest.fixture(scope="module")
def slam_rebound_generated():
    """The two slams of ``two_rebounds`` (the same seeds: rebound 2500 and 5000 N s/m, compression 2500,
    spring 0.55 x, friction 30 N), each on a bike of its own, fitted together with the friction given."""
    from mtbmj.identify.bounce_replay import SeatedReplay, prepare_slam
    from mtbmj.identify.bounce_slam_rebound import fit

    slams = []
    for reb in (2500.0, 5000.0):
        t, x = slam(scale=0.55, c=2500.0, rebound=reb, fc=30.0, seed=int(reb))
        slams.append(prepare_slam(t, x, None, f"rebound {reb:g}", SeatedReplay("sst")))
    return fit(slams, [0, 10], 30.0)


@pytest.mark.slow
def test_slam_rebound_recovers_the_generators_rebound(slam_rebound_generated):
    """(e) ``bounce_slam_rebound`` on the generator's two rebound settings, the spring and compression
    fitted (shared), the friction given: each rebound coefficient within 30 % of the generator's and
    inside its interval, the larger read as the larger, and the replay's peak within 1 mm and 10 ms of
    the record's (the spring's and compression's intervals hold 0.55 x and 2500 N s/m)."""
    got = slam_rebound_generated
    (a, b) = got["records"]
    for e, truth in ((a, 2500.0), (b, 5000.0)):
        assert "refused" not in e
        assert e["rebound_N_s_per_m"] == pytest.approx(truth, rel=0.30)
        lo, hi = e["rebound_N_s_per_m_ci95"]
        assert lo <= truth <= hi
        assert abs(e["replay_peak"]["above_rest_mm"] - e["record_peak"]["above_rest_mm"]) < 1.0
        assert abs(e["replay_peak"]["time_s"] - e["record_peak"]["time_s"]) <= 0.010 + 1e-9
    assert b["rebound_N_s_per_m"] > a["rebound_N_s_per_m"]
    assert got["spring_scale_ci95"][0] <= 0.55 <= got["spring_scale_ci95"][1]
    assert got["compression_N_s_per_m_ci95"][0] <= 2500.0 <= got["compression_N_s_per_m_ci95"][1]


@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_slam_rebound_meets_the_peak(shared_slam_rebound):
    """(e) The shared slams fitted together on each slam and first rebound: every record followed (the 17-click
    one too, which the whole-trace replay refuses) within 2 % of its rise, the replay's peak within 1.5 mm and
    15 ms of the record's (the whole-trace replay's: 7.6 mm high at 0 clicks, 30 ms late at 8), and the rebound
    coefficients in the clicks' order."""
    got = shared_slam_rebound
    recs = got["records"]
    assert [e["clicks"] for e in recs] == [0, 8, 17] and not any("refused" in e for e in recs)
    for e in recs:
        assert e["rms_mm"] < 0.02 * e["slam_rise_mm"]
        assert abs(e["replay_peak"]["above_rest_mm"] - e["record_peak"]["above_rest_mm"]) < 1.5
        assert abs(e["replay_peak"]["time_s"] - e["record_peak"]["time_s"]) <= 0.015 + 1e-9
    reb = [e["rebound_N_s_per_m"] for e in recs]
    assert reb[0] < reb[1] < reb[2]


@pytest.mark.slow
@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
@pytest.mark.xfail(strict=True, reason="the spring read from the ring-down's period, 0.46 x [0.33, 0.64] (6 of 7 free "
                                       "half periods: the 17-click slam's one, which no simulation has, left out), held "
                                       "in the slam-and-first-rebound fit and its interval carried: the rebound "
                                       "coefficients 1794 [0, 4938], 4418 [953, 7883], 6754 [4051, 9456] N s/m at 0, 8, "
                                       "17 clicks rise, the 8- and 17-click intervals clear of 0, the 0-click one not "
                                       "(0.47 x from 7 halves, before they were matched by turning point: 1907, 4504, "
                                       "6859) (conditional on the spring alone it already reaches 0 at 0.45 x: "
                                       "[0, 4744]); fitted on the window alone the spring was 0.73 x [0.00, 1.95] and "
                                       "every interval reached 0")
def test_shared_slam_rebound_rises_clear_of_0(shared_slam_rebound):
    assert shared_slam_rebound["rises"] is True


@pytest.mark.slow
def test_slam_rebound_with_the_spring_given_clears_0():
    """(e) The same two slams with the spring held at the generator's 0.55 x: each rebound coefficient
    within 20 %, its interval holding the truth and clear of 0 (given the spring, the window identifies
    the rebound; freed, the spring trades with it and every interval reaches 0)."""
    from mtbmj.identify.bounce_replay import SeatedReplay, prepare_slam
    from mtbmj.identify.bounce_slam_rebound import fit

    slams = []
    for reb in (2500.0, 5000.0):
        t, x = slam(scale=0.55, c=2500.0, rebound=reb, fc=30.0, seed=int(reb))
        slams.append(prepare_slam(t, x, None, f"rebound {reb:g}", SeatedReplay("sst")))
    got = fit(slams, [0, 10], 30.0, held={"spring_scale": 0.55})
    for e, truth in zip(got["records"], (2500.0, 5000.0)):
        lo, hi = e["rebound_N_s_per_m_ci95"]
        assert e["rebound_N_s_per_m"] == pytest.approx(truth, rel=0.20)
        assert 0.0 < lo <= truth <= hi
    assert got["rises"] is True and got["spring_scale_ci95"] == [0.55, 0.55]


@pytest.fixture(scope="module")
def ring_generated():
    """The two generator slams of ``slam_rebound_generated`` (spring 0.55 x), each replayed whole
    (``bounce_replay.replay``: the push, damper and friction the ring-down is simulated with), ready for
    ``spring_from_periods``: (rings, the same with the records' time stretched by 10 %, the replays'
    summaries as ``replay_records`` gives them)."""
    from mtbmj.identify.bounce_replay import SeatedReplay, prepare_slam, replay

    rings, slow, summary = [], [], []
    for reb in (2500.0, 5000.0):
        t, x = slam(scale=0.55, c=2500.0, rebound=reb, fc=30.0, seed=int(reb))
        sr = SeatedReplay("sst")
        rp = replay(t, x, None, name=f"rebound {reb:g}", seated=sr)
        sl = prepare_slam(t, x, None, f"rebound {reb:g}", sr, start=dict(rp.values))
        rings.append((sl.name, t, x, sl, dict(rp.values)))
        slow.append((sl.name, 1.1 * t, x, sl, dict(rp.values)))
        summary.append({**{k: float(v) for k, v in rp.values.items()}, **rp.summary(), "file": sl.name})
    return rings, slow, summary


@pytest.mark.slow
def test_spring_from_the_ring_downs_period_holds_the_generators(ring_generated):
    """(e) The spring read from the generator's free half periods through the MuJoCo bike: its interval holds
    the generator's 0.55 x (measured: 0.47 x [0.36, 0.60], 15 % low, from three free half periods); the same
    records with their time stretched 10 % (every period 10 % longer: a spring about 0.83 x as stiff) read
    below that interval (measured 0.33 x; its own interval, from three halves at Student's t for 2 degrees of
    freedom, is too wide to exclude 0.55 x)."""
    from mtbmj.identify.bounce_slam_rebound import spring_from_periods

    rings, slow, _ = ring_generated
    got = spring_from_periods(rings)
    lo, hi = got["spring_scale_ci95"]
    assert lo <= 0.55 <= hi and 0.0 < lo
    assert got["spring_scale"] == pytest.approx(0.55, rel=0.20)
    wrong = spring_from_periods(slow)
    assert "refused" in wrong or wrong["spring_scale"] < lo


@pytest.fixture(scope="module")
def ring_fit_generated(ring_generated):
    """The generator's two slams read as ``fit bounce --replay`` reads them (``bounce_slam_rebound.read_records``
    on its whole-trace replays: the period's spring, the slam-and-first-rebound fit held at it, then the
    ring-down fit, ``"ring_fit"``)."""
    from types import SimpleNamespace

    from mtbmj.identify import bounce_slam_rebound as bsr

    rings, _, summary = ring_generated
    records = [SimpleNamespace(name=name, time_s=t, shock_mm=x, fork_mm=None) for name, t, x, *_ in rings]
    return bsr.read_records(records, [0, 10], summary, "sst")


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the spring from the generator's ring-down periods alone reads 0.47 x [0.36, 0.60] "
                                       "for 0.55 x: 15 % low (within 10 % is the target). Not the bike's stiffening "
                                       "(at 0.55 x the bike's free halves are 0.5-0.8 % shorter than the generator's "
                                       "with the generator's own damper, friction 0: a 2 % spring). The reading runs "
                                       "the bike with the whole-trace replays' friction (64 and 0 N for 30) and one "
                                       "damper both ways (1888 and 3742 N s/m for 2500 both ways and 2500 / 5000); "
                                       "with the generator's friction given instead it reads 0.52 [0.49, 0.56], with "
                                       "its damper and friction 0.52 [0.46, 0.58]: the halves of a 2-3 half ring-down "
                                       "move about 0.3 x the log spring, so a 5 % period shift from borrowed friction "
                                       "and damping is a 15 % spring. The ring-down fit (bounce_ring, the next test), "
                                       "with a friction and dampers of its own, meets it")
def test_spring_from_the_periods_alone_within_10_percent(ring_generated):
    from mtbmj.identify.bounce_slam_rebound import spring_from_periods

    assert spring_from_periods(ring_generated[0])["spring_scale"] == pytest.approx(0.55, rel=0.10)


@pytest.mark.slow
def test_spring_from_the_ring_downs_period_within_10_percent(ring_fit_generated):
    """(e) The ring-down fit (``bounce_ring.from_slam_rebound``: the free half periods and swing ratios, the spring,
    friction and a scale on the slam-and-first-rebound fit's dampers fitted together) on the generator's two slams
    reads its spring within 10 % (measured 0.52 x [0.49, 0.56] for 0.55, both chosen by AICc; before the
    smooth residual and the model choice 0.54 x [0.52, 0.57]; the periods alone with the borrowed friction and
    damper 0.47 x), its interval holding it, a friction clear of 0 (measured 36 N [15, 56] for the generator's
    30; before, 23 N [15, 32]) and the dampers it gives within 20 % of the generator's (measured compression
    2448 for 2500, rebound 2008 and 4132 for 2500 and 5000: the slam-and-first-rebound fit's 2360, 1936 and
    3984 at the period's spring, scaled 1.04; before, scaled 1.16: 2740, 2250 and 4620)."""
    got = ring_fit_generated["ring_fit"]
    assert "refused" not in got
    assert got["spring_scale"] == pytest.approx(0.55, rel=0.10)
    lo, hi = got["spring_scale_ci95"]
    assert lo <= 0.55 <= hi
    assert got["friction_N_ci95"][0] > 0.0
    assert got["compression_N_s_per_m"] == pytest.approx(2500.0, rel=0.20)
    reb = got["rebound_N_s_per_m"]
    assert reb["rebound 2500"] == pytest.approx(2500.0, rel=0.20)
    assert reb["rebound 5000"] == pytest.approx(5000.0, rel=0.20)


@functools.lru_cache(maxsize=None)
def _ring_alone(c, fc):
    """A slam of this file's generator (spring 0.55 x, damper ``c`` both ways, friction ``fc``; resting at 30 mm
    and pushed lightly so its ring-down stays clear of the top-out: seven free turning points or more), its push
    fitted up to the peak on the bike (spring 0.55 x, 1000 N s/m both ways), then the ring-down fit with 1000 N
    s/m both ways given and scaled (cached: two tests read each)."""
    from mtbmj.identify import bounce_ring
    from mtbmj.identify.bounce_replay import NAMES, PUSH_NAMES, SeatedReplay, fit_push, prepare_slam

    t, x = slam(scale=0.55, c=c, fc=fc, push=0.3, lift=0.3, rest_mm=30.0, seed=7, after=3.0)
    start = {"lift_N": 400.0, "lift_start_s": -0.6, "lift_s": 0.25, "slam_N": 400.0, "slam_end_s": -0.08,
             "slam_s": 0.2, "spring_scale": 0.55, "damper_N_s_per_m": 1000.0, "friction_N": 30.0}
    sl = prepare_slam(t, x, None, "made", SeatedReplay("sst"), start=start)
    u = np.zeros(sl.x0.size)
    fit_push(sl, u, extra={"compression_N_s_per_m": 1000.0})
    push = dict(zip(NAMES, sl.x0 + u * sl.base))
    given = {"compression_N_s_per_m": 1000.0, "rebound_N_s_per_m": 1000.0}
    return bounce_ring.fit([("made", t, x, sl, {k: push[k] for k in PUSH_NAMES}, given)],
                           fitted=("spring_scale", "friction_N", "damper_scale"))


@pytest.mark.slow
def test_ring_fit_reads_a_viscous_ring_down_without_friction():
    """(e) Wrong input told apart: the generator with viscous damping only (1000 N s/m both ways, no friction)
    reads a friction whose interval holds 0 and under 10 N (measured 2 N [0, 13]; before the residual moved
    smoothly where the simulation sticks sooner, 5 N [0, 20]), and the criterion chooses viscous only
    (measured AICc viscous 33.4, friction 54.8, both 37.1; the friction-only model refused at 4.7 sd)."""
    got = _ring_alone(1000.0, 0.0)
    assert got["friction_N_ci95"][0] == 0.0 and got["friction_N"] < 10.0
    assert got["model"] == "viscous"


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the generator with viscous damping only (1000 N s/m both ways) reads the dampers "
                                       "1.26 x 1000 N s/m [1.03, 1.53] (the viscous-only model 1.29 x [1.01, 1.66]; "
                                       "spring 0.53 x [0.50, 0.57], 2.3 sd RMS): the bike with the generator's damper "
                                       "decays slower than the generator. Before the residual moved smoothly where the "
                                       "simulation sticks sooner it read 1.21 x [0.74, 1.98], holding 1000 N s/m by "
                                       "its width, not its value")
def test_ring_fit_reads_a_viscous_ring_downs_damper():
    lo, hi = _ring_alone(1000.0, 0.0)["damper_scale_ci95"]
    assert lo <= 1.0 <= hi


@pytest.mark.slow
def test_ring_fit_reads_a_friction_ring_down_without_damping():
    """(e) The generator with friction only (80 N, 100 N s/m both ways): the criterion chooses friction only
    (measured AICc viscous 42.8, friction 20.7, both 23.3), whose friction is within 20 % of 80 N (measured 85 N
    [73, 96], spring 0.49 x [0.46, 0.52], 1.7 sd RMS), and the fit with both free puts the dampers' interval
    below 300 N s/m from its low end (measured 0.19 x 1000 [0.05, 0.73], its friction 62 N [33, 91]). Before
    the residual moved smoothly where the simulation sticks sooner and the models were compared, a strict
    xfail: both free read 53 N [0, 113] and 0.37 x [0.06, 2.38] at 2.6 sd."""
    got = _ring_alone(100.0, 80.0)
    assert got["model"] == "friction"
    assert got["models"]["friction"]["friction_N"] == pytest.approx(80.0, rel=0.2)
    assert got["damper_scale_ci95"][0] * 1000.0 < 300.0


def test_a_replay_that_diverges_writes_no_mujoco_log(seated, tmp_path, monkeypatch):
    """A trial push far past the model's envelope makes MuJoCo warn (a value not finite, the state
    reset); the replay is refused naming the cause (it was returned as a replay) and the warning is
    routed away from MUJOCO_LOG.TXT in the working directory (it was written there: a file of the
    user's touched, found when a slow replay test's log landed beside another test)."""
    from mtbmj.identify.bounce import BounceError
    from mtbmj.identify.bounce_replay import NAMES

    monkeypatch.chdir(tmp_path)
    seated.set_rest(12.0, None)
    p = dict.fromkeys(NAMES, 0.1)
    p.update(lift_N=0.0, slam_N=1e12, spring_scale=0.5, damper_N_s_per_m=2000.0, friction_N=30.0)
    with pytest.raises(BounceError, match=r"^replay: the simulated bike diverged \(.*MuJoCo BAD"):
        seated.run(p)  # refused: MuJoCo reset the state, so the values stayed finite (it "ran" to 189.7 mm)
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    p.update(slam_N=1500.0)  # the same bike slammed as a person slams still replays
    assert np.all(np.isfinite(seated.run(p)["stroke_mm"]))

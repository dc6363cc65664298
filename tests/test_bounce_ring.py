"""The ring-down's turning points and residuals the spring, friction and dampers are read from
(``mtbmj.identify.bounce_ring``; the fit through the MuJoCo bike is checked on the independent slams of
``tests/test_bounce_replay.py``).

(a) Ring-downs made here by a model of this file's own: one mass on a spring with a linear damper and
Coulomb friction (a stick condition), released from a slam's height above rest, stepped by
semi-implicit Euler at 20 us and sampled at 5 kHz. Viscous damping alone keeps a constant share of the
swing each half cycle (exp(-pi zeta / sqrt(1 - zeta^2)), Den Hartog); friction alone takes a constant
4 F / k off it (Feeny and Liang, J. Sound Vib. 195(1), 1996). ``turning_points`` gives those back, so
the swing ratios ``residuals`` compares carry the difference between the two.
(b) ``residuals`` on turning points written here: zero on the record itself, log(1.05) / sd for half
periods 5 % longer, as many entries when the simulation sticks a half cycle sooner (its swing then 0).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mtbmj.identify.bounce_ring import PERIOD_SD, RATIO_SD, residuals, turning_points

FS = 5000.0
M_KG, K_N_PER_M = 100.0, 9000.0  # 1.51 Hz


def ring_down(c=0.0, fc=0.0, drop_mm=40.0, rest_mm=60.0, quiet=1.0, after=3.0, dt=2e-5, noise=0.02, seed=5):
    """(time_s, x_mm, peak index): at rest, a quick rise (0.1 s, sin^2) to ``drop_mm`` above rest, then free
    from rest there: m x'' = -k x - c x' - friction (friction up to ``fc`` holding it when still)."""
    n_quiet = int(round(quiet * FS))
    t_rise = np.arange(int(round(0.1 * FS))) / FS
    rise = drop_mm * np.sin(0.5 * np.pi * t_rise / 0.1) ** 2
    x, v = drop_mm * 1e-3, 0.0
    out = []
    every = int(round(1 / (FS * dt)))
    for i in range(int(round(after / dt))):
        if i % every == 0:
            out.append(x)
        f = -K_N_PER_M * x - c * v
        if abs(v) < 1e-5 and abs(f) <= fc:
            v = 0.0
            continue
        f -= fc * math.copysign(1.0, v if abs(v) >= 1e-5 else f)
        v += f / M_KG * dt
        x += v * dt
    xs = np.concatenate((np.zeros(n_quiet), rise, 1e3 * np.array(out))) + rest_mm
    xs += noise * np.random.default_rng(seed).standard_normal(xs.size)
    return np.arange(xs.size) / FS, xs, n_quiet + rise.size


def _swings(tp):
    lv = [q[1] for q in tp]
    return np.abs(np.diff(lv))


def test_viscous_ring_down_keeps_a_share_of_each_swing():
    """(a) Viscous only (zeta 0.12): the half cycles' swing ratios within 0.01 of the closed form's
    exp(-pi zeta / sqrt(1 - zeta^2)), and the half periods within 1 % of pi / wd."""
    zeta = 0.12
    c = 2 * zeta * math.sqrt(K_N_PER_M * M_KG)
    t, x, peak = ring_down(c=c)
    tp = turning_points(t, x, peak)
    assert [q[0] for q in tp][:4] == [0, 1, 2, 3]
    sw = _swings(tp)
    ratios = sw[1:5] / sw[:4]
    share = math.exp(-math.pi * zeta / math.sqrt(1 - zeta ** 2))
    assert np.all(np.abs(ratios - share) < 0.01)
    wd = math.sqrt(K_N_PER_M / M_KG) * math.sqrt(1 - zeta ** 2)
    halves = np.diff([q[2] for q in tp[1:5]])
    assert np.all(np.abs(halves / (math.pi / wd) - 1.0) < 0.01)


def test_friction_ring_down_loses_a_constant_swing():
    """(a) Friction only (40 N): each half cycle's swing 4 F / k (17.8 mm) less than the one before, within
    0.3 mm (to where it sticks), so its swing ratios fall half by half where the viscous one's stay: the
    last more than 0.1 below the first, which no one constant ratio (a viscous reading) gives."""
    fc = 40.0
    t, x, peak = ring_down(fc=fc)
    tp = turning_points(t, x, peak)
    sw = _swings(tp)
    loss = 4 * fc / K_N_PER_M * 1e3
    assert sw.size >= 4 and np.all(np.abs(-np.diff(sw) - loss) < 0.3)
    ratios = sw[1:] / sw[:-1]
    assert np.all(np.diff(ratios) < 0.0) and ratios[-1] < ratios[0] - 0.1


def test_residuals_zero_on_the_record_and_its_period_shift():
    """(b) The record against itself: every residual 0; against itself with every time 5 % later from the
    peak: the periods log(1.05) / PERIOD_SD, the swing ratios 0."""
    rec = [(0, 50.0, 0.0), (1, 5.0, 0.33), (2, 30.0, 0.66), (3, 10.0, 0.99), (4, 20.0, 1.32)]
    r, n = residuals(rec, rec)
    assert n == {"periods": 3, "ratios": 3, "missing": 0} and np.all(r == 0.0)
    slow = [(k, lv, 1.05 * ti) for k, lv, ti in rec]
    r, n = residuals(rec, slow)
    assert r[:3] == pytest.approx([math.log(1.05) / PERIOD_SD] * 3)
    assert r[3:] == pytest.approx([0.0] * 3, abs=1e-12)


def test_residuals_keep_their_number_when_the_simulation_sticks_sooner():
    """(b) A simulation that stops at turning point 3 (stuck) against a record with two more: as many
    residuals as the record gives, the missing half periods 0, the swing ratios it lacks read as 0 swing
    (the record's ratio over RATIO_SD below 0), and the missing counted."""
    rec = [(0, 50.0, 0.0), (2, 30.0, 0.66), (3, 10.0, 0.99), (4, 20.0, 1.32), (5, 14.0, float("nan"))]
    sim = [(0, 50.0, 0.0), (2, 30.0, 0.66), (3, 10.0, 0.99)]
    r_full, n_full = residuals(rec, rec)
    r, n = residuals(rec, sim)
    assert r.size == r_full.size and n["missing"] == 3
    assert r[n["periods"] - 1] == 0.0
    assert r[-1] == pytest.approx(-(6.0 / 10.0) / RATIO_SD)


# (c) the fit itself (``bounce_ring.fit``) with the bike replaced by a closed form written here: one mass on a
# spring (80 N/mm x the spring scale, 529 kg: 1.45 Hz at 0.55 x), a damper (1000 N s/m x the damper scale) and Coulomb friction F,
# its turning points half a damped period apart, each about the centre the friction shifts to, sign(a) F / k:
# a' - e = -r (a - e), r = exp(-pi zeta / sqrt(1 - zeta^2)), stuck where |a'| <= F / k (Den Hartog).
K0, C0, M0 = 80000.0, 1000.0, 529.0


def closed_points(scale, friction, damper, start_mm=40.0, rest=20.0, time_noise=0.0, level_noise=0.0, seed=0):
    k, m = K0 * scale, M0
    c = C0 * damper
    zeta = c / (2.0 * math.sqrt(k * m))
    wd = math.sqrt(k / m) * math.sqrt(1.0 - zeta ** 2)
    r = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta ** 2))
    band = 1e3 * friction / k
    rng = np.random.default_rng(seed)
    a, out = start_mm, [(0, rest + start_mm, 0.0)]
    for j in range(1, 12):
        e = math.copysign(band, a)
        a = e - r * (a - e)
        stuck = abs(a) <= band
        t = float("nan") if stuck else j * math.pi / wd + time_noise * rng.standard_normal()
        out.append((j, rest + a + level_noise * rng.standard_normal(), t))
        if stuck:
            break
    return out


@pytest.fixture()
def closed_form_bike(monkeypatch):
    """``bounce_ring``'s record and simulation replaced by the closed form: each ring's "record" its turning
    points given, the simulation's those of the closed form at the values tried."""
    from mtbmj.identify import bounce_ring

    monkeypatch.setattr(bounce_ring, "_record_points", lambda ring: ring[3])
    monkeypatch.setattr(bounce_ring, "_run", lambda ring, v: closed_points(v["spring_scale"], v["friction_N"],
                                                                            v.get("damper_scale", 1.0)))
    return bounce_ring


def test_fit_recovers_spring_friction_and_damper(closed_form_bike):
    """(c) A record of the closed form at 0.55 x, 30 N and the damper's scale 1 (vertex times within 0.5 ms,
    levels within 0.05 mm): the fit from 0.5 x, 30 N, 1 gives the spring within 2 %, the friction within 5 N,
    the damper's scale within 10 %, each interval holding it, not refused."""
    rec = closed_points(0.55, 30.0, 1.0, time_noise=5e-4, level_noise=0.05, seed=1)
    got = closed_form_bike.fit([("made", None, None, rec)], fitted=("spring_scale", "friction_N", "damper_scale"))
    assert "refused" not in got
    assert got["spring_scale"] == pytest.approx(0.55, rel=0.02)
    assert got["friction_N"] == pytest.approx(30.0, abs=5.0)
    assert got["damper_scale"] == pytest.approx(1.0, rel=0.10)
    for k, truth in (("spring_scale", 0.55), ("friction_N", 30.0), ("damper_scale", 1.0)):
        lo, hi = got[k + "_ci95"]
        assert lo <= truth <= hi


def test_fit_reads_a_viscous_ring_down_without_friction(closed_form_bike):
    """(c) Wrong input told apart: viscous only (0 N, the damper's scale 1) reads a friction under 3 N, its interval
    from below 1 N (measured 1 [0, 1]), the spring and the damper within 2 %; a dry ring-down (150 N, the
    damper's scale 0.05) read with the friction held at 0 (the viscous reading) cannot be followed: refused."""
    visc = closed_points(0.55, 0.0, 1.0, time_noise=5e-4, level_noise=0.05, seed=2)
    got = closed_form_bike.fit([("made", None, None, visc)], fitted=("spring_scale", "friction_N", "damper_scale"))
    assert "refused" not in got
    assert got["friction_N"] < 3.0 and got["friction_N_ci95"][0] < 1.0
    assert got["spring_scale"] == pytest.approx(0.55, rel=0.02) and got["damper_scale"] == pytest.approx(1.0, rel=0.02)
    dry = closed_points(0.55, 150.0, 0.05, time_noise=5e-4, level_noise=0.05, seed=3)
    held = closed_form_bike.fit([("made", None, None, dry)], fitted=("spring_scale", "damper_scale"),
                                held={"friction_N": 0.0})
    assert "refused" in held and "does not follow" in held["refused"]


@pytest.mark.xfail(strict=True, reason="a dry ring-down of the closed form (150 N, the damper's scale 0.05: 50 N s/m; 4 "
                                       "half periods and 5 swing ratios before it sticks) is refused at 3.1 sd RMS, "
                                       "spring 0.58 x, where the truth's residual is 0.2 sd: where the simulation sticks "
                                       "a half cycle sooner or later the residual jumps, and least squares from the "
                                       "best of the start grid (0.3-0.9 x, 1-240 N, 0.25-2 x) stays in a local minimum")
def test_fit_reads_a_dry_ring_down_without_damping(closed_form_bike):
    dry = closed_points(0.55, 150.0, 0.05, time_noise=5e-4, level_noise=0.05, seed=3)
    got = closed_form_bike.fit([("made", None, None, dry)], fitted=("spring_scale", "friction_N", "damper_scale"))
    assert "refused" not in got
    assert got["friction_N"] == pytest.approx(150.0, abs=10.0) and got["damper_scale"] < 0.3

"""The ring-down's turning points and residuals the spring, friction and dampers are read from
(``mtbmj.identify.bounce_ring``; the fit through the MuJoCo bike is checked on the independent slams of
``tests/test_bounce_replay.py``).

(a) Ring-downs made here by a model of this file's own: one mass on a spring with a linear damper and
Coulomb friction (a stick condition), released from a slam's height above rest, stepped by
semi-implicit Euler at 20 us and sampled at 5 kHz. Viscous damping alone keeps a constant share of the
swing each half cycle (exp(-pi zeta / sqrt(1 - zeta^2)), Den Hartog); friction alone takes a constant
4 F / k off it (REFERENCE.md section 8, Feeny and Liang 1996). ``turning_points`` gives those back, so
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

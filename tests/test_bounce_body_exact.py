"""The seated body's two-mass trace (``bounce_body.trace``: each stretch between switches propagated
exactly by its matrix exponential) against an independent integration written here: ``scipy``'s
``solve_ivp`` (RK45, rtol 1e-8, steps of 10 ms at most) with terminal events, the stops and stick-slip
handled by the same rules (what the module did before). Shared with the module: the two-mass model
itself (``TwoMass``: its rates, damping and friction from the law) and the switching rules (plastic
stops, held while the forces stay within friction); not shared: the integration and the switches'
timing. Checked against physics too: with no friction and no stop the trace's energy decays only by the
damping's work (the power balance, integrated by the trapezoid rule here)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mtbmj.identify import bounce_body as bb


def reference_trace(m, x0, x_eq, stroke_mm, duration_s, dt):
    """The trace by ``solve_ivp`` with events (this file's own integration of the module's rules)."""
    from scipy.integrate import solve_ivp

    tt = np.arange(int(duration_s / dt) + 1) * dt
    xx = np.full(tt.size, np.nan)
    lo, hi = -x_eq, stroke_mm - x_eq
    mb = 1.0 - m.mu
    q = np.array([x0 - x_eq, m.phi * (x0 - x_eq), 0.0, 0.0])
    t0, held, stalls, s = 0.0, True, 0, 1.0
    while t0 < tt[-1]:
        f = m.bike_force(q)
        if held:
            push = f - m.fc if not q[0] >= hi - 1e-9 else -math.inf
            pull = -f - m.fc if not q[0] <= lo + 1e-9 else -math.inf
            if push > 0 or pull > 0:
                held, s = False, (1.0 if push > 0 else -1.0)
        if held:
            u = q[0]

            def rhs(_, z, u=u):
                return [0.0, z[3], 0.0, m.body_acc((u, z[1], 0.0, z[3]))]
            evs = []
            if not q[0] >= hi - 1e-9:
                evs.append(lambda _, z, u=u: m.bike_force((u, z[1], 0.0, z[3])) - m.fc)
            if not q[0] <= lo + 1e-9:
                evs.append(lambda _, z, u=u: -m.bike_force((u, z[1], 0.0, z[3])) - m.fc)
            for e in evs:
                e.terminal, e.direction = True, 1
        else:
            def rhs(_, z, s=s):
                return [z[2], z[3], (m.bike_force(z) - m.fc * s) / mb, m.body_acc(z)]

            def rev(_, z):
                return z[2]

            def low(_, z):
                return z[0] - lo

            def high(_, z):
                return z[0] - hi
            rev.terminal, rev.direction = True, -s
            low.terminal, low.direction = True, -1
            high.terminal, high.direction = True, 1
            evs = [rev, low, high]
        sol = solve_ivp(rhs, (t0, tt[-1]), q, events=evs, max_step=0.01, rtol=1e-8, atol=1e-9, dense_output=True)
        sel = (tt >= t0) & (tt <= sol.t[-1])
        if sol.t[-1] > t0 and sel.any():
            xx[sel] = x_eq + sol.sol(tt[sel])[0]
        stalls = stalls + 1 if sol.t[-1] <= t0 + 1e-12 else 0
        t0, q = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status != 1 or stalls > bb.MAX_STALLS:
            break
        if not held:
            q[0] = min(max(q[0], lo), hi)
            q[2] = 0.0
            held = True
        else:
            held = False
            s = 1.0 if m.bike_force(q) > 0 else -1.0
            q[2] = 0.0
    rest = np.isnan(xx)
    if rest.any():
        xx[rest] = x_eq + q[0]
    return tt, np.clip(xx, 0.0, stroke_mm)


# (share, law's Hz, zeta, friction band mm, body zeta, x0, x_eq, stroke, dt): a slam to the top-out stop and
# and held there, one that stops short of the stops by friction (stick-slip), one with no stroke end (the fit's
# cases), one heavily damped, one to the bottom-out stop
CASES = [
    (0.5, 1.6, 0.05, 0.2, 0.475, 30.0, 8.0, 30.0, 1e-3),
    (0.3, 2.0, 0.05, 2.0, 0.35, 25.0, 15.0, 65.0, 5e-4),
    (0.6, 1.4, 0.10, 0.3, 0.6, 40.0, 18.0, math.inf, 1e-3),
    (0.2, 1.8, 0.45, 0.5, 0.475, 35.0, 10.0, 65.0, 2e-3),
    (0.45, 1.5, 0.05, 0.3, 0.3, 2.0, 20.0, 30.0, 1e-3),
]


@pytest.mark.parametrize("case", CASES)
def test_the_exact_trace_is_the_integrated_one(case):
    mu, fn, z, d, zb, x0, x_eq, stroke, dt = case
    m = bb.TwoMass.of_law(mu, fn, z, d, zb)
    t, x = bb.trace(m, x0, x_eq, stroke, 3.0, dt)
    tr, xr = reference_trace(m, x0, x_eq, stroke, 3.0, dt)
    assert np.array_equal(t, tr)
    assert np.max(np.abs(x - xr)) < 1e-5, float(np.max(np.abs(x - xr)))
    assert np.all(x >= 0.0) and np.all(x <= stroke)
    assert np.ptp(x) > 1.0  # the trace moves: the check is not of two rests


@pytest.mark.parametrize("case,end", [(CASES[0], 0.0), (CASES[4], 30.0)])
def test_a_slam_reaches_the_stop_and_is_held_there(case, end):
    """The first case's slam reaches the top-out stop (travel 0), the last's the bottom-out (its stroke), and
    each stays on it a while (held there by the body's push), in both integrations."""
    mu, fn, z, d, zb, x0, x_eq, stroke, dt = case
    m = bb.TwoMass.of_law(mu, fn, z, d, zb)
    for _, x in (bb.trace(m, x0, x_eq, stroke, 3.0, dt), reference_trace(m, x0, x_eq, stroke, 3.0, dt)):
        assert np.sum(np.abs(x - end) <= 1e-9) * dt > 0.01


def test_without_friction_or_stops_the_energy_falls_by_the_damping_s_work():
    """No friction, no stop reached: the two masses' energy at the end plus the damping's work (the
    power c u'^2 + cr (y' - u')^2, integrated here) is the energy at the start (per unit moving mass)."""
    m = bb.TwoMass.of_law(0.4, 1.7, 0.12, 0.0, 0.475)
    x_eq, x0, dt = 50.0, 60.0, 1e-4
    t, x = bb.trace(m, x0, x_eq, math.inf, 1.5, dt)
    u = x - x_eq
    # the body's motion is not returned: integrate it here from the bike's (its own ODE, driven by u)
    from scipy.integrate import solve_ivp
    from scipy.interpolate import CubicSpline
    us = CubicSpline(t, u)
    sol = solve_ivp(lambda tt, yv: [yv[1], -(m.kr * (yv[0] - us(tt)) + m.cr * (yv[1] - us(tt, 1))) / m.mu],
                    (0.0, t[-1]), [m.phi * (x0 - x_eq), 0.0], t_eval=t, rtol=1e-10, atol=1e-12, max_step=1e-3)
    y, yd, ud = sol.y[0], sol.y[1], us(t, 1)
    mb = 1.0 - m.mu
    energy = 0.5 * mb * ud ** 2 + 0.5 * m.mu * yd ** 2 + 0.5 * m.k * u ** 2 + 0.5 * m.kr * (y - u) ** 2
    power = m.c * ud ** 2 + m.cr * (yd - ud) ** 2
    lost = np.concatenate(([0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * dt)))
    assert energy[-1] < 0.5 * energy[0]  # the damping did work: the check is not of a still mass
    assert energy[-1] + lost[-1] == pytest.approx(energy[0], rel=2e-3)

"""The predicted ring-down through a stroke's end with the seated rider's body (``fit bounce``'s trace).

The decay law (:mod:`mtbmj.identify.bounce_predict`) is one mass. Where its motion reaches a stroke's
end a plastic stop would restart it from rest there; but a seated rider's body keeps moving when the bike
stops: it holds the bike on its stop and then drives it out. So where the stop is reached the trace
comes from two masses on one line: the bike on the suspension (its spring, viscous damping and Coulomb
friction) and the rider's body on the bike, a spring and damper at the seated body's vertical resonance,
5 Hz (the seated body's apparent mass, ``RIDER_SOURCE``: the replay's resonance). The body's share of
the moving mass, ``mu``, and its damping ratio ``zeta_b`` are fitted together on the other records whose
predicted motion reaches a stop (:func:`fit_body`, the trace's RMS over ``FIT_S`` after the slam's peak;
bounded Powell from the literature's 0.475), ``zeta_b`` within ``BODY_ZETA_BOUNDS``: Fairley and Griffin's
(1989) 0.475 fits the mean apparent mass of 60 subjects at small magnitudes; a single-degree-of-freedom
body's damping ratio moves with posture and vibration magnitude (Toward and Griffin 2010, Industrial
Health 48:654), so the search spans 0.475 +- 0.2 (the span is this module's assumption, not a value read
in those papers). With the damping fixed at 0.475 a body that returns more of the stop's energy than
the literature's mean (the three-mass test generator, 0.35 and 0.40) is missed: 0.565 mm RMS held out
against 0.31 with it fitted (tests/test_bounce_predict.py).

Given ``mu`` (masses per unit of the whole moving mass: the bike ``1 - mu``, the body ``mu``) the
suspension's rate makes the low mode ring at the law's undamped frequency f_n (closed form: the 2 x 2
characteristic equation is linear in the rate), its damping makes the low mode's modal damping ratio
the law's zeta (``phi' C phi / 2 sqrt(phi' K phi phi' M phi)``, linear in the damping; 0 where the
body's own damping already gives more), and its friction makes the mode's friction band the law's d
(``F_c = d w_n^2 phi' M phi``: the decays the band is fitted on are the mode's). The motion starts from
rest at the slam's peak in the low mode's shape.

The stops are plastic for the bike: a stop reached sets its speed to nil and holds it there while the
forces on it (the suspension's spring and the body's spring and damper) push it into the stop or do
not overcome the friction; it is released when they do. A velocity reversal inside the stroke holds it
likewise (stick-slip: held while the forces stay within the friction). The body is never held. Each
stretch is integrated by ``scipy.integrate.solve_ivp`` with events; so the trace never leaves the
stroke (it is clipped to it as well, against the integrator's last ulp)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

BODY_HZ = 5.0  # the seated body's vertical resonance (Fairley and Griffin 1989; 4-6 Hz: Griffin 1990, ISO 2631-1)
BODY_ZETA = 0.475  # its damping ratio (Fairley and Griffin 1989: bounce_bike.RIDER_ZETA, checked equal in a test)
BODY_ZETA_BOUNDS = (0.275, 0.675)  # the damping ratio searched: 0.475 +- 0.2 (the module docstring)
SHARE_BOUNDS = (0.05, 0.95)  # the body's share of the moving mass searched
FIT_S = 3.0  # the fit's window after the slam's peak
MAX_STALLS = 50  # switches in a row that do not advance the time: the bike held for good


@dataclass(frozen=True)
class TwoMass:
    """Bike (mass ``1 - mu``) on the suspension and body (mass ``mu``) on the bike, per unit of the whole
    moving mass: rates in 1/s^2, damping in 1/s, friction in mm/s^2 (forces per unit mass, travel in mm)."""

    mu: float
    k: float
    c: float
    fc: float
    kr: float
    cr: float
    phi: float  # the body's displacement over the bike's in the low mode

    @classmethod
    def of_law(cls, mu: float, fn_hz: float, zeta: float, d_mm: float, body_zeta: float = BODY_ZETA) -> "TwoMass":
        w2 = (2 * math.pi * fn_hz) ** 2
        mb, mr = 1.0 - mu, mu
        kr = mr * (2 * math.pi * BODY_HZ) ** 2
        cr = 2 * body_zeta * math.sqrt(kr * mr)
        if kr <= w2 * mr:
            raise ValueError(f"the law's frequency {fn_hz:.2f} Hz is not below the body's {BODY_HZ:g} Hz")
        k = kr * kr / (kr - w2 * mr) - kr + w2 * mb  # det(K - w^2 M) = 0, linear in k
        phi = kr / (kr - w2 * mr)
        pmp = mb + mr * phi * phi
        c = max(2 * zeta * math.sqrt(w2) * pmp - cr * (phi - 1.0) ** 2, 0.0)
        return cls(mu, k, c, d_mm * w2 * pmp, kr, cr, phi)

    def bike_force(self, q) -> float:
        """Every force on the bike but friction's and a stop's (q: u, y, u', y' from equilibrium)."""
        return -self.k * q[0] - self.c * q[2] + self.kr * (q[1] - q[0]) + self.cr * (q[3] - q[2])

    def body_acc(self, q) -> float:
        return -(self.kr * (q[1] - q[0]) + self.cr * (q[3] - q[2])) / self.mu


def trace(m: TwoMass, x0: float, x_eq: float, stroke_mm: float, duration_s: float, dt: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """The bike's travel (mm) from rest at ``x0`` in the low mode's shape, sampled every ``dt`` from 0
    for ``duration_s``: stops at 0 and ``stroke_mm`` (plastic, holding), stick-slip friction."""
    from scipy.integrate import solve_ivp

    tt = np.arange(int(duration_s / dt) + 1) * dt
    xx = np.full(tt.size, np.nan)
    lo, hi = -x_eq, stroke_mm - x_eq  # the stops in u
    mb = 1.0 - m.mu
    q = np.array([x0 - x_eq, m.phi * (x0 - x_eq), 0.0, 0.0])
    t0, held, stalls = 0.0, True, 0
    while t0 < tt[-1]:
        f = m.bike_force(q)
        if held:
            at_lo, at_hi = q[0] <= lo + 1e-9, q[0] >= hi - 1e-9
            push = f - m.fc if not at_hi else -math.inf  # the forces overcome friction into compression
            pull = -f - m.fc if not at_lo else -math.inf  # ... into extension
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
        if sol.status != 1 or stalls > MAX_STALLS:
            break
        if not held:
            q[0] = min(max(q[0], lo), hi)
            q[2] = 0.0  # a reversal or a plastic stop: the bike at rest, held while the forces allow
            held = True
        else:
            held = False
            s = 1.0 if m.bike_force(q) > 0 else -1.0
            q[2] = 0.0
    rest = np.isnan(xx)
    if rest.any():  # ended held (or the stall guard): the bike stays where it is
        xx[rest] = x_eq + q[0]
    return tt, np.clip(xx, 0.0, stroke_mm)


def fit_body(cases, fn_hz: float) -> tuple[float, float, float] | None:
    """The body's share ``mu`` and damping ratio ``zeta_b`` that make the two-mass traces follow ``cases``
    best, and the RMS (mm) there: each case (zeta, d, x0, x_eq, stroke_mm, travel after the slam's peak
    from the peak, dt). Bounded Powell (scipy) over SHARE_BOUNDS x BODY_ZETA_BOUNDS of the RMS pooled over
    the cases, from the share's middle and the literature's damping; None without a case."""
    from scipy.optimize import minimize

    if not cases:
        return None

    def cost(p):
        mu, zb = float(p[0]), float(p[1])
        tot, n = 0.0, 0
        for z, d, x0, x_eq, stroke, rec, dt in cases:
            _, xx = trace(TwoMass.of_law(mu, fn_hz, z, d, zb), x0, x_eq, stroke, FIT_S, dt)
            k = min(xx.size, rec.size)
            tot += float(np.sum((xx[:k] - rec[:k]) ** 2))
            n += k
        return math.sqrt(tot / n)

    res = minimize(cost, [0.5 * sum(SHARE_BOUNDS), BODY_ZETA], method="Powell",
                   bounds=[SHARE_BOUNDS, BODY_ZETA_BOUNDS], options={"xtol": 2e-3, "ftol": 1e-4})
    return float(res.x[0]), float(res.x[1]), float(res.fun)


def at_bound(v: float, bounds) -> float | None:
    lo, hi = bounds
    return lo if v - lo <= 0.01 * (hi - lo) else hi if hi - v <= 0.01 * (hi - lo) else None


def share_words(mu: float) -> str:
    """The fitted share in words, saying where it stopped at a bound of its search (within 1 % of the span)."""
    at = at_bound(mu, SHARE_BOUNDS)
    return f"{mu:.2f}" + ("" if at is None else f" (stopped at its bound {at:g}: the records want less loss at the stop)")


def zeta_words(zb: float) -> str:
    """The fitted body damping ratio in words, a bound of its search said."""
    at = at_bound(zb, BODY_ZETA_BOUNDS)
    return f"{zb:.3f}" + ("" if at is None else f" (stopped at its bound {at:g})")


__all__ = ["BODY_HZ", "BODY_ZETA", "BODY_ZETA_BOUNDS", "FIT_S", "SHARE_BOUNDS", "TwoMass", "at_bound", "fit_body",
           "share_words", "trace", "zeta_words"]

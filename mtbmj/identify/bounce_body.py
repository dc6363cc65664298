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
stretch between two such switches is a linear system with constant forcing, so it is propagated exactly
by its matrix exponential (``scipy.linalg.expm`` of the system with its forcing as a fifth state, one
step of the trace's sampling at a time); a switch is found where a switch's function (each linear in
the state) crosses zero between two samples, its time by ``scipy.optimize.brentq`` on the exact
motion. So the trace never leaves the stroke (it is clipped to it as well, against the last ulp). This
replaced ``scipy.integrate.solve_ivp`` with events (rtol 1e-8, steps of 10 ms at most), which gave
the same traces within 1e-5 mm (tests/test_bounce_body_exact.py), the body's fit on the tests' five
records about 8 times slower."""
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


def _force_row(m: TwoMass) -> np.ndarray:
    """``TwoMass.bike_force`` as coefficients on (u, y, u', y')."""
    return np.array([-m.k - m.kr, m.kr, -m.c - m.cr, m.cr])


def _body_row(m: TwoMass) -> np.ndarray:
    """``TwoMass.body_acc`` as coefficients on (u, y, u', y')."""
    return np.array([m.kr, -m.kr, m.cr, -m.cr]) / m.mu


def _system(m: TwoMass, held: bool, s: float) -> np.ndarray:
    """The stretch's linear system on (u, y, u', y', 1): free (sliding in direction ``s``, friction
    against it) or with the bike held (u and u' fixed, the body moving on it)."""
    mb = 1.0 - m.mu
    a = np.zeros((5, 5))
    a[1, 3] = 1.0
    a[3, :4] = _body_row(m)  # the body's acceleration
    if held:
        a[3, 2] = 0.0  # u' = 0 while held
    else:
        a[0, 2] = 1.0
        a[2, :4] = _force_row(m) / mb
        a[2, 4] = -m.fc * s / mb
    return a


def _switches(m: TwoMass, held: bool, s: float, u: float, lo: float, hi: float) -> list:
    """The stretch's switches as (g, direction): each fires where g . (u, y, u', y', 1) crosses zero in
    ``direction`` (+1 rising, -1 falling), as ``solve_ivp``'s terminal events did."""
    out = []
    if held:
        lin = np.append(_force_row(m), 0.0)
        lin[2] = 0.0
        if not u >= hi - 1e-9:
            out.append((lin - np.array([0, 0, 0, 0, m.fc]), 1))  # pushed into compression past friction
        if not u <= lo + 1e-9:
            out.append((-lin - np.array([0, 0, 0, 0, m.fc]), 1))  # pulled into extension past friction
    else:
        out.append((np.array([0.0, 0, 1, 0, 0]), -int(s)))  # the bike's velocity reverses
        if math.isfinite(lo):
            out.append((np.array([1.0, 0, 0, 0, -lo]), -1))  # the top-out stop
        if math.isfinite(hi):
            out.append((np.array([1.0, 0, 0, 0, -hi]), 1))  # the bottom-out stop
    return out


CHUNK = 4096  # samples propagated at once (powers of the step's exponential by doubling)


def _powers(step: np.ndarray, w: np.ndarray, n: int) -> np.ndarray:
    """(w, step w, step^2 w, ... step^(n-1) w) as columns: by doubling, log2(n) products."""
    out = np.empty((w.size, n))
    out[:, 0] = w
    have, p = 1, step
    while have < n:
        k = min(have, n - have)
        out[:, have:have + k] = p @ out[:, :k]
        have += k
        p = p @ p
    return out


def _stretch(a: np.ndarray, w0: np.ndarray, t0: float, tt: np.ndarray, dt: float, switches: list, uu: np.ndarray):
    """Propagate ``w0`` from ``t0`` by ``exp(a t)``, writing u at every sample of ``tt`` reached into ``uu``,
    to the first switch or the trace's end: (time, state, fired). A switch fires between two samples
    (``t0`` the first) where its function goes from at most 0 to at least 0 in its direction, as
    ``solve_ivp``'s events did between steps."""
    from scipy.linalg import expm
    from scipy.optimize import brentq

    j = int(np.searchsorted(tt, t0 - 1e-12))  # the first sample at or after t0
    if j < tt.size and abs(tt[j] - t0) <= 1e-12:
        uu[j] = w0[0]
        j += 1
    g = np.array([sw[0] for sw in switches], dtype=float).reshape(len(switches), 5)
    sign = np.array([sw[1] for sw in switches], dtype=float).reshape(-1, 1)
    if j >= tt.size:
        return t0, w0, False
    step = expm(a * dt)
    t_prev, w_prev = t0, w0
    w = expm(a * (tt[j] - t0)) @ w0
    while j < tt.size:
        n = min(CHUNK, tt.size - j)
        states = _powers(step, w, n)
        gv = sign * (g @ np.column_stack((w_prev, states)))  # each switch as rising through 0
        fired = (gv[:, :-1] <= 0) & (gv[:, 1:] >= 0)
        hit = np.flatnonzero(fired.any(axis=0))
        if hit.size:
            i = int(hit[0])  # between column i (t_prev or a sample) and i + 1 (sample j + i)
            base_t, base = (t_prev, w_prev) if i == 0 else (tt[j + i - 1], states[:, i - 1])
            uu[j:j + i] = states[0, :i]
            span = tt[j + i] - base_t

            def at(tau, k):
                return float(sign[k, 0] * (g[k] @ (expm(a * tau) @ base)))
            roots = []
            for k in np.flatnonzero(fired[:, i]):
                g0, g1 = at(0.0, k), at(span, k)
                roots.append(0.0 if g0 == 0 else span if g1 == 0 or g0 * g1 > 0 else
                             brentq(at, 0.0, span, args=(k,), xtol=1e-13, rtol=1e-12))
            tau = min(roots)
            return base_t + tau, expm(a * tau) @ base, True
        uu[j:j + n] = states[0]
        t_prev, w_prev = tt[j + n - 1], states[:, -1]
        w = step @ w_prev
        j += n
    return t_prev, w_prev, False


def trace(m: TwoMass, x0: float, x_eq: float, stroke_mm: float, duration_s: float, dt: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """The bike's travel (mm) from rest at ``x0`` in the low mode's shape, sampled every ``dt`` from 0
    for ``duration_s``: stops at 0 and ``stroke_mm`` (plastic, holding), stick-slip friction."""
    tt = np.arange(int(duration_s / dt) + 1) * dt
    uu = np.full(tt.size, np.nan)
    lo, hi = -x_eq, stroke_mm - x_eq  # the stops in u
    q = np.array([x0 - x_eq, m.phi * (x0 - x_eq), 0.0, 0.0])
    t0, held, stalls, s = 0.0, True, 0, 1.0
    while t0 < tt[-1]:
        f = m.bike_force(q)
        if held:
            at_lo, at_hi = q[0] <= lo + 1e-9, q[0] >= hi - 1e-9
            push = f - m.fc if not at_hi else -math.inf  # the forces overcome friction into compression
            pull = -f - m.fc if not at_lo else -math.inf  # ... into extension
            if push > 0 or pull > 0:
                held, s = False, (1.0 if push > 0 else -1.0)
        switches = _switches(m, held, s, float(q[0]), lo, hi)
        if held:
            q[2] = 0.0
        t1, w, fired = _stretch(_system(m, held, s), np.append(q, 1.0), t0, tt, dt, switches, uu)
        stalls = stalls + 1 if t1 <= t0 + 1e-12 else 0
        t0, q = float(t1), w[:4].copy()
        if not fired or stalls > MAX_STALLS:
            break
        if not held:
            q[0] = min(max(q[0], lo), hi)
            q[2] = 0.0  # a reversal or a plastic stop: the bike at rest, held while the forces allow
            held = True
        else:
            held = False
            s = 1.0 if m.bike_force(q) > 0 else -1.0
            q[2] = 0.0
    rest = np.isnan(uu)
    if rest.any():  # ended held (or the stall guard): the bike stays where it is
        uu[rest] = q[0]
    return tt, np.clip(x_eq + uu, 0.0, stroke_mm)


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

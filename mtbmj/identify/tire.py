"""Tire identification by the coefficient-of-restitution method (Sadauckas 2023; derivation in docs/reference.md §4.2).

A mass m dropped on the tire: the first impact gives the contact time t_c (deflection > 0) and the
restitution e = v_out / v_in, both found from the data. For a linear Kelvin-Voigt contact that
separates at zero deflection,

    zeta = -ln e / sqrt(pi^2 + ln^2 e),  k = m (pi^2 + ln^2 e) / t_c^2,  b = -2 m ln(e) / t_c.

Velocities come from a local polynomial fit of the free-flight deflection just before touchdown
and just after lift-off (a parabola of curvature g by default, a free quadratic on request), away
from the few milliseconds the anti-aliasing filter smears; touchdown and lift-off are where those
parabolas cross zero, so both carry the filter's delay and t_c does not. Sub-sample timing comes
from the fits, and their covariance is propagated to k and b.

The closed form ignores gravity. On a drop rig the mass weighs on the tire during the contact
(static deflection m g / k), which lengthens t_c by roughly 2 asin(m g / (k A)) / omega -- 10 % or
more for a tire -- and the contact that only pushes lets go slightly before zero deflection. By
default (``gravity_correction=True``) the formula's values are the starting point of an exact
inversion: the (k, b) whose bounce of mass m under gravity, with the push-only law, returns the
measured t_c and e at the measured v_in. ``extra["formula_values"]`` keeps the plain formula.

In-contact values come from the settled oscillation (the record after the last sample with
deflection <= 0): a damped sinusoid about the static deflection fitted by ``least_squares``;
omega_n^2 = omega_d^2 + sigma^2, k = m omega_n^2, b = 2 m sigma. The static rate is the slope of a
force-deflection ramp by least squares (an intercept absorbs a load-cell offset).
"""
from __future__ import annotations

import math
import re

import numpy as np
from scipy import optimize

from mtbmj.errors import MtbmjError

from mtbmj.identify.fitresult import FitResult, covariance_stderr, declare_bounds
from mtbmj.measured.records import Record

G = 9.81


# --- the formula and the exact bounce ---------------------------------------------------------

def cor_values(e: float, t_c: float, mass_kg: float) -> tuple[float, float, float]:
    """(k N/m, b N s/m, zeta) of the coefficient-of-restitution formula (no gravity)."""
    if not 0.0 < e < 1.0:
        raise MtbmjError(f"tire: restitution e = {e:.4g} is outside (0, 1); not a damped bounce")
    if not t_c > 0.0:
        raise MtbmjError(f"tire: contact time {t_c:.4g} s is not positive")
    ln_e = math.log(e)
    s = math.pi**2 + ln_e**2
    return mass_kg * s / t_c**2, -2.0 * mass_kg * ln_e / t_c, -ln_e / math.sqrt(s)


def kelvin_voigt_bounce(k: float, b: float, mass_kg: float, v_in: float, gravity: float = 0.0) -> tuple[float, float]:
    """(t_c, e) of one bounce of mass m hitting a push-only Kelvin-Voigt contact at ``v_in``.

    Closed form while the contact pushes (a damped oscillation about m g / k), then free flight
    if the force reaches zero before the deflection does. With ``gravity = 0`` and a contact that
    may pull, t_c = pi / omega_d and e = exp(-zeta omega_n t_c); here the contact never pulls.
    """
    m = mass_kg
    wn = math.sqrt(k / m)
    sigma = b / (2.0 * m)
    if sigma >= wn:
        raise MtbmjError("tire: overdamped contact, no bounce")
    wd = math.sqrt(wn**2 - sigma**2)
    ds = m * gravity / k
    c1, c2 = -ds, (v_in - sigma * ds) / wd

    def state(t):
        ex = math.exp(-sigma * t)
        cs, sn = math.cos(wd * t), math.sin(wd * t)
        d = ds + ex * (c1 * cs + c2 * sn)
        v = ex * ((c2 * wd - sigma * c1) * cs - (c1 * wd + sigma * c2) * sn)
        return d, v

    def force(t):
        d, v = state(t)
        return k * d + b * v

    period = 2.0 * math.pi / wd
    grid = np.linspace(0.0, 1.5 * period, 3001)[1:]
    values = np.array([force(t) for t in grid])
    neg = np.flatnonzero(values <= 0.0)
    if neg.size == 0:
        raise MtbmjError("tire: the contact never lets go (no rebound)")
    j = neg[0]
    lo = grid[j - 1] if j > 0 else 0.0
    t1 = optimize.brentq(force, lo, grid[j], xtol=1e-15, rtol=1e-14)
    d1, v1 = state(t1)
    if d1 <= 0.0 or gravity == 0.0:
        # let go at (or, numerically, just past) zero deflection: no free flight inside the tire
        tau = d1 / -v1 if v1 < 0 and d1 > 0 else 0.0
        return t1 + tau, -(v1 + gravity * tau) / v_in
    # free flight from d1 > 0 up to d = 0: d1 + v1 tau + g tau^2 / 2 = 0, first root
    disc = v1**2 - 2.0 * gravity * d1
    if disc < 0.0:
        raise MtbmjError("tire: the mass falls back before the tread leaves the ground")
    tau = (-v1 - math.sqrt(disc)) / gravity
    return t1 + tau, -(v1 + gravity * tau) / v_in


def invert_bounce(e: float, t_c: float, mass_kg: float, v_in: float, gravity: float = G) -> tuple[float, float]:
    """(k N/m, b N s/m) whose push-only bounce under gravity gives the measured (t_c, e)."""
    k0, b0, _ = cor_values(e, t_c, mass_kg)

    def resid(p):
        k, b = math.exp(p[0]), math.exp(p[1])
        try:
            tc_m, e_m = kelvin_voigt_bounce(k, b, mass_kg, v_in, gravity)
        except MtbmjError:
            return [10.0, 10.0]
        return [tc_m / t_c - 1.0, math.log(max(e_m, 1e-12)) - math.log(e)]

    sol = optimize.least_squares(resid, [math.log(k0), math.log(b0)], xtol=1e-14, ftol=1e-14, gtol=1e-14)
    if np.max(np.abs(sol.fun)) > 1e-7:
        raise MtbmjError(f"tire: no Kelvin-Voigt contact reproduces t_c = {t_c * 1e3:.2f} ms and e = {e:.4f} "
                         f"at {v_in:.3f} m/s (gravity-corrected inversion did not converge)")
    return math.exp(sol.x[0]), math.exp(sol.x[1])


# --- record helpers ---------------------------------------------------------------------------

def record_mass(record: Record, mass_kg: float | None = None) -> float:
    """The drop mass: the argument, else a ``mass_kg = ...`` comment in the record."""
    if mass_kg is None:
        for comment in record.comments:
            match = re.search(r"\bmass_kg\s*=\s*([-+0-9.eE]+)", comment)
            if match:
                try:
                    mass_kg = float(match.group(1))
                except ValueError:
                    continue
                break
    if mass_kg is None:
        raise MtbmjError(f"{record.path}: drop mass unknown: give mass_kg (or a '# mass_kg = ...' comment line)")
    if not (math.isfinite(mass_kg) and mass_kg > 0.0):
        raise MtbmjError(f"{record.path}: drop mass must be positive, got {mass_kg:g} kg")
    return float(mass_kg)


def _runs(mask: np.ndarray, start: int, value: bool, persist: int) -> int | None:
    """First index >= start where ``mask`` equals ``value`` for ``persist`` samples in a row."""
    idx = np.flatnonzero(mask[start:] == value)
    for i in idx:
        i = int(i) + start
        if i + persist <= mask.size and np.all(mask[i:i + persist] == value):
            return i
    return None


def _flight_fit(t: np.ndarray, d: np.ndarray, t_ref: float, gravity: float, curvature: str):
    """Fit d(tau) = a0 + a1 tau (+ g/2 tau^2 fixed, or + a2 tau^2 free), tau = t - t_ref.
    Returns (params, covariance, rms)."""
    tau = t - t_ref
    if curvature == "gravity":
        a = np.column_stack([np.ones_like(tau), tau])
        y = d - 0.5 * gravity * tau**2
    else:
        a = np.column_stack([np.ones_like(tau), tau, tau**2])
        y = d
    p, *_ = np.linalg.lstsq(a, y, rcond=None)
    r = y - a @ p
    dof = max(len(y) - len(p), 1)
    cov = np.linalg.pinv(a.T @ a) * float(r @ r) / dof
    return p, cov, float(np.sqrt(np.mean(r**2)))


def _crossing(p: np.ndarray, gravity: float, curvature: str, sign: int) -> tuple[float, float]:
    """(tau, velocity) where the flight parabola crosses d = 0 nearest tau = 0; sign +1 going in."""
    c = 0.5 * gravity if curvature == "gravity" else p[2]
    a0, a1 = p[0], p[1]
    if abs(c) < 1e-12:
        tau = -a0 / a1
    else:
        disc = a1**2 - 4.0 * c * a0
        if disc < 0:
            raise MtbmjError("tire: the flight fit does not reach zero deflection")
        roots = np.array([(-a1 + math.sqrt(disc)) / (2 * c), (-a1 - math.sqrt(disc)) / (2 * c)])
        vel = a1 + 2 * c * roots
        ok = np.sign(vel) == sign
        roots = roots[ok] if ok.any() else roots
        tau = float(roots[np.argmin(np.abs(roots))])
    return tau, a1 + 2.0 * c * tau


# --- fits -------------------------------------------------------------------------------------

def fit_impact(record: Record, mass_kg: float | None = None, gravity: float = G, window_s: float = 0.05,
               guard_s: float = 0.005, curvature: str = "gravity", gravity_correction: bool = True) -> FitResult:
    """Impact stiffness and damping from the first impact of a tire drop record."""
    record.require("time", "deflection", min_points=20)  # before the mass: a spring record lacks both
    m = record_mass(record, mass_kg)
    if curvature not in ("gravity", "free"):
        raise MtbmjError(f"tire: curvature must be 'gravity' or 'free', got {curvature!r}")
    t, d = record["time"], record["deflection"]
    dt = float(np.median(np.diff(t)))
    persist = max(3, int(round(0.002 / dt)))
    noise_floor = 3.0 * float(np.median(np.abs(np.diff(d)))) + 1e-6
    contact = d > 0.0
    first_air = _runs(contact, 0, False, persist)
    touch = _runs(contact, first_air, True, persist) if first_air is not None else None
    if touch is None:
        raise MtbmjError(f"{record.path}: no impact in the record (the deflection never turns positive after a fall)")
    lift = _runs(contact, touch, False, persist)
    if lift is None:
        raise MtbmjError(f"{record.path}: the tire never lifts off after the first impact, so there is no rebound to measure")
    land = _runs(contact, lift, True, persist)
    land = d.size if land is None else land
    guard = max(guard_s, 2 * dt)
    # before touchdown: free fall, at least noise_floor + 2 mm below the height it fell from
    before = np.arange(0, touch)
    start_height = float(np.min(d[:touch]))
    pre = before[(t[before] >= t[touch] - guard - window_s) & (t[before] <= t[touch] - guard)
                 & (d[before] > start_height + 2e-3 + noise_floor)]
    after = np.arange(lift, land)
    post = after[(t[after] >= t[lift] + guard) & (t[after] <= t[lift] + guard + window_s)
                 & (t[after] <= t[land - 1] - guard)]
    need = 8
    if pre.size < need or post.size < need:
        side = "before touchdown" if pre.size < need else "after lift-off"
        raise MtbmjError(f"{record.path}: too little free flight {side} to fit a velocity "
                         f"({min(pre.size, post.size)} samples, need {need})")
    t_td0, t_lo0 = float(t[touch]), float(t[lift])
    p_pre, c_pre, rms_pre = _flight_fit(t[pre], d[pre], t_td0, gravity, curvature)
    p_post, c_post, rms_post = _flight_fit(t[post], d[post], t_lo0, gravity, curvature)

    def measure(params: np.ndarray):
        n = p_pre.size
        a, bb = params[:n], params[n:]
        tau_in, v_in = _crossing(a, gravity, curvature, +1)
        tau_out, v_out = _crossing(bb, gravity, curvature, -1)
        return (t_lo0 + tau_out) - (t_td0 + tau_in), -v_out / v_in, v_in

    def values(params: np.ndarray):
        t_c, e, v_in = measure(params)
        if gravity_correction:
            k, b = invert_bounce(e, t_c, m, v_in, gravity)
        else:
            k, b, _ = cor_values(e, t_c, m)
        return np.array([k / 1e3, b])

    params = np.concatenate([p_pre, p_post])
    cov = np.zeros((params.size, params.size))
    cov[: p_pre.size, : p_pre.size] = c_pre
    cov[p_pre.size:, p_pre.size:] = c_post
    t_c, e, v_in = measure(params)
    k_b = values(params)
    # delta method: numerical Jacobian of (k, b) with respect to the fit parameters
    steps = np.sqrt(np.clip(np.diag(cov), 1e-30, None)) * 1e-2
    jac = np.zeros((2, params.size))
    for i, h in enumerate(steps):
        dp = np.zeros_like(params)
        dp[i] = h
        jac[:, i] = (values(params + dp) - values(params - dp)) / (2 * h)
    k_b_cov = jac @ cov @ jac.T
    stderr = np.sqrt(np.clip(np.diag(k_b_cov), 0, None))
    jac_m = np.zeros((2, params.size))
    for i, h in enumerate(steps):
        dp = np.zeros_like(params)
        dp[i] = h
        jac_m[:, i] = (np.array(measure(params + dp)[:2]) - np.array(measure(params - dp)[:2])) / (2 * h)
    tc_e_err = np.sqrt(np.clip(np.diag(jac_m @ cov @ jac_m.T), 0, None))
    k_f, b_f, zeta_f = cor_values(e, t_c, m)
    n_pre = p_pre.size
    tau_in, _ = _crossing(p_pre, gravity, curvature, +1)
    tau_out, _ = _crossing(p_post, gravity, curvature, -1)

    def curve(p, t0, tt):
        tau = tt - t0
        c = 0.5 * gravity if curvature == "gravity" else p[2]
        return (p[0] + p[1] * tau + c * tau**2) * 1e3

    t_pre_c = np.linspace(t[pre[0]], t_td0 + tau_in, 60)
    t_post_c = np.linspace(t_lo0 + tau_out, t[post[-1]], 60)
    n_pts = pre.size + post.size
    rms = math.sqrt((rms_pre**2 * pre.size + rms_post**2 * post.size) / n_pts)
    keys = {"tire.impact_rate_N_per_mm": float(k_b[0]), "tire.impact_damping_N_s_per_m": float(k_b[1])}
    return FitResult(
        kind="tire", model="impact_cor", values=keys,
        stderr={"tire.impact_rate_N_per_mm": float(stderr[0]), "tire.impact_damping_N_s_per_m": float(stderr[1])},
        rms=rms * 1e3, residual_unit="mm", n_points=n_pts, n_params=2 * n_pre,
        extra={
            "model_keys": {"tire.model": "impact"},
            "mass_kg": m,
            "contact_time_s": t_c, "contact_time_stderr_s": float(tc_e_err[0]),
            "restitution": e, "restitution_stderr": float(tc_e_err[1]),
            "impact_speed_m_per_s": v_in, "rebound_speed_m_per_s": e * v_in,
            "touchdown_s": t_td0 + tau_in, "lift_off_s": t_lo0 + tau_out,
            "damping_ratio": zeta_f,
            "gravity_correction": gravity_correction,
            "formula_values": {"tire.impact_rate_N_per_mm": k_f / 1e3, "tire.impact_damping_N_s_per_m": b_f},
            "curves": {
                "data": (t * 1.0, d * 1e3),
                "pre_fit": (t_pre_c, curve(p_pre, t_td0, t_pre_c)),
                "post_fit": (t_post_c, curve(p_post, t_lo0, t_post_c)),
                "pre_window": (t[pre], d[pre] * 1e3),
                "post_window": (t[post], d[post] * 1e3),
            },
        },
    )


def _damped(p, tau):
    c, a, b, sigma, wd = p
    return c + np.exp(-sigma * tau) * (a * np.cos(wd * tau) + b * np.sin(wd * tau))


def fit_contact(record: Record, mass_kg: float | None = None, guard_s: float = 0.01, min_cycles: float = 2.0) -> FitResult:
    """In-contact stiffness and damping from the settled oscillation (after the last lift-off)."""
    record.require("time", "deflection", min_points=20)  # before the mass: a spring record lacks both
    m = record_mass(record, mass_kg)
    t, d = record["time"], record["deflection"]
    if not np.any(d > 0.0):
        raise MtbmjError(f"{record.path}: no impact in the record (the deflection never turns positive after a fall)")
    off = np.flatnonzero(d <= 0.0)
    first = (int(off[-1]) + 1) if off.size else 0
    sel = np.flatnonzero(t >= t[min(first, d.size - 1)] + guard_s)
    if sel.size < 20:
        raise MtbmjError(f"{record.path}: the tire never settles in contact (no oscillation to fit after the last lift-off)")
    tt, dd = t[sel], d[sel]
    tau = tt - tt[0]
    # starting values: static level from the tail, frequency from the spectrum, decay from the envelope
    c0 = float(np.median(dd[-max(10, dd.size // 5):]))
    y = dd - c0
    dt = float(np.median(np.diff(tt)))
    spec = np.abs(np.fft.rfft(y * np.hanning(y.size), n=8 * y.size))
    freqs = np.fft.rfftfreq(8 * y.size, dt)
    spec[freqs < 1.0 / (tau[-1] + dt)] = 0.0
    f0 = float(freqs[np.argmax(spec)])
    if f0 <= 0.0 or tau[-1] * f0 < min_cycles:
        raise MtbmjError(f"{record.path}: too few settled oscillation cycles to fit ({tau[-1] * f0:.1f}, need {min_cycles:g})")
    wd0 = 2 * math.pi * f0
    third = y.size // 3
    a1 = np.sqrt(2) * np.std(y[:third]) + 1e-9
    a3 = np.sqrt(2) * np.std(y[2 * third:]) + 1e-9
    span = tau[2 * third + third // 2] - tau[third // 2]
    sigma0 = max(math.log(a1 / a3) / span, 1e-3) if a1 > a3 else 1e-2
    basis = np.column_stack([np.exp(-sigma0 * tau) * np.cos(wd0 * tau), np.exp(-sigma0 * tau) * np.sin(wd0 * tau)])
    ab, *_ = np.linalg.lstsq(basis, y, rcond=None)
    p0 = np.array([c0, ab[0], ab[1], sigma0, wd0])
    sol = optimize.least_squares(lambda p: _damped(p, tau) - dd, p0, x_scale=np.array([1e-3, 1e-3, 1e-3, 1.0, 10.0]),
                                 xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=2000)
    if not sol.success:
        raise MtbmjError(f"{record.path}: the damped-sinusoid fit of the settled oscillation did not converge")
    c, a, b, sigma, wd = sol.x
    std, _ = covariance_stderr(sol.jac, sol.fun, 5)
    wn2 = wd**2 + sigma**2
    k = m * wn2
    bb = 2.0 * m * sigma
    k_err = 2.0 * m * math.hypot(wd * std[4], sigma * std[3])
    b_err = 2.0 * m * std[3]
    rms = float(np.sqrt(np.mean(sol.fun**2)))
    t_curve = np.linspace(tt[0], tt[-1], 2000)
    return FitResult(
        kind="tire", model="contact_oscillation",
        values={"tire.contact_rate_N_per_mm": k / 1e3, "tire.contact_damping_N_s_per_m": bb},
        stderr={"tire.contact_rate_N_per_mm": k_err / 1e3, "tire.contact_damping_N_s_per_m": b_err},
        rms=rms * 1e3, residual_unit="mm", n_points=int(dd.size), n_params=5,
        extra={
            "model_keys": {"tire.model": "switch"},
            "mass_kg": m,
            "natural_frequency_Hz": math.sqrt(wn2) / (2 * math.pi),
            "damping_ratio": sigma / math.sqrt(wn2),
            "static_deflection_mm": c * 1e3,
            "residual": -sol.fun * 1e3,  # data - model, mm
            "window_s": (float(tt[0]), float(tt[-1])),
            "curves": {"window": (tt, dd * 1e3), "fit": (t_curve, _damped(sol.x, t_curve - tt[0]) * 1e3)},
        },
    )


def fit_static(record: Record) -> FitResult:
    """Static rate: least-squares slope of force against deflection (with an intercept)."""
    record.require("deflection", "force", min_points=5)
    d, f = record["deflection"], record["force"]
    if np.ptp(d) <= 0.0:
        raise MtbmjError(f"{record.path}: the deflection does not vary; no slope to fit")
    a = np.column_stack([d, np.ones_like(d)])
    p, *_ = np.linalg.lstsq(a, f, rcond=None)
    r = f - a @ p
    std, _ = covariance_stderr(a, r, 2)
    d_line = np.linspace(float(np.min(d)), float(np.max(d)), 50)
    return FitResult(
        kind="tire", model="static_ramp",
        values={"tire.static_rate_N_per_mm": float(p[0]) / 1e3},
        stderr={"tire.static_rate_N_per_mm": float(std[0]) / 1e3},
        rms=float(np.sqrt(np.mean(r**2))), residual_unit="N", n_points=int(d.size), n_params=2,
        extra={"model_keys": {}, "offset_N": float(p[1]), "residual": r,
               "curves": {"data": (d * 1e3, f), "fit": (d_line * 1e3, p[0] * d_line + p[1])}},
    )


def _is_ramp(record: Record) -> bool:
    return "time" not in record.columns and {"deflection", "force"} <= set(record.columns)


def fit_tire(record: Record, mass_kg: float | None = None, ramp: Record | None = None,
             gravity: float = G, gravity_correction: bool = True) -> dict[str, FitResult]:
    """All tire values a record supports: ``impact`` (always, from a drop record), ``contact``
    (when the drop record settles in contact), ``static`` (from a ramp record, given as
    ``record`` itself or as ``ramp``)."""
    results: dict[str, FitResult] = {}
    if _is_ramp(record):
        results["static"] = fit_static(record)
    else:
        results["impact"] = fit_impact(record, mass_kg, gravity=gravity, gravity_correction=gravity_correction)
        try:
            results["contact"] = fit_contact(record, mass_kg)
        except MtbmjError as exc:
            results["impact"].extra["notes"] = [f"no in-contact values: {exc}"]
        if ramp is not None:
            results["static"] = fit_static(ramp)
    for result in results.values():  # every tire rate and damping is positive; nothing else bounds them
        declare_bounds(result, {key: (0.0, np.inf) for key in result.values}, hint=TIRE_BOUND_HINT)
    return results


TIRE_BOUND_HINT = ("a tire's rate and damping are positive: the record does not show the law's behaviour (a "
                   "growing oscillation, a slope of the wrong sign); look at fit.png")


def tire_overrides(results: dict[str, FitResult]) -> dict:
    """Configuration keys of all parts (in-contact model choice wins)."""
    out: dict = {}
    for part in ("static", "impact", "contact"):
        if part in results:
            out.update(results[part].overrides())
    return out


def plot_tire(record: Record | None, results: dict[str, FitResult]):
    """Figure: the drop record with the flight fits around the first impact, the settled
    oscillation fit, and the static ramp (whichever parts are present)."""
    from matplotlib.figure import Figure

    panels = [p for p in ("impact", "contact", "static") if p in results]
    fig = Figure(figsize=(6.5 * max(len(panels), 1), 4.2), layout="constrained")
    axes = fig.subplots(1, max(len(panels), 1), squeeze=False)[0]
    for ax, part in zip(axes, panels):
        res = results[part]
        cur = res.extra.get("curves", {})
        if part == "impact":
            t, d = cur["data"]
            t0, t1 = cur["pre_window"][0][0] - 0.01, cur["post_window"][0][-1] + 0.01
            sel = (t >= t0) & (t <= t1)
            ax.plot(t[sel], d[sel], ".", ms=2, color="0.5", label="data")
            ax.plot(*cur["pre_fit"], "C0", label="free fall fit")
            ax.plot(*cur["post_fit"], "C1", label="rebound fit")
            ax.axhline(0.0, color="k", lw=0.5)
            x = res.extra
            ax.set_title(f"impact: e = {x['restitution']:.3f}, t_c = {x['contact_time_s'] * 1e3:.1f} ms\n"
                         f"k = {res.values['tire.impact_rate_N_per_mm']:.1f} N/mm, "
                         f"b = {res.values['tire.impact_damping_N_s_per_m']:.0f} N s/m", fontsize=9)
            ax.set_xlabel("time (s)")
            ax.set_ylabel("tire deflection (mm)")
        elif part == "contact":
            ax.plot(*cur["window"], ".", ms=2, color="0.5", label="data (in contact)")
            ax.plot(*cur["fit"], "C2", lw=1, label="damped sinusoid")
            ax.set_title(f"in contact: k = {res.values['tire.contact_rate_N_per_mm']:.1f} N/mm, "
                         f"b = {res.values['tire.contact_damping_N_s_per_m']:.0f} N s/m", fontsize=9)
            ax.set_xlabel("time (s)")
            ax.set_ylabel("tire deflection (mm)")
        else:
            ax.plot(*cur["data"], ".", ms=3, color="0.5", label="data")
            ax.plot(*cur["fit"], "C3", label="least-squares line")
            ax.set_title(f"static: k = {res.values['tire.static_rate_N_per_mm']:.1f} N/mm", fontsize=9)
            ax.set_xlabel("deflection (mm)")
            ax.set_ylabel("force (N)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if record is not None:
        fig.suptitle(f"tire, {record.path}" + (" (synthetic)" if record.synthetic else ""), fontsize=10)
    return fig


__all__ = ["cor_values", "kelvin_voigt_bounce", "invert_bounce", "record_mass", "fit_impact", "fit_contact",
           "fit_static", "fit_tire", "tire_overrides", "plot_tire"]

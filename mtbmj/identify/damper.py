"""Fork damper and friction from dyno peak force vs velocity (paper Fig. 6).

The record is either the dyno's peak points (columns velocity, force) or its time series (time,
displacement and/or velocity, force), which is reduced to one peak point per half-cycle first
(``dyno_synthetic.peak_points``). Compression velocity and force are positive, rebound negative.

Every fit models the measured force as hydraulic part + friction law, F = H(v) + R(v), with R one
of the library's friction laws (``controllers.friction``, sign regularised with the configuration's
default band of 5 mm/s) and solved by ``scipy.optimize.least_squares``:

* hydraulic ``linear``: one coefficient c (the average of compression and rebound), + Coulomb;
* hydraulic ``bilinear``: c_c for v > 0, c_r for v < 0, + Coulomb;
* hydraulic ``digressive``: per direction a low-speed rate up to a knee speed and a high-speed
  rate beyond it (``controllers.DigressiveDamper``, what shimmed dampers do), + Coulomb;
* hydraulic ``table``: the Coulomb offset at zero velocity from the test speeds of 20-150 mm/s
  (at least the 4 slowest at or above 20 mm/s) of each side (quadratic through the origin per side + a shared offset), then the hydraulic part at each test
  speed = mean of (force - offset), with (0, 0) added and force made non-decreasing: the rules of
  ``fork.damper.velocity_mm_per_s`` / ``force_N`` (>= 4 points, strictly increasing velocity);
* friction models, each with a hydraulic law (``fit_damper``: the bilinear one; ``mtbmj fit``:
  the one it writes, ``refit_friction``, so the law written is one fit): ``none``, ``coulomb``,
  ``coulomb_viscous`` (the viscous term is the slope common to both sides: min(c_c, c_r); the
  damper keeps the excess), ``stiction`` (Karnopp band), ``stribeck`` (exponent 2) and ``lugre``
  (its steady state, identical to Stribeck with exponent 2; the bristle stiffness and damping need
  time-domain pre-sliding data, which a peak record does not hold, so they are not fitted).

``select(results)`` picks the lowest BIC, so the friction model is chosen by the residual and the
number of parameters, not by default. Breakaway and Stribeck/stiction velocity are reported as
supported only when the record has test speeds low enough to show them. Every law is evaluated on
the whole record at once (``law_forces``: the law's own formula run on arrays), not by a Python
call per point.
"""
from __future__ import annotations

import math
import types
from dataclasses import replace
from typing import Iterable, Mapping

import numpy as np
from scipy.optimize import least_squares

from mtbmj import controllers as law
from mtbmj.errors import MtbmjError
from mtbmj.identify.dyno_synthetic import peak_points
from mtbmj.identify.fitresult import FitResult, covariance_stderr, declare_bounds
from mtbmj.measured.records import Record, RecordError

HYDRAULIC = ("linear", "bilinear", "digressive", "table")
FRICTION = ("none", "coulomb", "coulomb_viscous", "stiction", "stribeck", "lugre")
MODELS = HYDRAULIC + FRICTION
BAND = 5e-3  # m/s: fork.friction.sign_band_mm_per_s default
MIN_WIDTH = 4.0 * BAND  # compose: the sign band must be at most a quarter of the Stribeck/stiction velocity
MIN_POINTS = 6
D, R = "fork.damper.", "fork.friction."


class DamperFitError(MtbmjError):
    """A damper fit cannot be done on this record (one line, names the cause)."""


def peaks(record: Record) -> Record:
    """The record as peak points (velocity, force): a time series is reduced first."""
    if "time" in record.columns and ("displacement" in record.columns or "velocity" in record.columns):
        series = record
        try:
            record = peak_points(series)
        except RecordError as exc:
            if "no dyno strokes" not in str(exc):  # (a file too short or unordered: its own line)
                raise
            record = None
        found = 0 if record is None else len(record)
        if found < MIN_POINTS:  # it said "too few points (1, ...)" of a file of many rows
            raise RecordError(f"{series.path}: {found} stroke(s) repeated at a steady speed in its {len(series)} rows "
                              f"(a damper test strokes at {MIN_POINTS} speeds or more); one slow stroke is a spring "
                              f"test: fit spring")
    record.require("velocity", "force", min_points=MIN_POINTS)
    v = record["velocity"]
    if np.sum(v > 0) < 2 or np.sum(v < 0) < 2:
        raise RecordError(f"{record.path}: the damper fit needs compression (v > 0) and rebound (v < 0) points")
    if not np.any(record["force"] != 0.0):
        raise RecordError(f"{record.path}: the force is zero at every point: no damping or friction to fit")
    return record


# --- the library's laws on arrays of velocities -----------------------------------------------------
# A fit evaluates its law at every point of the record at every step of the solver. Point by point
# through the law objects that is a few Python calls per point: minutes for a record of samples
# (a dyno time series of 29 000 rows without time_s, fitted as points). The law's own source runs on
# the whole array instead: its functions bound to numpy's for ``math``'s, and a piecewise law
# evaluated once per side of its guards (``controllers.guards``: the sides frozen, so no branch
# looks at an array), on the points that lie there. Same formulas, same branch rule (a guard >= 0
# is on its positive side), the numbers of the point-by-point call to the last bits of tanh/exp.


class _ArrayMath:
    """``math``'s functions by name, numpy's (which take arrays)."""

    def __getattr__(self, name):
        return getattr(np, {"pow": "power"}.get(name, name))


_ARRAY_MATH = _ArrayMath()
_ARRAY_TWINS: dict = {}


def _names(code) -> set[str]:
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _names(const)
    return names


def _array_twin(fn):
    """``fn`` (a law's method or formula) with the same code, its ``math`` numpy's and every law
    formula it calls the formula's own twin."""
    twin = _ARRAY_TWINS.get(fn)
    if twin is None:
        namespace = dict(fn.__globals__)
        twin = types.FunctionType(fn.__code__, namespace, fn.__name__, fn.__defaults__, fn.__closure__)
        _ARRAY_TWINS[fn] = twin
        if "math" in namespace:
            namespace["math"] = _ARRAY_MATH
        for name in _names(fn.__code__):
            value = namespace.get(name)
            if isinstance(value, types.FunctionType) and value.__module__.startswith(law.__name__ + "."):
                namespace[name] = _array_twin(value)
    return twin


def law_forces(obj, v) -> np.ndarray:
    """``obj.force`` (a damper or a stateless friction law of ``controllers``) at every velocity of
    ``v`` (m/s), as one array: each side of its guards evaluated once, on its points."""
    v = np.asarray(v, float)
    force = _array_twin(type(obj).force)
    if not getattr(obj, "n_guards", 0):
        return np.broadcast_to(np.asarray(force(obj, v), float), v.shape).copy()
    sides = np.array([np.broadcast_to(g, v.shape) >= 0.0 for g in obj.guards(0.0, v)]).reshape(obj.n_guards, -1)
    flat, out = v.ravel(), np.empty(v.size)
    for at, combo in _branches(sides):
        out[at] = force(obj, flat[at], sides=combo)
    return out.reshape(v.shape)


def _branches(sides: np.ndarray):
    """(the points, the sides) of every combination of guard sides that ``sides`` (guards x
    points, True: the guard >= 0) holds."""
    n = sides.shape[0]
    if n <= 16:  # each point's sides as one number, the ones present counted in one pass
        codes = np.zeros(sides.shape[1], np.int64)
        for i in range(n):
            codes |= sides[i].astype(np.int64) << i
        for code in np.flatnonzero(np.bincount(codes, minlength=1)):
            yield codes == code, tuple(bool(code >> i & 1) for i in range(n))
        return
    packed = np.ascontiguousarray(np.packbits(sides, axis=0).T)  # a table's many guards: one key a point
    keys = packed.view(np.dtype((np.void, packed.shape[1]))).ravel()
    _, first, which = np.unique(keys, return_index=True, return_inverse=True)
    which = which.ravel()
    for j, i in enumerate(first):
        yield which == j, tuple(bool(s) for s in sides[:, i])


# --- friction laws as vectorised functions of the parameters -------------------------------------

def _friction_law(name: str, q: np.ndarray):
    if name == "none":
        return law.NoFriction()
    if name == "coulomb":
        return law.Coulomb(q[0], BAND)
    if name == "coulomb_viscous":
        return law.CoulombViscous(q[0], q[1], BAND)
    if name == "stiction":
        return law.Stiction(q[0], q[1], 0.0, q[2], BAND)
    if name == "stribeck":
        return law.Stribeck(q[0], q[1], 0.0, q[2], 2.0, BAND)
    raise ValueError(name)


def _friction_force(name: str, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    if name == "lugre":  # steady state: g(v) sgn(v) (+ sigma2 v, here in the damper)
        g = q[0] + (q[1] - q[0]) * np.exp(-((v / q[2]) ** 2))
        return g * np.sign(v)
    return law_forces(_friction_law(name, q), v)


_FRICTION_PARAMS = {
    "none": [], "coulomb": ["coulomb_N"], "coulomb_viscous": ["coulomb_N", "viscous_N_s_per_m"],
    "stiction": ["coulomb_N", "breakaway_N", "stiction_band_mm_per_s"],
    "stribeck": ["coulomb_N", "breakaway_N", "stribeck_velocity_mm_per_s"],
    "lugre": ["coulomb_N", "breakaway_N", "stribeck_velocity_mm_per_s"],
}


def _hydraulic(name: str, p: np.ndarray, v: np.ndarray) -> np.ndarray:
    if name == "linear":
        return p[0] * v
    if name == "digressive":
        return law_forces(law.DigressiveDamper(*map(float, p[:6])), v)
    if name == "smooth_knee":  # the same two rates with a smooth knee: only for the friction check
        speed = np.abs(v)
        comp = p[1] * speed + (p[0] - p[1]) * p[2] * np.tanh(speed / p[2])
        reb = p[4] * speed + (p[3] - p[4]) * p[5] * np.tanh(speed / p[5])
        return np.where(v >= 0, comp, -reb)
    if name == "power":  # a v^n per side: only for the friction check
        speed = np.abs(v)
        return np.where(v >= 0, p[0] * speed ** p[1], -p[2] * speed ** p[3])
    return np.where(v > 0, p[0] * v, p[1] * v)


POLISH_NFEV = 2000  # evaluations per parameter a fit that ran out of them may take to finish from its best
N_HYDRAULIC = {"linear": 1, "bilinear": 2, "digressive": 6, "smooth_knee": 6, "power": 4}
CHECK_SHAPES = ("smooth_knee", "power")  # other shapes of the hydraulic force near zero speed, for the friction check
FRICTION_AGREEMENT = 0.2  # the friction under two shapes of the hydraulic knee: more than 20 % apart, it is not told
REJECTED_BIC = 10.0  # a BIC worse by this much is strong evidence against a model (Kass & Raftery 1995)
DIGRESSIVE_KEYS = ("compression_low_N_s_per_m", "compression_high_N_s_per_m", "compression_knee_mm_per_s",
                   "rebound_low_N_s_per_m", "rebound_high_N_s_per_m", "rebound_knee_mm_per_s")


def _digressive_start(v: np.ndarray, f: np.ndarray):
    """Start, lower and upper bounds of the digressive part: per side the slope of the slower and
    of the faster half of the test speeds, the knee between them (within the tested speeds)."""
    x0, lo, hi = [], [], []
    for side in (1, -1):
        sel = np.sign(v) == side
        speed, force = np.abs(v[sel]), np.abs(f[sel])
        knee = float(np.median(speed))
        slow, fast = speed <= knee, speed >= knee
        low = float(np.polyfit(speed[slow], force[slow], 1)[0]) if np.sum(slow) >= 2 else 100.0
        high = float(np.polyfit(speed[fast], force[fast], 1)[0]) if np.sum(fast) >= 2 else low
        x0 += [max(low, 1.0), max(min(high, low), 1.0), knee]
        lo += [0.0, 0.0, float(speed.min())]
        hi += [np.inf, np.inf, float(speed.max())]
    return x0, lo, hi


# --- fits ----------------------------------------------------------------------------------------

def parametric_fit(rec: Record, hydraulic: str, friction: str, name: str) -> FitResult:
    v, f = np.asarray(rec["velocity"], float), np.asarray(rec["force"], float)
    nh = N_HYDRAULIC[hydraulic]
    fric = "coulomb" if friction == "coulomb_viscous" else friction  # reparametrised afterwards
    names = _FRICTION_PARAMS[fric]
    # start: slopes per side from the fast half, offset from the intercepts
    fast = np.abs(v) >= np.median(np.abs(v))
    cc = np.polyfit(v[fast & (v > 0)], f[fast & (v > 0)], 1) if np.sum(fast & (v > 0)) >= 2 else (100.0, 0.0)
    cr = np.polyfit(v[fast & (v < 0)], f[fast & (v < 0)], 1) if np.sum(fast & (v < 0)) >= 2 else (100.0, 0.0)
    fc0 = max(0.5 * (cc[1] - cr[1]), 1.0)
    h0 = [0.5 * (cc[0] + cr[0])] if nh == 1 else [cc[0], cr[0]]
    q0, lo, hi = [], [], []
    for n in names:
        if n == "coulomb_N":
            q0.append(fc0), lo.append(0.0), hi.append(np.inf)
        elif n == "breakaway_N":
            q0.append(1.2 * fc0), lo.append(0.0), hi.append(np.inf)
        else:  # a velocity width, m/s
            q0.append(2.0 * MIN_WIDTH), lo.append(MIN_WIDTH), hi.append(1.0)
    if hydraulic in ("digressive", "smooth_knee"):
        h0, hlo, hhi = _digressive_start(v, f)
    elif hydraulic == "power":  # force = a |v|^n per side, from a unit slope at 1 m/s
        h0 = [max(h0[0] if len(h0) == 2 else 100.0, 1.0), 0.8, max(h0[-1], 1.0), 0.8]
        hlo, hhi = [0.0, 0.1, 0.0, 0.1], [np.inf, 2.0, np.inf, 2.0]
    else:
        h0, hlo, hhi = [max(h, 1.0) for h in h0], [0.0] * nh, [np.inf] * nh
    x0 = np.array(h0 + q0, float)
    lower = np.array(hlo + lo, float)
    upper = np.array(hhi + hi, float)
    scale = np.maximum(np.abs(x0), 1e-3)

    def resid(z):
        p = z * scale
        return _hydraulic(hydraulic, p[:nh], v) + _friction_force(fric, p[nh:], v) - f

    starts = [x0]
    if hydraulic in ("digressive", "smooth_knee"):  # the knees are multimodal: try a few
        for q in (0.25, 0.75):
            z = x0.copy()
            z[2] = float(np.quantile(np.abs(v[v > 0]), q))
            z[5] = float(np.quantile(np.abs(v[v < 0]), q))
            starts.append(z)
    if fric in ("stribeck", "stiction", "lugre"):  # the width is multimodal: try a few
        for w in (1.5 * MIN_WIDTH, 4 * MIN_WIDTH, 10 * MIN_WIDTH):
            z = x0.copy()
            z[-1] = w
            starts.append(z)
    best = None
    for z0 in starts:
        sol = least_squares(resid, np.clip(z0, lower, upper) / scale, bounds=(lower / scale, upper / scale),
                            method="trf", x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    if best.status == 0 and np.all(np.isfinite(best.x)):  # out of evaluations on its way: let it finish
        sol = least_squares(resid, best.x, bounds=(lower / scale, upper / scale), method="trf", x_scale="jac",
                            max_nfev=POLISH_NFEV * best.x.size)
        if sol.cost <= best.cost:
            best = sol
    if best.status <= 0 or not np.all(np.isfinite(best.x)):
        raise RecordError(f"{rec.path}: the {name} damper fit did not converge ({best.message})")
    p = best.x * scale
    r = resid(best.x)
    std, corr = covariance_stderr(best.jac / scale, r, len(p))
    values, stderr = {}, {}
    notes = []
    if hydraulic == "linear":
        values[D + "coefficient_N_s_per_m"], stderr[D + "coefficient_N_s_per_m"] = float(p[0]), float(std[0])
    elif hydraulic in ("digressive", "smooth_knee"):
        for i, key in enumerate(DIGRESSIVE_KEYS):
            unit = 1e3 if key.endswith("mm_per_s") else 1.0
            values[D + key], stderr[D + key] = float(p[i] * unit), float(std[i] * unit)
    else:
        values[D + "compression_N_s_per_m"], stderr[D + "compression_N_s_per_m"] = float(p[0]), float(std[0])
        values[D + "rebound_N_s_per_m"], stderr[D + "rebound_N_s_per_m"] = float(p[1]), float(std[1])
    for i, n in enumerate(names):
        scale_out = 1e3 if n.endswith("mm_per_s") else 1.0
        values[R + n] = float(p[nh + i] * scale_out)
        stderr[R + n] = float(std[nh + i] * scale_out)
    if fric in ("stiction", "stribeck", "lugre"):
        values[R + "viscous_N_s_per_m"] = 0.0
        notes.append("viscous friction term fixed at 0: on peak data it is not separable from the damper slope")
        width = p[-1]
        slow = np.sum(np.abs(v) < 2.0 * width)
        rel = [stderr[R + "breakaway_N"] / max(values[R + "breakaway_N"], 1e-9),
               std[-1] / max(width, 1e-12)]
        peak = values[R + "breakaway_N"] - values[R + "coulomb_N"]
        supported = bool(slow >= 4 and max(rel) < 0.3 and peak > 2.0 * stderr[R + "breakaway_N"])
        if peak <= 2.0 * stderr[R + "breakaway_N"]:
            notes.append(f"no breakaway peak in the data: breakaway - Coulomb = {peak:.1f} N is within "
                         f"2 standard errors ({2 * stderr[R + 'breakaway_N']:.1f} N)")
        if not supported:
            notes.append(f"not supported by the data: {slow} points below 2 x the fitted width "
                         f"({2e3 * width:.0f} mm/s) and relative errors {rel[0]:.2g}/{rel[1]:.2g}; record "
                         "lower test speeds to identify breakaway and its velocity")
    else:
        supported = True
    if friction == "coulomb_viscous":
        rates = [k for k in values if k.startswith(D) and k.endswith("_N_s_per_m")]  # every stage's rate
        common = min(values[k] for k in rates)
        for key in rates:
            values[key] -= common
        values[R + "viscous_N_s_per_m"] = float(common)
        stderr[R + "viscous_N_s_per_m"] = float(min(stderr[k] for k in rates))
        notes.append("viscous term = the slope common to compression and rebound (every stage); the damper keeps "
                     "the excess")
    if friction == "lugre":
        notes.append("LuGre bristle stiffness and damping are not identified: they need time-domain pre-sliding "
                     "data (small strokes below the breakaway force); the base configuration's values are kept")
    identified = True
    if R + "coulomb_N" in values:
        fc, se = values[R + "coulomb_N"], stderr[R + "coulomb_N"]
        if not (np.isfinite(se) and fc - 2.0 * se > 0.0 and se <= 0.5 * fc):
            identified = False
            notes.append(f"the friction cannot be told from the {hydraulic} hydraulic law on this record: Coulomb "
                         f"{fc:.1f} N with a standard error of {se:.2g} N (record slower test speeds to separate them)")
    grid = np.linspace(min(v.min(), 0.0), max(v.max(), 0.0), 400)
    curve_f = _hydraulic(hydraulic, p[:nh], grid) + _friction_force(fric, p[nh:], grid)
    result = FitResult("damper", name, values, stderr, float(np.sqrt(np.mean(r ** 2))), "N", len(v), len(p),
                     {"model_keys": {D + "model": hydraulic, R + "model": friction}, "hydraulic": hydraulic,
                      "law": f"{hydraulic} hydraulic law with {friction} friction",
                      "residual": -r,  # data - model
                      "friction": friction, "curve": (grid * 1e3, curve_f), "correlation": corr,
                      "supported": supported, "notes": notes, "friction_identified": identified,
                      **({"unidentified": [R + "bristle_stiffness_N_per_mm", R + "bristle_damping_N_s_per_m"]}
                         if friction == "lugre" else {})})
    if hydraulic not in CHECK_SHAPES:  # the check shapes' rates are not the written law's keys
        keys = _parameter_keys(hydraulic, fric)
        if friction == "coulomb_viscous":  # the rates are reparametrised: only the friction level is free as fitted
            keys = [k if k == R + "coulomb_N" else None for k in keys]
        unit = [1e3 if k and k.endswith("mm_per_s") else 1.0 for k in keys]
        declare_bounds(result, {k: (lower[i] * unit[i], upper[i] * unit[i]) for i, k in enumerate(keys) if k},
                       {k: x0[i] * unit[i] for i, k in enumerate(keys) if k})
    return result


def _parameter_keys(hydraulic: str, friction: str) -> list[str]:
    """The configuration key of each fitted parameter, in the fit's order (hydraulic, friction)."""
    hydraulic_keys = {"linear": ["coefficient_N_s_per_m"], "bilinear": ["compression_N_s_per_m", "rebound_N_s_per_m"],
                      "digressive": list(DIGRESSIVE_KEYS)}[hydraulic]
    return [D + k for k in hydraulic_keys] + [R + n for n in _FRICTION_PARAMS[friction]]


def _clusters(speed: np.ndarray) -> list[np.ndarray]:
    """Indices grouped by test speed (sorted |v| within 10 % of the group's first)."""
    order = np.argsort(speed)
    groups, current = [], [order[0]]
    for i in order[1:]:
        if speed[i] > 1.1 * speed[current[0]]:
            groups.append(np.array(current))
            current = []
        current.append(i)
    groups.append(np.array(current))
    return groups


def noise_floor(rec: Record) -> tuple[float, int]:
    """The peak force's own scatter (N) and its degrees of freedom: the points of one test speed
    (``_clusters``) about their own straight line in velocity (their mean, with fewer than 3 points
    or no spread of speed), pooled over the test speeds of both sides. ``(nan, 0)`` when no test
    speed has repeated points: a record of one point per speed cannot tell its noise."""
    v, f = np.asarray(rec["velocity"], float), np.asarray(rec["force"], float)
    squares, dof = 0.0, 0
    for side in (1, -1):
        idx = np.flatnonzero(np.sign(v) == side)
        if idx.size == 0:
            continue
        for g in _clusters(np.abs(v[idx])):
            sel = idx[g]
            if sel.size < 2:
                continue
            if sel.size >= 3 and np.ptp(v[sel]) > 0.0:
                fit = np.polyfit(v[sel], f[sel], 1)
                squares += float(np.sum((f[sel] - np.polyval(fit, v[sel])) ** 2))
                dof += sel.size - 2
            else:
                squares += float(np.sum((f[sel] - f[sel].mean()) ** 2))
                dof += sel.size - 1
    if dof == 0:
        return float("nan"), 0
    return float(np.sqrt(squares / dof)), dof


MIN_NOISE_DOF = 6  # repeated points (less the test speeds) a damper record needs for its noise floor


def damper_model_check(rec: Record, result: FitResult) -> dict | None:
    """A damper fit's model check: its residual RMS against the record's scatter at repeated test
    speeds (``noise_floor``), limit ``fitresult.MODEL_CHECK_FACTOR`` x noise; where the residual is
    largest (test speed). ``None`` when the record has too few repeated points to tell its noise."""
    from mtbmj.identify.fitresult import model_check

    noise, dof = noise_floor(rec)
    if dof < MIN_NOISE_DOF or not noise > 0.0:
        return None
    v, f = np.asarray(rec["velocity"], float), np.asarray(rec["force"], float)
    residual = result.extra.get("residual")
    if residual is None:
        return None
    worst = int(np.argmax(np.abs(residual)))
    return model_check(result.rms, noise, 0.0, "N",
                       f"{residual[worst]:+.3g} N at {v[worst] * 1e3:+.0f} mm/s (force {f[worst]:.0f} N)",
                       residual=[np.asarray(residual)[np.argsort(v)]])  # along the velocity


def table_fit(rec: Record) -> FitResult:
    v, f = np.asarray(rec["velocity"], float), np.asarray(rec["force"], float)
    # Coulomb offset at zero velocity: per side a quadratic through the origin on the slowest
    # test speeds, with a shared offset +/- F_C (regularised sign, as in the drop model).
    slow = []
    for idx in (np.flatnonzero(v >= MIN_WIDTH), np.flatnonzero(v <= -MIN_WIDTH)):
        groups = _clusters(np.abs(v[idx])) if len(idx) else []
        if groups:  # the slowest speeds up to 150 mm/s, at least 4 of them
            speeds = [float(np.mean(np.abs(v[idx[g]]))) for g in groups]
            n = max(4, sum(sp <= 0.15 for sp in speeds))
            slow.append(idx[np.concatenate(groups[:n])])
        else:
            slow.append(idx)
    if min(len(s) for s in slow) < 3:
        raise DamperFitError(f"{rec.path}: too few points above {MIN_WIDTH * 1e3:g} mm/s on each side to find "
                             "the friction offset")
    vc, vr = v[slow[0]], v[slow[1]]
    vs = np.concatenate([vc, vr])
    fs = np.concatenate([f[slow[0]], f[slow[1]]])
    isc = np.concatenate([np.ones(len(vc)), np.zeros(len(vr))])
    a = np.column_stack([np.tanh(vs / BAND), isc * vs, isc * vs ** 2, (1 - isc) * vs, (1 - isc) * vs ** 2])
    sol = least_squares(lambda z: a @ z - fs, np.zeros(a.shape[1]))
    res_slow = a @ sol.x - fs
    std_slow, _ = covariance_stderr(a, res_slow, a.shape[1])
    fc, fc_err = max(float(sol.x[0]), 0.0), float(std_slow[0])
    hyd = f - fc * np.tanh(v / BAND)
    nodes_v, nodes_f, nodes_se, counts = [0.0], [0.0], [0.0], []
    for side in (1, -1):
        idx = np.flatnonzero(np.sign(v) == side)
        for g in _clusters(np.abs(v[idx])):
            sel = idx[g]
            nodes_v.append(float(np.mean(v[sel])))
            nodes_f.append(float(np.mean(hyd[sel])))
            nodes_se.append(float(np.std(hyd[sel], ddof=1) / math.sqrt(len(sel))) if len(sel) > 1 else float("nan"))
            counts.append(len(sel))
    order = np.argsort(nodes_v)
    tv = np.asarray(nodes_v)[order]
    tf = np.asarray(nodes_f)[order]
    tse = np.asarray(nodes_se)[order]
    zero = int(np.flatnonzero(tv == 0.0)[0])
    # non-decreasing force (a damper dissipates): running max above zero, running min below it
    tf[zero:] = np.maximum.accumulate(np.maximum(tf[zero:], 0.0))
    tf[:zero + 1] = np.minimum.accumulate(np.minimum(tf[:zero + 1], 0.0)[::-1])[::-1]
    if len(tv) < 4 or np.any(np.diff(tv) <= 0):
        raise DamperFitError(f"{rec.path}: a lookup table needs at least 4 distinct test speeds (found {len(tv)} "
                             "velocities including 0)")
    damper = law.TableDamper(tv, tf)
    pred = law_forces(damper, v) + fc * np.tanh(v / BAND)
    r = pred - f
    grid = np.linspace(min(v.min(), 0.0), max(v.max(), 0.0), 400)
    curve_f = law_forces(damper, grid) + fc * np.tanh(grid / BAND)
    values = {D + "velocity_mm_per_s": tuple(float(x) for x in np.round(tv * 1e3, 3)),
              D + "force_N": tuple(float(x) for x in np.round(tf, 3)),
              R + "coulomb_N": fc}
    stderr = {R + "coulomb_N": fc_err, D + "force_N": float(np.nanmax(tse)) if np.any(np.isfinite(tse)) else float("nan")}
    result = FitResult("damper", "table", values, stderr, float(np.sqrt(np.mean(r ** 2))), "N", len(v),
                       len(tv) - 1 + 1,
                     {"model_keys": {D + "model": "table", R + "model": "coulomb"}, "hydraulic": "table",
                      "law": "table hydraulic law with coulomb friction",
                      "residual": -r,  # data - model
                      "friction": "coulomb", "curve": (grid * 1e3, curve_f), "force_stderr_N": tse.tolist(),
                      "supported": True,
                      "notes": [f"Coulomb offset at zero velocity {fc:.1f} +/- {fc_err:.2g} N from the test speeds "
                                f"{MIN_WIDTH * 1e3:g}-150 mm/s (at least 4) per side; table = mean force - offset per test speed, through (0, 0)"]})
    declare_bounds(result, {R + "coulomb_N": (0.0, np.inf)}, {R + "coulomb_N": fc_err})
    return result


def fit_damper(record: Record, model: str = "bilinear", *, friction: str | None = None) -> FitResult:
    """Fit one model (see the module doc). ``model`` is a hydraulic model (``linear``,
    ``bilinear``, ``table``; friction ``coulomb`` unless ``friction`` names another) or a friction
    model (fitted with the bilinear hydraulic part)."""
    if model not in MODELS:
        raise MtbmjError(f"fit damper: unknown model {model!r} (one of {', '.join(MODELS)})")
    if friction is not None and friction not in FRICTION:
        raise MtbmjError(f"fit damper: unknown friction model {friction!r} (one of {', '.join(FRICTION)})")
    rec = peaks(record)
    if model == "table":
        if friction not in (None, "coulomb"):
            raise MtbmjError("fit damper: the table is fitted with the Coulomb offset only (the table absorbs the rest)")
        return table_fit(rec)
    if model in HYDRAULIC:
        return parametric_fit(rec, model, friction or "coulomb", model)
    return parametric_fit(rec, "bilinear", model, model)


def fit_damper_all(record: Record, friction: bool = True, step=None) -> dict[str, FitResult]:
    """Every hydraulic model (with Coulomb friction) and, with ``friction``, every friction model
    (with the bilinear hydraulic part), keyed by model name. Each result with a Coulomb level
    carries ``extra["friction_check"]`` (:func:`friction_check`). ``friction=False``: the
    hydraulic models only (``mtbmj fit`` fits the friction models with the hydraulic law it
    chooses, ``refit_friction``). ``step()``, if given, is called after each fit (a progress
    bar: ``len(HYDRAULIC) + len(CHECK_SHAPES)`` calls, ``+ len(FRICTION)`` with ``friction``)."""
    rec = peaks(record)
    out = {}
    for name in MODELS if friction else HYDRAULIC:
        try:
            out[name] = fit_damper(rec, name)
        except DamperFitError:
            if name != "table":
                raise
        if step is not None:
            step()
    if "digressive" in out:
        out["digressive"].extra["friction_check"] = friction_check(rec, out["digressive"], step)
        _carry_friction_check(out)
    return out


def _carry_friction_check(results: dict[str, FitResult]) -> None:
    """Every fit with a Coulomb level carries the digressive fit's friction check (and its warning
    when the friction is not told)."""
    check = results["digressive"].extra["friction_check"]
    for result in results.values():
        if R + "coulomb_N" in result.values:
            result.extra["friction_check"] = check
            if not check["told"]:
                warnings = result.extra.setdefault("warnings", [])
                if check["line"] not in warnings:
                    warnings.append(check["line"])
                result.extra["friction_identified"] = False


def refit_friction(record: Record, results: dict[str, FitResult], hydraulic: str, step=None) -> None:
    """Fit every friction model (again) with the ``hydraulic`` law the fit writes (``linear``,
    ``bilinear`` or ``digressive``), so the friction models are compared, and the friction
    written, on the law that carries them, fitted together with it (on digressive data a bilinear
    law bends the friction to make up its shape). A friction law that cannot be fitted with it
    (``RecordError``: the solver did not converge) is left out, with a note on the hydraulic fit,
    rather than ending the fit. ``step()``: called after each fit."""
    rec = peaks(record)
    for name in FRICTION:
        done = results.get(hydraulic)
        if name == "coulomb" and done is not None and done.extra.get("friction") == "coulomb":
            results[name] = replace(done, model=name, extra=dict(done.extra))  # the same fit: not run twice
        else:
            try:
                results[name] = parametric_fit(rec, hydraulic, name, name)
            except RecordError as exc:  # one friction law that cannot be fitted here is left out, not fatal
                results.pop(name, None)
                if done is not None:
                    done.extra.setdefault("notes", []).append(f"{name} friction: not fitted with this law, left out "
                                                              f"of the comparison ({exc})")
        if step is not None:
            step()
    if "digressive" in results:
        _carry_friction_check(results)


def sign_band_floor(rec: Record, results: Mapping[str, FitResult]) -> float:
    """The residual RMS below which a damper fit counts as exact: the library's friction laws
    turn with tanh(v / ``BAND``), not with an exact step, so a record made with an exact friction
    step (a closed form, a dyno with a sharp turn) differs from every one of them by
    F (1 - tanh(|v| / band)) at each test speed, F the largest friction level fitted: at most
    7e-4 F at the speeds of ``MIN_WIDTH`` (4 bands) and up, the ones counted (slower, the band
    shapes the force itself). Residuals below that are no evidence between the laws
    (``run._choose``'s floor)."""
    speed = np.abs(np.asarray(rec["velocity"], float))
    level = max((float(r.values.get(R + k, 0.0)) for r in results.values() for k in ("coulomb_N", "breakaway_N")),
                default=0.0)
    short = np.where(speed >= MIN_WIDTH, 1.0 - np.tanh(speed / BAND), 0.0)
    return float(level * np.sqrt(np.mean(short ** 2)))


def friction_check(rec: Record, digressive: FitResult, step=None) -> dict:
    """Can the record tell the friction from the hydraulic law? A peak-force record shows the
    friction only as what is left at zero speed, extrapolated from its slowest test speeds by the
    hydraulic law. The digressive fit (a sharp knee) is refitted with other shapes of the force
    near zero speed (``CHECK_SHAPES``: a smooth tanh knee, a power law a v^n). The friction is told
    when the sharp knee is among the shapes the record does not reject (BIC within
    ``REJECTED_BIC`` of the best), all those shapes give friction levels within
    ``FRICTION_AGREEMENT`` of each other, and its interval excludes 0."""
    fits = {"sharp knee": digressive}
    for shape in CHECK_SHAPES:
        try:
            fits[shape.replace("_", " ")] = parametric_fit(rec, shape, "coulomb", shape)
        except RecordError:
            continue
        finally:
            if step is not None:
                step()
    best = min(f.bic for f in fits.values())
    # a shape the record rejects (BIC worse by REJECTED_BIC or more) is no alternative to weigh
    plausible = {name: f.values[R + "coulomb_N"] for name, f in fits.items() if f.bic - best < REJECTED_BIC}
    levels = list(plausible.values())
    sharp, se = digressive.values[R + "coulomb_N"], digressive.stderr[R + "coulomb_N"]
    agree = max(levels) - min(levels) <= FRICTION_AGREEMENT * max(levels)
    # told: the law written (the sharp knee) is among the shapes the record allows, they all agree,
    # and the level's interval excludes 0
    told = bool("sharp knee" in plausible and agree and sharp - 2.0 * se > 0.0)
    shown = ", ".join(f"{level:.1f} N with {'a ' if 'knee' in name else ''}{name}"
                      + ("" if name in plausible else " (rejected by the record)")
                      for name, level in ((n, f.values[R + "coulomb_N"]) for n, f in fits.items()))
    line = f"friction {'told' if told else 'NOT told'} from the hydraulic law: Coulomb {shown}"
    if not told:
        line += ("; the record cannot tell friction from how the damping approaches zero speed (record test speeds "
                 "below 25 mm/s, or measure the friction on its own); the value written rests on the law's shape")
    return {"told": told, "levels_N": {n: float(f.values[R + "coulomb_N"]) for n, f in fits.items()},
            "plausible": sorted(plausible), "line": line}


# adjuster labels of ``fit damper --clicks`` (riders' abbreviations) -> the config's circuit names
def select(results: Mapping[str, FitResult] | Iterable[FitResult]) -> FitResult:
    """The result with the lowest BIC (ties: fewer parameters, then the order given); a saturated
    model (``FitResult.saturated``) only when every model is."""
    items = list(results.values()) if isinstance(results, Mapping) else list(results)
    if not items:
        raise MtbmjError("select: no fit results to choose from")
    return min(enumerate(items), key=lambda t: (t[1].saturated, round(t[1].bic, 6), t[1].n_params, t[0]))[1]


def plot_damper(record: Record, results: Mapping[str, FitResult] | FitResult):
    """Peak force vs velocity in the style of the paper's Fig. 6: dyno points and fitted curves
    (left: hydraulic models; right: friction models near zero velocity)."""
    from matplotlib.figure import Figure

    if isinstance(results, FitResult):
        results = {results.model: results}
    rec = peaks(record)
    v, f = rec["velocity"] * 1e3, rec["force"]
    fig = Figure(figsize=(11, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    styles = {"linear": ("tab:green", "--"), "bilinear": ("tab:red", "-"), "digressive": ("tab:orange", "-"),
              "table": ("tab:purple", "-.")}
    for ax in (ax1, ax2):
        ax.plot(v, f, "o", ms=3, color="k", label="dyno peaks")
        ax.axhline(0, color="0.7", lw=0.6)
        ax.axvline(0, color="0.7", lw=0.6)
        ax.set_xlabel("velocity (mm/s, compression +)")
        ax.set_ylabel("force (N)")
        ax.grid(alpha=0.3)
    for name, r in results.items():
        if "curve" not in r.extra:
            continue
        if name in HYDRAULIC:
            color, ls = styles[name]
            ax1.plot(*r.extra["curve"], ls, color=color, lw=1.3, label=f"{name} (RMS {r.rms:.1f} N)")
        else:
            ax2.plot(*r.extra["curve"], lw=1.2, label=f"{name} (BIC {r.bic:.0f})")
    lim = max(0.15 * np.max(np.abs(v)), 60.0)
    near = np.abs(v) <= lim
    ax2.set_xlim(-lim, lim)
    if np.any(near) and np.max(np.abs(f[near])) > 0:
        span = np.max(np.abs(f[near]))
        ax2.set_ylim(-1.3 * span, 1.3 * span)
    ax1.set_title("damping: peak force vs velocity", fontsize=9)
    ax2.set_title("friction models near zero velocity", fontsize=9)
    ax1.legend(fontsize=7)
    ax2.legend(fontsize=7)
    synthetic = " (synthetic record)" if getattr(rec, "synthetic", False) else ""
    fig.suptitle(f"Fork damper{synthetic}", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["MODELS", "HYDRAULIC", "FRICTION", "DamperFitError", "peaks", "fit_damper", "fit_damper_all",
           "select", "plot_damper", "table_fit", "parametric_fit"]

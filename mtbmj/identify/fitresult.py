"""The result of one identification: values in configuration units, their uncertainty, the
residual, and the configuration keys a drop run accepts."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class FitResult:
    """One fitted model.

    ``values`` and ``stderr`` are keyed by configuration key (``fork.spring.rate_N_per_mm``) in
    the key's unit; ``rms`` is the residual RMS in ``residual_unit``; ``aic``/``bic`` compare
    models fitted to the same data (lower is better).
    """

    kind: str  # "spring", "damper", "tire", "drop"
    model: str  # e.g. "bilinear", "coulomb_viscous"
    values: dict[str, Any]
    stderr: dict[str, float]
    rms: float
    residual_unit: str
    n_points: int
    n_params: int
    extra: dict = field(default_factory=dict)  # model keys, curves for plots, correlation ...

    @property
    def aic(self) -> float:
        n = max(self.n_points, 1)
        return n * log_ms(self.rms) + 2 * self.n_params

    @property
    def bic(self) -> float:
        return self.bic_with_floor(0.0)

    def bic_with_floor(self, rms_floor: float) -> float:
        """BIC with the residual RMS taken as at least ``rms_floor`` (the data's resolution): fits
        better than the data can tell apart then count as equal, and only their size differs."""
        n = max(self.n_points, 1)
        return n * log_ms(max(self.rms, rms_floor)) + self.n_params * math.log(n)

    @property
    def saturated(self) -> bool:
        """As many parameters as half the points or more: the model can follow the points
        themselves, so its small residual is no evidence (never chosen by the criterion)."""
        return self.n_points < 2 * self.n_params

    def overrides(self) -> dict[str, Any]:
        """Configuration keys to apply: the fitted values plus the model choices."""
        out = dict(self.extra.get("model_keys", {}))
        out.update(self.values)
        return out

    def interval95(self, key: str) -> tuple[float, float] | None:
        """The 95 % interval of ``key``: the fit's own (``extra["ci95"]``) or value -/+ t x stderr
        (Student t on n_points - n_params); ``None`` where there is none or it means nothing (the
        value stopped at a bound, the model check failed)."""
        if not self.extra.get("ci95_meaningful", {}).get(key, True):
            return None
        if key in self.extra.get("ci95", {}):
            low, high = self.extra["ci95"][key]
            return float(low), float(high)
        err, value = self.stderr.get(key), self.values.get(key)
        if err is None or not np.isfinite(err) or not isinstance(value, (int, float)):
            return None
        from scipy import stats

        t = float(stats.t.ppf(0.975, max(self.n_points - self.n_params, 1)))
        return float(value - t * err), float(value + t * err)

    def line(self) -> str:
        """One line: each value with its 95 % interval (and its bounds, when the fit had any)."""
        parts = []
        bounds = self.extra.get("bounds", {})
        reached = self.extra.get("at_bound", {})
        for key, value in self.values.items():
            name = key.rsplit('.', 1)[-1]
            if isinstance(value, (tuple, list)):
                parts.append(f"{name} = [{len(value)} values]")
                continue
            interval = self.interval95(key)
            if interval is not None:
                unc = f" (95 % interval {interval[0]:.6g} to {interval[1]:.6g})"
            elif isinstance(reached, dict) and key in reached:
                unc = f" (AT ITS {reached[key].upper()} BOUND: no interval)"
            elif self.stderr.get(key) is not None:
                unc = " (no meaningful interval)"
            else:
                unc = ""
            span = f" [bounds {_bound_text(bounds[key][0])} to {_bound_text(bounds[key][1])}]" if key in bounds else ""
            parts.append(f"{name} = {value:.6g}{unc}{span}")
        label = self.extra.get("law", self.model)  # a damper fit: its hydraulic and friction laws
        return f"{self.kind} {label}: " + ", ".join(parts) + f"; residual RMS {self.rms:.4g} {self.residual_unit}"


def _bound_text(value: float) -> str:
    return f"{value:g}" if np.isfinite(value) else ("+inf" if value > 0 else "-inf")


def log_ms(rms: float) -> float:
    """log of the mean square residual, finite for a zero residual (noise-free data)."""
    return 2.0 * math.log(max(float(rms), 1e-150))


def covariance_stderr(jac: np.ndarray, residuals: np.ndarray, n_params: int) -> tuple[np.ndarray, np.ndarray]:
    """Standard errors and correlation from a least-squares Jacobian (Gauss-Newton covariance
    scaled by the residual variance)."""
    dof = max(len(residuals) - n_params, 1)
    sigma2 = float(residuals @ residuals) / dof
    jtj = jac.T @ jac
    cov = np.linalg.pinv(jtj) * sigma2
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    return std, np.nan_to_num(corr)


def andrews_bandwidth(scores: np.ndarray) -> float:
    """Bartlett-kernel bandwidth (in samples) from Andrews' (1991) AR(1) plug-in rule, fitted to
    each column of ``scores`` (time along axis 0): long when the residuals are coloured."""
    n = scores.shape[0]
    num = den = 0.0
    for x in scores.T:
        x = x - x.mean()
        denom = float(x[:-1] @ x[:-1])
        if denom <= 0.0:
            continue
        rho = float(np.clip((x[1:] @ x[:-1]) / denom, -0.99, 0.99))
        var = float(np.mean((x[1:] - rho * x[:-1]) ** 2))
        num += 4.0 * rho**2 * var**2 / ((1.0 - rho) ** 6 * (1.0 + rho) ** 2)
        den += var**2 / (1.0 - rho) ** 4
    if den == 0.0:
        return 0.0
    return float(min(1.1447 * (num / den * n) ** (1.0 / 3.0), n / 2.0))


def hac_covariance(jac: np.ndarray, residual: np.ndarray, n_params: int, n_channels: int = 1,
                   bandwidth: float | None = None) -> tuple[np.ndarray, dict]:
    """Parameter covariance of a least-squares fit whose residuals are correlated in time and
    across channels (Newey-West): cov = B S B, B = (J'J)^-1, S the Bartlett-weighted sum of the
    autocovariances of the scores g_t = sum over channels of J_ct' r_ct (residuals stacked by
    channel, ``n_channels`` blocks of equal length). ``bandwidth`` in samples: Andrews' plug-in
    by default. Returns (covariance, {"bandwidth_samples", "dof"})."""
    n = residual.size // n_channels
    r = residual.reshape(n_channels, n)
    blocks = jac.reshape(n_channels, n, -1)
    scores = np.einsum("cnp,cn->np", blocks, r)
    lag = andrews_bandwidth(scores) if bandwidth is None else float(bandwidth)
    meat = scores.T @ scores
    for k in range(1, int(np.floor(lag)) + 1):
        w = 1.0 - k / (lag + 1.0)
        gamma = scores[k:].T @ scores[:-k]
        meat += w * (gamma + gamma.T)
    dof = max(n - n_params, 1)
    meat *= n / dof
    bread = np.linalg.pinv(jac.T @ jac)
    return bread @ meat @ bread, {"bandwidth_samples": lag, "dof": dof}


def correlation(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(standard errors, correlation matrix) of a covariance."""
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    return std, np.nan_to_num(corr)


def correlated_pairs(keys, corr: np.ndarray, limit: float = 0.9) -> list[str]:
    """Notes on parameter pairs whose estimates are strongly correlated (|r| >= ``limit``)."""
    notes = []
    for i in range(len(keys)):
        for j in range(i + 1, len(keys)):
            if abs(corr[i, j]) >= limit:
                notes.append(f"{keys[i]} and {keys[j]} are correlated (r = {corr[i, j]:+.2f}): the record fixes "
                             "a combination of them better than each; their intervals are not independent")
    return notes


# --- what a fit must say about itself: its bounds and whether its model explains the data -------

# Default bounds of a free parameter with a start value (drop fits without --bound, the air spring
# fit): start / 4 to 4 x start (a positive or non-negative key), start -/+ 4 |start| (a signed one);
# see docs/identification.md
DEFAULT_BOUND_FACTOR = 4.0
BOUND_MARGIN = 0.01  # a value within 1 % of its bounds' span from a bound has stopped at it
MODEL_CHECK_FACTOR = 3.0  # a residual RMS above 3 x the record's noise floor (plus the allowance) fails


def bounds_reached(values: dict, bounds: dict, scales: dict | None = None) -> dict[str, str]:
    """``{key: "lower" | "upper"}`` for the values within ``BOUND_MARGIN`` of the span of their
    bounds ``(low, high)`` from one of them (or beyond it): the optimum may lie beyond, so the
    value and its interval say nothing about the truth. A bound pair open on one side (a rate
    bounded only by 0) has no span: there the margin is ``BOUND_MARGIN`` times ``scales[key]``
    (the fit's start, or the value itself)."""
    reached = {}
    for key, (low, high) in bounds.items():
        value = values.get(key)
        if value is None or isinstance(value, (tuple, list)):
            continue
        if np.isfinite(low) and np.isfinite(high):
            margin = BOUND_MARGIN * (high - low)
        else:
            scale = abs((scales or {}).get(key, 0.0)) or abs(value)
            margin = BOUND_MARGIN * scale
        if np.isfinite(low) and value <= low + margin:
            reached[key] = "lower"
        elif np.isfinite(high) and value >= high - margin:
            reached[key] = "upper"
    return reached


def bound_warnings(values: dict, bounds: dict, reached: dict[str, str], hint: str | None = None) -> list[str]:
    """One line per value that stopped at a bound. ``hint``: what the user can do (default: widen
    the bounds with ``--bound``; a bench fit's bounds are the law's physical limits instead)."""
    out = []
    for key, side in reached.items():
        low, high = bounds[key]
        what = hint if hint is not None else f"widen the bounds with --bound {key}=LOW:HIGH"
        out.append(f"{key} = {values[key]:.6g} stopped at its {side} bound {low if side == 'lower' else high:g} "
                   f"(bounds {low:g} to {high:g}): the optimum may lie beyond it, and its interval means nothing; "
                   f"{what}")
    return out


PHYSICAL_HINT = ("the bound is the law's physical limit, so the record asks for a value the law cannot take: "
                 "another model may serve (see the comparison in fit.json)")


def declare_bounds(result: "FitResult", bounds: dict, scales: dict | None = None, hint: str | None = PHYSICAL_HINT,
                   ) -> dict[str, str]:
    """Put a fit's bounds in the open: record them in ``result.extra["bounds"]`` (the free keys,
    in their configuration units; +/-inf where a side is open), the values that stopped at one in
    ``extra["at_bound"]`` with a warning line each, and withdraw those values' intervals
    (``extra["ci95_meaningful"]``). Returns the keys that stopped at a bound."""
    bounds = {k: (float(a), float(b)) for k, (a, b) in bounds.items() if k in result.values}
    reached = bounds_reached(result.values, bounds, scales)
    result.extra["bounds"] = bounds
    result.extra["bound_scales"] = dict(scales or {})
    result.extra["at_bound"] = reached
    warnings = result.extra.setdefault("warnings", [])
    warnings.extend(w for w in bound_warnings(result.values, bounds, reached, hint) if w not in warnings)
    meaningful = result.extra.setdefault("ci95_meaningful", {})
    for key in reached:
        meaningful[key] = False
    return reached


def json_bounds(bounds: dict) -> dict:
    """Bounds for JSON: an open side (+/-inf) as null."""
    return {k: [float(v) if np.isfinite(v) else None for v in pair] for k, pair in bounds.items()}


STRUCTURE_Z = 4.0  # runs test: this many standard deviations too few runs (p < 4e-5 for white residuals)


def runs_test(residual) -> dict | None:
    """Wald-Wolfowitz runs test of the residuals' signs about their median, in their order along
    the record (several channels: summed over the channels). White residuals make as many runs
    as chance (z about 0); a model that misses a shape leaves long runs (z strongly negative).
    Returns ``{"runs", "expected", "z", "lag1"}`` (``lag1``: the lag-1 autocorrelation), or
    ``None`` with fewer than 20 residuals."""
    segments = [np.asarray(r, float) for r in (residual if isinstance(residual, (list, tuple)) else [residual])]
    runs = expected = var = 0.0
    lag_num = lag_den = 0.0
    for r in segments:
        r = r[np.isfinite(r)]
        if r.size < 2:
            continue
        above = r > np.median(r)
        n1, n2 = float(np.sum(above)), float(np.sum(~above))
        n = n1 + n2
        if n1 == 0 or n2 == 0:
            continue
        runs += 1.0 + float(np.sum(above[1:] != above[:-1]))
        expected += 2.0 * n1 * n2 / n + 1.0
        var += 2.0 * n1 * n2 * (2.0 * n1 * n2 - n) / (n * n * (n - 1.0))
        c = r - r.mean()
        lag_num += float(c[1:] @ c[:-1])
        lag_den += float(c @ c)
    if sum(r.size for r in segments) < 20 or var <= 0.0:
        return None
    return {"runs": int(runs), "expected": float(expected), "z": float((runs - expected) / np.sqrt(var)),
            "lag1": float(lag_num / lag_den) if lag_den > 0 else 0.0}


def model_check(rms: float, noise: float, allowance: float, unit: str, worst: str, residual=None) -> dict:
    """Does the model explain the record? Two tests, either fails the check:

    - size: the residual RMS against ``MODEL_CHECK_FACTOR`` times the record's own noise floor
      plus ``allowance`` (what the model may differ by without being wrong: the engines'
      agreement, quantisation);
    - structure (with ``residual``, in record order; a list for several channels): the runs test
      finds the residuals' signs in runs no white noise makes (z below -``STRUCTURE_Z``) while
      the part of the residual that is not noise, sqrt(RMS^2 - noise^2), exceeds the noise plus
      the allowance: a systematic misfit at least as large as the noise.

    ``worst``: where the residual is largest."""
    limit = MODEL_CHECK_FACTOR * noise + allowance
    size_ok = bool(np.isfinite(rms) and rms <= limit)
    ratio = rms / noise if noise > 0 else float("inf")
    runs = runs_test(residual) if residual is not None else None
    excess = float(np.sqrt(max(rms * rms - noise * noise, 0.0))) if np.isfinite(rms) else float("inf")
    structured = bool(runs is not None and runs["z"] < -STRUCTURE_Z and excess > noise + allowance)
    passed = size_ok and not structured
    line = (f"model check {'passed' if passed else 'FAILED'}: residual RMS {rms:.4g} {unit} against the record's "
            f"noise floor {noise:.3g} {unit} ({ratio:.1f}x; limit {limit:.3g} {unit} = {MODEL_CHECK_FACTOR:g} x noise "
            f"+ {allowance:g})")
    if runs is not None:
        line += (f", residual runs {runs['runs']} against {runs['expected']:.0f} for white noise (z = {runs['z']:.1f}"
                 f"{': STRUCTURED' if structured else ''})")
    line += f"; largest {worst}"
    if not passed:
        line += ": the model does not explain this record, so its values and intervals do not describe it"
    return {"passed": passed, "rms": float(rms), "noise_floor": float(noise), "limit": float(limit),
            "ratio": float(ratio), "unit": unit, "largest": worst, "line": line,
            "size_passed": size_ok, "structure": runs, "structured": structured,
            "excess_over_noise": excess}

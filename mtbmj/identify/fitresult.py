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
            span = f" [bounds {bounds[key][0]:g} to {bounds[key][1]:g}]" if key in bounds else ""
            parts.append(f"{name} = {value:.6g}{unc}{span}")
        return f"{self.kind} {self.model}: " + ", ".join(parts) + f"; residual RMS {self.rms:.4g} {self.residual_unit}"


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

BOUND_MARGIN = 0.01  # a value within 1 % of its bounds' span from a bound has stopped at it
MODEL_CHECK_FACTOR = 3.0  # a residual RMS above 3 x the record's noise floor (plus the allowance) fails


def bounds_reached(values: dict, bounds: dict) -> dict[str, str]:
    """``{key: "lower" | "upper"}`` for the values within ``BOUND_MARGIN`` of the span of their
    bounds ``(low, high)`` from one of them: the optimum may lie beyond, so the value and its
    interval say nothing about the truth."""
    reached = {}
    for key, (low, high) in bounds.items():
        value = values.get(key)
        if value is None or not np.isfinite(low) or not np.isfinite(high):
            continue
        margin = BOUND_MARGIN * (high - low)
        if value <= low + margin:
            reached[key] = "lower"
        elif value >= high - margin:
            reached[key] = "upper"
    return reached


def bound_warnings(values: dict, bounds: dict, reached: dict[str, str]) -> list[str]:
    return [f"{key} = {values[key]:.6g} stopped at its {side} bound {bounds[key][0 if side == 'lower' else 1]:g} "
            f"(bounds {bounds[key][0]:g} to {bounds[key][1]:g}): the optimum may lie beyond it, and its interval "
            f"means nothing; widen the bounds with --bound {key}=LOW:HIGH"
            for key, side in reached.items()]


def model_check(rms: float, noise: float, allowance: float, unit: str, worst: str) -> dict:
    """Does the model explain the record? The residual RMS against ``MODEL_CHECK_FACTOR`` times
    the record's own noise floor plus ``allowance`` (what the model may differ by without being
    wrong: the engines' agreement, quantisation). ``worst``: where the residual is largest."""
    limit = MODEL_CHECK_FACTOR * noise + allowance
    passed = bool(np.isfinite(rms) and rms <= limit)
    ratio = rms / noise if noise > 0 else float("inf")
    line = (f"model check {'passed' if passed else 'FAILED'}: residual RMS {rms:.4g} {unit} against the record's "
            f"noise floor {noise:.3g} {unit} ({ratio:.1f}x; limit {limit:.3g} {unit} = {MODEL_CHECK_FACTOR:g} x noise "
            f"+ {allowance:g}); largest {worst}")
    if not passed:
        line += ": the model does not explain this record, so its values and intervals do not describe it"
    return {"passed": passed, "rms": float(rms), "noise_floor": float(noise), "limit": float(limit),
            "ratio": float(ratio), "unit": unit, "largest": worst, "line": line}

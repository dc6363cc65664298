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

    def line(self) -> str:
        parts = []
        for key, value in self.values.items():
            if isinstance(value, (tuple, list)):
                parts.append(f"{key.rsplit('.', 1)[-1]} = [{len(value)} values]")
                continue
            err = self.stderr.get(key)
            unc = f" +/- {err:.3g}" if err is not None and np.isfinite(err) else ""
            parts.append(f"{key.rsplit('.', 1)[-1]} = {value:.6g}{unc}")
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

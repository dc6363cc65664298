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
        return 2 * n * math.log(max(self.rms, 1e-300)) + 2 * self.n_params  # log(rms**2), no underflow

    @property
    def bic(self) -> float:
        n = max(self.n_points, 1)
        return 2 * n * math.log(max(self.rms, 1e-300)) + self.n_params * math.log(n)  # log(rms**2), no underflow

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

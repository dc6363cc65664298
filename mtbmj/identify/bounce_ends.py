"""What the whole-trace replay's fit says of its values together (``bounce_replay``, ``bounce_pooled``,
``bounce_slam_rebound``): the covariance of a least squares' values from its Jacobian, inflated for
the residual's lag-1 autocorrelation, and the correlations it gives; and the ends of the friction's
and compression's joint 95 % interval the rebound dampers are read again at (``joint_ends``).

**The joint ends.** The whole-trace replay's friction and its one damper (taken as the compression
by ``bounce_rebound``) trade: its Jacobian's covariance correlates them (``rho``,
``"friction_compression_correlation"`` in the replay's summary). Read again at each value's own ends
(the other held), a reading moves as if they were independent. Here the two are standardised by their
95 % half-widths above (h_f, h_c: the intervals' lower sides are cut at 0) and moved along the two
principal axes of their correlation matrix: **together** (both up, or both down) by sqrt((1 + rho) / 2)
of their half-widths, and **traded** (the friction up and the compression down, or the reverse) by
sqrt((1 - rho) / 2). Each axis' two ends are its own 95 % ends (1.96 of its standard deviation), the
two axes are uncorrelated, so a reading that is linear in the two moves at the axes' ends by its own
95 % move, the two axes' in quadrature, correlation included (with rho = 0 the same sum of squares as
each value's own ends). Values below 0 are cut to 0 (a friction and a damper are not negative).
"""
from __future__ import annotations

import numpy as np

from mtbmj.identify.bounce import lag1


def covariance(r: np.ndarray, J: np.ndarray, rho: float | None = None):
    """(covariance of the values, t-quantile factor): the Jacobian ``J`` (d residual / d value) with the
    residual's variance, inflated for its lag-1 autocorrelation (``rho``, or read from ``r``)."""
    from scipy.stats import t as student

    n, k = r.size, J.shape[1]
    rho = lag1(r) if rho is None else rho
    n_eff = max(n * (1 - rho) / (1 + rho), k + 2.0)
    s2 = float(r @ r) / max(n - k, 1) * n / n_eff
    cov = np.linalg.pinv(J.T @ J) * s2
    return cov, float(student.ppf(0.975, max(n_eff - k, 1.0)) / 1.959963984540054)


def correlations(cov: np.ndarray, names) -> dict:
    dev = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    return {f"{a}|{b}": float(cov[i, j] / (dev[i] * dev[j]))
            for i, a in enumerate(names) for j, b in enumerate(names) if i < j}


JOINT = ("friction_compression_together", "friction_compression_traded")  # the joint interval's two axes
CORRELATION = "friction_compression_correlation"  # the replay's summary: its friction's and damper's


def friction_compression_correlation(corr: dict | None) -> float | None:
    """The friction's and the damper's correlation in a replay's ``correlations`` (None where not read)."""
    if not corr:
        return None
    v = corr.get("damper_N_s_per_m|friction_N", corr.get("friction_N|damper_N_s_per_m"))
    return None if v is None or not np.isfinite(v) else float(v)


def joint_ends(best: dict) -> dict | None:
    """{axis (``JOINT``): [(friction, compression) at its lower end, at its upper end]} for the whole-trace
    replay ``best`` (its summary: friction and damper with their 95 % intervals and their correlation,
    ``CORRELATION``); None where the summary carries no correlation (module docstring)."""
    rho = best.get(CORRELATION)
    if rho is None:
        return None
    rho = float(np.clip(rho, -1.0, 1.0))
    f, c = float(best["friction_N"]), float(best["damper_N_s_per_m"])
    hf = float(best["friction_N_ci95"][1]) - f
    hc = float(best["damper_N_s_per_m_ci95"][1]) - c
    out = {}
    for name, sign, w in ((JOINT[0], 1.0, np.sqrt((1.0 + rho) / 2.0)), (JOINT[1], -1.0, np.sqrt((1.0 - rho) / 2.0))):
        # the traded axis' lower end: the friction down, the compression up
        out[name] = [(max(f - s * w * hf, 0.0), max(c - s * sign * w * hc, 0.0)) for s in (1.0, -1.0)]
    return out


__all__ = ["CORRELATION", "JOINT", "correlations", "covariance", "friction_compression_correlation", "joint_ends"]

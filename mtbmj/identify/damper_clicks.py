"""A damper's adjusters from dyno records at several settings: ``fit_clicks`` (one adjuster, a law
per position read through one model) and ``fit_settings`` (labelled positions of low- and
high-speed compression and rebound, combined additively around their reference), each giving a
``clicks`` damper that ``mtbmj.compose`` turns into a lookup table; ``plot_clicks`` draws them.
Each dyno file is fitted by the one-law fits of ``mtbmj.identify.damper``."""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from mtbmj import controllers as law
from mtbmj.identify.damper import (D, DIGRESSIVE_KEYS, MIN_NOISE_DOF, R, DamperFitError, damper_model_check, law_forces,
                                    parametric_fit, peaks, table_fit)
from mtbmj.identify.fitresult import FitResult, declare_bounds
from mtbmj.measured.records import Record

ADJUSTERS = {"lsc": "low_speed_compression", "hsc": "high_speed_compression", "lsr": "low_speed_rebound",
             "hsr": "high_speed_rebound", "c": "compression", "r": "rebound"}
STROKE_ADJUSTERS = {"compression": (("lsc", "hsc"), ("c",)), "rebound": (("lsr", "hsr"), ("r",))}


def fit_clicks(records: list[Record], clicks: list[float], model: str = "table") -> FitResult:
    """A ``clicks`` damper from dyno records taken at several adjuster positions (``clicks[i]``
    clicks from closed for ``records[i]``, compression and rebound adjusters alike); see
    ``fit_settings``. The setting written is the middle measured position."""
    if len(clicks) != len(records):
        raise DamperFitError(f"--clicks: {len(clicks)} positions for {len(records)} dyno files")
    clicks = [float(c) for c in clicks]
    if any(not math.isfinite(c) or c < 0 or c != round(c) for c in clicks) or len(set(clicks)) != len(clicks):
        raise DamperFitError("--clicks: positions must be distinct whole numbers of clicks from closed")
    return fit_settings(records, [{"c": c, "r": c} for c in clicks], model)


def _solve_additive(rows: np.ndarray, low: list[float], high: list[float]):
    """Least squares of F_i = g_low(low_i) + g_high(high_i) over the files (one column per
    velocity), g_high fixed to 0 at the high-speed reference; returns the low-speed rows (measured
    with the high-speed adjuster at its reference), the high-speed rows (low-speed adjuster at its
    reference), both position lists and both references. The reference of each adjuster is the
    position most files share (ties: the lowest)."""
    lows, highs = sorted(set(low)), sorted(set(high))
    l_ref = max(lows, key=lambda p: (low.count(p), -p))
    h_ref = max(highs, key=lambda p: (high.count(p), -p))
    columns = [("low", p) for p in lows] + [("high", p) for p in highs if p != h_ref]
    A = np.zeros((len(low), len(columns)))
    for i, (lo, hi) in enumerate(zip(low, high)):
        A[i, columns.index(("low", lo))] = 1.0
        if hi != h_ref:
            A[i, columns.index(("high", hi))] = 1.0
    if np.linalg.matrix_rank(A) < len(columns):
        raise DamperFitError("--clicks: the files do not tie every low-speed position to every high-speed one "
                             "(sweep each adjuster with the other at one shared position)")
    g = np.linalg.lstsq(A, rows, rcond=None)[0]
    g_low = g[:len(lows)]
    g_high = np.vstack([np.zeros(rows.shape[1]) if p == h_ref else g[columns.index(("high", p))] for p in highs])
    high_rows = g_low[lows.index(l_ref)] + g_high
    return g_low, high_rows, lows, highs, l_ref, h_ref


def _dissipative(rows: np.ndarray, stroke: str) -> np.ndarray:
    """Rows made to rise with velocity and keep the stroke's sign (noise and a least-squares
    split can leave small dips)."""
    rows = np.maximum.accumulate(rows, axis=1)
    return np.round(np.clip(rows, 0.0, None) if stroke == "compression" else np.clip(rows, None, 0.0), 3)


CLICKS_MODELS = ("table", "digressive")  # the law each dyno file of a clicks fit is read through


def fit_settings(records: list[Record], settings: list[Mapping[str, float]], model: str = "table") -> FitResult:
    """A ``clicks`` damper from dyno records each labelled with its adjuster settings in clicks from
    closed, by ``ADJUSTERS`` label: per stroke either one adjuster (``c``, ``r``) or a low- and a
    high-speed one (``lsc``/``hsc``, ``lsr``/``hsr``). Each record's lookup table (``table_fit``:
    Coulomb offset removed) is resampled on the velocities common to all of them. One adjuster:
    one row per position (the mean of files at the same position). Two: the additive model
    F = g_low(L) + g_high(H) fitted by least squares over the files (exact for one-at-a-time sweeps
    around a shared reference), written as each adjuster's rows with the other at its reference.
    The Coulomb level is the mean of the records' offsets (friction does not depend on the
    adjusters). The settings written are the references (two adjusters) or the middle position.

    ``model``: ``table`` (each file's rows are its own mean force per test speed) or
    ``digressive`` (each file fitted by the two-stage law with its Coulomb friction, and its rows
    the law's force at the common velocities: the law smooths each file, and its fit is checked
    against the file's noise). Either way each file's fit is checked against its own scatter at
    repeated test speeds (``damper_model_check``), and the worst file's check is the result's."""
    if model not in CLICKS_MODELS:
        raise DamperFitError(f"fit damper --clicks: --model {model} (one of {', '.join(CLICKS_MODELS)}); "
                             "each dyno file is read through that law")
    if len(settings) != len(records):
        raise DamperFitError(f"--clicks: {len(settings)} settings for {len(records)} dyno files")
    if len(records) < 2:
        raise DamperFitError("fit damper --clicks: give at least two dyno files taken at different positions")
    for label in settings:
        unknown = sorted(set(label) - set(ADJUSTERS))
        if unknown:
            raise DamperFitError(f"--clicks: unknown adjuster {unknown[0]!r} (use {', '.join(ADJUSTERS)})")
        if any(not math.isfinite(v) or v < 0 or v != round(v) for v in label.values()):
            raise DamperFitError("--clicks: positions must be whole numbers of clicks from closed")
    seen = {}  # one dyno file twice (or a copy) would be one test read at two settings: no change in clicks
    for k, rec in enumerate(records):
        first = seen.setdefault(tuple((q, np.asarray(v, float).tobytes()) for q, v in rec.columns.items()), k)
        if first != k:
            at = [f"{settings[i]['c']:g} clicks" if settings[i].keys() == {"c", "r"} and settings[i]["c"] == settings[i]["r"]
                  else ",".join(f"{a}={v:g}" for a, v in settings[i].items()) for i in (first, k)]
            raise DamperFitError(f"{rec.path}: the same record as {records[first].path} (the same values), labelled "
                                 f"{at[0]} and {at[1]}: one test read at two settings would say the adjuster changes "
                                 f"nothing; give each setting's file once")
    points = [peaks(r) for r in records]
    tables = [table_fit(r) for r in points]
    fits = tables if model == "table" else [parametric_fit(r, "digressive", "coulomb", "digressive") for r in points]
    grids = [np.asarray(f.values[D + "velocity_mm_per_s"]) for f in tables]
    if len({len(g) for g in grids}) != 1 or any(np.any(np.sign(g) != np.sign(grids[0])) for g in grids):
        raise DamperFitError("fit damper --clicks: the dyno files do not share their test speeds "
                             f"({', '.join(str(len(g)) for g in grids)} velocities)")
    grid = np.round(np.mean(grids, axis=0), 3)
    if model == "table":
        rows = np.array([np.interp(grid, g, f.values[D + "force_N"]) for g, f in zip(grids, fits)])
    else:  # the law's hydraulic force (no friction) at the common velocities
        rows = np.array([law_forces(_digressive_law(f), grid * 1e-3) for f in fits])
    values: dict[str, Any] = {D + "velocity_mm_per_s": tuple(float(x) for x in grid)}
    described = []
    for stroke, side in (("compression", grid > 0), ("rebound", grid < 0)):
        pair, single = STROKE_ADJUSTERS[stroke]
        kinds = {tuple(a for a in pair + single if a in label) for label in settings}
        if kinds == {pair}:
            low = [float(label[pair[0]]) for label in settings]
            high = [float(label[pair[1]]) for label in settings]
            low_rows, high_rows, lows, highs, l_ref, h_ref = _solve_additive(rows[:, side], low, high)
            for name, table, positions, ref, setting in ((pair[0], low_rows, lows, l_ref, l_ref),
                                                         (pair[1], high_rows, highs, h_ref, h_ref)):
                key = D + ADJUSTERS[name]
                values.update({key + "_clicks_measured": tuple(positions),
                               key + "_force_N": tuple(tuple(float(x) for x in r)
                                                       for r in _dissipative(np.atleast_2d(table), stroke)),
                               key + "_reference_clicks": ref, key + "_clicks": setting})
            described.append(f"{stroke}: {len(lows)} low-speed and {len(highs)} high-speed positions "
                             f"around {l_ref:g}/{h_ref:g} clicks")
        elif kinds == {single}:
            at = [float(label[single[0]]) for label in settings]
            positions = sorted(set(at))
            table = np.vstack([np.mean([r for r, p in zip(rows[:, side], at) if p == q], axis=0) for q in positions])
            values.update({D + f"{stroke}_clicks_measured": tuple(positions),
                           D + f"{stroke}_force_N": tuple(tuple(float(x) for x in r)
                                                          for r in _dissipative(table, stroke)),
                           D + f"{stroke}_clicks": positions[(len(positions) - 1) // 2]})
            described.append(f"{stroke}: {len(positions)} positions")
        else:
            raise DamperFitError(f"--clicks: label every file's {stroke} adjuster(s) the same way, either "
                                 f"{single[0]}=N or {pair[0]}=N,{pair[1]}=N")
    coulomb = float(np.mean([f.values[R + "coulomb_N"] for f in fits]))
    values[R + "coulomb_N"] = coulomb
    n_points = sum(f.n_points for f in fits)
    rms = float(np.sqrt(sum(f.rms ** 2 * f.n_points for f in fits) / n_points))
    stderr = {R + "coulomb_N": float(np.std([f.values[R + "coulomb_N"] for f in fits], ddof=1)
                                     / math.sqrt(len(fits)))}
    labels = [",".join(f"{k}={v:g}" for k, v in label.items()) for label in settings]
    checks = []
    warnings = []
    for label, rec, fit in zip(labels, points, fits):
        check = damper_model_check(rec, fit)  # the clicks fit's check (worst file), attached below
        if check is not None:
            checks.append((label, check))
        warnings += [f"file at {label}: {w}" for w in fit.extra.get("warnings", []) if "friction" not in w]
    result = FitResult("damper", "clicks", values, stderr, rms, "N", n_points, sum(f.n_params for f in fits),
                     {"model_keys": {D + "model": "clicks", R + "model": "coulomb"}, "supported": True,
                      "law": model, "warnings": warnings,
                      **({"model_check": _worst_file(checks)} if checks else {}),
                      "curves": [(lab, f.extra["curve"]) for lab, f in zip(labels, fits)],
                      "notes": [f"{len(records)} dyno files on {len(grid)} common velocities; "
                                + "; ".join(described) + f"; Coulomb offset {coulomb:.1f} N (mean of the files)"]})
    declare_bounds(result, {R + "coulomb_N": (0.0, np.inf)}, {R + "coulomb_N": stderr[R + "coulomb_N"]})
    if model == "digressive":
        result.extra["per_file"] = {label: f.values for label, f in zip(labels, fits)}
        result.extra["notes"].append("each file read through the two-stage (digressive) law: " + "; ".join(
            f"{label}: knees {f.values[D + 'compression_knee_mm_per_s']:.0f}/{f.values[D + 'rebound_knee_mm_per_s']:.0f} "
            f"mm/s, Coulomb {f.values[R + 'coulomb_N']:.1f} N" for label, f in zip(labels, fits)))
    if not checks:
        result.extra["notes"].append(f"no model check: no file has {MIN_NOISE_DOF} repeated points at its test speeds "
                                     "to tell its noise")
    return result


def _digressive_law(fit: FitResult) -> law.DigressiveDamper:
    """The two-stage law of a digressive fit (its values in configuration units)."""
    return law.DigressiveDamper(*(fit.values[D + k] * (1e-3 if k.endswith("mm_per_s") else 1.0)
                                  for k in DIGRESSIVE_KEYS))


def _worst_file(checks: list[tuple[str, dict]]) -> dict:
    """The model check of a clicks fit: the file whose residual is largest against its noise,
    failed when any file's fails."""
    label, worst = max(checks, key=lambda c: (not c[1]["passed"], c[1]["ratio"]))
    out = dict(worst)
    out["passed"] = all(c["passed"] for _, c in checks)
    out["line"] = f"file at {label} (the worst of {len(checks)}): " + worst["line"]
    out["per_file"] = {lab: {"passed": c["passed"], "ratio": c["ratio"]} for lab, c in checks}
    return out


def plot_clicks(records: list[Record], result: FitResult):
    """Each dyno file's peak points and its table, coloured by the file's adjuster settings."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure  # the object API: the caller's backend is left alone

    fig = Figure(figsize=(7.5, 4.5))
    ax = fig.subplots()
    colours = colormaps["viridis"](np.linspace(0, 0.9, len(records)))
    for rec, (label, curve), colour in zip(records, result.extra["curves"], colours):
        pts = peaks(rec)
        ax.plot(pts["velocity"] * 1e3, pts["force"], "o", ms=3, color=colour)
        ax.plot(*curve, "-", color=colour, lw=1.2, label=f"{label} (clicks from closed)")
    ax.axhline(0, color="0.7", lw=0.6)
    ax.axvline(0, color="0.7", lw=0.6)
    ax.set_xlabel("velocity (mm/s, compression +)")
    ax.set_ylabel("force (N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    synthetic = " (synthetic records)" if any(getattr(r, "synthetic", False) for r in records) else ""
    ax.set_title(f"Fork damper by adjuster position{synthetic}", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["fit_clicks", "fit_settings", "ADJUSTERS", "STROKE_ADJUSTERS", "CLICKS_MODELS", "plot_clicks"]

"""The whole model from a sled drop record: chosen free parameters of a configuration fitted to
the sled, fork and tire traces by bounded nonlinear least squares.

The residual is model - data of the sled, fork and (when recorded) tire displacement in mm at the
record's time stamps; the model is ``run_drop`` on either engine, its 1 kHz logged signals (the
same 400 Hz anti-aliasing view the sled logger has) interpolated onto the record's times. The
Jacobian is a forward difference with a relative step (1e-3 by default: the drop is smooth in its
parameters there -- steps of 1e-4 and 1e-3 agree to about 0.1 %, 1e-2 already bends), one engine
run per column. On the MuJoCo engine its parameter points (with the base point when it is not
known yet) run as one batch through ``mtbmj.drop.engine_batch.drop_traces`` (``mujoco.rollout`` on the
compiled laws, ``workers`` threads, bit-identical to ``run_drop``); on the ODE engine (or without
the compiled laws) the columns run in a pool of ``workers`` processes (2 by default). With
``starts=N`` the fit runs from the configuration's start values and N - 1 Latin hypercube points
within the bounds (their first evaluations batched together); the lowest final cost wins.

Time zero comes from ``mtbmj.measured.time_zero`` (the rule ``mtbmj validate`` uses): a record with a
free fall on any clock, or one that starts at impact, or ``touch_s`` given. The fit starts
``FIT_FROM_S`` after touch: before, a real logger's filter still carries the free fall, which the
model's logger (started at touch) does not see.

Confidence intervals (95 %) and the correlation matrix: the residuals are not white (the 400 Hz
filter colours the noise; sled, fork and tire share the pots; the engine has its own error), so
the covariance is the Newey-West sandwich of the scores over time (``fitresult.hac_covariance``,
Bartlett bandwidth by Andrews' rule, channels pooled per time stamp), plus the squares of two
biases carried to the parameters through the Jacobian: the engine's own error (the other engine
run once at the optimum, ``engine_error``: for the MuJoCo and the fast engines the reference's
equations stepped finely by the fast engine, for the ODE reference MuJoCo; ``OTHER_ENGINE``) and one
standard error of the touch time. The Student t
quantile uses the effective number of independent samples (time samples / bandwidth).
``extra["stderr_white"]`` keeps the white-in-time channel sandwich, ``extra["stderr_iid"]`` the
plain ``covariance_stderr``. ``benchmarks/interval_coverage.py`` measures the coverage. The intervals
assume the configuration's laws are right.

Why ``scipy.optimize.least_squares`` and not ``mujoco.minimize.least_squares``: both are bounded
Gauss-Newton/Levenberg-Marquardt type solvers that finite-difference a residual, and mujoco's
has a nice batched-residual interface that would suit a parallel Jacobian just as well. We chose
scipy on the merits for this problem:
  * the free parameters span six orders of magnitude in config units (a cubic spring term of
    3e-4 N/mm^3 next to a 200 N preload); scipy takes a relative finite-difference step per
    parameter (``diff_step``; here our own parallel Jacobian uses the same rule), while mujoco's
    ``jacobian_fd`` uses one step eps * max(1, |x|), i.e. an absolute step for small parameters
    that would have to be rescaled by hand;
  * the fit must run on both engines, including the scipy ODE reference, which has nothing to do
    with MuJoCo; scipy's solver is the engine-neutral one;
  * scipy returns the Jacobian at the solution, the active bound mask, the number of function and
    Jacobian evaluations and a termination status with a message in one result object, which is
    what the confidence intervals and the report need; it is also the long-established,
    widely-used implementation (trust-region reflective for bounds) with documented tolerances.
mujoco.minimize would be the natural choice for derivatives through MuJoCo itself
(``mjd_transitionFD``) or a C-batched rollout; neither applies to a Python-callback model
compared against 1 kHz logged data.
"""
from __future__ import annotations

import contextlib
import multiprocessing
import os
import time
from typing import Mapping, Sequence

import numpy as np
from scipy import optimize, stats
from scipy.stats import qmc

from mtbmj.config import ALTERNATIVES, CANONICAL, SCHEMA, Config
from mtbmj.controllers import jit as _jit, native
from mtbmj.drop.chain import resolve
from mtbmj.drop.run import run_drop
from mtbmj.errors import ConfigError, MtbmjError

from mtbmj.identify.fitresult import (DEFAULT_BOUND_FACTOR, FitResult, bound_warnings, bounds_reached, correlated_pairs, correlation,
                                      covariance_stderr, hac_covariance, model_check)
from mtbmj.measured.records import Record, read_record
from mtbmj.measured import sled as sled_data
from mtbmj.workers import process_pool

CHANNELS = ("sled", "fork", "tire")
FIT_FROM_S = 0.005  # fitted from 5 ms after touch: before, a logger's filter still carries the free fall
# the run at the optimum that measures the fitting engine's own error. The fast engine integrates
# the ODE reference's equations themselves, so its own error is its discretisation: measured by the
# same equations stepped REFINE_FAST times finer everywhere ("fast_refined"), the difference scaled
# by k / (k - 1): the whole error where it falls as the step (near a kink of the friction law), twice
# it where it falls as the step's fourth power. That refined run is also what MuJoCo's error is
# measured against: at S12 away from its defaults it is 0.3 um from the ODE reference's own run
# (whose tolerance shows there), MuJoCo 1.2 um from the reference and 0.9 um from it; it costs a
# tenth of the reference's run. Without numba, or (for MuJoCo) where the fast engine would have to be
# compiled first, the reference's run (error_engine). The ODE fit is measured against MuJoCo.
# tests/test_dropfit_engine_error.py
OTHER_ENGINE = {"mujoco": "fast_refined", "ode": "mujoco", "fast": "fast_refined"}
REFINE_FAST = 2
ERROR_SCALE = {"fast": REFINE_FAST / (REFINE_FAST - 1)}
ERROR_RUNS = {"fast_refined": "the fast engine stepped twice as finely", "ode": "the ODE reference",
              "mujoco": "MuJoCo"}  # how a fit's report names the run that measured its engine's error
# keys that take whole numbers (spacers, adjuster clicks): a least-squares step cannot move them
WHOLE_NUMBER_KEYS = ("fork.spring.tokens",)
# the relative accuracy a drop record can fix a parameter to, whatever its noise: the model's own
# fidelity (benchmarks/model_check.py measured the engines 0.005 % +/- 0.005 % off an independent
# closed-form generator on the spring rate); see docs/identification.md
MODEL_FLOOR_REL = 1e-4
MODEL_CHECK_ALLOWANCE_MM = 0.1  # the crosscheck tolerance: what the engines may differ by without the model being wrong
IMPACT_SPEED_TOLERANCE = 0.05  # the record's impact speed vs the drop height's: beyond 5 %, they disagree
MODEL_KEYS = ("fork.spring.model", "fork.spring.top_out", "fork.spring.preload", "fork.damper.model",
              "fork.friction.model", "tire.model")

def error_engine(engine: str) -> str:
    """The run that measures ``engine``'s own error (``OTHER_ENGINE``). For a fit on another engine
    than the fast one, its refined run only where the fast engine's compiled code is loaded or in
    numba's disk cache: compiling it (about 10 s, and in every process of an install without a
    cache directory) would cost more than the ODE reference's run, which is taken instead."""
    other = OTHER_ENGINE[engine]
    if other != "fast_refined" or engine == "fast":
        return other
    if _jit.numba is None:
        return "ode"
    from mtbmj.drop import engine_fast

    return other if engine_fast.ready() else "ode"


def error_note(extra: Mapping) -> str:
    """How a fit's report says what measured its engine's own error (``extra`` of ``fit_drop``)."""
    run = extra.get("engine_error_run")
    if run is None:
        return "not measured: the run at the optimum failed or was not asked for"
    scale = ERROR_SCALE.get(extra.get("engine"), 1.0)  # as fit_drop scaled the difference
    scaled = "" if scale == 1.0 else ", its difference doubled" if scale == 2.0 else f", its difference times {scale:g}"
    return f"against {ERROR_RUNS[run]} at the optimum{scaled}"


# --- the model run (module level so worker processes can call it) ------------------------------

_WORKER: dict = {}


def _init_worker(config: Config, engine: str, duration: float, times: np.ndarray, channels: tuple) -> None:
    _WORKER.update(config=config, engine=engine, duration=duration, times=times, channels=channels)


def _model(values: Sequence[float], keys: Sequence[str], config: Config | None = None, engine: str | None = None,
           duration: float | None = None, times: np.ndarray | None = None, channels: tuple | None = None):
    """Model signals (mm) of the channels at ``times`` for the free values; None if the run fails."""
    w = _WORKER
    config = config if config is not None else w["config"]
    engine = engine or w["engine"]
    duration = duration if duration is not None else w["duration"]
    times = times if times is not None else w["times"]
    channels = channels or w["channels"]
    overrides = dict(zip(keys, map(float, values)))
    try:
        if engine in ("fast", "fast_refined"):
            refine = REFINE_FAST if engine == "fast_refined" else 1
            return _sample(_fast_signals(config, overrides, duration, channels, refine), times, channels)
        native.expect_many()  # a fit's runs repay loading the compiled laws
        result = run_drop(config, engine, overrides=overrides, duration=duration)
    except MtbmjError as exc:
        return str(exc)
    return _sample(result.signals, times, channels)


def _fast_signals(config: Config, overrides: Mapping, duration: float, channels: tuple, refine: int = 1) -> dict:
    """The logged channels of ``run_drop(config, "fast", overrides, duration)`` (the same numbers),
    without what a fit does not read: the other signals and the summary; ``refine`` > 1 steps the
    same equations finer (``engine_fast.run``)."""
    from mtbmj.drop import chain, engine_fast

    _, setup = chain.prepare(config, overrides, duration, warn=False)
    trace = engine_fast.run(setup, duration, refine=refine)
    return chain.finish(setup, trace, "fast", channels=channels, summary=False).logged


def _sample(signals: Mapping, times: np.ndarray, channels: tuple) -> np.ndarray:
    """The channels of logged ``signals`` interpolated onto ``times``, stacked (mm)."""
    t = signals["time_s"]
    return np.concatenate([np.interp(times, t, signals[f"{c}_mm"]) for c in channels])


def _shifted(model: np.ndarray, times: np.ndarray, n_channels: int, shift_s: float) -> np.ndarray:
    """The stacked channels of ``model`` read ``shift_s`` later (linear interpolation)."""
    parts = model.reshape(n_channels, times.size)
    return np.concatenate([np.interp(times + shift_s, times, p) for p in parts])


def channel_sandwich(jac: np.ndarray, residual: np.ndarray, n_params: int, n_channels: int):
    """Standard errors and correlation for residuals stacked by channel, white in time but
    correlated across channels at each time stamp (the tire trace is sled - fork of the same
    pots, so its noise is not independent of theirs): cov = B M B with B = (J'J)^-1 and
    M = sum over channel pairs of S[c, c'] J_c' J_c', S the channel covariance of the residuals.
    With independent channels of equal noise this is ``covariance_stderr``."""
    n = residual.size // n_channels
    r = residual.reshape(n_channels, n)
    dof = max(n - n_params / n_channels, 1.0)
    s = r @ r.T / dof
    blocks = jac.reshape(n_channels, n, -1)
    bread = np.linalg.pinv(jac.T @ jac)
    meat = sum(s[a, b] * blocks[a].T @ blocks[b] for a in range(n_channels) for b in range(n_channels))
    cov = bread @ meat @ bread
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    return std, np.nan_to_num(corr)


def _as_record(record: Record | str | os.PathLike) -> Record:
    return record if isinstance(record, Record) else read_record(record)


def default_bounds(key: str, start: float) -> tuple[float, float]:
    """The bounds of a free parameter given none: ``start / 4`` to ``4 x start`` for a positive or
    non-negative key (a rate, a mass, a preload), ``start -/+ 4 |start|`` for a signed one; a start
    of 0 has no scale, so it needs ``--bound``."""
    if start == 0.0:
        raise ConfigError(f"{key}: start value is 0, so it sets no scale for default bounds; give them with "
                          f"--bound {key}=LOW:HIGH")
    if SCHEMA.get(key) in ("pos", "nonneg") and start > 0.0:
        return start / DEFAULT_BOUND_FACTOR, start * DEFAULT_BOUND_FACTOR
    return start - DEFAULT_BOUND_FACTOR * abs(start), start + DEFAULT_BOUND_FACTOR * abs(start)


def start_value(cfg: Config, key: str) -> float:
    """The start of free key ``key``: its value in ``cfg``, in the key's own unit. A key in a
    rider's unit (``fork.spring.rate_lb_per_in``, ``config.ALTERNATIVES``) is read from the
    canonical key a configuration stores it under (a file that sets ``rate_lb_per_in`` holds
    ``rate_N_per_mm`` once loaded), so either key of the pair can be freed on either."""
    canonical, per = ALTERNATIVES.get(key, (key, 1.0))
    if canonical in cfg.values:
        return float(cfg.values[canonical]) / per
    other = CANONICAL.get(key) or (canonical if canonical != key else None)
    given = f"{key} or {other}" if other else key
    raise ConfigError(f"{key}: missing (a free parameter needs a start value: set {given} in the configuration, "
                      f"or --set {key}=VALUE)")


def same_quantity(free: Sequence[str]) -> None:
    """Refuse two free keys that are one value in two units (``rate_N_per_mm`` and
    ``rate_lb_per_in``): the fit could not move them apart."""
    seen: dict[str, str] = {}
    for key in free:
        canonical = ALTERNATIVES.get(key, (key, 1.0))[0]
        if canonical in seen:
            raise ConfigError(f"{seen[canonical]} and {key}: the same value in two units; free one of them")
        seen[canonical] = key


def noise_floor(aligned, channels: Sequence[str], keep: np.ndarray) -> float:
    """The record's own noise (mm, RMS over the fitted channels): each channel's white noise from
    its third differences (``mtbmj.measured.peaks.noise_sigma``, robust to the impact's few steep
    samples) over the fitted stretch."""
    from mtbmj.measured.peaks import noise_sigma

    sigmas = [noise_sigma(getattr(aligned, f"{c}_mm")[keep]) for c in channels]
    return float(np.sqrt(np.mean(np.square(sigmas))))


def impact_speed_check(aligned, cfg: Config, free: Sequence[str]) -> dict | None:
    """The impact speed the record's free fall shows against the configuration's drop height:
    ``None`` without a fall in the record; a ``line`` when they disagree by more than
    ``IMPACT_SPEED_TOLERANCE`` (the drop height is then not the record's)."""
    touch = aligned.touch
    if touch is None or touch.impact_speed_m_per_s is None:
        return None
    g = float(cfg.get("sled.gravity_m_per_s2", 9.81))
    height_mm = float(cfg["sled.drop_height_mm"])
    expected = float(np.sqrt(2.0 * g * height_mm * 1e-3))
    measured = float(touch.impact_speed_m_per_s)
    implied_mm = measured**2 / (2.0 * g) * 1e3
    out = {"record_m_per_s": measured, "config_m_per_s": expected, "config_drop_height_mm": height_mm,
           "implied_drop_height_mm": implied_mm, "agree": True}
    if expected > 0 and abs(measured - expected) > IMPACT_SPEED_TOLERANCE * expected:
        out["agree"] = False
        fitted = "sled.drop_height_mm" in free
        out["line"] = (f"the record's free fall reaches {measured:.3f} m/s at touch, a drop from {implied_mm:.0f} mm; "
                       f"the configuration drops from {height_mm:g} mm ({expected:.3f} m/s)"
                       + ("" if fitted else f": give --set sled.drop_height_mm={implied_mm:.0f}, or fit it with "
                                            f"--free ...,sled.drop_height_mm"))
    return out


def fit_drop(record: Record | str | os.PathLike, config: Config | str = "S12", free: Sequence[str] = (),
             bounds: Mapping[str, tuple[float, float]] | None = None, engine: str = "mujoco",
             overrides: Mapping | None = None, workers: int = 2, diff_step: float = 1e-3,
             max_nfev: int = 40, xtol: float = 1e-6, ftol: float = 1e-8,
             progress=None, starts: int = 1, seed: int = 0, batched: bool | None = None,
             touch_s: float | None = None, engine_error: bool = True) -> FitResult:
    """Fit the ``free`` configuration keys of ``config`` (with ``overrides``) to a sled drop record.

    ``bounds`` maps a free key to (low, high) in its config unit; unlisted keys get
    :func:`default_bounds` (start / 4 to 4 x start). A value that ends within 1 % of the span from
    a bound is reported in ``extra["at_bound"]`` and ``extra["warnings"]``, its interval marked not
    meaningful (``extra["ci95_meaningful"]``); ``extra["model_check"]`` compares the residual with
    the record's noise floor, ``extra["impact_speed"]`` its free fall with the drop height. Returns a ``FitResult`` with values keyed by the free keys, and in
    ``extra``: ``ci95``, ``correlation`` (with ``correlation_keys``), ``engine_runs``,
    ``model_keys``, ``start``, ``bounds``, ``wall_time_s``, ``status`` and ``curves`` for plots.

    ``starts``: the number of fits (the start values, then Latin hypercube points in the bounds
    drawn with ``seed``); the one with the lowest final cost is returned, ``extra["starts"]``
    lists each. ``batched``: evaluate the Jacobian's points as one ``mujoco.rollout`` batch
    (default: on the MuJoCo engine when the compiled laws are available).
    """
    start_time = time.perf_counter()
    rec = _as_record(record)
    aligned = sled_data.from_record(rec, touch_s=touch_s)  # the one time-zero rule (mtbmj.measured.time_zero)
    channels = ("sled", "fork") + (() if aligned.tire_computed else ("tire",))
    cfg = resolve(config, overrides)
    free = list(free)
    if not free:
        raise ConfigError("fit_drop: no free parameters given")
    if len(set(free)) != len(free):
        raise ConfigError("fit_drop: a free parameter is listed twice")
    same_quantity(free)
    for key in bounds or {}:
        if key not in free:
            raise ConfigError(f"--bound {key}: not a free parameter (free: {', '.join(free)}); add it to --free "
                              f"or drop the bound")
    x0, lo, hi = [], [], []
    for key in free:
        if key not in SCHEMA:
            raise ConfigError(f"{key}: unknown key (free parameters are configuration keys)")
        if SCHEMA[key] not in ("pos", "nonneg", "real"):
            raise ConfigError(f"{key}: only numeric scalar keys can be free parameters")
        if key in WHOLE_NUMBER_KEYS or key.endswith("_clicks"):
            raise ConfigError(f"{key}: takes whole numbers, which a least-squares fit cannot step through; run each "
                              f"setting instead (mtbmj sweep CONFIG --vary {key}=LOW:HIGH:N) and compare")
        value = start_value(cfg, key)
        low, high = default_bounds(key, value) if not (bounds and key in bounds) else map(float, bounds[key])
        if not (np.isfinite(low) and np.isfinite(high)):
            raise ConfigError(f"{key}: bounds ({low:g}, {high:g}) must be finite numbers")
        if not low < high:
            raise ConfigError(f"{key}: bounds ({low:g}, {high:g}) are empty (the low bound must be below the high one)")
        if SCHEMA[key] == "pos" and low <= 0.0:
            raise ConfigError(f"{key}: lower bound {low:g} must be positive")
        if SCHEMA[key] == "nonneg" and low < 0.0:
            raise ConfigError(f"{key}: lower bound {low:g} must not be negative")
        if not low <= value <= high:
            raise ConfigError(f"--bound {key}={low:g}:{high:g}: excludes the start value {value:g}; start inside "
                              f"the bounds (--set {key}=VALUE) or widen them")
        x0.append(value)
        lo.append(low)
        hi.append(high)
    x0, lo, hi = np.array(x0), np.array(lo), np.array(hi)
    keep = aligned.time_s >= FIT_FROM_S - 1e-9
    times = aligned.time_s[keep]
    if times.size < 20:
        raise MtbmjError(f"{rec.path}: too few points after touch to fit ({times.size})")
    data = np.concatenate([getattr(aligned, f"{c}_mm")[keep] for c in channels])
    duration = float(times[-1]) + 0.003
    scale = np.maximum(np.abs(x0), 1e-3 * (hi - lo))
    runs = {"n": 0}
    cache: dict[bytes, np.ndarray | str] = {}  # model (or a failed run's reason) by point
    penalty = 1e3  # mm: a failed run (e.g. a preload the top-out spring cannot hold) is far off
    starts = max(1, int(starts))
    workers = max(1, int(workers))
    if batched is None:
        from mtbmj.controllers import compiled

        batched = engine == "mujoco" and compiled.available()
    if batched and engine != "mujoco":
        raise ConfigError("fit_drop: the batched path runs the mujoco engine only")

    def to_residual(model):
        if isinstance(model, str):
            return np.full(data.size, penalty)
        return model - data

    context = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    pool = (process_pool(workers, _init_worker, (cfg, engine, duration, times, channels), context)
            if workers > 1 and not batched else None)

    def evaluate(points) -> list[np.ndarray]:
        """Residuals at ``points``; the ones not known yet run together (one batch or the pool)."""
        new = list({p.tobytes(): p for p in points if p.tobytes() not in cache}.values())
        if len(new) == 1:
            models = [_model(new[0], free, cfg, engine, duration, times, channels)]
        elif new and batched:
            from mtbmj.drop.engine_batch import drop_traces

            out = drop_traces(cfg, [dict(zip(free, map(float, p))) for p in new], duration, threads=workers)
            models = [m if isinstance(m, str) else _sample(m, times, channels) for m in out]
        elif new and pool is not None:
            models = list(pool.map(_model, new, [free] * len(new)))
        else:
            models = [_model(p, free, cfg, engine, duration, times, channels) for p in new]
        for p, m in zip(new, models):
            runs["n"] += 1
            cache[p.tobytes()] = m
            if progress:
                progress(runs["n"], p, float(np.sqrt(np.mean(to_residual(m) ** 2))))
        return [to_residual(cache[p.tobytes()]) for p in points]

    def fun(x):
        return evaluate([x])[0]

    def jac(x):
        steps = diff_step * np.maximum(np.abs(x), scale)
        steps = np.where(x + steps > hi, -steps, steps)  # step inwards at an upper bound
        points = [x + np.eye(x.size)[i] * steps[i] for i in range(x.size)]
        r0, *rs = evaluate([x] + points)
        return np.column_stack([(r - r0) / h for r, h in zip(rs, steps)])

    def failure(sol) -> str | None:
        if not np.all(np.isfinite(sol.x)) or np.max(np.abs(sol.fun)) >= penalty:
            return "fit_drop: the fit did not converge (the model run fails at the optimum)"
        if sol.status <= 0:  # 0: the evaluation budget ran out before any tolerance was met
            return (f"fit drop: did not converge within {sol.nfev} evaluations ({runs['n']} engine runs); "
                    "free fewer parameters, narrow the bounds or start closer")
        return None

    points = [x0]
    if starts > 1:
        points += list(qmc.scale(qmc.LatinHypercube(d=x0.size, seed=seed).random(starts - 1), lo, hi))
    fits = []
    # (a pool ends its workers at once when the block is left on an interrupt or an error)
    with pool if pool is not None else contextlib.nullcontext():
        if starts > 1:
            evaluate(points)  # the start points' first evaluations, together
        for point in points:
            sol = optimize.least_squares(fun, point, jac=jac, bounds=(lo, hi), x_scale=scale, method="trf",
                                         xtol=xtol, ftol=ftol, gtol=1e-10, max_nfev=max_nfev)
            fits.append((sol, failure(sol)))
    good = [f for f in fits if f[1] is None]
    if not good:
        raise MtbmjError(fits[0][1])
    sol = min(good, key=lambda f: f[0].cost)[0]
    best = next(i for i, f in enumerate(fits) if f[0] is sol)
    final_jac = sol.jac
    runs_in_fit = runs["n"]
    residual = sol.fun
    n = x0.size
    std_iid, _ = covariance_stderr(final_jac, residual, n)
    std_white, _ = channel_sandwich(final_jac, residual, n, len(channels))
    cov, hac = hac_covariance(final_jac, residual, n, len(channels))
    values = {k: float(v) for k, v in zip(free, sol.x)}
    at_bound = [k for k, a in zip(free, sol.active_mask) if a != 0]
    model = cache[sol.x.tobytes()] if sol.x.tobytes() in cache else _model(sol.x, free, cfg, engine, duration,
                                                                            times, channels)
    engine_shift = np.zeros(n)
    error_run = None  # what measured the engine's own error (ERROR_RUNS' keys), None: not measured
    if engine_error and not isinstance(model, str):
        # the engine's own error: the other engine at the optimum, its difference carried to the
        # parameters through the same Jacobian (a bias, added to the covariance as its square)
        other_engine = error_engine(engine)
        other = _model(sol.x, free, cfg, other_engine, duration, times, channels)
        if not isinstance(other, str):
            error_run = other_engine
            engine_shift = np.linalg.pinv(final_jac) @ ((other - model) * ERROR_SCALE.get(engine, 1.0))
            cov = cov + np.outer(engine_shift, engine_shift)
    touch_shift = np.zeros(n)
    touch_err = aligned.touch.stderr_s if aligned.touch else 0.0
    if touch_err > 0 and not isinstance(model, str):
        # the uncertainty of time zero: the model shifted by one standard error of the touch
        shifted = _shifted(model, times, len(channels), touch_err)
        touch_shift = np.linalg.pinv(final_jac) @ (shifted - model)
        cov = cov + np.outer(touch_shift, touch_shift)
    # what neither engine carries (the logger as modelled, the free fall's start): a relative floor
    # per parameter, the size of the gap between the engines and an independent generator
    cov = cov + np.diag((MODEL_FLOOR_REL * np.abs(sol.x)) ** 2)
    std, corr = correlation(cov)
    bound_map = {k: (float(a), float(b)) for k, a, b in zip(free, lo, hi)}
    reached = bounds_reached(values, bound_map)
    warnings = bound_warnings(values, bound_map, reached)
    speed = impact_speed_check(aligned, cfg, free)
    if speed is not None and not speed["agree"]:
        warnings.append(speed["line"])
    worst = int(np.argmax(np.abs(residual)))
    channel, sample = divmod(worst, times.size)
    check = model_check(float(np.sqrt(np.mean(residual**2))), noise_floor(aligned, channels, keep),
                        MODEL_CHECK_ALLOWANCE_MM, "mm",
                        f"{residual[worst]:+.3g} mm in the {channels[channel]} trace at t = {times[sample]:.4f} s",
                        residual=list(np.asarray(residual).reshape(len(channels), times.size)))
    # Student t on the effective number of independent samples (time samples / bandwidth)
    dof = max(times.size / max(hac["bandwidth_samples"], 1.0) - n, 1.0)
    tq = float(stats.t.ppf(0.975, dof))
    per_channel = {}
    curves = {"time_s": times}
    for i, c in enumerate(channels):
        part = slice(i * times.size, (i + 1) * times.size)
        per_channel[c] = float(np.sqrt(np.mean(residual[part] ** 2)))
        curves[f"{c}_data_mm"] = data[part]
        curves[f"{c}_model_mm"] = model[part] if not isinstance(model, str) else np.full(times.size, np.nan)
    start_model = cache.get(x0.tobytes())
    if start_model is None:
        start_model = _model(x0, free, cfg, engine, duration, times, channels)
    if not isinstance(start_model, str):
        for i, c in enumerate(channels):
            curves[f"{c}_start_mm"] = start_model[i * times.size:(i + 1) * times.size]
    model_keys = {k: cfg.values[k] for k in MODEL_KEYS if k in cfg.values}
    return FitResult(
        kind="drop", model=f"{cfg.name} ({engine})", values=values,
        stderr={k: float(s) for k, s in zip(free, std)},
        rms=float(np.sqrt(np.mean(residual**2))), residual_unit="mm", n_points=int(residual.size), n_params=n,
        extra={
            "stderr_iid": {k: float(e) for k, e in zip(free, std_iid)},
            "stderr_white": {k: float(e) for k, e in zip(free, std_white)},
            "engine_error_shift": {k: float(e) for k, e in zip(free, engine_shift)},
            "engine_error_run": error_run,
            "touch_error_shift": {k: float(e) for k, e in zip(free, touch_shift)},
            "hac_bandwidth_s": float(hac["bandwidth_samples"] * np.median(np.diff(times))),
            "effective_dof": float(dof), "time_zero": aligned.touch.to_dict() if aligned.touch else None,
            "notes": correlated_pairs(free, corr),
            "ci95": {k: (float(v - tq * s), float(v + tq * s)) for k, v, s in zip(free, sol.x, std)},
            "correlation": corr.tolist(), "correlation_keys": list(free),
            "engine_runs": runs["n"] + (sol.x.tobytes() not in cache) + (x0.tobytes() not in cache),
            "engine_runs_in_fit": runs_in_fit, "batched": bool(batched),
            "starts": [{"start": {k: float(v) for k, v in zip(free, p)}, "cost": float(f.cost),
                        "status": int(f.status), "nfev": int(f.nfev), "failed": why}
                       for p, (f, why) in zip(points, fits)], "best_start": best,
            "iterations": int(sol.njev or 0), "nfev": int(sol.nfev),
            "status": int(sol.status), "message": sol.message, "at_bound": reached,
            "active_bounds": at_bound, "warnings": warnings, "model_check": check, "impact_speed": speed,
            "ci95_meaningful": {k: k not in reached and check["passed"] for k in free},
            "start": {k: float(v) for k, v in zip(free, x0)},
            "bounds": bound_map,
            "rms_by_channel_mm": per_channel, "channels": list(channels),
            "model_keys": model_keys, "config": cfg.name, "engine": engine,
            "workers": workers, "diff_step": diff_step,
            "wall_time_s": time.perf_counter() - start_time,
            "curves": curves,
        },
    )


def plot_drop(record: Record | None, result: FitResult):
    """Figure: data and fitted model of each channel (and the start model, dashed), with the
    residual underneath."""
    from matplotlib.figure import Figure

    cur = result.extra["curves"]
    channels = result.extra["channels"]
    t = cur["time_s"]
    fig = Figure(figsize=(10, 6.5), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    for i, c in enumerate(channels):
        color = f"C{i}"
        axes[0].plot(t, cur[f"{c}_data_mm"], ".", ms=1.5, color=color, alpha=0.5, label=f"{c} data")
        axes[0].plot(t, cur[f"{c}_model_mm"], "-", lw=1.2, color=color, label=f"{c} fitted")
        if f"{c}_start_mm" in cur:
            axes[0].plot(t, cur[f"{c}_start_mm"], "--", lw=0.8, color=color, alpha=0.6, label=f"{c} start")
        axes[1].plot(t, cur[f"{c}_model_mm"] - cur[f"{c}_data_mm"], lw=0.8, color=color, label=c)
    axes[0].set_ylabel("displacement (mm)")
    axes[0].grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=3)
    axes[1].set_ylabel("model - data (mm)")
    axes[1].set_xlabel("time from tire touch (s)")
    axes[1].grid(alpha=0.3)
    lines = []
    for k, v in result.values.items():
        interval = result.interval95(k)
        lines.append(f"{k.rsplit('.', 1)[-1]} = {v:.4g} " + (f"(95 %: {interval[0]:.4g} to {interval[1]:.4g})"
                                                               if interval is not None else "(no interval)"))
    name = record.path if record is not None else "drop record"
    check = result.extra.get("model_check")
    verdict = "" if check is None else (", model check passed" if check["passed"] else
                                        f", MODEL CHECK FAILED ({check['ratio']:.0f}x the noise floor)")
    axes[0].set_title(f"{name}: {result.model}, RMS {result.rms:.3f} mm{verdict}\n" + "; ".join(lines), fontsize=8)
    return fig


__all__ = ["fit_drop", "plot_drop"]

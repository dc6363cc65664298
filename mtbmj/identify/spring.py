"""Fork spring from a dyno force-displacement stroke (paper Fig. 3).

The record holds displacement (compression positive; negative = pulled into extension) and force
(positive pushing the fork apart), optionally time. Friction opposes the stroke, so the loading
(compression) and unloading (rebound) branches form a loop: every fit models the elastic curve as
the loop's mid-line and the loop's half-width as a constant friction force ``f``,

    F_i = F_el(x_i) + s_i f,   s_i = +1 on the compression branch, -1 on the rebound branch,

with the branch of each point from the sign of d(displacement)/dt (Savitzky-Golay; by sample order
when there is no time column); points near the turns (slow stroke, friction changing sign) are
left out. The elastic curve uses the library's laws in configuration units (mm, N):

* ``linear``: k x through 0 (no top-out, no preload), on x > 0, both strokes pooled.
* ``compression_rebound``: k_c x on the compression branch, k_r x on rebound (S2).
* ``bilinear``: rate k1 below the knee and k2 above it, continuous; the knee is found by the fit.
* ``progressive``: k x + c x^3.
* with ``top_out``: the ``TopOutSpring`` of the main curve, i.e. P + F_main(x) - k_t max(0, P/k_t - x),
  which for engagement x_e = P / k_t is F_main(x) + k_t min(x, x_e); fitted on the whole stroke
  including extension (x < 0), where the fork's slope is k_main + k_t. Needs points below -1 mm.
* ``preload`` (with top-out): P = k_t x_e with x_e fitted; without it x_e = 0.
* ``top_out`` and ``preload`` as model names: the top-out rate and preload of the full
  (progressive main curve) model, as a result holding only those keys.
* ``air`` (``fit_air``, offered when the fit is given an air configuration): the gauge pressure and
  the positive-chamber volume of ``controllers.AirSpring`` (built by ``mtbmj.compose``, so exactly
  the simulated law, top-out spring and negative chamber included) with the fork's geometry
  (piston, spacers, negative chamber, port, polytropic index, top-out rate) from that
  configuration; the whole stroke, nonlinear least squares.

Linear parameters are solved by bounded linear least squares (``scipy.optimize.lsq_linear``) for a
profile over the knee and the engagement; the best point is then polished by
``scipy.optimize.least_squares`` on all parameters together, whose Jacobian gives the standard errors.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares, lsq_linear, minimize_scalar
from scipy.signal import savgol_filter

from mtbmj.errors import MtbmjError
from mtbmj.identify.fitresult import DEFAULT_BOUND_FACTOR, FitResult, covariance_stderr, declare_bounds
from mtbmj.measured.records import Record, RecordError

MODELS = ("linear", "compression_rebound", "bilinear", "progressive", "top_out", "preload")
MAIN_MODELS = MODELS[:4]
EXTENSION_MM = -1.0  # a stroke "reaches extension" with points below this
TURN_FRACTION = 0.3  # points slower than this x the median stroke speed are left out (turns)
MIN_POINTS = 20
K = "fork.spring."


class SpringFitError(MtbmjError):
    """A spring fit cannot be done on this record (one line, names the cause)."""


# --- data preparation -------------------------------------------------------------------------

class _Data:
    def __init__(self, record: Record):
        record.require("displacement", "force", min_points=MIN_POINTS)
        self.path = record.path
        x = np.asarray(record["displacement"], float) * 1e3  # mm
        force = np.asarray(record["force"], float)
        t = np.asarray(record["time"], float) if "time" in record.columns else np.arange(len(x), dtype=float)
        window = min(51, len(x) - (1 - len(x) % 2))
        window = max(window if window % 2 else window - 1, 5)
        speed = savgol_filter(x, window, 2, deriv=1) / float(np.median(np.diff(t)))
        moving = np.abs(speed) >= TURN_FRACTION * np.median(np.abs(speed))
        self.x_all, self.f_all, self.s_all = x, force, np.sign(speed)
        self.x, self.f, self.s = x[moving], force[moving], np.sign(speed[moving])
        if len(self.x) < MIN_POINTS:
            raise RecordError(f"{self.path}: too few points on the strokes ({len(self.x)} away from the turns, "
                              f"need at least {MIN_POINTS})")

    @property
    def reaches_extension(self) -> bool:
        return bool(np.any(self.x < EXTENSION_MM))

    def need_extension(self, why: str) -> None:
        if not self.reaches_extension:
            raise SpringFitError(
                f"{self.path}: the stroke never reaches extension (lowest displacement {self.x.min():.1f} mm, "
                f"need points below {EXTENSION_MM:g} mm), so {why} cannot be fitted")


# --- the model: design matrix for fixed nonlinear parameters ------------------------------------

class _Model:
    """F = A(x, s; knee, x_e) @ p, p >= 0 (friction, rates ...)."""

    def __init__(self, main: str, top_out: bool, preload: bool):
        self.main, self.top_out, self.preload = main, top_out, preload
        names = ["friction"]
        names += {"linear": ["k"], "compression_rebound": ["kc", "kr"], "bilinear": ["k1", "k2"],
                  "progressive": ["k", "c"]}[main]
        if top_out:
            names.append("kt")
        self.linear_names = names
        self.nonlinear_names = (["knee"] if main == "bilinear" else []) + (["xe"] if top_out and preload else [])

    def matrix(self, x, s, knee=None, xe=0.0):
        cols = [s]
        if self.main == "linear":
            cols.append(x)
        elif self.main == "compression_rebound":
            cols += [np.where(s > 0, x, 0.0), np.where(s > 0, 0.0, x)]
        elif self.main == "bilinear":
            cols += [np.minimum(x, knee), np.maximum(x - knee, 0.0)]
        else:
            cols += [x, x ** 3]
        if self.top_out:
            cols.append(np.minimum(x, xe))
        return np.column_stack(cols)

    def split(self, theta):
        nl = len(self.linear_names)
        lin, nonlin = theta[:nl], theta[nl:]
        named = dict(zip(self.nonlinear_names, nonlin))
        return lin, named.get("knee"), named.get("xe", 0.0)

    def predict(self, theta, x, s):
        lin, knee, xe = self.split(theta)
        return self.matrix(x, s, knee, xe) @ lin


def _solve_linear(model, x, s, f, knee=None, xe=0.0):
    a = model.matrix(x, s, knee, xe)
    scale = np.maximum(np.abs(a).max(axis=0), 1e-12)
    sol = lsq_linear(a / scale, f, bounds=(0.0, np.inf))
    p = sol.x / scale
    r = a @ p - f
    return p, float(r @ r)


def _profile(model, x, s, f, lo, hi, fixed: dict, name: str) -> float:
    """Best value of one nonlinear parameter: grid, then a bounded scalar refinement."""
    def cost(value):
        kw = dict(fixed)
        kw[name] = value
        return _solve_linear(model, x, s, f, **kw)[1]

    grid = np.linspace(lo, hi, 60)
    costs = [cost(g) for g in grid]
    i = int(np.argmin(costs))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    if b <= a:
        return float(grid[i])
    best = minimize_scalar(cost, bounds=(a, b), method="bounded", options={"xatol": 1e-3})
    return float(best.x) if best.fun <= costs[i] else float(grid[i])


def _fit(data: _Data, main: str, top_out: bool, preload: bool):
    model = _Model(main, top_out, preload)
    if top_out:
        x, s, f = data.x, data.s, data.f
    else:
        keep = data.x > 0.0
        x, s, f = data.x[keep], data.s[keep], data.f[keep]
    n_params = len(model.linear_names) + len(model.nonlinear_names)
    if len(x) < max(MIN_POINTS, 2 * n_params):
        raise RecordError(f"{data.path}: too few points for the {main} spring fit ({len(x)})")
    if main == "compression_rebound" and (np.sum(s > 0) < 5 or np.sum(s < 0) < 5):
        raise SpringFitError(f"{data.path}: compression_rebound needs both a compression and a rebound stroke")
    xmax = float(x.max())
    knee = xe = None
    if main == "bilinear":
        if xmax < 10.0:
            raise SpringFitError(f"{data.path}: the stroke reaches only {xmax:.1f} mm, too short for a knee")
    if model.nonlinear_names:
        knee0 = 0.5 * xmax if main == "bilinear" else None
        xe = 0.0
        for _ in range(2):  # alternate the two 1-D profiles, then polish jointly
            if "xe" in model.nonlinear_names:
                xe = _profile(model, x, s, f, 0.0, min(30.0, 0.5 * xmax), {"knee": knee0}, "xe")
            if main == "bilinear":
                knee0 = _profile(model, x, s, f, max(2.0, 0.05 * xmax), 0.95 * xmax, {"xe": xe}, "knee")
        knee = knee0
    lin, _ = _solve_linear(model, x, s, f, knee, xe if xe is not None else 0.0)
    theta0 = list(lin) + ([knee] if main == "bilinear" else []) + ([xe] if "xe" in model.nonlinear_names else [])
    theta0 = np.maximum(np.asarray(theta0, float), 0.0)
    lower = np.zeros(len(theta0))
    upper = np.full(len(theta0), np.inf)
    if main == "bilinear":
        i = len(model.linear_names)
        lower[i], upper[i] = 0.5, xmax
    theta0 = np.clip(theta0, lower + 1e-9, np.where(np.isfinite(upper), upper - 1e-9, np.inf))
    scale = np.maximum(np.abs(theta0), 1e-3)
    sol = least_squares(lambda th: model.predict(th * scale, x, s) - f, theta0 / scale,
                        bounds=(lower / scale, upper / scale), method="trf", x_scale="jac")
    if sol.status <= 0 or not np.all(np.isfinite(sol.x)):
        raise SpringFitError(f"fit spring: the {model.name if hasattr(model, 'name') else 'spring'} fit did not "
                             f"converge ({sol.message})")
    theta = sol.x * scale
    resid = model.predict(theta, x, s) - f
    std, corr = covariance_stderr(sol.jac / scale, resid, len(theta))
    names = model.linear_names + model.nonlinear_names
    model.bounds = {n: (float(a), float(b)) for n, a, b in zip(names, lower, upper)}  # config units (N/mm, mm)
    model.start = dict(zip(names, map(float, theta0)))
    return model, theta, std, corr, resid, len(x)


def _keys(model) -> dict[str, str]:
    """The model's parameter names -> their configuration keys (without ``fork.spring.``)."""
    keys = {"k": "rate_N_per_mm", "kc": "compression_rate_N_per_mm", "kr": "rebound_rate_N_per_mm",
            "k1": "rate_below_knee_N_per_mm", "k2": "rate_above_knee_N_per_mm", "knee": "knee_mm",
            "kt": "top_out_rate_N_per_mm"}
    if model.main == "progressive":
        keys.update(k="progressive_rate_N_per_mm", c="progressive_cubic_N_per_mm3")
    return keys


def _bounds(model) -> tuple[dict, dict]:
    """The fit's bounds and start values by configuration key (the preload, kt x_e, from x_e's)."""
    keys = _keys(model)
    bounds = {K + keys[n]: b for n, b in model.bounds.items() if n in keys}
    starts = {K + keys[n]: v for n, v in model.start.items() if n in keys}
    if "xe" in model.bounds:
        low, high = model.bounds["xe"]
        kt = model.start.get("kt", 0.0)
        bounds[K + "preload_N"] = (0.0, np.inf)
        starts[K + "preload_N"] = kt * model.start["xe"] or kt  # x_e starts at 0: 1 mm of it for the scale
    return bounds, starts


def _values(model, theta, std, corr):
    names = model.linear_names + model.nonlinear_names
    val = dict(zip(names, theta))
    err = dict(zip(names, std))
    keys = _keys(model)
    values, stderr = {}, {}
    for name in names:
        if name in keys:
            values[K + keys[name]] = float(val[name])
            stderr[K + keys[name]] = float(err[name])
    if model.top_out and model.preload:
        kt, xe = val["kt"], val["xe"]
        i, j = names.index("kt"), names.index("xe")
        var = (xe * std[i]) ** 2 + (kt * std[j]) ** 2 + 2 * kt * xe * corr[i, j] * std[i] * std[j]
        values[K + "preload_N"] = float(kt * xe)
        stderr[K + "preload_N"] = float(np.sqrt(max(var, 0.0)))
    return values, stderr, float(val["friction"]), float(err["friction"])


def _curves(model, theta, data: _Data):
    lo = min(float(data.x_all.min()), 0.0) if model.top_out else 0.0
    grid = np.linspace(lo, float(data.x_all.max()), 300)
    lin, knee, xe = model.split(theta)
    up = model.matrix(grid, np.ones_like(grid), knee, xe) @ lin
    down = model.matrix(grid, -np.ones_like(grid), knee, xe) @ lin
    friction = lin[0]
    mid = 0.5 * (up + down)
    return (grid, mid), {"compression": (grid, up), "rebound": (grid, down), "friction_N": friction}


def fit_spring(record: Record, model: str = "progressive", *, top_out: bool | None = None,
               preload: bool | None = None) -> FitResult:
    """Fit one spring model (see the module doc) and return its ``FitResult``.

    ``top_out``: fit the top-out spring on the extension side (error if the stroke never reaches
    extension); default False for ``linear`` and ``compression_rebound`` (paper S1, S2, through 0),
    otherwise whether the stroke reaches extension. ``preload``: fit the preload (needs
    ``top_out``); default = ``top_out``.
    """
    if model not in MODELS:
        raise MtbmjError(f"fit spring: unknown model {model!r} (one of {', '.join(MODELS)})")
    data = _Data(record)
    if model in ("top_out", "preload"):
        data.need_extension("the top-out rate" if model == "top_out" else "the preload (it sits against the top-out spring)")
        full = fit_spring(record, "progressive", top_out=True, preload=True)
        keys = [K + "top_out_rate_N_per_mm", K + "preload_N"]
        values = {k: full.values[k] for k in keys}
        extra = dict(full.extra)
        extra["model_keys"] = {K + "top_out": True, K + "preload": True}
        extra["main_values"] = {k: v for k, v in full.values.items() if k not in keys}
        result = FitResult("spring", model, values, {k: full.stderr[k] for k in keys}, full.rms, "N",
                           full.n_points, full.n_params, {k: v for k, v in extra.items()
                                                          if k not in ("bounds", "at_bound", "warnings",
                                                                       "ci95_meaningful")})
        declare_bounds(result, full.extra["bounds"], full.extra["bound_scales"])
        return result
    if top_out is None:
        top_out = False if model in ("linear", "compression_rebound") else data.reaches_extension
    if preload is None:
        preload = top_out
    if top_out:
        data.need_extension("the top-out rate")
    if preload and not top_out:
        raise SpringFitError("fit spring: a preload needs the top-out spring (top_out=True); without it the "
                             "preload is a force step at full extension")
    m, theta, std, corr, resid, n = _fit(data, model, top_out, preload)
    values, stderr, friction, friction_err = _values(m, theta, std, corr)
    curve, branches = _curves(m, theta, data)
    extra = {
        "model_keys": {K + "model": model, K + "top_out": bool(top_out), K + "preload": bool(preload)},
        "curve": curve,
        "branches": branches,
        "friction_N": friction,
        "friction_stderr_N": friction_err,
        "correlation": corr,
        "residual": -resid,  # data - model, in record order
        "parameters": m.linear_names + m.nonlinear_names,
        "notes": [f"loop half-width (friction at the stroke speed) {friction:.1f} +/- {friction_err:.2g} N; "
                  "the elastic curve is the loop's mid-line"],
    }
    if not top_out:
        extra["notes"].append("fitted on the compression side (x > 0) through 0, no top-out or preload")
    result = FitResult("spring", model, values, stderr, float(np.sqrt(np.mean(resid ** 2))), "N", n, len(theta),
                       extra)
    declare_bounds(result, *_bounds(m))
    return result


def fit_air(record: Record, config) -> FitResult:
    """Fit ``fork.spring.air_pressure_psi`` and ``fork.spring.air_volume_cm3`` (with the loop's
    friction half-width) to a dyno stroke, the rest of the air spring taken from ``config`` (an air
    configuration). See the module doc."""
    from mtbmj import compose
    from mtbmj.errors import ConfigError

    if config.get("fork.spring.model") != "air":
        raise SpringFitError(f"fit spring air: {config.name} is not an air configuration (fork.spring.model = air)")
    data = _Data(record)
    x, s, f = data.x * 1e-3, data.s, data.f  # the whole stroke: the law includes the top-out spring
    keys = (K + "air_pressure_psi", K + "air_volume_cm3")

    def curve(theta, xs):
        try:
            spring = compose.fork_law(config.with_overrides(dict(zip(keys, theta)))).spring.main  # no end stops on a dyno
        except ConfigError:
            return None
        return np.array([spring.force(float(xi), 0.0) for xi in xs])

    def residual(q):
        elastic = curve(q[:2], x)
        if elastic is None:  # e.g. a volume the travel would compress to zero: far off
            return np.full(len(x), 1e6)
        return elastic + q[2] * s - f

    start = np.array([config[keys[0]], config[keys[1]], 10.0])
    # the pressure and volume within a factor DEFAULT_BOUND_FACTOR of the configuration's (a gauge
    # pressure of 0 sets no scale: up to 4 x 100 psi); the friction non-negative
    p_hi = DEFAULT_BOUND_FACTOR * (start[0] if start[0] > 0 else 100.0)
    lower = np.array([start[0] / DEFAULT_BOUND_FACTOR, start[1] / DEFAULT_BOUND_FACTOR, 0.0])
    upper = np.array([p_hi, start[1] * DEFAULT_BOUND_FACTOR, np.inf])
    sol = least_squares(residual, start, x_scale=np.array([10.0, 20.0, 5.0]), method="trf", bounds=(lower, upper))
    if sol.status <= 0 or not np.all(np.isfinite(sol.x)) or curve(sol.x[:2], x[:1]) is None:
        raise SpringFitError(f"{data.path}: the air spring fit did not converge ({sol.message})")
    theta = sol.x
    r = residual(theta)
    std, corr = covariance_stderr(sol.jac, r, len(theta))
    grid = np.linspace(min(float(data.x_all.min()), 0.0), float(data.x_all.max()), 300)
    mid = curve(theta[:2], grid * 1e-3)
    values = {keys[0]: float(theta[0]), keys[1]: float(theta[1])}
    stderr = {keys[0]: float(std[0]), keys[1]: float(std[1])}
    extra = {
        "model_keys": {K + "model": "air", K + "preload": False},
        "curve": (grid, mid),
        "branches": {"compression": (grid, mid + theta[2]), "rebound": (grid, mid - theta[2]), "friction_N": theta[2]},
        "friction_N": float(theta[2]), "friction_stderr_N": float(std[2]), "correlation": corr, "residual": -r,
        "parameters": ["air_pressure_psi", "air_volume_cm3", "friction"],
        "notes": [f"air spring of {config.name} with its piston, spacers, negative chamber, port, index and top-out "
                  f"rate; loop half-width {theta[2]:.1f} +/- {std[2]:.2g} N"],
    }
    result = FitResult("spring", "air", values, stderr, float(np.sqrt(np.mean(r ** 2))), "N", len(x), 3, extra)
    declare_bounds(result, {k: (lower[i], upper[i]) for i, k in enumerate(keys)}, dict(zip(keys, start[:2])),
                   hint=f"the bounds are {DEFAULT_BOUND_FACTOR:g} x the configuration's value either way: start from "
                        f"a configuration nearer the fork (--config)")
    return result


def fit_spring_all(record: Record) -> dict[str, FitResult]:
    """Every spring model this record supports (top-out and preload when it reaches extension)."""
    data = _Data(record)
    out = {name: fit_spring(record, name) for name in MAIN_MODELS}
    if data.reaches_extension:
        out["top_out"] = fit_spring(record, "top_out")
        out["preload"] = fit_spring(record, "preload")
    return out


def plot_spring(record: Record, results: dict[str, FitResult] | FitResult):
    """Force vs displacement in the style of the paper's Fig. 3: the dyno loop (points) and, one
    panel per model, the fitted compression and rebound curves and the elastic mid-line."""
    from matplotlib.figure import Figure

    if isinstance(results, FitResult):
        results = {results.model: results}
    shown = {k: r for k, r in results.items() if k in MAIN_MODELS + ("air",)} or dict(results)
    n = max(len(shown), 1)
    cols = 2 if n > 1 else 1
    rows = (n + cols - 1) // cols
    fig = Figure(figsize=(5.2 * cols, 3.9 * rows))
    axes = fig.subplots(rows, cols, squeeze=False)
    x = np.asarray(record["displacement"]) * 1e3
    f = np.asarray(record["force"])
    step = max(len(x) // 2000, 1)
    letters = "abcdefgh"
    for ax, (letter, (name, r)) in zip(axes.flat, zip(letters, shown.items())):
        ax.plot(x[::step], f[::step], ".", ms=1.5, color="0.25", label="dyno data")
        br = r.extra.get("branches")
        if br:
            ax.plot(*br["compression"], "-", color="tab:red", lw=1.4, label="fit, compression")
            ax.plot(*br["rebound"], "-", color="tab:blue", lw=1.4, label="fit, rebound")
        if "curve" in r.extra:
            ax.plot(*r.extra["curve"], "--", color="tab:green", lw=1.2, label="elastic mid-line")
        if K + "knee_mm" in r.values:
            ax.axvline(r.values[K + "knee_mm"], color="0.5", ls=":", lw=1)
        ax.axvline(0.0, color="0.7", lw=0.6)
        ax.set_title(f"({letter}) {name}: RMS {r.rms:.1f} N", fontsize=9)
        ax.set_xlabel("displacement (mm, compression +)")
        ax.set_ylabel("force (N)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    for ax in list(axes.flat)[len(shown):]:
        ax.set_visible(False)
    synthetic = " (synthetic record)" if getattr(record, "synthetic", False) else ""
    fig.suptitle(f"Fork spring: force vs displacement{synthetic}", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["MODELS", "SpringFitError", "fit_spring", "fit_spring_all", "fit_air", "plot_spring"]

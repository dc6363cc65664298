"""Global sensitivity of drop outputs to configuration parameters, with SALib.

Sobol indices (Saltelli sampling, first-order S1 and total ST with bootstrap confidence
intervals) or Morris elementary effects (mu*, sigma, with the CI of mu*), computed over the
``--vary key=lo:hi`` box from runs made by the sweep runner (so they are journaled, resumable
and can run on the Dask backend)."""
from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from mtbmj import limits
from mtbmj.errors import ConfigError, MtbmjError, RunError
from mtbmj.sweep.runner import OUTPUT_COLUMNS, Range, run_sweep

METHODS = ("sobol", "morris")
CONF_LEVEL = 0.95


@dataclass
class SensitivityResult:
    method: str
    problem: dict
    outputs: list[str]
    indices: dict  # output -> parameter -> {index name: value}
    runs: int
    files: list[Path]
    sweep: object  # the SweepResult of the runs

    def line(self) -> str:
        main = "ST" if self.method == "sobol" else "mu_star"
        parts = []
        for out in self.outputs:
            ranked = sorted(self.indices[out].items(), key=lambda kv: -_num(kv[1][main]))
            top = ", ".join(f"{k} {_num(v[main]):.3g}" for k, v in ranked[:3])
            parts.append(f"{out}: {top}")
        return f"{self.method} on {self.runs} runs; largest {main}: " + "; ".join(parts)


def _num(x) -> float:
    return float("nan") if x is None else float(x)


def problem(ranges: Sequence[Range]) -> dict:
    if not ranges:
        raise ConfigError("sensitivity: give at least one --vary key=lo:hi")
    names = [r.key for r in ranges]
    if len(set(names)) != len(names):
        raise ConfigError("--vary: a key is given twice")
    return {"num_vars": len(ranges), "names": names, "bounds": [[r.lo, r.hi] for r in ranges]}


def check_outputs(outputs: Sequence[str]) -> list[str]:
    if not isinstance(outputs, (list, tuple)):  # "fork_peak1_mm" was read letter by letter: "'f' is not an output"
        outputs = limits.names("outputs", outputs, "fork_peak1_mm", none_ok=False)  # a generator read once, here
    odd = [o for o in outputs if not isinstance(o, str)]
    if odd:
        raise ConfigError(f"outputs: each must be an output's name, e.g. 'fork_peak1_mm', got {odd[0]!r}")
    outputs = [o.strip() for o in outputs if o.strip()]
    if not outputs:
        raise ConfigError("--output: name at least one output, e.g. fork_peak1_mm")
    boolean = {"lifts_off", "fork_tops_out", "at_rest", "bottomed_out"}
    for o in outputs:
        if o not in OUTPUT_COLUMNS or o in boolean:
            import difflib

            close = difflib.get_close_matches(o, [c for c in OUTPUT_COLUMNS if c not in boolean], n=1)
            hint = f"did you mean {close[0]}? " if close else ""
            raise ConfigError(f"--output: {o!r} is not a numeric sweep output ({hint}they are "
                              f"{_outputs([c for c in OUTPUT_COLUMNS if c not in boolean])})")
    return list(dict.fromkeys(outputs))


def _outputs(columns: Sequence[str]) -> str:
    """``columns`` in short: the events' columns of the three signals as one pattern
    ({sled,fork,tire}_{peak1,...}_{mm,s}), the rest by name."""
    import re

    parts = [re.fullmatch(r"(sled|fork|tire)_(peak1|topping|peak2|valley1|peak3)_(mm|s)", c) for c in columns]
    signals, events = ({m.group(i): None for m in parts if m} for i in (1, 2))
    grid = [f"{s}_{e}_{u}" for s in signals for e in events for u in ("mm", "s")]
    if not signals or sorted(grid) != sorted(c for c, m in zip(columns, parts) if m):  # not the whole grid: each
        return ", ".join(columns)
    pattern = f"{{{','.join(signals)}}}_{{{','.join(events)}}}_{{mm,s}}"
    return ", ".join([pattern] + [c for c, m in zip(columns, parts) if not m])


def samples(prob: dict, n: int, method: str, seed: int = 0, levels: int = 4) -> np.ndarray:
    """SALib's design: Saltelli/Sobol (n (D + 2) rows, no second order) or Morris (n (D + 1) rows)."""
    if method not in METHODS:
        raise ConfigError(f"--method: {method!r} is not one of {', '.join(METHODS)}")
    n, seed = limits.whole("--samples", n, 2, False), limits.whole("--seed", seed, 0, False)
    if method == "morris":  # sobol has no levels: its default levels=4 passed whatever was given
        levels = limits.whole("--levels", levels, 2, False)
    with warnings.catch_warnings():  # SALib's "N should be a power of 2" note
        warnings.simplefilter("ignore")
        if method == "sobol":
            from SALib.sample import sobol

            return sobol.sample(prob, n, calc_second_order=False, seed=seed)
        from SALib.sample import morris

        return morris.sample(prob, n, num_levels=levels, seed=seed)


def analyze(prob: dict, x: np.ndarray, y: np.ndarray, method: str, seed: int = 0, levels: int = 4) -> dict:
    """Indices of one output: parameter -> {S1, S1_conf, ST, ST_conf} or {mu, mu_star, sigma,
    mu_star_conf}; NaN where undefined (a constant output), as None."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if method == "sobol":
            from SALib.analyze import sobol

            res = sobol.analyze(prob, y, calc_second_order=False, conf_level=CONF_LEVEL, seed=seed)
            keys = ("S1", "S1_conf", "ST", "ST_conf")
        else:
            from SALib.analyze import morris

            res = morris.analyze(prob, x, y, conf_level=CONF_LEVEL, num_levels=levels, seed=seed)
            keys = ("mu", "mu_star", "sigma", "mu_star_conf")
    clean = lambda v: None if not math.isfinite(float(v)) else float(v)
    return {name: {k: clean(res[k][i]) for k in keys} for i, name in enumerate(prob["names"])}


def run_sensitivity(config, ranges: Sequence[Range], outputs: Sequence[str], out_dir, *, method: str = "sobol",
                    n: int = 64, seed: int = 0, levels: int = 4, engine: str = "mujoco",
                    duration: float | None = None, base_overrides: Mapping | None = None, workers: int | None = None,
                    backend: str = "local", scheduler=None, resume: bool = False, progress=False,
                    runner=None) -> SensitivityResult:
    """Sample, run through the sweep (journal and table in ``out_dir``), analyse, and write
    ``sensitivity.json``, ``sensitivity.csv`` and ``sensitivity.png``."""
    from mtbmj.extras import require

    require("sweep", "mtbmj sensitivity", ["SALib", "pandas", "pyarrow"])
    outputs = check_outputs(outputs)
    prob = problem(ranges)
    x = samples(prob, n, method, seed, levels)
    variants = [dict(zip(prob["names"], map(float, row))) for row in x]
    extra = {"runner": runner} if runner is not None else {}
    found: dict = {}

    def analysed(table) -> dict[str, bytes]:
        """The indices, written with the sweep's table in one step; a failure writes neither."""
        failed = table[table["status"] != "ok"]
        if len(failed):
            # RunError: the runs, not an argument, failed; the command line's line names every warning with it
            # (an --vary range in metres for mm, the likeliest cause)
            raise RunError(f"sensitivity: {len(failed)} of {len(table)} runs failed (first: "
                             f"{failed['reason'].iloc[0]}); narrow the --vary ranges (the runs are journaled in "
                             f"{Path(out_dir) / 'journal'})")
        indices = {}
        for out in outputs:
            y = table[out].to_numpy(dtype=float)
            if not np.all(np.isfinite(y)):
                raise RunError(f"sensitivity: {out} is undefined in {int(np.sum(~np.isfinite(y)))} of {len(y)} "
                                 f"runs (the event does not occur); choose another --output or a longer --duration")
            indices[out] = analyze(prob, x, y, method, seed, levels)
        found["indices"] = indices
        return {
            "sensitivity.json": _json(method, prob, n, len(x), outputs, indices, seed),
            "sensitivity.csv": _csv(method, outputs, indices),
            "sensitivity.png": _plot(method, prob, outputs, indices, len(x)),
        }

    sweep = run_sweep(config, variants, out_dir, engine=engine, duration=duration, base_overrides=base_overrides,
                      workers=workers, backend=backend, scheduler=scheduler, resume=resume, progress=progress,
                      manifest_extra={"sensitivity": {"method": method, "samples": n, "seed": seed,
                                                      "problem": prob}}, extra_files=analysed, **extra)
    return SensitivityResult(method, prob, outputs, found["indices"], len(x), sweep.files, sweep)


def _json(method, prob, n, runs, outputs, indices, seed) -> bytes:
    payload = {"method": method, "conf_level": CONF_LEVEL, "samples": n, "runs": runs, "seed": seed,
               "problem": prob, "outputs": outputs, "indices": indices,
               "meaning": ("S1 first-order and ST total Sobol indices (Saltelli sampling), *_conf the half-width "
                           "of the bootstrap confidence interval" if method == "sobol" else
                           "Morris elementary effects: mu mean, mu_star mean of |effect|, sigma standard "
                           "deviation, mu_star_conf the half-width of the bootstrap confidence interval of mu_star")}
    return (json.dumps(payload, indent=2) + "\n").encode()


def _csv(method, outputs, indices) -> bytes:
    keys = ("S1", "S1_conf", "ST", "ST_conf") if method == "sobol" else ("mu", "mu_star", "sigma", "mu_star_conf")
    lines = [",".join(("output", "parameter") + keys)]
    for out in outputs:
        for name, values in indices[out].items():
            cells = ["" if values[k] is None else repr(values[k]) for k in keys]
            lines.append(",".join([out, name] + cells))
    return ("\n".join(lines) + "\n").encode()


def _plot(method, prob, outputs, indices, runs) -> bytes:
    from matplotlib.figure import Figure

    names = prob["names"]
    fig = Figure(figsize=(max(6, 1.6 * len(names) + 3), 2.8 * len(outputs) + 0.6), layout="constrained")
    axes = fig.subplots(len(outputs), 1, squeeze=False)
    pos = np.arange(len(names))
    bars = (("S1", "S1_conf", "first order S1"), ("ST", "ST_conf", "total ST")) if method == "sobol" else \
        (("mu_star", "mu_star_conf", "mu* (mean |effect|)"), ("sigma", None, "sigma"))
    width = 0.38
    for ax, out in zip(axes[:, 0], outputs):
        for k, (key, conf, label) in enumerate(bars):
            vals = [_num(indices[out][p][key]) for p in names]
            err = [_num(indices[out][p][conf]) for p in names] if conf else None
            ax.bar(pos + (k - 0.5) * width, vals, width, yerr=err, capsize=3, label=label)
        ax.set_xticks(pos, [n.replace(".", ".\u200b") for n in names], fontsize="small")
        ax.set_ylabel(out)
        ax.grid(True, axis="y", alpha=0.3)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.legend(fontsize="small")
    title = "Sobol indices, 95 % CI" if method == "sobol" else "Morris elementary effects, 95 % CI of mu*"
    fig.suptitle(f"{title} ({runs} runs)")
    from mtbmj.readout.quicklook import png

    return png(fig, dpi=110)


__all__ = ["SensitivityResult", "run_sensitivity", "problem", "samples", "analyze", "check_outputs", "METHODS"]

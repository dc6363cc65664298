"""One entry point for every identification: read the data, fit, choose, and package the
parameter set (TOML), the figure (PNG) and the numbers (JSON) for ``mtbmj fit``."""
from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

from mtbmj import output
from mtbmj.config import parameter_set_toml
from mtbmj.errors import MtbmjError
from mtbmj.identify.fitresult import FitResult
from mtbmj.identify.records import Record, read_record

KINDS = ("spring", "damper", "tire", "drop")


@dataclass
class Identification:
    """Fitted models of one kind, the ones chosen for the parameter set, and how to plot them."""

    kind: str
    records: list[Record]
    results: dict[str, FitResult]
    chosen: list[str]
    plot_fn: Callable
    base: str = "reference"
    notes: list[str] = field(default_factory=list)
    friction: str | None = None  # damper fits: the friction model whose fork.friction keys win

    def _sources(self) -> dict[str, str]:
        """Configuration key -> name of the fit that supplies its value (later fits win; for a
        damper the chosen friction model supplies every fork.friction key)."""
        source: dict[str, str] = {}
        for name in self.chosen:
            source.update({k: name for k in self.results[name].overrides()})
        fitted_with = {self.results[n].overrides().get("fork.friction.model") for n in self.chosen}
        # the hydraulic fit already carries the friction it was fitted with; another friction
        # model replaces it (its level near zero velocity is what the hydraulic fit leaves out)
        if self.friction is not None and self.friction not in fitted_with:
            source = {k: n for k, n in source.items() if not k.startswith("fork.friction.")}
            source.update({k: self.friction for k in self.results[self.friction].overrides()
                           if k.startswith("fork.friction.")})
        return source

    def parameter_set(self) -> dict:
        return {key: self.results[name].overrides()[key] for key, name in self._sources().items()}

    def toml(self) -> str:
        comments = {}
        for key, name in self._sources().items():
            err = self.results[name].stderr.get(key)
            if err is not None and err == err:  # not NaN
                comments[key] = f"+/- {err:.3g} (1 sigma), {self.kind} fit '{name}'"
        sources = ", ".join(Path(r.path).name for r in self.records)
        synthetic = " (synthetic data)" if any(r.synthetic for r in self.records) else ""
        return parameter_set_toml(self.parameter_set(), self.base,
                                  f"mtbmj fit {self.kind} from {sources}{synthetic}", comments)

    def summary(self) -> dict:
        return {
            "kind": self.kind,
            "data": [r.path for r in self.records],
            "synthetic_data": any(r.synthetic for r in self.records),
            "chosen": self.chosen + ([f"friction: {self.friction}"] if self.friction else []),
            "models": {name: _result_json(r) for name, r in self.results.items()},
            "parameter_set": {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.parameter_set().items()},
            "notes": self.notes,
        }

    def plot(self):
        return self.plot_fn()

    def files(self) -> dict[str, bytes]:
        fig = self.plot()
        png = io.BytesIO()
        fig.savefig(png, format="png", dpi=110)
        return {"fit.toml": self.toml().encode(), "fit.json": output.json_bytes(self.summary()),
                "fit.png": png.getvalue()}

    def write(self, out_dir) -> list[Path]:
        return output.write_atomically(out_dir, self.files())


def _result_json(r: FitResult) -> dict:
    plain = lambda v: list(v) if isinstance(v, tuple) else v  # noqa: E731
    out = {"model": r.model, "values": {k: plain(v) for k, v in r.values.items()},
           "stderr": r.stderr, "rms": r.rms, "residual_unit": r.residual_unit,
           "n_points": r.n_points, "n_params": r.n_params, "aic": r.aic, "bic": r.bic}
    for key in ("ci95", "correlation", "engine_runs", "free", "notes"):
        if key in r.extra:
            value = r.extra[key]
            out[key] = value.tolist() if hasattr(value, "tolist") else value
    return out


SPRING_MODELS = ("linear", "compression_rebound", "bilinear", "progressive")  # candidates for "auto"
SPRING_PARTS = SPRING_MODELS + ("top_out", "preload")  # may be asked for by name
HYDRAULIC_MODELS = ("linear", "bilinear", "table")
FRICTION_MODELS = ("none", "coulomb", "coulomb_viscous", "stiction", "stribeck", "lugre")


def _choose(results: dict[str, FitResult], names: Sequence[str], requested: str, what: str) -> str:
    """The requested model, or with "auto" the lowest BIC among the models fitted to the same
    (largest) set of points and supported by the data."""
    fitted = [n for n in names if n in results]
    if requested != "auto":
        if requested not in fitted:
            raise MtbmjError(f"--{what} {requested}: not among the fitted models ({', '.join(fitted)})")
        return requested
    supported = [n for n in fitted if results[n].extra.get("supported", True)]
    most = max(results[n].n_points for n in supported)
    comparable = [n for n in supported if results[n].n_points == most]
    return min(comparable, key=lambda n: results[n].bic)


def _spring(records, results, model, plot_fn) -> Identification:
    main = _choose(results, SPRING_PARTS if model != "auto" else SPRING_MODELS, model, "model")
    notes = ["models compared by BIC: " + ", ".join(
        f"{n} {results[n].bic:.1f}" for n in SPRING_MODELS if n in results)]
    if "friction_N" in results[main].extra:
        notes.append(f"hysteresis half-width (friction) {results[main].extra['friction_N']:.1f} N")
    return Identification("spring", records, results, [main], lambda: plot_fn(records[0], results), notes=notes)


def _damper(records, results, model, friction, module) -> Identification:
    hydraulic = _choose(results, HYDRAULIC_MODELS, model, "model")
    chosen_friction = _choose(results, FRICTION_MODELS, friction, "friction")
    supported = [n for n in FRICTION_MODELS if n in results and results[n].extra.get("supported", True)]
    notes = ["hydraulic models by BIC: " + ", ".join(f"{n} {results[n].bic:.1f}" for n in HYDRAULIC_MODELS if n in results),
             "friction models by BIC: " + ", ".join(f"{n} {results[n].bic:.1f}" for n in supported)]
    return Identification("damper", records, results, [hydraulic], lambda: module.plot_damper(records[0], results),
                          notes=notes, friction=chosen_friction)


def identify(kind: str, data: Sequence[str | Path], model: str = "auto", friction: str = "auto",
             mass_kg: float | None = None, config: str = "S12", free: Sequence[str] = (),
             bounds: dict | None = None, engine: str = "mujoco", starts: int = 1) -> Identification:
    """Fit ``kind`` ("spring", "damper", "tire", "drop") to the record(s) in ``data``; ``starts``:
    drop fits from that many start points (the best wins)."""
    if kind not in KINDS:
        raise MtbmjError(f"fit: unknown kind {kind!r} (one of {', '.join(KINDS)})")
    if not data:
        raise MtbmjError(f"fit {kind}: no data file given")
    records = [read_record(p) for p in data]
    if kind == "spring":
        from mtbmj.identify import spring

        results = spring.fit_spring_all(records[0])
        if model not in ("auto", *results):
            results[model] = spring.fit_spring(records[0], model)  # raises the precise cause, e.g. no extension
        return _spring(records, results, model, spring.plot_spring)
    if kind == "damper":
        from mtbmj.identify import damper

        results = damper.fit_damper_all(records[0])
        return _damper(records, results, model, friction, damper)
    if kind == "tire":
        from mtbmj.identify import tire

        drops = [r for r in records if "time" in r.columns]
        ramps = [r for r in records if "time" not in r.columns]
        if len(drops) != 1 or len(ramps) > 1:
            raise MtbmjError("fit tire: give one tire drop record (time_s, deflection_mm) and at most one "
                             "static ramp (deflection_mm, force_N)")
        results = tire.fit_tire(drops[0], mass_kg, ramp=ramps[0] if ramps else None)
        order = [part for part in ("static", "impact", "contact") if part in results]  # as tire.tire_overrides
        return Identification("tire", records, results, order, lambda: tire.plot_tire(drops[0], results))
    from mtbmj.identify import dropfit

    if not free:
        raise MtbmjError("fit drop: name the free parameters with --free key,key,...")
    result = dropfit.fit_drop(records[0], config=config, free=list(free), bounds=bounds, engine=engine,
                              starts=starts)
    return Identification("drop", records, {"drop": result}, ["drop"],
                          lambda: dropfit.plot_drop(records[0], result), base=config)

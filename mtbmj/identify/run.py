"""One entry point for every identification: read the data, fit, choose, and package the
parameter set (TOML), the figure (PNG) and the numbers (JSON) for ``mtbmj fit``."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from mtbmj import output
from mtbmj.config import load as load_config, parameter_set_toml, preset_names
from mtbmj.errors import MtbmjError
from mtbmj.identify.fitresult import FitResult
from mtbmj.measured.records import Record, read_record

KINDS = ("spring", "damper", "tire", "drop")
DEFAULT_DROP_FREE = ("tire.impact_rate_N_per_mm", "fork.spring.preload_N")  # fit drop without --free


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
    overrides: dict = field(default_factory=dict)  # the --set values the fit ran on (written with it)

    @property
    def _written(self) -> list[str]:
        """The fits whose values are written (a damper's friction model only where it supplies
        the friction keys)."""
        return list(dict.fromkeys(self.chosen + [n for n in self._sources().values() if n not in self.chosen]))

    @property
    def warnings(self) -> list[str]:
        """What the user must know before trusting the result: values stopped at a bound, a
        record that disagrees with the configuration."""
        return list(dict.fromkeys(w for name in self._written for w in self.results[name].extra.get("warnings", [])))

    @property
    def model_checks(self) -> list[dict]:
        checks = {}  # one line each: a damper's hydraulic and friction choice can be the same fit
        for name in self._written:
            check = self.results[name].extra.get("model_check")
            if check is not None:
                checks.setdefault(check["line"], check)
        return list(checks.values())

    @property
    def model_check_passed(self) -> bool:
        return all(check["passed"] for check in self.model_checks)

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
        fitted = {key: self.results[name].overrides()[key] for key, name in self._sources().items()}
        return {**_without_counterparts(self.overrides, fitted), **fitted}

    def toml(self) -> str:
        comments = {}
        for key, name in self._sources().items():
            result = self.results[name]
            interval = result.interval95(key)
            fit = f"{self.kind} fit '{name}'" + (f" ({result.extra['law']})" if "law" in result.extra else "")
            if interval is not None:
                comments[key] = f"95 % interval {interval[0]:.6g} to {interval[1]:.6g}, {fit}"
            elif result.stderr.get(key) is not None:
                comments[key] = f"NO meaningful interval (see the header), {fit}"
        for key in self.overrides:
            comments.setdefault(key, "set for the fit (--set)")
        sources = ", ".join(Path(r.path).name for r in self.records)
        synthetic = " (synthetic data)" if any(r.synthetic for r in self.records) else ""
        problems = [c["line"] for c in self.model_checks if not c["passed"]] + self.warnings
        warning = ("NOT A CLEAN RESULT: " + " | ".join(problems) + " | ") if problems else ""
        values, base = self.parameter_set(), self.base
        if base not in preset_names():
            # a configuration file: its values go into fit.toml, which then stands alone (a base
            # outside the fit's folder would not be read back: mtbmj.config's base rule)
            own = {k: v for k, v in load_config(base).values.items() if k not in ("description", "reading")}
            values, base = {**_without_counterparts(own, values), **values}, "reference"
            from mtbmj.compose import unread  # keys the file carried that its models do not read: left out

            idle = set(unread(load_config(base).with_overrides(values)))
            values = {k: v for k, v in values.items() if k not in idle}
        return parameter_set_toml(values, base, f"{warning}mtbmj fit {self.kind} from {sources}{synthetic}", comments)

    def summary(self) -> dict:
        return {
            "kind": self.kind,
            "data": [r.path for r in self.records],
            "synthetic_data": any(r.synthetic for r in self.records),
            "chosen": self.chosen + ([f"friction: {self.friction}"] if self.friction else []),
            "models": {name: _result_json(r) for name, r in self.results.items()},
            "parameter_set": {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.parameter_set().items()},
            "set": dict(self.overrides),
            "warnings": self.warnings,
            "model_check_passed": self.model_check_passed,
            "notes": self.notes,
        }

    def plot(self):
        return self.plot_fn()

    def files(self) -> dict[str, bytes]:
        fig = self.plot()
        from mtbmj.readout.quicklook import png

        return {"fit.toml": self.toml().encode(), "fit.json": output.json_bytes(self.summary()),
                "fit.png": png(fig, dpi=110)}

    def write(self, out_dir) -> list[Path]:
        return output.write_atomically(out_dir, self.files())


def _without_counterparts(values: Mapping, winners: Mapping) -> dict:
    """``values`` less the keys that give a key of ``winners`` in another unit
    (``fork.spring.rate_N_per_mm`` when ``rate_lb_per_in`` wins, ``config.ALTERNATIVES``): one
    file may not give a value in two units, and the fitted (or later) one is meant."""
    from mtbmj.config import ALTERNATIVES, CANONICAL

    others = {ALTERNATIVES[k][0] for k in winners if k in ALTERNATIVES} | {CANONICAL[k] for k in winners
                                                                          if k in CANONICAL}
    return {k: v for k, v in values.items() if k not in others}


def _result_json(r: FitResult) -> dict:
    plain = lambda v: list(v) if isinstance(v, tuple) else v  # noqa: E731
    out = {"model": r.model, "values": {k: plain(v) for k, v in r.values.items()},
           "stderr": r.stderr, "rms": r.rms, "residual_unit": r.residual_unit,
           "n_points": r.n_points, "n_params": r.n_params, "aic": r.aic, "bic": r.bic}
    out["ci95"] = {k: r.interval95(k) for k, v in r.values.items() if not isinstance(v, (tuple, list))
                   and r.stderr.get(k) is not None}  # null: no meaningful interval (at a bound, model check failed)
    if "bounds" in r.extra:
        from mtbmj.identify.fitresult import json_bounds

        out["bounds"] = json_bounds(r.extra["bounds"])  # null: that side is open
    for key in ("correlation", "engine_runs", "free", "notes", "at_bound", "warnings", "model_check",
                "impact_speed", "friction_check"):
        if key in r.extra:
            value = r.extra[key]
            out[key] = value.tolist() if hasattr(value, "tolist") else value
    return out


SPRING_MODELS = ("linear", "compression_rebound", "bilinear", "progressive", "air")  # candidates for "auto"
SPRING_PARTS = SPRING_MODELS + ("top_out", "preload")  # may be asked for by name
HYDRAULIC_MODELS = ("linear", "bilinear", "digressive", "table")
FRICTION_MODELS = ("none", "coulomb", "coulomb_viscous", "stiction", "stribeck", "lugre")


INDISTINGUISHABLE_BIC = 2.0  # BIC differences below this are no evidence either way (Kass & Raftery 1995)
RESOLUTION = 1e-6  # residuals below this fraction of the data's RMS count as zero in the comparison


def _floor(records: Sequence[Record], quantity: str) -> float:
    values = records[0].columns.get(quantity)
    if values is None or values.size == 0:
        return 0.0
    unit = records[0].units[quantity]
    from mtbmj.measured.records import UNITS

    return RESOLUTION * float(np.sqrt(np.mean(values**2))) / UNITS[unit]


def _choose(results: dict[str, FitResult], names: Sequence[str], requested: str, what: str,
            floor: float = 0.0) -> str:
    """The requested model, or with "auto" the lowest BIC (residuals below ``floor`` counted as
    ``floor``; ties go to fewer parameters) among the models fitted to the same (largest) set of
    points, supported by the data and not saturated (fewer than half as many parameters as
    points)."""
    fitted = [n for n in names if n in results]
    if requested != "auto":
        if requested not in fitted:
            raise MtbmjError(f"--{what} {requested}: not among the fitted models ({', '.join(fitted)})")
        return requested
    eligible = [n for n in _eligible(results, fitted)]
    if not eligible:
        raise MtbmjError(f"fit: too few points to choose a {what} (every model has at least half as many "
                         "parameters as the record has points); name one with --" + what)
    return min(eligible, key=lambda n: (round(results[n].bic_with_floor(floor), 6), results[n].n_params))


def _eligible(results: dict[str, FitResult], fitted: Sequence[str]) -> list[str]:
    supported = [n for n in fitted if results[n].extra.get("supported", True)]
    if not supported:
        return []
    most = max(results[n].n_points for n in supported)
    return [n for n in supported if results[n].n_points == most and not results[n].saturated]


def _comparison(results: dict[str, FitResult], names: Sequence[str], chosen: str, floor: float, label: str) -> list[str]:
    """Notes: the BIC of each model, the models left out (saturated, unsupported) and the ones the
    data cannot tell from the chosen one."""
    fitted = [n for n in names if n in results]
    eligible = _eligible(results, fitted)
    bic = {n: results[n].bic_with_floor(floor) for n in fitted}
    notes = [f"{label} by BIC: " + ", ".join(f"{n} {bic[n]:.1f}" for n in eligible)]
    saturated = [n for n in fitted if results[n].saturated]
    if saturated:
        notes.append(", ".join(f"{n} ({results[n].n_params} parameters for {results[n].n_points} points)"
                               for n in saturated) + ": as many parameters as the data can carry, not compared")
    if chosen in bic:
        close = [n for n in eligible if n != chosen and abs(bic[n] - bic[chosen]) < INDISTINGUISHABLE_BIC]
        better = [n for n in eligible if bic[n] <= bic[chosen] - INDISTINGUISHABLE_BIC]
        if better:  # a model named by the user that the record does not prefer
            notes.append(f"the record prefers {', '.join(better)} to {chosen} (BIC {bic[min(better, key=bic.get)]:.1f} "
                         f"against {bic[chosen]:.1f})")
        if close:
            notes.append(f"the data cannot distinguish {chosen} from {', '.join(close)} "
                         f"(BIC within {INDISTINGUISHABLE_BIC:g}); {chosen} has the fewest parameters or lowest BIC")
    return notes


def _spring(records, results, model, plot_fn, base="reference") -> Identification:
    floor = _floor(records, "force")
    main = _choose(results, SPRING_PARTS if model != "auto" else SPRING_MODELS, model, "model", floor)
    notes = _comparison(results, SPRING_MODELS, main, floor, "models compared")
    if "friction_N" in results[main].extra:
        notes.append(f"hysteresis half-width (friction) {results[main].extra['friction_N']:.1f} N")
    check = _noise_check(records[0], "force", 1.0, results[main], "N", "residual: see fit.png")
    if check is not None:
        if not check["passed"] and results[main].model != "air":
            check["line"] += ("; an air spring? name an air configuration with --config (e.g. air120) to fit the "
                              "air model")
        _attach_check(results[main], check)
    return Identification("spring", records, results, [main], lambda: plot_fn(records[0], results), base=base,
                          notes=notes)


def _attach_check(result: FitResult, check: dict) -> None:
    """A fit's model check, with its intervals withdrawn when the check fails (the values then
    describe no fork, so neither do their intervals)."""
    result.extra["model_check"] = check
    if not check["passed"]:
        meaningful = result.extra.setdefault("ci95_meaningful", {})
        for key in result.stderr:
            meaningful[key] = False


NOISE_CHECK_MIN_POINTS = 30  # a record this long at least has a noise floor to speak of


def _noise_check(record: Record, quantity: str, scale: float, result: FitResult, unit: str,
                 worst: str) -> dict | None:
    """A bench fit's model check (spring, tire): its residual RMS against the noise floor of the
    record's ``quantity`` (white noise from third differences along the record,
    ``mtbmj.measured.peaks.noise_sigma``; SI times ``scale`` gives ``unit``), limit 3 x noise
    (``fitresult.model_check``). ``None`` for a record too short to tell its noise."""
    from mtbmj.identify.fitresult import model_check
    from mtbmj.measured.peaks import noise_sigma

    values = record.columns.get(quantity)
    if values is None or values.size < NOISE_CHECK_MIN_POINTS:
        return None
    noise = float(noise_sigma(np.asarray(values, float))) * scale
    if not noise > 0.0:
        return None
    return model_check(result.rms, noise, 0.0, unit, worst, residual=result.extra.get("residual"))


def _steps(progress: Callable[[float], None] | None, total: int) -> Callable[[], None] | None:
    """A ``step()`` that reports one more of ``total`` steps done to ``progress``."""
    if progress is None:
        return None
    done = [0]
    progress(0.0)

    def step() -> None:
        done[0] += 1
        progress(min(done[0] / total, 1.0))

    return step


MANY_ROWS = 1000  # a damper record this long without time_s is samples, not one point per half-cycle


def _damper(records, results, model, friction, module, step=None) -> Identification:
    """The damper law written: the hydraulic law (``model``, or the lowest BIC) and the friction
    law fitted together with it (``friction``, or the lowest BIC among the friction laws each
    fitted with that hydraulic law). One fit supplies every value written, so what the fit prints,
    what fit.json records and what fit.toml writes are that one law, and the model check judges
    it. A table carries its own Coulomb offset (it takes up any other friction shape)."""
    rec = module.peaks(records[0])
    floor = max(_floor(records, "force"), module.sign_band_floor(rec, results))
    hydraulic = _choose(results, HYDRAULIC_MODELS, model, "model", floor)
    notes = _comparison(results, HYDRAULIC_MODELS, hydraulic, floor, "hydraulic models")
    if hydraulic == "table":
        if friction not in ("auto", "coulomb"):
            raise MtbmjError(f"--friction {friction}: the table is fitted with its Coulomb offset alone (the table takes "
                             "up any other friction shape); leave --friction out, or name another --model")
        chosen_friction, written = "coulomb", "table"
        notes.append("friction: the table's own Coulomb offset (a table takes up any other friction shape, so no other "
                     "friction law is fitted with it)")
    else:  # every friction law fitted with the hydraulic law written, the one written chosen among them
        module.refit_friction(rec, results, hydraulic, step)
        chosen_friction = _choose(results, FRICTION_MODELS, friction, "friction", floor)
        written = hydraulic if chosen_friction == "coulomb" else chosen_friction  # (the same fit for coulomb)
        notes += _comparison(results, FRICTION_MODELS, chosen_friction, floor, f"friction models (each with the "
                             f"{hydraulic} law)")
        notes += _friction_said(results, hydraulic, chosen_friction, written, floor, friction != "auto")
    notes.append(f"written: the {results[written].extra['law']}, its values fitted together (fit.json: "
                 f"models.{written})")
    raw = records[0]
    if "time" not in raw.columns and ("displacement" in raw.columns or len(raw) > MANY_ROWS):
        notes.append(f"no time_s: the {len(raw)} rows are fitted as (velocity, force) points as they stand, not reduced "
                     "to the dyno's peak points (one per half-cycle) as a time series with time_s is")
    ident = Identification("damper", records, results, [written], lambda: module.plot_damper(records[0], results),
                           notes=notes, friction=chosen_friction)
    check = module.damper_model_check(rec, results[written])  # the law written, as written
    if check is not None:
        _attach_check(results[written], check)
    else:
        notes.append(f"no model check: the record has fewer than {module.MIN_NOISE_DOF} repeated points at its test "
                     "speeds, so it cannot tell its own noise (record several cycles per speed)")
    return ident


def _friction_said(results: dict[str, FitResult], hydraulic: str, friction: str, written: str,
                   floor: float, asked: bool) -> list[str]:
    """Notes on what the record tells of the friction written: where the hydraulic law with no
    friction, or with Coulomb friction, fits as well as the one written (BIC within
    ``INDISTINGUISHABLE_BIC``, or both within ``floor``: exact), the record cannot tell the
    friction from the hydraulic law's shape; the note says so, what the other would write and why
    this one is written (``asked``: named by --friction). The two-stage law's friction check
    (``damper.friction_check``) becomes a warning on the written fit when it says the friction is
    not told."""
    notes = []
    other = "coulomb" if friction != "coulomb" else "none"
    mine, theirs = results[written], results.get(hydraulic if other == "coulomb" else other)
    if theirs is not None:
        exact = max(mine.rms, theirs.rms) <= floor
        a, b = mine.bic_with_floor(floor), theirs.bic_with_floor(floor)
        if exact or abs(a - b) < INDISTINGUISHABLE_BIC:
            without = mine if other == "coulomb" else theirs
            at = without.extra.get("at_bound", {})
            knees = [f"{key.split('.')[-1].split('_')[0]} {value:.4g}" for key, value in without.values.items()
                     if key.endswith("knee_mm_per_s") and at.get(key) == "lower"]
            shape = (f"; {'without friction' if other == 'coulomb' else 'then'} its knees sit at the slowest test speeds "
                     f"({' and '.join(knees)} mm/s), where a steep low-speed stage gives the forces a friction step "
                     "gives" if knees else "")
            alternative = (f"with {theirs.values.get('fork.friction.coulomb_N', 0.0):.4g} N of Coulomb friction"
                           if other == "coulomb" else "without friction")
            why = "as --friction asks" if asked else "the fewer parameters" if exact or a >= b else "the lower BIC"
            notes.append(f"the record cannot tell the friction from the {hydraulic} law's shape: {alternative} the "
                         f"{hydraulic} law fits {'exactly too' if exact else 'as well'} (BIC {b:.1f} against {a:.1f})"
                         f"{shape}; written: {friction} friction, {why} (--friction {other} writes the other; test "
                         "speeds below the slowest tell them apart)")
    check = mine.extra.get("friction_check") or results.get("digressive", mine).extra.get("friction_check")
    if check is not None and not check["told"]:
        warnings = mine.extra.setdefault("warnings", [])
        if check["line"] not in warnings:
            warnings.append(check["line"])
    return notes


def _check_arguments(engine, starts, free, bounds, mass_kg, touch_s, clicks) -> tuple:
    """``identify``'s arguments from Python, each refused in one line naming it before any record is read: a str
    where a list goes was read letter by letter (free="fork.spring.rate_N_per_mm": "a free parameter is listed
    twice"; clicks="1,2": "3 positions for 1 dyno files"), starts=0 or "2" ran, engine="x" was "the fit did not
    converge", touch_s="0.1" met numpy's isfinite."""
    from collections.abc import Mapping

    from mtbmj import limits
    from mtbmj.drop.run import ENGINES
    from mtbmj.errors import ConfigError

    if engine not in ENGINES:
        raise ConfigError(f"engine: {engine!r} is not one of {', '.join(ENGINES)}")
    limits.whole("starts", starts, 1, none_ok=False)
    if free is not None and not (isinstance(free, (list, tuple)) and not free):  # None and () are the default
        free = limits.names("free", free, "fork.spring.rate_N_per_mm", none_ok=False, what="keys")
    if bounds is not None and not isinstance(bounds, Mapping):
        raise ConfigError(f"bounds: must be a mapping of key to (low, high), e.g. "
                          f"{{'fork.spring.rate_N_per_mm': (5, 15)}}, got {limits.described(bounds)}")
    for label, value, what in (("mass_kg", mass_kg, "a number of kg"), ("touch_s", touch_s, "a number of s")):
        if value is not None:
            limits.number(label, value, what)
    if clicks is not None:
        clicks = limits.names("clicks", clicks, 12, none_ok=False, what="positions, one per file", as_item=False)
    return free, clicks  # as lists: a generator given is read once, here


def identify(kind: str, data: Sequence[str | Path], model: str = "auto", friction: str = "auto",
             mass_kg: float | None = None, config: str = "S12", free: Sequence[str] = (),
             bounds: dict | None = None, engine: str = "mujoco", starts: int = 1,
             touch_s: float | None = None, clicks: Sequence[float | Mapping[str, float]] | None = None,
             overrides: Mapping | None = None, progress: Callable[[float], None] | None = None) -> Identification:
    """Fit ``kind`` ("spring", "damper", "tire", "drop") to the record(s) in ``data``; ``starts``:
    drop fits from that many start points (the best wins); ``free``: the drop fit's free keys
    (default ``DEFAULT_DROP_FREE``); ``touch_s``: the drop record's time zero on its clock
    (default: found by ``mtbmj.measured.time_zero``); ``clicks``: damper fits from several dyno files,
    the adjuster position (clicks from closed) of each, or a mapping per file of its adjusters'
    positions by label (``damper_clicks.ADJUSTERS``: lsc, hsc, lsr, hsr, c, r), giving a ``clicks`` damper;
    ``overrides``: drop fits run on ``config`` with these keys set (written into fit.toml too);
    ``progress(fraction)``: called as a damper fit's laws are fitted (a progress bar)."""
    from mtbmj import limits
    from mtbmj.errors import ConfigError

    if kind not in KINDS:  # a bad argument: a ConfigError, a ValueError as Python's own bad values are
        raise ConfigError(f"fit: unknown kind {kind!r} (one of {', '.join(KINDS)})")
    if overrides and kind != "drop":
        raise ConfigError(f"fit {kind}: --set applies to drop fits (the configuration they run on)")
    if data is None or (isinstance(data, (list, tuple)) and not data):
        raise ConfigError(f"fit {kind}: no data file given")
    if isinstance(data, Path):  # one file, not in a list: "dyno.csv" read letter by letter was "d: no such file"
        data = [data]
    data = limits.names("data", data, "dyno.csv", what="files", none_ok=False)
    free, clicks = _check_arguments(engine, starts, free, bounds, mass_kg, touch_s, clicks)
    records = [read_record(p) for p in data]
    if kind in ("spring", "damper"):
        force = records[0].columns.get("force")
        if force is not None and force.size and float(np.ptp(force)) == 0.0:
            raise MtbmjError(f"{records[0].path}: the force column is {force[0]:g} N everywhere: nothing to fit")
    if kind == "spring":
        from mtbmj.identify import spring

        from mtbmj.config import load

        results = spring.fit_spring_all(records[0])
        geometry = load(config)
        base = "reference"
        if geometry.get("fork.spring.model") == "air":  # an air fork's geometry: offer the air model
            results["air"] = spring.fit_air(records[0], geometry)
            from mtbmj.config import preset_names

            named = any(str(config).lower() == n.lower() for n in preset_names())
            base = geometry.name if named else str(Path(config).resolve())
        if model not in ("auto", *results):
            results[model] = spring.fit_spring(records[0], model)  # raises the precise cause, e.g. no extension
        return _spring(records, results, model, spring.plot_spring, base)
    if kind == "damper":
        from mtbmj.identify import damper

        if clicks:
            from mtbmj.identify import damper_clicks

            labelled = any(isinstance(c, Mapping) for c in clicks)
            law = "table" if model == "auto" else model  # the law each file is read through
            result = (damper_clicks.fit_settings(records, [dict(c) if isinstance(c, Mapping) else {"c": c, "r": c}
                                                    for c in clicks], law)
                      if labelled else damper_clicks.fit_clicks(records, list(clicks), law))
            if "model_check" in result.extra:
                _attach_check(result, result.extra["model_check"])
            return Identification("damper", records, {"clicks": result}, ["clicks"],
                                  lambda: damper_clicks.plot_clicks(records, result),
                                  notes=result.extra["notes"])
        if len(records) > 1:
            raise MtbmjError("fit damper: several dyno files need --clicks (the adjuster position of each)")
        step = _steps(progress, len(damper.HYDRAULIC) + len(damper.CHECK_SHAPES) + len(damper.FRICTION))
        results = damper.fit_damper_all(records[0], friction=False, step=step)  # friction: with the law chosen
        return _damper(records, results, model, friction, damper, step)
    if kind == "tire":
        from mtbmj.identify import tire

        drops = [r for r in records if "time" in r.columns]
        ramps = [r for r in records if "time" not in r.columns]
        if len(drops) != 1 or len(ramps) > 1:
            raise MtbmjError("fit tire: give one tire drop record (time_s, deflection_mm) and at most one "
                             "static ramp (deflection_mm, force_N)")
        results = tire.fit_tire(drops[0], mass_kg, ramp=ramps[0] if ramps else None)
        order = [part for part in ("static", "impact", "contact") if part in results]  # as tire.tire_overrides
        for part in ("impact", "contact"):  # the fits of the drop record (the ramp's residual is in N)
            if part in results:
                check = _noise_check(drops[0], "deflection", 1e3, results[part], "mm",
                                     f"residual of the {part} fit: see fit.png")
                if check is not None:
                    _attach_check(results[part], check)
        if "static" in results:  # the ramp: its force against the force's own noise along the ramp
            check = _noise_check(ramps[0], "force", 1.0, results["static"], "N",
                                 "residual of the static ramp: see fit.png")
            if check is not None:
                _attach_check(results["static"], check)
        return Identification("tire", records, results, order, lambda: tire.plot_tire(drops[0], results))
    from mtbmj.identify import dropfit
    from mtbmj.identify.dropfit import error_note

    notes = []
    if not free:
        free = DEFAULT_DROP_FREE
        notes.append(f"no --free given: fitting {', '.join(free)}")
    result = dropfit.fit_drop(records[0], config=config, free=list(free), bounds=bounds, engine=engine,
                              starts=starts, touch_s=touch_s, overrides=overrides)
    x = result.extra
    if x.get("time_zero"):
        notes.append(x["time_zero"]["description"])
    notes.append(f"95 % intervals: Newey-West over residuals correlated for {x['hac_bandwidth_s'] * 1e3:.1f} ms, "
                 f"plus the engine's own error ({error_note(x)}) and the touch's uncertainty; "
                 f"Student t on {x['effective_dof']:.0f} effective samples")
    notes += x.get("notes", [])
    notes.append("bounds: " + "; ".join(f"{k} {a:g} to {b:g}" for k, (a, b) in x["bounds"].items())
                 + " (default: start / 4 to 4 x start; --bound KEY=LOW:HIGH)")
    return Identification("drop", records, {"drop": result}, ["drop"],
                          lambda: dropfit.plot_drop(records[0], result), base=config, notes=notes,
                          overrides={k: v for k, v in (overrides or {}).items() if k not in result.values})

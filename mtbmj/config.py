"""Configurations: TOML files with units in the key names, validated into a flat mapping.

A configuration is a TOML file whose tables mirror the model (``[sled]``, ``[fork.spring]``,
``[fork.damper]``, ``[fork.friction]``, ``[tire]``, ``[solver]``). A file may name a ``base`` (a
preset name or a path) whose values it overrides; the presets S1-S14 all build on ``reference``.
Values are plain numbers in the unit their key names (SI inside the package after conversion in
``mtbmj.compose``). Every problem raises ``ConfigError`` naming the key.
"""
from __future__ import annotations

import difflib
import hashlib
import json
import math
import sys
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from mtbmj.errors import ConfigError
from mtbmj.textfile import read_text

# kinds: "pos" > 0, "nonneg" >= 0, "real" any finite number, "list" of finite numbers, "rows" a
# list of such lists (a table, one row each), "bool", "text", or a tuple of allowed strings.
SPRING_MODELS = ("linear", "compression_rebound", "bilinear", "progressive", "air")
DAMPER_MODELS = ("linear", "bilinear", "digressive", "table", "clicks")
FRICTION_MODELS = ("none", "coulomb", "coulomb_viscous", "stiction", "stribeck", "lugre")
TIRE_MODELS = ("impact", "switch", "undamped", "static")
INTEGRATORS = ("euler", "implicitfast", "implicit", "rk4")
ODE_METHODS = ("Radau", "BDF", "LSODA")

SCHEMA: dict[str, Any] = {
    "description": "text",
    "reading": "text",
    "sled.body_mass_kg": "pos",
    "sled.wheel_mass_kg": "pos",
    "sled.drop_height_mm": "nonneg",
    "sled.gravity_m_per_s2": "pos",
    "fork.travel_mm": "pos",
    "fork.length_mm": "pos",
    "fork.spring.model": SPRING_MODELS,
    "fork.spring.rate_N_per_mm": "pos",
    "fork.spring.compression_rate_N_per_mm": "pos",
    "fork.spring.rebound_rate_N_per_mm": "pos",
    "fork.spring.knee_mm": "pos",
    "fork.spring.rate_below_knee_N_per_mm": "pos",
    "fork.spring.rate_above_knee_N_per_mm": "pos",
    "fork.spring.rebound_curve": "bool",
    "fork.spring.progressive_rate_N_per_mm": "pos",
    "fork.spring.progressive_cubic_N_per_mm3": "nonneg",
    "fork.spring.top_out": "bool",
    "fork.spring.top_out_rate_N_per_mm": "pos",
    "fork.spring.preload": "bool",
    "fork.spring.preload_N": "nonneg",
    "fork.spring.direction_band_mm_per_s": "pos",
    "fork.spring.air_pressure_psi": "real",
    "fork.spring.piston_diameter_mm": "pos",
    "fork.spring.air_volume_cm3": "pos",
    "fork.spring.tokens": "nonneg",
    "fork.spring.token_volume_cm3": "pos",
    "fork.spring.negative_volume_cm3": "nonneg",
    "fork.spring.transfer_port_mm": "nonneg",
    "fork.spring.polytropic_index": "pos",
    "fork.damper.model": DAMPER_MODELS,
    "fork.damper.coefficient_N_s_per_m": "nonneg",
    "fork.damper.compression_N_s_per_m": "nonneg",
    "fork.damper.rebound_N_s_per_m": "nonneg",
    "fork.damper.compression_low_N_s_per_m": "nonneg",
    "fork.damper.compression_high_N_s_per_m": "nonneg",
    "fork.damper.compression_knee_mm_per_s": "pos",
    "fork.damper.rebound_low_N_s_per_m": "nonneg",
    "fork.damper.rebound_high_N_s_per_m": "nonneg",
    "fork.damper.rebound_knee_mm_per_s": "pos",
    "fork.damper.velocity_mm_per_s": "list",
    "fork.damper.force_N": "list",
    "fork.damper.compression_clicks": "nonneg",
    "fork.damper.rebound_clicks": "nonneg",
    "fork.damper.compression_clicks_measured": "list",
    "fork.damper.rebound_clicks_measured": "list",
    "fork.damper.compression_force_N": "rows",
    "fork.damper.rebound_force_N": "rows",
    "fork.damper.low_speed_compression_clicks": "nonneg",
    "fork.damper.low_speed_compression_clicks_measured": "list",
    "fork.damper.low_speed_compression_force_N": "rows",
    "fork.damper.low_speed_compression_reference_clicks": "nonneg",
    "fork.damper.high_speed_compression_clicks": "nonneg",
    "fork.damper.high_speed_compression_clicks_measured": "list",
    "fork.damper.high_speed_compression_force_N": "rows",
    "fork.damper.high_speed_compression_reference_clicks": "nonneg",
    "fork.damper.low_speed_rebound_clicks": "nonneg",
    "fork.damper.low_speed_rebound_clicks_measured": "list",
    "fork.damper.low_speed_rebound_force_N": "rows",
    "fork.damper.low_speed_rebound_reference_clicks": "nonneg",
    "fork.damper.high_speed_rebound_clicks": "nonneg",
    "fork.damper.high_speed_rebound_clicks_measured": "list",
    "fork.damper.high_speed_rebound_force_N": "rows",
    "fork.damper.high_speed_rebound_reference_clicks": "nonneg",
    "fork.friction.model": FRICTION_MODELS,
    "fork.friction.coulomb_N": "nonneg",
    "fork.friction.breakaway_N": "nonneg",
    "fork.friction.viscous_N_s_per_m": "nonneg",
    "fork.friction.stiction_band_mm_per_s": "pos",
    "fork.friction.stribeck_velocity_mm_per_s": "pos",
    "fork.friction.stribeck_exponent": "pos",
    "fork.friction.sign_band_mm_per_s": "pos",
    "fork.friction.bristle_stiffness_N_per_mm": "pos",
    "fork.friction.bristle_damping_N_s_per_m": "nonneg",
    "fork.friction.stick": "bool",
    "fork.friction.stick_stiffness_N_per_mm": "pos",
    "fork.friction.stick_damping_N_s_per_m": "nonneg",
    "fork.friction.stick_damping_velocity_mm_per_s": "pos",
    "fork.stops.bumper_length_mm": "pos",
    "fork.stops.bumper_force_N": "nonneg",
    "fork.stops.stop_rate_N_per_mm": "pos",
    "fork.stops.stop_damping_N_s_per_m": "nonneg",
    "fork.stops.extension_mm": "pos",
    "tire.model": TIRE_MODELS,
    "tire.radius_mm": "pos",
    "tire.impact_rate_N_per_mm": "pos",
    "tire.impact_damping_N_s_per_m": "nonneg",
    "tire.contact_rate_N_per_mm": "pos",
    "tire.contact_damping_N_s_per_m": "nonneg",
    "tire.static_rate_N_per_mm": "pos",
    "tire.max_deflection_mm": "pos",
    "tire.rim_rate_N_per_mm": "pos",
    "tire.rim_damping_N_s_per_m": "nonneg",
    "tire.pressure_psi": "real",
    "solver.duration_s": "pos",
    "solver.timestep_s": "pos",
    "solver.integrator": INTEGRATORS,
    "solver.ode_method": ODE_METHODS,
    "solver.ode_rtol": "pos",
    "solver.ode_atol_mm": "pos",
    "solver.sample_rate_Hz": "pos",
    "solver.antialias_Hz": "pos",
}

UNIT_SUFFIXES = (
    "_N_s_per_m", "_N_per_mm3", "_N_per_mm", "_mm_per_s", "_m_per_s2", "_kg", "_mm", "_N", "_s", "_Hz",
    "_psi", "_cm3",
)


def _stem(key: str) -> str:
    for suffix in UNIT_SUFFIXES:
        if key.endswith(suffix):
            return key[: -len(suffix)]
    return key


_STEMS = {_stem(k): k for k in SCHEMA if _stem(k) != k}


MAX_TABLE_DEPTH = 6  # the schema nests 3 deep (fork.spring.rate_N_per_mm)


def _flatten(table: Mapping[str, Any], prefix: str = "", depth: int = 0) -> dict[str, Any]:
    if depth > MAX_TABLE_DEPTH:
        raise ConfigError(f"{prefix[:60]}...: tables nested deeper than {MAX_TABLE_DEPTH} levels")
    flat: dict[str, Any] = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(_flatten(value, name + ".", depth + 1))
        else:
            flat[name] = value
    return flat


def check_value(key: str, value: Any) -> Any:
    """Validate one value against the schema; return it (lists as tuples of floats)."""
    if key not in SCHEMA:
        if key in _STEMS:
            raise ConfigError(f"{key}: value without its unit; the key is {_STEMS[key]}")
        close = difflib.get_close_matches(key, list(SCHEMA), n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise ConfigError(f"{key}: unknown key{hint}")
    kind = SCHEMA[key]
    if kind == "bool":
        if not isinstance(value, bool):
            raise ConfigError(f"{key}: must be true or false, got {value!r}")
        return value
    if kind == "text":
        if not isinstance(value, str):
            raise ConfigError(f"{key}: must be text")
        return value
    if isinstance(kind, tuple):
        if value not in kind:
            raise ConfigError(f"{key}: {value!r} is not one of {', '.join(kind)}")
        return value
    if kind == "rows":
        if not isinstance(value, (list, tuple)) or not value or not all(
                isinstance(row, (list, tuple)) and all(_is_number(v) for v in row) for row in value):
            raise ConfigError(f"{key}: must be a list of lists of numbers (one list per row)")
        if not all(math.isfinite(v) for row in value for v in row):
            raise ConfigError(f"{key}: contains NaN or infinity")
        return tuple(tuple(float(v) for v in row) for row in value)
    if kind == "list":
        if not isinstance(value, (list, tuple)) or not all(_is_number(v) for v in value):
            raise ConfigError(f"{key}: must be a list of numbers")
        if len(value) > MAX_LIST:
            raise ConfigError(f"{key}: more than {MAX_LIST} values")
        if not all(_is_finite(v) for v in value):
            raise ConfigError(f"{key}: contains NaN, infinity or a number too large")
        return tuple(float(v) for v in value)
    if isinstance(value, str):
        raise ConfigError(f"{key}: must be a plain number (the unit is in the key name), got {value!r}")
    if not _is_number(value):
        raise ConfigError(f"{key}: must be a number, got {value!r}")
    if not _is_finite(value):
        raise ConfigError(f"{key}: must be finite, got {value if isinstance(value, float) else 'a number too large'}")
    value = float(value)
    if abs(value) > MAX_MAGNITUDE:
        raise ConfigError(f"{key}: {value:g} is beyond any physical fork or sled (at most {MAX_MAGNITUDE:g} in its unit)")
    if kind == "pos" and value <= 0.0:
        raise ConfigError(f"{key}: must be positive, got {value:g}")
    if kind == "nonneg" and value < 0.0:
        raise ConfigError(f"{key}: must not be negative, got {value:g}")
    return value


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_finite(value: int | float) -> bool:
    try:
        return math.isfinite(float(value))
    except OverflowError:  # an integer beyond the float range
        return False


MAX_LIST = 10_000  # values in a list key (a damper table)
# No key's value is anywhere near this in its unit (N/mm, kg, mm, s); beyond it MuJoCo's model
# becomes singular (a 1e200 kg wheel) and it prints its own warnings before failing.
MAX_MAGNITUDE = 1e30


def preset_names() -> list[str]:
    files = resources.files("mtbmj.presets").iterdir()
    names = [f.name[:-5] for f in files if f.name.endswith(".toml")]
    return sorted(names, key=lambda n: (not n.startswith("S"), int(n[1:]) if n[1:].isdigit() else 0, n))


def study_presets() -> list[str]:
    return [f"S{i}" for i in range(1, 15)]


@dataclass(frozen=True)
class Config:
    """A validated configuration: ``values`` maps dotted keys (``fork.spring.rate_N_per_mm``)
    to numbers, strings or tuples of numbers."""

    name: str
    values: Mapping[str, Any]
    sources: tuple[str, ...] = field(default=())

    def __getitem__(self, key: str) -> Any:
        return self.require(key)

    def get(self, key: str, default: Any = None) -> Any:
        return self.values.get(key, default)

    def require(self, key: str, why: str = "") -> Any:
        if key not in self.values:
            reason = f" ({why})" if why else ""
            raise ConfigError(f"{key}: missing{reason}")
        return self.values[key]

    def with_overrides(self, overrides: Mapping[str, Any]) -> "Config":
        values = dict(self.values)
        for key, value in overrides.items():
            values[key] = check_value(key, value)
        return Config(self.name, values, self.sources)

    def digest(self) -> str:
        """SHA-256 of the canonical JSON of the values: the config hash in manifests."""
        text = json.dumps({k: self.values[k] for k in sorted(self.values)}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def to_toml(self) -> str:
        """The configuration as TOML, tables in schema order; loads back to the same values."""
        sections: dict[str, list[str]] = {}
        for key in sorted(self.values, key=lambda k: list(SCHEMA).index(k)):
            section, _, leaf = key.rpartition(".")
            sections.setdefault(section, []).append(f"{leaf} = {_toml_value(self.values[key])}")
        chunks = ["\n".join(sections.pop(""))] if "" in sections else []
        chunks += [f"[{s}]\n" + "\n".join(lines) for s, lines in sections.items()]
        return "\n\n".join(chunks) + "\n"


def parameter_set_toml(values: Mapping[str, Any], base: str = "reference", description: str = "",
                       comments: Mapping[str, str] | None = None) -> str:
    """A configuration file holding ``values`` on top of ``base``: what identification writes.

    Every value is validated, and the text is checked to load back to the same values, so the
    file is accepted by ``mtbmj drop`` as is."""
    checked = {k: check_value(k, v) for k, v in values.items()}
    comments = comments or {}
    head = []
    if description:
        head.append(f"description = {json.dumps(description)}")
    head.append(f"base = {json.dumps(base)}")
    sections: dict[str, list[str]] = {}
    for key in sorted(checked, key=lambda k: list(SCHEMA).index(k)):
        section, _, leaf = key.rpartition(".")
        note = f"  # {comments[key]}" if key in comments else ""
        sections.setdefault(section, []).append(f"{leaf} = {_toml_value(checked[key])}{note}")
    chunks = ["\n".join(head + sections.pop("", []))]
    chunks += [f"[{s}]\n" + "\n".join(lines) for s, lines in sections.items()]
    text = "\n\n".join(chunks) + "\n"
    back = _flatten(tomllib.loads(text))
    back.pop("base", None)
    back.pop("description", None)
    assert {k: check_value(k, v) for k, v in back.items()} == checked
    return text


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, tuple):
        if value and isinstance(value[0], tuple):
            return "[" + ", ".join(_toml_value(row) for row in value) + "]"
        return "[" + ", ".join(repr(float(v)) for v in value) + "]"
    return repr(float(value))


def parse_assignment(text: str) -> tuple[str, Any]:
    """Parse a ``--set key=value`` override; the value is read as TOML (numbers, lists) or,
    failing that, as a bare word (model names)."""
    if "=" not in text:
        raise ConfigError(f"--set {text}: expected key=value")
    key, raw = (part.strip() for part in text.split("=", 1))
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    except RecursionError:
        raise ConfigError(f"--set {key}: value nested too deeply") from None
    return key, value


def _read_toml(path: Path) -> dict[str, Any]:
    text = read_text(path, ConfigError, str(path), "not a text file, so not a TOML configuration")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ConfigError(f"{path}: arrays or tables nested too deeply") from None


def _locate(ref: str) -> tuple[str, Path | Any]:
    """Resolve a preset name (case-insensitive) or a TOML path."""
    for name in preset_names():
        if ref.lower() == name.lower():
            return name, resources.files("mtbmj.presets") / f"{name}.toml"
    path = Path(ref)
    if path.suffix.lower() == ".toml" or path.exists():
        if not path.exists():
            raise ConfigError(f"{ref}: no such configuration file")
        return path.stem, path
    known = ", ".join(preset_names())
    raise ConfigError(f"{ref}: unknown preset (known: {known}) and no such file")


def _is_preset(name: str) -> bool:
    return any(name.lower() == n.lower() for n in preset_names())


def _base_path(base: str, including: Path, roots: tuple[Path, ...]) -> str:
    """Where a ``base`` path of the file ``including`` points, if it is allowed there.

    The rule: a base is a preset name or a ``.toml`` file; a relative path is relative to the
    folder of the file that names it; and the file must lie (symbolic links resolved) inside the
    current directory or the folder of the configuration named on the command line, or below
    either. So a configuration cannot make mtbmj read, or name keys of, files elsewhere."""
    if Path(base).suffix.lower() != ".toml":
        raise ConfigError(f"{including}: base {base!r} must be a preset name or a .toml file")
    path = Path(base) if Path(base).is_absolute() else including.parent / base
    try:
        real = path.resolve()
    except (OSError, RuntimeError) as exc:  # a symbolic-link loop
        raise ConfigError(f"{including}: base {base!r} cannot be resolved ({exc})") from None
    if not any(real.is_relative_to(root) for root in roots):
        raise ConfigError(f"{including}: base {base!r} lies outside the current directory and the folder of "
                          f"the configuration named on the command line; copy it there")
    return str(path)


MAX_BASE_DEPTH = 8


def load(ref: str | Path, overrides: Mapping[str, Any] | None = None, _depth: int = 0,
         _roots: tuple[Path, ...] | None = None) -> Config:
    """Load a preset name or a TOML file, following ``base`` links (see :func:`_base_path` for
    where a base may be), then apply overrides."""
    if _depth > MAX_BASE_DEPTH:
        raise ConfigError(f"{ref}: base chain longer than {MAX_BASE_DEPTH} (a cycle?)")
    name, location = _locate(str(ref))
    if isinstance(location, Path):
        table = _read_toml(location)
        if _roots is None:
            _roots = (Path.cwd().resolve(), location.resolve().parent)
    else:
        table = tomllib.loads(location.read_text())
    values: dict[str, Any] = {}
    sources: tuple[str, ...] = ()
    base = table.pop("base", None)
    try:
        flat = _flatten(table)
    except ConfigError as exc:
        raise ConfigError(f"{location}: {exc}") from None
    if base is not None:
        if not isinstance(base, str):
            raise ConfigError(f"{location}: base must be a preset name or a path")
        if isinstance(location, Path) and not _is_preset(base):
            base = _base_path(base, location, _roots or ())
        parent_config = load(base, _depth=_depth + 1, _roots=_roots)
        values.update(parent_config.values)
        sources = parent_config.sources
        values.pop("description", None)
        values.pop("reading", None)
    for key, value in flat.items():
        try:
            values[key] = check_value(key, value)
        except ConfigError as exc:
            raise ConfigError(f"{location}: {exc}") from None
    config = Config(name, values, sources + (str(location),))
    if overrides:
        config = config.with_overrides(overrides)
    return config


__all__ = ["Config", "ConfigError", "load", "parse_assignment", "preset_names", "study_presets", "SCHEMA"]

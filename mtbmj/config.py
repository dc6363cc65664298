"""Configurations: TOML files with units in the key names, validated into a flat mapping.

A configuration is a TOML file whose tables mirror the model (``[sled]``, ``[fork.spring]``,
``[fork.damper]``, ``[fork.friction]``, ``[tire]``, ``[solver]``). A file may name a ``base`` (a
preset name or a path) whose values it overrides; the presets S1-S14 all build on ``reference``.
Values are plain numbers in the unit their key names (SI inside the package after conversion in
``mtbmj.compose``). Every problem raises ``ConfigError`` naming the key.

A few keys give a value in a rider's terms and are converted as they are read, so the rest of the
package sees only the canonical key: ``fork.spring.rate_lb_per_in`` (for ``rate_N_per_mm``), the
pressures in bar (for psi), and the load as ``sled.rider_mass_kg``, ``sled.bike_mass_kg`` and
``sled.front_share_percent`` (for ``sled.body_mass_kg``, see :func:`sprung_front_mass`). A value
far outside what any bike or sled has is not refused but warned about (:func:`plausibility`,
:class:`ConfigWarning`). Every key with its unit, default and range: docs/configuration.md.
"""
from __future__ import annotations

import difflib
import hashlib
import json
import sys
import warnings as _warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from mtbmj import limits
from mtbmj.limits import MISTAKES, N_PER_MM_PER_LB_PER_IN, PA_PER_PSI, PSI_PER_BAR  # noqa: F401 (re-exported)
from mtbmj.errors import ConfigError, ConfigWarning  # ConfigWarning: a value far outside what any bike has
from mtbmj.presets import is_preset as _is_preset, locate as _locate, preset_names, study_presets  # noqa: F401
from mtbmj.textfile import read_text

# kinds: "pos" > 0, "nonneg" >= 0, "real" any finite number, "list" of finite numbers, "rows" a
# list of such lists (a table, one row each), "bool", "text", or a tuple of allowed strings.
SPRING_MODELS = ("linear", "compression_rebound", "bilinear", "progressive", "air")
DAMPER_MODELS = ("linear", "bilinear", "digressive", "orifice", "table", "clicks")
FRICTION_MODELS = ("none", "coulomb", "coulomb_viscous", "stiction", "stribeck", "lugre")
TIRE_MODELS = ("impact", "switch", "undamped", "static")
INTEGRATORS = ("euler", "implicitfast", "implicit", "rk4")
ODE_METHODS = ("Radau", "BDF", "LSODA")

SCHEMA: dict[str, Any] = {
    "description": "text",
    "reading": "text",
    "sled.body_mass_kg": "pos",
    "sled.rider_mass_kg": "pos",
    "sled.bike_mass_kg": "pos",
    "sled.front_share_percent": "pos",
    "sled.wheel_mass_kg": "pos",
    "sled.drop_height_mm": "nonneg",
    "sled.gravity_m_per_s2": "pos",
    "fork.travel_mm": "pos",
    "fork.length_mm": "pos",
    "fork.spring.model": SPRING_MODELS,
    "fork.spring.rate_N_per_mm": "pos",
    "fork.spring.rate_lb_per_in": "pos",
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
    "fork.spring.air_pressure_bar": "nonneg",
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
    "fork.damper.bleed_N_s_per_m": "nonneg",
    "fork.damper.compression_orifice_N_s2_per_m2": "nonneg",
    "fork.damper.rebound_orifice_N_s2_per_m2": "nonneg",
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
    "tire.pressure_psi": "pos",
    "tire.pressure_bar": "pos",
    "solver.duration_s": "pos",
    "solver.timestep_s": "pos",
    "solver.integrator": INTEGRATORS,
    "solver.ode_method": ODE_METHODS,
    "solver.ode_rtol": "pos",
    "solver.ode_atol_mm": "pos",
    "solver.sample_rate_Hz": "pos",
    "solver.antialias_Hz": "pos",
}

# The unit each key name ends in (the longest match first), as messages and docs write it.
UNITS = {
    "_N_s_per_m": "N s/m", "_N_per_mm3": "N/mm3", "_N_per_mm": "N/mm", "_mm_per_s": "mm/s", "_m_per_s2": "m/s2",
    "_lb_per_in": "lb/in", "_percent": "%", "_kg": "kg", "_mm": "mm", "_N": "N", "_s": "s", "_Hz": "Hz",
    "_psi": "psi", "_bar": "bar", "_cm3": "cm3",
}
UNIT_SUFFIXES = tuple(UNITS)


def unit_of(key: str) -> str:
    """The unit a key's name states (``"N/mm"`` for ``fork.spring.rate_N_per_mm``), or ``""``."""
    for suffix, unit in UNITS.items():
        if key.endswith(suffix):
            return unit
    return ""


def _stem(key: str) -> str:
    for suffix in UNIT_SUFFIXES:
        if key.endswith(suffix):
            return key[: -len(suffix)]
    return key


_STEMS: dict[str, list[str]] = {}
for _key in SCHEMA:
    if _stem(_key) != _key:
        _STEMS.setdefault(_stem(_key), []).append(_key)


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
            first, *others = _STEMS[key]
            also = "".join(f" (or {k})" for k in others)
            raise ConfigError(f"{key}: value without its unit; the key is {first}{also}")
        inside = next((name for name in SCHEMA if name.startswith(f"{key}.")), None)
        if inside is not None and isinstance(value, dict):  # `--set 'sled={body_mass_kg=5}'` (a file flattens it)
            first = next(iter(value), inside[len(key) + 1:])
            raise ConfigError(f"{key}: a table given whole; set its keys one at a time, e.g. --set "
                              f"{key}.{first}={value.get(first, '...')}")
        if inside is not None:  # `sled = 5` in a file, `--set fork=5`: a table given a value
            raise ConfigError(f"{key}: is a table of keys (e.g. {inside}), not a value; got {value!r}")
        raise ConfigError(f"{key}: unknown key{_hint(key)}")
    kind = SCHEMA[key]
    if kind == "bool":
        if not isinstance(value, bool):
            meant = _STEMS.get(key) if _is_number(value) else None  # preload=60: the force is preload_N
            raise ConfigError(f"{key}: must be true or false, got {value!r}" + (f" (a number is {meant[0]})" if meant
                                                                                  else ""))
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
        return tuple(tuple(limits.number(key, v) for v in row) for row in value)
    if kind == "list":
        if not isinstance(value, (list, tuple)) or not all(_is_number(v) for v in value):
            raise ConfigError(f"{key}: must be a list of numbers")
        if len(value) > MAX_LIST:
            raise ConfigError(f"{key}: more than {MAX_LIST} values")
        return tuple(limits.number(key, v) for v in value)
    if isinstance(value, str):
        raise ConfigError(f"{key}: must be a plain number (the unit is in the key name), got {value!r}")
    value = limits.number(key, value)  # the numeric-input gate: finite, fits a float, within MAX_MAGNITUDE
    if kind == "pos" and value <= 0.0:
        raise ConfigError(f"{key}: must be positive, got {value:g}")
    if kind == "nonneg" and value < 0.0:
        raise ConfigError(f"{key}: must not be negative, got {value:g}")
    if key in UPPER_LIMITS and value > UPPER_LIMITS[key][0]:
        raise ConfigError(f"{key}: {value:g} is more than {UPPER_LIMITS[key][1]}")
    return value


def unit_keys(key: str, keys=SCHEMA) -> list[str] | None:
    """The keys among ``keys`` of ``key``'s table in the unit its name holds alone (``fork.spring.psi``:
    ``fork.spring.air_pressure_psi``), or None where its last part is no unit."""
    table, _, last = key.rpartition(".")
    if f"_{last}" not in UNITS:
        return None
    return [k for k in keys if k.rpartition(".")[0] == table and k.endswith(f"_{last}")]


def _hint(key: str) -> str:
    """The key meant: a unit alone in the name's place (``fork.spring.psi``) is the keys of that
    table in that unit (spelling alone took it for ``fork.spring.tokens``), else the closest name."""
    in_unit = unit_keys(key)
    if in_unit:
        return f" (a unit, not a key: did you mean {' or '.join(in_unit)}?)"
    close = difflib.get_close_matches(key, list(SCHEMA), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


MAX_LIST = 10_000  # values in a list key (a damper table)
# No key's value is anywhere near this in its unit (N/mm, kg, mm, s); beyond it MuJoCo's model
# becomes singular (a 1e200 kg wheel) and it prints its own warnings before failing.
MAX_MAGNITUDE = limits.MAX_MAGNITUDE


# --- keys a rider gives in other terms -----------------------------------------------------------
# Converted when a configuration is read (``load``, ``Config.with_overrides``), so everything
# downstream sees only the canonical key; a file or a set of overrides may give one key of a pair,
# not both. A later source (a file over its base, overrides over the file) replaces the value
# whichever key it uses.

# The one table of lb/in and psi, and the unit slips, are mtbmj.limits' (floor 0: a command's argument
# names a slip as a key does); compose reads PA_PER_PSI here, bike.shock N_PER_MM_PER_LB_PER_IN.

ALTERNATIVES: dict[str, tuple[str, float]] = {
    # key: (canonical key, its value per unit of the key)
    "fork.spring.rate_lb_per_in": ("fork.spring.rate_N_per_mm", N_PER_MM_PER_LB_PER_IN),
    "fork.spring.air_pressure_bar": ("fork.spring.air_pressure_psi", PSI_PER_BAR),
    "tire.pressure_bar": ("tire.pressure_psi", PSI_PER_BAR),
}
CANONICAL = {canonical: alt for alt, (canonical, _) in ALTERNATIVES.items()}

# The load as a rider gives it. The fork carries the front share of the weight of rider and bike
# less the front wheel's own (the wheel is below the fork: unsprung):
#   sled.body_mass_kg = sled.front_share_percent / 100 x (sled.rider_mass_kg + sled.bike_mass_kg)
#                       - sled.wheel_mass_kg
# (the paper's 53.2 kg is about an 85 kg rider and an 11 kg bike at 57.8 % on the front).
RIDER_KEYS = ("sled.rider_mass_kg", "sled.bike_mass_kg", "sled.front_share_percent")
BODY_KEY = "sled.body_mass_kg"
WHEEL_KEY = "sled.wheel_mass_kg"

# hard upper limits: (limit, what is beyond it)
UPPER_LIMITS = {"sled.front_share_percent": (100.0, "100 %: the front cannot carry more than all of rider and bike")}


def sprung_front_mass(rider_kg: float, bike_kg: float, front_share_percent: float, wheel_kg: float) -> float:
    """The mass the fork carries (kg): the front share of rider and bike, less the front wheel."""
    return front_share_percent / 100.0 * (rider_kg + bike_kg) - wheel_kg


# --- plausibility ---------------------------------------------------------------------------------
# What any bike or the drop sled has, wide: a value outside is more likely a unit mistake than a
# bike. It is a warning (the run proceeds), not a refusal. 0 is exempt where a key allows it (no
# damping, no drop). See docs/configuration.md.
_SPRING = (0.5, 200.0)        # N/mm: a fork coil (about 3-15) to a stiff rear-shock coil (700 lb/in = 123)
_DAMPING = (10.0, 50000.0)    # N s/m: a bike damper's slopes are about 100-5000
_TIRE_RATE = (10.0, 500.0)    # N/mm: 62-86 for the sled's 29 x 2.3 (docs/reference.md); fat to road tires
PLAUSIBLE: dict[str, tuple[float, float]] = {
    "sled.body_mass_kg": (5.0, 150.0),  # the mass the fork carries (what --load-kg sets): at most a heavy rider's
    "sled.rider_mass_kg": (15.0, 250.0),
    "sled.bike_mass_kg": (3.0, 60.0),
    "sled.front_share_percent": (20.0, 80.0),
    "sled.wheel_mass_kg": (0.3, 15.0),
    "sled.drop_height_mm": (1.0, 5000.0),
    "sled.gravity_m_per_s2": (1.0, 30.0),
    "fork.travel_mm": (20.0, 300.0),
    "fork.length_mm": (200.0, 1500.0),
    "fork.spring.rate_N_per_mm": _SPRING,
    "fork.spring.rate_lb_per_in": (3.0, 1150.0),
    "fork.spring.compression_rate_N_per_mm": _SPRING,
    "fork.spring.rebound_rate_N_per_mm": _SPRING,
    "fork.spring.rate_below_knee_N_per_mm": _SPRING,
    "fork.spring.rate_above_knee_N_per_mm": _SPRING,
    "fork.spring.progressive_rate_N_per_mm": _SPRING,
    "fork.spring.knee_mm": (1.0, 300.0),
    "fork.spring.top_out_rate_N_per_mm": (0.5, 2000.0),
    "fork.spring.preload_N": (1.0, 5000.0),
    "fork.spring.air_pressure_psi": (15.0, 400.0),
    "fork.spring.air_pressure_bar": (1.0, 27.5),
    "fork.spring.piston_diameter_mm": (10.0, 80.0),
    "fork.spring.air_volume_cm3": (20.0, 2000.0),
    "fork.spring.token_volume_cm3": (1.0, 100.0),
    "fork.spring.negative_volume_cm3": (1.0, 2000.0),
    "fork.damper.coefficient_N_s_per_m": _DAMPING,
    "fork.damper.compression_N_s_per_m": _DAMPING,
    "fork.damper.rebound_N_s_per_m": _DAMPING,
    "fork.damper.compression_low_N_s_per_m": _DAMPING,
    "fork.damper.compression_high_N_s_per_m": _DAMPING,
    "fork.damper.rebound_low_N_s_per_m": _DAMPING,
    "fork.damper.rebound_high_N_s_per_m": _DAMPING,
    "fork.damper.compression_knee_mm_per_s": (5.0, 5000.0),
    "fork.damper.rebound_knee_mm_per_s": (5.0, 5000.0),
    "fork.damper.bleed_N_s_per_m": _DAMPING,
    # N s^2/m^2: about 1000 N at 1-3 m/s makes 100-1000
    "fork.damper.compression_orifice_N_s2_per_m2": (10.0, 50000.0),
    "fork.damper.rebound_orifice_N_s2_per_m2": (10.0, 50000.0),
    "fork.friction.coulomb_N": (1.0, 1000.0),
    "fork.friction.breakaway_N": (1.0, 1000.0),
    "fork.stops.bumper_length_mm": (0.5, 100.0),
    "fork.stops.bumper_force_N": (10.0, 100000.0),
    "fork.stops.stop_rate_N_per_mm": (100.0, 1e6),
    "fork.stops.extension_mm": (0.5, 100.0),
    "tire.radius_mm": (150.0, 500.0),
    "tire.impact_rate_N_per_mm": _TIRE_RATE,
    "tire.contact_rate_N_per_mm": _TIRE_RATE,
    "tire.static_rate_N_per_mm": _TIRE_RATE,
    "tire.impact_damping_N_s_per_m": (5.0, 10000.0),
    "tire.contact_damping_N_s_per_m": (5.0, 10000.0),
    "tire.max_deflection_mm": (5.0, 150.0),
    "tire.rim_rate_N_per_mm": (100.0, 1e6),
    "tire.pressure_psi": (5.0, 60.0),
    "tire.pressure_bar": (0.35, 4.0),
}


# The tire's pressure-to-rate relation rests on measurements from 15 to 25 psi (Dressel & Sadauckas
# 2020, secondhand; mtbmj.controllers.tire.PRESSURE_RANGE): outside it the rates are extrapolated.
TIRE_PRESSURE_MEASURED_PSI = (15.0, 25.0)


def plausibility(key: str, value: Any) -> str | None:
    """The warning for ``key = value`` (a checked value), or None when it is plausible."""
    if key not in PLAUSIBLE or isinstance(value, bool) or not isinstance(value, float) or value <= 0.0:
        return None
    low, high = PLAUSIBLE[key]
    unit = unit_of(key)
    if low <= value <= high:
        canonical, per = ALTERNATIVES.get(key, (key, 1.0))
        if canonical == "tire.pressure_psi":
            psi = value * per
            lo, hi = TIRE_PRESSURE_MEASURED_PSI
            if not lo <= psi <= hi:
                return (f"{key} = {value:g} {unit} is outside {lo:g}-{hi:g} psi, the measured range of the tire's "
                        f"pressure-to-rate relation (Dressel & Sadauckas 2020): its rates are extrapolated "
                        f"(rate proportional to the gauge pressure, assumed)")
        return None
    said = f"{key} = {value:g} {unit} is far {'below' if value < low else 'above'} what any bike or sled has"
    meant = limits.slip(value, unit, (low, high))
    if meant:
        return f"{said} ({low:g}-{high:g} {unit}):{meant}"
    return f"{said}: probably meant a value within {low:g}-{high:g} {unit}"


def _apply(values: dict[str, Any], notes: dict[str, str], given: Mapping[str, Any]) -> None:
    """Apply the keys one source gives (a file's table or a set of overrides, unchecked) onto
    ``values`` and their warnings ``notes`` (keyed by the key whose value they concern), in place."""
    checked = {key: check_value(key, value) for key, value in given.items()}
    for alt, (canonical, _) in ALTERNATIVES.items():
        if alt in checked and canonical in checked:
            raise ConfigError(f"{canonical} and {alt}: the same value given in two units; give one of them")
    rider = [k for k in RIDER_KEYS if k in checked]
    if rider and BODY_KEY in checked:
        raise ConfigError(f"{BODY_KEY} and {', '.join(rider)}: the load given two ways; give either {BODY_KEY} or "
                          f"the rider inputs ({', '.join(RIDER_KEYS)})")
    for key, value in checked.items():
        target, per = ALTERNATIVES.get(key, (key, 1.0))
        values[target] = value * per if per != 1.0 else value
        notes.pop(target, None)
        note = plausibility(key, value)
        if note:
            notes[target] = note
    if BODY_KEY in checked:  # the load given as the sprung mass replaces rider inputs from below
        for k in RIDER_KEYS:
            values.pop(k, None)
            notes.pop(k, None)
    elif rider or (WHEEL_KEY in checked and all(k in values for k in RIDER_KEYS)):
        missing = [k for k in RIDER_KEYS if k not in values]
        if missing:
            raise ConfigError(f"{', '.join(rider)}: the load from rider inputs needs {' and '.join(missing)} too "
                              f"(or give {BODY_KEY} alone)")
        if WHEEL_KEY not in values:
            raise ConfigError(f"{WHEEL_KEY}: missing (the load from rider inputs subtracts the front wheel)")
        mass = sprung_front_mass(*(values[k] for k in RIDER_KEYS), values[WHEEL_KEY])
        if not mass > 0.0:
            front = mass + values[WHEEL_KEY]
            hints = "".join(f"; {notes[k]}" for k in RIDER_KEYS + (WHEEL_KEY,) if k in notes)  # a unit mistake?
            raise ConfigError(f"{', '.join(RIDER_KEYS)}: the front carries {front:g} kg of rider and bike, no more than "
                              f"{WHEEL_KEY} = {values[WHEEL_KEY]:g} kg, leaving nothing for the fork{hints}")
        values[BODY_KEY] = mass
        notes.pop(BODY_KEY, None)


def warn(messages, stacklevel: int = 2) -> None:
    """Issue each message as a :class:`ConfigWarning` (shown as the caller's filters say)."""
    for message in messages:
        _warnings.warn(message, ConfigWarning, stacklevel=stacklevel + 1)


@dataclass(frozen=True)
class Config:
    """A validated configuration: ``values`` maps dotted keys (``fork.spring.rate_N_per_mm``)
    to numbers, strings or tuples of numbers."""

    name: str
    values: Mapping[str, Any]
    sources: tuple[str, ...] = field(default=())
    # the plausibility warnings of the values in effect, keyed by the key each concerns
    notes: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)
    given: frozenset = field(default=frozenset(), compare=False, repr=False)  # the keys a person set
    # the keys the file named sets itself on its base (not its bases', nor overrides): key -> that file; one
    # its model does not read is said in a warning line (mtbmj.compose)
    filed: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)

    @property
    def warnings(self) -> list[str]:
        """One line per value far outside what any bike or sled has (see :func:`plausibility`)."""
        return list(self.notes.values())

    def get(self, key: str, default: Any = None) -> Any:
        return self.values.get(key, default)

    def require(self, key: str, why: str = "") -> Any:
        if key not in self.values:
            first = Path(self.sources[0]) if self.sources else None  # the chain's start: a preset, or a file
            unbased = first is not None and not (first.parent.name == "presets" and _is_preset(first.stem))
            raise ConfigError(f"{key}: missing" + (f" ({why})" if why else "") + (
                f" ({first.name} starts from no preset: a file gives every key or names one it changes, e.g. "
                f'base = "S12"; mtbmj presets lists them)' if unbased else ""))
        return self.values[key]

    __getitem__ = require

    def with_overrides(self, overrides: Mapping[str, Any]) -> "Config":
        """A copy with ``overrides`` applied as one source: an alternative-unit key sets its
        canonical key, rider inputs set ``sled.body_mass_kg``; the copy's ``warnings`` cover them
        (issued by :func:`load`, not here: fits and solvers call this in their loops)."""
        limits.require_mapping(overrides, "'sled.drop_height_mm': 300", none_ok=False)  # not an AttributeError
        values, notes = dict(self.values), dict(self.notes)
        _apply(values, notes, overrides)
        typed = getattr(overrides, "typed", False)  # a person's keys (mtbmj.cli.common.Typed): each must be read
        given = self.given | ({ALTERNATIVES.get(k, (k,))[0] for k in overrides} if typed else set())
        replaced = {ALTERNATIVES.get(k, (k,))[0] for k in overrides}
        return Config(self.name, values, self.sources, notes, given,
                      {k: f for k, f in self.filed.items() if k not in replaced})

    def digest(self) -> str:
        """SHA-256 of the canonical JSON of the values: the config hash in manifests."""
        text = json.dumps({k: self.values[k] for k in sorted(self.values)}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def lines(self) -> list[tuple[str, str]]:
        """Every key with its value as TOML writes it, in schema order (``mtbmj presets --show``)."""
        return [(key, _toml_value(self.values[key])) for key in sorted(self.values, key=list(SCHEMA).index)]

    def to_toml(self) -> str:
        """The configuration as TOML, tables in schema order; loads back to the same values."""
        sections: dict[str, list[str]] = {}
        derived = {BODY_KEY} if all(k in self.values for k in RIDER_KEYS) else set()  # load() derives it again
        for key in sorted(set(self.values) - derived, key=lambda k: list(SCHEMA).index(k)):
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


def _read_toml(path: Path, what: str = "a TOML configuration") -> dict[str, Any]:
    text = read_text(path, ConfigError, str(path), f"not a text file, so not {what}")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ConfigError(f"{path}: arrays or tables nested too deeply") from None


def _base_path(base: str, including: Path, roots: tuple[Path, ...], what: str = "a TOML configuration") -> str:
    """Where a ``base`` path of the file ``including`` (of ``what``) points, if it is allowed there.

    The rule: a base is a preset name or a ``.toml`` file, a relative path relative to the folder of the file
    naming it, lying (symbolic links resolved) in or below the current directory or the folder of the configuration
    named on the command line: a configuration cannot make mtbmj read, or name keys of, files elsewhere."""
    if Path(base).suffix.lower() != ".toml":  # a bike file given for a fork's configuration names "trail"
        from mtbmj.presets import bike_preset_names

        kind = "a bike's" if base.lower() in bike_preset_names() else "a fork's" if _is_preset(base) else None
        raise ConfigError(f"{including}: base {base!r} must be a preset name or a .toml file ({base!r} is no preset "
                          f"of {what}" + (f": {including.name} is {kind}, a file of the other kind)" if kind else ")"))
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


def read_chain(ref: str, locate=None, is_preset=None, what: str = "a TOML configuration", _depth: int = 0,
               _roots: tuple[Path, ...] | None = None) -> list[tuple[str, Path | Any, dict]]:
    """The files of ``ref``'s ``base`` chain, the last base first: (name, location, table without
    ``base``) each. ``locate(ref)`` gives a name and a location (a packaged resource for a preset, a
    ``Path`` for a file; the configurations' presets by default, the bikes' for a bike);
    ``is_preset(name)`` tells a preset name from a path. A file's base follows the rule of
    :func:`_base_path`; a chain longer than ``MAX_BASE_DEPTH`` is refused. The one reader of base
    chains, for the drop's configurations and the bike files alike."""
    locate = _locate if locate is None else locate
    is_preset = _is_preset if is_preset is None else is_preset
    if _depth > MAX_BASE_DEPTH:
        raise ConfigError(f"{ref}: base chain longer than {MAX_BASE_DEPTH} (a cycle?)")
    if not str(ref).strip():  # Path("") is the current folder: "is a directory" was the line
        raise ConfigError(f"{ref!r}: an empty name; give a preset or the path of {what} (mtbmj presets lists "
                          f"the presets)")
    name, location = locate(str(ref))
    if isinstance(location, Path):
        table = _read_toml(location, what)
        if _roots is None:
            _roots = (Path.cwd().resolve(), location.resolve().parent)
    else:
        table = tomllib.loads(location.read_text())
    base = table.pop("base", None)
    chain: list[tuple[str, Path | Any, dict]] = []
    if base is not None:
        if not isinstance(base, str):
            raise ConfigError(f"{location}: base must be a preset name or a path")
        if isinstance(location, Path) and not is_preset(base):
            base = _base_path(base, location, _roots or (), what)
        chain = read_chain(base, locate, is_preset, what, _depth + 1, _roots)
    return chain + [(name, location, table)]


def load(ref: str | Path, overrides: Mapping[str, Any] | None = None) -> Config:
    """Load a preset name or a TOML file, following ``base`` links (:func:`read_chain`; see
    :func:`_base_path` for where a base may be), then apply overrides."""
    values: dict[str, Any] = {}
    notes: dict[str, str] = {}
    sources: tuple[str, ...] = ()
    chain = read_chain(str(ref))
    for i, (_, location, table) in enumerate(chain):
        try:
            flat = _flatten(table)
        except ConfigError as exc:
            raise ConfigError(f"{location}: {exc}") from None
        if i:  # a base's description is not the file's
            values.pop("description", None)
            values.pop("reading", None)
        try:
            _apply(values, notes, flat)
        except ConfigError as exc:
            raise ConfigError(f"{location}: {exc}") from None
        sources += (str(location),)
    # a file of the user's on a base (one without is a whole configuration, as the reference, keys for every model)
    mine = isinstance(location, Path) and not _is_preset(str(ref)) and len(chain) > 1
    own = {ALTERNATIVES.get(k, (k,))[0]: str(location) for k in flat} if mine else {}
    config = Config(chain[-1][0], values, sources, notes, filed=own)
    if overrides:
        config = config.with_overrides(overrides)
    warn(config.warnings)
    return config


def resolve(config: Config | str, overrides: Mapping | None = None) -> Config:
    """A ``Config`` from a preset name, a TOML path or a ``Config``, with overrides applied; the
    overrides' plausibility warnings are issued (``ConfigWarning``) as ``load`` issues
    a file's."""
    if isinstance(config, Config):
        if not overrides:
            return config
        changed = config.with_overrides(overrides)
        warn([w for w in changed.warnings if w not in config.warnings])
        return changed
    return load(config, overrides)


__all__ = ["Config", "ConfigError", "ConfigWarning", "load", "preset_names", "study_presets",
           "sprung_front_mass", "resolve", "SCHEMA"]

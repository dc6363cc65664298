"""Setting sag the way riders do: the air pressure (air spring) or the preload (coil spring) that
makes the fork rest at a given percentage of its travel under a given load, and where its friction
lets it rest instead.

The load is the mass the fork carries, which on the sled is the body mass. It is given once:
``--load-kg`` (written as ``sled.body_mass_kg``), or the rider inputs (``sled.rider_mass_kg``,
``sled.bike_mass_kg``, ``sled.front_share_percent``, in ``--set`` or in the configuration file,
turned into the body mass by :func:`mtbmj.config.sprung_front_mass` as every run does), or
``--set sled.body_mass_kg``; ``--load-kg`` beside a load in ``--set`` is refused. The
configuration written carries the load the way it was given, so ``mtbmj drop`` on it runs the
same load.

The static balance is the spring's force at the sag against the load's weight, F(x_sag, v = 0) = m g
(damping carries no force at rest), solved for the pressure or preload by a sign-change scan and
``scipy.optimize.brentq``. Friction can hold up to its force at rest H (``fork.friction.coulomb_N``;
the breakaway force of the Stribeck, stiction and LuGre laws), so the fork can rest anywhere the
spring carries the load within H, |F(x) - m g| <= H: from where it stops when the load is lowered
onto it from full extension, F(x_low) = m g - H, to where it stops when let up from deep in the
travel, F(x_high) = m g + H. The solver reports that band; the drop lands deep and rebounds, and
comes to rest inside it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from shlex import quote
from typing import Any, Mapping

import numpy as np
from scipy.optimize import brentq

from mtbmj import compose, limits
from mtbmj.config import BODY_KEY, RIDER_KEYS, WHEEL_KEY, Config, parameter_set_toml, preset_names
from mtbmj.controllers import friction as friction_laws
from mtbmj.errors import ConfigError
from mtbmj.output import write_atomically

AIR_KEY = "fork.spring.air_pressure_psi"
PRELOAD_KEY = "fork.spring.preload_N"
AIR_RANGE_PSI = (0.0, 600.0)  # the atmosphere (the lowest pressure accepted) to far beyond any fork's rating
SCAN_POINTS = 241
SETTLE_S = 3.0  # s: the drop the command suggests; 1.5 s (the default) leaves air120 at 70 kg still moving


@dataclass(frozen=True)
class SagSetting:
    """The solved setting: ``key`` = ``value`` gives ``sag_percent`` of travel under ``load_kg``;
    with its friction (up to ``holding_N`` at rest) the fork can rest anywhere from ``rest_low_mm``
    to ``rest_high_mm`` (both ``sag_mm`` without friction)."""

    config: Config  # the configuration with the setting, the load and any overrides applied
    key: str
    value: float
    load_kg: float
    sag_percent: float
    sag_mm: float
    base: str
    written: Mapping[str, Any] = field(default_factory=dict)  # the values config.toml sets on its base
    load_from: str = "--load-kg"  # how the load was given, as the line says it
    holding_N: float = 0.0  # the friction force at rest
    rest_low_mm: float = math.nan  # the rest band: lowered onto the fork from full extension ...
    rest_high_mm: float = math.nan  # ... and let up from deep in the travel

    def line(self) -> str:
        unit = "psi" if self.key == AIR_KEY else "N preload"
        travel = self.config["fork.travel_mm"]
        text = (f"{self.config.name}: {self.value:.1f} {unit} gives {self.sag_percent:g} % sag "
                f"({self.sag_mm:.1f} mm) under {self.load_kg:g} kg ({self.load_from})")
        if self.holding_N > 0.0:
            text += (f"; with its friction ({self.holding_N:.4g} N at rest) the fork comes to rest anywhere from "
                     f"{self.rest_low_mm:.1f} to {self.rest_high_mm:.1f} mm ({100 * self.rest_low_mm / travel:.1f}-"
                     f"{100 * self.rest_high_mm / travel:.1f} %), {self.sag_mm - self.rest_low_mm:.1f} mm less to "
                     f"{self.rest_high_mm - self.sag_mm:.1f} mm more than the sag")
        return text

    def toml(self) -> str:
        return parameter_set_toml(self.written, self.base, f"{self.config.name} set to {self.sag_percent:g} % sag "
                                  f"under {self.load_kg:g} kg (mtbmj sag)")

    def write(self, out_dir: str | Path) -> list[Path]:
        """``out_dir/config.toml``, all at once or not at all."""
        return write_atomically(out_dir, {"config.toml": self.toml().encode()})

    def drop_command(self, path: str | Path) -> str:
        """The command that runs the written configuration at ``path`` long enough to come to rest."""
        return f"mtbmj drop {quote(str(path))} --duration {SETTLE_S:g}"


def _static_force(cfg: Config, x: float) -> float:
    return compose.fork_law(cfg).spring.force(x, 0.0)


def holding_force(friction: object) -> float:
    """The largest force (N) the fork's friction law carries at rest: the sliding level at v = 0
    (F_C, or the breakaway force F_S of the Stribeck and stiction curves), LuGre's g(0) = F_S, 0
    without friction. Viscous friction and the damper carry nothing at rest."""
    if isinstance(friction, friction_laws.NoFriction):
        return 0.0
    if isinstance(friction, friction_laws.Sticking):
        friction = friction.inner
    if isinstance(friction, friction_laws.LuGre):
        return float(friction.g(0.0))
    return float(friction_laws.sliding_level(friction, 0.0)[0])


def rest_band(cfg: Config, sag: float) -> tuple[float, float, float]:
    """(H, x_low, x_high): the friction force at rest and the compressions (m) between which the
    fork of ``cfg`` can rest under its body mass, |F(x) - m g| <= H, ``sag`` being where
    F(x) = m g. x_low is where the load lowered onto the fork from full extension stops (the first
    x with F(x) >= m g - H, 0 when friction holds it there), x_high where the fork let up from
    its full travel stops (the last x with F(x) <= m g + H, the full travel when friction holds
    it there)."""
    fork = compose.fork_law(cfg)
    held = holding_force(fork.friction)
    if held <= 0.0:
        return 0.0, sag, sag
    weight = cfg["sled.body_mass_kg"] * cfg.get("sled.gravity_m_per_s2", 9.81)
    travel = cfg["fork.travel_mm"] * compose.MM

    def excess(x: float, level: float) -> float:
        return fork.spring.force(x, 0.0) - level

    def crossing(a: float, b: float, level: float) -> float:
        return brentq(excess, a, b, args=(level,), xtol=1e-12, rtol=1e-14)

    low_level, high_level = weight - held, weight + held
    above = np.linspace(0.0, sag, SCAN_POINTS)
    holds = np.flatnonzero(np.array([excess(x, low_level) for x in above]) >= 0.0)
    if not holds.size:  # (at the sag the excess is H > 0: only a rounding error comes here)
        low = sag
    else:
        first = int(holds[0])
        low = 0.0 if first == 0 else crossing(above[first - 1], above[first], low_level)
    below = np.linspace(sag, travel, SCAN_POINTS)
    holds = np.flatnonzero(np.array([excess(x, high_level) for x in below]) <= 0.0)
    if not holds.size:  # (at the sag the excess is -H < 0)
        high = sag
    else:
        last = int(holds[-1])
        high = travel if last == below.size - 1 else crossing(below[last], below[last + 1], high_level)
    return held, float(low), float(high)


def _rider_text(cfg: Config) -> str:
    rider, bike, share = (cfg[k] for k in RIDER_KEYS)
    return (f"{share:g} % of the {rider:g} kg rider and {bike:g} kg bike, less the {cfg[WHEEL_KEY]:g} kg front "
            f"wheel")


def _has_rider_inputs(cfg: Config) -> bool:
    return all(k in cfg.values for k in RIDER_KEYS)


def _check_load_kg(load_kg: float | None, overrides: Mapping[str, Any]) -> None:
    """Refuse ``--load-kg`` beside a load in ``--set`` (the load given two ways), or not a mass."""
    if load_kg is None:
        return
    in_set = [k for k in (*RIDER_KEYS, BODY_KEY) if k in overrides]
    if in_set:
        other = (f"the rider inputs ({', '.join(RIDER_KEYS)})" if set(in_set) & set(RIDER_KEYS)
                 else f"--set {BODY_KEY}")
        raise ConfigError(f"--load-kg and --set {', '.join(in_set)}: the load given two ways; give either "
                          f"--load-kg or {other}")
    if not (isinstance(load_kg, (int, float)) and not isinstance(load_kg, bool) and math.isfinite(load_kg)
            and load_kg > 0):
        raise ConfigError(f"--load-kg: must be a positive number of kg, got {load_kg!r}")


def _load(cfg: Config, load_kg: float | None, overrides: Mapping[str, Any]) -> tuple[dict, str]:
    """(the values that set the load on ``cfg``, the configuration with the overrides; how the load
    was given, as the line says it), or a one-line refusal when it was not given at all."""
    if load_kg is not None:
        said = "--load-kg"
        if _has_rider_inputs(cfg):  # a file's rider inputs, replaced as --set sled.body_mass_kg replaces them
            said += f", in place of the rider inputs of {cfg.name}"
        return {BODY_KEY: float(load_kg)}, said
    if _has_rider_inputs(cfg):
        return {}, _rider_text(cfg)
    if BODY_KEY in overrides:
        return {}, f"--set {BODY_KEY}"
    raise ConfigError(f"--load-kg: missing; give the load the fork carries as --load-kg KG or as the rider inputs "
                      f"(--set {'=... --set '.join(RIDER_KEYS)}=...)")


def solve_sag(config: Config | str, load_kg: float | None, sag_percent: float,
              overrides: Mapping[str, Any] | None = None) -> SagSetting:
    """The pressure (``fork.spring.model = "air"``) or preload (coil models, with the top-out
    spring) that puts the fork at ``sag_percent`` of its travel under ``load_kg`` kg; with
    ``load_kg=None`` under the load the rider inputs give (in ``overrides`` or the configuration),
    or ``sled.body_mass_kg`` in ``overrides``. Also the band its friction lets it rest in."""
    from mtbmj.drop.chain import resolve

    overrides = dict(overrides or {})
    _check_load_kg(load_kg, overrides)
    if not (isinstance(sag_percent, (int, float)) and not isinstance(sag_percent, bool) and 0 < sag_percent < 100):
        raise ConfigError(f"--sag-percent: must be between 0 and 100 (percent of travel), got {sag_percent!r}")
    if load_kg is not None:  # the command line's warnings, said to a caller from Python too (70 kg as 0.2 %: 20 %?)
        limits.plausible("--load-kg", load_kg)
    limits.plausible("--sag-percent", sag_percent)
    cfg = resolve(config, overrides)
    fixed, load_from = _load(cfg, load_kg, overrides)
    model = cfg.require("fork.spring.model")
    travel_mm = cfg.require("fork.travel_mm")
    sag = sag_percent / 100.0 * travel_mm * compose.MM
    if fixed:
        cfg = cfg.with_overrides(fixed)
    load = float(cfg.require(BODY_KEY))
    weight = load * cfg.get("sled.gravity_m_per_s2", 9.81)
    if model == "air":
        key, grid = AIR_KEY, np.linspace(*AIR_RANGE_PSI, SCAN_POINTS)
        what = "pressure"
    else:
        key, grid = PRELOAD_KEY, np.linspace(0.0, weight, SCAN_POINTS)
        fixed["fork.spring.preload"] = True
        what = "preload"

    def trial(value: float) -> Config:
        return cfg.with_overrides({**fixed, key: float(value)})

    residual = np.full(grid.size, np.nan)
    first_error = None
    for i, value in enumerate(grid):
        try:
            residual[i] = _static_force(trial(value), sag) - weight
        except ConfigError as error:  # e.g. a pressure whose top-out stays engaged: not a candidate
            first_error = first_error or error
    valid = np.isfinite(residual)
    if valid.sum() < 2:  # the configuration refuses (almost) every setting: say why
        raise first_error
    crossings = np.flatnonzero(valid[:-1] & valid[1:] & (np.sign(residual[:-1]) != np.sign(residual[1:])))
    if not crossings.size:
        direction = "less" if np.all(residual[valid] > 0) else "more"
        raise ConfigError(f"--sag-percent: no {what} gives {cfg.name} (fork.spring.model = {model}) {sag_percent:g} % "
                          f"sag under {load:g} kg; at every {what} it sags {direction}")
    i = int(crossings[0])
    value = brentq(lambda p: _static_force(trial(p), sag) - weight, grid[i], grid[i + 1], xtol=1e-10, rtol=1e-13)
    solved = trial(value)
    compose.setup(solved)  # every cross-key rule, the timestep rule included, holds for the file written
    held, low, high = rest_band(solved, sag)
    if isinstance(config, str) and any(config.lower() == n.lower() for n in preset_names()):
        base, written = cfg.name, {**overrides, **fixed, key: float(value)}
    else:
        base = "reference"
        written = {k: v for k, v in solved.values.items() if k not in ("description", "reading")}
        if _has_rider_inputs(solved):  # the body mass is theirs: the file gives the load one way
            written.pop(BODY_KEY)
    return SagSetting(solved, key, float(value), load, float(sag_percent), sag / compose.MM, base, written,
                      load_from, held, low / compose.MM, high / compose.MM)


__all__ = ["SagSetting", "holding_force", "rest_band", "solve_sag"]

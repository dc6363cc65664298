"""Setting sag the way riders do: the air pressure (air spring) or the preload (coil spring) that
makes the fork rest at a given percentage of its travel under a given load.

The load is the mass the fork carries, which on the sled is the body mass, so the configuration
written sets ``sled.body_mass_kg`` to it: ``mtbmj drop`` on that file rests at the asked sag. The
static balance is the spring's force at the sag against the load's weight, F(x_sag, v = 0) = m g
(friction and damping carry no force at rest), solved for the pressure or preload by a sign-change
scan and ``scipy.optimize.brentq``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from scipy.optimize import brentq

from mtbmj import compose
from mtbmj.config import Config, parameter_set_toml, preset_names
from mtbmj.errors import ConfigError
from mtbmj.output import write_atomically

AIR_KEY = "fork.spring.air_pressure_psi"
PRELOAD_KEY = "fork.spring.preload_N"
AIR_RANGE_PSI = (0.0, 600.0)  # the atmosphere (the lowest pressure accepted) to far beyond any fork's rating
SCAN_POINTS = 241


@dataclass(frozen=True)
class SagSetting:
    """The solved setting: ``key`` = ``value`` gives ``sag_percent`` of travel under ``load_kg``."""

    config: Config  # the configuration with the setting, the load and any overrides applied
    key: str
    value: float
    load_kg: float
    sag_percent: float
    sag_mm: float
    base: str
    written: Mapping[str, Any] = field(default_factory=dict)  # the values config.toml sets on its base

    def line(self) -> str:
        unit = "psi" if self.key == AIR_KEY else "N preload"
        return (f"{self.config.name}: {self.value:.1f} {unit} gives {self.sag_percent:g} % sag "
                f"({self.sag_mm:.1f} mm) under {self.load_kg:g} kg")

    def toml(self) -> str:
        return parameter_set_toml(self.written, self.base, f"{self.config.name} set to {self.sag_percent:g} % sag "
                                  f"under {self.load_kg:g} kg (mtbmj sag)")

    def write(self, out_dir: str | Path) -> list[Path]:
        """``out_dir/config.toml``, all at once or not at all."""
        return write_atomically(out_dir, {"config.toml": self.toml().encode()})


def _static_force(cfg: Config, x: float) -> float:
    return compose.fork_law(cfg).spring.force(x, 0.0)


def solve_sag(config: Config | str, load_kg: float, sag_percent: float,
              overrides: Mapping[str, Any] | None = None) -> SagSetting:
    """The pressure (``fork.spring.model = "air"``) or preload (coil models, with the top-out
    spring) that puts the fork at ``sag_percent`` of its travel under ``load_kg``."""
    from mtbmj.drop.chain import resolve

    if not (isinstance(load_kg, (int, float)) and math.isfinite(load_kg) and load_kg > 0):
        raise ConfigError(f"--load-kg: must be a positive number of kg, got {load_kg}")
    if not (isinstance(sag_percent, (int, float)) and 0 < sag_percent < 100):
        raise ConfigError(f"--sag-percent: must be between 0 and 100 (percent of travel), got {sag_percent}")
    cfg = resolve(config, overrides)
    model = cfg.require("fork.spring.model")
    travel_mm = cfg.require("fork.travel_mm")
    sag = sag_percent / 100.0 * travel_mm * compose.MM
    weight = load_kg * cfg.get("sled.gravity_m_per_s2", 9.81)
    fixed = {"sled.body_mass_kg": float(load_kg)}
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
                          f"sag under {load_kg:g} kg; at every {what} it sags {direction}")
    i = int(crossings[0])
    value = brentq(lambda p: _static_force(trial(p), sag) - weight, grid[i], grid[i + 1], xtol=1e-10, rtol=1e-13)
    solved = trial(value)
    compose.setup(solved)  # every cross-key rule, the timestep rule included, holds for the file written
    if isinstance(config, str) and any(config.lower() == n.lower() for n in preset_names()):
        base, written = cfg.name, {**dict(overrides or {}), **fixed, key: float(value)}
    else:
        base = "reference"
        written = {k: v for k, v in solved.values.items() if k not in ("description", "reading")}
    return SagSetting(solved, key, float(value), float(load_kg), float(sag_percent), sag / compose.MM, base,
                      written)


__all__ = ["SagSetting", "solve_sag"]

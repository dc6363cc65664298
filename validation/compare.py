"""Lining an engine's run (MuJoCo by default, or the fast engine) up against the ODE reference of
the same configuration."""
from __future__ import annotations

from dataclasses import dataclass

from mtbmj.drop.chain import resolve
from mtbmj.drop.run import run_drop
from mtbmj.drop.result import DISPLACEMENTS, DropResult

DEFAULT_TOLERANCE_MM = 0.1
LABELS = {"mujoco": "MuJoCo", "fast": "fast-engine"}  # the accuracy target at default settings (1e-4 s, implicitfast)


def mm(value: float) -> str:
    """A difference in mm: four decimals, or two significant digits below a micrometre."""
    return f"{value:.4f}" if value >= 1e-3 or value == 0.0 else f"{value:.1e}"


@dataclass(frozen=True)
class Crosscheck:
    """Engine-vs-reference differences of one configuration (raw traces on the MuJoCo grid)."""

    name: str
    tolerance_mm: float
    differences: dict  # column -> {"max_abs_mm", "at_time_s"}
    mujoco_wall_s: float  # wall time of the engine under test (``engine``; MuJoCo unless told)
    ode_wall_s: float
    engine: str = "mujoco"

    @property
    def worst(self) -> tuple[str, float, float]:
        column = max(self.differences, key=lambda c: self.differences[c]["max_abs_mm"])
        d = self.differences[column]
        return column, d["max_abs_mm"], d["at_time_s"]

    @property
    def passed(self) -> bool:
        return self.worst[1] <= self.tolerance_mm

    def line(self) -> str:
        column, value, at = self.worst
        verdict = "within" if self.passed else "EXCEEDS"
        return (f"{self.name}: largest {LABELS.get(self.engine, self.engine)}-ODE difference {mm(value)} mm in "
                f"{column.removesuffix('_mm')} "
                f"at t = {at:.4f} s, {verdict} the tolerance {self.tolerance_mm:g} mm")

    def row(self) -> dict:
        row = {"config": self.name, "engine": self.engine}
        for column in DISPLACEMENTS:
            row[f"max_diff_{column}"] = self.differences[column]["max_abs_mm"]
            row[f"at_time_{column.removesuffix('_mm')}_s"] = self.differences[column]["at_time_s"]
        row.update({"tolerance_mm": self.tolerance_mm, "passed": self.passed,
                    "mujoco_wall_s": self.mujoco_wall_s, "ode_wall_s": self.ode_wall_s})
        return row


def from_results(mujoco: DropResult, ode: DropResult, tolerance_mm: float = DEFAULT_TOLERANCE_MM) -> Crosscheck:
    """The check of ``mujoco`` (a run on any engine but the reference) against ``ode``."""
    return Crosscheck(mujoco.name, tolerance_mm, mujoco.difference(ode, raw=True),
                      mujoco.wall_time_s, ode.wall_time_s, mujoco.engine)


def crosscheck(config, tolerance_mm: float = DEFAULT_TOLERANCE_MM, overrides=None, duration=None,
               engine: str = "mujoco") -> Crosscheck:
    """Run ``config`` on ``engine`` and on the ODE reference and compare sled, fork and tire."""
    return crosscheck_all(config, (engine,), tolerance_mm, overrides, duration)[0]


def crosscheck_all(config, engines=("mujoco",), tolerance_mm: float = DEFAULT_TOLERANCE_MM, overrides=None,
                   duration=None) -> list[Crosscheck]:
    """One ``Crosscheck`` per engine of ``engines`` against one ODE reference run."""
    cfg = resolve(config, overrides)
    ode = run_drop(cfg, "ode", duration=duration)
    return [from_results(run_drop(cfg, e, duration=duration), ode, tolerance_mm) for e in engines]

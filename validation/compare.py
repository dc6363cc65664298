"""Lining a MuJoCo run up against the ODE reference of the same configuration."""
from __future__ import annotations

from dataclasses import dataclass

from mtbmj.drop.run import resolve, run_drop
from mtbmj.drop.result import DISPLACEMENTS, DropResult

DEFAULT_TOLERANCE_MM = 0.1  # the accuracy target at default settings (1e-4 s, implicitfast)


@dataclass(frozen=True)
class Crosscheck:
    """Engine-vs-reference differences of one configuration (raw traces on the MuJoCo grid)."""

    name: str
    tolerance_mm: float
    differences: dict  # column -> {"max_abs_mm", "at_time_s"}
    mujoco_wall_s: float
    ode_wall_s: float

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
        return (f"{self.name}: largest MuJoCo-ODE difference {value:.4f} mm in {column.removesuffix('_mm')} "
                f"at t = {at:.4f} s, {verdict} the tolerance {self.tolerance_mm:g} mm")

    def row(self) -> dict:
        row = {"config": self.name}
        for column in DISPLACEMENTS:
            row[f"max_diff_{column}"] = self.differences[column]["max_abs_mm"]
            row[f"at_time_{column.removesuffix('_mm')}_s"] = self.differences[column]["at_time_s"]
        row.update({"tolerance_mm": self.tolerance_mm, "passed": self.passed,
                    "mujoco_wall_s": self.mujoco_wall_s, "ode_wall_s": self.ode_wall_s})
        return row


def from_results(mujoco: DropResult, ode: DropResult, tolerance_mm: float = DEFAULT_TOLERANCE_MM) -> Crosscheck:
    return Crosscheck(mujoco.name, tolerance_mm, mujoco.difference(ode, raw=True),
                      mujoco.wall_time_s, ode.wall_time_s)


def crosscheck(config, tolerance_mm: float = DEFAULT_TOLERANCE_MM, overrides=None, duration=None) -> Crosscheck:
    """Run ``config`` on both engines and compare sled, fork and tire displacement."""
    cfg = resolve(config, overrides)
    return from_results(run_drop(cfg, "mujoco", duration=duration), run_drop(cfg, "ode", duration=duration),
                        tolerance_mm)

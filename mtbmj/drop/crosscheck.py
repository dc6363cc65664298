"""Lining an engine's run (MuJoCo by default, or the fast engine) up against the ODE reference of
the same configuration: sled, fork and tire compared sample by sample on the engine's raw grid,
each within the tolerance (a ``mtbmj.runpath.crosscheck.CrosscheckResult``)."""
from __future__ import annotations

import numpy as np

from mtbmj.drop.chain import resolve
from mtbmj import limits
from mtbmj.drop.run import run_drop
from mtbmj.drop.result import DISPLACEMENTS, DropResult
from mtbmj.runpath.crosscheck import CrosscheckResult, compare_series

DEFAULT_TOLERANCE_MM = 0.1  # the accuracy target at default settings (1e-4 s, implicitfast)


def from_results(mujoco: DropResult, ode: DropResult, tolerance_mm: float = DEFAULT_TOLERANCE_MM) -> CrosscheckResult:
    """The check of ``mujoco`` (a run on any engine but the reference) against ``ode``: the raw
    traces on their shared grid (the shorter run's length)."""
    a, b = mujoco.raw, ode.raw
    n = min(len(a["time_s"]), len(b["time_s"]))
    if not np.allclose(a["time_s"][:n], b["time_s"][:n], atol=1e-9):
        raise ValueError("results are not on the same time grid")
    signals = [compare_series(column.removesuffix("_mm"), "mm", a["time_s"][:n], a[column][:n], b[column][:n],
                              tolerance_mm) for column in DISPLACEMENTS]
    return CrosscheckResult("drop", mujoco.name, mujoco.engine, "ODE reference", signals, mujoco.wall_time_s,
                            ode.wall_time_s, {"config": mujoco.name, "tolerance_mm": tolerance_mm})


def crosscheck(config, tolerance_mm: float = DEFAULT_TOLERANCE_MM, overrides=None, duration=None,
               engine: str = "mujoco") -> CrosscheckResult:
    """Run ``config`` on ``engine`` and on the ODE reference and compare sled, fork and tire."""
    return crosscheck_all(config, (engine,), tolerance_mm, overrides, duration)[0]


def crosscheck_all(config, engines=("mujoco",), tolerance_mm: float = DEFAULT_TOLERANCE_MM, overrides=None,
                   duration=None) -> list[CrosscheckResult]:
    """One cross-check per engine of ``engines`` against one ODE reference run."""
    # refused before the runs, naming the argument, within --tolerance-mm's range (5000 mm ran from Python where
    # --tolerance-mm 5000 is refused) and warned about outside its plausible one, as the command line is
    limits.given("--tolerance-mm", "tolerance_mm", tolerance_mm)
    cfg = resolve(config, overrides)
    ode = run_drop(cfg, "ode", duration=duration)
    return [from_results(run_drop(cfg, e, duration=duration), ode, tolerance_mm) for e in engines]

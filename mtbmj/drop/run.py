"""Run one drop on any engine and return a ``DropResult`` (the chain itself is ``chain``)."""
from __future__ import annotations

import time
from typing import Callable, Mapping

from mtbmj.config import Config
from mtbmj.controllers import native
from mtbmj.drop import chain
from mtbmj.drop.result import DropResult
from mtbmj.errors import ConfigError, diverging


# Each engine is imported when it first runs: MuJoCo's, scipy's integrators and numba cost
# start-up time a run on another engine does not need.
def _mujoco(setup, duration=None, progress=None):
    from mtbmj.drop import engine_mujoco

    return engine_mujoco.run(setup, duration, progress)


def _ode(setup, duration=None, progress=None):
    from mtbmj.drop import engine_ode

    return engine_ode.run(setup, duration, progress)


def _fast(setup, duration=None, progress=None):
    from mtbmj.drop import engine_fast

    return engine_fast.run(setup, duration, progress)


ENGINES = {"mujoco": _mujoco, "ode": _ode, "fast": _fast}


def run_drop(config: Config | str, engine: str = "mujoco", overrides: Mapping | None = None,
             duration: float | None = None, progress: Callable[[float], None] | None = None) -> DropResult:
    """Drop from the configured height: ``engine`` is "mujoco" (the default), "ode" (the scipy
    reference) or "fast" (the same ODE integrated natively on the compiled laws; see
    ``mtbmj.drop.engine_fast``)."""
    if engine not in ENGINES:
        raise ConfigError(f"engine: {engine!r} is not one of {', '.join(ENGINES)}")
    cfg, setup = chain.prepare(config, overrides, duration)
    native.drop_started()  # a process that drops again and again reaches the compiled laws on its own
    start = time.perf_counter()
    with diverging(f"drop ({engine})"):  # numpy's overflow or invalid value while stepping: divergence
        trace = ENGINES[engine](setup, duration, progress)
    wall = time.perf_counter() - start
    raw, logged, summary = chain.finish(setup, trace, engine)
    return DropResult(name=cfg.name, engine=engine, config=cfg, signals=logged, raw=raw, trace=trace,
                      summary=summary, wall_time_s=wall)

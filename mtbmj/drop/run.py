"""Run one drop on either engine and return a ``DropResult``."""
from __future__ import annotations

import time
from typing import Callable, Mapping

import numpy as np

from mtbmj import compose, config as config_mod, limits
from mtbmj.controllers import native
from mtbmj.drop import events
from mtbmj.drop import measure
from mtbmj.config import Config
from mtbmj.errors import ConfigError, RunError
from mtbmj.drop.result import DropResult


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


def resolve(config: Config | str, overrides: Mapping | None = None) -> Config:
    """A ``Config`` from a preset name, a TOML path or a ``Config``, with overrides applied; the
    overrides' plausibility warnings are issued (``config_mod.ConfigWarning``) as ``load`` issues
    a file's."""
    if isinstance(config, Config):
        if not overrides:
            return config
        changed = config.with_overrides(overrides)
        config_mod.warn([w for w in changed.warnings if w not in config.warnings])
        return changed
    return config_mod.load(config, overrides)


def run_drop(config: Config | str, engine: str = "mujoco", overrides: Mapping | None = None,
             duration: float | None = None, progress: Callable[[float], None] | None = None) -> DropResult:
    """Drop from the configured height: ``engine`` is "mujoco" (the default), "ode" (the scipy
    reference) or "fast" (the same ODE integrated natively on the compiled laws; see
    ``mtbmj.drop.engine_fast``)."""
    if engine not in ENGINES:
        raise ConfigError(f"engine: {engine!r} is not one of {', '.join(ENGINES)}")
    cfg = resolve(config, overrides)
    if duration is not None and not duration > 0:
        raise ConfigError(f"duration: must be positive, got {duration}")
    setup = compose.setup(cfg)
    limits.check_run(setup.duration if duration is None else duration, setup.timestep, setup.sample_rate)
    native.drop_started()  # a process that drops again and again reaches the compiled laws on its own
    start = time.perf_counter()
    trace = ENGINES[engine](setup, duration, progress)
    wall = time.perf_counter() - start
    for name in ("sled", "fork", "sled_velocity", "fork_velocity", "friction_state"):
        values = getattr(trace, name)
        if not np.all(np.isfinite(values)):
            at = trace.time[int(np.argmax(~np.isfinite(values)))]
            raise RunError(f"run diverged at t = {at:.4f} s: {name.replace('_', ' ')} is not finite ({engine})")
    raw = measure.engine_signals(setup, trace)
    logged = measure.logged(setup, raw)
    summary = events.summarize(setup, trace, logged, raw)
    return DropResult(name=cfg.name, engine=engine, config=cfg, signals=logged, raw=raw, trace=trace,
                      summary=summary, wall_time_s=wall)

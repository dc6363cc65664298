"""One drop from configuration to record, assembled here once: configuration -> ``prepare``
(overrides, ``compose.setup``: the laws in SI and the step rule's timestep, the run's length
checked) -> an engine (a ``RawTrace``) -> ``finish`` (a finite trace, the engine-rate signals,
the sled logger's 1 kHz view, the event summary).

Every drop path runs this chain: ``run_drop`` (one drop on any engine), the batched MuJoCo engine
(``engine_batch``), the sweep's fast-engine runner and the drop fit. A path that needs less of a
run asks ``finish`` for less (``channels``: only those logged signals; ``summary=False``: no
summary), and gets the same numbers as ``run_drop`` for what it asks.
"""
from __future__ import annotations

from typing import Mapping, NamedTuple

import numpy as np

from mtbmj import compose, config as config_mod, limits
from mtbmj.compose import Setup
from mtbmj.config import Config, resolve  # noqa: F401  (resolve: drop.chain's name for it, kept)
from mtbmj.drop import measure
from mtbmj.drop import summary as summary_mod
from mtbmj.errors import ConfigError, MtbmjError, RunError
from mtbmj.trace import RawTrace

# the state the engines integrate: a run whose trace holds anything else diverged
INTEGRATED = ("sled", "fork", "sled_velocity", "fork_velocity", "friction_state")


def prepare(config: Config | str, overrides: Mapping | None = None, duration: float | None = None,
            warn: bool = True) -> tuple[Config, Setup]:
    """(the configuration, its ``Setup``) for a run of ``duration`` (default: the configured one):
    raises ``ConfigError`` for a bad value or a run too long for the memory. ``warn=False``
    applies the overrides to a ``Config`` without issuing their warnings (a fit's or a sweep's
    loop, where they are issued once elsewhere)."""
    if warn or not isinstance(config, Config):
        cfg = resolve(config, overrides)
    else:
        cfg = config.with_overrides(overrides) if overrides else config
    limits.check_duration("duration", duration)  # a str, a NaN from Python: one line, not a TypeError
    setup = compose.setup(cfg)
    limits.check_run(setup.duration if duration is None else duration, setup.timestep, setup.sample_rate,
                     "solver.duration_s" if duration is None else "duration")  # the length given, by its name
    return cfg, setup


def check_finite(trace: RawTrace, engine: str) -> None:
    """Raise ``RunError`` naming the first time a state of ``trace`` is not finite."""
    for name in INTEGRATED:
        values = getattr(trace, name)
        if not np.all(np.isfinite(values)):
            at = trace.time[int(np.argmax(~np.isfinite(values)))]
            raise RunError(f"run diverged at t = {at:.4f} s: {name.replace('_', ' ')} is not finite ({engine})")


def summary_signals(setup: Setup, trace: RawTrace) -> dict[str, np.ndarray]:
    """The engine-rate signals the summary reads (``measure.engine_signals`` without the fork
    force and the sled velocity; the same numbers)."""
    tire = trace.tire
    return {
        "time_s": trace.time,
        "sled_mm": trace.sled * 1e3,
        "fork_mm": trace.fork * 1e3,
        "tire_mm": tire * 1e3,
        "tire_force_N": measure.tire_forces(setup.tire, tire, trace.tire_velocity, trace.tire_phase),
        "fork_velocity_mm_per_s": trace.fork_velocity * 1e3,
        "tire_velocity_mm_per_s": trace.tire_velocity * 1e3,
    }


def position_signals(trace: RawTrace) -> dict[str, np.ndarray]:
    """The displacements at the engine rate (mm): all a fit to a record reads."""
    return {"time_s": trace.time, "sled_mm": trace.sled * 1e3, "fork_mm": trace.fork * 1e3, "tire_mm": trace.tire * 1e3}


class Finished(NamedTuple):
    """What ``finish`` makes of a trace: engine-rate signals, logged signals, summary (or None)."""

    raw: dict
    logged: dict
    summary: dict | None


def finish(setup: Setup, trace: RawTrace, engine: str, channels=None, summary: bool = True) -> Finished:
    """The record of a finished run: the trace checked (``check_finite``), its engine-rate signals
    (``measure.engine_signals``), their logged 1 kHz view (``measure.logged``) and the summary
    (``summary.summarize``). With ``channels`` (e.g. ``("sled", "fork", "tire")``) only those
    displacements are logged and the engine-rate signals are the ones the summary reads (or, with
    ``summary=False``, the displacements only)."""
    check_finite(trace, engine)
    if channels is None:
        raw = measure.engine_signals(setup, trace)
        logged = measure.logged(setup, raw)
    else:
        raw = summary_signals(setup, trace) if summary else position_signals(trace)
        logged = measure.logged(setup, {"time_s": raw["time_s"], **{f"{c}_mm": raw[f"{c}_mm"] for c in channels}})
    return Finished(raw, logged, summary_mod.summarize(setup, trace, logged, raw) if summary else None)


def failure_reason(exc: BaseException) -> str:
    """How a drop that raised is recorded (a sweep's table, a fit's failed point): a model error's
    own line, a numpy warning as a divergence, anything else as an internal error."""
    if isinstance(exc, MtbmjError):
        return str(exc)
    if isinstance(exc, (RuntimeWarning, FloatingPointError)):  # a caller's own filter or error state
        return f"run diverged ({exc})"
    return f"internal error: {type(exc).__name__}: {exc}"


__all__ = ["resolve", "prepare", "check_finite", "summary_signals", "position_signals", "Finished", "finish",
           "failure_reason", "INTEGRATED"]

"""mtbmj: a mountain-bike front suspension (fork + tire) on MuJoCo, with an independent scipy ODE
reference, reproducing the drop-sled study S1-S14 of Schoeneck, Sadauckas & Nagurka (BMD 2023).

    >>> import mtbmj
    >>> result = mtbmj.run_drop("S12")              # MuJoCo engine
    >>> reference = mtbmj.run_drop("S12", engine="ode")
    >>> result.difference(reference)["fork_mm"]["max_abs_mm"] < 0.1
    True

The names below are imported on first use, so ``import mtbmj`` stays cheap. Subsystems:
``mtbmj.measured`` (records and telemetry read in), ``mtbmj.drop`` (the drop test), ``mtbmj.rolling``
(front end on terrain), ``mtbmj.bike`` (the whole bike), ``mtbmj.ride`` (a ride through the bike, advice), ``mtbmj.sweep`` (sweeps and sensitivity), ``mtbmj.identify`` (fits),
``mtbmj.validation`` (engine cross-check, sled records), ``mtbmj.cli`` (the command line).
"""
from mtbmj._package import __version__, lazy_exports  # noqa: F401

_LAZY = {
    "Config": "mtbmj.config",
    "load_config": "mtbmj.config:load",
    "preset_names": "mtbmj.config",
    "study_presets": "mtbmj.config",
    "run_drop": "mtbmj.drop.run",
    "DropResult": "mtbmj.drop.result",
    "run_study": "mtbmj.drop.study",
    "write_study": "mtbmj.drop.study",
    "solve_sag": "mtbmj.drop.sag",
    "crosscheck": "mtbmj.drop.crosscheck",
    "run_roll": "mtbmj.rolling.frontend",
    "RollResult": "mtbmj.rolling.frontend",
    "run_bike": "mtbmj.bike.run",
    "BikeResult": "mtbmj.bike.run",
    "MtbmjError": "mtbmj.errors",
    "ConfigError": "mtbmj.errors",
    "RunError": "mtbmj.errors",
}
__all__ = ['BikeResult', 'Config', 'ConfigError', 'DropResult', 'MtbmjError', 'RollResult', 'RunError', 'crosscheck', 'load_config', 'preset_names', 'run_bike', 'run_drop', 'run_roll', 'run_study', 'solve_sag', 'study_presets', 'write_study']


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

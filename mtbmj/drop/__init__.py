"""The drop test: the sled scene, the MuJoCo and ODE engines, the logger's view, events, the study.

Flow of one drop: configuration -> ``compose.setup`` (force laws in SI) -> engine
(``engine_mujoco.run`` or ``engine_ode.run``, a ``RawTrace``) -> ``measure`` (sled conventions,
anti-aliasing, 1 kHz) -> ``events`` (Peak 1, topping, ...) -> ``result.DropResult``.
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "run_drop": "mtbmj.drop.run",
    "resolve": "mtbmj.drop.run",
    "ENGINES": "mtbmj.drop.run",
    "DropResult": "mtbmj.drop.result",
    "run_study": "mtbmj.drop.study",
    "solve_sag": "mtbmj.drop.sag",
    "run_air_study": "mtbmj.drop.air_study",
    "write_air_study": "mtbmj.drop.air_study",
    "SagSetting": "mtbmj.drop.sag",
    "write_study": "mtbmj.drop.study",
}
__all__ = ['DropResult', 'ENGINES', 'SagSetting', 'resolve', 'run_air_study', 'run_drop', 'run_study', 'solve_sag', 'write_air_study', 'write_study']


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

"""The drop test: the sled scene, the engines (MuJoCo, batched MuJoCo, ODE, fast), the step rule,
the logger's view, the event detector and the summary, the study.

Flow of one drop, assembled once in ``chain``: configuration -> ``chain.prepare``
(``compose.setup``: force laws in SI, the step) -> an engine (``engine_mujoco.run``,
``engine_ode.run``, ``engine_fast.run``, or many drops at once in ``engine_batch``; a
``RawTrace``) -> ``chain.finish``: ``measure`` (sled conventions, anti-aliasing, 1 kHz) and
``summary`` (events found by ``events.detect``: Peak 1, topping, ...) -> ``result.DropResult``.
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "run_drop": "mtbmj.drop.run",
    "resolve": "mtbmj.drop.chain",
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

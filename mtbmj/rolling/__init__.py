"""Rolling over terrain: the planar front end, the terrain library, the tire on terrain, the
dm_control task (``mtbmj.rolling.env``) and headless video (``mtbmj.rolling.render``).
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "run_roll": "mtbmj.rolling.frontend",
    "roll_trajectory": "mtbmj.rolling.frontend",
    "RollResult": "mtbmj.rolling.frontend",
    "DEFAULT_HEAD_ANGLE_DEG": "mtbmj.rolling.frontend",
}
__all__ = ['DEFAULT_HEAD_ANGLE_DEG', 'RollResult', 'roll_trajectory', 'run_roll']


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

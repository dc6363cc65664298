"""Rolling over terrain: the planar front end, the terrain library, the tire on terrain, the
dm_control task (``mtbmj.rolling.env``) and headless video (``mtbmj.rolling.render``).
"""
_LAZY = {
    "run_roll": "mtbmj.rolling.frontend",
    "roll_trajectory": "mtbmj.rolling.frontend",
    "RollResult": "mtbmj.rolling.frontend",
    "DEFAULT_HEAD_ANGLE_DEG": "mtbmj.rolling.frontend",
}
__all__ = ['DEFAULT_HEAD_ANGLE_DEG', 'RollResult', 'roll_trajectory', 'run_roll']


def __getattr__(name):  # PEP 562: import a submodule only when one of its names is asked for
    try:
        module, _, attribute = _LAZY[name].partition(":")  # "module" or "module:name there"
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    import importlib

    value = getattr(importlib.import_module(module), attribute or name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))

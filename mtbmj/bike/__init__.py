"""A whole bike on the trail: the planar bike in MuJoCo (fork, swingarm on its main pivot with the
shock through a leverage curve, a rider on legs and arms, two radial tires), its own ODE reference,
and the bike descriptions (``mtbmj/bike/presets``).
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "run_bike": "mtbmj.bike.run",
    "BikeResult": "mtbmj.bike.run",
    "load": "mtbmj.bike.spec",
    "preset_names": "mtbmj.bike.spec",
    "resolve": "mtbmj.bike.spec",
    "ResolvedBike": "mtbmj.bike.spec",
}
__all__ = ["BikeResult", "ResolvedBike", "load", "preset_names", "resolve", "run_bike"]


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

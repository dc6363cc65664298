"""The rider's ride through the bike: a ride reconstructed (speed, terrain, the rear predicted),
setup advice, a bike run beside a ride, the bike pedalled as recorded rides were. The readers of
the ride's records are ``mtbmj.measured``'s (``read_sst`` and ``summarize`` are still named here).
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "read_sst": "mtbmj.measured.telemetry",
    "summarize": "mtbmj.measured.metrics",
}
__all__ = ['read_sst', 'summarize']


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

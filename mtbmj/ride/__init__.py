"""Ride telemetry: SST files from a real ride and the metrics riders read from them (travel and
velocity histograms, bottom-outs, airtime), computed the same way for simulated runs.
"""
from mtbmj._package import lazy_exports

_LAZY = {
    "read_sst": "mtbmj.measured.telemetry",
    "summarize": "mtbmj.measured.metrics",
}
__all__ = ['read_sst', 'summarize']


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

"""Ride telemetry: SST files from a real ride and the metrics riders read from them (travel and
velocity histograms, bottom-outs, airtime), computed the same way for simulated runs.
"""
_LAZY = {
    "read_sst": "mtbmj.ride.telemetry",
    "summarize": "mtbmj.ride.metrics",
}
__all__ = ['read_sst', 'summarize']


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

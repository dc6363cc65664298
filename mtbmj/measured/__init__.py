"""Measured data in: the readers of what comes from the world (SST and travel-CSV telemetry, dyno,
tire, terrain and sled records) and the signal tools every rig, fit and check reads them with
(rider metrics, pedal-bob reading, a sled record's time zero, noise, smoothing and peaks). Nothing
here imports a rig."""
from mtbmj._package import lazy_exports

_LAZY = {
    "read_sst": "mtbmj.measured.telemetry",
    "summarize": "mtbmj.measured.metrics",
    "read_record": "mtbmj.measured.records",
    "read_sled": "mtbmj.measured.sled",
}
__all__ = ["read_record", "read_sled", "read_sst", "summarize"]


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

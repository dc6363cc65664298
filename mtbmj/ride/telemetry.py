"""Moved to ``mtbmj.measured.telemetry`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.ride.telemetry", "mtbmj.measured.telemetry")

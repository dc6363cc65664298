"""Moved to ``mtbmj.measured.metrics`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.ride.metrics", "mtbmj.measured.metrics")

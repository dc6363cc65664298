"""Moved to ``mtbmj.sweep.bike`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.bike.sweep", "mtbmj.sweep.bike")

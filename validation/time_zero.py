"""Moved to ``mtbmj.measured.time_zero`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.validation.time_zero", "mtbmj.measured.time_zero")

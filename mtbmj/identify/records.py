"""Moved to ``mtbmj.measured.records`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.identify.records", "mtbmj.measured.records")

"""Moved to ``mtbmj.measured.peaks`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.drop.peaks", "mtbmj.measured.peaks")

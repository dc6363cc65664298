"""Moved to ``mtbmj.drop.crosscheck`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.validation.compare", "mtbmj.drop.crosscheck")

"""Moved to ``mtbmj.ride.beside`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.bike.ride", "mtbmj.ride.beside")

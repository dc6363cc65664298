"""Moved to ``mtbmj.ride.pedalling`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.bike.pedalling", "mtbmj.ride.pedalling")

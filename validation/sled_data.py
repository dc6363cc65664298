"""Moved to ``mtbmj.measured.sled`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.validation.sled_data", "mtbmj.measured.sled")

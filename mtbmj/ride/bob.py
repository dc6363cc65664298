"""Moved: the bob reading to ``mtbmj.measured.bob``, a bike run's bob beside a ride to
``mtbmj.ride.beside`` (importable from here for one release, with a DeprecationWarning)."""
from mtbmj._package import moved

__getattr__ = moved("mtbmj.ride.bob", "mtbmj.measured.bob", {"compare": "mtbmj.ride.beside:bob_compare",
                    "figure": "mtbmj.ride.beside:bob_figure", "png": "mtbmj.ride.beside:bob_png",
                    "json_ready": "mtbmj.ride.beside:bob_json_ready"})

"""When the drop reaches for the compiled (numba) laws.

Loading numba and the cached laws into a fresh process takes about a second, three times a
default drop's whole run; the Python laws give the same trajectories and forces bit for bit, at
about 0.1 ms more per MuJoCo step. So a drop uses the compiled laws once numba is in the process
anyway (a sweep, the fast engine, an earlier long run: they cost nothing more to reach then) or
when the run is long enough to repay loading it, ``COMPILED_FROM_STEPS`` steps. Only the logged
signals can differ, in their last bits (about 1e-13 mm: the filter's compiled and numpy
recursions round differently). Nothing here imports numba.
"""
from __future__ import annotations

import sys

COMPILED_FROM_STEPS = 10_000  # MuJoCo steps (10 s at the default 1 ms) from which loading numba pays


def loaded() -> bool:
    """Whether numba is already imported in this process."""
    return sys.modules.get("numba") is not None


def worth(steps: float) -> bool:
    """Whether work of about ``steps`` MuJoCo steps should run on the compiled laws."""
    return loaded() or steps >= COMPILED_FROM_STEPS


def expect_many() -> None:
    """For a caller about to make many runs in this process (a sweep's worker, a fit, a study):
    load numba and the compiled laws now, so that every run takes them. Without numba, nothing."""
    if not loaded():
        from mtbmj.controllers import compiled  # noqa: F401  (imports numba when it is installed)


__all__ = ["COMPILED_FROM_STEPS", "loaded", "worth", "expect_many"]

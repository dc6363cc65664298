"""Round depth33: what round 32 noticed and left, each mended at its cause. Inputs are written here."""
from __future__ import annotations

import re
import warnings

import pytest

from mtbmj.errors import ConfigError


# --- 1. a command option's number given from Python: one check against the option's range -------------------

def test_a_start_given_from_python_is_held_to_the_start_options_range():
    """``run_bike(start_x=-1e5)`` went on to the terrain (``mtbmj bike --start-m -1e5`` is refused before any
    work: at least -10000 m); now the same range, named ``start_x``, as speed and tolerance_mm are held."""
    from mtbmj.bike import run as R

    for start, shown in ((-1e5, "-100000"), (2e4, "20000")):
        with pytest.raises(ConfigError, match=re.escape(f"start_x: {shown} m is outside the range allowed: at least "
                                                        f"-10000 and at most 10000 m")):
            R.prepare("sst", "flat", 4.0, start_x=start)
    with pytest.raises(ConfigError, match=re.escape("start_x: must be a finite number of m (the front axle's start), "
                                                    "got nan")):
        R.prepare("sst", "flat", 4.0, start_x=float("nan"))
    with pytest.warns(Warning, match=re.escape("--start-m = -500 m is outside -100-100 m")):  # the command's warning
        try:
            R.prepare("sst", "flat", 4.0, start_x=-500.0)
        except ConfigError:  # 500 m before a 10 m flat is its own matter (the terrain's); the number passed the gate
            pass


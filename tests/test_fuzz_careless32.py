"""Careless input, round 32: what round 31b (``tests/test_fuzz_careless31b.py``) left, then new cases typed as a
new user would across the commands. Each case failed before its fix: a run out of the model's envelope that
said nothing, a unit slip not named, a traceback or a refusal for a false reason. Inputs are written here."""
from __future__ import annotations

import re
import warnings

import pytest

from mtbmj import limits
from mtbmj.rolling import terrain as T

KMH = 1000.0 / 3600.0  # m/s per km/h, by the definitions of the kilometre and the hour


# --- 1. what round 31b left: a rock garden scaled to rocks of metres; a speed typed in km/h -----------------

def test_a_rock_garden_scaled_past_a_trail_is_named():
    """``rock_garden:height_scale=20`` (its 110 mm rock made 2.2 m) ran unsaid: height_scale is no ``_mm`` key.
    The garden's rocks are 50-110 mm (the docstring of ``rock_garden``); x20 is 2200 mm, over the 1000 mm
    a wheel rolls over; x9 (990 mm) is not."""
    with pytest.warns(Warning, match=re.escape("terrain rock_garden: height_scale = 20 makes its tallest rock "
                                               "2200 mm, over 1000 mm, taller than any trail feature")):
        T.make("rock_garden:height_scale=20")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        T.make("rock_garden:height_scale=9")
        T.make("rock_garden")


def test_a_speed_typed_in_km_per_h_names_km_per_h():
    """``--speed 40`` (km/h) warned "(a unit mistake?)" alone: m/s had no slip in the units' table."""
    with pytest.warns(Warning, match=re.escape(f"(a unit mistake? probably meant 40 km/h = {40 * KMH:.4g} m/s)")):
        limits.argument("--speed", "40")
    with pytest.warns(Warning, match=re.escape("(a unit mistake?)")):  # the other side: 0.1 m/s is no km/h slip
        limits.argument("--speed", "0.1")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert limits.argument("--speed", "12") == 12.0

"""The rolling front end as a rig of the run path's registry (``mtbmj.runpath.rig``): its presets
are the drop study's configurations that carry a fork and a tire over terrain; a case is the
terrain ``scenario``, ``speed_m_per_s``, ``duration`` (s), ``overrides`` and ``callback``."""
from __future__ import annotations

from mtbmj.rolling import frontend, reference
from mtbmj.runpath.rig import Rig

PRESETS = ("S12", "reference", "air120")  # a coil fork as the study's S12, the reference setup, an air fork


def _presets():
    return list(PRESETS)


def _prepare(preset, scenario="flat", speed_m_per_s=4.0, duration=None, overrides=None, callback="auto"):
    return frontend.prepare(scenario, speed_m_per_s, config=preset, overrides=overrides, callback=callback)


def _run(preset, scenario="flat", speed_m_per_s=4.0, duration=None, overrides=None, callback="auto"):
    return frontend.run_roll(scenario, speed_m_per_s, config=preset, duration=duration, overrides=overrides,
                             callback=callback)


def _crosscheck(preset, scenario="flat", speed_m_per_s=4.0, duration=None, overrides=None, callback="auto"):
    return reference.crosscheck(scenario, speed_m_per_s, config=preset, duration=duration, overrides=overrides)


RIG = Rig("rolling", "roll", _presets, _prepare, _run, _crosscheck,
          example={"scenario": "square_edge:at_m=0.3", "speed_m_per_s": 3.0, "duration": 0.4},
          callbacks=frontend.CALLBACKS)

__all__ = ["RIG", "PRESETS"]

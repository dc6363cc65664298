"""The whole bike as a rig of the run path's registry (``mtbmj.runpath.rig``): its presets are the
shipped bikes (``mtbmj.bike.spec.preset_names()``); a case is the terrain ``scenario``,
``speed_m_per_s``, ``duration`` (s), ``overrides`` and ``callback``."""
from __future__ import annotations

from mtbmj.bike import crosscheck as bike_crosscheck
from mtbmj.bike import run as bike_run
from mtbmj.bike.spec import preset_names
from mtbmj.runpath.rig import Rig


def _prepare(preset, scenario="flat", speed_m_per_s=4.0, duration=None, overrides=None, callback="auto"):
    return bike_run.prepare(preset, scenario, speed_m_per_s, callback=callback, overrides=overrides)


def _run(preset, scenario="flat", speed_m_per_s=4.0, duration=None, overrides=None, callback="auto"):
    return bike_run.run_bike(preset, scenario, speed_m_per_s=speed_m_per_s, duration=duration, overrides=overrides,
                             callback=callback)


def _crosscheck(preset, scenario="flat", speed_m_per_s=4.0, duration=None, overrides=None, callback="auto"):
    return bike_crosscheck.crosscheck(preset, scenario, speed_m_per_s, duration=duration, overrides=overrides)


RIG = Rig("bike", "bike", preset_names, _prepare, _run, _crosscheck,
          example={"scenario": "root:at_m=0.4", "speed_m_per_s": 4.0, "duration": 0.6},
          callbacks=bike_run.CALLBACKS)

__all__ = ["RIG"]

"""The drop as a rig of the run path's registry (``mtbmj.runpath.rig``): its presets are the study's
configurations (S1-S14 and the rest of ``mtbmj.preset_names()``); a case is ``duration`` (s) and
``overrides``."""
from __future__ import annotations

from mtbmj.config import preset_names
from mtbmj.drop import chain
from mtbmj.drop.crosscheck import crosscheck
from mtbmj.drop.run import run_drop
from mtbmj.runpath.rig import Rig


def _prepare(preset, duration=None, overrides=None):
    return chain.prepare(preset, overrides, duration)


def _run(preset, duration=None, overrides=None):
    return run_drop(preset, overrides=overrides, duration=duration)


def _crosscheck(preset, duration=None, overrides=None):
    return crosscheck(preset, overrides=overrides, duration=duration)


RIG = Rig("drop", "drop", preset_names, _prepare, _run, _crosscheck, example={"duration": 0.3},
          callbacks=("auto",))  # run_drop takes the compiled fork callback where it pays (engine_mujoco.run)

__all__ = ["RIG"]

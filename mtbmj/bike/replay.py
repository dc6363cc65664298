"""A bike run folder (``mtbmj bike ... --out DIR``) replayed: ``mtbmj render DIR`` and
``mtbmj telemetry FILE.SST --compare DIR`` read bike folders through here.

A bike folder is recognised by its manifest (``bike_source``) or by its timeseries' columns
(``front_travel_mm`` and ``rear_travel_mm``). For a video the run is re-simulated,
deterministically, from the manifest (the bike: a preset name or the bike file's path, the
scenario, the locks) and the summary (speed, start, drive, duration), as ``mtbmj render`` does for
a rolling run; the replay's front travel must equal the folder's timeseries (within 1e-3 mm, the
CSV's rounding), else the folder is refused (e.g. a bike changed in Python, whose preset name
no longer describes it, or a bike file changed since).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mtbmj.errors import MtbmjError

MATCH_MM = 1e-3


def is_bike_dir(run_dir) -> bool:
    """True for a folder written by ``mtbmj bike`` / ``BikeResult.write``."""
    try:
        manifest = json.loads((Path(run_dir) / "manifest.json").read_text())
    except (OSError, ValueError):
        return False
    return isinstance(manifest, dict) and "bike_source" in manifest


def trajectory(result, fps: float = 30.0, duration: float | None = None, label: str | None = None):
    """The ``mtbmj.rolling.render.Trajectory`` of a ``BikeResult`` (its pose kept at 240 Hz)."""
    from mtbmj.rolling import render

    times, qpos = result.motion
    return render.rolling_frames(result.prepared.bike.model, times, qpos, fps, duration,
                                 label or f"bike {result.name} over {result.scenario}")


def _read(run_dir: Path, error) -> tuple[dict, dict]:
    try:
        manifest = json.loads((run_dir / "manifest.json").read_text())
        summary = json.loads((run_dir / "summary.json").read_text())
        if not isinstance(manifest, dict) or not isinstance(summary, dict):
            raise ValueError("not a JSON object")
        return manifest, summary
    except (OSError, ValueError, RecursionError) as exc:
        raise error(f"{run_dir}: not a complete bike run ({exc.__class__.__name__}: {exc})") from None


def rerun(run_dir, duration: float | None = None, error=MtbmjError):
    """The ``BikeResult`` of the bike folder ``run_dir``, re-simulated (``duration`` s, default the
    folder's whole run), checked against the folder's timeseries."""
    from mtbmj.bike.run import run_bike

    run_dir = Path(run_dir)
    manifest, summary = _read(run_dir, error)
    try:
        info = manifest.get("engine_info") or {}
        kwargs = {"drive": summary["drive"]["mode"], "start_x": summary.get("start_m"),
                  "callback": "auto", "lock": tuple(info.get("locked", ())),
                  "rear_tire": bool(info.get("rear_tire", True))}
        whole = float(summary["duration_s"])
        result = run_bike(manifest["bike_source"], manifest["scenario"], float(summary["speed_m_per_s"]),
                          whole if duration is None else min(whole, float(duration)), **kwargs)
    except MtbmjError as exc:
        raise error(f"{run_dir}: cannot replay this bike run ({exc})") from None
    except (KeyError, TypeError, ValueError) as exc:
        raise error(f"{run_dir}: not a complete bike run ({exc.__class__.__name__}: {exc})") from None
    from mtbmj.cli.telemetry import read_columns

    columns = read_columns(run_dir, error)
    recorded = columns.get("front_travel_mm")
    if recorded is None:
        raise error(f"{run_dir}: timeseries.csv has no front_travel_mm column")
    replayed = result.raw["front_travel_mm"]
    n = min(recorded.size, replayed.size)
    if n == 0 or not np.max(np.abs(recorded[:n] - replayed[:n])) <= MATCH_MM:
        raise error(f"{run_dir}: the bike {manifest['bike_source']!r} replayed does not reproduce this folder's "
                    "timeseries.csv (a bike changed in Python or a bike file changed since); render it from Python "
                    "with BikeResult.video")
    return result


def run_dir_trajectory(run_dir, fps: float = 30.0, duration: float | None = None, error=MtbmjError):
    """The ``Trajectory`` of a bike folder, re-simulated (``rerun``)."""
    result = rerun(run_dir, duration, error)
    return trajectory(result, fps, duration, f"bike {result.name} over {result.scenario} ({Path(run_dir).name})")


__all__ = ["is_bike_dir", "trajectory", "rerun", "run_dir_trajectory", "MATCH_MM"]

"""A bike run folder (``mtbmj bike ... --out DIR``) replayed for ``mtbmj render DIR``.

A bike folder is recognised by its manifest (``bike_source``) or by its timeseries' columns
(``front_travel_mm`` and ``rear_travel_mm``). For a video the run is re-simulated,
deterministically, from the manifest (the bike: a preset name or the bike file's path, the
scenario, the locks) and the summary (speed, start, drive and a pedalling rider's cadence and power,
duration), as ``mtbmj render`` does for
a rolling run; the replay's front travel must equal the folder's timeseries (within 1e-3 mm, the
CSV's rounding), else the folder is refused (e.g. a bike changed in Python, whose preset name
no longer describes it, or a bike file changed since).
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

from mtbmj.errors import ConfigWarning, MtbmjError
from mtbmj.textfile import run_file_text

MATCH_MM = 1e-3


def is_bike_dir(run_dir) -> bool:
    """True for a folder written by ``mtbmj bike`` / ``BikeResult.write``; a manifest that is not a
    regular file (a FIFO, a device) is refused in one line, not waited on."""
    path = Path(run_dir) / "manifest.json"
    if not path.exists():
        return False
    try:
        manifest = json.loads(run_file_text(path, MtbmjError, "config"))
    except ValueError:
        return False
    return isinstance(manifest, dict) and "bike_source" in manifest


def _read(run_dir: Path, error) -> tuple[dict, dict]:
    try:
        manifest = json.loads(run_file_text(run_dir / "manifest.json", error, "config"))
        summary = json.loads(run_file_text(run_dir / "summary.json", error, "config"))
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
    if summary.get("speed_profile_m_per_s") is not None:  # the folder keeps its range, not the profile itself
        raise error(f"{run_dir}: a run along a speed profile (--speed-profile) is not replayed: the folder does not "
                    f"keep the profile; write its video with mtbmj bike ... --speed-profile CSV --video")
    try:
        info = manifest.get("engine_info") or {}
        pedal = summary["drive"].get("pedal")  # a pedalling rider: its cadence and power again
        kwargs = {"drive": "rider" if pedal else summary["drive"]["mode"], "start_x": summary.get("start_m"),
                  "callback": "auto", "lock": tuple(info.get("locked", ())),
                  "rear_tire": bool(info.get("rear_tire", True)), "overrides": manifest.get("bike_overrides") or None,
                  "seated": bool(info.get("seated", False)),
                  "rider": str((summary.get("rider") or {}).get("kind", "passive")),  # the active rider again
                  "legs_swing": bool(((summary.get("rider") or {}).get("pedal_leg") or {}).get("legs_swing", False)),
                  "pedal": (float(pedal["cadence_rpm"]), float(pedal["power_W"])) if pedal else None}
        whole = float(summary["duration_s"])
    except (KeyError, TypeError, ValueError) as exc:
        raise error(f"{run_dir}: not a complete bike run ({exc.__class__.__name__}: {exc})") from None
    times, recorded = _columns(run_dir, error)
    step = float(np.median(np.diff(times))) if times.size > 1 else 0.0
    held = times[-1] + step if times.size else 0.0
    if not (times.size > 1 and step > 0 and abs(held - whole) <= 2.0 * step + 1e-9):
        raise error(f"{run_dir}: summary.json says {whole:g} s but timeseries.csv holds {held:.4g} s "
                    f"({times.size} samples): the folder was changed since mtbmj wrote it; not replayed")
    try:
        with warnings.catch_warnings():  # the saved speed's plausibility was said when the run was made
            warnings.filterwarnings("ignore", message=r"--speed = ", category=ConfigWarning)
            result = run_bike(manifest["bike_source"], manifest["scenario"], float(summary["speed_m_per_s"]),
                              whole if duration is None else min(whole, float(duration)), **kwargs)
    except MtbmjError as exc:
        raise error(f"{run_dir}: cannot replay this bike run ({exc})") from None
    except (KeyError, TypeError, ValueError) as exc:
        raise error(f"{run_dir}: not a complete bike run ({exc.__class__.__name__}: {exc})") from None
    replayed = result.raw["front_travel_mm"]
    n = replayed.size  # every sample replayed is compared: the whole run, or its first --duration s
    if n == 0 or n > recorded.size or (duration is None and n != recorded.size) \
            or not np.max(np.abs(recorded[:n] - replayed)) <= MATCH_MM:
        raise error(f"{run_dir}: the bike {manifest['bike_source']!r} replayed does not reproduce this folder's "
                    "timeseries.csv (a bike changed in Python or a bike file changed since); render it from Python "
                    "with BikeResult.video")
    return result


def _columns(run_dir: Path, error) -> tuple[np.ndarray, np.ndarray]:
    """The time_s and front_travel_mm columns of the folder's timeseries.csv."""
    path = run_dir / "timeseries.csv"
    try:
        lines = [line for line in run_file_text(path, error, "record").splitlines() if line.strip() and not line.startswith("#")]
        names = [n.strip() for n in lines[0].split(",")]
        table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
        return table[:, names.index("time_s")], table[:, names.index("front_travel_mm")]
    except (OSError, UnicodeDecodeError, ValueError, IndexError) as exc:
        raise error(f"{path}: cannot read its time_s and front_travel_mm columns ({exc.__class__.__name__}: {exc})") from None


__all__ = ["is_bike_dir", "rerun", "MATCH_MM"]

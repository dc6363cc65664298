"""The end of travel: one definition of bottom-outs and rim strikes for every command.

Every run that moves the fork (``drop``, ``study``, ``sweep``, ``validate``, ``roll``) reports the
same keys, computed here from the engine-rate signals (never the filtered 1 kHz record, which
rounds off the deepest millimetre):

* ``bumper``: the fork inside its bottom-out bumper (compression past ``travel - bumper
  length``): what a rider calls a bottom-out, the elastomer or hydraulic end of the stroke;
* ``hard_stop``: the fork past its full travel, metal on metal (the stop's compliance lets it pass
  the travel by a millimetre or two);
* ``rim_strikes``: the tire deflected past its maximum deflection, the rim on the ground;

each as ``{"count", "deepest_mm", "peak_force_N"}`` (``deepest_mm`` and ``peak_force_N`` are
``None`` with a count of 0; ``peak_force_N`` is that element's own force: the bumper's, the
stop's, the rim's), and the stroke: ``travel_mm``, ``travel_used_mm``, ``travel_used_percent`` and
``travel_remaining_mm`` (negative when the fork passed its travel). An episode starts when the
signal crosses its threshold and ends when it falls ``RELEASE_MM`` below it, so a fork resting at
the bumper's edge is one engagement, not a chatter of many. ``bottomed_out`` is True when the
bumper or the hard stop engaged.

The keys are flat in sweep tables (``bumper_count``, ``hard_stop_deepest_mm``,
``rim_strikes_peak_force_N`` ...), see ``TABLE_COLUMNS``.
"""
from __future__ import annotations

import numpy as np

RELEASE_MM = 0.5  # an engagement ends this far below its threshold (hysteresis)
ELEMENTS = ("bumper", "hard_stop", "rim_strikes")
WHAT = {"bumper": "bottomed out on the bumper", "hard_stop": "hit the hard stop", "rim_strikes": "struck the rim"}
TABLE_COLUMNS = (["travel_used_percent", "travel_remaining_mm", "bottomed_out"]
                 + [f"{e}_{field}" for e in ELEMENTS for field in ("count", "deepest_mm", "peak_force_N")])


def episodes(signal: np.ndarray, threshold: float, release: float = RELEASE_MM) -> list[slice]:
    """Runs where ``signal`` is above ``threshold``; each ends when the signal falls ``release``
    below the threshold (so an episode includes its dips shallower than that)."""
    signal = np.asarray(signal, float)
    out = []
    above = np.flatnonzero(signal > threshold)
    if above.size == 0:
        return out
    below = signal < threshold - release
    i = int(above[0])
    n = signal.size
    while i < n:
        released = np.flatnonzero(below[i:])
        end = i + int(released[0]) if released.size else n
        out.append(slice(i, end))
        later = above[above >= end]
        if later.size == 0:
            break
        i = int(later[0])
    return out


def _element(signal_mm: np.ndarray, threshold_mm: float | None, force) -> dict:
    """Count, deepest (mm) and peak force (N, from ``force(i)`` at each sample of an episode)."""
    if threshold_mm is None:
        return {"count": 0, "deepest_mm": None, "peak_force_N": None}
    runs = episodes(signal_mm, threshold_mm)
    if not runs:
        return {"count": 0, "deepest_mm": None, "peak_force_N": None}
    idx = np.concatenate([np.arange(r.start, r.stop) for r in runs])
    return {"count": len(runs), "deepest_mm": float(np.max(signal_mm[idx])),
            "peak_force_N": float(max(force(int(i)) for i in idx))}


def bumper_engages(spring) -> bool:
    """Whether ``spring`` has end stops with a bumper that pushes (a length and a force)."""
    return (hasattr(spring, "stop_forces") and getattr(spring, "bumper_length", 0.0) > 0.0
            and getattr(spring, "bumper_force", 0.0) > 0.0)


def end_of_travel(setup, fork_mm, fork_velocity_mm_per_s, tire_mm, tire_velocity_mm_per_s=None,
                  time_s=None) -> dict:
    """The end-of-travel report of one run (see the module doc) from its engine-rate signals:
    fork compression and its rate, tire deflection and its rate (from ``time_s`` by finite
    differences when not given)."""
    fork = np.asarray(fork_mm, float)
    fork_v = np.asarray(fork_velocity_mm_per_s, float) * 1e-3
    tire = np.asarray(tire_mm, float)
    if tire_velocity_mm_per_s is None:
        tire_v = np.gradient(tire, np.asarray(time_s, float)) * 1e-3 if tire.size > 1 else np.zeros_like(tire)
    else:
        tire_v = np.asarray(tire_velocity_mm_per_s, float) * 1e-3
    travel_mm = setup.travel * 1e3
    spring = setup.fork.spring
    stops = hasattr(spring, "stop_forces")
    has_bumper = bumper_engages(spring)
    bumper = _element(fork, spring.bumper_start * 1e3 if has_bumper else None,
                      lambda i: spring.stop_forces(fork[i] * 1e-3, fork_v[i])[0])
    hard = _element(fork, travel_mm if stops else None, lambda i: spring.stop_forces(fork[i] * 1e-3, fork_v[i])[1])
    if not stops:  # a law without end stops (S1-S9's plain springs): the travel is still the travel
        hard = _element(fork, travel_mm, lambda i: 0.0)
        if hard["count"]:
            hard["peak_force_N"] = None  # the law has no stop to push back
    rim = setup.tire.rim
    strikes = _element(tire, rim.max_deflection * 1e3 if rim is not None else None,
                       lambda i: rim.force(tire[i] * 1e-3, tire_v[i]))
    used = float(np.max(fork)) if fork.size else 0.0
    return {
        "travel_mm": travel_mm,
        "travel_used_mm": used,
        "travel_used_percent": used / travel_mm * 100.0,
        "travel_remaining_mm": travel_mm - used,
        "bumper_engages_at_mm": spring.bumper_start * 1e3 if has_bumper else None,
        "rim_max_deflection_mm": rim.max_deflection * 1e3 if rim is not None else None,
        "bumper": bumper,
        "hard_stop": hard,
        "rim_strikes": strikes,
        "bottomed_out": bool(bumper["count"] or hard["count"]),
    }


def line(report: dict) -> str:
    """What the one-line summary of a command adds: "; bottomed out on the bumper 2x (deepest
    158.5 mm, 1.9 kN); struck the rim 1x (...)", or "" when nothing engaged."""
    parts = []
    for key in ELEMENTS:
        e = report.get(key) or {}
        if e.get("count"):
            force = f", {e['peak_force_N'] / 1e3:.1f} kN" if e.get("peak_force_N") is not None else ""
            parts.append(f"{WHAT[key]} {e['count']}x (deepest {e['deepest_mm']:.1f} mm{force})")
    return "".join(f"; {p}" for p in parts)


def table_row(report: dict) -> dict:
    """The report as flat table columns (``TABLE_COLUMNS``)."""
    row = {"travel_used_percent": report["travel_used_percent"], "travel_remaining_mm": report["travel_remaining_mm"],
           "bottomed_out": report["bottomed_out"]}
    for element in ELEMENTS:
        for field in ("count", "deepest_mm", "peak_force_N"):
            row[f"{element}_{field}"] = report[element][field]
    return row


__all__ = ["end_of_travel", "bumper_engages", "episodes", "line", "table_row", "TABLE_COLUMNS", "ELEMENTS", "RELEASE_MM"]

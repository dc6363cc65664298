"""A bike's frame from its geometry chart (``[geometry]`` in a bike file).

A chart is read with both wheels (of one size) on flat ground at full extension, so the axles are
level and the chart's head angle is the frame's. Frame coordinates: origin at the bottom bracket,
x forward along the ground, z up. What the chart gives and what it sets:

- ``head_angle_deg``, ``wheelbase_mm``, ``chainstay_mm``, ``fork_offset_mm`` and the bottom
  bracket as ``bb_drop_mm`` (below the axles) or ``bb_height_mm`` (above the ground, with
  ``wheel_diameter_mm``): the frame's axles and head angle (``bike.*``, :func:`frame_keys`).
- ``reach_mm``, ``stack_mm``, ``head_tube_mm`` with the fork's ``fork_length_mm`` (axle to crown):
  the front axle a second way, which must agree with the first.
- ``wheel_diameter_mm`` (the tyres' outer diameter), ``fork_travel_mm`` and ``fork_length_mm``: the
  fork configuration's ``tire.radius_mm``, ``fork.travel_mm`` and ``fork.length_mm``
  (:func:`fork_keys`), set in the file's ``[fork.set]`` as if written there.
- ``rear_travel_mm``: checked against the wheel travel the shock's stroke gives through the rear
  end (:func:`check_rear_travel`).
- ``seat_tube_angle_deg`` (effective) and ``saddle_height_mm`` (bottom bracket to the saddle along
  that line): the saddle, and with ``rider.seated_com_from_saddle_mm`` the seated rider's centre
  of mass (:func:`seated_com`).

Values that over-determine one another are refused in one line naming them when they disagree by
more than the tolerances below; a chart's numbers are rounded to the millimetre.
"""
from __future__ import annotations

import math

from mtbmj import limits
from mtbmj.errors import ConfigError

# what a chart sets in [bike]
SETS = ("head_angle_deg", "fork_offset_mm", "front_axle_mm", "rear_axle_mm")
REQUIRED = ("head_angle_deg", "wheelbase_mm", "chainstay_mm", "fork_offset_mm")
BOTTOM_BRACKET = ("bb_drop_mm", "bb_height_mm")
CHECK = ("reach_mm", "stack_mm", "head_tube_mm")  # with fork_length_mm: the front axle a second way
FORK = {"wheel_diameter_mm": "tire.radius_mm", "fork_travel_mm": "fork.travel_mm", "fork_length_mm": "fork.length_mm"}
SEAT = ("seat_tube_angle_deg", "saddle_height_mm")
# the keys that place the frame: a --set of one drops the reach-and-stack check (it checked the chart as published)
FRAME = REQUIRED + BOTTOM_BRACKET + ("wheel_diameter_mm", "fork_length_mm")
KEYS = REQUIRED + BOTTOM_BRACKET + CHECK + tuple(FORK) + ("rear_travel_mm",) + SEAT

AXLE_TOLERANCE_MM = 5.0  # the front axle from reach and stack against the one from the wheelbase
BB_TOLERANCE_MM = 2.0  # bb_height_mm against wheel_diameter_mm / 2 - bb_drop_mm
REAR_TRAVEL_TOLERANCE_MM = 5.0  # rear_travel_mm against the wheel travel at the shock's full stroke

RANGES = {"head_angle_deg": (45.0, 90.0), "wheelbase_mm": (500.0, 2000.0), "chainstay_mm": (300.0, 600.0),
          "bb_drop_mm": (-150.0, 150.0), "bb_height_mm": (150.0, 500.0), "fork_offset_mm": (0.0, 150.0),
          "reach_mm": (300.0, 600.0), "stack_mm": (500.0, 750.0), "head_tube_mm": (50.0, 250.0),
          "fork_length_mm": (400.0, 700.0), "wheel_diameter_mm": (300.0, 1000.0), "fork_travel_mm": (20.0, 250.0),
          "rear_travel_mm": (20.0, 250.0), "seat_tube_angle_deg": (60.0, 90.0), "saddle_height_mm": (400.0, 1100.0)}


def number(chart: dict, key: str) -> float:
    """``geometry.KEY``, a finite number within its range (``RANGES``)."""
    v = chart.get(key)
    if v is None:
        raise ConfigError(f"geometry.{key}: missing")
    v = limits.number(f"geometry.{key}", v)  # the numeric-input gate: finite, fits a float
    low, high = RANGES[key]
    if not low <= v <= high:
        unit = " mm" if key.endswith("_mm") else " deg" if key.endswith("_deg") else ""
        hint = (f" (metres typed for mm? {v:g} m is {v * 1000.0:g} mm)" if unit == " mm" and low <= v * 1000.0 <= high
                else f" (radians? {v:g} rad is {math.degrees(v):.1f} deg)" if unit == " deg"
                and low <= math.degrees(v) <= high else "")
        raise ConfigError(f"geometry.{key}: {v:g}{unit} is outside {low:g}-{high:g}{unit}{hint}")
    return float(v)


def check_keys(chart: dict) -> None:
    unknown = sorted(set(chart) - set(KEYS))
    if unknown:
        raise ConfigError(f"geometry.{unknown[0]}: unknown key (known: {', '.join(KEYS)})")


def bb_drop(chart: dict) -> float:
    """The bottom bracket's drop below the axles (mm): ``bb_drop_mm``, or ``wheel_diameter_mm`` / 2
    less ``bb_height_mm``; both given must agree within ``BB_TOLERANCE_MM``."""
    given = [k for k in BOTTOM_BRACKET if k in chart]
    if not given:
        raise ConfigError("geometry.bb_drop_mm: missing (give the bottom bracket as bb_drop_mm, or as bb_height_mm "
                          "with wheel_diameter_mm)")
    drop = number(chart, "bb_drop_mm") if "bb_drop_mm" in chart else None
    if "bb_height_mm" not in chart:
        return drop
    height = number(chart, "bb_height_mm")
    if "wheel_diameter_mm" not in chart:
        raise ConfigError("geometry.bb_height_mm: needs geometry.wheel_diameter_mm (the drop below the axles is the "
                          "wheels' radius less the height)")
    radius = number(chart, "wheel_diameter_mm") / 2.0
    if drop is None:
        return radius - height
    if abs(radius - height - drop) > BB_TOLERANCE_MM:
        raise ConfigError(f"geometry: bb_height_mm {height:g} on wheels of {2 * radius:g} mm puts the bottom bracket "
                          f"{radius - height:g} mm below the axles, but bb_drop_mm is {drop:g}; more than "
                          f"{BB_TOLERANCE_MM:g} mm apart: a value is wrong")
    return drop


def frame_keys(chart: dict) -> dict:
    """The [bike] geometry keys the chart gives: the rear axle ``chainstay_mm`` from the bottom
    bracket and its drop above it; the front axle at the same height ``wheelbase_mm`` ahead. With
    ``reach_mm``, ``stack_mm``, ``head_tube_mm`` and ``fork_length_mm`` the front axle is found a
    second way (down the steering axis from the head tube's top by the head tube and the fork's
    axle-to-crown, then the offset forward), and the two must agree within ``AXLE_TOLERANCE_MM``."""
    check_keys(chart)
    head = number(chart, "head_angle_deg")
    wheelbase, chainstay = number(chart, "wheelbase_mm"), number(chart, "chainstay_mm")
    offset = number(chart, "fork_offset_mm")
    drop = bb_drop(chart)
    if abs(drop) >= chainstay:
        raise ConfigError(f"geometry.bb_drop_mm: {drop:g} mm is not less than the chainstay, {chainstay:g} mm")
    rear = (-math.sqrt(chainstay ** 2 - drop ** 2), drop)
    front = (wheelbase + rear[0], drop)
    if front[0] <= 0.0:
        raise ConfigError(f"geometry.wheelbase_mm: {wheelbase:g} mm leaves the front axle behind the bottom bracket "
                          f"(chainstay {chainstay:g} mm)")
    given = [k for k in CHECK if k in chart]
    if given:
        missing = [k for k in CHECK + ("fork_length_mm",) if k not in chart]
        if missing:
            raise ConfigError(f"geometry.{missing[0]}: needed with {', '.join('geometry.' + k for k in given)} (the "
                              f"front axle found from reach and stack takes all of {', '.join(CHECK)} and "
                              f"fork_length_mm)")
        reach, stack = number(chart, "reach_mm"), number(chart, "stack_mm")
        tube, crown = number(chart, "head_tube_mm"), number(chart, "fork_length_mm")
        a = math.radians(head)
        down = (math.cos(a), -math.sin(a))  # along the steering axis, down and forward
        ahead = (math.sin(a), math.cos(a))  # across it, forward: the offset's direction
        along = tube + crown
        axle = (reach + along * down[0] + offset * ahead[0], stack + along * down[1] + offset * ahead[1])
        miss = math.hypot(axle[0] - front[0], axle[1] - front[1])
        if miss > AXLE_TOLERANCE_MM:
            raise ConfigError(
                f"geometry: reach {reach:g}, stack {stack:g}, head tube {tube:g}, axle-to-crown {crown:g}, offset "
                f"{offset:g} and head angle {head:g} put the front axle at ({axle[0]:.0f}, {axle[1]:.0f}) mm, "
                f"{miss:.0f} mm from where wheelbase {wheelbase:g}, chainstay {chainstay:g} and BB drop {drop:g} put "
                f"it ({front[0]:.0f}, {front[1]:.0f}); more than {AXLE_TOLERANCE_MM:g} mm: a value is wrong")
    return {"head_angle_deg": head, "fork_offset_mm": offset, "front_axle_mm": [front[0], front[1]],
            "rear_axle_mm": [rear[0], rear[1]]}


def fork_keys(chart: dict) -> dict:
    """The fork configuration's keys a chart sets (``[fork.set]``): the tyres' radius (both wheels
    are the fork configuration's tyre), the fork's travel and its axle-to-crown."""
    out = {}
    for key, schema in FORK.items():
        if key in chart:
            v = number(chart, key)
            out[schema] = v / 2.0 if key == "wheel_diameter_mm" else v
    return out


def saddle(chart: dict) -> tuple[float, float] | None:
    """The saddle (mm, frame coordinates) ``saddle_height_mm`` up the effective seat-tube angle from
    the bottom bracket, or None when the chart gives neither; one without the other is refused."""
    given = [k for k in SEAT if k in chart]
    if not given:
        return None
    if len(given) < 2:
        other = SEAT[1 - SEAT.index(given[0])]
        raise ConfigError(f"geometry.{other}: needed with geometry.{given[0]} (the saddle lies saddle_height_mm up "
                          f"the seat-tube angle from the bottom bracket)")
    a, height = math.radians(number(chart, "seat_tube_angle_deg")), number(chart, "saddle_height_mm")
    return (-height * math.cos(a), height * math.sin(a))


def seated_com(chart: dict, from_saddle) -> list[float] | None:
    """The seated rider's centre of mass (mm): the chart's saddle plus ``from_saddle``
    (``rider.seated_com_from_saddle_mm``), or None when the chart places no saddle."""
    point = saddle(chart)
    if point is None:
        return None
    if (not isinstance(from_saddle, (list, tuple)) or len(from_saddle) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in from_saddle)):
        raise ConfigError("rider.seated_com_from_saddle_mm: "
                          + ("missing (needed with geometry.seat_tube_angle_deg: where the seated rider's centre of "
                             "mass lies from the saddle, e.g. [60, 200])" if from_saddle is None
                             else f"must be [x, z] in mm, got {from_saddle!r}"))
    return [point[0] + float(from_saddle[0]), point[1] + float(from_saddle[1])]


def check_rear_travel(chart: dict, leverage, stroke: float) -> None:
    """``rear_travel_mm`` against the rear wheel's travel at the shock's full ``stroke`` (m) through
    ``leverage`` (``spec.Leverage``; past its table the last ratio is carried on)."""
    if "rear_travel_mm" not in chart:
        return
    travel = number(chart, "rear_travel_mm")
    has = leverage.travel_at_stroke(stroke) * 1e3
    if abs(has - travel) > REAR_TRAVEL_TOLERANCE_MM:
        raise ConfigError(f"geometry.rear_travel_mm: {travel:g} mm, but the shock's {stroke * 1e3:g} mm stroke "
                          f"(shock.stroke_mm) gives {has:.1f} mm of wheel travel through the rear end; more than "
                          f"{REAR_TRAVEL_TOLERANCE_MM:g} mm apart: a value is wrong")

"""A bike's description: geometry, masses, rider, leverage curve, and the fork and shock laws.

A bike is a TOML file of its own schema (``mtbmj/bike/presets/*.toml``, or a path), read here
into a ``BikeSpec`` in SI units. The fork's and the shock's force laws are not described here:
each names a configuration of the fork schema (a preset such as ``reference`` and overrides),
which ``mtbmj.compose`` turns into the same law objects the drop and the rolling front end use.
The shock's configuration is read in *shock* coordinates: its ``fork.travel_mm`` is the shock's
stroke, its spring and damper act on the shock's own stroke and speed.

Frame coordinates: origin at the bottom bracket, x forward, z up, the bike with both ends at full
extension (every joint at 0). Bad input raises ``ConfigError`` naming the key (one line, exit
status 2 on the command line).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


from mtbmj import limits
from mtbmj.bike import chart as _chart
from mtbmj.bike import linkage as _linkage
from mtbmj.bike import shock as _shock
from mtbmj.bike.bikefile import (KNOWN, SENSOR_KEYS, gated, mapping, merge, overridden, preset_names,  # noqa: F401
                                  read_leverage_csv, read_table)
from mtbmj.bike.bikefile import USED, reads_key  # the configurations' keys the bike reads
from mtbmj.errors import ConfigError
from mtbmj.measured.leverage import Leverage, leverage_ratio, leverage_stroke, stroke_piece  # noqa: F401

MM = 1e-3


@dataclass(frozen=True)
class Rider:
    mass: float  # kg, the body on the legs and arms (the whole rider less ``on_bike_mass``)
    on_bike_mass: float  # kg, feet, shanks, hands and forearms: moving with the frame
    com: tuple[float, float]  # m, frame coordinates, standing at rest
    pitch_inertia: float  # kg m^2 about the body's centre of mass
    leg_x: float  # m, where the legs meet the frame (the pedals), frame x
    arm_x: float  # m, where the arms meet the frame (the bars), frame x
    leg_z: float  # m, frame z of the pedals
    arm_z: float  # m, frame z of the bars
    leg_length: float  # m, pedals to hips (vertical, at rest)
    arm_length: float  # m, bars to shoulders (vertical, at rest)
    leg_stiffness: float  # N/m, both legs
    leg_damping: float  # N s/m
    arm_stiffness: float  # N/m, both arms
    arm_damping: float  # N s/m
    seated_com: tuple[float, float] | None = None  # m, frame coordinates, seated on the saddle (None: not given)
    height: float = 1.78  # m, the whole rider's stature (the active rider's segments: mtbmj.bike.rider_body)


@dataclass(frozen=True)
class BikeSpec:
    name: str
    head_angle: float  # rad from the frame's x axis (frame coordinates): the chart's plus the frame's pitch on flat ground
    fork_offset: float  # m, perpendicular to the steering axis, forward
    front_axle: tuple[float, float]  # m, frame coordinates at full extension
    rear_axle: tuple[float, float]
    pivot: tuple[float, float]
    frame_mass: float
    frame_com: tuple[float, float]
    frame_inertia: float  # kg m^2 about its centre of mass (pitch)
    swingarm_mass: float
    swingarm_inertia: float  # about its centre of mass, which is midway between pivot and axle
    fork_lower_mass: float  # lower legs, at the front axle
    front_wheel_mass: float
    rear_wheel_mass: float
    wheel_inertia: float  # kg m^2 about the axle (spin; no effect on the planar motion)
    leverage: Leverage
    shock_stroke: float  # m
    rider: Rider
    fork_config: str
    fork_overrides: dict
    shock_config: str
    shock_overrides: dict
    drive: dict
    source: str
    overrides: dict = field(default_factory=dict)  # what ``load``'s overrides changed (for the manifest)
    # the pivot is a four-bar's instant centre at top-out (``[linkage]``), not a bearing on the frame
    virtual_pivot: bool = False
    sensors: dict = field(default_factory=dict)  # the telemetry sensors' calibration, mm (``[sensors]``)
    # a four-bar's rear caliper on a link that turns otherwise than the bike's arm: d(its turn) /
    # d(the arm's turn) at each point of the leverage table (``linkage.caliper_ratio``); None: 1
    caliper_ratio: tuple | None = None
    # the shock configuration's keys its [shock] keys as sold set (``mtbmj.bike.shock.written``)
    shock_sold: frozenset = frozenset()

    @property
    def swingarm_length(self) -> float:
        return math.hypot(self.rear_axle[0] - self.pivot[0], self.rear_axle[1] - self.pivot[1])

    @property
    def swingarm_angle(self) -> float:
        """beta0 (rad): the swingarm's angle below the horizontal at full extension (axle behind
        the pivot; positive when the axle is below it)."""
        return math.atan2(self.pivot[1] - self.rear_axle[1], self.pivot[0] - self.rear_axle[0])

    @property
    def total_mass(self) -> float:
        return (self.frame_mass + self.swingarm_mass + self.fork_lower_mass + self.front_wheel_mass
                + self.rear_wheel_mass + self.rider.mass + self.rider.on_bike_mass)


def _sensors(table: dict) -> dict:
    """The ``[sensors]`` calibration (mm), checked: each a positive number, and each triangle one
    that closes (the fork's base at most twice its arm; the shock's sides a triangle)."""
    got = table.get("sensors") or {}
    out = {}
    for key in SENSOR_KEYS:
        if key in got:
            value = limits.number(f"sensors.{key}", got[key], "a positive number of mm")
            if value <= 0:
                raise ConfigError(f"sensors.{key}: must be a positive number of mm, got {value!r}")
            out[key] = value
    fork = [k for k in ("fork_arm_mm", "fork_max_mm") if k in out]
    if len(fork) == 1:
        raise ConfigError(f"sensors.{fork[0]}: give fork_arm_mm and fork_max_mm together")
    if fork and out["fork_max_mm"] >= 2.0 * out["fork_arm_mm"]:
        raise ConfigError(f"sensors.fork_max_mm: {out['fork_max_mm']:g} mm is not shorter than the two arms "
                          f"({2 * out['fork_arm_mm']:g} mm): that triangle does not close")
    shock = [k for k in ("shock_arm1_mm", "shock_arm2_mm", "shock_max_mm") if k in out]
    if 0 < len(shock) < 3:
        missing = [k for k in ("shock_arm1_mm", "shock_arm2_mm", "shock_max_mm") if k not in out]
        raise ConfigError(f"sensors.{missing[0]}: give shock_arm1_mm, shock_arm2_mm and shock_max_mm together")
    if shock:
        a, b, c = out["shock_arm1_mm"], out["shock_arm2_mm"], out["shock_max_mm"]
        if not (abs(a - b) < c < a + b):
            raise ConfigError(f"sensors.shock_max_mm: {c:g} mm with arms {a:g} and {b:g} mm: that triangle does not close")
    return out


LINKAGE_AXLE_TOLERANCE_MM = 1.0  # the linkage's rear axle against the frame's (bike.rear_axle_mm or the chart's)
PATH_TOLERANCE_MM = 0.1  # a four-bar's axle path and the bike's circle: farther apart than this, a warning says so


def _with_linkage(table: dict) -> tuple[dict, tuple | None, object, object]:
    """``table`` with ``bike.pivot_mm`` and ``[leverage]`` from its ``[linkage]`` (``mtbmj.bike.linkage``),
    and the rear caliper's link's turn against the arm's at each point of that table (None where
    the caliper rides on the arm):
    the pivot the rear axle turns about (for a four-bar whose axle rides on its coupler, the centre of
    the circle that best fits the linkage's axle path, ``linkage.fitted_pivot``, with a warning when
    it leaves the path by more than 0.1 mm) and the leverage ratio every millimetre of wheel travel
    up to the shock's stroke; then the linkage and its curves over that stroke (solved here once)."""
    from mtbmj.bike import linkage as lk
    from mtbmj.config import warn

    link = lk.from_table(table["linkage"])
    stroke = _number(table, "shock", "stroke_mm", positive=True) * MM
    c = lk.curves(link, stroke)
    bike = dict(table.get("bike") or {})
    axle = link.p0["rear_axle"] / MM
    if "rear_axle_mm" in bike:
        given = np.asarray(bike["rear_axle_mm"], float)
        if given.shape != (2,) or float(np.hypot(*(given - axle))) > LINKAGE_AXLE_TOLERANCE_MM:
            raise ConfigError(f"linkage.rear_axle_mm: {axle.round(1).tolist()} lies more than "
                              f"{LINKAGE_AXLE_TOLERANCE_MM:g} mm from bike.rear_axle_mm (or the chart's) "
                              f"{bike['rear_axle_mm']!r}")
    bike["rear_axle_mm"] = axle.tolist()
    if link.four_bar is None or link.kind == "linkage_driven_single_pivot":
        pivot = link.p0["main_pivot"]
    else:  # the axle rides on the coupler: the circle that fits its path (lk.fitted_pivot)
        if link.pose(0.0).axle_centre is None:
            a, b, c, d = (f"linkage.{n}_mm" for n in link.four_bar)
            raise ConfigError(f"{a} to {b} and {d} to {c}: parallel at full extension: the four-bar's frame links "
                              f"have no instant centre")
        pivot = lk.fitted_pivot(link, c)
    bike["pivot_mm"] = (pivot / MM).tolist()
    if link.kind in ("horst_link", "short_link"):
        off = lk.path_departure(link, c, pivot)
        if off > PATH_TOLERANCE_MM * MM:
            warn([f"linkage.kind = {link.kind}: the bike turns its rear axle on the circle that best fits the "
                  f"linkage's axle path (centre {pivot[0] / MM:.1f}, {pivot[1] / MM:.1f} mm), {off / MM:.2f} mm at "
                  f"most from that path over the travel; the leverage ratio is the linkage's (mtbmj linkage draws "
                  f"both)"])
    lev = {"wheel_travel_mm": (c.travel / MM).tolist(), "ratio": c.leverage_ratio.tolist()}
    out = {k: v for k, v in table.items() if k != "linkage"}
    out.update({"bike": bike, "leverage": lev})
    ratio = lk.caliper_ratio(c, pivot)
    return out, (tuple(float(x) for x in ratio) if np.max(np.abs(ratio - 1.0)) > 1e-9 else None), link, c


def _number(table: dict, section: str, key: str, positive: bool = False, nonneg: bool = False) -> float:
    full = f"{section}.{key}"
    if key not in table.get(section, {}):
        raise ConfigError(f"{full}: missing")
    from mtbmj.config import unit_of

    typed = table[section][key]
    v = limits.number(full, typed, "a plain number (the unit is in the key name)"
                      if isinstance(typed, str) and unit_of(key) else "a finite number")
    if positive and not v > 0:
        raise ConfigError(f"{full}: must be > 0, got {v!r}")
    if nonneg and v < 0:
        raise ConfigError(f"{full}: must be >= 0, got {v!r}")
    return float(v)


def _point(table: dict, section: str, key: str) -> tuple[float, float]:
    full = f"{section}.{key}"
    if key not in table.get(section, {}):
        raise ConfigError(f"{full}: missing")
    v = table[section][key]
    if not isinstance(v, list) or len(v) != 2:
        raise ConfigError(f"{full}: must be two numbers [x, z] in mm, got {v!r}")
    v = [limits.number(full, x, "two numbers [x, z] in mm") for x in v]
    far = [x for x in v if abs(x) > MAX_COORDINATE_MM]
    if far:
        raise ConfigError(f"{full}: {far[0]:g} mm is more than {MAX_COORDINATE_MM / 1000:g} m from the bottom "
                          f"bracket; no part of a bike or rider is")
    return float(v[0]) * MM, float(v[1]) * MM


MAX_COORDINATE_MM = 5000.0  # no point of a bike or its rider lies farther from the bottom bracket


# A leverage table may need this share of the shock's stroke more than the stroke without being refused:
# a table of ratios every millimetre, linear between them, integrates (``Leverage``) to the stroke of
# the curve it samples only within its discretisation error, ~h^2 |LR''| / (8 LR) for a step h. A table
# solved from hardpoints at the very stroke (``_with_linkage``) needed 1.1e-7 more on the test's single
# pivot (50.000006 mm of 50 mm, refused as "shorter") and up to 7e-5 on 300 fuzzed single pivots, Horst
# and short links with ratios up to 69; 1e-3 is 0.05 mm on a 50 mm stroke, half the 0.1 mm a shock's
# stroke is given to, and far below what a table that really needs more stroke is short by.
STROKE_TOLERANCE = 1e-3

# A shock stroke longer than the leverage table needs by more than this is warned of: the wheel
# can travel past the table's end, where the curve is extrapolated (both presets are within 0.6 mm).
STROKE_GAP_M = 1e-3

# The share of a rider's mass in the segments that move with the bike: feet, shanks, hands and
# forearms, both sides; sourced: de Leva 1996 (J. Biomech. 29(9):1223), male segment masses in % of
# body mass: foot 1.37, shank 4.33, hand 0.61, forearm 1.62.
LIMBS_SHARE_PERCENT = 2 * (1.37 + 4.33 + 0.61 + 1.62)
RETIRED = {"rider.on_bike_mass_kg": "rider.mass_kg is the whole rider; the share of it that moves with the bike "
                                    "is rider.limbs_share_percent (de Leva's 15.86 % by default)"}


def _set_hint(section: str, key: str) -> str:
    """What a key a part's configuration does not read was likely meant as: a bike key (given to
    ``--shock-set`` or in a ``set`` table), or the configuration's ``fork.*`` key without or with
    another first part (``spring.rate_N_per_mm``, ``shock.damper.rebound_N_s_per_m``)."""
    from mtbmj.bike.bikefile import bike_key

    if bike_key(key):
        part, _, name = key.partition(".")
        return f"; {key} is a key of the bike file ([{part}] {name}), given on the command line with --set {key}=VALUE"
    from mtbmj.config import ALTERNATIVES, SCHEMA

    if section == "shock" and str(key).startswith("tire."):  # both tyres are the fork's configuration's
        from mtbmj.bike.bikefile import configuration_option

        said = configuration_option(key)
        if said:
            return said
    first, _, rest = key.partition(".")
    for meant in (f"fork.{key}", f"fork.{rest}" if rest and first in ("shock", "fork") else ""):
        if meant and meant != key and (meant in SCHEMA or meant in ALTERNATIVES) and reads_key(section, meant):
            return f"; did you mean {meant!r}?"
    return ""


@dataclass(frozen=True)
class ResolvedBike:
    """A bike file resolved once (:func:`resolve`): the file's table as read (``read``: its bases,
    chart, shock as sold and leverage CSV's path merged, no overrides), the ``overrides`` over it,
    the resolved ``table`` the bike was built from (the chart's frame and the linkage's pivot and
    leverage derived), the checked ``spec``, and for a rear end given by hardpoints its ``linkage``
    and their ``curves`` over the shock's stroke (``mtbmj.bike.linkage.curves``; None for a table).
    Every command and run that takes a bike takes this; :meth:`with_overrides` gives the same file
    at other settings without reading it again."""

    source: str
    read: dict = field(repr=False)
    overrides: dict
    table: dict = field(repr=False)
    spec: BikeSpec
    linkage: object | None = field(default=None, repr=False)
    curves: object | None = field(default=None, repr=False)
    csv: dict = field(default_factory=dict, repr=False)  # the leverage CSVs read: path -> (travel mm, ratio)

    @property
    def name(self) -> str:
        return self.spec.name

    def with_overrides(self, overrides) -> "ResolvedBike":
        """The same file with ``overrides`` (every override over the file: these replace this
        bike's own, they do not add to them), derived and checked again, not read again."""
        return derive(self.source, self.read, overrides, self.csv)


def resolve(ref, overrides=None) -> ResolvedBike:
    """A bike preset name (``preset_names()``) or a TOML path read (``mtbmj.bike.bikefile.read_table``),
    ``overrides`` applied (:func:`overridden`), derived and checked: the one resolution of a bike
    file. A :class:`ResolvedBike` is taken as it is (with ``overrides``: those over its file)."""
    mapping(overrides)  # before the file's errors are told from the overrides' by their keys
    if isinstance(ref, ResolvedBike):
        return ref if overrides is None else ref.with_overrides(overrides)
    table, source = read_table(str(ref))
    try:
        return derive(source, table, overrides, {})
    except ConfigError as exc:  # a key of the file at fault: name the file (not a preset's, nor one typed)
        said = str(exc)
        key = said.partition(":")[0]
        typed = key.startswith("-") or any(key == k or key.startswith(f"{k}.") or k.endswith(f".{key}")
                                           for k in (overrides or {}))
        if source in preset_names() or typed or said.startswith(source) or key.startswith("leverage.csv"):
            # (the leverage CSV's own errors name that file, the one at fault)
            raise
        bases = " or ".join(f'"{n}"' for n in preset_names())
        hint = (f" (a bike file gives every key or starts from a bike that does: base = {bases}, or a file of "
                f"your own)" if said.endswith(": missing") else "")
        raise ConfigError(f"{source}: {said}{hint}") from None


def load(ref, overrides=None) -> BikeSpec:
    """A ``BikeSpec`` from a bike preset name (``preset_names()``), a TOML path or a
    :class:`ResolvedBike`, checked, with ``overrides`` applied (:func:`overridden`): ``resolve(ref, overrides).spec``."""
    return resolve(ref, overrides).spec


def derive(source: str, read: dict, overrides=None, csv: dict | None = None) -> ResolvedBike:
    """The bike of a file's table as read (``read``: ``read_table``'s, left as it was) with
    ``overrides``: derived and checked, nothing read but a leverage CSV not in ``csv`` (the CSVs
    read so far, path -> rows: read once, kept there)."""
    csv = {} if csv is None else csv
    table = overridden(read, overrides)
    if isinstance(table.get("geometry"), dict):  # a geometry chart: the frame's geometry derived from it
        table = merge(table, {"bike": _chart.frame_keys(table["geometry"])})
        seated = _chart.seated_com(table["geometry"], table.get("rider", {}).get("seated_com_from_saddle_mm"))
        if seated is not None:
            table = merge(table, {"rider": {"seated_com_mm": seated}})
    from mtbmj.bike import keys as keys_mod
    from mtbmj.config import warn

    metres = keys_mod.metres_for_millimetres(table)  # before the hardpoints are solved in the wrong unit
    if metres is not None:
        raise ConfigError(metres)
    derived, hardpoints, caliper, link, curves = (), table.get("linkage"), None, None, None
    if "linkage" in table:  # a rear end from hardpoints: its pivot and leverage table derived from it
        table, caliper, link, curves = _with_linkage(table)
        derived = ("pivot_mm",)  # a four-bar's instant centre may lie anywhere: not a key the user typed
    for section, value in table.items():
        if section not in KNOWN:
            raise ConfigError(f"{section}: unknown section or key (known: {', '.join(k for k in KNOWN)})")
        keys = KNOWN[section]
        if keys is None:
            continue
        if not isinstance(value, dict):
            raise ConfigError(f"{section}: must be a table")
        for key in value:
            if f"{section}.{key}" in RETIRED:
                raise ConfigError(f"{section}.{key}: no longer read: {RETIRED[f'{section}.{key}']}")
            if key not in keys:
                raise ConfigError(f"{section}.{key}: unknown key (known: {', '.join(sorted(keys))})")
    head = _number(table, "bike", "head_angle_deg")
    if not 45.0 <= head <= 90.0:
        raise ConfigError(f"bike.head_angle_deg: must be within 45-90 degrees from the horizontal, got {head:g}")
    masses = {}
    for key in ("frame_mass_kg", "swingarm_mass_kg", "fork_lower_mass_kg", "front_wheel_mass_kg", "rear_wheel_mass_kg"):
        masses[key] = _number(table, "bike", key, positive=True)
    inertias = {k: _number(table, "bike", k, positive=True)
                for k in ("frame_inertia_kg_m2", "swingarm_inertia_kg_m2", "wheel_inertia_kg_m2")}
    offset = _number(table, "bike", "fork_offset_mm", nonneg=True) * MM
    front, rear, pivot = (_point(table, "bike", k) for k in ("front_axle_mm", "rear_axle_mm", "pivot_mm"))
    lev, named = table.get("leverage", {}), None  # named: the CSV the curve is read from, in messages
    if "csv" in lev:
        if "wheel_travel_mm" in lev or "ratio" in lev:
            raise ConfigError("leverage.csv: give the curve as a CSV or as wheel_travel_mm and ratio, not both")
        named = f"leverage.csv ({lev['csv']})"
        if not (isinstance(lev["csv"], str) and lev["csv"] in csv):  # a CSV is read once (a path: else refused)
            csv[lev["csv"]] = read_leverage_csv(lev["csv"])
        lev = dict(zip(("wheel_travel_mm", "ratio"), (list(v) for v in csv[lev["csv"]])))

    def label(key: str) -> str:  # a leverage key, or the CSV's column that stands for it
        return f"{named}: {key.split('.', 1)[1]}" if named else key

    if named:  # the lists typed in the file are checked so by the one warning of every key (keys.warnings)
        warn([m.replace(f"{k} = ", f"{label(k)} ", 1).replace("(of the list)", "(a row of the CSV)")
              for m in keys_mod.warnings({"leverage": lev}) for k in ("leverage.ratio", "leverage.wheel_travel_mm")
              if m.startswith(f"{k} = ")])
    w, r = lev.get("wheel_travel_mm"), lev.get("ratio")
    for key, arr in (("leverage.wheel_travel_mm", w), ("leverage.ratio", r)):
        if (not isinstance(arr, list) or len(arr) < 2
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in arr)):
            raise ConfigError(f"{key}: must be a list of at least 2 numbers")
    if len(w) != len(r):
        raise ConfigError(f"leverage.ratio: {len(r)} values for {len(w)} wheel travels in leverage.wheel_travel_mm")
    if w[0] != 0.0:
        raise ConfigError(f"{label('leverage.wheel_travel_mm')}: must start at 0 mm, got {w[0]:g}")
    back = next(((i, a, b) for i, (a, b) in enumerate(zip(w, w[1:]), 2) if b <= a), None)
    if back is not None:  # the value at fault named, its place counted as a list's and a CSV's rows are
        raise ConfigError(f"{label('leverage.wheel_travel_mm')}: must increase strictly (the shock stroke must be "
                          f"monotonic in the wheel travel): value {back[0]}, {back[2]:g} mm, follows {back[1]:g} mm")
    if any(x <= 0.0 for x in r):
        raise ConfigError(f"{label('leverage.ratio')}: every leverage ratio must be > 0")
    leverage = Leverage(tuple(x * MM for x in w), tuple(float(x) for x in r))
    stroke = _number(table, "shock", "stroke_mm", positive=True) * MM
    if isinstance(table.get("geometry"), dict):
        _chart.check_rear_travel(table["geometry"], leverage, stroke)
    if leverage.full_stroke > stroke * (1.0 + STROKE_TOLERANCE):
        raise ConfigError(f"shock.stroke_mm: {stroke / MM:g} mm is shorter than the leverage curve needs over "
                          f"{leverage.full_travel / MM:g} mm of wheel travel ({leverage.full_stroke / MM:.2f} mm)")
    if stroke - leverage.full_stroke > STROKE_GAP_M:
        warn([f"leverage: the table covers {leverage.full_stroke / MM:.2f} mm of the shock's {stroke / MM:g} mm stroke "
              f"(shock.stroke_mm); past its end ({leverage.full_travel / MM:g} mm of wheel travel) the last ratio is "
              f"carried on, and a run that goes there says so"])
    whole = _number(table, "rider", "mass_kg", positive=True)  # the whole rider
    share = table.get("rider", {}).get("limbs_share_percent", LIMBS_SHARE_PERCENT)
    if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0.0 <= share < 50.0:
        raise ConfigError(f"rider.limbs_share_percent: must be a number within 0-50 %, got {share!r}")
    on_bike = whole * share / 100.0
    rider_mass = whole - on_bike
    pedals = _point(table, "rider", "pedals_mm")
    bars = _point(table, "rider", "bars_mm")
    com = _point(table, "rider", "com_mm")
    if not pedals[0] < com[0] < bars[0]:
        raise ConfigError("rider.com_mm: the rider's centre of mass must lie between the pedals and the bars in x "
                          "(the legs and arms carry it)")
    rider = Rider(rider_mass, on_bike, com, _number(table, "rider", "pitch_inertia_kg_m2", positive=True),
                  pedals[0], bars[0], pedals[1], bars[1],
                  _number(table, "rider", "leg_length_mm", positive=True) * MM,
                  _number(table, "rider", "arm_length_mm", positive=True) * MM,
                  _number(table, "rider", "leg_stiffness_N_per_mm", positive=True) * 1e3,
                  _number(table, "rider", "leg_damping_N_s_per_m", nonneg=True),
                  _number(table, "rider", "arm_stiffness_N_per_mm", positive=True) * 1e3,
                  _number(table, "rider", "arm_damping_N_s_per_m", nonneg=True),
                  _point(table, "rider", "seated_com_mm") if "seated_com_mm" in table.get("rider", {}) else None,
                  _number(table, "rider", "height_m", positive=True) if "height_m" in table.get("rider", {}) else 1.78)
    limits.within("rider.height_m", rider.height, limits.RIDER_HEIGHT_M, "m")
    for section in ("fork", "shock"):
        cfg = table.get(section, {}).get("config", "reference")
        if not isinstance(cfg, str):
            raise ConfigError(f"{section}.config: must be a preset name or a TOML file")
        given = table.get(section, {}).get("set", {})
        if not isinstance(given, dict):
            raise ConfigError(f"{section}.set: must be a table of configuration keys")
        for key in given:
            if not reads_key(section, str(key)):
                raise ConfigError(f"{section}.set: {key!r} is not used by the bike (of the {section}'s configuration "
                                  f"it reads {', '.join(USED[section])}){_set_hint(section, str(key))}")
    drive = {}
    for key in ("push_N", "power_W", "brake_N", "traction"):
        if key in table.get("drive", {}):
            drive[key] = _number(table, "drive", key, nonneg=True)
    through = table.get("drive", {}).get("chain", True)
    if not isinstance(through, bool):
        raise ConfigError(f"drive.chain: must be true (the drive pulls the chain) or false (a hub drive), got "
                          f"{through!r}")
    teeth = [k for k in ("chainring_teeth", "cog_teeth") if k in table.get("drive", {})] if through else []
    if teeth:  # the drive through the chain (controllers.drive.chain_pull)
        if len(teeth) == 1:
            other = "cog_teeth" if teeth[0] == "chainring_teeth" else "chainring_teeth"
            raise ConfigError(f"drive.{other}: needed with drive.{teeth[0]} (the chain runs from the chainring to the "
                              f"cog)")
        for key, (low, high) in (("chainring_teeth", (20, 60)), ("cog_teeth", (9, 60))):
            n = table["drive"][key]
            if isinstance(n, bool) or not isinstance(n, int) or not low <= n <= high:
                raise ConfigError(f"drive.{key}: must be a whole number of teeth within {low}-{high}, got {n!r}")
        drive["teeth"] = (int(table["drive"]["chainring_teeth"]), int(table["drive"]["cog_teeth"]))
        drive["chain_m"] = (_linkage.sprocket_radius(table["drive"]["chainring_teeth"]),
                            _linkage.sprocket_radius(table["drive"]["cog_teeth"]))
    warn(keys_mod.warnings({**table, "bike": {k: v for k, v in table["bike"].items() if k not in derived},
                            **({"linkage": hardpoints} if isinstance(hardpoints, dict) else {})}))
    spec = BikeSpec(
        name=source if source in preset_names() else Path(source).stem,
        head_angle=math.radians(head) + level_pitch(front, rear),
        fork_offset=offset, front_axle=front, rear_axle=rear, pivot=pivot,
        frame_mass=masses["frame_mass_kg"], frame_com=_point(table, "bike", "frame_com_mm"),
        frame_inertia=inertias["frame_inertia_kg_m2"], swingarm_mass=masses["swingarm_mass_kg"],
        swingarm_inertia=inertias["swingarm_inertia_kg_m2"], fork_lower_mass=masses["fork_lower_mass_kg"],
        front_wheel_mass=masses["front_wheel_mass_kg"], rear_wheel_mass=masses["rear_wheel_mass_kg"],
        wheel_inertia=inertias["wheel_inertia_kg_m2"], leverage=leverage, shock_stroke=stroke, rider=rider,
        fork_config=table.get("fork", {}).get("config", "reference"), fork_overrides=dict(table.get("fork", {}).get("set", {})),
        shock_config=table.get("shock", {}).get("config", "reference"),
        shock_overrides=dict(table.get("shock", {}).get("set", {})), drive=drive, source=source,
        overrides=dict(overrides or {}),
        virtual_pivot=isinstance(hardpoints, dict) and hardpoints.get("kind") in ("horst_link", "short_link"),
        caliper_ratio=caliper,
        sensors=_sensors(table), shock_sold=_shock.written(table.get("shock", {})))
    return ResolvedBike(source, read, dict(overrides or {}), table, spec, link, curves, csv)


def level_pitch(front_axle, rear_axle) -> float:
    """How far (rad, nose up) the frame's x axis is turned from the horizontal when both wheels (of
    one size) stand on flat ground at full extension: the axles level. ``bike.head_angle_deg`` is a
    geometry chart's head angle, measured so; in frame coordinates the steering axis lies this much
    steeper (axles 20 mm apart in height over a 1255 mm wheelbase: 0.91 deg; a chart gives level axles)."""
    (fx, fz), (rx, rz) = front_axle, rear_axle
    return math.atan2(rz - fz, fx - rx)


def check_geometry(spec: BikeSpec, tire_radius: float) -> None:
    """Cross-checks that need the tire: the main pivot outside the rear wheel, the swingarm able to
    reach the full wheel travel."""
    ls = spec.swingarm_length
    if ls <= tire_radius and not spec.virtual_pivot:  # a four-bar's circle may have a short radius
        raise ConfigError(f"bike.pivot_mm: the main pivot lies inside the rear wheel ({ls / MM:.0f} mm from the axle, "
                          f"tire radius {tire_radius / MM:.0f} mm)")
    beta = spec.swingarm_angle
    if spec.leverage.full_travel >= ls * (1.0 + math.sin(beta)) * 0.99:
        raise ConfigError(f"leverage.wheel_travel_mm: {spec.leverage.full_travel / MM:g} mm of wheel travel is more "
                          f"than the swingarm ({ls / MM:.0f} mm) can give")
    front_gap = math.hypot(spec.front_axle[0] - spec.pivot[0], spec.front_axle[1] - spec.pivot[1])
    if front_gap <= tire_radius and not spec.virtual_pivot:  # an instant centre may lie anywhere
        raise ConfigError("bike.pivot_mm: the main pivot lies inside the front wheel")


def rear_axle_in_frame(spec: BikeSpec, phi) -> tuple[np.ndarray, np.ndarray]:
    """(x, z) of the rear axle in the frame's coordinates (m) at swingarm angles ``phi`` (rad, rear
    wheel up positive): the axle turned about the main pivot. Its rise, z less the axle's z at
    ``phi`` = 0, is the rear wheel's travel."""
    phi = np.asarray(phi, dtype=float)
    (px, pz), (rx, rz) = spec.pivot, spec.rear_axle
    rho = (rx - px, rz - pz)
    return (px + np.cos(phi) * rho[0] + np.sin(phi) * rho[1],
            pz - np.sin(phi) * rho[0] + np.cos(phi) * rho[1])


def ride_decoding(bike) -> dict:
    """How a ride recorded on ``bike`` (a loaded ``BikeSpec``) is read (``mtbmj.measured.telemetry``'s
    read_sst / read_ride keywords): its fork travel and shock stroke, its leverage curve, and its
    recorder's sensors (``[sensors]``; where absent, the reader's defaults, the SST example's)."""
    from mtbmj.config import load as load_config
    from mtbmj.measured import telemetry

    fork_travel_mm = load_config(bike.fork_config, bike.fork_overrides or None).require("fork.travel_mm")
    out = {"fork_max_mm": float(fork_travel_mm), "shock_max_mm": bike.shock_stroke * 1e3,
           "leverage": bike.leverage}  # the one leverage class: the bike's curve decodes the ride as it is
    sensors = bike.sensors
    if "fork_arm_mm" in sensors:
        out["front"] = telemetry.IsoscelesTriangle(sensors["fork_arm_mm"], sensors["fork_max_mm"])
    if "shock_arm1_mm" in sensors:
        out["rear"] = telemetry.Triangle(sensors["shock_arm1_mm"], sensors["shock_arm2_mm"], sensors["shock_max_mm"])
    return out


__all__ = ["BikeSpec", "Leverage", "ResolvedBike", "Rider", "derive", "ride_decoding", "load", "resolve", "preset_names", "check_geometry", "level_pitch", "leverage_ratio", "leverage_stroke",
           "stroke_piece", "rear_axle_in_frame"]

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

import bisect
import copy
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np


from mtbmj import limits
from mtbmj.bike import chart as _chart
from mtbmj.bike import linkage as _linkage
from mtbmj.bike import shock as _shock
from mtbmj.errors import ConfigError

MM = 1e-3


@dataclass(frozen=True)
class Leverage:
    """Leverage ratio LR = d(rear wheel travel) / d(shock stroke), piecewise linear in the rear
    wheel travel ``travel`` (m, from 0, strictly increasing); constant past the table's ends.
    The shock stroke is s(w) = integral from 0 to w of dw / LR(w), exact on each linear piece."""

    travel: tuple[float, ...]
    ratio: tuple[float, ...]

    def __post_init__(self):
        w, r = [float(x) for x in self.travel], [float(x) for x in self.ratio]
        s = [0.0]
        for i in range(len(w) - 1):  # the stroke at each table point, exact for a ratio linear in w
            s.append(s[-1] + stroke_piece(r[i], r[i + 1], w[i + 1] - w[i], w[i + 1] - w[i]))
        # plain lists: the callback asks for one value at a time, where bisect beats numpy
        object.__setattr__(self, "_w", w)
        object.__setattr__(self, "_r", r)
        object.__setattr__(self, "_s", s)

    def ratio_at(self, w: float) -> float:
        """LR at rear wheel travel ``w`` (m)."""
        return leverage_ratio(self._w, self._r, bisect.bisect_right(self._w, w) - 1, w)

    def stroke(self, w: float) -> float:
        """Shock stroke (m) at rear wheel travel ``w`` (m); below 0 and past the table the ratio
        is held at its end value."""
        return leverage_stroke(self._w, self._r, self._s, bisect.bisect_right(self._w, w) - 1, w)

    def strokes(self, w) -> np.ndarray:
        """``stroke`` over an array of rear wheel travels (m): the same pieces, in numpy."""
        w = np.asarray(w, dtype=float)
        w_tab, r, s = (np.asarray(v, dtype=float) for v in (self._w, self._r, self._s))
        n = w_tab.size
        i = np.clip(np.searchsorted(w_tab, w, side="right") - 1, 0, n - 2)
        r0, r1, h, x = r[i], r[i + 1], w_tab[i + 1] - w_tab[i], w - w_tab[i]
        b = (r1 - r0) / h
        linear = np.abs(b) * x < 1e-9 * r0
        with np.errstate(divide="ignore", invalid="ignore"):  # the linear pieces' log is not used
            piece = np.where(linear, x / r0, np.log((r0 + b * x) / r0) / np.where(linear, 1.0, b))
        out = s[i] + piece
        out = np.where(w <= 0.0, w / r[0], out)
        return np.where(w >= w_tab[n - 1], s[n - 1] + (w - w_tab[n - 1]) / r[n - 1], out)

    @property
    def table(self) -> tuple[list[float], list[float], list[float]]:
        """(travel, ratio, stroke) at the table's points (m, -, m): the lookups' arguments."""
        return self._w, self._r, self._s

    def travel_at_stroke(self, stroke: float) -> float:
        """The rear wheel travel (m) at shock ``stroke`` (m): ``stroke``'s inverse, the ratio held at
        the table's ends beyond them."""
        w, r, s = self._w, self._r, self._s
        if stroke <= 0.0:
            return stroke * r[0]
        if stroke >= s[-1]:
            return w[-1] + (stroke - s[-1]) * r[-1]
        i = bisect.bisect_right(s, stroke) - 1
        b, ds = (r[i + 1] - r[i]) / (w[i + 1] - w[i]), stroke - s[i]
        return w[i] + (ds * r[i] if abs(b) * ds < 1e-12 else r[i] * math.expm1(b * ds) / b)

    @property
    def full_travel(self) -> float:
        return float(self._w[-1])

    @property
    def full_stroke(self) -> float:
        return float(self._s[-1])


def stroke_piece(r0: float, r1: float, h: float, x: float) -> float:
    """Integral from 0 to x of du / (r0 + (r1 - r0) u / h)."""
    b = (r1 - r0) / h
    if abs(b) * x < 1e-9 * r0:
        return x / r0
    return math.log((r0 + b * x) / r0) / b


# The leverage curve's lookups as plain functions of the table (travel w_tab, ratio r, stroke s at
# each point) and the piece i = bisect_right(w_tab, w) - 1 holding w: ``Leverage`` calls them on
# its lists, the compiled bike callback (``mtbmj.bike.callback_compiled``) compiles these same
# functions and finds i by its own bisection.
def leverage_ratio(w_tab, r, i, w: float) -> float:
    """LR at rear wheel travel ``w`` (m); constant past the table's ends."""
    n = len(w_tab)
    if w <= w_tab[0]:
        return r[0]
    if w >= w_tab[n - 1]:
        return r[n - 1]
    return r[i] + (r[i + 1] - r[i]) * (w - w_tab[i]) / (w_tab[i + 1] - w_tab[i])


def leverage_stroke(w_tab, r, s, i, w: float) -> float:
    """Shock stroke (m) at rear wheel travel ``w`` (m), the ratio held at its end values outside
    the table."""
    n = len(w_tab)
    if w <= 0.0:
        return w / r[0]
    if w >= w_tab[n - 1]:
        return s[n - 1] + (w - w_tab[n - 1]) / r[n - 1]
    return s[i] + stroke_piece(r[i], r[i + 1], w_tab[i + 1] - w_tab[i], w - w_tab[i])


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


def preset_names() -> list[str]:
    return sorted(p.name[:-5] for p in resources.files("mtbmj.bike.presets").iterdir() if p.name.endswith(".toml"))


def _locate(ref: str):
    for name in preset_names():
        if ref.lower() == name.lower():
            return name, resources.files("mtbmj.bike.presets") / f"{name}.toml"
    path = Path(ref)
    if not path.exists():
        raise ConfigError(f"{ref}: not a bike preset (known: {', '.join(preset_names())}) and no such file")
    return path.stem, path


def _is_preset(name: str) -> bool:
    return any(name.lower() == n.lower() for n in preset_names())


def read_leverage_csv(path) -> tuple[list[float], list[float]]:
    """(wheel travel mm, leverage ratio) of a leverage-ratio CSV as linkage tools and telemetry apps
    export it: two numbers a row, wheel travel first, separated by a comma, a semicolon or a tab
    (Sufni's "0.0,3.18"; Linkage's "0;3.18"); header lines before the first number row are skipped."""
    import re

    from mtbmj.textfile import read_text

    if not isinstance(path, str):
        raise ConfigError(f"leverage.csv: must be a file's path, got {path!r}")
    # the one reader of a user's files: a FIFO, a device or a directory refused without waiting, a
    # file over 1 MiB (60 000 rows; a tool's export every 0.1 mm of 260 mm is 2 600) before it is read
    text = read_text(Path(path), ConfigError, f"leverage.csv: {path}", "not a text file (wheel travel and leverage "
                     "ratio, two numbers a row)", "config")
    w, r = [], []
    for number, line in enumerate(text.splitlines(), 1):
        cells = [c.strip() for c in re.split(r"[,;\t]", line) if c.strip()]
        if not cells:
            continue
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not w:
                continue  # a header
            raise ConfigError(f"{path}, line {number}: not two numbers ({line.strip()!r})") from None
        if len(values) != 2 or not all(math.isfinite(v) for v in values):
            raise ConfigError(f"{path}, line {number}: expected wheel travel and leverage ratio, got {line.strip()!r}")
        w.append(values[0])
        r.append(values[1])
    if len(w) < 2:
        raise ConfigError(f"leverage.csv: {path} holds {len(w)} row(s) of wheel travel and leverage ratio (at least 2)")
    return w, r


def _chart_over_bases(table: dict, part: dict, location) -> tuple[dict, dict]:
    """One file's geometry chart over its bases' ``table`` (``read_table``): the chart replaces
    the axles and head angle its bases gave (and their chart), its fork keys are set in the file's
    ``[fork.set]`` as if written there, and its saddle replaces their seated rider. A file whose own
    ``rider.seated_com_mm`` follows a chart with a saddle replaces that saddle; a chart without a
    saddle after one with a saddle keeps the seated rider the old saddle gave."""
    geo, bike, rider = part.get("geometry"), part.get("bike") or {}, part.get("rider") or {}
    old = table.get("geometry") if isinstance(table.get("geometry"), dict) else {}
    old_saddle = _chart.saddle(old)
    part = dict(part)

    def keep_old_seat(table: dict) -> None:  # the bases' saddle placed the seated rider: it stays there
        if old_saddle is not None and "seated_com_mm" not in rider:
            from_saddle = {**(table.get("rider") or {}), **rider}.get("seated_com_from_saddle_mm")
            table.setdefault("rider", {})["seated_com_mm"] = _chart.seated_com(old, from_saddle)

    if isinstance(geo, dict):
        _chart.check_keys(geo)
        given = [k for k in _chart.SETS if k in bike]
        if given:
            raise ConfigError(f"{location}: bike.{given[0]} and [geometry] give the frame's geometry two ways; give one")
        fork = _chart.fork_keys(geo)
        mine = part.get("fork", {}).get("set", {}) if isinstance(part.get("fork"), dict) else {}
        mine = mine if isinstance(mine, dict) else {}
        both = [k for k in fork if k in mine]
        if both:
            chart_key = next(k for k, v in _chart.FORK.items() if v == both[0])
            raise ConfigError(f"{location}: geometry.{chart_key} and [fork.set] {both[0]!r} give it two ways; give one")
        if fork:
            part["fork"] = {**(part.get("fork") or {}), "set": {**mine, **fork}}
        new_saddle = _chart.saddle(geo)
        if new_saddle is not None and "seated_com_mm" in rider:
            raise ConfigError(f"{location}: rider.seated_com_mm and the chart's saddle (geometry.seat_tube_angle_deg) "
                              f"give the seated rider two ways; give one")
        if isinstance(table.get("bike"), dict):
            table["bike"] = {k: v for k, v in table["bike"].items() if k not in _chart.SETS}
        if new_saddle is None:
            keep_old_seat(table)
        elif isinstance(table.get("rider"), dict):  # this chart's saddle places the seated rider
            table["rider"] = {k: v for k, v in table["rider"].items() if k != "seated_com_mm"}
        table.pop("geometry", None)
    elif old and ("linkage" in part or [k for k in _chart.SETS if k in bike]):
        # axles or hardpoints over a base's chart: the chart becomes the axles it gave, then these replace them
        table = _merge(table, {"bike": _chart.frame_keys(old)})
        keep_old_seat(table)
        table.pop("geometry")
    else:
        if old_saddle is not None and "seated_com_mm" in rider:  # the file's own seated rider wins
            table["geometry"] = old = {k: v for k, v in old.items() if k not in _chart.SEAT}
        shock = part.get("shock") if isinstance(part.get("shock"), dict) else {}
        if "rear_travel_mm" in old and ("leverage" in part or "stroke_mm" in shock):
            # the base chart's rear travel described the base's rear end, not this one
            table["geometry"] = {k: v for k, v in old.items() if k != "rear_travel_mm"}
    return table, part


def read_table(ref: str) -> tuple[dict, str]:
    """A bike file's table with its ``base`` chain merged in (read by ``mtbmj.config.read_chain``,
    the drop configurations' reader: the same base rules)."""
    from mtbmj.config import read_chain

    table: dict = {}
    for _, location, part in read_chain(ref, _locate, _is_preset, "a bike description"):
        part = gated(part, location)  # every number through the numeric-input gate before any is used
        lev = part.get("leverage")
        if isinstance(lev, dict):
            if isinstance(lev.get("csv"), str) and isinstance(location, Path):
                lev["csv"] = str((location.resolve().parent / lev["csv"]))  # relative to the file that names it
            # a curve replaces its bases' curve, given as a CSV or as the two lists
            if isinstance(table.get("leverage"), dict):
                drop = ("wheel_travel_mm", "ratio") if "csv" in lev else ("csv",) if lev.keys() & {"wheel_travel_mm", "ratio"} else ()
                table["leverage"] = {k: v for k, v in table["leverage"].items() if k not in drop}
        table, part = _chart_over_bases(table, part, location)
        if isinstance(part.get("linkage"), dict):  # hardpoints replace the rear end its bases gave
            if "leverage" in part or "pivot_mm" in (part.get("bike") or {}):
                raise ConfigError(f"{location}: [linkage] and {'[leverage]' if 'leverage' in part else 'bike.pivot_mm'} "
                                  f"give the rear end two ways; give one (the linkage's pivot and leverage ratio "
                                  f"follow from its points)")
            table.pop("leverage", None)
            table.pop("linkage", None)
            if isinstance(table.get("bike"), dict):
                table["bike"] = {k: v for k, v in table["bike"].items() if k not in ("pivot_mm", "rear_axle_mm")}
        elif "leverage" in part or "pivot_mm" in (part.get("bike") or {}):
            table.pop("linkage", None)  # a table or a pivot replaces the hardpoints its bases gave
        table = _merge(table, part)
        mine = part.get("shock")
        if isinstance(mine, dict) and mine.keys() & set(_shock.KEYS):  # a shock as sold: its keys set this
            # file's [shock.set] over its bases' (mtbmj.bike.shock), so a later file's [shock.set] wins
            table["shock"]["set"] = _shock.schema_keys(mine, table["shock"].get("set", {}), table["shock"].get("spring"))
    return table, str(ref)


# A telemetry recorder's sensors on this bike (Sufni's AS5600 angle sensors): the fork's isosceles
# triangle (two equal arms, the stroke as its base) and the shock's triangle (two arms, the shock's
# eye-to-eye as the third side), in mm, as its setup record gives them (``mtbmj telemetry --bike``)
SENSOR_KEYS = ("fork_arm_mm", "fork_max_mm", "shock_arm1_mm", "shock_arm2_mm", "shock_max_mm")


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


def _with_linkage(table: dict) -> tuple[dict, tuple | None]:
    """``table`` with ``bike.pivot_mm`` and ``[leverage]`` from its ``[linkage]`` (``mtbmj.bike.linkage``),
    and the rear caliper's link's turn against the arm's at each point of that table (None where
    the caliper rides on the arm):
    the pivot the rear axle turns about (for a four-bar whose axle rides on its coupler, the centre of
    the circle that best fits the linkage's axle path, ``linkage.fitted_pivot``, with a warning when
    it leaves the path by more than 0.1 mm) and the leverage ratio every millimetre of wheel travel
    up to the shock's stroke."""
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
    return out, (tuple(float(x) for x in ratio) if np.max(np.abs(ratio - 1.0)) > 1e-9 else None)


def _merge(a: dict, b: dict) -> dict:
    out = dict(a)
    for k, v in b.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


KNOWN = {
    "description": None, "reading": None,
    "bike": {"head_angle_deg", "fork_offset_mm", "front_axle_mm", "rear_axle_mm", "pivot_mm", "frame_mass_kg",
             "frame_com_mm", "frame_inertia_kg_m2", "swingarm_mass_kg", "swingarm_inertia_kg_m2",
             "fork_lower_mass_kg", "front_wheel_mass_kg", "rear_wheel_mass_kg", "wheel_inertia_kg_m2"},
    "leverage": {"wheel_travel_mm", "ratio", "csv"},
    "linkage": _linkage.known_keys(),
    "shock": {"stroke_mm", "config", "set", *_shock.KEYS},
    "fork": {"config", "set"},
    "rider": {"mass_kg", "limbs_share_percent", "com_mm", "pitch_inertia_kg_m2", "pedals_mm", "bars_mm",
              "seated_com_mm", "seated_com_from_saddle_mm", "height_m", "leg_length_mm", "arm_length_mm", "leg_stiffness_N_per_mm", "leg_damping_N_s_per_m",
              "arm_stiffness_N_per_mm", "arm_damping_N_s_per_m"},
    "drive": {"push_N", "power_W", "brake_N", "traction", "chainring_teeth", "cog_teeth", "chain"},
    "sensors": set(SENSOR_KEYS),
    "geometry": set(_chart.KEYS),
}


def _number(table: dict, section: str, key: str, positive: bool = False, nonneg: bool = False) -> float:
    full = f"{section}.{key}"
    if key not in table.get(section, {}):
        raise ConfigError(f"{full}: missing")
    v = limits.number(full, table[section][key], "a finite number")
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


# The keys of the fork's and the shock's configurations the bike reads: the fork's laws, tire,
# gravity and integrator; the shock's laws (the fork schema read in shock coordinates; its length,
# tire, sled and solver keys have no part in the bike). A key set in [fork.set] or [shock.set]
# outside these changed nothing and is refused.
USED = {"fork": ("fork.*", "tire.*", "sled.gravity_m_per_s2", "solver.integrator"),
        "shock": ("fork.* but fork.length_mm",)}


def _used(section: str, key: str) -> bool:
    if section == "fork":
        return key.startswith(("fork.", "tire.")) or key in ("sled.gravity_m_per_s2", "solver.integrator")
    return key.startswith("fork.") and key != "fork.length_mm"


def gated(table: dict, location=None) -> dict:
    """``table`` (a bike file's, or overrides by key) with every number in it passed through the
    numeric-input gate (``mtbmj.limits.numbers_in``): a value that is NaN, infinite, an integer too
    large for a float or beyond ``limits.MAX_MAGNITUDE`` is refused in one line naming its key
    (and the file), before any key is converted or used. The plausible ranges are warned about
    when the bike is loaded (``mtbmj.bike.keys.warnings``)."""
    try:
        return {key: limits.numbers_in(str(key), value) for key, value in table.items()}
    except ConfigError as exc:
        raise ConfigError(f"{location}: {exc}" if isinstance(location, Path) else str(exc)) from None


def overridden(table: dict, overrides) -> dict:
    """``table`` with ``overrides`` applied: ``"section.key": value`` for a bike key (``rider.mass_kg``),
    ``"fork.set": {KEY: value}`` / ``"shock.set": {KEY: value}`` for keys of the fork's and the
    shock's configurations (merged into the file's). Unknown keys are refused by ``load``. ``table``
    itself is left as it was (its nested tables too)."""
    out = copy.deepcopy(table)
    for key, value in gated(dict(overrides or {})).items():
        if key in ("fork.set", "shock.set"):
            if not isinstance(value, dict):
                raise ConfigError(f"{key}: overrides must be a table of configuration keys")
            section = out.setdefault(key.split(".")[0], {})
            if not isinstance(section, dict):
                raise ConfigError(f"{key.split('.')[0]}: must be a table")
            section["set"] = {**section.get("set", {}), **value}
            continue
        section, dot, name = str(key).partition(".")
        if not dot or not name:
            raise ConfigError(f"--set {key}: a bike key is SECTION.KEY (e.g. rider.mass_kg; known sections: "
                              f"{', '.join(k for k, v in KNOWN.items() if v)})")
        if section not in KNOWN or not KNOWN[section]:
            raise ConfigError(f"--set {key}: unknown section {section!r} (known: "
                              f"{', '.join(k for k, v in KNOWN.items() if v)})")
        if name not in KNOWN[section] or name == "set":
            raise ConfigError(f"--set {key}: unknown key (known in [{section}]: "
                              f"{', '.join(sorted(k for k in KNOWN[section] if k != 'set'))})")
        if section == "bike" and name in _chart.SETS and isinstance(out.get("geometry"), dict):
            raise ConfigError(f"--set {key}: this bike's frame is given by its geometry chart; set the chart's keys "
                              f"(geometry.{'head_angle_deg' if name == 'head_angle_deg' else 'wheelbase_mm'}, ...)")
        if section == "geometry" and not isinstance(out.get("geometry"), dict):  # a bike given by its axles
            if name not in _chart.FORK:
                raise ConfigError(f"--set {key}: this bike's frame is given by its axles (bike.front_axle_mm, "
                                  f"bike.rear_axle_mm, bike.head_angle_deg), not a geometry chart; set those")
            out.setdefault("fork", {}).setdefault("set", {}).update(_chart.fork_keys({name: value}))
            continue
        out.setdefault(section, {})[name] = value
        if (section == "geometry" and name in _chart.FRAME
                and not any(str(k).partition(".")[2] in _chart.CHECK for k in overrides)):
            # the chart's reach and stack checked the chart as published: a changed frame drops them
            out["geometry"] = {k: v for k, v in out["geometry"].items() if k not in _chart.CHECK}
        if section == "geometry" and name in _chart.FORK:  # a chart's fork key sets the fork's, as in a file
            out.setdefault("fork", {}).setdefault("set", {}).update(_chart.fork_keys({name: value}))
        if section == "geometry" and name in _chart.SEAT and isinstance(out.get("rider"), dict):
            out["rider"] = {k: v for k, v in out["rider"].items() if k != "seated_com_mm"}  # the saddle places it
        if (section, name) == ("rider", "seated_com_mm") and isinstance(out.get("geometry"), dict):
            out["geometry"] = {k: v for k, v in out["geometry"].items() if k not in _chart.SEAT}
        if section == "shock" and name in _shock.KEYS:  # a shock's key as sold sets its [shock.set] now
            sh = out["shock"]
            sh["set"] = _shock.schema_keys({name: value}, sh.get("set", {}), sh.get("spring"))
    return out


def load(ref: str, overrides=None) -> BikeSpec:
    """A ``BikeSpec`` from a bike preset name (``preset_names()``) or a TOML path, checked, with
    ``overrides`` applied (:func:`overridden`)."""
    table, source = read_table(str(ref))
    table = overridden(table, overrides)
    if isinstance(table.get("geometry"), dict):  # a geometry chart: the frame's geometry derived from it
        table = _merge(table, {"bike": _chart.frame_keys(table["geometry"])})
        seated = _chart.seated_com(table["geometry"], table.get("rider", {}).get("seated_com_from_saddle_mm"))
        if seated is not None:
            table = _merge(table, {"rider": {"seated_com_mm": seated}})
    from mtbmj.bike import keys as keys_mod
    from mtbmj.config import warn

    metres = keys_mod.metres_for_millimetres(table)  # before the hardpoints are solved in the wrong unit
    if metres is not None:
        raise ConfigError(metres)
    derived, hardpoints, caliper = (), table.get("linkage"), None
    if "linkage" in table:  # a rear end from hardpoints: its pivot and leverage table derived from it
        table, caliper = _with_linkage(table)
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
        lev = dict(zip(("wheel_travel_mm", "ratio"), read_leverage_csv(lev["csv"])))

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
    if any(b <= a for a, b in zip(w, w[1:])):
        raise ConfigError(f"{label('leverage.wheel_travel_mm')}: must increase strictly (the shock stroke must be "
                          f"monotonic in the wheel travel)")
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
            if not _used(section, str(key)):
                raise ConfigError(f"{section}.set: {key!r} is not used by the bike (of the {section}'s configuration "
                                  f"it reads {', '.join(USED[section])})")
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
        sensors=_sensors(table))
    return spec


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


__all__ = ["BikeSpec", "Leverage", "Rider", "load", "preset_names", "check_geometry", "level_pitch", "leverage_ratio", "leverage_stroke",
           "stroke_piece", "rear_axle_in_frame"]

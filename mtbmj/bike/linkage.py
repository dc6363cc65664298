"""A bike's rear end from its hardpoints: a planar linkage solved for every rear wheel travel.

A ``[linkage]`` table in a bike file gives named points in frame coordinates (mm, origin the bottom
bracket, x forward, z up) at full extension, for one of four layouts:

* ``single_pivot``: the swingarm turns about ``main_pivot`` and carries ``rear_axle`` and the
  shock's end ``shock_swingarm``;
* ``linkage_driven_single_pivot`` (the SST ride's Commencal Clash): the swingarm turns about
  ``main_pivot`` and carries ``rear_axle`` and ``swingarm_link``; a link joins ``swingarm_link`` to
  ``rocker_link`` on a rocker that turns about ``rocker_pivot`` and carries the shock's end
  ``shock_rocker``;
* ``horst_link``: a chainstay turns about ``main_pivot`` to ``horst_pivot``; the seatstay joins
  ``horst_pivot`` to ``seatstay_rocker`` and carries ``rear_axle``; a rocker turns about
  ``rocker_pivot`` to ``seatstay_rocker`` and carries ``shock_rocker``;
* ``short_link`` (a short-link virtual pivot): a lower link turns about ``lower_pivot`` to
  ``lower_link``, an upper link about ``upper_pivot`` to ``upper_link`` and carries the shock's end
  ``shock_upper_link``; the rear triangle joins ``lower_link`` to ``upper_link`` and carries
  ``rear_axle``.

Every layout also has ``shock_frame``, the shock's end on the front triangle. The four-bars are one
mechanism: the frame (ground) with pivots A and D, an input link A-B turned by an angle, a coupler
B-C and an output link D-C; C is where the circles about B and D (the coupler's and the output
link's lengths) meet, on the branch the mechanism starts on. Each link's other points ride with it
as a rigid body.

Definitions (each at a rear wheel travel w, the axle's rise in frame coordinates, as the bike's
leverage table counts it; the frame level; the ground a tyre radius below the rear axle):

* leverage ratio: dw/ds, s the shock's stroke (its eye-to-eye shortening from full extension);
* instant centre: the point the rear axle's link turns about relative to the frame (the main pivot
  of a single pivot; for a four-bar the intersection of its two frame links' lines);
* anti-squat (the common construction, e.g. Linkage's documentation and Cossalter, *Motorcycle
  Dynamics*, 2nd ed., 2006, sec. 6.4): the instant force centre is where the chain's upper run
  (the outer tangent of chainring and cog) meets the line from the rear axle to the instant centre;
  the line from the rear tyre's contact through it is taken to the front contact's x (the front
  axle's, at full extension); its height there over the centre of mass's height, in percent;
* anti-rise: the same with the line from the rear contact through the instant centre of the link
  carrying the brake caliper (``brake_on``);
* pedal kickback: the crank's rotation (degrees, positive backwards) as the wheel travels from full
  extension with the rear wheel held still relative to the frame: the chain's upper run, its
  straight span and its wrap on both sprockets, stays as long (chain wrap included).

Sprockets: pitch 12.7 mm, radius p / (2 sin(pi / N)) (the pitch circle). This module is the
kinematics alone; ``mtbmj.bike.rear_end`` solves a bike file's ``[linkage]`` with its tyre, front
axle and centre of mass, and writes what ``mtbmj linkage`` shows.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from mtbmj.errors import ConfigError

MM = 1e-3
CHAIN_PITCH_M = 12.7e-3
LAYOUTS = {
    "single_pivot": ("main_pivot", "rear_axle", "shock_swingarm", "shock_frame"),
    "linkage_driven_single_pivot": ("main_pivot", "rear_axle", "swingarm_link", "rocker_pivot", "rocker_link",
                                    "shock_rocker", "shock_frame"),
    "horst_link": ("main_pivot", "horst_pivot", "rear_axle", "rocker_pivot", "seatstay_rocker", "shock_rocker",
                   "shock_frame"),
    "short_link": ("lower_pivot", "lower_link", "upper_pivot", "upper_link", "rear_axle", "shock_upper_link",
                   "shock_frame"),
}
# the shock's eye on the rear end, per layout (the other is shock_frame)
SHOCK_END = {"single_pivot": "shock_swingarm", "linkage_driven_single_pivot": "shock_rocker",
             "horst_link": "shock_rocker", "short_link": "shock_upper_link"}
# the links a caliper can sit on, per layout (the first is the default)
BRAKE_LINKS = {
    "single_pivot": ("swingarm",),
    "linkage_driven_single_pivot": ("swingarm",),
    "horst_link": ("seatstay", "chainstay"),
    "short_link": ("rear_triangle",),
}
OTHER_KEYS = {"kind", "chainring_teeth", "cog_teeth", "brake_on", "com_height_mm"}
DEFAULT_CHAINRING, DEFAULT_COG = 32, 24  # assumed: a common 1x chainring and a middle cog


def sprocket_radius(teeth: int) -> float:
    """Pitch radius (m) of a sprocket of ``teeth`` teeth on a 1/2 in chain."""
    return CHAIN_PITCH_M / (2.0 * math.sin(math.pi / teeth))


def _rotate(v, a):
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _meet(p, u, q, v):
    """Where the line p + t u meets the line q + r v (None if parallel)."""
    den = _cross(u, v)
    if abs(den) < 1e-12 * math.hypot(*u) * math.hypot(*v):
        return None
    t = _cross(q - p, v) / den
    return p + t * u


@dataclass(frozen=True)
class Pose:
    """Every named point (m, frame coordinates) at one input angle, and the instant centres of the
    axle's link and of the caliper's link."""

    points: dict
    axle_centre: np.ndarray | None
    brake_centre: np.ndarray | None
    caliper_turn: float = 0.0  # rad: the turn from full extension of the link carrying the caliper


class Linkage:
    """A solved rear end: ``kind``, ``points`` (name -> (x, z) m at full extension)."""

    def __init__(self, kind: str, points: dict, chainring: int = DEFAULT_CHAINRING, cog: int = DEFAULT_COG,
                 brake_on: str | None = None):
        self.kind, self.chainring, self.cog = kind, int(chainring), int(cog)
        self.p0 = {k: np.asarray(v, float) for k, v in points.items()}
        self.brake_on = brake_on or BRAKE_LINKS[kind][0]
        if kind == "single_pivot":
            self.four_bar = None
            self.A = self.p0["main_pivot"]
            self.input_points = ("rear_axle", "shock_swingarm")
        else:
            names = {"linkage_driven_single_pivot": ("main_pivot", "swingarm_link", "rocker_link", "rocker_pivot"),
                     "horst_link": ("main_pivot", "horst_pivot", "seatstay_rocker", "rocker_pivot"),
                     "short_link": ("lower_pivot", "lower_link", "upper_link", "upper_pivot")}[kind]
            self.four_bar = names
            a, b, c, d = (self.p0[n] for n in names)
            self.A, self.D = a, d
            self.coupler = float(np.hypot(*(c - b)))
            self.output = float(np.hypot(*(c - d)))
            for what, length in (("coupler", self.coupler), ("output link", self.output),
                                 ("input link", float(np.hypot(*(b - a))))):
                if length < 1e-3:
                    raise ConfigError(f"linkage: the {what} is shorter than 1 mm ({', '.join(names)})")
            self.branch = 1.0 if _cross(c - b, d - b) >= 0.0 else -1.0  # which side of B-D the point C lies
            self.input_points = {"linkage_driven_single_pivot": ("rear_axle", "swingarm_link"),
                                 "horst_link": ("horst_pivot",), "short_link": ("lower_link",)}[kind]
        self.coupler_points = {"horst_link": ("rear_axle",), "short_link": ("rear_axle",)}.get(kind, ())
        self.output_points = {"linkage_driven_single_pivot": ("shock_rocker", "rocker_link"),
                              "horst_link": ("shock_rocker", "seatstay_rocker"),
                              "short_link": ("shock_upper_link", "upper_link")}.get(kind, ())
        self.length0 = float(np.hypot(*(self._shock_end(self.p0) - self.p0["shock_frame"])))

    def _shock_end(self, points) -> np.ndarray:
        return points[SHOCK_END[self.kind]]

    def pose(self, angle: float) -> Pose | None:
        """Every point with the input link turned by ``angle`` (rad, the sense that raises the
        axle counted by the caller); None where the four-bar cannot close."""
        p = dict(self.p0)
        for n in self.input_points:
            p[n] = self.A + _rotate(self.p0[n] - self.A, angle)
        if self.four_bar is None:
            return Pose(p, self.A.copy(), self.A.copy(), angle)
        a_name, b_name, c_name, d_name = self.four_bar
        b0, c0 = self.p0[b_name], self.p0[c_name]
        b = self.A + _rotate(b0 - self.A, angle)
        p[b_name] = b
        bd = self.D - b
        dist = float(np.hypot(*bd))
        r1, r2 = self.coupler, self.output
        if dist > r1 + r2 or dist < abs(r1 - r2) or dist < 1e-12:
            return None
        along = (r1 * r1 - r2 * r2 + dist * dist) / (2.0 * dist)
        h = math.sqrt(max(r1 * r1 - along * along, 0.0))
        e = bd / dist
        n = np.array([-e[1], e[0]])
        c = b + along * e - self.branch * h * n  # the branch the mechanism starts on
        p[c_name] = c
        turn_out = math.atan2(*(_rot_args(c0 - self.D, c - self.D)))
        for name in self.output_points:
            if name != c_name:
                p[name] = self.D + _rotate(self.p0[name] - self.D, turn_out)
        turn_c = math.atan2(*(_rot_args(c0 - b0, c - b)))
        for name in self.coupler_points:
            p[name] = b + _rotate(self.p0[name] - b0, turn_c)
        centre = _meet(self.A, b - self.A, self.D, c - self.D)
        axle_on_coupler = self.kind in ("horst_link", "short_link")
        axle_centre = centre if axle_on_coupler else self.A.copy()
        on_input = self.brake_on in ("swingarm", "chainstay")
        brake_centre = self.A.copy() if on_input else centre
        return Pose(p, axle_centre, brake_centre, angle if on_input else turn_c)

    def travel(self, angle: float) -> float:
        """The rear axle's rise (m) in frame coordinates at ``angle``."""
        pose = self.pose(angle)
        return math.nan if pose is None else float(pose.points["rear_axle"][1] - self.p0["rear_axle"][1])

    def stroke(self, angle: float) -> float:
        pose = self.pose(angle)
        if pose is None:
            return math.nan
        return self.length0 - float(np.hypot(*(self._shock_end(pose.points) - pose.points["shock_frame"])))


def _rot_args(v0, v1):
    """(sin, cos) of the angle from v0 to v1 (for atan2)."""
    return _cross(v0, v1), float(np.dot(v0, v1))


@dataclass
class Curves:
    """The rear end's curves over the rear wheel travel (SI units; see the module doc)."""

    travel: np.ndarray
    stroke: np.ndarray
    leverage_ratio: np.ndarray
    axle_x: np.ndarray
    axle_z: np.ndarray
    centre_x: np.ndarray
    centre_z: np.ndarray
    anti_squat: np.ndarray
    anti_rise: np.ndarray
    kickback_deg: np.ndarray
    com_height: float
    stroke_limit: float
    caliper_turn: np.ndarray | None = None  # rad: the caliper's link's turn from full extension

    def rows(self) -> list[dict]:
        return [{"wheel_travel_mm": self.travel[i] / MM, "shock_stroke_mm": self.stroke[i] / MM,
                 "leverage_ratio": self.leverage_ratio[i], "axle_x_mm": self.axle_x[i] / MM,
                 "axle_z_mm": self.axle_z[i] / MM, "instant_centre_x_mm": self.centre_x[i] / MM,
                 "instant_centre_z_mm": self.centre_z[i] / MM, "anti_squat_percent": self.anti_squat[i],
                 "anti_rise_percent": self.anti_rise[i], "pedal_kickback_deg": self.kickback_deg[i]}
                for i in range(self.travel.size)]


def _direction(link: Linkage) -> float:
    """+1 or -1: the sense of the input angle that raises the rear axle."""
    small = 1e-4
    up = link.travel(small)
    return 1.0 if up > 0.0 else -1.0


def _chain_normal(ring_centre, ring_r, cog_centre, cog_r):
    """(unit normal of the chain's upper run, span length): the outer tangent above both sprockets."""
    d = cog_centre - ring_centre
    dist = float(np.hypot(*d))
    delta = math.acos(max(-1.0, min(1.0, (ring_r - cog_r) / dist)))  # n . (cog - ring) = ring_r - cog_r
    base = math.atan2(d[1], d[0])
    normals = [np.array([math.cos(base + s * delta), math.sin(base + s * delta)]) for s in (1.0, -1.0)]
    n = max(normals, key=lambda v: v[1])  # the upper run
    return n, math.sqrt(max(dist * dist - (ring_r - cog_r) ** 2, 0.0))


def _line_height(contact, through, x_front) -> float:
    """Height over the contact at ``x_front`` of the line from ``contact`` through ``through``."""
    dx = through[0] - contact[0]
    if abs(dx) < 1e-12:
        return math.inf
    return (through[1] - contact[1]) / dx * (x_front - contact[0])


def curves(link: Linkage, stroke_limit: float, tyre_radius: float | None = None, front_axle_x: float | None = None,
           com_height: float | None = None, step: float = 1e-3) -> Curves:
    """The curves every ``step`` of rear wheel travel from full extension to where the shock's
    stroke reaches ``stroke_limit`` (m); ``tyre_radius`` and ``front_axle_x`` (frame x of the front
    axle) place the contacts, ``com_height`` (m over the ground) the centre of mass (without them
    anti-squat and anti-rise are NaN)."""
    forces = tyre_radius is not None and front_axle_x is not None and com_height is not None
    sign = _direction(link)

    def stroke_at(a):
        return link.stroke(sign * a)

    # the input angle at which the stroke reaches the limit: bracket it outward
    hi = 0.05
    while True:
        s = stroke_at(hi)
        if not math.isfinite(s) or link.pose(sign * hi) is None:
            raise ConfigError(f"linkage: the mechanism locks before the shock's stroke reaches "
                              f"{stroke_limit / MM:g} mm (shock.stroke_mm)")
        if s >= stroke_limit:
            break
        hi *= 1.5
        if hi > math.pi:
            raise ConfigError(f"linkage: the shock's stroke never reaches {stroke_limit / MM:g} mm (shock.stroke_mm): "
                              f"check the shock's points")
    if stroke_at(1e-4) <= 0.0:
        raise ConfigError("linkage: the shock lengthens as the wheel rises: check shock_frame and the shock's other point")
    a_end = brentq(lambda a: stroke_at(a) - stroke_limit, 0.0, hi, xtol=1e-13)
    w_end = link.travel(sign * a_end)
    grid = np.arange(0.0, w_end, step)
    grid = np.append(grid, w_end) if w_end - grid[-1] > 1e-9 else grid
    angles = [0.0]
    for w in grid[1:]:
        angles.append(brentq(lambda a: link.travel(sign * a) - w, angles[-1], a_end + 1e-9, xtol=1e-14))
    ring_r, cog_r = sprocket_radius(link.chainring), sprocket_radius(link.cog)
    bb = np.zeros(2)
    out = {k: [] for k in ("s", "lr", "ax", "az", "cx", "cz", "as", "ar", "kb", "ct")}
    n0, span0 = _chain_normal(bb, ring_r, link.p0["rear_axle"], cog_r)
    theta0 = math.atan2(n0[1], n0[0])
    for a in angles:
        h = 1e-7
        lo_a, hi_a = max(a - h, 0.0), a + h
        dw = link.travel(sign * hi_a) - link.travel(sign * lo_a)
        ds = stroke_at(hi_a) - stroke_at(lo_a)
        pose = link.pose(sign * a)
        axle = pose.points["rear_axle"]
        out["s"].append(stroke_at(a))
        out["lr"].append(dw / ds)
        out["ax"].append(axle[0])
        out["az"].append(axle[1])
        out["ct"].append(pose.caliper_turn)
        centre = pose.axle_centre
        out["cx"].append(np.nan if centre is None else centre[0])
        out["cz"].append(np.nan if centre is None else centre[1])
        n, span = _chain_normal(bb, ring_r, axle, cog_r)
        if forces:
            contact = np.array([axle[0], axle[1] - tyre_radius])
            tangent = np.array([-n[1], n[0]])
            top = bb + ring_r * n
            force_centre = None if centre is None else _meet(top, tangent, axle, centre - axle)
            out["as"].append(math.nan if force_centre is None else
                             100.0 * _line_height(contact, force_centre, front_axle_x) / com_height)
            brake = pose.brake_centre
            out["ar"].append(math.nan if brake is None else
                             100.0 * _line_height(contact, brake, front_axle_x) / com_height)
        else:
            out["as"].append(math.nan)
            out["ar"].append(math.nan)
        theta = math.atan2(n[1], n[0])
        turn = ((span - span0) + (ring_r - cog_r) * (theta - theta0)) / ring_r
        out["kb"].append(math.degrees(turn))
    arr = {k: np.asarray(v, float) for k, v in out.items()}
    return Curves(grid, arr["s"], arr["lr"], arr["ax"], arr["az"], arr["cx"], arr["cz"], arr["as"], arr["ar"],
                  arr["kb"], math.nan if com_height is None else com_height, stroke_limit, arr["ct"])


def circle_path(link: Linkage, c: Curves, pivot) -> tuple[np.ndarray, np.ndarray]:
    """(x, z) m of the rear axle turned about ``pivot`` to the same wheel travels as ``c`` (the
    path the bike's single pivot gives it)."""
    a0 = link.p0["rear_axle"] - np.asarray(pivot, float)
    r = float(np.hypot(*a0))
    z = a0[1] + c.travel
    x = np.sign(a0[0]) * np.sqrt(np.maximum(r * r - z * z, 0.0))
    return pivot[0] + x, pivot[1] + z


def fitted_pivot(link: Linkage, c: Curves) -> np.ndarray:
    """The centre (m) of the circle through the rear axle at full extension that best fits (least
    squares, ``scipy.optimize.least_squares``) the linkage's axle path over its travel: where the
    bike's single pivot turns the axle of a four-bar whose axle rides on its coupler (a Horst link's
    seatstay, a short link's rear triangle). The instant centre at full extension gives the path's
    direction there but not its curvature (the coupler point's centre of curvature lies elsewhere:
    Euler-Savary), so its circle leaves the path by millimetres; this circle follows it."""
    from scipy.optimize import least_squares

    a0 = link.p0["rear_axle"]

    def residual(centre):
        return np.hypot(c.axle_x - centre[0], c.axle_z - centre[1]) - np.hypot(*(a0 - centre))

    start = link.pose(0.0).axle_centre
    guess = [link.p0["main_pivot"] if "main_pivot" in link.p0 else a0 + np.array([0.4, 0.05])]
    if start is not None:
        guess.insert(0, start)
    best = min((least_squares(residual, g, x_scale=0.1, xtol=1e-14, ftol=1e-14) for g in guess),
               key=lambda r: float(np.max(np.abs(r.fun))))
    return np.asarray(best.x, float)


def caliper_ratio(c: Curves, pivot) -> np.ndarray:
    """At each travel of ``c``, how fast the link carrying the rear caliper turns against the bike's
    arm turning the axle about ``pivot`` (d caliper turn / d arm turn, both relative to the frame):
    the factor on the brake couple's generalised force on the arm's hinge (its virtual work is the
    couple times the caliper link's turn). 1 where the caliper rides on the arm itself."""
    arm = np.unwrap(np.arctan2(c.axle_z - pivot[1], c.axle_x - pivot[0]))
    return np.gradient(c.caliper_turn, arm, edge_order=2)


def path_departure(link: Linkage, c: Curves, pivot) -> float:
    """The largest distance (m) between the linkage's axle path and the circle about ``pivot``, at equal travel."""
    x, z = circle_path(link, c, pivot)
    return float(np.max(np.hypot(x - c.axle_x, z - c.axle_z)))


def _point(table, key):
    value = table.get(key)
    if value is None:
        raise ConfigError(f"linkage.{key}: missing (a {table.get('kind')} rear end needs "
                          f"{', '.join(n + '_mm' for n in LAYOUTS[table['kind']])})")
    if (not isinstance(value, (list, tuple)) or len(value) != 2
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value)):
        raise ConfigError(f"linkage.{key}: must be [x, z] in mm, got {value!r}")
    if max(abs(float(x)) for x in value) > 5000.0:
        raise ConfigError(f"linkage.{key}: {value!r} lies more than 5 m from the bottom bracket (mm expected)")
    return np.array([float(value[0]), float(value[1])]) * MM


def known_keys() -> set:
    return OTHER_KEYS | {n + "_mm" for names in LAYOUTS.values() for n in names}


def from_table(table: dict) -> Linkage:
    """A :class:`Linkage` from a bike file's ``[linkage]`` table (checked; one line on bad input)."""
    if not isinstance(table, dict):
        raise ConfigError("linkage: must be a table")
    kind = table.get("kind")
    if kind not in LAYOUTS:
        raise ConfigError(f"linkage.kind: must be one of {', '.join(LAYOUTS)}, got {kind!r}")
    allowed = OTHER_KEYS | {n + "_mm" for n in LAYOUTS[kind]}
    for key in table:
        if key not in allowed:
            raise ConfigError(f"linkage.{key}: not a point of a {kind} rear end (known: {', '.join(sorted(allowed))})")
    points = {n: _point(table, n + "_mm") for n in LAYOUTS[kind]}
    teeth = {}
    for key, default in (("chainring_teeth", DEFAULT_CHAINRING), ("cog_teeth", DEFAULT_COG)):
        value = table.get(key, default)
        if not isinstance(value, int) or isinstance(value, bool) or not 9 <= value <= 60:
            raise ConfigError(f"linkage.{key}: must be a whole number of teeth within 9-60, got {value!r}")
        teeth[key] = value
    brake = table.get("brake_on", BRAKE_LINKS[kind][0])
    if brake not in BRAKE_LINKS[kind]:
        raise ConfigError(f"linkage.brake_on: a {kind}'s caliper sits on {' or '.join(BRAKE_LINKS[kind])}, got {brake!r}")
    return Linkage(kind, points, teeth["chainring_teeth"], teeth["cog_teeth"], brake)


__all__ = ["Linkage", "Curves", "curves", "from_table", "known_keys", "sprocket_radius", "circle_path",
           "path_departure", "LAYOUTS", "BRAKE_LINKS"]

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


# The names of each four-bar's loop (A, B, C, D: the frame pivot of the input link, the input link's
# joint with the coupler, the coupler's joint with the output link, the output link's frame pivot)
# and of its three moving links.
FOUR_BARS = {"linkage_driven_single_pivot": ("main_pivot", "swingarm_link", "rocker_link", "rocker_pivot"),
             "horst_link": ("main_pivot", "horst_pivot", "seatstay_rocker", "rocker_pivot"),
             "short_link": ("lower_pivot", "lower_link", "upper_link", "upper_pivot")}
LINK_NAMES = {"linkage_driven_single_pivot": ("swingarm", "link", "rocker"),
              "horst_link": ("chainstay", "seatstay", "rocker"),
              "short_link": ("lower link", "rear triangle", "upper link")}
# the pivot the shock's rear-end eye turns about, per layout
SHOCK_PIVOT = {"single_pivot": "main_pivot", "linkage_driven_single_pivot": "rocker_pivot",
               "horst_link": "rocker_pivot", "short_link": "upper_pivot"}
# Two points of a member closer than this make it no member (a link, the shock, a lever arm): the
# coordinates are typed in whole or tenths of millimetres, and no bike has a link, a shock or a lever
# arm of 1 mm.
MIN_SPAN = 1e-3


def _key(name: str) -> str:
    return f"linkage.{name}_mm"


def _line_distance(p, a, b) -> float:
    """The distance of ``p`` from the line through ``a`` and ``b``."""
    return abs(_cross(b - a, p - a)) / float(np.hypot(*(b - a)))


def check_points(kind: str, p: dict) -> None:
    """Refuse, in one line naming the keys, points that leave the mechanism without a defined motion:
    coincident points of one member (a link, the shock, the axle's or the shock's lever arm), a
    four-bar whose four loop points meet or lie on one line, a shock whose line passes through the
    pivot its eye turns about, a rear axle straight above or below the pivot of the arm carrying it."""
    pairs = []  # (name, name, what it leaves)
    end, pivot = SHOCK_END[kind], SHOCK_PIVOT[kind]
    if kind == "single_pivot" or kind == "linkage_driven_single_pivot":
        pairs.append(("main_pivot", "rear_axle", "the swingarm has no length (the rear axle on the main pivot)"))
    if kind in FOUR_BARS:
        a, b, c, d = FOUR_BARS[kind]
        first, coupler, output = LINK_NAMES[kind]
        pairs += [(a, b, f"the {first} has no length"), (b, c, f"the {coupler} has no length"),
                  (d, c, f"the {output} has no length"), (a, d, "the four-bar's two frame pivots are one point"),
                  (a, c, "a four-bar's joint on the other link's frame pivot leaves its motion undefined"),
                  (b, d, "a four-bar's joint on the other link's frame pivot leaves its motion undefined")]
    pairs += [(pivot, end, "the shock's eye on the pivot its link turns about: the shock would not stroke"),
              (end, "shock_frame", "the shock has no length"),
              (pivot, "shock_frame", "the shock's frame end on the pivot of the link it is driven by: its length "
                                     "would not change")]
    for one, two, what in pairs:
        gap = float(np.hypot(*(p[one] - p[two])))
        if gap < MIN_SPAN:
            raise ConfigError(f"{_key(one)} and {_key(two)}: {gap / MM:.2g} mm apart: {what}")
    if kind in FOUR_BARS:
        loop = [p[n] for n in FOUR_BARS[kind]]
        far = max(((i, j) for i in range(4) for j in range(i + 1, 4)),
                  key=lambda ij: float(np.hypot(*(loop[ij[0]] - loop[ij[1]]))))
        if all(_line_distance(q, loop[far[0]], loop[far[1]]) < MIN_SPAN for q in loop):
            raise ConfigError(f"{', '.join(_key(n) for n in FOUR_BARS[kind])}: on one line (within 1 mm): the "
                              f"four-bar's motion is not defined there")
    if _line_distance(p[pivot], p[end], p["shock_frame"]) < MIN_SPAN:
        raise ConfigError(f"{_key('shock_frame')}, {_key(end)} and {_key(pivot)}: on one line (within 1 mm): the "
                          f"shock's line passes through the pivot its eye turns about, so at full extension the "
                          f"shock does not stroke as the wheel rises")
    if kind in ("single_pivot", "linkage_driven_single_pivot") and \
            abs(float(p["rear_axle"][0] - p["main_pivot"][0])) < MIN_SPAN:
        raise ConfigError(f"{_key('rear_axle')}: straight above or below {_key('main_pivot')} (within 1 mm): the "
                          f"swingarm would move the axle fore and aft, not up")


def _circles(p, rp: float, q, rq: float, side: float):
    """The point ``rp`` from ``p`` and ``rq`` from ``q`` on the ``side`` of the line p -> q (+1: to
    its left); None where the circles do not meet."""
    pq = q - p
    dist = float(np.hypot(*pq))
    if dist < 1e-12 or dist > rp + rq or dist < abs(rp - rq):
        return None
    along = (rp * rp - rq * rq + dist * dist) / (2.0 * dist)
    h = math.sqrt(max(rp * rp - along * along, 0.0))
    e = pq / dist
    return p + along * e + side * h * np.array([-e[1], e[0]])


@dataclass(frozen=True)
class Pose:
    """Every named point (m, frame coordinates) at one input angle, and the instant centres of the
    axle's link and of the caliper's link."""

    points: dict
    axle_centre: np.ndarray | None
    brake_centre: np.ndarray | None
    caliper_turn: float = 0.0  # rad: the turn from full extension of the link carrying the caliper


class Linkage:
    """A solved rear end: ``kind``, ``points`` (name -> (x, z) m at full extension).

    A four-bar is driven from one of its frame links (``driver``): "input" (A-B) turned by the angle
    and the joint C found on the circles about B and D, or "output" (D-C) turned by the angle and B
    found on the circles about C and A. Each solve fails where its own link reverses (its dead point:
    B, C and D on one line for the input, A, B and C for the output), so :func:`curves` drives the
    loop from whichever link turns one way over the travel."""

    def __init__(self, kind: str, points: dict, chainring: int = DEFAULT_CHAINRING, cog: int = DEFAULT_COG,
                 brake_on: str | None = None, driver: str = "input"):
        self.kind, self.chainring, self.cog = kind, int(chainring), int(cog)
        self.p0 = {k: np.asarray(v, float) for k, v in points.items()}
        self.brake_on = brake_on or BRAKE_LINKS[kind][0]
        check_points(kind, self.p0)
        self.driver = driver
        if kind == "single_pivot":
            self.four_bar = None
            self.A = self.p0["main_pivot"]
            self.input_points = ("rear_axle", "shock_swingarm")
            self.driver = "input"
        else:
            names = FOUR_BARS[kind]
            self.four_bar = names
            a, b, c, d = (self.p0[n] for n in names)
            self.A, self.D = a, d
            self.input_length = float(np.hypot(*(b - a)))
            self.coupler = float(np.hypot(*(c - b)))
            self.output = float(np.hypot(*(c - d)))
            self.branch = 1.0 if _cross(c - b, d - b) >= 0.0 else -1.0  # which side of B-D the point C lies
            self.branch_b = 1.0 if _cross(a - c, b - c) > 0.0 else -1.0  # which side of C-A the point B lies
            self.input_points = {"linkage_driven_single_pivot": ("rear_axle", "swingarm_link"),
                                 "horst_link": ("horst_pivot",), "short_link": ("lower_link",)}[kind]
        self.coupler_points = {"horst_link": ("rear_axle",), "short_link": ("rear_axle",)}.get(kind, ())
        self.output_points = {"linkage_driven_single_pivot": ("shock_rocker", "rocker_link"),
                              "horst_link": ("shock_rocker", "seatstay_rocker"),
                              "short_link": ("shock_upper_link", "upper_link")}.get(kind, ())
        self.length0 = float(np.hypot(*(self._shock_end(self.p0) - self.p0["shock_frame"])))

    def driven_by(self, driver: str) -> "Linkage":
        """The same rear end driven from its input ("input") or output ("output") link."""
        if driver == self.driver:
            return self
        return Linkage(self.kind, self.p0, self.chainring, self.cog, self.brake_on, driver)

    @property
    def driver_name(self) -> str:
        """The link the loop is solved from (its frame pivot and its joint's keys)."""
        if self.four_bar is None:
            return "swingarm"
        return LINK_NAMES[self.kind][0 if self.driver == "input" else 2]

    def _shock_end(self, points) -> np.ndarray:
        return points[SHOCK_END[self.kind]]

    def pose(self, angle: float) -> Pose | None:
        """Every point with the driving link turned by ``angle`` (rad, the sense that raises the
        axle counted by the caller); None where the four-bar cannot close."""
        p = dict(self.p0)
        if self.four_bar is None:
            for n in self.input_points:
                p[n] = self.A + _rotate(self.p0[n] - self.A, angle)
            return Pose(p, self.A.copy(), self.A.copy(), angle)
        a_name, b_name, c_name, d_name = self.four_bar
        b0, c0 = self.p0[b_name], self.p0[c_name]
        if self.driver == "input":
            turn_in = angle
            b = self.A + _rotate(b0 - self.A, angle)
            c = _circles(b, self.coupler, self.D, self.output, -self.branch)  # the branch the mechanism starts on
            if c is None:
                return None
        else:
            c = self.D + _rotate(c0 - self.D, angle)
            b = _circles(c, self.coupler, self.A, self.input_length, self.branch_b)
            if b is None:
                return None
            turn_in = math.atan2(*(_rot_args(b0 - self.A, b - self.A)))
        for n in self.input_points:
            p[n] = self.A + _rotate(self.p0[n] - self.A, turn_in)
        p[b_name], p[c_name] = b, c
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
        return Pose(p, axle_centre, brake_centre, turn_in if on_input else turn_c)

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
    driver: str = "swingarm"  # the link the loop was solved from (a four-bar's input or output link)

    def rows(self) -> list[dict]:
        return [{"wheel_travel_mm": self.travel[i] / MM, "shock_stroke_mm": self.stroke[i] / MM,
                 "leverage_ratio": self.leverage_ratio[i], "axle_x_mm": self.axle_x[i] / MM,
                 "axle_z_mm": self.axle_z[i] / MM, "instant_centre_x_mm": self.centre_x[i] / MM,
                 "instant_centre_z_mm": self.centre_z[i] / MM, "anti_squat_percent": self.anti_squat[i],
                 "anti_rise_percent": self.anti_rise[i], "pedal_kickback_deg": self.kickback_deg[i]}
                for i in range(self.travel.size)]


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


class _Unsolved(Exception):
    """The loop cannot be driven from this link over the travel; the message says why."""


MARCH = 0.005  # rad: the driving link's step searching for the stroke's end (2 mm of a 400 mm swingarm's arc)


def _drive(link: Linkage, stroke_limit: float) -> tuple[float, float]:
    """(sign, angle): the sense of ``link``'s driving angle that raises the rear axle, and the angle at
    which the shock's stroke reaches ``stroke_limit`` (m), marching out from full extension in steps
    of :data:`MARCH` (the edge where the loop stops closing found by bisection). Over the way the
    rear axle must rise and the shock shorten at every step; ``_Unsolved`` where the driving link
    cannot take the mechanism there (it locks, or the axle stops rising as it turns: the driving link
    itself reverses), ``ConfigError`` where no driver can (the shock lengthens as the wheel rises)."""
    name = link.driver_name
    ups = [(sg, link.travel(sg * 1e-4)) for sg in (1.0, -1.0)]
    ups = [(sg, w) for sg, w in ups if math.isfinite(w) and w > 0.0]
    if not ups:
        raise _Unsolved(f"turning the {name} either way does not raise the rear axle")
    sign = max(ups, key=lambda u: u[1])[0]

    def at(a):
        pose = link.pose(sign * a)
        if pose is None:
            return None
        return (float(pose.points["rear_axle"][1] - link.p0["rear_axle"][1]),
                link.length0 - float(np.hypot(*(link._shock_end(pose.points) - pose.points["shock_frame"]))))

    end, limit = SHOCK_END[link.kind], f"{stroke_limit / MM:g} mm (shock.stroke_mm)"
    a_prev, w_prev, s_prev = 0.0, 0.0, 0.0
    while True:
        a = a_prev + MARCH
        if a > math.pi:
            raise _Unsolved(f"turned half a turn, the {name} strokes the shock {s_prev / MM:.1f} mm")
        here = at(a)
        if here is None:  # the loop stops closing within this step: its edge
            lo, hi = a_prev, a
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if at(mid) is not None else (lo, mid)
            a, here = lo, at(lo)
            if here is None or here[1] < stroke_limit or here[0] <= w_prev:
                stroke = s_prev if here is None else max(here[1], s_prev)
                raise _Unsolved(f"driven by the {name}, the mechanism locks at {stroke / MM:.1f} mm of stroke")
        w, s = here
        if w <= w_prev:
            raise _Unsolved(f"driven by the {name}, the rear axle stops rising at {w_prev / MM:.1f} mm of wheel "
                            f"travel")
        if s <= s_prev:
            if s_prev == 0.0:
                raise ConfigError(f"linkage: the shock lengthens as the wheel rises: check {_key('shock_frame')} "
                                  f"and {_key(end)}")
            raise ConfigError(f"linkage: the shock lengthens again past {s_prev / MM:.1f} mm of stroke ("
                              f"{w_prev / MM:.1f} mm of wheel travel), before its stroke reaches {limit}: check "
                              f"{_key('shock_frame')} and {_key(end)}")
        if s >= stroke_limit:
            break
        a_prev, w_prev, s_prev = a, w, s
    if a_prev == 0.0 and at(1e-4)[1] <= 0.0:
        raise ConfigError(f"linkage: the shock lengthens as the wheel rises: check {_key('shock_frame')} and "
                          f"{_key(end)}")
    return sign, brentq(lambda u: at(u)[1] - stroke_limit, a_prev, a, xtol=1e-13)


def _drivers(link: Linkage) -> list[str]:
    """The links to drive a four-bar from, the one farther from its dead point at full extension
    first (the input's: B, C and D on one line; the output's: A, B and C)."""
    if link.four_bar is None:
        return ["input"]
    a, b, c, d = (link.p0[n] for n in link.four_bar)
    sine = lambda u, v: abs(_cross(u, v)) / float(np.hypot(*u) * np.hypot(*v))  # noqa: E731
    return ["input", "output"] if sine(c - b, d - c) >= sine(b - c, a - b) else ["output", "input"]


def curves(link: Linkage, stroke_limit: float, tyre_radius: float | None = None, front_axle_x: float | None = None,
           com_height: float | None = None, step: float = 1e-3) -> Curves:
    """The curves every ``step`` of rear wheel travel from full extension to where the shock's
    stroke reaches ``stroke_limit`` (m); ``tyre_radius`` and ``front_axle_x`` (frame x of the front
    axle) place the contacts, ``com_height`` (m over the ground) the centre of mass (without them
    anti-squat and anti-rise are NaN). A four-bar is solved from whichever of its frame links turns
    one way over the travel (:func:`_drive`; the other one may reverse); one line where neither can."""
    forces = tyre_radius is not None and front_axle_x is not None and com_height is not None
    reasons = []
    for driver in _drivers(link):
        try:
            driven = link.driven_by(driver)
            sign, a_end = _drive(driven, stroke_limit)
            break
        except _Unsolved as exc:
            reasons.append(str(exc))
    else:
        keys = ", ".join(_key(n) for n in (link.four_bar or LAYOUTS[link.kind]))
        raise ConfigError(f"linkage: the shock's stroke never reaches {stroke_limit / MM:g} mm (shock.stroke_mm): "
                          f"{'; '.join(reasons)}: check {keys}")
    link = driven

    def stroke_at(a):
        return link.stroke(sign * a)

    w_end = link.travel(sign * a_end)
    grid = np.arange(0.0, w_end, step)
    grid = np.append(grid, w_end) if w_end - grid[-1] > 1e-9 else grid
    angles = [0.0]
    for w in grid[1:]:
        angles.append(brentq(lambda a: link.travel(sign * a) - w, angles[-1], a_end, xtol=1e-14))
    ring_r, cog_r = sprocket_radius(link.chainring), sprocket_radius(link.cog)
    bb = np.zeros(2)
    out = {k: [] for k in ("s", "lr", "ax", "az", "cx", "cz", "as", "ar", "kb", "ct")}
    n0, span0 = _chain_normal(bb, ring_r, link.p0["rear_axle"], cog_r)
    theta0 = math.atan2(n0[1], n0[0])
    for a in angles:
        h = 1e-7
        lo_a, hi_a = max(a - h, 0.0), a + h
        if link.pose(sign * hi_a) is None:  # at the edge where the loop stops closing: a one-sided difference
            hi_a = a
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
    bad = np.flatnonzero(~(np.isfinite(arr["lr"]) & (arr["lr"] > 0.0)))
    if bad.size:  # a reversal finer than the march's step
        raise ConfigError(f"linkage: the leverage ratio is {arr['lr'][bad[0]]:.3g} at {grid[bad[0]] / MM:.1f} mm of "
                          f"wheel travel (the rear axle or the shock turns back there): check the points of "
                          f"[linkage]")
    return Curves(grid, arr["s"], arr["lr"], arr["ax"], arr["az"], arr["cx"], arr["cz"], arr["as"], arr["ar"],
                  arr["kb"], math.nan if com_height is None else com_height, stroke_limit, arr["ct"],
                  link.driver_name)


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
    return np.gradient(c.caliper_turn, arm, edge_order=2 if arm.size > 2 else 1)  # (a travel under 1 mm: 2 points)


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

"""Terrain library for rolling runs: 2-D profiles in the x-z plane (x forward, z up, SI).

Every terrain is a polyline ``(x, z)`` with ``x`` non-decreasing (two points with the same ``x``
make a vertical wall: steps, square edges, drops), flat lead-in before the feature so the wheel
starts at rest on flat ground, and flat continuation past the last point. The drum rig is the one
moving terrain: a cylinder with a cleat that turns under a wheel held in place.

Specs (``make``): a name with optional ``key=value`` parameters, units in the key names, e.g.
``"root"``, ``"root:radius_mm=60"``, ``"iso8608:class=D,seed=3"``, or a path to a CSV file with
columns ``distance_m`` and ``height_mm``. Bad specs raise ``TerrainError`` (one line, naming the
cause).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mtbmj.errors import MtbmjError

MM = 1e-3
LEAD_IN_M = 1.5  # flat ground before the feature: the wheel starts at rest on it
RUN_OUT_M = 3.0  # flat ground past the feature (the profile continues flat beyond anyway)
# The front end's head angle unless told (degrees from the horizontal); kept here, beside the
# terrain, so the command line can show it without loading MuJoCo and the front end.
DEFAULT_HEAD_ANGLE_DEG = 65.0
ISO8608_GD_N0 = {  # geometric mean of each class, Gd(n0 = 0.1 cycle/m) in m^3 (ISO 8608:2016 Table 1)
    "A": 16e-6, "B": 64e-6, "C": 256e-6, "D": 1024e-6,
    "E": 4096e-6, "F": 16384e-6, "G": 65536e-6, "H": 262144e-6,
}


class TerrainError(MtbmjError, ValueError):
    """A terrain spec that cannot be built: unknown name, bad parameter, bad CSV. An input error: a
    ``ValueError`` too, as ``ConfigError`` is (``except ValueError`` catches it)."""


@dataclass(frozen=True)
class Terrain:
    """A static profile: polyline ``x``, ``z`` (m), the axle's start ``start_x`` and the distance
    ``length`` (m) a run needs to cross the feature and settle after it."""

    name: str
    x: np.ndarray
    z: np.ndarray
    start_x: float
    length: float
    params: dict = field(default_factory=dict)
    moving: bool = False

    def height(self, x) -> np.ndarray:
        """Surface height (m) at ``x``; on a vertical wall the upper end."""
        x = np.asarray(x, dtype=float)
        # np.interp takes the last of equal abscissae: the right side of a wall; the upper end
        # is the max of both sides.
        right = np.interp(x, self.x, self.z)
        left = -np.interp(-x, -self.x[::-1], -self.z[::-1])
        return np.maximum(left, right)

    def polyline(self, x_lo: float, x_hi: float, t: float = 0.0):
        """Points of the profile covering [x_lo, x_hi] (one point beyond each end, extended flat):
        (px, pz, surface velocity x, surface velocity z); static terrain has zero velocity."""
        i = max(int(np.searchsorted(self.x, x_lo, side="left")) - 1, 0)
        j = min(int(np.searchsorted(self.x, x_hi, side="right")) + 1, self.x.size)
        px, pz = self.x[i:j], self.z[i:j]
        if px[0] > x_lo:
            px = np.concatenate(([x_lo - 1.0], px))
            pz = np.concatenate(([pz[0]], pz))
        if px[-1] < x_hi:
            px = np.concatenate((px, [x_hi + 1.0]))
            pz = np.concatenate((pz, [pz[-1]]))
        return px, pz, 0.0, 0.0

    def surface_velocity(self, qx: float, qz: float, t: float) -> tuple[float, float]:
        return 0.0, 0.0

    def start_height(self) -> float:
        return float(self.height(self.start_x))

    def describe(self) -> dict:
        return {"name": self.name, **{k: v for k, v in self.params.items()}}


@dataclass(frozen=True)
class DrumTerrain(Terrain):
    """A drum rig: a cylinder of ``radius`` (m) whose top is at z = 0 under x = 0, turning so
    that its surface moves at ``surface_speed`` (m/s) towards -x, with ``cleat`` points
    ((angle, radius) pairs in the drum frame) on its surface."""

    radius: float = 0.5
    surface_speed: float = 0.0
    polar: np.ndarray | None = None  # (n, 2): angle (rad, 0 = top at t = 0, positive towards +x), radius

    @property
    def omega(self) -> float:
        return self.surface_speed / self.radius

    def with_speed(self, speed: float) -> "DrumTerrain":
        return DrumTerrain(self.name, self.x, self.z, self.start_x, self.length, self.params, True,
                           self.radius, speed, self.polar)

    def polyline(self, x_lo: float, x_hi: float, t: float = 0.0):
        angle = self.polar[:, 0] - self.omega * t  # the top moves towards -x: angles decrease
        lim = math.asin(min(1.0, max(abs(x_lo), abs(x_hi)) / self.radius)) + 0.05
        wrapped = (angle + math.pi) % (2 * math.pi) - math.pi
        keep = np.abs(wrapped) <= lim
        a, r = wrapped[keep], self.polar[keep, 1]
        order = np.argsort(a, kind="stable")
        a, r = a[order], r[order]
        px = r * np.sin(a)
        pz = r * np.cos(a) - self.radius
        return px, pz, 0.0, 0.0

    def surface_velocity(self, qx: float, qz: float, t: float) -> tuple[float, float]:
        # Rotation about the drum centre (0, -R): in the x-z view the top moves towards -x.
        w = self.omega
        return -w * (qz + self.radius), w * qx

    def height(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return np.sqrt(np.maximum(self.radius**2 - x**2, 0.0)) - self.radius


def _profile(name, pieces, start_x=0.0, length=None, params=None) -> Terrain:
    x = np.concatenate([np.asarray(p[0], float) for p in pieces])
    z = np.concatenate([np.asarray(p[1], float) for p in pieces])
    if length is None:
        length = float(x[-1] - start_x)
    surface = float(np.sum(np.hypot(np.diff(x), np.diff(z))))
    if not surface <= MAX_SURFACE_M:  # the tyre's search cuts the surface into pieces: refused before they are
        where = (params or {}).get("csv", f"terrain {name}")
        raise TerrainError(f"{where}: its surface, along its distances and up and down its heights, is {surface:.4g} m "
                           f"long, more than the {MAX_SURFACE_M:g} m a terrain may be (it spans {np.ptp(x):.4g} m; "
                           f"its heights {np.ptp(z) / MM:.4g} mm)")
    return Terrain(name, x, z, start_x, length, dict(params or {}))


def _flat(a: float, b: float, h: float = 0.0):
    return [a, b], [h, h]


def flat(length_m: float = 10.0) -> Terrain:
    return _profile("flat", [_flat(-LEAD_IN_M, length_m)], length=length_m, params={"length_m": length_m})


def _graded(s, g: float, transition_m: float):
    """The rise (m) at ``s`` m along a grade ``g`` (rise / run) entered over a parabolic transition
    ``transition_m`` long from s = 0 (the grade grows linearly along it, so no kink jolts the wheels)."""
    return np.where(s < transition_m, 0.5 * g * s * s / transition_m, g * (s - 0.5 * transition_m))


def climb(grade_percent: float = 10.0, length_m: float = 40.0, at_m: float = LEAD_IN_M,
          transition_m: float = 3.0) -> Terrain:
    """A steady climb (or descent, a negative grade): flat to ``at_m``, then rising at
    ``grade_percent`` (100 x rise / run) for ``length_m`` along the ground's x, entered over a
    parabolic transition ``transition_m`` long (the grade grows linearly along it, so no kink jolts
    the wheels), sampled every 50 mm (chord sag below 0.01 mm)."""
    if not -40.0 <= grade_percent <= 40.0:
        raise TerrainError(f"climb: grade_percent {grade_percent:g} is outside -40 to 40 % (steeper than any trail "
                           f"a bike is ridden up or down seated on its wheels)")
    g, lt = grade_percent / 100.0, min(transition_m, length_m)
    s = np.linspace(0.0, length_m, max(2, int(round(length_m / 0.05)) + 1))
    z = _graded(s, g, lt)
    return _profile("climb", [_flat(-LEAD_IN_M, at_m), (at_m + s[1:], z[1:]),
                              _flat(at_m + length_m, at_m + length_m + RUN_OUT_M, z[-1])],
                    length=at_m + length_m,
                    params={"grade_percent": grade_percent, "length_m": length_m, "at_m": at_m})


def on_grade(ter: Terrain, grade_percent: float, at_m: float, transition_m: float = 3.0) -> Terrain:
    """``ter``'s profile laid on a steady grade (a descent: negative): its heights as they are to ``at_m``,
    then the grade's ``grade_percent`` (100 x rise / run) added from ``at_m`` on, entered over a
    parabolic transition ``transition_m`` long as :func:`climb` enters its own (the grade grows
    linearly along it). The transition is sampled every 50 mm; the profile's own samples are kept."""
    if not -40.0 <= grade_percent <= 40.0:
        raise TerrainError(f"grade_percent {grade_percent:g} is outside -40 to 40 % (steeper than any trail a bike is "
                           f"ridden up or down seated on its wheels)")
    x = np.asarray(ter.x, float)
    z = np.asarray(ter.z, float)
    added = at_m + np.linspace(0.0, transition_m, max(2, int(round(transition_m / 0.05)) + 1))
    added = added[(added > x[0]) & (added < x[-1])]
    near = np.searchsorted(x, added)  # none within a micrometre of the profile's own samples
    gap = np.minimum(np.abs(added - x[np.clip(near, 0, x.size - 1)]), np.abs(added - x[np.clip(near - 1, 0, x.size - 1)]))
    added = added[gap > 1e-6]
    xs = np.concatenate((x, added))
    # the profile's height at the added points (a wall's two ends kept in order: a stable sort after x's own)
    zs = np.concatenate((z, np.interp(added, x, z)))
    order = np.argsort(xs, kind="stable")
    xs, zs = xs[order], zs[order]
    g, s = grade_percent / 100.0, np.clip(xs - at_m, 0.0, None)
    zs = zs + _graded(s, g, transition_m)
    return Terrain(ter.name, xs, zs, ter.start_x, ter.length,
                   {**ter.params, "grade_percent": grade_percent, "grade_at_m": at_m})


def step_up(height_mm: float = 50.0, at_m: float = LEAD_IN_M) -> Terrain:
    h = height_mm * MM
    return _profile("step_up", [_flat(-LEAD_IN_M, at_m), _flat(at_m, at_m + RUN_OUT_M, h)],
                    length=at_m + 2.0, params={"height_mm": height_mm, "at_m": at_m})


def step_down(height_mm: float = 50.0, at_m: float = LEAD_IN_M) -> Terrain:
    h = height_mm * MM
    return _profile("step_down", [_flat(-LEAD_IN_M, at_m, h), _flat(at_m, at_m + RUN_OUT_M)],
                    length=at_m + 2.0, params={"height_mm": height_mm, "at_m": at_m})


def square_edge(height_mm: float = 50.0, width_mm: float = 100.0, at_m: float = LEAD_IN_M) -> Terrain:
    """A square-edged block (a curb, a sleeper) ``height_mm`` high and ``width_mm`` long."""
    h, w = height_mm * MM, width_mm * MM
    return _profile("square_edge", [_flat(-LEAD_IN_M, at_m), _flat(at_m, at_m + w, h),
                                    _flat(at_m + w, at_m + w + RUN_OUT_M)],
                    length=at_m + w + 2.0, params={"height_mm": height_mm, "width_mm": width_mm, "at_m": at_m})


def _arc(cx: float, a: float, b: float, n: int):
    """Upper half-ellipse centred at cx on the ground, semi-axes a (along x) and b (height)."""
    phi = np.linspace(math.pi, 0.0, n)
    return cx + a * np.cos(phi), b * np.sin(phi)


def root(radius_mm: float = 50.0, at_m: float = LEAD_IN_M) -> Terrain:
    """A root lying across the trail: a half-cylinder of ``radius_mm`` (polygon, 181 points:
    the chord sags at most r (1 - cos 0.5 deg) = 4e-5 r below the circle)."""
    r = radius_mm * MM
    ax, az = _arc(at_m + r, r, r, 181)
    return _profile("root", [_flat(-LEAD_IN_M, at_m), (ax[1:-1], az[1:-1]), _flat(at_m + 2 * r, at_m + 2 * r + RUN_OUT_M)],
                    length=at_m + 2 * r + 2.0, params={"radius_mm": radius_mm, "at_m": at_m})


def rock(height_mm: float = 100.0, length_mm: float = 300.0, at_m: float = LEAD_IN_M) -> Terrain:
    """A rock: a half-ellipse ``length_mm`` long and ``height_mm`` high (steep flanks, round top)."""
    h, L = height_mm * MM, length_mm * MM
    ax, az = _arc(at_m + L / 2, L / 2, h, 181)
    return _profile("rock", [_flat(-LEAD_IN_M, at_m), (ax[1:-1], az[1:-1]), _flat(at_m + L, at_m + L + RUN_OUT_M)],
                    length=at_m + L + 2.0, params={"height_mm": height_mm, "length_mm": length_mm, "at_m": at_m})


ROCK_GARDEN = ((0.0, 0.25, 80.0), (0.40, 0.30, 110.0), (0.85, 0.20, 60.0), (1.20, 0.35, 100.0), (1.70, 0.25, 70.0),
               (2.10, 0.30, 90.0), (2.55, 0.20, 50.0))  # (start from at_m m, length m, height mm) of each rock


def rock_garden(height_scale: float = 1.0, at_m: float = LEAD_IN_M) -> Terrain:
    """A rock garden: seven rocks 50-110 mm high (times ``height_scale``) and 0.2-0.35 m long, each a
    half-ellipse sampled at 40 points, 0.1-0.15 m of flat between them, over 2.75 m from ``at_m``."""
    pieces = [_flat(-LEAD_IN_M, at_m)]
    for start, length, height in ROCK_GARDEN:
        ax, az = _arc(at_m + start + length / 2, length / 2, height * MM * height_scale, 41)
        pieces += [(ax[1:-1], az[1:-1]), _flat(at_m + start + length, at_m + start + length + 0.1)]
    end = at_m + ROCK_GARDEN[-1][0] + ROCK_GARDEN[-1][1] + 0.1
    pieces.append(([end + RUN_OUT_M], [0.0]))
    return _profile("rock_garden", pieces, length=end + 2.0, params={"height_scale": height_scale, "at_m": at_m})


def drop(height_mm: float = 300.0, at_m: float = LEAD_IN_M) -> Terrain:
    """Drop to flat: a ledge ``height_mm`` high, then flat ground (a step down taken at speed)."""
    t = step_down(height_mm, at_m)
    return Terrain("drop", t.x, t.z, t.start_x, at_m + 4.0, {"height_mm": height_mm, "at_m": at_m})


def washboard(height_mm: float = 20.0, wavelength_mm: float = 300.0, length_m: float = 60.0,
              at_m: float = LEAD_IN_M) -> Terrain:
    """Washboard (braking bumps): z = h/2 (1 - cos 2 pi s / wavelength), ``height_mm`` peak to
    peak, from ``at_m`` for ``length_m``, sampled at 5 mm (chord sag below 0.02 mm)."""
    h, lam = height_mm * MM, wavelength_mm * MM
    n = int(math.ceil(length_m / lam))
    s = np.linspace(0.0, n * lam, max(2, int(round(n * lam / 0.005)) + 1))
    z = 0.5 * h * (1.0 - np.cos(2 * math.pi * s / lam))
    return _profile("washboard", [_flat(-LEAD_IN_M, at_m), (at_m + s[1:-1], z[1:-1]),
                                  _flat(at_m + n * lam, at_m + n * lam + RUN_OUT_M)],
                    length=at_m + n * lam + 1.0,
                    params={"height_mm": height_mm, "wavelength_mm": wavelength_mm, "length_m": length_m, "at_m": at_m})


def iso8608(road_class: str = "C", seed: int = 0, length_m: float = 100.0, sample_mm: float = 10.0,
            at_m: float = LEAD_IN_M) -> Terrain:
    """Random road profile of ISO 8608 class A-H: displacement PSD Gd(n) = Gd(n0) (n / n0)^-2,
    n0 = 0.1 cycle/m, over 0.011-2.83 cycles/m (the standard's band); spectral synthesis with
    deterministic amplitudes sqrt(2 Gd dn) and seeded uniform random phases (numpy), faded in
    over the first 2 m so the wheel starts on flat."""
    key = str(road_class).upper()
    if key not in ISO8608_GD_N0:
        raise TerrainError(f"iso8608: class {road_class!r} is not one of {', '.join(ISO8608_GD_N0)}")
    dx = sample_mm * MM
    n_pts = int(round(length_m / dx)) + 1
    s = np.arange(n_pts) * dx
    n0, n_lo, n_hi = 0.1, 0.011, 2.83
    dn = 1.0 / max(length_m, 1.0 / n_lo)
    n = np.arange(max(dn, n_lo), n_hi, dn)
    amp = np.sqrt(2.0 * ISO8608_GD_N0[key] * (n / n0) ** -2 * dn)
    phase = np.random.default_rng(int(seed)).uniform(0.0, 2 * math.pi, n.size)
    z = np.zeros(n_pts)
    for k in range(0, n.size, 256):  # chunks: bounded memory for long profiles
        z += (amp[k:k + 256, None] * np.cos(2 * math.pi * n[k:k + 256, None] * s[None, :] + phase[k:k + 256, None])).sum(0)
    fade = np.clip(s / 2.0, 0.0, 1.0)
    fade = fade * fade * (3 - 2 * fade)
    z = (z - z[0]) * fade
    return _profile("iso8608", [_flat(-LEAD_IN_M, at_m), (at_m + s[1:], z[1:]),
                                _flat(at_m + s[-1], at_m + s[-1] + RUN_OUT_M, z[-1])],
                    length=at_m + length_m,
                    params={"class": key, "seed": int(seed), "length_m": length_m, "sample_mm": sample_mm, "at_m": at_m})


def drum(radius_mm: float = 500.0, cleat_height_mm: float = 20.0, cleat_width_mm: float = 40.0,
         cleat_at_deg: float = 30.0, revolutions: float = 2.0) -> DrumTerrain:
    """Drum rig: the wheel stays at x = 0 on top of a drum of ``radius_mm``; a square cleat
    (``cleat_height_mm`` x ``cleat_width_mm``) starts ``cleat_at_deg`` ahead of the top. The
    surface speed is the run's speed; the run lasts ``revolutions`` turns."""
    R, h, w = radius_mm * MM, cleat_height_mm * MM, cleat_width_mm * MM
    if w >= R:
        raise TerrainError("drum: cleat_width_mm must be smaller than radius_mm")
    step = math.radians(0.1)
    base = np.arange(-math.pi, math.pi, step)
    a0 = math.radians(cleat_at_deg)
    half = w / (2 * R)
    out = (base < a0 - half) | (base > a0 + half)
    ang = np.concatenate((base[out], [a0 - half, a0 - half], np.linspace(a0 - half, a0 + half, 9)[1:-1],
                          [a0 + half, a0 + half]))
    rad = np.concatenate((np.full(out.sum(), R), [R, R + h], np.full(7, R + h), [R + h, R]))
    # at equal angles, the order of the wall points must follow the surface: sort by angle, then
    # radius ascending on the leading wall and descending on the trailing one
    key = np.where(np.isclose(ang, a0 + half), -rad, rad)
    order = np.lexsort((key, ang))
    polar = np.column_stack((ang[order], rad[order]))
    xs = np.linspace(-R, R, 401)
    t = DrumTerrain("drum", xs, np.sqrt(np.maximum(R**2 - xs**2, 0)) - R, 0.0, revolutions * 2 * math.pi * R,
                    {"radius_mm": radius_mm, "cleat_height_mm": cleat_height_mm, "cleat_width_mm": cleat_width_mm,
                     "cleat_at_deg": cleat_at_deg, "revolutions": revolutions},
                    True, R, 0.0, polar)
    return t


def from_csv(path: str | Path) -> Terrain:
    """A profile from a CSV record: columns ``distance_m`` (non-decreasing) and ``height_mm``;
    read by ``mtbmj.measured.records.read_record`` (units converted to SI there). The wheel starts
    at the first distance on a flat lead-in at the first height."""
    from mtbmj.measured.records import read_record

    rec = read_record(path)
    if set(rec.units) != {"distance", "height"} or rec.units.get("distance") != "m" or rec.units.get("height") != "mm":
        have = ", ".join(f"{q}_{u}" for q, u in rec.units.items())
        raise TerrainError(f"{path}: terrain CSV needs exactly the columns distance_m, height_mm (has {have})")
    x, z = rec["distance"], rec["height"]
    if x.size < 2:
        raise TerrainError(f"{path}: terrain CSV needs at least 2 rows")
    if np.any(np.diff(x) < 0):
        i = int(np.argmax(np.diff(x) < 0)) + 2
        raise TerrainError(f"{path}: distance_m decreases at data row {i}")
    for text in unit_mistakes(x, z):
        import warnings

        from mtbmj.errors import ConfigWarning

        warnings.warn(f"{path}: {text}", ConfigWarning, stacklevel=2)
    x0 = float(x[0])
    return _profile(Path(path).stem, [_flat(x0 - LEAD_IN_M, x0, z[0]), (x[1:], z[1:]), _flat(x[-1], x[-1] + RUN_OUT_M, z[-1])],
                    start_x=x0, length=float(x[-1] - x0) + 1.0, params={"csv": str(path)})


# A terrain CSV's units, told apart from a careless user's: distances in millimetres make a profile of
# a few metres kilometres long and its steepest grade a thousand times shallower (a 40 mm rock over
# 0.5 m, a grade of 8 %, becomes 0.008 %); heights in metres make a 1.5 m drop 1.5 mm. No trail
# feature a bike is run over (a CSV's, or a library terrain's height_mm or radius_mm) is under
# LEAST_FEATURE_MM high, nor a profile over CSV_LONG_M long with
# every grade under CSV_LEAST_GRADE (a road's camber and drainage are steeper).
CSV_LONG_M = 100.0
CSV_LEAST_GRADE = 0.002
LEAST_FEATURE_MM = 3.0
# Nor is any a wheel rolls up onto (an edge, a step, a rock, a root, a cleat, a bump) over TALLEST_FEATURE_MM
# high, about three times a 29er's wheel radius (370 mm): no wheel climbs a wall; nor a ledge dropped off
# over TALLEST_DROP_MM, the drop the sled's plausible range ends at (mtbmj.config.PLAUSIBLE). Warned, naming the key.
TALLEST_FEATURE_MM = 1000.0
TALLEST_DROP_MM = 5000.0
HEIGHT_KEYS = ("height_mm", "cleat_height_mm")


def unit_mistakes(x, z) -> list[str]:
    """One line for each unit of a terrain CSV (``x`` in m, ``z`` in m as read) that looks mistaken:
    distances in millimetres, heights in metres; none for a plausible profile or a flat one."""
    rise = float(np.ptp(z))
    if rise == 0.0:
        return []
    out = []
    run, dx, dz = float(x[-1] - x[0]), np.diff(x), np.diff(z)
    slope = np.abs(dz[dx > 0] / dx[dx > 0]) if np.any(dx > 0) else np.zeros(0)
    if run > CSV_LONG_M and not np.any(dz[dx == 0]) and (slope.size == 0 or slope.max() < CSV_LEAST_GRADE):
        out.append(f"distance_m spans {run:.6g} m and its steepest grade is {100 * slope.max():.2g} %: distances in "
                   f"millimetres? (a unit mistake: a run across it covers {run:.6g} m)")
    if rise < LEAST_FEATURE_MM * MM:
        out.append(f"height_mm rises and falls by {rise / MM:.3g} mm at most: heights in metres? (a unit mistake: "
                   f"{rise / MM:.3g} m would be {rise / MM * 1000:.4g} mm)")
    return out


# name -> (builder, {parameter: kind}); kinds: "height" (>= 0, mm), "pos" (> 0), "nonneg", "int", "text"
LIBRARY = {
    "flat": (flat, {"length_m": "pos"}),
    "climb": (climb, {"grade_percent": "any", "length_m": "pos", "at_m": "nonneg"}),
    "step_up": (step_up, {"height_mm": "height", "at_m": "nonneg"}),
    "step_down": (step_down, {"height_mm": "height", "at_m": "nonneg"}),
    "square_edge": (square_edge, {"height_mm": "height", "width_mm": "pos", "at_m": "nonneg"}),
    "root": (root, {"radius_mm": "pos", "at_m": "nonneg"}),
    "rock": (rock, {"height_mm": "pos", "length_mm": "pos", "at_m": "nonneg"}),
    "rock_garden": (rock_garden, {"height_scale": "pos", "at_m": "nonneg"}),
    "drop": (drop, {"height_mm": "height", "at_m": "nonneg"}),
    "washboard": (washboard, {"height_mm": "height", "wavelength_mm": "pos", "length_m": "pos", "at_m": "nonneg"}),
    "iso8608": (iso8608, {"class": "text", "seed": "int", "length_m": "pos", "sample_mm": "pos", "at_m": "nonneg"}),
    "drum": (drum, {"radius_mm": "pos", "cleat_height_mm": "height", "cleat_width_mm": "pos",
                    "cleat_at_deg": "any", "revolutions": "pos"}),
}
ARGUMENT = {"class": "road_class"}


def parse(spec: str) -> tuple[str, dict]:
    """``"name:key=value,key=value"`` -> (name, {key: value})."""
    name, _, rest = str(spec).strip().partition(":")
    params = {}
    for item in filter(None, (p.strip() for p in rest.split(","))):
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            raise TerrainError(f"terrain {spec!r}: expected key=value, got {item!r}")
        if key.strip() in params:
            raise TerrainError(f"terrain {spec!r}: {key.strip()} given twice ({params[key.strip()]!r} and "
                               f"{value.strip()!r}); give it once")
        params[key.strip()] = value.strip()
    return name.strip(), params


def _value(name: str, key: str, kind: str, value):
    if kind == "text":
        return str(value)
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise TerrainError(f"terrain {name}: {key} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise TerrainError(f"terrain {name}: {key} must be finite, got {value!r}")
    if kind == "int":
        if number != int(number) or number < 0:
            raise TerrainError(f"terrain {name}: {key} must be a non-negative integer, got {value!r}")
        return int(number)
    if kind in ("height", "nonneg") and number < 0:
        raise TerrainError(f"terrain {name}: {key} must not be negative, got {number:g}")
    if kind == "pos" and number <= 0:
        raise TerrainError(f"terrain {name}: {key} must be positive, got {number:g}")
    if key.endswith("_mm") and key != "sample_mm":  # a feature's size (a wavelength, a width too), not a sampling
        if 0.0 < number < LEAST_FEATURE_MM:
            import warnings

            from mtbmj.errors import ConfigWarning

            warnings.warn(f"terrain {name}: {key} = {number:g} mm is under {LEAST_FEATURE_MM:g} mm, smaller than any "
                          f"trail feature (a unit mistake? {number:g} m is {key}={number * 1000:g})", ConfigWarning,
                          stacklevel=3)
        tallest = TALLEST_DROP_MM if name in ("drop", "step_down") else TALLEST_FEATURE_MM
        if (key in HEIGHT_KEYS or (name, key) == ("root", "radius_mm")) and number > tallest:
            import warnings

            from mtbmj.errors import ConfigWarning

            warnings.warn(f"terrain {name}: {key} = {number:g} mm is over {tallest:g} mm, taller than any trail "
                          f"feature a wheel {'drops off' if tallest == TALLEST_DROP_MM else 'rolls over'} "
                          f"(a unit mistake?)", ConfigWarning, stacklevel=3)
    tallest_rock = max(height for _, _, height in ROCK_GARDEN)
    if (name, key) == ("rock_garden", "height_scale") and number * tallest_rock > TALLEST_FEATURE_MM:
        import warnings

        from mtbmj.errors import ConfigWarning

        warnings.warn(f"terrain {name}: {key} = {number:g} makes its tallest rock {number * tallest_rock:g} mm, over "
                      f"{TALLEST_FEATURE_MM:g} mm, taller than any trail feature a wheel rolls over ({key} scales "
                      f"rocks {min(h for _, _, h in ROCK_GARDEN):g}-{tallest_rock:g} mm high; 1 is the garden as "
                      f"shipped)", ConfigWarning, stacklevel=3)
    return number


def _not_a_profile(text: str) -> None:
    """Refuse a folder or a JSON file given as the terrain (a folder of ``mtbmj reconstruct``, its
    reconstruction.json), naming the profile beside it (its terrain.csv) where there is one."""
    beside = Path(text) / "terrain.csv" if Path(text).is_dir() else Path(text).with_name("terrain.csv")
    raise TerrainError(f"terrain {text}: not a terrain profile (a scenario name or a CSV of distance_m, height_mm)"
                       + (f"; the reconstruction's terrain is {beside}" if beside.is_file() else ""))


def make(spec, **params) -> Terrain:
    """A terrain from a spec string (``"root:radius_mm=60"``), a CSV path, or a ``Terrain``;
    keyword parameters override those in the string."""
    if isinstance(spec, Terrain):
        if params:
            raise TerrainError("terrain: parameters given with a ready-made Terrain")
        return spec
    text = str(spec)
    if Path(text).suffix.lower() == ".json" and Path(text).is_file():
        _not_a_profile(text)
    if text.lower().endswith(".csv") or (Path(text).suffix and Path(text).exists()):
        if params:
            raise TerrainError(f"terrain {text}: a CSV profile takes no parameters")
        return from_csv(text)
    name, given = parse(text)
    given.update(params)
    if name not in LIBRARY and name.lower() in LIBRARY:  # "Rock" is rock, as presets are named in any case
        name = name.lower()
    if name not in LIBRARY and Path(text).is_dir():
        _not_a_profile(text)
    if name not in LIBRARY:
        raise TerrainError(f"terrain: unknown scenario {name!r} (known: {', '.join(LIBRARY)}, or a .csv profile)")
    builder, kinds = LIBRARY[name]
    kwargs = {}
    for key, value in given.items():
        if key not in kinds:
            raise TerrainError(f"terrain {name}: unknown parameter {key!r} (known: {', '.join(kinds)})")
        kwargs[ARGUMENT.get(key, key)] = _value(name, key, kinds[key], value)
    _check_size(name, given, kwargs)
    return builder(**kwargs)


# A terrain longer than this, or sampled at more points, is refused before anything is allocated
# (a run of 2 km is 400 s at 5 m/s; ``washboard:length_m=1e9`` asked for 1.46 TiB); so is a feature longer than
# that (``washboard:wavelength_mm=1e9``, one wave of 1000 km sampled at 5 mm, asked for 38.7 GiB).
MAX_LENGTH_M = 2000.0
MAX_POINTS = 1_000_000
# The surface of a library terrain or a CSV profile (its distances, and its heights up and down) the tyre's
# search cuts into 1 cm pieces of 32 bytes (mtbmj.rolling.search_compiled.piece_table): 100 km is 320 MB of them.
# A CSV's distances typed in millimetres run with their warning (an 8 m profile, 8 km: tests/test_rolling.py);
# ``rock:height_mm=1e12`` asked for 5.82 TiB, a 10 km profile typed in millimetres (1e7 m) for 29.8 GiB.
MAX_SURFACE_M = 100_000.0

def _check_size(name: str, given: dict, kwargs: dict) -> None:
    for key in ("length_m", "at_m"):
        if key in given and kwargs[ARGUMENT.get(key, key)] > MAX_LENGTH_M:
            raise TerrainError(f"terrain {name}: {key} = {kwargs[ARGUMENT.get(key, key)]:g} m is longer than the "
                               f"{MAX_LENGTH_M:g} m a terrain may be")
    for key in ("width_mm", "length_mm", "wavelength_mm", "radius_mm"):
        if key in given and kwargs[key] * MM > MAX_LENGTH_M:
            raise TerrainError(f"terrain {name}: {key} = {kwargs[key]:g} mm is {kwargs[key] * MM:g} m, longer than the "
                               f"{MAX_LENGTH_M:g} m a terrain may be")
    if name == "iso8608":
        length = kwargs.get("length_m", 100.0)
        sample = kwargs.get("sample_mm", 10.0) * MM
        if length / sample + 1 > MAX_POINTS:
            raise TerrainError(f"terrain {name}: length_m / sample_mm gives {length / sample + 1:.3g} profile points, "
                               f"more than the {MAX_POINTS:,} a terrain may have (a larger sample_mm or a shorter length_m)")


def names() -> list[str]:
    return list(LIBRARY)


__all__ = ["Terrain", "DrumTerrain", "TerrainError", "LIBRARY", "make", "parse", "names", "flat", "climb", "on_grade", "step_up",
           "step_down", "square_edge", "root", "rock", "rock_garden", "drop", "washboard", "iso8608", "drum", "from_csv"]

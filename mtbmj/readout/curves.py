"""The fork's characteristic curves as a rider reads them: spring force against travel and damper
force against velocity, computed from the same laws the engines integrate
(``mtbmj.compose.fork_law``), drawn with matplotlib's object API and written as CSV.

Spring curve (``spring_curve``): force (N, pushing the fork apart positive) against travel (mm,
compression positive) at rest (v = 0), from the top stop (x = -``fork.stops.extension_mm``, where
the top-out bumper is fully compressed) to full travel, split into its parts:

* the main spring with its preload (an air fork: the air force, its own preload the force at full
  extension),
* the top-out spring, -k_t max(0, x_e - x) with x_e = preload / k_t (``controllers.spring.TopOutSpring``),
* the bottom-out bumper, F_b ((x - x_b) / L_b)^2 over its last L_b of travel (``controllers.stops``),

and their sum. The hard stops sit outside the drawn range (their force is zero up to the range's
ends), so the y range is the spring's own, not the stops' millions of newtons. A spring with
separate compression and rebound curves is also drawn on each stroke. The static sag is where the
at-rest force carries the load, F(x_sag) = m g with m = ``sled.body_mass_kg`` (friction and
damping carry nothing at rest; the same balance ``mtbmj.drop.sag`` solves for a setting).

Damper curve (``damper_curve``): the hydraulic force against velocity (mm/s, compression
positive), the friction while sliding (its steady state: F_C sgn(v) + F_v v or the Stribeck /
LuGre level) and their sum (what a dyno measures). A clicks damper (``fork.damper.model =
"clicks"``) gets one line per whole click of each adjuster over its measured positions, the other
adjusters at their settings.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np
from scipy.optimize import brentq

from mtbmj import compose, output
from mtbmj.config import Config
from mtbmj.controllers import friction as friction_laws
from mtbmj.controllers.spring import DirectionalSpring, TopOutSpring
from mtbmj.controllers.stops import EndStops
from mtbmj.errors import ConfigError

MM = 1e-3
POINTS = 601  # points along the travel
STROKE_SPEED = 1.0  # m/s: the speed at which a directional spring is on its compression / rebound curve
DEFAULT_VELOCITY_MM_PER_S = 1500.0  # damper curves without a table: a dyno's usual range (a sled hits at 1.4 m/s)
MAX_VELOCITY_MM_PER_S = 20000.0
AIR_TOKENS = 3  # the air progression shows 0 .. max(this, the configured number) volume spacers
ADJUSTERS = ("compression", "rebound", "low_speed_compression", "high_speed_compression",
             "low_speed_rebound", "high_speed_rebound")


# --- spring -----------------------------------------------------------------------------------------

@dataclass
class SpringCurve:
    """A fork spring's curve at rest over ``travel_mm`` (see the module doc); forces in N."""

    config: Config
    travel_mm: np.ndarray
    spring_N: np.ndarray  # the sum at rest (v = 0)
    main_N: np.ndarray  # main spring with its preload (air: the air force)
    top_out_N: np.ndarray
    bumper_N: np.ndarray
    compression_N: np.ndarray | None  # on the compression / rebound stroke, for a directional spring only
    rebound_N: np.ndarray | None
    model: str
    full_travel_mm: float
    extension_mm: float
    bumper_start_mm: float
    bumper_force_N: float
    preload_N: float  # coil: fork.spring.preload_N (0 without); air: the air force at full extension
    top_out_engagement_mm: float | None  # x_e; None without a top-out spring
    load_kg: float
    load_N: float
    sag_mm: float | None  # None: the spring does not carry the load anywhere in its travel

    @property
    def sag_percent(self) -> float | None:
        return None if self.sag_mm is None else 100.0 * self.sag_mm / self.full_travel_mm

    @property
    def name(self) -> str:
        return self.config.name

    def columns(self) -> dict[str, np.ndarray]:
        cols = {"travel_mm": self.travel_mm, "spring_N": self.spring_N}
        if self.compression_N is not None:
            cols["spring_compression_stroke_N"] = self.compression_N
            cols["spring_rebound_stroke_N"] = self.rebound_N
        cols.update({"main_spring_N": self.main_N, "top_out_N": self.top_out_N, "bumper_N": self.bumper_N})
        return cols

    def summary(self) -> dict:
        def mm(value):
            return None if value is None else round(float(value), 9)

        return {"config": self.name, "spring_model": self.model, "full_travel_mm": mm(self.full_travel_mm),
                "top_stop_mm": mm(-self.extension_mm), "bumper_start_mm": mm(self.bumper_start_mm),
                "bumper_force_N": self.bumper_force_N, "preload_N": self.preload_N,
                "top_out_engagement_mm": mm(self.top_out_engagement_mm), "load_kg": self.load_kg,
                "load_N": self.load_N, "sag_mm": self.sag_mm, "sag_percent": self.sag_percent,
                "spring_at_full_travel_N": float(self.spring_N[-1])}


def _parts(law) -> tuple[object, object]:
    """(end stops or None, the main spring inside them) of a fork spring law."""
    if isinstance(law, EndStops):
        return law, law.main
    return None, law


def _is_directional(law) -> bool:
    while law is not None:
        if isinstance(law, DirectionalSpring):
            return True
        law = getattr(law, "main", None)
    return False


def _knee(law) -> float | None:
    """A bilinear spring's knee (m) anywhere in the chain of wrapped laws, else None."""
    while law is not None:
        if hasattr(law, "knee"):
            return law.knee
        law = getattr(law, "main", None) or getattr(law, "compression", None)
    return None


def static_sag(spring, weight_N: float, travel: float) -> float | None:
    """Compression (m) where ``spring`` at rest carries ``weight_N``: 0 when it carries it at full
    extension already, ``None`` when it does not carry it anywhere up to ``travel`` (the fork
    would rest on its hard stop)."""
    def excess(x):
        return spring.force(x, 0.0) - weight_N

    if excess(0.0) >= 0.0:
        return 0.0
    if excess(travel) < 0.0:
        return None
    grid = np.linspace(0.0, travel, 241)  # the first crossing (a curve that dips back would have several)
    values = np.array([excess(x) for x in grid])
    i = int(np.flatnonzero(values >= 0.0)[0])
    return brentq(excess, grid[i - 1], grid[i], xtol=1e-12, rtol=1e-14)


def _grid(travel: float, extension: float, marks, points: int) -> np.ndarray:
    """Compression points (m) from the top stop to full travel, the laws' kinks among them."""
    x = np.linspace(-extension, travel, points)
    extra = [m for m in marks if m is not None and -extension < m < travel]
    return np.unique(np.concatenate([x, [0.0], extra]))


def spring_curve(config: Config | str, overrides: Mapping | None = None, points: int = POINTS,
                 travel_mm: np.ndarray | None = None) -> SpringCurve:
    """The spring curve of ``config`` (a preset name, TOML path or ``Config``); ``travel_mm`` a
    grid to use instead of the default one (it should stay within the top stop and full travel)."""
    from mtbmj.config import resolve

    cfg = resolve(config, overrides)
    setup = compose.setup(cfg)  # the whole configuration is valid (one line naming the key otherwise)
    law = setup.fork.spring
    stops, main = _parts(law)
    travel = setup.travel
    extension = stops.extension if stops is not None else 0.0
    top = main if isinstance(main, TopOutSpring) else None
    engagement = top.engagement if top is not None else None
    knee = _knee(main)
    if travel_mm is None:
        x = _grid(travel, extension, [engagement, stops.bumper_start if stops else None, knee], points)
    else:
        x = np.asarray(travel_mm, dtype=float) * MM

    def at(v):
        return np.array([law.force(xi, v) for xi in x])

    spring = at(0.0)
    bumper = np.array([stops.stop_forces(xi, 0.0)[0] for xi in x]) if stops is not None else np.zeros_like(x)
    if top is not None:
        top_out = -top.top_out_rate * np.maximum(0.0, top.engagement - x)
        main_part = np.array([top.preload + top.main.force(xi, 0.0) for xi in x])
    else:
        top_out = np.zeros_like(x)
        main_part = np.array([main.force(xi, 0.0) for xi in x])
    compression = rebound = None
    if _is_directional(main):
        compression, rebound = at(STROKE_SPEED), at(-STROKE_SPEED)
    model = cfg.require("fork.spring.model")
    preload = top.preload if top is not None else 0.0  # an air spring's: its force at full extension
    weight = setup.body_mass * setup.gravity
    sag = static_sag(law, weight, travel)
    return SpringCurve(
        config=cfg, travel_mm=x / MM, spring_N=spring, main_N=main_part, top_out_N=top_out, bumper_N=bumper,
        compression_N=compression, rebound_N=rebound, model=model, full_travel_mm=travel / MM,
        extension_mm=extension / MM, bumper_start_mm=(stops.bumper_start if stops else travel) / MM,
        bumper_force_N=stops.bumper_force if stops else 0.0, preload_N=float(preload),
        top_out_engagement_mm=None if engagement is None else engagement / MM, load_kg=setup.body_mass,
        load_N=weight, sag_mm=None if sag is None else sag / MM)


def air_progression(curve: SpringCurve) -> dict[str, SpringCurve]:
    """An air fork's curve with 0 .. max(3, configured) volume spacers at its pressure, on the same
    travel grid (label -> curve); spacer counts the chamber cannot hold are left out."""
    if curve.model != "air":
        return {}
    configured = int(curve.config.get("fork.spring.tokens", 0.0))
    curves = {}
    for n in range(0, max(AIR_TOKENS, configured) + 1):
        try:
            curves[f"{n} spacer{'' if n == 1 else 's'}"] = spring_curve(
                curve.config.with_overrides({"fork.spring.tokens": float(n)}), travel_mm=curve.travel_mm)
        except ConfigError:
            continue
    return curves


def _label(curve: SpringCurve) -> str:
    c = curve.config
    if curve.model == "air":
        n = c.get("fork.spring.tokens", 0.0)
        return f"air {c['fork.spring.air_pressure_psi']:g} psi, {n:g} spacer{'' if n == 1 else 's'}"
    return f"{curve.model} coil" + (f", preload {curve.preload_N:g} N" if curve.preload_N else "")


def physical_ylim(ax, arrays, pad: float = 0.06) -> tuple[float, float]:
    """Set the y range of ``ax`` to span ``arrays`` (finite values) with a margin; returns it."""
    values = np.concatenate([np.ravel(np.asarray(a, dtype=float)) for a in arrays])
    values = values[np.isfinite(values)]
    lo, hi = float(values.min()), float(values.max())
    span = hi - lo if hi > lo else max(abs(hi), 1.0)
    limits = (lo - pad * span, hi + pad * span)
    ax.set_ylim(*limits)
    return limits


def _travel_axes(ax, curve: SpringCurve) -> None:
    """Labels, the stroke's ends and the bumper zone; x range the drawn stroke."""
    ax.axvspan(curve.bumper_start_mm, curve.full_travel_mm, color="tab:red", alpha=0.07, lw=0)
    ax.axvline(curve.full_travel_mm, color="0.35", lw=1.0)
    ax.axvline(0.0, color="0.7", lw=0.6)
    at = ax.get_xaxis_transform()  # x in data, y in axes fraction
    ax.text(curve.full_travel_mm, 0.02, "full travel: hard stop", transform=at, rotation=90, ha="right",
            va="bottom", fontsize=7, color="0.35")
    ax.text(curve.bumper_start_mm, 0.02, " bumper ", transform=at, rotation=90, ha="right", va="bottom",
            fontsize=7, color="tab:red")
    if curve.extension_mm > 0:
        ax.axvline(-curve.extension_mm, color="0.35", lw=1.0)
        ax.text(-curve.extension_mm, 0.45, " top stop", transform=at, rotation=90, ha="left", va="center",
                fontsize=7, color="0.35")
    ax.axhline(0.0, color="0.7", lw=0.6)
    ax.set_xlim(float(curve.travel_mm[0]), float(curve.travel_mm[-1]))
    ax.set_xlabel("fork travel (mm), compression positive")
    ax.set_ylabel("force (N), pushing the fork apart positive")
    ax.grid(alpha=0.3)


def _mark_sag(ax, curve: SpringCurve, color="black", text: bool = True) -> None:
    if curve.sag_mm is None:
        if text:
            ax.annotate(f"the spring does not carry {curve.load_kg:g} kg: no sag (rests on the hard stop)",
                        xy=(0.02, 0.6), xycoords="axes fraction", fontsize=8)
        return
    ax.plot([curve.sag_mm], [curve.load_N], "o", color=color, ms=5, zorder=5)
    if text:
        ax.annotate(f"sag {curve.sag_mm:.1f} mm ({curve.sag_percent:.0f} %)\nunder {curve.load_kg:g} kg",
                    xy=(curve.sag_mm, curve.load_N), xytext=(-8, 12), textcoords="offset points", fontsize=8,
                    ha="right")


def draw_spring(ax, curve: SpringCurve) -> None:
    """The curve and its parts on ``ax``: sum (black), main spring, preload, top-out, bumper, the
    load (dotted) and the sag (dot), the full travel and the top stop (grey verticals)."""
    drawn = [curve.spring_N, curve.main_N, curve.top_out_N, curve.bumper_N]
    ax.plot(curve.travel_mm, curve.spring_N, color="black", lw=2.0, label="spring at rest (sum)")
    if curve.compression_N is not None:
        ax.plot(curve.travel_mm, curve.compression_N, color="0.3", lw=1.0, ls="--", label="on the compression stroke")
        ax.plot(curve.travel_mm, curve.rebound_N, color="0.3", lw=1.0, ls=":", label="on the rebound stroke")
        drawn += [curve.compression_N, curve.rebound_N]
    main_label = ("air spring" if curve.model == "air" else "main spring" +
                  (" + preload" if curve.preload_N else ""))
    ax.plot(curve.travel_mm, curve.main_N, color="tab:blue", lw=1.2, label=main_label)
    if curve.preload_N and curve.model != "air":
        ax.axhline(curve.preload_N, color="tab:blue", lw=0.8, ls="--", label=f"preload {curve.preload_N:g} N")
    if curve.top_out_engagement_mm is not None:
        ax.plot(curve.travel_mm, curve.top_out_N, color="tab:orange", lw=1.2, label="top-out spring")
    ax.plot(curve.travel_mm, curve.bumper_N, color="tab:red", lw=1.2,
            label=f"bottom-out bumper ({curve.bumper_force_N:g} N at full travel)")
    ax.axhline(curve.load_N, color="0.5", ls=":", lw=1.0, label=f"load {curve.load_kg:g} kg x g")
    _mark_sag(ax, curve)
    _travel_axes(ax, curve)
    physical_ylim(ax, drawn + [[curve.load_N]])
    ax.legend(fontsize=7.5, loc="upper left")


def draw_spring_totals(ax, curves: Mapping[str, SpringCurve], title: str = "") -> None:
    """The at-rest sum of several curves on ``ax`` (one line each, labelled), each one's sag as a
    dot in its colour and the load as a dotted line when they share one."""
    first = next(iter(curves.values()))
    for label, curve in curves.items():
        line, = ax.plot(curve.travel_mm, curve.spring_N, lw=1.4, label=label)
        _mark_sag(ax, curve, color=line.get_color(), text=False)
    loads = {round(c.load_N, 9) for c in curves.values()}
    for load in loads:
        ax.axhline(load, color="0.5", ls=":", lw=1.0)
    _travel_axes(ax, first)
    physical_ylim(ax, [c.spring_N for c in curves.values()] + [list(loads)])
    ax.legend(fontsize=8, loc="upper left")
    if title:
        ax.set_title(title, fontsize=9)


def spring_figure(curve: SpringCurve, progression: Mapping[str, SpringCurve] | None = None):
    """The spring curve's figure: its parts; an air fork's 0-3 spacer progression beside it."""
    from matplotlib.figure import Figure

    progression = air_progression(curve) if progression is None else progression
    if progression:
        fig = Figure(figsize=(12, 4.8), layout="constrained")
        left, right = fig.subplots(1, 2)
        draw_spring_totals(right, progression, f"(b) air progression: volume spacers at "
                                               f"{curve.config['fork.spring.air_pressure_psi']:g} psi; dots: sag")
        left.set_title("(a) spring and its parts", fontsize=9)
    else:
        fig = Figure(figsize=(7.5, 4.8), layout="constrained")
        left = fig.subplots(1, 1)
    draw_spring(left, curve)
    fig.suptitle(f"{curve.name}: fork spring curve ({_label(curve)}), top stop to full travel")
    return fig


# --- damper -----------------------------------------------------------------------------------------

@dataclass
class ClickLines:
    """One adjuster's curves: the damper force at each whole click over its stroke's velocities."""

    adjuster: str  # e.g. "rebound", "low_speed_compression"
    stroke: str  # "compression" or "rebound"
    setting: float  # fork.damper.<adjuster>_clicks
    velocity_mm_per_s: np.ndarray
    force_N: dict[int, np.ndarray]  # clicks -> hydraulic force
    refused: dict[int, str] = field(default_factory=dict)  # clicks the model refuses with the others' settings

    @property
    def key(self) -> str:
        return f"fork.damper.{self.adjuster}_clicks"


@dataclass
class DamperCurve:
    config: Config
    velocity_mm_per_s: np.ndarray
    damper_N: np.ndarray  # hydraulic
    friction_N: np.ndarray  # sliding friction (steady state)
    model: str
    friction_model: str
    clicks: list[ClickLines]

    @property
    def total_N(self) -> np.ndarray:
        return self.damper_N + self.friction_N

    @property
    def name(self) -> str:
        return self.config.name

    def columns(self) -> dict[str, np.ndarray]:
        return {"velocity_mm_per_s": self.velocity_mm_per_s, "damper_N": self.damper_N,
                "friction_N": self.friction_N, "total_N": self.total_N}

    def clicks_csv(self) -> bytes:
        """One row per (adjuster, click, velocity): the hydraulic force and with friction."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(["adjuster_key", "clicks", "setting_clicks", "velocity_mm_per_s", "damper_N", "total_N"])
        for lines in self.clicks:
            v = lines.velocity_mm_per_s
            friction = sliding_friction(compose.fork_law(self.config).friction, v * MM)
            for click, force in lines.force_N.items():
                for vi, fi, ri in zip(v, force, friction):
                    writer.writerow([lines.key, click, f"{lines.setting:g}", f"{vi:.9g}", f"{fi:.9g}",
                                     f"{fi + ri:.9g}"])
        return buffer.getvalue().encode()

    def summary(self) -> dict:
        return {"damper_model": self.model, "friction_model": self.friction_model,
                "velocity_range_mm_per_s": [float(self.velocity_mm_per_s[0]), float(self.velocity_mm_per_s[-1])],
                "clicks": {lines.key: {"setting": lines.setting, "drawn": sorted(lines.force_N),
                                       "refused": {str(k): why for k, why in lines.refused.items()}}
                           for lines in self.clicks}}


def sliding_friction(law, v: np.ndarray) -> np.ndarray:
    """The friction force (N) while sliding steadily at each velocity of ``v`` (m/s): a static
    law as it is; a sticking law its wrapped law (what it slides at); LuGre its steady state
    g(v) sgn(v) + sigma2 v (dz/dt = 0)."""
    v = np.asarray(v, dtype=float)
    if isinstance(law, friction_laws.Sticking):
        law = law.inner
    if isinstance(law, friction_laws.LuGre):
        return np.array([law.g(vi) * np.sign(vi) + law.viscous * vi for vi in v])
    return np.array([law.force(vi) for vi in v])


def _velocity_grid(top: float, marks=()) -> np.ndarray:
    """Velocities (m/s) from -top to top, dense near 0 where friction turns, and ``marks`` (a
    table's velocities, its kinks) within the range."""
    near = np.geomspace(1e-4, min(0.05, top / 2), 40)
    inside = [m for m in marks if -top < m < top]
    grid = np.concatenate([np.linspace(-top, top, 401), near, -near, [0.0], inside])
    return np.unique(grid)


def _table_top(damper) -> float | None:
    velocity = getattr(damper, "velocity", None)
    return max(abs(velocity[0]), abs(velocity[-1])) if velocity else None


def damper_curve(config: Config | str, overrides: Mapping | None = None,
                 max_velocity_mm_per_s: float | None = None) -> DamperCurve:
    """The damper curve of ``config`` up to ``max_velocity_mm_per_s`` in each direction (default:
    a lookup table's range, else 1500 mm/s)."""
    from mtbmj.config import resolve

    cfg = resolve(config, overrides)
    compose.setup(cfg)
    fork = compose.fork_law(cfg)
    if max_velocity_mm_per_s is not None:
        if not (math.isfinite(max_velocity_mm_per_s) and 0 < max_velocity_mm_per_s <= MAX_VELOCITY_MM_PER_S):
            raise ConfigError(f"--max-velocity-mm-per-s: must be in (0, {MAX_VELOCITY_MM_PER_S:g}] mm/s, "
                              f"got {max_velocity_mm_per_s:g}")
        top = max_velocity_mm_per_s * MM
    else:
        top = _table_top(fork.damper) or DEFAULT_VELOCITY_MM_PER_S * MM
    v = _velocity_grid(top, getattr(fork.damper, "velocity", ()))
    damper = np.array([fork.damper.force(vi) for vi in v])
    friction = sliding_friction(fork.friction, v)
    model = cfg.require("fork.damper.model")
    clicks = _click_lines(cfg, v) if model == "clicks" else []
    return DamperCurve(cfg, v / MM, damper, friction, model, cfg.get("fork.friction.model", "none"), clicks)


def _click_lines(cfg: Config, v: np.ndarray) -> list[ClickLines]:
    out = []
    for adjuster in ADJUSTERS:
        measured = cfg.get(f"fork.damper.{adjuster}_clicks_measured")
        if measured is None:
            continue
        stroke = "compression" if adjuster.endswith("compression") else "rebound"
        side = v >= 0.0 if stroke == "compression" else v <= 0.0
        lines = ClickLines(adjuster, stroke, float(cfg[f"fork.damper.{adjuster}_clicks"]), v[side] / MM, {})
        for click in range(int(measured[0]), int(measured[-1]) + 1):
            try:
                law = compose.fork_law(cfg.with_overrides({lines.key: float(click)})).damper
            except ConfigError as exc:  # e.g. the additive low/high-speed model falls at this pair
                lines.refused[click] = str(exc)
                continue
            lines.force_N[click] = np.array([law.force(vi) for vi in v[side]])
        out.append(lines)
    return out


def _adjuster_title(lines: ClickLines) -> str:
    return f"{lines.adjuster.replace('_', ' ')} adjuster: one line per click (setting {lines.setting:g})"


def draw_clicks(ax, lines: ClickLines) -> None:
    """One line per click (viridis from closed to open), the setting's line black and thick."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    clicks = sorted(lines.force_N)
    norm = Normalize(min(clicks), max(max(clicks), min(clicks) + 1))
    cmap = colormaps["viridis"]
    for click in clicks:
        setting = click == lines.setting
        ax.plot(lines.velocity_mm_per_s, lines.force_N[click], color="black" if setting else cmap(norm(click)),
                lw=2.2 if setting else 1.0, zorder=3 if setting else 2,
                label=f"{click} clicks" + (" (setting)" if setting else ""))
    if len(clicks) <= 8:
        ax.legend(fontsize=7.5, loc="upper left" if lines.stroke == "compression" else "lower right")
    else:
        bar = ax.figure.colorbar(ScalarMappable(norm, cmap), ax=ax, pad=0.01)
        bar.set_label("clicks from closed (black: the setting)", fontsize=8)
    ax.set_title(_adjuster_title(lines), fontsize=9)
    _velocity_axes(ax)
    physical_ylim(ax, list(lines.force_N.values()))


def _velocity_axes(ax) -> None:
    ax.axhline(0.0, color="0.7", lw=0.6)
    ax.axvline(0.0, color="0.7", lw=0.6)
    ax.set_xlabel("velocity (mm/s), compression positive")
    ax.set_ylabel("force (N)")
    ax.grid(alpha=0.3)


def draw_damper(ax, curve: DamperCurve) -> None:
    ax.plot(curve.velocity_mm_per_s, curve.total_N, color="black", lw=2.0, label="damper + friction (a dyno's curve)")
    ax.plot(curve.velocity_mm_per_s, curve.damper_N, color="tab:blue", lw=1.2, label=f"hydraulic ({curve.model})")
    ax.plot(curve.velocity_mm_per_s, curve.friction_N, color="tab:green", lw=1.2,
            label=f"friction while sliding ({curve.friction_model})")
    _velocity_axes(ax)
    ax.set_xlim(float(curve.velocity_mm_per_s[0]), float(curve.velocity_mm_per_s[-1]))
    physical_ylim(ax, [curve.total_N, curve.damper_N, curve.friction_N])
    ax.legend(fontsize=7.5, loc="upper left")


def damper_figure(curve: DamperCurve):
    """The damper's figure: hydraulic, friction and their sum at the settings; with clicks, one
    panel per adjuster with one line per click."""
    from matplotlib.figure import Figure

    n = 1 + len(curve.clicks)
    cols = 1 if n == 1 else 2
    rows = (n + cols - 1) // cols
    fig = Figure(figsize=(7.5 if cols == 1 else 12, 4.6 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    draw_damper(axes[0], curve)
    if curve.clicks:
        axes[0].set_title("(a) at the settings", fontsize=9)
    for ax, lines in zip(axes[1:], curve.clicks):
        draw_clicks(ax, lines)
    for ax in axes[n:]:
        ax.set_visible(False)
    fig.suptitle(f"{curve.name}: fork damper curve, compression (> 0) and rebound (< 0)")
    return fig


# --- output -----------------------------------------------------------------------------------------

@dataclass
class Curves:
    """Both curves of one configuration (what ``mtbmj curve`` writes)."""

    spring: SpringCurve
    progression: dict[str, SpringCurve]
    damper: DamperCurve

    def line(self) -> str:
        s = self.spring
        sag = (f"sag {s.sag_mm:.1f} mm ({s.sag_percent:.0f} % of {s.full_travel_mm:g} mm)" if s.sag_mm is not None
               else "no sag: the spring does not carry the load anywhere in its travel")
        clicks = "".join(f", {len(c.force_N)} clicks of {c.adjuster.replace('_', ' ')}" for c in self.damper.clicks)
        return (f"{s.name}: spring {s.spring_N[-1]:.0f} N at full travel ({s.bumper_force_N:g} N of it the bumper), "
                f"{sag} under {s.load_kg:g} kg; damper {self.damper.model}, friction {self.damper.friction_model}"
                f"{clicks}")

    def files(self) -> dict[str, bytes]:
        from mtbmj.readout.quicklook import png

        spring_cols = self.spring.columns()
        for label, curve in self.progression.items():
            spring_cols[f"spring_{label.split()[0]}_spacers_N"] = curve.spring_N
        files = {
            "spring_curve.png": png(spring_figure(self.spring, self.progression), dpi=110),
            "spring_curve.csv": output.csv_bytes(spring_cols, f"mtbmj curve {self.spring.name}: fork spring at rest "
                                                 "(v = 0), compression positive; hard stops outside the range"),
            "damper_curve.png": png(damper_figure(self.damper), dpi=110),
            "damper_curve.csv": output.csv_bytes(self.damper.columns(), f"mtbmj curve {self.damper.name}: fork damper "
                                                 "at its settings, compression positive; friction while sliding"),
            "curve.json": output.json_bytes({**self.spring.summary(), **self.damper.summary()}),
            "config.toml": self.spring.config.to_toml().encode(),
        }
        if self.damper.clicks:
            files["damper_clicks.csv"] = self.damper.clicks_csv()
        return files

    def write(self, out_dir: str | Path) -> list[Path]:
        """``out_dir`` holding the figures, tables and configuration, all at once or not at all."""
        return output.write_atomically(out_dir, self.files())


def fork_curves(config: Config | str, overrides: Mapping | None = None,
                max_velocity_mm_per_s: float | None = None) -> Curves:
    """The spring and damper curves of ``config`` (preset name, TOML path or ``Config``)."""
    from mtbmj.config import resolve

    cfg = resolve(config, overrides)
    spring = spring_curve(cfg)
    return Curves(spring, air_progression(spring), damper_curve(cfg, max_velocity_mm_per_s=max_velocity_mm_per_s))


__all__ = ["SpringCurve", "DamperCurve", "ClickLines", "Curves", "spring_curve", "damper_curve", "fork_curves",
           "air_progression", "static_sag", "sliding_friction", "spring_figure", "damper_figure", "draw_spring",
           "draw_spring_totals", "draw_damper", "draw_clicks", "physical_ylim"]

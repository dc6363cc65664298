"""Turn a validated ``Config`` into SI force-law objects and check the cross-key rules.

This is the one place where external units (mm, N/mm, mm/s) become SI (m, N/m, m/s). The step
``setup`` gives a run comes from the step rule, ``mtbmj.runpath.steprule``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtbmj import controllers as law
from mtbmj.config import PA_PER_PSI, Config, warn
from mtbmj.errors import ConfigError
from mtbmj.runpath import steprule

MM = 1e-3
N_PER_MM = 1e3
PSI = PA_PER_PSI  # Pa per psi (mtbmj.config's table of units)
CM3 = 1e-6  # m^3 per cm^3


@dataclass(frozen=True)
class Setup:
    """Everything an engine needs, in SI units."""

    config: Config
    body_mass: float
    wheel_mass: float
    gravity: float
    drop_height: float
    travel: float
    fork_length: float
    tire_radius: float
    fork: law.ForkLaw
    tire: law.TireLaw
    duration: float
    timestep: float
    integrator: str
    ode_method: str
    ode_rtol: float
    ode_atol: float
    sample_rate: float
    antialias: float
    # MuJoCo steps per ``timestep`` while an end stop or the rim may be engaged (the drop engine
    # refines there; engines that do not refine step at ``fine_timestep`` throughout)
    substeps: int = 1
    # the same in the drop engine's other zones (touchdown and lift-off, the band around rest, fast
    # sliding), where no stop or rim acts: at most ``substeps``; 0 means ``substeps``
    contact_substeps: int = 0

    @property
    def fine_timestep(self) -> float:
        return self.timestep / self.substeps

    @property
    def impact_speed(self) -> float:
        """v_i = sqrt(2 g h0) (paper eq. 1)."""
        return math.sqrt(2.0 * self.gravity * self.drop_height)


# End stops and rim (assumed values, see docs/model.md, "Parameters"): the defaults of keys a user file may omit.
STOP_DEFAULTS = {
    "fork.stops.bumper_length_mm": 8.0,
    "fork.stops.bumper_force_N": 3000.0,
    "fork.stops.stop_rate_N_per_mm": 20000.0,
    "fork.stops.stop_damping_N_s_per_m": 2000.0,
    "fork.stops.extension_mm": 5.0,
    "tire.rim_rate_N_per_mm": 30000.0,
    "tire.rim_damping_N_s_per_m": 3000.0,
}
STICK_DEFAULTS = {"fork.friction.stick": True, "fork.friction.stick_stiffness_N_per_mm": 30.0,
                  "fork.friction.stick_damping_N_s_per_m": 2500.0,
                  "fork.friction.stick_damping_velocity_mm_per_s": 50.0}


def _get(c: Config, key: str):
    return c.get(key, STOP_DEFAULTS.get(key, STICK_DEFAULTS.get(key)))


def _stops(c: Config, main) -> law.EndStops:
    travel = c.require("fork.travel_mm")
    bumper = _get(c, "fork.stops.bumper_length_mm")
    if bumper >= travel:
        raise ConfigError(f"fork.stops.bumper_length_mm: {bumper:g} mm is not shorter than fork.travel_mm ({travel:g} mm)")
    return law.EndStops(main, travel * MM, bumper * MM, _get(c, "fork.stops.bumper_force_N"),
                        _get(c, "fork.stops.stop_rate_N_per_mm") * N_PER_MM, _get(c, "fork.stops.stop_damping_N_s_per_m"),
                        _get(c, "fork.stops.extension_mm") * MM)


def _spring(c: Config) -> object:
    return _stops(c, _main_spring(c))


def _main_spring(c: Config) -> object:
    model = c.require("fork.spring.model")
    band = c.get("fork.spring.direction_band_mm_per_s", 20.0) * MM
    travel = c.require("fork.travel_mm")

    def rate(key):
        return c.require(f"fork.spring.{key}", f"needed by fork.spring.model = {model}") * N_PER_MM

    if model == "linear":
        main = law.LinearSpring(rate("rate_N_per_mm"))
    elif model == "compression_rebound":
        main = law.DirectionalSpring(
            law.LinearSpring(rate("compression_rate_N_per_mm")), law.LinearSpring(rate("rebound_rate_N_per_mm")), band
        )
    elif model == "bilinear":
        knee = c.require("fork.spring.knee_mm", "needed by fork.spring.model = bilinear")
        if not 0.0 < knee < travel:
            raise ConfigError(f"fork.spring.knee_mm: {knee:g} mm is outside the travel (0, {travel:g}) mm")
        main = law.BilinearSpring(rate("rate_below_knee_N_per_mm"), rate("rate_above_knee_N_per_mm"), knee * MM)
        if c.get("fork.spring.rebound_curve", False):  # S3, S4, S6: extending on S2's rebound rate
            main = law.DirectionalSpring(main, law.LinearSpring(rate("rebound_rate_N_per_mm")), band)
    elif model == "air":
        return _air_spring(c, travel)
    else:  # progressive
        cubic = c.require("fork.spring.progressive_cubic_N_per_mm3", "needed by fork.spring.model = progressive")
        main = law.ProgressiveSpring(rate("progressive_rate_N_per_mm"), cubic * N_PER_MM / MM**2)
    use_preload = c.get("fork.spring.preload", "fork.spring.preload_N" in c.values)
    use_top_out = c.get("fork.spring.top_out", "fork.spring.top_out_rate_N_per_mm" in c.values)
    preload = c.require("fork.spring.preload_N", "needed by fork.spring.preload = true") if use_preload else 0.0
    if not use_top_out:
        if preload > 0.0:
            raise ConfigError(
                "fork.spring.preload: a preload needs the top-out spring (fork.spring.top_out = true); "
                "without it the preload is a force step at full extension"
            )
        return main
    top = c.require("fork.spring.top_out_rate_N_per_mm", "needed by fork.spring.top_out = true") * N_PER_MM
    spring = law.TopOutSpring(main, top, preload)
    if spring.engagement >= travel * MM:
        raise ConfigError(f"fork.spring.preload_N / fork.travel_mm: the top-out spring would stay engaged over the "
                          f"whole travel (preload {preload:g} N / top-out rate {top / N_PER_MM:g} N/mm = "
                          f"{spring.engagement / MM:g} mm, not less than fork.travel_mm = {travel:g} mm)")
    return spring


def air_volume(c: Config) -> float:
    """Positive-chamber volume (m^3) at full extension with the volume spacers in, refused (naming
    ``fork.spring.tokens``) when the spacers fill the chamber."""
    why = "needed by fork.spring.model = air"
    volume = c.require("fork.spring.air_volume_cm3", why) * CM3
    tokens = c.get("fork.spring.tokens", 0.0)
    if tokens != int(tokens):
        raise ConfigError(f"fork.spring.tokens: must be a whole number of volume spacers, got {tokens:g}")
    if tokens:
        volume -= tokens * c.require("fork.spring.token_volume_cm3", "needed by fork.spring.tokens") * CM3
        if volume <= 0.0:
            raise ConfigError(f"fork.spring.tokens / fork.spring.air_volume_cm3: {tokens:g} spacers of "
                              f"{c['fork.spring.token_volume_cm3']:g} cm3 fill the "
                              f"{c['fork.spring.air_volume_cm3']:g} cm3 air chamber")
    return volume


def _air_spring(c: Config, travel_mm: float) -> object:
    """``fork.spring.model = "air"``: ``law.AirSpring`` with the top-out spring carrying its force at
    full extension (the air's own preload) the way ``TopOutSpring`` carries a coil's preload."""
    why = "needed by fork.spring.model = air"
    gauge = c.require("fork.spring.air_pressure_psi", why)
    if gauge < 0.0:
        raise ConfigError(f"fork.spring.air_pressure_psi: {gauge:g} psi gauge is below the atmosphere's pressure "
                          f"(a partial vacuum in the air chamber; {-law.P_ATM / PSI:.2f} psi gauge is none at all): "
                          f"air forks are pumped above it, typically 50-150 psi")
    diameter = c.require("fork.spring.piston_diameter_mm", why) * MM
    area = math.pi * diameter * diameter / 4.0
    volume = air_volume(c)
    travel = travel_mm * MM
    swept = area * travel
    if swept >= volume:
        raise ConfigError(f"fork.spring.air_volume_cm3: the travel ({travel_mm:g} mm) would compress the air chamber "
                          f"to zero volume (piston sweeps {swept / CM3:.1f} cm3, chamber holds {volume / CM3:.1f} cm3 "
                          f"with its spacers)")
    index = c.require("fork.spring.polytropic_index", why)
    if not 1.0 <= index <= 1.4:
        raise ConfigError(f"fork.spring.polytropic_index: {index:g} is outside 1 (isothermal) to 1.4 (adiabatic air)")
    negative = c.get("fork.spring.negative_volume_cm3", 0.0) * CM3
    port = c.get("fork.spring.transfer_port_mm", 0.0)
    if not 0.0 <= port < travel_mm:
        raise ConfigError(f"fork.spring.transfer_port_mm: {port:g} mm is outside the travel [0, {travel_mm:g}) mm")
    if c.get("fork.spring.preload", False):
        raise ConfigError("fork.spring.preload: an air spring takes its preload from fork.spring.air_pressure_psi; "
                          "set fork.spring.preload = false")
    spring = law.AirSpring(area, gauge * PSI, volume, index, negative, port * MM, travel)
    preload = max(0.0, spring.force(0.0, 0.0))
    use_top_out = c.get("fork.spring.top_out", "fork.spring.top_out_rate_N_per_mm" in c.values)
    if not use_top_out:
        if preload > 0.0:
            raise ConfigError("fork.spring.top_out: an air spring without a negative chamber pushes with "
                              f"{preload:.0f} N at full extension; it needs the top-out spring (fork.spring.top_out = true)")
        return spring
    top = c.require("fork.spring.top_out_rate_N_per_mm", "needed by fork.spring.top_out = true") * N_PER_MM
    spring = law.TopOutSpring(law.AirSpring(area, gauge * PSI, volume, index, negative, port * MM, travel, preload),
                              top, preload)
    if spring.engagement >= travel:
        raise ConfigError(f"fork.spring.air_pressure_psi / fork.travel_mm: the top-out spring would stay engaged over "
                          f"the whole travel (force at full extension {preload:.0f} N / top-out rate "
                          f"{top / N_PER_MM:g} N/mm exceeds fork.travel_mm = {travel_mm:g} mm)")
    return spring


def _damper(c: Config) -> object:
    model = c.require("fork.damper.model")
    why = f"needed by fork.damper.model = {model}"
    if model == "linear":
        return law.LinearDamper(c.require("fork.damper.coefficient_N_s_per_m", why))
    if model == "bilinear":
        return law.BilinearDamper(
            c.require("fork.damper.compression_N_s_per_m", why), c.require("fork.damper.rebound_N_s_per_m", why)
        )
    if model == "digressive":
        return law.DigressiveDamper(
            c.require("fork.damper.compression_low_N_s_per_m", why), c.require("fork.damper.compression_high_N_s_per_m", why),
            c.require("fork.damper.compression_knee_mm_per_s", why) * MM,
            c.require("fork.damper.rebound_low_N_s_per_m", why), c.require("fork.damper.rebound_high_N_s_per_m", why),
            c.require("fork.damper.rebound_knee_mm_per_s", why) * MM)
    if model == "orifice":
        return law.OrificeDamper(c.require("fork.damper.bleed_N_s_per_m", why),
                                 c.require("fork.damper.compression_orifice_N_s2_per_m2", why),
                                 c.require("fork.damper.rebound_orifice_N_s2_per_m2", why))
    if model == "clicks":
        return _clicks_damper(c)
    v = np.asarray(c.require("fork.damper.velocity_mm_per_s", why)) * MM
    f = np.asarray(c.require("fork.damper.force_N", why))
    if len(v) != len(f):
        raise ConfigError(
            f"fork.damper.force_N: {len(f)} values for {len(v)} velocities in fork.damper.velocity_mm_per_s"
        )
    if len(v) < 4:
        raise ConfigError(f"fork.damper.velocity_mm_per_s: table too short ({len(v)} points, need at least 4)")
    if np.any(np.diff(v) <= 0):
        raise ConfigError("fork.damper.velocity_mm_per_s: velocities must be strictly increasing")
    if np.any(np.diff(f) < 0):
        raise ConfigError("fork.damper.force_N: force must not decrease with velocity (a damper dissipates)")
    if not (v[0] < 0.0 < v[-1]):
        raise ConfigError("fork.damper.velocity_mm_per_s: the table must span rebound (<0) and compression (>0)")
    zero = np.flatnonzero(v == 0.0)
    if zero.size and f[zero[0]] != 0.0:
        raise ConfigError("fork.damper.force_N: force at zero velocity must be 0; put the offset in fork.friction")
    return law.TableDamper(v, f)


SPEED_CIRCUITS = {"compression": ("low_speed_compression", "high_speed_compression"),
                  "rebound": ("low_speed_rebound", "high_speed_rebound")}
# two curves measured at the same setting (the sweeps' shared reference) may differ by this much
# (a fraction of the larger curve's peak force, plus CLICKS_AGREE_N) before they are refused
CLICKS_AGREE = 0.10
CLICKS_AGREE_N = 5.0


def _clicks_rows(c: Config, circuit: str, stroke: str, points: int) -> tuple[np.ndarray, np.ndarray]:
    """The measured positions and force rows of one adjuster (``fork.damper.<circuit>_...``),
    checked against the stroke's share of the velocity grid."""
    why = "needed by fork.damper.model = clicks"
    key = f"fork.damper.{circuit}"
    measured = np.asarray(c.require(f"{key}_clicks_measured", why))
    rows = c.require(f"{key}_force_N", why)
    if len(measured) < 1 or np.any(measured != np.round(measured)) or np.any(measured < 0) or \
            np.any(np.diff(measured) <= 0):
        raise ConfigError(f"{key}_clicks_measured: must be whole clicks from closed, strictly increasing")
    if len(rows) != len(measured):
        raise ConfigError(f"{key}_force_N: {len(rows)} rows for {len(measured)} positions in {key}_clicks_measured")
    side = "compression (> 0)" if stroke == "compression" else "rebound (< 0)"
    for i, row in enumerate(rows):
        if len(row) != points:
            raise ConfigError(f"{key}_force_N: row {i + 1} has {len(row)} forces for the {points} {side} velocities "
                              "of fork.damper.velocity_mm_per_s")
        f = np.asarray(row)
        if np.any(np.diff(f) < 0) or (np.any(f < 0) if stroke == "compression" else np.any(f > 0)):
            raise ConfigError(f"{key}_force_N: row {i + 1} must rise with velocity and keep the sign of the "
                              f"{stroke} stroke (a damper dissipates)")
    return measured, np.asarray(rows, dtype=float)


def _at_clicks(key: str, setting: float, measured: np.ndarray, table: np.ndarray) -> np.ndarray:
    if setting != round(setting):
        raise ConfigError(f"{key}: {setting:g} is not a whole number of clicks")
    if not measured[0] <= setting <= measured[-1]:
        raise ConfigError(f"{key}: {setting:g} is outside the measured positions "
                          f"{measured[0]:g}-{measured[-1]:g} clicks from closed")
    return np.array([np.interp(setting, measured, table[:, j]) for j in range(table.shape[1])])


def _adjuster(c: Config, circuit: str, stroke: str, points: int, why: str):
    """(measured positions, force rows, force at the setting ``fork.damper.<circuit>_clicks``) of
    one adjuster of ``stroke``."""
    measured, table = _clicks_rows(c, circuit, stroke, points)
    key = f"fork.damper.{circuit}_clicks"
    return measured, table, _at_clicks(key, c.require(key, why), measured, table)


def clicks_curve(c: Config, circuit: str, points: int) -> np.ndarray:
    """Force (N) of a stroke's single adjuster (``circuit`` "compression" or "rebound") at its
    setting ``fork.damper.<circuit>_clicks``: each velocity's force interpolated linearly in clicks
    between the two neighbouring positions of ``<circuit>_clicks_measured`` (rows of
    ``<circuit>_force_N``)."""
    return _adjuster(c, circuit, circuit, points, "needed by fork.damper.model = clicks")[2]


def _has_speed_circuits(c: Config, stroke: str) -> bool:
    return any(k.startswith(f"fork.damper.{circuit}_") for circuit in SPEED_CIRCUITS[stroke] for k in c.values)


def stroke_clicks_curve(c: Config, stroke: str, points: int) -> np.ndarray:
    """One stroke's force (N) at its adjuster settings. With one adjuster per stroke, its
    ``clicks_curve``. With a low- and a high-speed adjuster, each measured while the other stood
    at its ``<circuit>_reference_clicks``, the adjusters' effects are taken as additive:
    F(L, H) = F_low(L) + F_high(H) - F(L_ref, H_ref), where both sweeps hold the reference curve
    F(L_ref, H_ref) (their mean is used; curves that disagree by more than CLICKS_AGREE are refused)."""
    low, high = SPEED_CIRCUITS[stroke]
    if not _has_speed_circuits(c, stroke):
        return clicks_curve(c, stroke, points)
    single = [k for k in c.values if k.startswith(f"fork.damper.{stroke}_clicks") or k == f"fork.damper.{stroke}_force_N"]
    if single:
        raise ConfigError(f"{single[0]}: give either one {stroke} adjuster or the low- and high-speed "
                          f"{stroke} adjusters, not both")
    why = f"needed by the {stroke} stroke's low- and high-speed adjusters"
    curves, bases = [], []
    for circuit, other in ((low, high), (high, low)):
        measured, table, curve = _adjuster(c, circuit, stroke, points, why)
        curves.append(curve)
        key = f"fork.damper.{circuit}"
        ref = c.require(f"{key}_reference_clicks", why)
        if ref not in measured:
            raise ConfigError(f"{key}_reference_clicks: {ref:g} is not one of {key}_clicks_measured "
                              f"(the {circuit.replace('_', '-')} adjuster's position while the "
                              f"{other.replace('_', '-')} curves were measured)")
        bases.append(table[list(measured).index(ref)])
    limit = CLICKS_AGREE * max(np.max(np.abs(bases[0])), np.max(np.abs(bases[1]))) + CLICKS_AGREE_N
    if np.max(np.abs(bases[0] - bases[1])) > limit:
        raise ConfigError(f"fork.damper.{high}_force_N: at the reference setting it differs from "
                          f"fork.damper.{low}_force_N by {np.max(np.abs(bases[0] - bases[1])):.0f} N "
                          f"(more than {limit:.0f} N); both sweeps should hold the same reference curve")
    force = curves[0] + curves[1] - 0.5 * (bases[0] + bases[1])
    if np.any(np.diff(force) < -1e-9) or (np.any(force < 0) if stroke == "compression" else np.any(force > 0)):
        raise ConfigError(f"fork.damper.{low}_clicks: at {c[f'fork.damper.{low}_clicks']:g} low-speed and "
                          f"{c[f'fork.damper.{high}_clicks']:g} high-speed clicks the adjusters' summed effects "
                          f"give a {stroke} curve that falls with velocity or changes sign; the additive model "
                          "does not hold this far from the measured settings")
    return force


def _clicks_damper(c: Config) -> object:
    """``fork.damper.model = "clicks"``: a lookup-table damper whose compression half (v > 0) and
    rebound half (v < 0) come from dyno curves measured at several adjuster positions."""
    v = np.asarray(c.require("fork.damper.velocity_mm_per_s", "needed by fork.damper.model = clicks"))
    force = np.zeros(len(v))
    force[v > 0] = stroke_clicks_curve(c, "compression", int(np.sum(v > 0)))
    force[v < 0] = stroke_clicks_curve(c, "rebound", int(np.sum(v < 0)))
    return _damper(c.with_overrides({"fork.damper.model": "table", "fork.damper.force_N": tuple(force)}))


def _friction(c: Config) -> object:
    friction = _static_friction(c)
    if friction.has_state or type(friction) is law.NoFriction or not _get(c, "fork.friction.stick"):
        return friction
    if friction.coulomb == 0.0:
        return friction  # nothing to stick with: the viscous part alone
    return law.Sticking(friction, _get(c, "fork.friction.stick_stiffness_N_per_mm") * N_PER_MM,
                        _get(c, "fork.friction.stick_damping_N_s_per_m"),
                        _get(c, "fork.friction.stick_damping_velocity_mm_per_s") * MM)


def _static_friction(c: Config) -> object:
    model = c.get("fork.friction.model", "none")
    why = f"needed by fork.friction.model = {model}"

    def get(key, scale=1.0):
        return c.require(f"fork.friction.{key}", why) * scale

    band = c.get("fork.friction.sign_band_mm_per_s", 5.0) * MM
    if model == "none":
        return law.NoFriction()
    if model == "coulomb":
        return law.Coulomb(get("coulomb_N"), band)
    if model == "coulomb_viscous":
        return law.CoulombViscous(get("coulomb_N"), get("viscous_N_s_per_m"), band)
    if model in ("stiction", "stribeck"):
        width_key = "stiction_band_mm_per_s" if model == "stiction" else "stribeck_velocity_mm_per_s"
        if band > 0.25 * get(width_key, MM):
            raise ConfigError(
                f"fork.friction.sign_band_mm_per_s: {band / MM:g} mm/s is more than a quarter of "
                f"fork.friction.{width_key}; the regularised sign would hide the breakaway peak"
            )
    if model == "stiction":
        return law.Stiction(get("coulomb_N"), get("breakaway_N"), get("viscous_N_s_per_m"),
                            get("stiction_band_mm_per_s", MM), band)
    if model == "stribeck":
        return law.Stribeck(get("coulomb_N"), get("breakaway_N"), get("viscous_N_s_per_m"),
                            get("stribeck_velocity_mm_per_s", MM), c.get("fork.friction.stribeck_exponent", 2.0), band)
    return law.LuGre(get("coulomb_N"), get("breakaway_N"), get("stribeck_velocity_mm_per_s", MM),
                     get("bristle_stiffness_N_per_mm", N_PER_MM), get("bristle_damping_N_s_per_m"),
                     c.get("fork.friction.viscous_N_s_per_m", 0.0))


def _rim(c: Config) -> law.Rim:
    radius = c.require("tire.radius_mm")
    deepest = c.require("tire.max_deflection_mm", "the rim strikes past it")
    if deepest >= radius:
        raise ConfigError(f"tire.max_deflection_mm: {deepest:g} mm is not smaller than tire.radius_mm ({radius:g} mm)")
    return law.Rim(deepest * MM, _get(c, "tire.rim_rate_N_per_mm") * N_PER_MM, _get(c, "tire.rim_damping_N_s_per_m"))


def tire_rates_from_pressure(pressure_psi: float) -> dict[str, float]:
    """``tire.pressure_psi`` -> the tire's static, impact and in-contact rates (N/mm), from
    ``controllers.tire.static_rate_from_pressure`` and the sourced dynamic/static ratios. A gauge
    pressure of 0 or less is refused (a flat tire carries nothing on its air); outside the measured
    ``PRESSURE_RANGE`` the rates are extrapolated, which ``mtbmj.config`` warns about when the
    value is read."""
    from mtbmj.controllers import tire as tire_model

    if not pressure_psi > 0.0:
        raise ConfigError(f"tire.pressure_psi: {pressure_psi:g} psi gauge: the tire must be inflated (above 0)")
    static = tire_model.static_rate_from_pressure(pressure_psi * PSI) / N_PER_MM
    return {"tire.static_rate_N_per_mm": static,
            "tire.impact_rate_N_per_mm": static * tire_model.IMPACT_OVER_STATIC,
            "tire.contact_rate_N_per_mm": static * tire_model.CONTACT_OVER_STATIC}


def _tire(c: Config) -> law.TireLaw:
    model = c.require("tire.model")
    why = f"needed by tire.model = {model}"
    if "tire.pressure_psi" in c.values:  # the pressure sets the rates (the damping stays as configured)
        c = c.with_overrides(tire_rates_from_pressure(c["tire.pressure_psi"]))
    k_impact = c.require("tire.impact_rate_N_per_mm", why) * N_PER_MM
    b_impact = c.require("tire.impact_damping_N_s_per_m", why)
    rim = _rim(c)
    if model == "impact":
        return law.TireLaw(law.KelvinVoigt(k_impact, b_impact), rim=rim)
    if model == "undamped":
        return law.TireLaw(law.KelvinVoigt(k_impact, 0.0), rim=rim)
    if model == "static":
        return law.TireLaw(law.KelvinVoigt(c.require("tire.static_rate_N_per_mm", why) * N_PER_MM, b_impact), rim=rim)
    return law.TireLaw(
        law.KelvinVoigt(k_impact, b_impact),
        law.KelvinVoigt(c.require("tire.contact_rate_N_per_mm", why) * N_PER_MM,
                        c.require("tire.contact_damping_N_s_per_m", why)),
        rim=rim,
    )


def fork_law(c: Config) -> law.ForkLaw:
    return law.ForkLaw(_spring(c), _damper(c), _friction(c))


# the keys whose meaning a model chooses: a key set here that the part's model does not read changes nothing
MODEL_FAMILIES = ("fork.spring.", "fork.damper.", "fork.friction.", "tire.")


class NotRead(ConfigError):
    """A key the caller set that the part's model does not read (``_composed``)."""


class _Reading:
    """A configuration seen through a note of every key asked for (``get``, ``require``, ``[]``)."""

    def __init__(self, c, read=None):
        self._c, self.read = c, set() if read is None else read

    def __getattr__(self, name):
        return getattr(self._c, name)

    def get(self, key, default=None):
        self.read.add(key)
        return self._c.get(key, default)

    def require(self, key, why=""):
        self.read.add(key)
        return self._c.require(key, why)

    __getitem__ = require

    def with_overrides(self, overrides):
        return _Reading(self._c.with_overrides(overrides), self.read)


def unread(c: Config) -> list[str]:
    """The keys of ``c``'s model families (``MODEL_FAMILIES``) that the spring, damper, friction and tire
    models ``c`` chooses do not read: what a file written to stand alone (``mtbmj fit``'s fit.toml) leaves
    out, so that it loads back without a warning about a key of its own."""
    _, read = _read_laws(c)
    return sorted(k for k in c.values if k.startswith(MODEL_FAMILIES) and k not in read)


def _read_laws(c: Config):
    """((fork law, tire law) of ``c``, the keys their models asked for)."""
    seen = _Reading(c)
    return (fork_law(seen), _tire(seen)), seen.read


def _composed(c: Config):
    """(fork law, tire law) of ``c``, refusing in one line a key a person typed (``Config.given``:
    ``--set``, a bike's ``--fork-set`` / ``--shock-set``; not a file's or a program's) that the part's
    model does not read: the spring, damper, friction or tire model chosen reads other keys, so the
    setting would change nothing. Such a key the file named sets itself (``Config.filed``; not its
    bases', which other files may build on) is said in one warning line naming the key and the file."""
    typed = sorted(k for k in c.given if k.startswith(MODEL_FAMILIES))
    filed = sorted(k for k in c.filed if k.startswith(MODEL_FAMILIES) and k not in c.given)
    if not typed and not filed:
        return fork_law(c), _tire(c)
    laws, read = _read_laws(c)
    for key in [k for k in typed + filed if k not in read]:
        family = next(f for f in MODEL_FAMILIES if key.startswith(f))
        model = f"{family}model"
        reads = sorted(k[len(family):] for k in read if k.startswith(family) and k != model and k in c.values)
        said = (f"{key}: set, but {model} = {c.get(model)!r} does not read it, so it would change nothing (that "
                f"model reads {family}{{{', '.join(reads)}}})")
        if key in c.given:
            raise NotRead(said)
        warn([f"{c.filed[key]}: {said.replace('it would change', 'it changes')}"])
    return laws


def setup(c: Config) -> Setup:
    """Build and cross-check everything a run needs."""
    wheel = c.require("sled.wheel_mass_kg")
    body = c.require("sled.body_mass_kg")
    fork, tire = _composed(c)
    s = Setup(
        config=c,
        body_mass=body,
        wheel_mass=wheel,
        gravity=c.get("sled.gravity_m_per_s2", 9.81),
        drop_height=c.require("sled.drop_height_mm") * MM,
        travel=c.require("fork.travel_mm") * MM,
        fork_length=c.get("fork.length_mm", 500.0) * MM,
        tire_radius=c.require("tire.radius_mm") * MM,
        fork=fork,
        tire=tire,
        duration=c.get("solver.duration_s", 1.5),
        timestep=c.get("solver.timestep_s", 0.0),  # 0: chosen below by the step rule
        integrator=c.get("solver.integrator", steprule.DEFAULT_INTEGRATOR),
        ode_method=c.get("solver.ode_method", "Radau"),
        ode_rtol=c.get("solver.ode_rtol", 1e-8),
        ode_atol=c.get("solver.ode_atol_mm", 1e-7) * MM,
        sample_rate=c.get("solver.sample_rate_Hz", 1000.0),
        antialias=c.get("solver.antialias_Hz", 400.0),
    )
    s = steprule.choose_timestep(s)
    if s.antialias >= s.sample_rate / 2:
        raise ConfigError(
            f"solver.antialias_Hz: {s.antialias:g} Hz must be below half of solver.sample_rate_Hz ({s.sample_rate:g} Hz)"
        )
    return s

"""Turn a validated ``Config`` into SI force-law objects and check the cross-key rules.

This is the one place where external units (mm, N/mm, mm/s) become SI (m, N/m, m/s).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtbmj import controllers as law
from mtbmj.config import Config
from mtbmj.errors import ConfigError

MM = 1e-3
N_PER_MM = 1e3
PSI = 6894.757293168  # Pa per psi (1 lbf/in^2, exact by the definitions of the pound and the inch)
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

    @property
    def impact_speed(self) -> float:
        """v_i = sqrt(2 g h0) (paper eq. 1)."""
        return math.sqrt(2.0 * self.gravity * self.drop_height)


def _spring(c: Config) -> object:
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
        raise ConfigError("fork.spring.preload_N: the top-out spring would stay engaged over the whole travel "
                          "(preload / top-out rate exceeds fork.travel_mm)")
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
            raise ConfigError(f"fork.spring.tokens: {tokens:g} spacers fill the air chamber "
                              f"(fork.spring.air_volume_cm3 = {c['fork.spring.air_volume_cm3']:g})")
    return volume


def _air_spring(c: Config, travel_mm: float) -> object:
    """``fork.spring.model = "air"``: ``law.AirSpring`` with the top-out spring carrying its force at
    full extension (the air's own preload) the way ``TopOutSpring`` carries a coil's preload."""
    why = "needed by fork.spring.model = air"
    gauge = c.require("fork.spring.air_pressure_psi", why)
    if gauge * PSI <= -law.P_ATM:
        raise ConfigError(f"fork.spring.air_pressure_psi: {gauge:g} psi gauge is at or below vacuum "
                          f"({-law.P_ATM / PSI:.2f} psi gauge)")
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
        raise ConfigError("fork.spring.air_pressure_psi: the top-out spring would stay engaged over the whole travel "
                          "(force at full extension / top-out rate exceeds fork.travel_mm)")
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


def clicks_curve(c: Config, circuit: str, points: int) -> np.ndarray:
    """Force (N) of one damper circuit ("compression" or "rebound") at its adjuster setting
    ``fork.damper.<circuit>_clicks``: each velocity's force interpolated linearly in clicks between
    the two neighbouring positions of ``<circuit>_clicks_measured`` (rows of ``<circuit>_force_N``)."""
    why = "needed by fork.damper.model = clicks"
    key = f"fork.damper.{circuit}"
    measured = np.asarray(c.require(f"{key}_clicks_measured", why))
    rows = c.require(f"{key}_force_N", why)
    setting = c.require(f"{key}_clicks", why)
    if len(measured) < 1 or np.any(measured != np.round(measured)) or np.any(measured < 0) or \
            np.any(np.diff(measured) <= 0):
        raise ConfigError(f"{key}_clicks_measured: must be whole clicks from closed, strictly increasing")
    if len(rows) != len(measured):
        raise ConfigError(f"{key}_force_N: {len(rows)} rows for {len(measured)} positions in {key}_clicks_measured")
    side = "compression (> 0)" if circuit == "compression" else "rebound (< 0)"
    for i, row in enumerate(rows):
        if len(row) != points:
            raise ConfigError(f"{key}_force_N: row {i + 1} has {len(row)} forces for the {points} {side} velocities "
                              "of fork.damper.velocity_mm_per_s")
        f = np.asarray(row)
        if np.any(np.diff(f) < 0) or (np.any(f < 0) if circuit == "compression" else np.any(f > 0)):
            raise ConfigError(f"{key}_force_N: row {i + 1} must rise with velocity and keep the sign of the "
                              f"{circuit} stroke (a damper dissipates)")
    if setting != round(setting):
        raise ConfigError(f"{key}_clicks: {setting:g} is not a whole number of clicks")
    if not measured[0] <= setting <= measured[-1]:
        raise ConfigError(f"{key}_clicks: {setting:g} is outside the measured positions "
                          f"{measured[0]:g}-{measured[-1]:g} clicks from closed")
    table = np.asarray(rows)
    return np.array([np.interp(setting, measured, table[:, j]) for j in range(points)])


def _clicks_damper(c: Config) -> object:
    """``fork.damper.model = "clicks"``: a lookup-table damper whose compression half (v > 0) and
    rebound half (v < 0) come from dyno curves measured at several adjuster positions."""
    v = np.asarray(c.require("fork.damper.velocity_mm_per_s", "needed by fork.damper.model = clicks"))
    force = np.zeros(len(v))
    force[v > 0] = clicks_curve(c, "compression", int(np.sum(v > 0)))
    force[v < 0] = clicks_curve(c, "rebound", int(np.sum(v < 0)))
    return _damper(c.with_overrides({"fork.damper.model": "table", "fork.damper.force_N": tuple(force)}))


def _friction(c: Config) -> object:
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


def tire_rates_from_pressure(pressure_psi: float) -> dict[str, float]:
    """``tire.pressure_psi`` -> the tire's static, impact and in-contact rates (N/mm), from
    ``controllers.tire.static_rate_from_pressure`` and the sourced dynamic/static ratios; refused
    (naming the key) outside the model's range."""
    from mtbmj.controllers import tire as tire_model

    low, high = (p / PSI for p in tire_model.PRESSURE_RANGE)
    if not low <= pressure_psi <= high:
        raise ConfigError(f"tire.pressure_psi: {pressure_psi:g} psi is outside the tire model's range "
                          f"{low:g}-{high:g} psi (the published measurements it rests on)")
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
    if model == "impact":
        return law.TireLaw(law.KelvinVoigt(k_impact, b_impact))
    if model == "undamped":
        return law.TireLaw(law.KelvinVoigt(k_impact, 0.0))
    if model == "static":
        return law.TireLaw(law.KelvinVoigt(c.require("tire.static_rate_N_per_mm", why) * N_PER_MM, b_impact))
    return law.TireLaw(
        law.KelvinVoigt(k_impact, b_impact),
        law.KelvinVoigt(c.require("tire.contact_rate_N_per_mm", why) * N_PER_MM,
                        c.require("tire.contact_damping_N_s_per_m", why)),
    )


def fork_law(c: Config) -> law.ForkLaw:
    return law.ForkLaw(_spring(c), _damper(c), _friction(c))


def setup(c: Config) -> Setup:
    """Build and cross-check everything a run needs."""
    wheel = c.require("sled.wheel_mass_kg")
    body = c.require("sled.body_mass_kg")
    fork = fork_law(c)
    tire = _tire(c)
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
        timestep=c.get("solver.timestep_s", 1e-4),
        integrator=c.get("solver.integrator", "implicitfast"),
        ode_method=c.get("solver.ode_method", "Radau"),
        ode_rtol=c.get("solver.ode_rtol", 1e-8),
        ode_atol=c.get("solver.ode_atol_mm", 1e-7) * MM,
        sample_rate=c.get("solver.sample_rate_Hz", 1000.0),
        antialias=c.get("solver.antialias_Hz", 400.0),
    )
    check_timestep(s)
    if s.antialias >= s.sample_rate / 2:
        raise ConfigError(
            f"solver.antialias_Hz: {s.antialias:g} Hz must be below half of solver.sample_rate_Hz ({s.sample_rate:g} Hz)"
        )
    if 1.0 / s.timestep < 2 * s.sample_rate:
        raise ConfigError("solver.timestep_s: must resolve at least twice solver.sample_rate_Hz")
    return s


def stiffest_rates(s: Setup) -> tuple[float, float]:
    """Largest stiffness (N/m) and damping-like slope (N s/m) the wheel meets, for the step rule."""
    k_fork = max(
        abs(s.fork.spring.force(x + 1e-4, 0.0) - s.fork.spring.force(x, 0.0)) / 1e-4
        for x in np.linspace(-0.02, s.travel * 1.2, 400)
    )
    tires = [s.tire.impact] + ([s.tire.in_contact] if s.tire.in_contact else [])
    k_tire = max(t.rate for t in tires)
    c_tire = max(t.damping for t in tires)
    c_fork = max(
        abs(s.fork.force(0.05, v + 1e-5) - s.fork.force(0.05, v)) / 1e-5 for v in np.linspace(-3.0, 3.0, 601)
    )
    return k_fork + k_tire, c_fork + c_tire


def _round_down(value: float, digits: int = 2) -> str:
    """``value`` to ``digits`` significant digits, never above it (a limit stated must hold)."""
    exponent = math.floor(math.log10(value)) - digits + 1
    return f"{math.floor(value / 10**exponent) * 10**exponent:.{digits}g}"


def check_timestep(s: Setup) -> None:
    """Reject a MuJoCo timestep too large for the stiffest element: at least 25 steps per period
    of the wheel on the combined fork and tire stiffness, a damping slope the explicit force
    callback can follow (c dt / m <= 0.5), and for LuGre a bristle state it can follow."""
    k, c = stiffest_rates(s)
    reduced = s.wheel_mass * s.body_mass / (s.wheel_mass + s.body_mass)
    period = 2.0 * math.pi * math.sqrt(s.wheel_mass / k)
    limit = min(period / 25.0, 0.5 * reduced / c if c > 0 else math.inf)
    friction = s.fork.friction
    if friction.has_state:
        # Explicit integration of the bristle state: rate sigma0 |v| / F_C at strokes up to 2 m/s.
        limit = min(limit, friction.coulomb / (friction.stiffness * 2.0))
    if s.timestep > limit:
        raise ConfigError(
            f"solver.timestep_s: {s.timestep:g} s is too large for the configured stiffness "
            f"({k / 1e3:.0f} N/mm, {c:.0f} N s/m on the wheel); use at most {_round_down(limit)} s"
        )

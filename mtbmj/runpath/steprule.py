"""The step rule: how finely MuJoCo steps a fork law, the same whichever rig runs it.

A configuration's fork and tire laws (a ``mtbmj.compose.Setup``) meet the wheel's and the body's
masses; the rule turns the stiffest rates and slopes they can meet into step limits (:func:`limits`:
steps per period of the wheel on the spring and tire, on the stops and the rim where the run can
reach them, explicit damping, the logger's rate, the steep band around rest, the friction state at
the fastest stroke) and those limits into steps:

* the drop (``compose.setup`` calls :func:`choose_timestep`): the coarse step from ``STEP_LADDER``
  within the working stroke's limit, ``substeps`` finer steps near a stop or the rim and
  ``contact_substeps`` in the other zones (:func:`refine_zones`, which ``mtbmj.drop.stepping``
  watches);
* the rolling rigs, the front end (:func:`rolling`) and the whole bike (``mtbmj.bike.stepping``,
  the same limits with the bike's masses): a coarse step, a whole fraction of ``ROLLING_STEP_S``
  (:func:`fraction_within`) within the limits away from the stops, cut evenly (:func:`cuts_within`)
  where a stop or the rim may act (:func:`stop_zone`), which stretches are decided after the fact
  (:func:`reach_span`, ``mtbmj.runpath.loop.AfterTheFact``); a raw rollout steps at the drop's
  fine step throughout (:func:`at_fine_step`).

``compose`` imports this module to choose a setup's step, so the setup is not imported here: the
functions take any ``Setup`` and read the fields of :class:`StepSetup`.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import NamedTuple, Protocol

import numpy as np

from mtbmj import controllers as law
from mtbmj.controllers import native
from mtbmj.controllers.stops import STIFFENING_M
from mtbmj.errors import ConfigError


class StepSetup(Protocol):
    """What the rule reads of a ``mtbmj.compose.Setup`` (SI units)."""

    body_mass: float
    wheel_mass: float
    gravity: float
    drop_height: float
    travel: float
    fork: law.ForkLaw
    tire: law.TireLaw
    timestep: float  # 0: to be chosen
    integrator: str
    sample_rate: float
    substeps: int

    @property
    def fine_timestep(self) -> float: ...


DEFAULT_INTEGRATOR = "rk4"
# Steps per period of the stiffest oscillation the wheel can meet (hard stops and rim included)
# for RK4, and of the stiffest one over the working stroke (spring, bumper, tire) for the
# first-order integrators, whose error grows with the step (calibrated on the random envelope of
# tests/test_envelope.py against the ODE reference: <= 0.05 mm).
STEPS_PER_PERIOD = {"rk4": 16.0, "implicitfast": 250.0, "implicit": 250.0, "euler": 250.0}
# The same for the brief, stiff contacts of a hard stop or the rim (a half period each), and
# where the run can reach the compression stop or the rim (``reachable``): a fork rattling
# between them meets hundreds of such contacts, and an error made at each adds up (one random
# S4 fork: 0.15 mm off the reference at 12, 0.03 mm at 24).
STOP_STEPS_PER_PERIOD = {"rk4": 12.0, "implicitfast": 40.0, "implicit": 40.0, "euler": 40.0}
HARD_STOP_STEPS_PER_PERIOD = {"rk4": 24.0, "implicitfast": 40.0, "implicit": 40.0, "euler": 40.0}
# A fixed step keeps the output grid regular: the largest of these within the limit is chosen.
STEP_LADDER = (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6)


def _along(fork_law, xs, vs, python) -> np.ndarray:
    """``fork_law``'s force along (xs, vs) through the compiled kernel (the same numbers as the
    Python law, 50 times faster: the step rule runs for every variant of a sweep), else
    ``python(x, v)`` point by point."""
    out = None
    if native.loaded():  # the Python scan costs a few ms: not worth loading numba for
        from mtbmj.controllers import compiled

        out = compiled.fork_forces_along(fork_law, xs, vs, np.zeros_like(xs))
    if out is None:
        out = np.array([python(x, v) for x, v in zip(xs, vs)])
    return out


def _stroke(s: StepSetup, points: int) -> np.ndarray:
    """Fork compressions (m) from the extension stop to full travel."""
    return np.linspace(-getattr(s.fork.spring, "extension", 0.02), s.travel, points)


def _spring_along(s: StepSetup, xs, v) -> np.ndarray:
    """The main spring's force (N; end stops left out) along compressions ``xs`` at each of the
    stroke velocities ``v`` (a sequence), one row per velocity, all from one pass through the
    kernel (the step rule's scans of the stroke, for every variant of a sweep)."""
    spring = s.fork.spring
    main = getattr(spring, "main", spring)
    free = law.ForkLaw(main, law.LinearDamper(0.0), law.NoFriction())
    rows = len(v)
    forces = _along(free, np.tile(xs, rows), np.repeat(np.asarray(v, dtype=float), xs.size),
                    lambda x, vv: main.force(x, vv))
    return forces.reshape(rows, xs.size)


STROKE_POINTS = 2001  # the step rule's samples of the stroke
SCAN_VELOCITIES = (-1.0, 0.0, 1.0)  # m/s: the spring's lower curve, of compression, rest and rebound


def _spring_scan(s: StepSetup) -> tuple[np.ndarray, np.ndarray]:
    """(compressions along the stroke, the main spring's force there at each of
    ``SCAN_VELOCITIES``, one row each): what :func:`reachable` and :func:`stiffest_rates` read."""
    xs = _stroke(s, STROKE_POINTS)
    return xs, _spring_along(s, xs, SCAN_VELOCITIES)


# The stops' and the rim's stiffening is met at this penetration when the step is chosen: the
# depth a hard landing reaches at most (controllers.stops), where their tangent rate is
# k (1 + 3 (p / p0)^2), 34 times the linear rate.
STOP_DEPTH_M = 2.0e-3


def reachable(s: StepSetup, scan: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, bool]:
    """Which of the bumper, the compression stop, the extension stop and the rim the run can
    reach at all, by an energy bound: the fall's kinetic energy plus the work of gravity as the
    sled and wheel go down can at most fill the spring (its lower curve, of compression and
    rebound, friction and damping left out) and the softest tire. What cannot be reached does
    not set the fine step. ``scan``: :func:`_spring_scan`'s samples, if already taken."""
    spring = s.fork.spring
    g, mb, mw = s.gravity, s.body_mass, s.wheel_mass
    xs, forces = _spring_scan(s) if scan is None else scan
    low = np.minimum.reduce(list(forces))
    energy = np.concatenate(([0.0], np.cumsum(0.5 * (low[1:] + low[:-1]) * np.diff(xs))))
    energy -= np.interp(0.0, xs, energy)  # from full extension
    k_tire = min(t.rate for t in [s.tire.impact] + ([s.tire.in_contact] if s.tire.in_contact else []))
    weight = (mb + mw) * g
    fork_budget = weight * s.drop_height + mb * g * xs - energy  # fork at x, nothing else stored
    tire_best = weight ** 2 / (2.0 * k_tire)  # the most the tire's fall can add beyond its storage
    out = {"bumper": bool(np.interp(getattr(spring, "bumper_start", s.travel), xs, fork_budget) + tire_best >= 0.0),
           "compression_stop": bool(fork_budget[-1] + tire_best >= 0.0),
           "extension_stop": bool(fork_budget[0] + tire_best >= 0.0)}
    rim = s.tire.rim
    if rim is not None:
        d = rim.max_deflection
        out["rim"] = bool(np.max(fork_budget) + weight * d - 0.5 * k_tire * d * d >= 0.0)
    else:
        out["rim"] = False
    return out


def stiffest_rates(s: StepSetup, reach: dict[str, bool] | None = None,
                   scan: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, float]:
    """Stiffness (N/m) and damping-like slopes (N s/m) the wheel meets: ``working`` (the spring's
    steepest slope over the whole stroke, top-out included, sampled finely, plus the stiffer tire
    rate), ``stops`` (that plus the bumper at full travel, a hard stop and the rim at their
    tangent rate ``STOP_DEPTH_M`` deep, engaged together in the worst case; only those the run
    can reach, see :func:`reachable`) and ``damping`` (fork damping slope over the velocity
    range, stops, tire and rim); ``stops_out_of_reach`` and ``stop_damping_out_of_reach``: the
    same for this fork with every stop and the rim out of reach. ``scan``: :func:`_spring_scan`'s
    samples, if already taken."""
    spring = s.fork.spring
    xs, forces = _spring_scan(s) if scan is None else scan
    force = forces[SCAN_VELOCITIES.index(0.0)]
    k_spring = float(np.max(np.abs(np.diff(force)) / np.diff(xs)))
    k_bumper = 2.0 * spring.bumper_force / spring.bumper_length if hasattr(spring, "bumper_force") else 0.0
    tires = [s.tire.impact] + ([s.tire.in_contact] if s.tire.in_contact else [])
    k_tire = max(t.rate for t in tires)
    c_tire = max(t.damping for t in tires)
    rim = s.tire.rim
    reach = reachable(s, (xs, forces)) if reach is None else reach
    stiffening = 1.0 + 3.0 * (STOP_DEPTH_M / STIFFENING_M) ** 2
    # the extension stop is within the bound for nearly every fork (the bound leaves damping out,
    # and a rebound past full extension is cheap): it counts at its linear rate, the compression
    # stop at its tangent rate where the run can reach it
    k_stop = getattr(spring, "stop_rate", 0.0) * (stiffening if reach["compression_stop"] else 1.0)
    c_stop = getattr(spring, "stop_damping", 0.0)
    k_bumper = k_bumper if reach["bumper"] else 0.0
    rim = rim if reach["rim"] else None
    vs = np.linspace(-4.0, 4.0, 801)
    fork = _along(law.ForkLaw(law.LinearSpring(0.0), s.fork.damper, law.NoFriction()), np.zeros_like(vs), vs,
                  lambda x, v: s.fork.damper.force(v))
    c_fork = float(np.max(np.abs(np.diff(fork)) / np.diff(vs))) + getattr(s.fork.friction, "damping", 0.0)
    return {"working": k_spring + k_tire,
            "stops": k_spring + k_bumper + k_tire + k_stop + (rim.rate * stiffening if rim is not None else 0.0),
            "damping": c_fork + c_tire,
            "stop_damping": c_fork + c_tire + c_stop + (rim.damping if rim is not None else 0.0),
            "stops_out_of_reach": k_spring + k_tire + getattr(spring, "stop_rate", 0.0),
            "stop_damping_out_of_reach": c_fork + c_tire + c_stop}


def _round_down(value: float, digits: int = 2) -> str:
    """``value`` to ``digits`` significant digits, never above it (a limit stated must hold)."""
    exponent = math.floor(math.log10(value)) - digits + 1
    return f"{math.floor(value / 10**exponent) * 10**exponent:.{digits}g}"


# c dt / m for the callback's explicit damping (fork, tire, the stick's damping) over the working stroke.
DAMPING_STEP = {"rk4": 1.5, "implicitfast": 0.25, "implicit": 0.25, "euler": 0.25}
# Steps per wheel time constant m / c on the steep force-velocity slope some laws have near rest
# (a direction-dependent spring, regularised Coulomb friction): met only within a few bands of
# v = 0, where the drop engine refines (calibrated on the envelope of tests/test_envelope.py).
BAND_STEP = {"rk4": 2.0, "implicitfast": 1.0, "implicit": 1.0, "euler": 1.0}
BAND_WIDTHS = 3.0  # the refined velocity zone, in bands: tanh's slope is 1 % of its peak there


def _bands(law_object) -> list[float]:
    """The velocity bands (m/s) of the laws inside a spring or friction law."""
    found = []
    band = getattr(law_object, "band", None)
    if isinstance(band, float) and band > 0.0:
        found.append(band)
    for name in ("main", "inner", "compression", "rebound"):
        part = getattr(law_object, name, None)
        if part is not None and not isinstance(part, (int, float)):
            found += _bands(part)
    return found


def velocity_band(s: StepSetup) -> tuple[float, float]:
    """(half-width in m/s of the zone around v = 0 where the fork force changes steeply with the
    stroke velocity, the steepest slope there in N s/m); (0, 0) if there is none."""
    spring = s.fork.spring
    main = getattr(spring, "main", spring)
    friction = s.fork.friction
    bands = _bands(main) + ([] if friction.has_state else _bands(friction))
    if not bands:
        return 0.0, 0.0
    dv = 1e-3 * min(bands)
    xs = _stroke(s, 101)
    up, down = _spring_along(s, xs, (dv, -dv))
    slope = float(np.max(np.abs(up - down))) / (2.0 * dv)
    if not friction.has_state:
        slope += abs(friction.force(dv) - friction.force(-dv)) / (2.0 * dv)
    return BAND_WIDTHS * max(bands), slope


# A coarse step is refined when, at either end, the fork or the tire is within this distance
# plus what the step can cover of a stop's or the rim's reach (drop.stepping.stop_index).
STOP_MARGIN_M = 0.2e-3
STICK_SLIDING_STEP = 2.0  # RK4: dt |v| / z_ss while sliding (its stability bound is 2.8)


def stroke_speed_bound(s: StepSetup) -> float:
    """A bound on the fork's stroke speed (m/s): 1.5 times the speed of a fall from the drop
    height plus the travel."""
    return 1.5 * math.sqrt(2.0 * s.gravity * (s.drop_height + s.travel))


def state_step_per_speed(s: StepSetup) -> tuple[float, str]:
    """(L in m, what it is) where the friction state limits the step to L / |v| at stroke speed v
    (its rate grows with the speed); (0, "") for a law without a state."""
    friction = s.fork.friction
    if isinstance(friction, law.LuGre):
        return friction.coulomb / friction.stiffness, "the LuGre bristle state"
    if isinstance(friction, law.Sticking):
        # sliding, z relaxes at |v| / z_ss; through the elastic-to-sliding blend its slope peaks
        # at (1 + pi / (2 (1 - elastic))) times that. First-order integrators stay within 2 on
        # the peak; RK4 within STICK_SLIDING_STEP on the sliding rate (calibrated on the envelope)
        z_ss = friction.coulomb / friction.stiffness
        if s.integrator == "rk4":
            return STICK_SLIDING_STEP * z_ss, f"the stick state (presliding {z_ss * 1e3:.2f} mm)"
        return (2.0 * z_ss / (1.0 + math.pi / (2.0 * (1.0 - friction.elastic))),
                f"the stick state (presliding {z_ss * 1e3:.2f} mm)")
    return 0.0, ""


def refined_speed(s: StepSetup) -> float:
    """The stroke speed (m/s) above which the drop engine steps finely for the friction state,
    inf where ``s.timestep`` holds it at every speed."""
    per_speed, _ = state_step_per_speed(s)
    if per_speed <= 0.0 or per_speed / stroke_speed_bound(s) >= s.timestep:
        return math.inf
    return per_speed / s.timestep


def refined_band(s: StepSetup) -> float:
    """The velocity half-width (m/s) around rest that the drop engine steps finely, 0 where the
    slope there does not need it at ``s.timestep``."""
    half_width, slope = velocity_band(s)
    reduced = s.wheel_mass * s.body_mass / (s.wheel_mass + s.body_mass)
    return half_width if slope > 0.0 and BAND_STEP[s.integrator] * reduced / slope < s.timestep else 0.0


def stop_zone(spring) -> tuple[float, float]:
    """(low, high): fork compressions (m) at or below which the extension stop acts and at or above
    which the bumper (then the compression stop) does, also a bumper of no force; (-inf, inf) for a
    law without end stops. Where every rig steps finely for a stop (the drop, the bike's fork and
    its shock)."""
    if not hasattr(spring, "stop_forces"):
        return -math.inf, math.inf
    return -spring.extension, spring.bumper_start


def refine_zones(s: StepSetup) -> tuple[float, float, float, float, float]:
    """Where the drop engines step finely: (fork compression at the bumper or the compression
    stop, fork compression at the extension stop, :func:`stop_zone`; tire deflection at the rim,
    inf where there is none; the half-width of the steep velocity band around rest,
    :func:`refined_band`; the stroke speed above which the friction state is stiff,
    :func:`refined_speed`)."""
    extend, compress = stop_zone(s.fork.spring)
    rim = s.tire.rim.max_deflection if s.tire.rim is not None else math.inf
    return compress, extend, rim, refined_band(s), refined_speed(s)


class Limits(NamedTuple):
    """A setup's step limits, each a list of (largest step in s, what sets it): see :func:`limits`."""

    working: list  # the working stroke: hold everywhere
    stops: list  # an end stop or the rim engaged: only while one may act
    zones: list  # the other zones (the band around rest, fast sliding): hold near the stops as well
    far: list  # the stops' limits of the same fork with every stop out of reach

    @property
    def coarse(self) -> tuple[float, str]:
        """Over the working stroke: the drop's coarse step (:func:`timestep_limit`)."""
        return min(self.working)

    @property
    def away_from_stops(self) -> tuple[float, str]:
        """Where no end stop or rim acts, the other zones included: a rig that refines only near
        the stops steps within it throughout (:func:`away_from_stops_limit`)."""
        return min(self.working + self.zones)

    @property
    def fine(self) -> tuple[float, str]:
        """While an end stop or the rim may be engaged (:func:`fine_limit`)."""
        return min(self.working + self.stops + self.zones)

    @property
    def contact(self) -> tuple[float, str]:
        """In the drop's other zones (touchdown, lift-off, the band, fast sliding) away from the
        stops: ``contact_substeps``."""
        return min(self.working + self.far + self.zones)


def limits(s: StepSetup) -> Limits:
    """The step limits (s, what sets it) of the working stroke; those of the end stops and the
    rim, which the drop engine meets with ``substeps`` finer steps only while they may act; those
    of its other zones (the band around rest, fast sliding), which hold near the stops as well;
    and, for those other zones away from the stops (``contact_substeps``), the stops' limits of
    the same fork with every stop out of reach, at the steps per period of this one (a fork that
    can reach its compression stop or the rim lands hard: the tire's damping force jumps by B v
    at touchdown; one random S10 fork was 0.049 mm off the reference at 12 steps per period,
    0.006 mm at 24). ``s.wheel_mass`` is the mass on the tire and the stops, the reduced mass of
    it and ``s.body_mass`` the one the damping and the band act on."""
    scan = _spring_scan(s)
    reach = reachable(s, scan)
    rates = stiffest_rates(s, reach, scan)
    hard = reach["compression_stop"] or reach["rim"]
    wheel = s.wheel_mass
    reduced = s.wheel_mass * s.body_mass / (s.wheel_mass + s.body_mass)

    def period(name, table, what):
        per_period = table[s.integrator]
        return (2.0 * math.pi * math.sqrt(wheel / rates[name]) / per_period,
                f"{per_period:g} steps per period of the wheel on the {what} ({rates[name] / 1e3:.0f} N/mm)")

    working = [period("working", STEPS_PER_PERIOD, "spring and tire over the stroke")]
    per_stop = HARD_STOP_STEPS_PER_PERIOD if hard else STOP_STEPS_PER_PERIOD
    stops = [period("stops", per_stop, "bumper, hard stops and rim")]
    far = [period("stops_out_of_reach", per_stop, "stops out of reach")]
    zones = []
    for name, found in (("stop_damping", stops), ("stop_damping_out_of_reach", far)):
        if rates[name] > 0:  # brief contacts: the stability bound of explicit damping
            found.append((0.5 * reduced / rates[name],
                           f"explicit damping with a stop engaged ({rates[name]:.0f} N s/m on the wheel)"))
    if rates["damping"] > 0:
        # the callback's damping forces are explicit: c dt / m within DAMPING_STEP (the stability
        # bounds are 2 for explicit Euler, 2.8 for RK4; the margin keeps the envelope at 0.05 mm)
        factor = DAMPING_STEP[s.integrator]
        working.append((factor * reduced / rates["damping"],
                        f"explicit damping, c dt / m <= {factor:g} ({rates['damping']:.0f} N s/m on the wheel)"))
    per_speed, what = state_step_per_speed(s)
    if per_speed > 0.0:  # the friction state stiffens with the stroke speed: refined when fast
        v_max = stroke_speed_bound(s)
        zones.append((per_speed / v_max, f"{what} at {v_max:.1f} m/s"))
    working.append((1.0 / s.sample_rate, f"solver.sample_rate_Hz ({s.sample_rate:g} Hz)"))
    half_width, slope = velocity_band(s)
    if slope > 0.0:
        zones.append((BAND_STEP[s.integrator] * reduced / slope,
                      f"the force-velocity slope near rest ({slope:.0f} N s/m within {half_width * 1e3:.0f} mm/s)"))
    return Limits(working, stops, zones, far)


def timestep_limit(s: StepSetup) -> tuple[float, str]:
    """(largest MuJoCo step in s for this configuration and integrator over the working stroke,
    what sets it). While a stop may act the drop engine steps finer (:func:`fine_limit`)."""
    return limits(s).coarse


def away_from_stops_limit(s: StepSetup) -> tuple[float, str]:
    """(largest step where no end stop or rim acts, what sets it): the working stroke's limits and
    those of the other zones (the band around rest, fast sliding), which may hold anywhere."""
    return limits(s).away_from_stops


def fine_limit(s: StepSetup) -> tuple[float, str]:
    """(largest step while an end stop or the rim may be engaged, what sets it)."""
    return limits(s).fine


def _whole_fraction(interval: float, step: float) -> bool:
    """Whether ``step`` goes into ``interval`` a whole number of times."""
    ratio = interval / step
    return round(ratio) >= 1 and abs(ratio - round(ratio)) <= 1e-6 * ratio


def cuts_within(interval: float, limit: float) -> int:
    """The fewest equal steps ``interval`` is cut into for each to stay within ``limit`` (at least 1)."""
    return max(1, math.ceil(interval / limit * (1.0 - 1e-12)))


def fraction_within(interval: float, limit: float) -> float:
    """The largest whole fraction interval / k not above ``limit``."""
    return interval / cuts_within(interval, limit)


def choose_timestep(s: StepSetup) -> StepSetup:
    """The step for MuJoCo: the user's ``solver.timestep_s`` if within the limit and a whole
    fraction of the logger's sample interval (else one line naming the limit), or the largest
    step of ``STEP_LADDER`` within the limit that is such a fraction (else the largest fraction
    within it); and the number of finer steps it is cut into where the drop engine refines
    (``substeps``). The output is the step's grid decimated to the logger's rate: a step that
    did not divide its interval would log at another rate than the one asked for."""
    bounds = limits(s)
    limit, what = bounds.coarse
    interval = 1.0 / s.sample_rate
    if s.timestep > 0.0:
        if s.timestep > limit:
            raise ConfigError(
                f"solver.timestep_s: {s.timestep:g} s is too large for solver.integrator = {s.integrator} "
                f"with this configuration ({what}); use at most {fraction_within(interval, limit):.10g} s, or "
                f"leave it out to have it chosen")
        if not _whole_fraction(interval, s.timestep):
            raise ConfigError(
                f"solver.timestep_s: {s.timestep:g} s does not go a whole number of times into the logger's "
                f"sample interval (1 / solver.sample_rate_Hz = {interval:.10g} s); use "
                f"{fraction_within(interval, s.timestep):.10g} s or another whole fraction of it")
        step = s.timestep
    else:
        if not limit >= STEP_LADDER[-1]:  # also a limit of 0 (a mass of 5e-324 kg) or NaN: no step would do
            raise ConfigError(f"solver.timestep_s: this configuration needs a step below "
                              f"{_round_down(limit) if limit > 0.0 else '0'} s ({what}); check its rates and masses")
        step = next((h for h in STEP_LADDER if h <= limit and _whole_fraction(interval, h)), None)
        if step is None:
            step = fraction_within(interval, limit)
        if step < STEP_LADDER[-1]:
            raise ConfigError(f"solver.timestep_s: this configuration needs a step below {_round_down(limit)} s "
                              f"({what}); check its rates and masses")
    fine, what = bounds.fine
    substeps = _cuts(step, fine)
    if substeps > 1 and fine < STEP_LADDER[-1]:
        raise ConfigError(f"solver.timestep_s: this configuration needs a step below {_round_down(fine)} s "
                          f"while a stop acts ({what}); check its rates and masses")
    # the other zones (touchdown, lift-off, the band, fast sliding) away from the stops
    contact = min(substeps, _cuts(step, bounds.contact[0]))
    return replace(s, timestep=step, substeps=substeps, contact_substeps=contact)


def _cuts(step: float, fine: float) -> int:
    """How many steps ``step`` is cut into to stay within ``fine``: the largest step of the
    ladder within the limit that divides it, else an even cut."""
    ratios = [step / h for h in STEP_LADDER if h <= min(fine, step)]
    whole = [round(r) for r in ratios if abs(r - round(r)) < 1e-9]
    return whole[0] if whole else cuts_within(step, fine)


ROLLING_STEP_S = 5e-4  # the rolling rigs' largest step (RK4): the step their cross-checks cover
REACH_MARGIN_M = 1e-3  # distance from a stop (fork travel, tire deflection) taken as within reach


def rolling(s: StepSetup) -> StepSetup:
    """``s`` stepped as a rolling rig steps it: ``timestep`` the largest whole fraction of
    ``ROLLING_STEP_S`` within the limits away from the stops (:attr:`Limits.away_from_stops`),
    ``substeps`` finer steps, each within the drop's fine step (the step the drop's cross-checks
    cover at its stops and rim), where the rig finds that one may act (``contact_substeps`` 1)."""
    coarse = fraction_within(ROLLING_STEP_S, limits(s).away_from_stops[0])
    substeps = cuts_within(coarse, s.fine_timestep)
    return replace(s, timestep=coarse, substeps=substeps, contact_substeps=1)


def reach_span(signals) -> tuple[int, int] | None:
    """The first row of a chunk stepped coarse at which a stop, the rim or a band of fast-changing
    force was within reach, and the last row of the run of rows within reach that it starts; or
    None. ``signals``: (values, (low, high), margin) per signal, one value per coarse step, a stop at
    or below ``low`` and at or above ``high``; or (values, (low, high), margin, "inside"): a band
    from ``low`` to ``high``. Within reach of row i: within ``margin`` plus twice the larger change
    of the coarse steps into and out of it, so a stop or band met between two rows is within reach
    of both. (Rows after the run are stepped again anyway: the plan keeps what lies before it.)"""
    hit = None
    for x, (low, high), margin, *kind in signals:
        x = np.asarray(x, float)
        step = np.abs(np.diff(x))
        move = np.zeros_like(x)
        if x.size > 1:
            move[:-1] = step
            move[1:] = np.maximum(move[1:], step)
        reach = margin + 2.0 * move
        if kind == ["inside"]:
            near = (x >= low - reach) & (x <= high + reach)
        else:
            near = (x >= high - reach) | (x <= low + reach)
        hit = near if hit is None else hit | near
    if hit is None or not hit.any():
        return None
    first = int(np.argmax(hit))
    after = np.flatnonzero(~hit[first:])
    return first, first + (int(after[0]) - 1 if after.size else len(hit) - 1 - first)


def at_fine_step(s: StepSetup) -> StepSetup:
    """``s`` stepped at its fine step throughout (``substeps`` 1): for a model stepped directly,
    without refinement near stops (raw rollouts, a test that looks at every fine step)."""
    return replace(s, timestep=s.fine_timestep, substeps=1, contact_substeps=1)

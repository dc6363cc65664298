"""Tire laws: a radial Kelvin-Voigt spring and damper that pushes but never pulls.

The MuJoCo engine realises the law as a calibrated soft contact (``mtbmj.drop.scene``); the ODE
reference evaluates ``force`` directly. Deflection is positive into the ground.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from mtbmj.controllers.stops import DAMPING_RAMP

SWITCH_RULE = ("impact values through the first impact; in-contact values from the first lift-off of the tire, "
               "or, if it stays on the ground, from the end of the fork's first rebound stroke")


def kelvin_voigt_force(rate, damping, deflection, deflection_rate):
    """max(0, k d + b dd/dt) while d > 0, else 0 (written once; the fast engine compiles it)."""
    if deflection <= 0.0:
        return 0.0
    return max(0.0, rate * deflection + damping * deflection_rate)


def floor_correction(factor, wheel_weight, rate, damping, deflection, deflection_rate, wheel_force):
    """``ContactFloor.correction`` (written once; the drop's compiled callback compiles it)."""
    if deflection <= 0.0:
        return 0.0
    f = rate * deflection + damping * deflection_rate
    if f <= 0.0:
        return 0.0
    return factor * (f + wheel_force - wheel_weight)


@dataclass(frozen=True)
class KelvinVoigt:
    """F = max(0, k d + b dd/dt) while d > 0, else 0: a contact can only push."""

    rate: float  # N/m
    damping: float  # N s/m

    def force(self, deflection, rate):
        return kelvin_voigt_force(self.rate, self.damping, deflection, rate)


# The rolling tire's damping sets in with the depth of each contact patch, c tanh(DAMPING_RAMP d /
# TIRE_DAMPING_DEPTH_M) dd/dt (20 % at 0.2 mm, 76 % at 1 mm, 99.5 % at 3 mm), as a patch's area grows
# from nothing: rolling onto an edge meets a new patch at dd/dt = v n (about 2 m/s at 4 m/s), where the
# drop's Kelvin-Voigt law would jump by c v n at first touch (302 N on the square edge, 28 % of its
# peak, in one 0.1 ms step). Assumed (no measurement of a tire's damping against its deflection); 3 mm
# is a tenth of the tire's working deflection. The drop keeps the paper's law (KelvinVoigt).
TIRE_DAMPING_DEPTH_M = 3e-3


def rolling_tire_force(rate: float, damping: float, d: float, v: float) -> float:
    """One contact patch of the rolling tire at deflection d >= 0 and rate dd/dt = v, before
    clipping (the caller keeps it >= 0): k d + c tanh(DAMPING_RAMP d / TIRE_DAMPING_DEPTH_M) v.
    Written once: ``mtbmj.rolling.tire.RadialTire`` calls it and the compiled rolling callback
    compiles this same source."""
    return rate * d + damping * math.tanh(DAMPING_RAMP * (d / TIRE_DAMPING_DEPTH_M)) * v


@dataclass(frozen=True)
class ContactFloor:
    """The force the MuJoCo engine adds to the wheel so that its soft tire contact acts as the
    Kelvin-Voigt law exactly (the drop scene; ``mtbmj.drop.scene``).

    MuJoCo softens a contact through its impedance d, which it never lets fall below 1e-4
    (``mjMINIMP``). With the calibrated solref the contact pushes with (1 - d) f - d F, where f is
    the law's force and F every other force on the wheel (its weight, the fork, the rim): in
    contact the wheel accelerates as (1 - d)(f + F) / m, as if its mass were m / (1 - d). Adding
    C = d / (1 - d) (f + F) upward on the wheel while the contact pushes makes that (f + F) / m,
    the reference's equation. ``rate`` and ``damping`` are the law's current values (they change
    at the tire switch)."""

    factor: float  # d / (1 - d)
    wheel_weight: float  # N, m g
    rate: float  # N/m
    damping: float  # N s/m

    def correction(self, deflection: float, rate: float, wheel_force: float) -> float:
        """C (N, upward on the wheel) at tire ``deflection`` and its ``rate``, with
        ``wheel_force`` the upward force of the fork and the rim on the wheel (the callback's
        generalized force on the fork joint); 0 while the contact does not push."""
        return floor_correction(self.factor, self.wheel_weight, self.rate, self.damping, deflection, rate, wheel_force)


@dataclass(frozen=True)
class TireLaw:
    """Tire values per phase: phase 0 (impact values) through the first impact, phase 1 (the
    in-contact values of the coefficient-of-restitution method) afterwards, and the rim.

    ``in_contact`` is None for laws that never switch (impact, undamped, static). The switch is
    made by the contact state (``SWITCH_RULE``): at the first of (a) the tire leaving the ground
    after the first impact (its deflection falls to zero) and (b) the end of the fork's first
    rebound stroke while the tire stays on the ground (the fork stops extending: its velocity
    crosses zero from extension into compression). On the paper's drop (a) comes first: the tire
    lifts off before the fork tops out in the air, so the landing (Peak 2) and everything after
    it uses the in-contact values; on a drop too small to lift off, (b) ends the impact event.
    ``rim`` (``controllers.stops.Rim``) adds the rim's force past the maximum deflection.
    """

    impact: KelvinVoigt
    in_contact: KelvinVoigt | None = None
    rim: object | None = None

    @property
    def switches(self) -> bool:
        return self.in_contact is not None

    def values(self, phase: int) -> KelvinVoigt:
        return self.in_contact if (phase and self.in_contact is not None) else self.impact

    def force(self, deflection, rate, phase=0):
        f = self.values(phase).force(deflection, rate)
        if self.rim is not None:
            f += self.rim.force(deflection, rate)
        return f


PSI = 6894.757293168  # Pa per psi

# Tire rates from the inflation pressure (``tire.pressure_psi``), a 29 x 2.3 in knobby tire; every
# number with its source (docs/reference.md section 3, docs/configuration.md):
REFERENCE_STATIC_RATE = 62e3  # N/m, sourced (secondhand): static radial stiffness at 25 psi, 418 N load
REFERENCE_PRESSURE = 25.0 * PSI  # Pa, sourced: 1.72 bar, with the rate above (Dressel & Sadauckas 2020)
# Pa: the measured range, 1.03 bar (sourced: the pressure of their largest deflection, 48.7 mm) to
# 1.72 bar (sourced: the anchor above). Outside it the relation is extrapolated (assumed: the same
# proportionality, the carcass's own stiffness still neglected); mtbmj.config warns there.
PRESSURE_RANGE = (15.0 * PSI, 25.0 * PSI)
IMPACT_OVER_STATIC = 1.38  # sourced (secondhand): first-impact dynamic / static (Sadauckas et al. 2024)
CONTACT_OVER_STATIC = 1.19  # sourced (secondhand): settled in-contact dynamic / static (same source)


def static_rate_from_pressure(pressure: float) -> float:
    """Static radial stiffness (N/m) of the tire at gauge ``pressure`` (Pa).

    Model: a tire whose walls do not stretch carries its load by the inflation pressure over the
    contact patch (Renart & Roura-Grabulosa, "Deformation of an inflated bicycle tire when loaded",
    Am. J. Phys. 87, 102, 2019), so at a given deflection the force, and the rate, scale with the
    gauge pressure: k(p) = k_ref p / p_ref, anchored at 62 N/mm and 25 psi (Dressel & Sadauckas
    2020, Appl. Sci. 10(9):3156). Assumed: the carcass's own stiffness is neglected (so the rate is
    likely too soft at low pressure), and the proportionality holds outside the measured
    ``PRESSURE_RANGE`` (15-25 psi), where ``mtbmj.config`` warns that the rates are extrapolated.
    """
    return REFERENCE_STATIC_RATE * pressure / REFERENCE_PRESSURE


__all__ = ["kelvin_voigt_force", "floor_correction", "rolling_tire_force", "TIRE_DAMPING_DEPTH_M", "KelvinVoigt", "TireLaw", "static_rate_from_pressure", "PRESSURE_RANGE", "IMPACT_OVER_STATIC",
           "CONTACT_OVER_STATIC"]

"""Tire laws: a radial Kelvin-Voigt spring and damper that pushes but never pulls.

The MuJoCo engine realises the law as a calibrated soft contact (``mtbmj.drop.scene``); the ODE
reference evaluates ``force`` directly. Deflection is positive into the ground.
"""
from __future__ import annotations

from dataclasses import dataclass

SWITCH_RULE = ("impact values through the first impact; in-contact values from the first lift-off of the tire, "
               "or, if it stays on the ground, from the end of the fork's first rebound stroke")


@dataclass(frozen=True)
class KelvinVoigt:
    """F = max(0, k d + b dd/dt) while d > 0, else 0: a contact can only push."""

    rate: float  # N/m
    damping: float  # N s/m

    def force(self, deflection, rate):
        if deflection <= 0.0:
            return 0.0
        return max(0.0, self.rate * deflection + self.damping * rate)


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

    @staticmethod
    def switch_now(previous_deflection: float, deflection: float, previous_fork_velocity: float,
                   fork_velocity: float) -> bool:
        """The switching event between two states of phase 0 after the first impact: the tire
        leaves the ground (deflection falls to <= 0) or the fork ends its first rebound stroke
        (velocity crosses from < 0 to >= 0)."""
        return (previous_deflection > 0.0 >= deflection) or (previous_fork_velocity < 0.0 <= fork_velocity)


__all__ = ["KelvinVoigt", "TireLaw"]

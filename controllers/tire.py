"""Tire laws: a radial Kelvin-Voigt spring and damper that pushes but never pulls.

The MuJoCo engine realises the law as a calibrated soft contact (``mtbmj.drop.scene``); the ODE
reference evaluates ``force`` directly. Deflection is positive into the ground.
"""
from __future__ import annotations

from dataclasses import dataclass


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
    """Tire values per phase: phase 0 from free fall through the first fork topping event,
    phase 1 afterwards (the in-contact values of the coefficient-of-restitution method).

    ``in_contact`` is None for laws that never switch (impact, undamped, static). The switch
    happens when the fork first tops out (its compression crosses zero going into extension),
    which on the drop sled happens while the tire is in the air after the first bounce.
    """

    impact: KelvinVoigt
    in_contact: KelvinVoigt | None = None

    @property
    def switches(self) -> bool:
        return self.in_contact is not None

    def values(self, phase: int) -> KelvinVoigt:
        return self.in_contact if (phase and self.in_contact is not None) else self.impact

    def force(self, deflection, rate, phase=0):
        return self.values(phase).force(deflection, rate)

    @staticmethod
    def topped_out(previous_compression: float, compression: float) -> bool:
        """The switching event: fork compression crosses zero going into extension."""
        return previous_compression > 0.0 >= compression


__all__ = ["KelvinVoigt", "TireLaw"]

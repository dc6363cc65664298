"""Fork friction laws after Olsson, Astrom, Canudas de Wit, Gafvert & Lischinsky (1998),
"Friction models and friction compensation", Eur. J. Control 4(3):176-195, and the LuGre model of
Canudas de Wit, Olsson, Astrom & Lischinsky (1995), IEEE TAC 40(3):419-425.

Force in N opposing the stroke (positive for compression velocity v > 0). The sign function of
the static models is regularised as tanh(v / band): an exact sgn(v) would make every velocity
reversal a force step that no fixed-step engine can resolve. The band is a stated model parameter
and both engines use the same regularised law, so they can be compared exactly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from mtbmj.controllers.guards import SmoothLaw, on_positive_side


def smooth_sign(v: float, band: float) -> float:
    """tanh(v / band): sgn(v) for |v| >> band, linear with slope 1/band near zero."""
    return math.tanh(v / band)


@dataclass(frozen=True)
class NoFriction(SmoothLaw):
    def force(self, v, z=0.0, sides=None):
        return 0.0


@dataclass(frozen=True)
class Coulomb(SmoothLaw):
    """F = F_C sgn(v) (Olsson 1998, Fig. 1a); the friction offset seen on a dyno at v = 0."""

    coulomb: float  # N
    band: float  # m/s
    def force(self, v, z=0.0, sides=None):
        return self.coulomb * smooth_sign(v, self.band)


@dataclass(frozen=True)
class CoulombViscous(SmoothLaw):
    """F = F_C sgn(v) + F_v v (Olsson 1998, Fig. 1b)."""

    coulomb: float  # N
    viscous: float  # N s/m
    band: float
    def force(self, v, z=0.0, sides=None):
        return self.coulomb * smooth_sign(v, self.band) + self.viscous * v


@dataclass(frozen=True)
class Stiction:
    """Coulomb + viscous with stiction (Olsson 1998, Fig. 1c), Karnopp style.

    Inside the band |v| < dv (Karnopp's "zero velocity" band) the friction can reach the
    breakaway force F_S; outside it falls to F_C sgn(v) + F_v v. The level drops linearly from
    F_S at v = 0 to F_C at |v| = dv so the force stays continuous; the kinks at |v| = dv are
    guards for the ODE reference.
    """

    coulomb: float
    breakaway: float
    viscous: float
    stiction_band: float  # m/s, Karnopp's DV
    band: float
    n_guards = 2
    has_state = False

    def guards(self, x, v):
        return (v - self.stiction_band, v + self.stiction_band)

    def force(self, v, z=0.0, sides=None):
        outside = on_positive_side(v - self.stiction_band, sides, 0) or not on_positive_side(
            v + self.stiction_band, sides, 1
        )
        level = self.coulomb
        if not outside:
            level += (self.breakaway - self.coulomb) * (1.0 - abs(v) / self.stiction_band)
        return level * smooth_sign(v, self.band) + self.viscous * v


@dataclass(frozen=True)
class Stribeck(SmoothLaw):
    """F = [F_C + (F_S - F_C) exp(-|v/v_S|^delta)] sgn(v) + F_v v (Olsson 1998, eq. 3, Fig. 1d)."""

    coulomb: float
    breakaway: float
    viscous: float
    stribeck_velocity: float  # m/s
    exponent: float
    band: float
    def force(self, v, z=0.0, sides=None):
        level = self.coulomb + (self.breakaway - self.coulomb) * math.exp(
            -abs(v / self.stribeck_velocity) ** self.exponent
        )
        return level * smooth_sign(v, self.band) + self.viscous * v


@dataclass(frozen=True)
class LuGre:
    """Dynamic LuGre friction (Canudas de Wit et al. 1995; Olsson 1998 eq. 10-12).

    dz/dt = v - sigma0 |v| z / g(v),  g(v) = F_C + (F_S - F_C) exp(-(v / v_S)^2),
    F = sigma0 z + sigma1 dz/dt + sigma2 v.
    z (m) is the mean bristle deflection, an internal state integrated with the rest of the state
    on both engines. No regularisation is needed: the bristles give the stiction.
    """

    coulomb: float
    breakaway: float
    stribeck_velocity: float
    stiffness: float  # sigma0, N/m
    damping: float  # sigma1, N s/m
    viscous: float  # sigma2, N s/m
    n_guards = 1
    has_state = True

    def guards(self, x, v):
        return (v,)

    def g(self, v):
        return self.coulomb + (self.breakaway - self.coulomb) * math.exp(-((v / self.stribeck_velocity) ** 2))

    def state_rate(self, v, z, sides=None):
        speed = v if on_positive_side(v, sides, 0) else -v
        return v - self.stiffness * speed * z / self.g(v)

    def force(self, v, z=0.0, sides=None):
        return self.stiffness * z + self.damping * self.state_rate(v, z, sides) + self.viscous * v


__all__ = ["smooth_sign", "NoFriction", "Coulomb", "CoulombViscous", "Stiction", "Stribeck", "LuGre"]

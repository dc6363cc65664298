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


def sliding_level(law, v, sides=None) -> tuple[float, float]:
    """(level, viscous) of a static law: |F(v)| without its viscous part, and that part's
    coefficient. The level is what ``Sticking`` slides at."""
    kind = type(law)
    if kind is Coulomb:
        return law.coulomb, 0.0
    if kind is CoulombViscous:
        return law.coulomb, law.viscous
    if kind is Stribeck:
        return law.coulomb + (law.breakaway - law.coulomb) * math.exp(
            -abs(v / law.stribeck_velocity) ** law.exponent), law.viscous
    if kind is Stiction:
        outside = on_positive_side(v - law.stiction_band, sides, 0) or not on_positive_side(
            v + law.stiction_band, sides, 1)
        level = law.coulomb
        if not outside:
            level += (law.breakaway - law.coulomb) * (1.0 - abs(v) / law.stiction_band)
        return level, law.viscous
    raise TypeError(f"{kind.__name__} has no sliding level")


@dataclass(frozen=True)
class Sticking:
    """A static friction law that sticks: the elasto-plastic bristle model of Dupont, Hayward,
    Armstrong & Altpeter (2002), "Single state elastoplastic friction models", IEEE TAC 47(5):787-792.

    The bristle deflection z (m) is a state integrated with the rest (MuJoCo: an actuator
    activation, as LuGre's). With z_ss(v) = level(v) / sigma0 the steady sliding deflection
    (``level`` from the wrapped law: F_C, or its Stribeck/stiction curve),

        dz/dt = v (1 - alpha(z, v) |z| / z_ss(v)),    F = sigma0 z + sigma1 dz/dt + F_v v,

    where sigma1 fades with speed, sigma1 exp(-(v / v_d)^2), so that it damps the stuck fork without
    adding damping to the stroke; and alpha = 0 while |z| <= elastic * z_ss or z and v have opposite signs (pure stick: z follows
    the stroke exactly, so a fork at rest under a load below the breakaway does not creep), alpha = 1
    for |z| >= z_ss (sliding at the wrapped law's level), and a C1 half-sine between. Unlike the
    regularised sign of the static laws (which lets the fork creep towards the frictionless
    balance) and unlike LuGre (which drifts under small oscillating loads), the fork stays where
    it stuck. The price: a presliding displacement up to z_ss, and a stiff z equation while sliding
    (rate |v| / z_ss), which the step rule accounts for.
    """

    inner: object  # Coulomb, CoulombViscous, Stribeck or Stiction
    stiffness: float  # sigma0, N/m
    damping: float  # sigma1, N s/m, at rest
    damping_velocity: float = 0.01  # m/s: sigma1 fades as exp(-(v / this)^2) (Dupont et al. 2002, eq. 14)
    elastic: float = 0.5  # z_ba / z_ss
    has_state = True

    @property
    def coulomb(self) -> float:
        return self.inner.coulomb

    @property
    def n_guards(self):
        # No guard at v = 0: dz/dt is continuous there (zero on both sides), and a stuck fork's
        # velocity decays to zero, where a guard would fire at every rounding error.
        return self.inner.n_guards

    def guards(self, x, v):
        return self.inner.guards(x, v)

    def state_rate(self, v, z, sides=None):
        level, _ = sliding_level(self.inner, v, None if sides is None else sides[: self.inner.n_guards])
        return self._rate(v, z, level)

    def _rate(self, v, z, level):
        z_ss = level / self.stiffness
        if (z > 0.0) != (v >= 0.0) or z == 0.0:
            return v
        r = abs(z) / z_ss
        if r <= self.elastic:
            return v
        if r >= 1.0:
            alpha = 1.0
        else:
            alpha = 0.5 + 0.5 * math.sin(math.pi * (r - 0.5 * (1.0 + self.elastic)) / (1.0 - self.elastic))
        return v * (1.0 - alpha * r)

    def force(self, v, z=0.0, sides=None):
        level, viscous = sliding_level(self.inner, v, None if sides is None else sides[: self.inner.n_guards])
        w = v / self.damping_velocity
        damping = self.damping * math.exp(-(w * w))
        return self.stiffness * z + damping * self._rate(v, z, level) + viscous * v


__all__ = ["smooth_sign", "NoFriction", "Coulomb", "CoulombViscous", "Stiction", "Stribeck", "LuGre", "Sticking",
           "sliding_level"]

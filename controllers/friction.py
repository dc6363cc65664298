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

from mtbmj.controllers.guards import LIVE, SmoothLaw, flag, side

# LuGre's g(v) has the exponent 2 (Canudas de Wit et al. 1995). Kept as a float so that Python and
# the compiled kernels make the same pow() call (a literal 2 may be folded into v * v).
LUGRE_EXPONENT = 2.0


# ----------------------------------------------------------------------------------------------
# The formulas, each written once (see ``controllers.spring``: the law objects call them, the
# compiled kernels compile the same source).
# ----------------------------------------------------------------------------------------------
def smooth_sign(v: float, band: float) -> float:
    """tanh(v / band): sgn(v) for |v| >> band, linear with slope 1/band near zero."""
    return math.tanh(v / band)


def coulomb_force(coulomb, band, v):
    return coulomb * smooth_sign(v, band)


def coulomb_viscous_force(coulomb, viscous, band, v):
    return coulomb * smooth_sign(v, band) + viscous * v


def stiction_level(coulomb, breakaway, stiction_band, v, s0=LIVE, s1=LIVE):
    """Karnopp's level: F_S at rest falling linearly to F_C at |v| = dv."""
    outside = side(v - stiction_band, s0) or not side(v + stiction_band, s1)
    level = coulomb
    if not outside:
        level += (breakaway - coulomb) * (1.0 - abs(v) / stiction_band)
    return level


def stiction_force(coulomb, breakaway, viscous, stiction_band, band, v, s0=LIVE, s1=LIVE):
    return stiction_level(coulomb, breakaway, stiction_band, v, s0, s1) * smooth_sign(v, band) + viscous * v


def stribeck_level(coulomb, breakaway, stribeck_velocity, exponent, v):
    return coulomb + (breakaway - coulomb) * math.exp(-abs(v / stribeck_velocity) ** exponent)


def stribeck_force(coulomb, breakaway, viscous, stribeck_velocity, exponent, band, v):
    return stribeck_level(coulomb, breakaway, stribeck_velocity, exponent, v) * smooth_sign(v, band) + viscous * v


def lugre_rate(coulomb, breakaway, stribeck_velocity, stiffness, v, z, s0=LIVE):
    """dz/dt = v - sigma0 |v| z / g(v)."""
    g = coulomb + (breakaway - coulomb) * math.exp(-((v / stribeck_velocity) ** LUGRE_EXPONENT))
    speed = v if side(v, s0) else -v
    return v - stiffness * speed * z / g


def lugre_force(stiffness, damping, viscous, rate, v, z):
    """sigma0 z + sigma1 dz/dt + sigma2 v, given dz/dt."""
    return stiffness * z + damping * rate + viscous * v


def sticking_rate(stiffness, elastic, level, v, z):
    """The elasto-plastic bristle's dz/dt at the wrapped law's sliding ``level``."""
    z_ss = level / stiffness
    if (z > 0.0) != (v >= 0.0) or z == 0.0:
        return v
    r = abs(z) / z_ss
    if r <= elastic:
        return v
    if r >= 1.0:
        alpha = 1.0
    else:
        alpha = 0.5 + 0.5 * math.sin(math.pi * (r - 0.5 * (1.0 + elastic)) / (1.0 - elastic))
    return v * (1.0 - alpha * r)


def sticking_force(stiffness, damping, damping_velocity, viscous, rate, v, z):
    """sigma0 z + sigma1 exp(-(v / v_d)^2) dz/dt + F_v v, given dz/dt."""
    w = v / damping_velocity
    return stiffness * z + damping * math.exp(-(w * w)) * rate + viscous * v


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
        return coulomb_force(self.coulomb, self.band, v)


@dataclass(frozen=True)
class CoulombViscous(SmoothLaw):
    """F = F_C sgn(v) + F_v v (Olsson 1998, Fig. 1b)."""

    coulomb: float  # N
    viscous: float  # N s/m
    band: float
    def force(self, v, z=0.0, sides=None):
        return coulomb_viscous_force(self.coulomb, self.viscous, self.band, v)


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
        return stiction_force(self.coulomb, self.breakaway, self.viscous, self.stiction_band, self.band, v,
                              flag(sides, 0), flag(sides, 1))


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
        return stribeck_force(self.coulomb, self.breakaway, self.viscous, self.stribeck_velocity, self.exponent,
                              self.band, v)


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
        return lugre_rate(self.coulomb, self.breakaway, self.stribeck_velocity, self.stiffness, v, z, flag(sides, 0))

    def force(self, v, z=0.0, sides=None):
        return lugre_force(self.stiffness, self.damping, self.viscous, self.state_rate(v, z, sides), v, z)


def sliding_level(law, v, sides=None) -> tuple[float, float]:
    """(level, viscous) of a static law: |F(v)| without its viscous part, and that part's
    coefficient. The level is what ``Sticking`` slides at."""
    kind = type(law)
    if kind is Coulomb:
        return law.coulomb, 0.0
    if kind is CoulombViscous:
        return law.coulomb, law.viscous
    if kind is Stribeck:
        return stribeck_level(law.coulomb, law.breakaway, law.stribeck_velocity, law.exponent, v), law.viscous
    if kind is Stiction:
        return stiction_level(law.coulomb, law.breakaway, law.stiction_band, v, flag(sides, 0),
                              flag(sides, 1)), law.viscous
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
        return sticking_rate(self.stiffness, self.elastic, level, v, z)

    def force(self, v, z=0.0, sides=None):
        level, viscous = sliding_level(self.inner, v, None if sides is None else sides[: self.inner.n_guards])
        return sticking_force(self.stiffness, self.damping, self.damping_velocity, viscous, self._rate(v, z, level),
                              v, z)


__all__ = ["coulomb_force", "coulomb_viscous_force", "stiction_level", "stiction_force", "stribeck_level",
           "stribeck_force", "lugre_rate", "lugre_force", "sticking_rate", "sticking_force", "LUGRE_EXPONENT",
           "smooth_sign", "NoFriction", "Coulomb", "CoulombViscous", "Stiction", "Stribeck", "LuGre", "Sticking",
           "sliding_level"]

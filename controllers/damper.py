"""Fork damper laws: hydraulic force in N from compression velocity v (m/s), compression positive.

The friction offset a dyno shows at v = 0 is not part of these laws; it is a friction law
(``controllers.friction``) added by ``controllers.fork.ForkLaw``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.controllers.guards import LIVE, SmoothLaw, flag, side


# The formulas, each written once (see ``controllers.spring``: the law objects call them, the
# compiled kernels compile the same source).
def linear_damper_force(coefficient, v):
    return coefficient * v


def bilinear_damper_force(compression, rebound, v, s0=LIVE):
    return (compression if side(v, s0) else rebound) * v


def digressive_damper_force(compression_low, compression_high, compression_knee, rebound_low, rebound_high,
                            rebound_knee, v, s0=LIVE, s1=LIVE, s2=LIVE):
    if side(v, s0):
        if side(v - compression_knee, s1):
            return compression_low * compression_knee + compression_high * (v - compression_knee)
        return compression_low * v
    if side(v + rebound_knee, s2):
        return rebound_low * v
    return -rebound_low * rebound_knee + rebound_high * (v + rebound_knee)


def orifice_damper_force(bleed, compression, rebound, v):
    """A bleed in parallel with an orifice: bleed v + c v |v|, c by direction."""
    c = compression if v >= 0.0 else rebound
    return bleed * v + c * v * abs(v)


def table_segment(velocity, n, v):
    """The segment of a table of ``n`` velocities (ascending) that v falls in, 0 to n - 2."""
    i = 0
    for j in range(1, n - 1):
        if v >= velocity[j]:
            i += 1
        else:
            break
    return i


def table_damper_force(velocity, force, slopes, i, v):
    """Linear on segment i of the table (extrapolated with the end slopes)."""
    return force[i] + slopes[i] * (v - velocity[i])


@dataclass(frozen=True)
class LinearDamper(SmoothLaw):
    """F = c v with one coefficient (the average of compression and rebound; S1-S8)."""

    coefficient: float  # N s/m

    def force(self, v, sides=None):
        return linear_damper_force(self.coefficient, v)


@dataclass(frozen=True)
class BilinearDamper:
    """Separate compression and rebound coefficients (paper Fig. 6, S9)."""

    compression: float  # N s/m, v >= 0
    rebound: float  # N s/m, v < 0
    n_guards = 1

    def guards(self, x, v):
        return (v,)

    def force(self, v, sides=None):
        return bilinear_damper_force(self.compression, self.rebound, v, flag(sides, 0))


@dataclass(frozen=True)
class DigressiveDamper:
    """Two stages per direction, as shimmed dampers behave: a steep low-speed rate up to a knee
    speed, a flatter high-speed rate beyond it (continuous at the knee). Speeds in m/s, rates in
    N s/m; rebound mirrors compression with its own three values."""

    compression_low: float  # N s/m, 0 <= v <= compression_knee
    compression_high: float  # N s/m, v > compression_knee
    compression_knee: float  # m/s, > 0
    rebound_low: float  # N s/m, -rebound_knee <= v < 0
    rebound_high: float  # N s/m, v < -rebound_knee
    rebound_knee: float  # m/s, > 0
    n_guards = 3

    def guards(self, x, v):
        return (v, v - self.compression_knee, v + self.rebound_knee)

    def force(self, v, sides=None):
        return digressive_damper_force(self.compression_low, self.compression_high, self.compression_knee,
                                       self.rebound_low, self.rebound_high, self.rebound_knee, v,
                                       flag(sides, 0), flag(sides, 1), flag(sides, 2))


@dataclass(frozen=True)
class OrificeDamper(SmoothLaw):
    """A bleed and an orifice in parallel: F = b v + c v |v|, with c_c in compression and c_r in
    rebound.

    Flow through a sharp-edged orifice drops the pressure by rho / 2 (Q / (C_d A))^2, so the force
    of a piston pushing oil through it rises as the square of its speed (Dixon, *The Shock Absorber
    Handbook*, 2nd ed., Wiley 2007, on orifice flow); a bleed (a laminar path) adds a force linear
    in the speed. Without shims that open (``DigressiveDamper``) this is the classic passive
    damper: progressive, soft at low speed. The force and its slope (b) are continuous at v = 0,
    where only the curvature changes with the direction: no guard is needed there.
    """

    bleed: float  # N s/m
    compression: float  # N s^2/m^2, v >= 0
    rebound: float  # N s^2/m^2, v < 0

    def force(self, v, sides=None):
        return orifice_damper_force(self.bleed, self.compression, self.rebound, v)


class TableDamper:
    """Lookup table F(v) from dyno peak force vs velocity, linear between points and extrapolated
    with the end slopes. The table passes through (0, 0); the offset at zero velocity is the
    friction law's (S10-S14 use ``Coulomb``). Each interior table velocity is a guard."""

    def __init__(self, velocity, force):
        v = np.asarray(velocity, dtype=float)
        f = np.asarray(force, dtype=float)
        if not np.any(v == 0.0):
            i = int(np.searchsorted(v, 0.0))
            v = np.insert(v, i, 0.0)
            f = np.insert(f, i, 0.0)
        self.velocity = tuple(float(a) for a in v)
        self.force_table = tuple(float(a) for a in f)
        self.slopes = tuple(float(s) for s in np.diff(f) / np.diff(v))
        self.n_guards = len(v) - 2

    def guards(self, x, v):
        return tuple(v - b for b in self.velocity[1:-1])

    def segment(self, v, sides=None):
        if sides is None:
            return table_segment(self.velocity, len(self.velocity), v)
        return sum(1 for s in sides if s)

    def force(self, v, sides=None):
        return table_damper_force(self.velocity, self.force_table, self.slopes, self.segment(v, sides), v)

    def __repr__(self):
        return f"TableDamper(velocity={self.velocity}, force={self.force_table})"


__all__ = ["orifice_damper_force", "OrificeDamper", "linear_damper_force", "bilinear_damper_force", "digressive_damper_force", "table_segment",
           "table_damper_force", "LinearDamper", "BilinearDamper", "DigressiveDamper", "TableDamper"]

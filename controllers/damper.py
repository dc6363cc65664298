"""Fork damper laws: hydraulic force in N from compression velocity v (m/s), compression positive.

The friction offset a dyno shows at v = 0 is not part of these laws; it is a friction law
(``controllers.friction``) added by ``controllers.fork.ForkLaw``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.controllers.guards import SmoothLaw, on_positive_side


@dataclass(frozen=True)
class LinearDamper(SmoothLaw):
    """F = c v with one coefficient (the average of compression and rebound; S1-S8)."""

    coefficient: float  # N s/m

    def force(self, v, sides=None):
        return self.coefficient * v


@dataclass(frozen=True)
class BilinearDamper:
    """Separate compression and rebound coefficients (paper Fig. 6, S9)."""

    compression: float  # N s/m, v >= 0
    rebound: float  # N s/m, v < 0
    n_guards = 1

    def guards(self, x, v):
        return (v,)

    def force(self, v, sides=None):
        positive = on_positive_side(v, sides, 0)
        return (self.compression if positive else self.rebound) * v


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
        if on_positive_side(v, sides, 0):
            if on_positive_side(v - self.compression_knee, sides, 1):
                return self.compression_low * self.compression_knee + self.compression_high * (v - self.compression_knee)
            return self.compression_low * v
        if on_positive_side(v + self.rebound_knee, sides, 2):
            return self.rebound_low * v
        return -self.rebound_low * self.rebound_knee + self.rebound_high * (v + self.rebound_knee)


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
        self._slopes = tuple(float(s) for s in np.diff(f) / np.diff(v))
        self.n_guards = len(v) - 2

    def guards(self, x, v):
        return tuple(v - b for b in self.velocity[1:-1])

    def _segment(self, v, sides):
        if sides is None:
            i = 0
            for b in self.velocity[1:-1]:
                if v >= b:
                    i += 1
                else:
                    break
            return i
        return sum(1 for s in sides if s)

    def force(self, v, sides=None):
        i = self._segment(v, sides)
        return self.force_table[i] + self._slopes[i] * (v - self.velocity[i])

    def __repr__(self):
        return f"TableDamper(velocity={self.velocity}, force={self.force_table})"


__all__ = ["LinearDamper", "BilinearDamper", "DigressiveDamper", "TableDamper"]

"""Fork spring laws: force in N (positive pushes the fork apart) from compression x (m) and
compression velocity v (m/s), compression positive. Piecewise laws follow the guard protocol of
``controllers.guards``; every law also gives its stored ``energy(x)`` for the energy balance.
"""
from __future__ import annotations

from dataclasses import dataclass

from mtbmj.controllers.friction import smooth_sign
from mtbmj.controllers.guards import SmoothLaw, on_positive_side as _side


@dataclass(frozen=True)
class LinearSpring(SmoothLaw):
    """F = k x, the same rate in compression and extension (the classic quarter car, S1)."""

    rate: float  # N/m

    def force(self, x, v, sides=None):
        return self.rate * x

    def energy(self, x):
        return 0.5 * self.rate * x * x


@dataclass(frozen=True)
class BilinearSpring:
    """Rate k1 below the knee and k2 beyond it, force continuous at the knee (paper eq. 4)."""

    rate: float  # N/m, 0 <= x < knee
    rate_above_knee: float  # N/m, x >= knee
    knee: float  # m
    n_guards = 1

    def guards(self, x, v):
        return (x - self.knee,)

    def force(self, x, v, sides=None):
        if _side(x - self.knee, sides, 0):
            return self.rate * self.knee + self.rate_above_knee * (x - self.knee)
        return self.rate * x

    def energy(self, x):
        if x < self.knee:
            return 0.5 * self.rate * x * x
        d = x - self.knee
        return 0.5 * self.rate * self.knee ** 2 + self.rate * self.knee * d + 0.5 * self.rate_above_knee * d * d


@dataclass(frozen=True)
class ProgressiveSpring(SmoothLaw):
    """F = k x + c x^3: the slightly rising rate of a coil fork with trapped air (paper Fig. 3d)."""

    rate: float  # N/m
    cubic: float  # N/m^3

    def force(self, x, v, sides=None):
        return self.rate * x + self.cubic * x * x * x

    def energy(self, x):
        return 0.5 * self.rate * x * x + 0.25 * self.cubic * x ** 4


@dataclass(frozen=True)
class DirectionalSpring:
    """Separate compression and rebound curves (the hysteresis loop of paper Fig. 3a).

    The curve is chosen by the sign of the stroke velocity. A hard switch at v = 0 would make the
    force jump at every turning point, so the two curves are blended with the smooth sign
    tanh(v / band) used by the friction laws: compression curve for v >> band, rebound for
    v << -band, their mean at rest.
    """

    compression: object
    rebound: object
    band: float  # m/s

    @property
    def n_guards(self):
        return self.compression.n_guards + self.rebound.n_guards

    def guards(self, x, v):
        return self.compression.guards(x, v) + self.rebound.guards(x, v)

    def force(self, x, v, sides=None):
        nc = self.compression.n_guards
        sc = None if sides is None else sides[:nc]
        sr = None if sides is None else sides[nc:]
        w = 0.5 * (1.0 + smooth_sign(v, self.band))
        return w * self.compression.force(x, v, sc) + (1.0 - w) * self.rebound.force(x, v, sr)

    def energy(self, x):
        return 0.5 * (self.compression.energy(x) + self.rebound.energy(x))


@dataclass(frozen=True)
class TopOutSpring:
    """Main spring (with optional preload P) working against a top-out spring of rate k_t.

    The two springs oppose each other. The top-out spring is engaged below x_e = P / k_t, where
    it pushes back with k_t (x_e - x); at x = 0 it exactly balances the preload, so the fork rests
    unloaded at full extension and the net force

        F(x) = P + F_main(x, v) - k_t max(0, x_e - x)

    is continuous, zero at x = 0 and steep near full extension (rate k_main + k_t), and equals the
    preloaded main curve beyond x_e. Pulled past full extension (x < 0) the fork's rate is
    k_main + k_t, which is what a dyno measures there (paper Fig. 3c). Without preload x_e = 0 and
    the top-out spring acts only in extension.
    """

    main: object
    top_out_rate: float  # N/m, the top-out spring's own rate
    preload: float = 0.0  # N

    @property
    def engagement(self) -> float:
        """x_e (m): compression where the top-out spring comes free."""
        return self.preload / self.top_out_rate

    @property
    def n_guards(self):
        return self.main.n_guards + 1

    def guards(self, x, v):
        return self.main.guards(x, v) + (x - self.engagement,)

    def force(self, x, v, sides=None):
        nm = self.main.n_guards
        force = self.preload + self.main.force(x, v, None if sides is None else sides[:nm])
        if not _side(x - self.engagement, sides, nm):
            force -= self.top_out_rate * (self.engagement - x)
        return force

    def energy(self, x):
        xe = self.engagement
        engaged = xe * x - 0.5 * x * x if x <= xe else 0.5 * xe * xe
        return self.preload * x + self.main.energy(x) - self.top_out_rate * engaged


__all__ = ["LinearSpring", "BilinearSpring", "ProgressiveSpring", "DirectionalSpring", "TopOutSpring"]

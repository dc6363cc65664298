"""Fork spring laws: force in N (positive pushes the fork apart) from compression x (m) and
compression velocity v (m/s), compression positive.

Every law offers ``force(x, v, sides=None)`` and ``guards(x, v)``. A guard is a smooth function
whose sign selects the branch of a piecewise law; ``sides`` (a tuple of booleans, one per guard,
True for guard >= 0) freezes the branch so an ODE integrator can step up to a branch change
without evaluating the other formula (see ``mtbmj.engine_ode``). With ``sides=None`` the branch
follows the state, which is what the MuJoCo callback uses.
"""
from __future__ import annotations

from dataclasses import dataclass

from .friction import smooth_sign


def _side(value: float, sides, index: int) -> bool:
    """True when the guard at ``index`` is on its non-negative side (frozen or live)."""
    return value >= 0.0 if sides is None else sides[index]


@dataclass(frozen=True)
class LinearSpring:
    """F = k x, the same rate in compression and extension (the classic quarter car, S1)."""

    rate: float  # N/m
    n_guards = 0

    def guards(self, x, v):
        return ()

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
class ProgressiveSpring:
    """F = k x + c x^3: the slightly rising rate of a coil fork with trapped air (paper Fig. 3d)."""

    rate: float  # N/m
    cubic: float  # N/m^3
    n_guards = 0

    def guards(self, x, v):
        return ()

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
    """Main spring (with optional preload) working against a top-out spring.

    The net force is F = min(k_top x, P + F_main(x, v)), where k_top is the rate measured when
    the fork is pulled past full extension (x < 0, paper Fig. 3c) and P the preload. At x = 0 the
    preloaded main spring sits against the top-out spring and the net force is zero; near full
    extension the stiff top-out rate governs until it meets the preloaded main curve. The force is
    continuous everywhere, so integrators do not chatter at full extension.
    """

    main: object
    top_out_rate: float  # N/m
    preload: float = 0.0  # N

    @property
    def n_guards(self):
        return self.main.n_guards + 1

    def guards(self, x, v):
        return self.main.guards(x, v) + (self.top_out_rate * x - self.preload - self.main.force(x, v),)

    def force(self, x, v, sides=None):
        nm = self.main.n_guards
        main = self.preload + self.main.force(x, v, None if sides is None else sides[:nm])
        top = self.top_out_rate * x
        if _side(top - main, sides, nm):
            return main
        return top

    def energy(self, x):
        # Integrate the zero-velocity curve numerically: the min() has no simple closed form.
        n = 200
        h = x / n
        total = 0.0
        for i in range(n):
            xi = (i + 0.5) * h
            total += self.force(xi, 0.0) * h
        return total


__all__ = ["LinearSpring", "BilinearSpring", "ProgressiveSpring", "DirectionalSpring", "TopOutSpring"]

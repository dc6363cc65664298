"""Fork spring laws: force in N (positive pushes the fork apart) from compression x (m) and
compression velocity v (m/s), compression positive. Piecewise laws follow the guard protocol of
``controllers.guards``; every law also gives its stored ``energy(x)`` for the energy balance.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from mtbmj.controllers.friction import smooth_sign
from mtbmj.controllers.guards import LIVE, SmoothLaw, flag, side


# ----------------------------------------------------------------------------------------------
# The formulas, each written once. Plain arithmetic on floats: the law objects below call them,
# and the compiled kernels (``controllers.kernels``) compile this same source with numba, reading
# the parameters by name from the law's layout (``controllers.layout``). A trailing ``s*`` argument
# is a guard's frozen side (``controllers.guards.flag``; LIVE: follow the state).
# ----------------------------------------------------------------------------------------------
def linear_spring_force(rate, x):
    return rate * x


def bilinear_spring_force(rate, rate_above_knee, knee, x, s0=LIVE):
    if side(x - knee, s0):
        return rate * knee + rate_above_knee * (x - knee)
    return rate * x


def progressive_spring_force(rate, cubic, x):
    return rate * x + cubic * x * x * x


def directional_blend(band, v, compression, rebound):
    """The compression and rebound curves' forces blended by the smooth sign of v."""
    w = 0.5 * (1.0 + smooth_sign(v, band))
    return w * compression + (1.0 - w) * rebound


def top_out_force(top_out_rate, preload, engagement, main, x, s0=LIVE):
    """The main spring's force ``main`` with the preload and the top-out spring."""
    force = preload + main
    if not side(x - engagement, s0):
        force -= top_out_rate * (engagement - x)
    return force


def air_chamber_force(area, absolute, volume, index, atmospheric, has_negative, positive_at_port,
                      negative_at_port, port, x):
    """The air force at compression x on its formula (sealed branch; no tangent, no offset)."""
    if has_negative:
        d = x - port
        return area * absolute * ((positive_at_port / (positive_at_port - area * d)) ** index
                                  - (negative_at_port / (negative_at_port + area * d)) ** index)
    return area * (absolute * (volume / (volume - area * x)) ** index - atmospheric)


def air_spring_force(area, absolute, volume, index, atmospheric, has_negative, positive_at_port, negative_at_port,
                     port, limit, limit_force, limit_rate, offset, x, s0=LIVE):
    if has_negative and not side(x - port, s0):
        return -offset
    if x - limit >= 0.0:
        return limit_force + limit_rate * (x - limit) - offset
    return air_chamber_force(area, absolute, volume, index, atmospheric, has_negative, positive_at_port,
                             negative_at_port, port, x) - offset


@dataclass(frozen=True)
class LinearSpring(SmoothLaw):
    """F = k x, the same rate in compression and extension (the classic quarter car, S1)."""

    rate: float  # N/m

    def force(self, x, v, sides=None):
        return linear_spring_force(self.rate, x)

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
        return bilinear_spring_force(self.rate, self.rate_above_knee, self.knee, x, flag(sides, 0))

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
        return progressive_spring_force(self.rate, self.cubic, x)

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
        return directional_blend(self.band, v, self.compression.force(x, v, sc), self.rebound.force(x, v, sr))

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
    derived = ("engagement",)

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
        main = self.main.force(x, v, None if sides is None else sides[:nm])
        return top_out_force(self.top_out_rate, self.preload, self.engagement, main, x, flag(sides, nm))

    def energy(self, x):
        xe = self.engagement
        engaged = xe * x - 0.5 * x * x if x <= xe else 0.5 * xe * xe
        return self.preload * x + self.main.energy(x) - self.top_out_rate * engaged


P_ATM = 101325.0  # Pa, standard atmosphere (ISO 2533): the absolute pressure of a gauge reading of 0


def _polytropic_work(volume: float, ratio: float, n: float) -> float:
    """W / p0 (m^3) of a polytropic change from ``volume`` to ``volume / ratio`` at the starting
    absolute pressure p0: the integral of (p / p0) dV swept, V (ratio^(n-1) - 1) / (n - 1), or
    V ln(ratio) for the isothermal n = 1 (expm1 keeps n close to 1 exact). Negative when the gas
    expands (ratio < 1)."""
    log_ratio = math.log(ratio)
    if n == 1.0:
        return volume * log_ratio
    return volume * math.expm1((n - 1.0) * log_ratio) / (n - 1.0)


@dataclass(frozen=True)
class AirSpring:
    """An air spring: the positive chamber of an air fork, optionally with a negative chamber.

    Positive chamber alone (``negative_volume`` = 0), a polytropic gas of index n compressed by a
    piston of area A from its volume V at full extension (gauge pressure p there, atmospheric
    pressure p_a on the other side of the piston):

        F(x) = A [(p + p_a) (V / (V - A x))^n - p_a]

    Negative chamber (``negative_volume`` = V_n > 0): a second chamber below the same piston that
    grows as the fork compresses and pulls the fork into its travel. Model (after the single-valve
    "dimple" forks, e.g. RockShox DebonAir as described by Bike Magazine, "RockShox updates its
    DebonAir spring", 2020): a transfer port at compression x_p (``port``, at or near full
    extension) joins the two chambers while the piston seal is above it, so there they share one
    pressure p + p_a and, acting on the same area, cancel (zero net force for x <= x_p). Below the
    port each chamber is sealed and polytropic from the state it had at the port:

        F(x) = A (p + p_a) [(V_p / (V_p - A d))^n - (V_m / (V_m + A d))^n],  d = x - x_p

    with V_p = V - A x_p and V_m = V_n + A x_p. Assumptions: the shaft area is neglected (the
    negative chamber acts on the full piston area A), both chambers follow the same index n, no
    leakage across the seal. The force is continuous at the port, where its slope jumps (a guard).

    Past ``limit`` (normally the travel, where the fork's end stop takes over) the curve continues
    along its tangent, so the force stays finite for any compression; a configuration whose travel
    would compress the chamber to zero volume is refused in ``mtbmj.compose``. ``offset`` (N) is
    subtracted from the force so that a ``TopOutSpring`` can carry the force at full extension as
    its preload (``mtbmj.compose`` sets both to that force).
    """

    area: float  # m^2, piston area A
    pressure: float  # Pa, gauge pressure of the positive chamber at full extension
    volume: float  # m^3, positive chamber at full extension (volume spacers already taken out)
    index: float  # polytropic index n (1 isothermal, 1.4 adiabatic air)
    negative_volume: float = 0.0  # m^3, negative chamber at full extension; 0 = no negative chamber
    port: float = 0.0  # m, compression of the transfer port
    limit: float = math.inf  # m, compression beyond which the curve continues along its tangent
    offset: float = 0.0  # N, subtracted from the force (carried as a TopOutSpring preload)
    atmospheric: float = P_ATM  # Pa
    derived = ("absolute", "has_negative", "positive_at_port", "negative_at_port", "limit_force", "limit_rate")

    @property
    def has_negative(self) -> bool:
        return self.negative_volume > 0.0

    @property
    def n_guards(self) -> int:
        return 1 if self.has_negative else 0

    has_state = False

    def guards(self, x, v):
        return (x - self.port,) if self.has_negative else ()

    @property
    def absolute(self) -> float:
        """p + p_a (Pa): absolute pressure at full extension."""
        return self.pressure + self.atmospheric

    @property
    def positive_at_port(self) -> float:
        """V_p (m^3): the positive chamber where the transfer port closes."""
        return self.volume - self.area * self.port

    @property
    def negative_at_port(self) -> float:
        """V_m (m^3): the negative chamber where the transfer port closes."""
        return self.negative_volume + self.area * self.port

    def air_force(self, x: float, below_port: bool = True) -> float:
        """The air force (N) at compression x on its formula (no tangent continuation, no offset);
        ``below_port`` picks the sealed branch of the negative-chamber model."""
        if self.has_negative and not below_port:
            return 0.0
        return air_chamber_force(self.area, self.absolute, self.volume, self.index, self.atmospheric,
                                 self.has_negative, self.positive_at_port, self.negative_at_port, self.port, x)

    def air_rate(self, x: float) -> float:
        """dF/dx (N/m) of ``air_force`` at x (sealed branch)."""
        a, n = self.area, self.index
        if self.has_negative:
            d = x - self.port
            vp, vm = self.positive_at_port, self.negative_at_port
            up, um = vp - a * d, vm + a * d
            return a * a * self.absolute * n * ((vp / up) ** n / up + (vm / um) ** n / um)
        u = self.volume - self.area * x
        return a * a * self.absolute * n * (self.volume / u) ** n / u

    @functools.cached_property
    def limit_force(self) -> float:
        return self.air_force(self.limit) if math.isfinite(self.limit) else math.nan

    @functools.cached_property
    def limit_rate(self) -> float:
        return self.air_rate(self.limit) if math.isfinite(self.limit) else math.nan

    def force(self, x, v, sides=None):
        return air_spring_force(self.area, self.absolute, self.volume, self.index, self.atmospheric,
                                self.has_negative, self.positive_at_port, self.negative_at_port, self.port,
                                self.limit, self.limit_force, self.limit_rate, self.offset, x,
                                flag(sides, 0) if self.has_negative else LIVE)  # (the port's guard, if any)

    def _air_energy(self, x: float) -> float:
        a, n = self.area, self.index
        if self.has_negative:
            if x <= self.port:
                return 0.0
            d = x - self.port
            vp, vm = self.positive_at_port, self.negative_at_port
            return self.absolute * (_polytropic_work(vp, vp / (vp - a * d), n)
                                    + _polytropic_work(vm, vm / (vm + a * d), n))
        return (self.absolute * _polytropic_work(self.volume, self.volume / (self.volume - a * x), n)
                - self.atmospheric * a * x)

    def energy(self, x):
        """Work (J) done compressing the spring from full extension to x: the integral of force."""
        if x > self.limit:
            d = x - self.limit
            stored = self._air_energy(self.limit) + self.limit_force * d + 0.5 * self.limit_rate * d * d
        else:
            stored = self._air_energy(x)
        return stored - self.offset * x


__all__ = ["linear_spring_force", "bilinear_spring_force", "progressive_spring_force", "directional_blend",
           "top_out_force", "air_chamber_force", "air_spring_force", "LinearSpring", "BilinearSpring", "ProgressiveSpring", "DirectionalSpring", "TopOutSpring",
           "AirSpring", "P_ATM"]

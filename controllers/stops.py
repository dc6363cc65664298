"""The fork's end stops: a bottom-out bumper, and hard stops at both ends of the stroke.

``EndStops`` wraps a main spring law (coil, progressive, top-out, ...) and adds

* a **bottom-out bumper** that engages over the last ``bumper_length`` of travel and rises
  progressively (quadratically, continuous with zero slope at engagement) to ``bumper_force`` at
  full travel: the elastomer or hydraulic bottom-out of a real fork;
* a **hard stop** at full compression (x = travel) and one at full extension (x = -extension,
  the top-out bumper fully compressed): a stiff, damped contact that pushes but never pulls and
  stiffens as it goes (metal taking the load), F = max(0, k p (1 + (p / p0)^2) + c tanh(3 p / p0) dp/dt)
  for a penetration p > 0, p0 = ``STIFFENING_M`` (the damping sets in over the first tenths of a
  millimetre, so the force is continuous at contact): a hard landing of a heavy rider on a soft fork passes
  the travel by about 2 mm at most.

Force in N (positive pushes the fork apart), compression x in m, velocity v in m/s. The stop's
compliance F / k is what the fork may pass its travel by. Every kink is a guard for the ODE
reference (``controllers.guards``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from mtbmj.controllers.guards import LIVE, flag, side

STIFFENING_M = 0.6e-3  # p0 of the stops' and the rim's stiffening: 12x the linear force at 2 mm
# the damping of a stop or the rim sets in with depth, c tanh(DAMPING_RAMP p / p0) dp/dt (76 % at
# 0.2 mm, 99.5 % at p0), so the force is continuous at contact: a damper that acted at full
# strength from the first micrometre would jump by c times the impact speed (10 kN at 5 m/s), which
# a fixed-step engine meets between two steps and the error grows with the step, not its fourth power
DAMPING_RAMP = 3.0


def contact_force(rate: float, damping: float, p: float, v: float) -> float:
    """The hard stops' and the rim's force law, written once: at penetration p >= 0 and rate dp/dt
    = v, k p (1 + (p / p0)^2) + c tanh(DAMPING_RAMP p / p0) v (the caller keeps it >= 0: it pushes,
    never pulls). Plain arithmetic on floats: the Python laws call it, and the compiled kernels
    (``controllers.compiled``, ``mtbmj.rolling.callback_compiled``, ``drop.engine_fast``) compile this same
    source with numba, so one edit here changes every engine."""
    r = p / STIFFENING_M
    return rate * p * (1.0 + r * r) + damping * math.tanh(DAMPING_RAMP * r) * v


def pushing(rate, damping, p, v, s0=LIVE, s1=LIVE):
    """A stop's force at penetration p (0 while p < 0, and while ``contact_force`` would pull)."""
    if not side(p, s0):
        return 0.0
    f = contact_force(rate, damping, p, v)
    return f if side(f, s1) else 0.0


def bumper_force_at(bumper_start, bumper_length, bumper_force, x, s0=LIVE):
    """The bottom-out bumper: rising as the square of its engagement to ``bumper_force``."""
    s = x - bumper_start
    if not side(s, s0):
        return 0.0
    r = s / bumper_length
    return bumper_force * r * r


def end_stops_force(travel, bumper_length, bumper_force, stop_rate, stop_damping, extension, bumper_start, main,
                    x, v, s0=LIVE, s1=LIVE, s2=LIVE, s3=LIVE, s4=LIVE):
    """The main spring's force ``main`` with the bumper, the compression stop and the extension stop."""
    bumper = bumper_force_at(bumper_start, bumper_length, bumper_force, x, s0)
    stop = pushing(stop_rate, stop_damping, x - travel, v, s1, s2)
    top = pushing(stop_rate, stop_damping, -extension - x, -v, s3, s4)
    return main + bumper + stop - top


def rim_force(max_deflection, rate, damping, deflection, deflection_rate, s0=LIVE, s1=LIVE):
    """The rim through the tire past its maximum deflection."""
    return pushing(rate, damping, deflection - max_deflection, deflection_rate, s0, s1)


def stop_energy(rate: float, p: float) -> float:
    """Its stored energy: k (p^2 / 2 + p^4 / (4 p0^2))."""
    return rate * (0.5 * p * p + 0.25 * p ** 4 / STIFFENING_M ** 2)


@dataclass(frozen=True)
class EndStops:
    main: object
    travel: float  # m
    bumper_length: float  # m, engages at travel - bumper_length
    bumper_force: float  # N at full travel
    stop_rate: float  # N/m, hard stops
    stop_damping: float  # N s/m, hard stops
    extension: float  # m, hard top stop at x = -extension
    derived = ("bumper_start",)

    @property
    def bumper_start(self) -> float:
        return self.travel - self.bumper_length

    @property
    def n_guards(self):
        return self.main.n_guards + 5

    @property
    def live_guards(self) -> tuple[int, ...]:
        """Guards the ODE reference evaluates live instead of locating: the stops' "pushes, never
        pulls" kinks, where the force is continuous. Located, a root that a stop resting under
        load crosses twice within one solver step is missed, and the stop then stays off."""
        o = self.main.n_guards
        return (o + 2, o + 4)

    def guards(self, x, v):
        p = x - self.travel
        q = -self.extension - x
        return self.main.guards(x, v) + (
            x - self.bumper_start, p, contact_force(self.stop_rate, self.stop_damping, p, v),
            q, contact_force(self.stop_rate, self.stop_damping, q, -v))

    def stop_forces(self, x, v, sides=None):
        """(bumper, compression stop, extension stop) forces in N, each >= 0 in its own direction."""
        o = self.main.n_guards
        return (bumper_force_at(self.bumper_start, self.bumper_length, self.bumper_force, x, flag(sides, o)),
                pushing(self.stop_rate, self.stop_damping, x - self.travel, v, flag(sides, o + 1), flag(sides, o + 2)),
                pushing(self.stop_rate, self.stop_damping, -self.extension - x, -v, flag(sides, o + 3),
                        flag(sides, o + 4)))

    def force(self, x, v, sides=None):
        o = self.main.n_guards
        main = self.main.force(x, v, None if sides is None else sides[:o])
        if sides is None:
            return end_stops_force(self.travel, self.bumper_length, self.bumper_force, self.stop_rate,
                                   self.stop_damping, self.extension, self.bumper_start, main, x, v)
        return end_stops_force(self.travel, self.bumper_length, self.bumper_force, self.stop_rate, self.stop_damping,
                               self.extension, self.bumper_start, main, x, v, flag(sides, o), flag(sides, o + 1),
                               flag(sides, o + 2), flag(sides, o + 3), flag(sides, o + 4))

    def energy(self, x):
        """Elastic energy (J): the main spring, the bumper and the stops' springs."""
        e = self.main.energy(x)
        s = x - self.bumper_start
        if s > 0.0:
            e += self.bumper_force * s ** 3 / (3.0 * self.bumper_length ** 2)
        p = x - self.travel
        if p > 0.0:
            e += stop_energy(self.stop_rate, p)
        q = -self.extension - x
        if q > 0.0:
            e += stop_energy(self.stop_rate, q)
        return e


@dataclass(frozen=True)
class Rim:
    """The rim striking through the tire: past ``max_deflection`` a stiff, damped contact that
    stiffens like the hard stops, F = max(0, k p (1 + (p / p0)^2) + c tanh(3 p / p0) dp/dt) for
    p = deflection - max_deflection > 0, added to the tire force."""

    max_deflection: float  # m
    rate: float  # N/m
    damping: float  # N s/m

    live_guards = (1,)  # as EndStops.live_guards

    def guards(self, deflection, rate):
        p = deflection - self.max_deflection
        return (p, contact_force(self.rate, self.damping, p, rate))

    def force(self, deflection, rate, sides=None):
        return rim_force(self.max_deflection, self.rate, self.damping, deflection, rate, flag(sides, 0),
                         flag(sides, 1))

    def energy(self, deflection):
        p = deflection - self.max_deflection
        return stop_energy(self.rate, p) if p > 0.0 else 0.0


__all__ = ["EndStops", "Rim", "STIFFENING_M", "DAMPING_RAMP", "contact_force", "pushing", "bumper_force_at",
           "end_stops_force", "rim_force", "stop_energy"]

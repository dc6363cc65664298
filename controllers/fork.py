"""The fork as one force element: spring + hydraulic damper + friction, in parallel.

Force in N, positive pushing the fork apart (resisting compression); compression x in m and
velocity v in m/s, compression positive. ``z`` is the friction law's internal state (LuGre
bristle deflection, m), zero for static laws.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ForkLaw:
    spring: object
    damper: object
    friction: object

    @property
    def has_state(self) -> bool:
        return self.friction.has_state

    @property
    def n_guards(self) -> int:
        return self.spring.n_guards + self.damper.n_guards + self.friction.n_guards

    def guards(self, x, v):
        return self.spring.guards(x, v) + self.damper.guards(x, v) + self.friction.guards(x, v)

    def _split(self, sides):
        if sides is None:
            return None, None, None
        a = self.spring.n_guards
        b = a + self.damper.n_guards
        return sides[:a], sides[a:b], sides[b:]

    def parts(self, x, v, z=0.0, sides=None):
        """(spring, damper, friction) forces in N."""
        ss, ds, fs = self._split(sides)
        return (
            self.spring.force(x, v, ss),
            self.damper.force(v, ds),
            self.friction.force(v, z, fs),
        )

    def force(self, x, v, z=0.0, sides=None):
        if sides is None:  # the live path, once per MuJoCo callback: keep it lean
            return self.spring.force(x, v) + self.damper.force(v) + self.friction.force(v, z)
        ss, ds, fs = self._split(sides)
        return self.spring.force(x, v, ss) + self.damper.force(v, ds) + self.friction.force(v, z, fs)

    def state_rate(self, v, z, sides=None):
        """dz/dt of the friction state (0 for static friction laws)."""
        if not self.friction.has_state:
            return 0.0
        return self.friction.state_rate(v, z, self._split(sides)[2])

    def elastic_energy(self, x):
        """Energy stored in the spring at compression x (J), for the energy balance."""
        return self.spring.energy(x)


__all__ = ["ForkLaw"]

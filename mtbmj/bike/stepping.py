"""How the bike follows the step rule: a coarse RK4 step where no end stop or rim acts, finer steps
where one may.

The bike's slow motions (the frame on its tires, the rider on legs and arms, the fork and the shock
over their working stroke) are resolved at a coarse step, 0.5 ms at most: the cross-checks against
the bike's ODE reference hold there on every terrain of the library (``docs/bike.md``). The end
stops (bumper, hard stop, top-out stop) and the rims are far stiffer: where one of them may act the
run is stepped ``substeps`` times finer.

Both steps come from the step rule (``mtbmj.runpath.steprule``, the drop's and the front end's),
its limits evaluated with the bike's own masses instead of the sled's: the coarse step is the
largest whole fraction of ``COARSE_STEP_S`` within those that hold anywhere (steps per period of
the wheel on the spring and tire, explicit damping, the logger's rate, the friction state at the
fastest stroke: a LuGre fork steps at ~0.06 ms throughout; ``steprule.fraction_within``), cut
evenly (``steprule.cuts_within``) to stay within the stops' and the rim's as well:

* the fork: the front unsprung mass (fork lower and wheel) as the wheel, half the sprung mass
  (frame and rider) as the body; the lighter of the two wheels where lighter (the same tire and rim
  law rolls at both ends);
* the shock, in shock coordinates: the rear wheel's mass times the smallest leverage ratio squared
  (a mass m at the wheel moves LR times as far as the shock: m LR^2 at the shock; the smallest ratio
  gives the smallest mass, the stiffest case), the body likewise. The swingarm's own inertia is
  left out, which only makes the steps smaller.

Which stretches need the fine step is decided after the fact: ``Stepping.refinement`` looks at
a chunk stepped coarse and finds the first and the last sample within reach of a stop (where the
drop refines too: ``steprule.stop_zone``) or the rim (within a margin of 1 mm at the wheel, 0.5 mm
at the shock, plus twice the largest motion of one coarse step in the chunk); ``mtbmj.bike.run``
keeps the chunk's coarse steps before the first, steps again from the sample before it at the fine
step to one sample past the last (at least ``FINE_MIN_STEPS`` coarse steps), keeping every
``substeps``-th state so the output stays on the coarse grid, and goes on from there with the next
chunk, coarse.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from mtbmj import compose
from mtbmj.bike.spec import rear_axle_in_frame
from mtbmj.runpath import loop, steprule

COARSE_STEP_S = steprule.ROLLING_STEP_S  # the bike's largest step (RK4): the step the cross-checks cover
CHUNK_STEPS = loop.REFINE_CHUNK  # coarse steps per chunk checked for a stop or the rim within reach
FINE_MIN_STEPS = loop.FINE_MIN_STEPS  # a stretch stepped fine covers at least this many coarse steps
FORK_MARGIN_M = steprule.REACH_MARGIN_M  # distance from a stop (fork travel, tire deflection) taken as within reach
SHOCK_MARGIN_M = 5e-4  # the same at the shock (its stroke is the wheel's over a ratio of 2.4-3.2)


@dataclass(frozen=True)
class Stepping:
    """One bike's steps: ``coarse`` (s), ``substeps`` fine steps per coarse one where a stop or the
    rim may act, what sets each, and the zones ``refinement`` watches."""

    coarse: float
    substeps: int
    coarse_why: str
    fine_why: str
    fork_zone: tuple[float, float]
    stroke_zone: tuple[float, float]
    rim_deflections: tuple[float, float]  # m, each tire's rim (front, rear); inf without one
    spec: object  # the BikeSpec: the swingarm angle -> rear wheel travel -> stroke

    @property
    def fine(self) -> float:
        return self.coarse / self.substeps

    def stroke(self, phi) -> np.ndarray:
        """Shock stroke (m) at swingarm angles ``phi`` (rad)."""
        _, z = rear_axle_in_frame(self.spec, phi)
        return self.spec.leverage.strokes(z - self.spec.rear_axle[1])

    def refinement(self, fork_col: int, phi_col: int, deflection_cols, before=lambda: None) -> loop.Refinement:
        """The bike's refinement (``mtbmj.runpath.loop.Refinement``, the front end's kind): the fork
        travel (state column ``fork_col``, m), the shock stroke (from the swingarm angle in state
        column ``phi_col``, rad) and each tire's deepest deflection (sensor columns
        ``deflection_cols``, front then rear, m) watched. Within reach: within the margin
        (FORK_MARGIN_M at the wheel and the rims, SHOCK_MARGIN_M at the shock) plus twice the largest
        motion of one coarse step in the chunk, so a stop met between two rows is met within reach
        of both; ``before`` is called before a fine stretch."""
        watches = [loop.Watch("state", fork_col, self.fork_zone, FORK_MARGIN_M),
                   loop.Watch("state", phi_col, self.stroke_zone, SHOCK_MARGIN_M, of=self.stroke)]
        watches += [loop.Watch("sensor", c, (-math.inf, rim), FORK_MARGIN_M)
                    for c, rim in zip(deflection_cols, self.rim_deflections)]
        return loop.Refinement(self.substeps, tuple(watches), before, FINE_MIN_STEPS, CHUNK_STEPS)

def stepping(spec, fork_setup: compose.Setup, shock_setup: compose.Setup, rims=None) -> Stepping:
    """The steps of the bike ``spec`` with these fork and shock setups (see the module doc);
    ``rims`` each tire's ``controllers.Rim`` or None (front, rear; default the fork setup's tire's at
    both)."""
    front_unsprung = spec.fork_lower_mass + spec.front_wheel_mass
    sprung = spec.total_mass - front_unsprung - spec.rear_wheel_mass - spec.swingarm_mass
    wheel = min(front_unsprung, spec.rear_wheel_mass)
    fork = dataclasses.replace(fork_setup, wheel_mass=wheel, body_mass=sprung / 2.0)
    lr2 = min(spec.leverage.ratio) ** 2
    shock = dataclasses.replace(shock_setup, wheel_mass=spec.rear_wheel_mass * lr2, body_mass=sprung / 2.0 * lr2)
    at_fork, at_shock = steprule.limits(fork), steprule.limits(shock)
    limit, why = min(at_fork.away_from_stops, at_shock.away_from_stops)
    coarse = steprule.fraction_within(COARSE_STEP_S, limit)
    if coarse == COARSE_STEP_S and limit > COARSE_STEP_S:
        why = f"the bike's largest step, {COARSE_STEP_S * 1e3:g} ms (the step its cross-checks cover)"
    fine, fine_why = min(at_fork.fine, at_shock.fine)
    substeps = steprule.cuts_within(coarse, fine)
    if rims is None:
        rims = (fork_setup.tire.rim, fork_setup.tire.rim)
    return Stepping(coarse, substeps, why, fine_why, steprule.stop_zone(fork_setup.fork.spring),
                    steprule.stop_zone(shock_setup.fork.spring),
                    tuple(r.max_deflection if r is not None else math.inf for r in rims), spec)


__all__ = ["Stepping", "stepping", "COARSE_STEP_S", "CHUNK_STEPS", "FINE_MIN_STEPS"]

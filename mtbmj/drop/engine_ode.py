"""The independent reference: the same force laws integrated by scipy's ``solve_ivp``.

State y = [s, x, ds/dt, dx/dt, z]: sled descent, fork compression, their rates and the friction
state. Equations (paper eqs. 2-3 with the fork force F_f pushing sled and wheel apart and the tire
force F_t pushing the wheel up):

    m_b s'' = m_b g - F_f
    m_w w'' = m_w g + F_f - F_t,   w = s - x (wheel descent = tire deflection)

Every piecewise law exposes guards (see ``controllers.spring``). The integration runs in segments
with each law's branch frozen; a terminal event stops a segment exactly where a guard changes
sign (tire touch or separation, the knee, the top-out hand-over, a table breakpoint, a stop or
the rim engaging, the tire-law switch), so no step ever integrates across a discontinuity or a kink.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from mtbmj.compose import Setup
from mtbmj.errors import RunError
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace

MAX_SEGMENTS = 20000


class _Model:
    def __init__(self, setup: Setup):
        self.s = setup
        self.fork = setup.fork
        self.tire = setup.tire
        self.nf = setup.fork.n_guards
        self._cache_key = None
        self._cache_value = ()

    def cached_guards(self, t, y, phase):
        """solve_ivp evaluates every event at the same (t, y): compute the guards once."""
        key = (t, phase, y.tobytes())
        if key != self._cache_key:
            self._cache_key = key
            self._cache_value = self.guards(y, phase)
        return self._cache_value

    def live_guards(self) -> set[int]:
        """Indices of the guards evaluated live, never located (``live_guards`` of the laws)."""
        live = set(getattr(self.fork.spring, "live_guards", ()))
        if self.tire.rim is not None:
            live |= {self.nf + 2 + i for i in self.tire.rim.live_guards}
        return live

    def guards(self, y, phase):
        s, x, sd, xd, z = y
        tv = self.tire.values(phase)
        deflection, rate = s - x, sd - xd
        rim = self.tire.rim.guards(deflection, rate) if self.tire.rim is not None else ()
        return self.fork.guards(x, xd) + (deflection, tv.rate * deflection + tv.damping * rate) + rim

    def rhs(self, t, y, sides, phase):
        s, x, sd, xd, z = y
        nf = self.nf
        fork_sides = sides[:nf] if sides is not None else None
        f_fork = self.fork.force(x, xd, z, fork_sides)
        tv = self.tire.values(phase)
        if sides is None:
            f_tire = self.tire.force(s - x, sd - xd, phase)
        else:
            f_tire = tv.rate * (s - x) + tv.damping * (sd - xd) if sides[nf] and sides[nf + 1] else 0.0
            if self.tire.rim is not None:
                f_tire += self.tire.rim.force(s - x, sd - xd, sides[nf + 2:nf + 4])
        g = self.s.gravity
        sdd = g - f_fork / self.s.body_mass
        wdd = g + (f_fork - f_tire) / self.s.wheel_mass
        return np.array([sd, xd, sdd, sdd - wdd, self.fork.state_rate(xd, z, fork_sides)])


def _initial_sides(model: _Model, y0, phase):
    """Branch of each guard at the start; a guard that is exactly zero takes the side it moves to."""
    values = np.array(model.guards(y0, phase))
    sides = list(values >= 0.0)
    zero = np.flatnonzero(values == 0.0)
    if zero.size:
        y = np.array(y0, dtype=float)
        for eps in (1e-9, 1e-7, 1e-5):
            probe = model.guards(y + eps * model.rhs(0.0, y, None, phase), phase)
            for i in zero:
                if probe[i] != 0.0:
                    sides[i] = probe[i] > 0.0
            if all(p != 0.0 for p in (probe[i] for i in zero)):
                break
    return tuple(bool(v) for v in sides)


PROBE_S = 1e-7  # look-ahead that decides which side of a root a guard is on
CHATTER_S = 1e-6  # a segment this short that ends on the same guard as the last one ...
CHATTER_COUNT = 5  # ... this many times in a row releases that guard
REARM_MAGNITUDE = 1e-4  # a released guard is re-armed once |its value| exceeds this (m, m/s or N)


def _resync(model: _Model, y, phase, sides: list, fired) -> tuple:
    """After an event, bring every other guard's side in line with where the state is going.

    Two guards can share a root (the damper table and LuGre both switch at v = 0): the solver
    stops at one, and the other sits within rounding of its root, where its direction-filtered
    event may never fire. Each guard's side is therefore taken from the state PROBE_S ahead
    along the new branch, which is decisive even when the value at the event is rounding noise.
    """
    probe = model.guards(y + PROBE_S * model.rhs(0.0, y, tuple(sides), phase), phase)
    for i, value in enumerate(probe):
        if i not in fired and sides[i] is not None and value != 0.0 and (value > 0.0) != sides[i]:
            sides[i] = not sides[i]
    return tuple(sides)


def run(setup: Setup, duration: float | None = None, progress=None) -> RawTrace:
    duration = setup.duration if duration is None else duration
    model = _Model(setup)
    grid = np.arange(int(round(duration / setup.timestep)) + 1) * setup.timestep  # the MuJoCo step times
    y = np.array([0.0, 0.0, setup.impact_speed, 0.0, 0.0])
    phase = 0
    sides = _initial_sides(model, y, phase)
    out = np.empty((grid.size, 5))
    phases = np.zeros(grid.size, dtype=np.int8)
    filled = 0
    t = 0.0
    solver_steps = 0
    events_log: list[tuple[float, str]] = []
    n_guards = len(sides)
    extended = False  # the fork has been extending (its first rebound stroke has begun)
    live = model.live_guards()  # never located: kinks of a continuous force (see EndStops.live_guards)
    sides = tuple(None if i in live else side for i, side in enumerate(sides))
    released: set[int] = set(live)  # guards evaluated live (and those that chattered: see CHATTER_*)
    last_fired, short_runs = None, 0
    for _segment in range(MAX_SEGMENTS):
        if released - live:  # re-arm a released guard once its value has clearly left its root
            values = model.guards(y, phase)
            for i in list(released - live):
                if abs(values[i]) > REARM_MAGNITUDE:
                    released.discard(i)
                    sides = sides[:i] + (bool(values[i] > 0.0),) + sides[i + 1:]
        # extending, or at a turning point into extension (a segment that ended on v = 0)
        extended = extended or y[3] < 0.0 or (abs(y[3]) < 1e-9 and model.rhs(t, y, sides, phase)[3] < 0.0)
        armed = [i for i in range(n_guards) if i not in released]
        events = []
        for i in armed:
            def event(tt, yy, sides_, phase_, i=i):  # solve_ivp passes args to events too
                return model.cached_guards(tt, yy, phase_)[i]
            event.terminal = True
            event.direction = -1.0 if sides[i] else 1.0
            events.append(event)
        if setup.tire.switches and phase == 0:
            # The tire-law switch (controllers.tire.SWITCH_RULE): the tire leaves the ground, or,
            # once the fork has been extending, it turns back into compression.
            def separation(tt, yy, sides_, phase_):
                return yy[0] - yy[1]
            separation.terminal = True
            separation.direction = -1.0
            events.append(separation)
            if not extended:
                def fork_turns(tt, yy, sides_, phase_):  # compression -> extension: only marks the segment
                    return yy[3]
                fork_turns.terminal = True
                fork_turns.direction = -1.0
                events.append(fork_turns)
            else:
                def rebound_end(tt, yy, sides_, phase_):
                    return yy[3]
                rebound_end.terminal = True
                rebound_end.direction = 1.0
                events.append(rebound_end)
        # scipy's finite-difference Jacobian grows its step factors until they overflow on a stiff
        # stop (a RuntimeWarning from numpy inside num_jac, harmless: the factor is reset); the
        # library does not print it to the caller's terminal
        with np.errstate(over="ignore"):
            sol = solve_ivp(model.rhs, (t, duration), y, method=setup.ode_method, rtol=setup.ode_rtol,
                            atol=setup.ode_atol, events=events, dense_output=True, args=(sides, phase))
        if sol.status < 0:
            raise RunError(f"ODE reference failed at t = {t:.4f} s: {sol.message}")
        solver_steps += len(sol.t) - 1
        t_end = sol.t[-1]
        stop = np.searchsorted(grid, t_end, side="right") if sol.status == 1 else grid.size
        if stop > filled:
            out[filled:stop] = sol.sol(grid[filled:stop]).T
            phases[filled:stop] = phase
            filled = stop
        if progress is not None:
            progress(t_end / duration)
        if not np.all(np.isfinite(sol.y)) or np.max(np.abs(sol.y[:2])) > MAX_DISPLACEMENT_M:
            raise RunError(f"ODE reference diverged before t = {t_end:.4f} s: displacement not finite or beyond 10 m")
        if sol.status == 0:
            break
        y = sol.y[:, -1].copy()
        t = t_end
        fired_events = [k for k, te in enumerate(sol.t_events) if len(te)]
        switch_events = events[len(armed):]
        fired = [armed[k] for k in fired_events if k < len(armed)]
        new_sides = list(sides)
        for k in fired:
            new_sides[k] = not new_sides[k]
            events_log.append((t, f"guard {k}"))
        switched = False
        for k in fired_events:
            if k < len(armed):
                continue
            if switch_events[k - len(armed)].__name__ == "fork_turns":
                extended = True
            else:
                phase, switched = 1, True
                events_log.append((t, "tire switch"))
        if setup.tire.switches and phase == 0 and not switched and fired:
            # A guard sharing the switch's root (the damper table's v = 0 breakpoint, the tire's
            # own touch guard) may end the segment first: solve_ivp then drops the other root.
            rates = model.rhs(t, y, tuple(new_sides), phase)
            leaves = abs(y[0] - y[1]) < 1e-12 and rates[0] - rates[1] < 0.0 and np.max(sol.y[0] - sol.y[1]) > 0.0
            turns = extended and abs(y[3]) < 1e-9 and rates[3] > 0.0 and np.min(sol.y[3]) < 0.0
            if leaves or turns:
                phase, switched = 1, True
                events_log.append((t, "tire switch"))
        # A guard whose root the state sits on (a stuck fork's velocity decaying to zero at a damper
        # breakpoint) fires again and again on rounding errors: after CHATTER_COUNT segments
        # shorter than CHATTER_S ending on it, it is released (evaluated live, no event) until
        # its value clearly leaves the root. Laws are continuous at such guards (kinks only).
        if fired and t_end - sol.t[0] < CHATTER_S and fired[0] == last_fired:
            short_runs += 1
            if short_runs >= CHATTER_COUNT:
                released.add(fired[0])
                new_sides[fired[0]] = None
                short_runs = 0
        else:
            short_runs = 0
        last_fired = fired[0] if fired else None
        sides = _resync(model, y, phase, new_sides, fired)
        if switched:
            # The tire guards depend on the tire values: take them afresh for the new phase.
            fresh = _initial_sides(model, y, phase)
            sides = sides[: model.nf] + fresh[model.nf:]
            released = {i for i in released if i < model.nf} | live
            sides = tuple(None if i in live else side for i, side in enumerate(sides))

    else:
        raise RunError(f"ODE reference: more than {MAX_SEGMENTS} law switches before t = {t:.4f} s (chattering)")
    return RawTrace(
        engine="ode",
        time=grid,
        sled=out[:, 0],
        fork=out[:, 1],
        sled_velocity=out[:, 2],
        fork_velocity=out[:, 3],
        friction_state=out[:, 4],
        tire_phase=phases,
        info={"method": setup.ode_method, "rtol": setup.ode_rtol, "atol_m": setup.ode_atol,
              "solver_steps": solver_steps, "segments": len(events_log) + 1, "events": events_log},
    )

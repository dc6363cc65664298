"""The fast engine: the drop's five-state ODE integrated natively on the compiled force laws.

The same equations as the reference (``engine_ode``; paper eqs. 2-3)

    m_b s'' = m_b g - F_f(x, x', z)
    m_w w'' = m_w g + F_f - F_t(w, w', phase),   w = s - x,   z' = dz/dt of the friction law

stepped by classical fourth-order Runge-Kutta inside one numba function. The fork force is the
compiled kernel of ``controllers.compiled`` (``fork_force_rate`` on the law flattened
by ``compiled.flatten``), the one the MuJoCo callback runs: a law added there is a law this engine
has, with nothing to write here.

Events are located, not stepped over. :func:`_guards` lists every function whose sign change is
an event: tire touchdown and separation (the deflection and the Kelvin-Voigt force, where the tire
force jumps or kinks), the fork's direction (the tire-law switch, ``controllers.tire.SWITCH_RULE``)
and the rim; :func:`_on_event` says what an event changes (the tire phase). A step
over which a guard changes sign is cut where it does (bisection on the step length to ``EVENT_TIME_S``)
and resumed from there, so no Runge-Kutta step integrates across a jump. To locate another event
(an end stop, a stick-slip state), add its guard to ``_guards`` and its effect to ``_on_event``.

The state is sampled on the run's grid (``solver.timestep_s``) as in the other engines. Each grid
step is taken as one Runge-Kutta step where the step rule allows it; where that step comes near
something stiffer (an end stop, the rim, the tire at the ground, the steep band around rest, a
stroke faster than the friction state allows: the zones the MuJoCo engine refines in) it is
redone in equal sub-steps no longer than ``MAX_STEP_S`` nor the MuJoCo engine's fine step
(``Setup.fine_timestep``: 0.02 ms where the run may reach a hard stop or the rim). Needs numba; this is the engine for many drops
(sweeps, fits); MuJoCo stays the default engine and the only one that rolls over terrain.
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.compose import Setup
from mtbmj.runpath import steprule
from mtbmj.controllers import jit as _jit
from mtbmj.controllers.lawcodes import UnsupportedLaw, law_arrays as _law_arrays
from mtbmj.controllers.stops import STIFFENING_M
from mtbmj.errors import ConfigError, RunError
from mtbmj.trace import MAX_DISPLACEMENT_M, RawTrace

MAX_STEP_S = 5e-5  # longest Runge-Kutta step (s); see benchmarks/fast_engine.py for the accuracy
CHUNK_S = 0.25  # simulated time per kernel call (progress is reported between calls)
MAX_EVENTS_PER_STEP = 16  # more than this in one step is chattering: the step is taken as it is
# An event is located to within this (s): the step resumes at most this long after it, where a
# force jump of 10 kN on a 1.5 kg wheel moves it by less than 1e-8 mm. Bisecting on down to the
# step length's last bit took twice the Runge-Kutta steps for nothing visible.
EVENT_TIME_S = 1e-12

# parameter vector of the kernel
(Q_MB, Q_MW, Q_G, Q_K0, Q_B0, Q_K1, Q_B1, Q_SWITCHES, Q_H, Q_SUB, Q_LIMIT,
 Q_RIM, Q_RIM_D, Q_RIM_K, Q_RIM_C, Q_RIM_P0, Q_BUMPER, Q_TRAVEL, Q_TOP,
 Q_COARSE, Q_MARGIN, Q_BAND, Q_FAST) = range(23)
Q_WIDTH = Q_FAST + 1  # one row per name above

# status codes
OK, DIVERGED = 0, 1

_numba = _jit.numba
if _numba is not None:
    # Module level, as numba's on-disk cache needs (a function built inside another is compiled
    # afresh in every process).
    from mtbmj.controllers import kernels as _kernels

    fork_force_rate = _kernels.inlined.fork_force_rate  # compiled into rhs: no call per evaluation
    borrow_f64, borrow_i64 = _kernels.borrow_f64, _kernels.borrow_i64
    contact_force = _kernels.contact_force  # the one stop/rim law (controllers.stops)
    kelvin_voigt_force, rim_force = _kernels.kelvin_voigt_force, _kernels.rim_force  # controllers.tire, .stops
    numba = _numba

    @_jit.kernel
    def tire_force(d, dd, phase, q):
        """TireLaw.force(d, dd, phase): KelvinVoigt of the phase, pushing only, plus the rim."""
        if d <= 0.0:
            return 0.0
        if phase == 1:
            f = kelvin_voigt_force(q[Q_K1], q[Q_B1], d, dd)
        else:
            f = kelvin_voigt_force(q[Q_K0], q[Q_B0], d, dd)
        if q[Q_RIM] != 0.0:  # Rim.force
            f += rim_force(q[Q_RIM_D], q[Q_RIM_K], q[Q_RIM_C], d, dd)
        return f

    @_jit.kernel
    def rhs(I, P, q, s, x, sd, xd, z, phase):
        """(ds, dx, dsd, dxd, dz)/dt: the equations of ``engine_ode._Model.rhs``."""
        f_fork, z_rate = fork_force_rate(I, P, x, xd, z)
        f_tire = tire_force(s - x, sd - xd, phase, q)
        sdd = q[Q_G] - f_fork / q[Q_MB]
        wdd = q[Q_G] + (f_fork - f_tire) / q[Q_MW]
        return sd, xd, sdd, sdd - wdd, z_rate

    @_jit.kernel
    def guards(y, phase, q):
        """The event functions (see the module docstring): their signs change at an event."""
        d = y[0] - y[1]
        dd = y[2] - y[3]
        if phase == 1:
            force = q[Q_K1] * d + q[Q_B1] * dd
        else:
            force = q[Q_K0] * d + q[Q_B0] * dd
        # touchdown / separation (geometric); the contact stops pushing (separation); the fork's
        # direction (the tire-law switch at the end of its first rebound stroke); the rim
        p = d - q[Q_RIM_D]
        rim = False
        if q[Q_RIM] != 0.0 and p >= 0.0:
            rim = contact_force(q[Q_RIM_K], q[Q_RIM_C], p, dd) >= 0.0
        # the fork's end stops: the bumper's and the hard stops' engagement (kinks of its force)
        x = y[1]
        return d > 0.0, force > 0.0, y[3] >= 0.0, rim, x >= q[Q_BUMPER], x >= q[Q_TRAVEL], x <= q[Q_TOP]

    @_jit.kernel
    def on_event(y, phase, before, after, q):
        """The tire phase after an event (guard signs ``before`` -> ``after`` across it): the
        switch (``controllers.tire.SWITCH_RULE``) when the tire leaves the ground or the fork turns
        from extension into compression, once, for a tire that switches."""
        if phase == 0 and q[Q_SWITCHES] != 0.0 and ((before[0] and not after[0]) or (not before[2] and after[2])):
            return 1
        return phase

    @_jit.kernel
    def rk4(I, P, q, y, phase, h):
        s, x, sd, xd, z = y
        a = rhs(I, P, q, s, x, sd, xd, z, phase)
        b = rhs(I, P, q, s + 0.5 * h * a[0], x + 0.5 * h * a[1], sd + 0.5 * h * a[2], xd + 0.5 * h * a[3],
                z + 0.5 * h * a[4], phase)
        c = rhs(I, P, q, s + 0.5 * h * b[0], x + 0.5 * h * b[1], sd + 0.5 * h * b[2], xd + 0.5 * h * b[3],
                z + 0.5 * h * b[4], phase)
        d = rhs(I, P, q, s + h * c[0], x + h * c[1], sd + h * c[2], xd + h * c[3], z + h * c[4], phase)
        w = h / 6.0
        return (s + w * (a[0] + 2.0 * b[0] + 2.0 * c[0] + d[0]), x + w * (a[1] + 2.0 * b[1] + 2.0 * c[1] + d[1]),
                sd + w * (a[2] + 2.0 * b[2] + 2.0 * c[2] + d[2]), xd + w * (a[3] + 2.0 * b[3] + 2.0 * c[3] + d[3]),
                z + w * (a[4] + 2.0 * b[4] + 2.0 * c[4] + d[4]))

    @_jit.kernel
    def advance(I, P, q, y, phase, h, counts):
        """One Runge-Kutta step of length ``h`` from ``y``, cut at every event in it (bisection on
        the step length to ``EVENT_TIME_S``) and resumed from there: (state, phase) at its end."""
        left = h
        for event in range(MAX_EVENTS_PER_STEP + 1):
            y1 = rk4(I, P, q, y, phase, left)
            counts[1] += 1
            g0 = guards(y, phase, q)
            if event == MAX_EVENTS_PER_STEP or g0 == guards(y1, phase, q):
                return y1, phase
            # the first sign change in (0, left]: bisect on the step length, to EVENT_TIME_S
            lo, hi = 0.0, left
            for _b in range(60):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi or hi - lo <= EVENT_TIME_S:
                    break
                if guards(rk4(I, P, q, y, phase, mid), phase, q) == g0:
                    lo = mid
                else:
                    hi = mid
            ye = rk4(I, P, q, y, phase, hi)
            phase = on_event(ye, phase, g0, guards(ye, phase, q), q)
            counts[0] += 1
            y = ye
            left -= hi
            if left <= 0.0:
                break
        return y, phase

    @_jit.kernel
    def near(y0, y1, h, q):
        """Whether a step of length ``h`` from ``y0`` to ``y1`` may have met something stiffer
        than the coarse step allows (``stepping.stop_index``'s zones): an end stop, the rim,
        the tire at the ground (located, but the step is short there as in MuJoCo), the steep
        band around rest, a stroke faster than the friction state allows."""
        x0, x1, v0, v1 = y0[1], y1[1], y0[3], y1[3]
        dv = abs(v1 - v0)
        margin = h * (abs(v0) + abs(v1) + dv) + q[Q_MARGIN]
        if max(x0, x1) + margin > q[Q_BUMPER] or min(x0, x1) - margin < q[Q_TOP]:
            return True
        d0, d1 = y0[0] - y0[1], y1[0] - y1[1]
        w0, w1 = y0[2] - y0[3], y1[2] - y1[3]
        reach = h * (abs(w0) + abs(w1) + abs(w1 - w0)) + q[Q_MARGIN]
        if q[Q_RIM] != 0.0 and max(d0, d1) + reach > q[Q_RIM_D]:
            return True
        if min(d0, d1) - reach < 0.0 < max(d0, d1) + reach:  # touchdown, lift-off
            return True
        if q[Q_BAND] > 0.0 and (v0 * v1 <= 0.0 or min(abs(v0), abs(v1)) - dv < q[Q_BAND]):
            return True
        return max(abs(v0), abs(v1)) + dv > q[Q_FAST]

    @_jit.kernel
    def integrate(I, P, q, y0, phase, first, last, out, phases, counts):
        """Step from grid index ``first`` (state ``y0``, tire ``phase``) to ``last``, writing the
        state at each grid point into ``out`` (and back into ``y0``) and the phase into
        ``phases``. Each grid step is one coarse step (``q[Q_COARSE]`` set) unless that step
        comes ``near`` a stiff zone, where it is redone in ``q[Q_SUB]`` fine steps. ``counts``
        gets [events, steps, status, index where it stopped, grid steps refined]. Returns the
        phase at the end."""
        # borrowed views: no reference counting in the calls below (controllers.compiled.borrow_f64)
        I, P, q, counts = borrow_i64(I), borrow_f64(P), borrow_f64(q), borrow_i64(counts)
        h_grid, sub = q[Q_H], int(q[Q_SUB])
        h = h_grid / sub
        y = (y0[0], y0[1], y0[2], y0[3], y0[4])
        for i in range(first, last):
            fine = True
            if q[Q_COARSE] != 0.0:
                yc, pc = advance(I, P, q, y, phase, h_grid, counts)
                if not near(y, yc, h_grid, q):
                    y, phase, fine = yc, pc, False
            if fine:
                counts[4] += 1
                for _ in range(sub):
                    y, phase = advance(I, P, q, y, phase, h, counts)
            for j in range(5):
                out[i + 1, j] = y[j]
            phases[i + 1] = phase
            bad = False
            for j in range(5):
                if not math.isfinite(y[j]):
                    bad = True
            if bad or abs(y[0]) > q[Q_LIMIT] or abs(y[1]) > q[Q_LIMIT]:
                counts[2] = DIVERGED
                counts[3] = i + 1
                break
        for j in range(5):
            y0[j] = y[j]
        return phase


_WARM = False


def kernel():
    """The compiled integrator; the first call in a process loads it from numba's cache (or, on
    a cold first run, compiles it, saying so through ``controllers.compiled.compiling``)."""
    global _WARM
    if _numba is None:
        raise ConfigError(f"engine: fast needs numba ({_jit.FALLBACK_MESSAGE.split(':')[0]}); "
                          "use engine mujoco or ode")
    if not _WARM:
        with _jit.compiling("the fast engine", integrate):
            _warm(integrate)
        _WARM = True
    return integrate


def ready() -> bool:
    """Whether the compiled integrator runs here without compiling first: loaded in this process, or
    in numba's disk cache for these sources (``controllers.jit.cold``)."""
    if _numba is None:
        return False
    return _WARM or (bool(_jit.CACHE) and not _jit.cold(integrate))


def _warm(integrate) -> None:
    """Run the kernel once on a trivial law so its compilation happens here, inside the notice."""
    from mtbmj.controllers import ForkLaw, LinearDamper, LinearSpring, NoFriction

    I, P = _law_arrays(ForkLaw(LinearSpring(1e4), LinearDamper(100.0), NoFriction()))
    q = np.zeros(Q_WIDTH)
    q[:11] = [50.0, 2.0, 9.81, 8e4, 100.0, 8e4, 100.0, 1.0, 1e-4, 1.0, 10.0]
    q[Q_BUMPER], q[Q_TRAVEL], q[Q_TOP], q[Q_COARSE], q[Q_FAST] = 1e9, 1e9, -1e9, 1.0, 1e9
    integrate(I, P, q, np.array([0.0, 0.0, 1.0, 0.0, 0.0]), 0, 0, 2, np.zeros((3, 5)),
              np.zeros(3, dtype=np.int8), np.zeros(5, dtype=np.int64))


def parameters(setup: Setup, substeps: int) -> np.ndarray:
    """The kernel's parameter vector for ``setup``."""
    impact = setup.tire.values(0)
    contact = setup.tire.values(1)
    q = np.zeros(Q_WIDTH)
    q[Q_MB], q[Q_MW], q[Q_G] = setup.body_mass, setup.wheel_mass, setup.gravity
    q[Q_K0], q[Q_B0], q[Q_K1], q[Q_B1] = impact.rate, impact.damping, contact.rate, contact.damping
    q[Q_SWITCHES] = 1.0 if setup.tire.switches else 0.0
    q[Q_H], q[Q_SUB], q[Q_LIMIT] = setup.timestep, substeps, MAX_DISPLACEMENT_M
    spring = setup.fork.spring
    q[Q_BUMPER], q[Q_TRAVEL], q[Q_TOP] = (
        (spring.bumper_start, spring.travel, -spring.extension) if hasattr(spring, "bumper_start") else (1e9, 1e9, -1e9))
    rim = setup.tire.rim
    if rim is not None:
        q[Q_RIM], q[Q_RIM_D], q[Q_RIM_K], q[Q_RIM_C] = 1.0, rim.max_deflection, rim.rate, rim.damping
        q[Q_RIM_P0] = STIFFENING_M
    # the grid step is taken whole where the step rule allows it (away from the zones the MuJoCo
    # engine refines in), else in sub-steps of at most MAX_STEP_S
    q[Q_COARSE] = 1.0 if setup.substeps > 1 else 0.0
    q[Q_MARGIN] = steprule.STOP_MARGIN_M
    _, _, _, q[Q_BAND], speed = steprule.refine_zones(setup)
    q[Q_FAST] = speed if math.isfinite(speed) else 1e30
    return q


def law_arrays(setup: Setup):
    try:
        return _law_arrays(setup.fork)
    except UnsupportedLaw as error:
        raise ConfigError(f"engine: fast cannot run this fork ({error}); use engine mujoco or ode") from None


def run(setup: Setup, duration: float | None = None, progress=None, refine: int = 1) -> RawTrace:
    """Integrate the drop from tire touch (t = 0, both bodies at the impact speed). ``refine`` > 1
    steps every grid step in ``refine`` times the sub-steps the step rule takes near a zone (no
    coarse steps): the same equations at a far finer step, whose difference from the run at
    ``refine=1`` estimates that run's discretisation error (``identify.dropfit``'s engine error)."""
    duration = setup.duration if duration is None else duration
    integrate = kernel()
    I, P = law_arrays(setup)
    steps = int(round(duration / setup.timestep))
    # near a zone: sub-steps of at most MAX_STEP_S, and no longer than the MuJoCo engine's fine
    # step (the step rule's limit while a stop or the rim may act, steprule.fine_limit)
    substeps = max(1, math.ceil(setup.timestep / MAX_STEP_S - 1e-9), setup.substeps)
    q = parameters(setup, substeps * max(1, int(refine)))
    if refine > 1:
        q[Q_COARSE] = 0.0
    out = np.empty((steps + 1, 5))
    phases = np.zeros(steps + 1, dtype=np.int8)
    y = np.array([0.0, 0.0, setup.impact_speed, 0.0, 0.0])
    out[0] = y
    counts = np.zeros(5, dtype=np.int64)
    chunk = max(1, int(round(CHUNK_S / setup.timestep)))
    phase = 0
    done = 0
    while done < steps:
        end = min(steps, done + chunk)
        phase = integrate(I, P, q, y, phase, done, end, out, phases, counts)
        if counts[2] == DIVERGED:
            at = int(counts[3]) * setup.timestep
            raise RunError(f"run diverged at t = {at:.4f} s: state not finite or beyond 10 m (fast)")
        done = end
        if progress is not None:
            progress(done / steps)
    return RawTrace(
        engine="fast",
        time=np.arange(steps + 1) * setup.timestep,
        sled=out[:, 0], fork=out[:, 1], sled_velocity=out[:, 2], fork_velocity=out[:, 3],
        friction_state=out[:, 4], tire_phase=phases,
        info={"method": "rk4", "step_s": setup.timestep / substeps, "substeps": substeps,
              "rk4_steps": int(counts[1]), "events": int(counts[0]), "steps_refined": int(counts[4]),
              "timestep_s": setup.timestep},
    )


__all__ = ["run", "kernel", "ready", "parameters", "MAX_STEP_S"]

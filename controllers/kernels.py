"""The fork law's compiled kernels: ``fork_force``, ``state_rate`` and their kin, evaluating a
``ForkLaw`` flattened by ``controllers.lawcodes.flatten`` (integer row I, float row P).

Every formula here is the law module's own plain function compiled by numba
(``controllers.jit.law_function``), its parameters read by name from the law's layout
(``controllers.layout``): ``P[o + BILINEAR.knee]``. What this module adds is only the dispatch on
the law codes and the spring program's stack, so a formula edited in its law module changes the
Python laws and every compiled engine at once (the MuJoCo callbacks, the fast engine, the rolling
callback), and the two agree bit for bit.

Importing this module imports numba; ``controllers.native`` decides when a drop does that. Without
numba, ``available`` is False and nothing below it is defined.
"""
from __future__ import annotations

import time
import types

from mtbmj.controllers import damper as _damper
from mtbmj.controllers import friction as _friction
from mtbmj.controllers import guards as _guards
from mtbmj.controllers import spring as _spring
from mtbmj.controllers import stops as _stops
from mtbmj.controllers import tire as _tire
from mtbmj.controllers.jit import compiling, kernel, law_function, notice, numba, rebound, say_now_if_cold
from mtbmj.controllers.layout import offsets
from mtbmj.controllers.lawcodes import (
    DA_BILINEAR, DA_DIGRESSIVE, DA_LINEAR, DA_ORIFICE, FR_COULOMB, FR_COULOMB_VISCOUS, FR_LUGRE, FR_NONE, FR_STICKING,
    FR_STICTION, FR_STRIBECK, I_DAMPER, I_DAMPER_AT, I_DAMPER_N, I_FRICTION, I_FRICTION_AT, I_FRICTION_INNER,
    I_FRICTION_INNER_AT, I_NSPRING, I_SPRING, SP_AIR, SP_BILINEAR, SP_DIRECTIONAL, SP_LINEAR, SP_PROGRESSIVE,
    SP_TOPOUT,
)

available = numba is not None
COMPILE_SECONDS: float | None = None  # wall time to compile (or load from numba's cache) the kernels

# each law's layout: the offsets of its parameters by name
LINEAR, BILINEAR, PROGRESSIVE = offsets(_spring.LinearSpring), offsets(_spring.BilinearSpring), \
    offsets(_spring.ProgressiveSpring)
DIRECTIONAL, TOPOUT, AIR = offsets(_spring.DirectionalSpring), offsets(_spring.TopOutSpring), \
    offsets(_spring.AirSpring)
STOPS = offsets(_stops.EndStops)
LINEAR_DAMPER, BILINEAR_DAMPER, DIGRESSIVE = offsets(_damper.LinearDamper), offsets(_damper.BilinearDamper), \
    offsets(_damper.DigressiveDamper)
ORIFICE = offsets(_damper.OrificeDamper)
COULOMB, COULOMB_VISCOUS = offsets(_friction.Coulomb), offsets(_friction.CoulombViscous)
STICTION, STRIBECK, LUGRE = offsets(_friction.Stiction), offsets(_friction.Stribeck), offsets(_friction.LuGre)
STICKING = offsets(_friction.Sticking)

if available:
    from mtbmj.controllers.native_data import f64_pointer, i64_pointer, stack_buffer

    _compile_start = time.perf_counter()
    _compile_notice = notice("the force laws")

    # the formulas, from their law modules (the helpers they call first)
    law_function(_guards.side)
    law_function(_friction.smooth_sign)
    contact_force = law_function(_stops.contact_force)
    pushing = law_function(_stops.pushing)
    bumper_force_at = law_function(_stops.bumper_force_at)
    end_stops_force = law_function(_stops.end_stops_force)
    rim_force = law_function(_stops.rim_force)
    linear_spring_force = law_function(_spring.linear_spring_force)
    bilinear_spring_force = law_function(_spring.bilinear_spring_force)
    progressive_spring_force = law_function(_spring.progressive_spring_force)
    directional_blend = law_function(_spring.directional_blend)
    top_out_force = law_function(_spring.top_out_force)
    law_function(_spring.air_chamber_force)
    air_spring_force = law_function(_spring.air_spring_force)
    linear_damper_force = law_function(_damper.linear_damper_force)
    bilinear_damper_force = law_function(_damper.bilinear_damper_force)
    digressive_damper_force = law_function(_damper.digressive_damper_force)
    orifice_damper_force = law_function(_damper.orifice_damper_force)
    table_segment = law_function(_damper.table_segment)
    table_damper_force = law_function(_damper.table_damper_force)
    coulomb_force = law_function(_friction.coulomb_force)
    coulomb_viscous_force = law_function(_friction.coulomb_viscous_force)
    stiction_level = law_function(_friction.stiction_level)
    stiction_force = law_function(_friction.stiction_force)
    stribeck_level = law_function(_friction.stribeck_level)
    stribeck_force = law_function(_friction.stribeck_force)
    lugre_rate = law_function(_friction.lugre_rate)
    lugre_force = law_function(_friction.lugre_force)
    sticking_rate = law_function(_friction.sticking_rate)
    sticking_force = law_function(_friction.sticking_force)
    kelvin_voigt_force = law_function(_tire.kelvin_voigt_force)
    floor_correction = law_function(_tire.floor_correction)
    rolling_tire_force = law_function(_tire.rolling_tire_force)

    # A numpy array handed from one compiled function to the next is reference-counted at every
    # call (two atomic operations per array), which cost more than the law itself: 139 against
    # 39 ns for S1's fork force. The kernels that call the laws in a loop borrow views without
    # a reference count instead, valid while the caller holds the array.
    @kernel
    def borrow_f64(a):
        """A view of the contiguous 1-d float64 array ``a`` that is not reference-counted."""
        return numba.carray(f64_pointer(a.ctypes.data), a.shape)

    @kernel
    def borrow_i64(a):
        """A view of the contiguous 1-d int64 array ``a`` that is not reference-counted."""
        return numba.carray(i64_pointer(a.ctypes.data), a.shape)

    @kernel
    def spring_force(I, P, x, v):
        """The spring tree's force: its program run on a stack (a wrapper combines what it follows)."""
        stack = stack_buffer()
        top = 0
        for k in range(I[I_NSPRING]):
            op = I[I_SPRING + 2 * k]
            o = I[I_SPRING + 2 * k + 1]
            if op == SP_LINEAR:
                stack[top] = linear_spring_force(P[o + LINEAR.rate], x)
                top += 1
            elif op == SP_BILINEAR:
                stack[top] = bilinear_spring_force(P[o + BILINEAR.rate], P[o + BILINEAR.rate_above_knee],
                                                   P[o + BILINEAR.knee], x)
                top += 1
            elif op == SP_PROGRESSIVE:
                stack[top] = progressive_spring_force(P[o + PROGRESSIVE.rate], P[o + PROGRESSIVE.cubic], x)
                top += 1
            elif op == SP_AIR:
                stack[top] = air_spring_force(
                    P[o + AIR.area], P[o + AIR.absolute], P[o + AIR.volume], P[o + AIR.index], P[o + AIR.atmospheric],
                    P[o + AIR.has_negative] != 0.0, P[o + AIR.positive_at_port], P[o + AIR.negative_at_port],
                    P[o + AIR.port], P[o + AIR.limit], P[o + AIR.limit_force], P[o + AIR.limit_rate],
                    P[o + AIR.offset], x)
                top += 1
            elif op == SP_DIRECTIONAL:
                top -= 1
                stack[top - 1] = directional_blend(P[o + DIRECTIONAL.band], v, stack[top - 1], stack[top])
            elif op == SP_TOPOUT:
                stack[top - 1] = top_out_force(P[o + TOPOUT.top_out_rate], P[o + TOPOUT.preload],
                                               P[o + TOPOUT.engagement], stack[top - 1], x)
            else:  # SP_STOPS
                stack[top - 1] = end_stops_force(
                    P[o + STOPS.travel], P[o + STOPS.bumper_length], P[o + STOPS.bumper_force], P[o + STOPS.stop_rate],
                    P[o + STOPS.stop_damping], P[o + STOPS.extension], P[o + STOPS.bumper_start], stack[top - 1], x, v)
        return stack[0]

    @kernel
    def damper_force(I, P, v):
        code = I[I_DAMPER]
        o = I[I_DAMPER_AT]
        if code == DA_LINEAR:
            return linear_damper_force(P[o + LINEAR_DAMPER.coefficient], v)
        if code == DA_BILINEAR:
            return bilinear_damper_force(P[o + BILINEAR_DAMPER.compression], P[o + BILINEAR_DAMPER.rebound], v)
        if code == DA_DIGRESSIVE:
            return digressive_damper_force(
                P[o + DIGRESSIVE.compression_low], P[o + DIGRESSIVE.compression_high],
                P[o + DIGRESSIVE.compression_knee], P[o + DIGRESSIVE.rebound_low], P[o + DIGRESSIVE.rebound_high],
                P[o + DIGRESSIVE.rebound_knee], v)
        if code == DA_ORIFICE:
            return orifice_damper_force(P[o + ORIFICE.bleed], P[o + ORIFICE.compression], P[o + ORIFICE.rebound], v)
        n = I[I_DAMPER_N]  # DA_TABLE: velocity[n], force[n], slopes[n - 1]
        velocity = P[o:o + n]
        return table_damper_force(velocity, P[o + n:o + 2 * n], P[o + 2 * n:o + 3 * n - 1],
                                  table_segment(velocity, n, v), v)

    @kernel
    def sliding_level(code, P, o, v):
        """controllers.friction.sliding_level's level for the static law of ``code`` at P[o:]."""
        if code == FR_STRIBECK:
            return stribeck_level(P[o + STRIBECK.coulomb], P[o + STRIBECK.breakaway],
                                  P[o + STRIBECK.stribeck_velocity], P[o + STRIBECK.exponent], v)
        if code == FR_STICTION:
            return stiction_level(P[o + STICTION.coulomb], P[o + STICTION.breakaway], P[o + STICTION.stiction_band], v)
        if code == FR_COULOMB_VISCOUS:
            return P[o + COULOMB_VISCOUS.coulomb]
        return P[o + COULOMB.coulomb]

    @kernel
    def sliding_viscous(code, P, o):
        """controllers.friction.sliding_level's viscous coefficient for the static law at P[o:]."""
        if code == FR_STRIBECK:
            return P[o + STRIBECK.viscous]
        if code == FR_STICTION:
            return P[o + STICTION.viscous]
        if code == FR_COULOMB_VISCOUS:
            return P[o + COULOMB_VISCOUS.viscous]
        return 0.0

    @kernel
    def _sticking_rate(I, P, v, z):
        o = I[I_FRICTION_AT]
        level = sliding_level(I[I_FRICTION_INNER], P, I[I_FRICTION_INNER_AT], v)
        return sticking_rate(P[o + STICKING.stiffness], P[o + STICKING.elastic], level, v, z)

    @kernel
    def _sticking_force(I, P, v, z, rate):
        o = I[I_FRICTION_AT]
        viscous = sliding_viscous(I[I_FRICTION_INNER], P, I[I_FRICTION_INNER_AT])
        return sticking_force(P[o + STICKING.stiffness], P[o + STICKING.damping], P[o + STICKING.damping_velocity],
                              viscous, rate, v, z)

    @kernel
    def _lugre_rate(P, o, v, z):
        return lugre_rate(P[o + LUGRE.coulomb], P[o + LUGRE.breakaway], P[o + LUGRE.stribeck_velocity],
                          P[o + LUGRE.stiffness], v, z)

    @kernel
    def friction_force(I, P, v, z):
        if I[I_FRICTION] == FR_STICKING:
            return _sticking_force(I, P, v, z, _sticking_rate(I, P, v, z))
        return _friction_force(I, P, v, z)

    @kernel
    def _friction_force(I, P, v, z):
        """``friction_force`` for every law but Sticking."""
        code = I[I_FRICTION]
        o = I[I_FRICTION_AT]
        if code == FR_NONE:
            return 0.0
        if code == FR_COULOMB:
            return coulomb_force(P[o + COULOMB.coulomb], P[o + COULOMB.band], v)
        if code == FR_COULOMB_VISCOUS:
            return coulomb_viscous_force(P[o + COULOMB_VISCOUS.coulomb], P[o + COULOMB_VISCOUS.viscous],
                                         P[o + COULOMB_VISCOUS.band], v)
        if code == FR_STICTION:
            return stiction_force(P[o + STICTION.coulomb], P[o + STICTION.breakaway], P[o + STICTION.viscous],
                                  P[o + STICTION.stiction_band], P[o + STICTION.band], v)
        if code == FR_STRIBECK:
            return stribeck_force(P[o + STRIBECK.coulomb], P[o + STRIBECK.breakaway], P[o + STRIBECK.viscous],
                                  P[o + STRIBECK.stribeck_velocity], P[o + STRIBECK.exponent], P[o + STRIBECK.band], v)
        return lugre_force(P[o + LUGRE.stiffness], P[o + LUGRE.damping], P[o + LUGRE.viscous],
                           _lugre_rate(P, o, v, z), v, z)

    @kernel
    def fork_force(I, P, x, v, z):
        """ForkLaw.force(x, v, z) from a flattened law."""
        return spring_force(I, P, x, v) + damper_force(I, P, v) + friction_force(I, P, v, z)

    @kernel
    def state_rate(I, P, v, z):
        """ForkLaw.state_rate(v, z) from a flattened law."""
        if I[I_FRICTION] == FR_STICKING:
            return _sticking_rate(I, P, v, z)
        if I[I_FRICTION] != FR_LUGRE:
            return 0.0
        return _lugre_rate(P, I[I_FRICTION_AT], v, z)

    @kernel
    def fork_force_rate(I, P, x, v, z):
        """(fork_force, state_rate) at once: the stick state's rate is worked out once for both."""
        if I[I_FRICTION] == FR_STICKING:
            rate = _sticking_rate(I, P, v, z)
            friction = _sticking_force(I, P, v, z, rate)
        else:  # _friction_force written once: inlined, each call is another copy of it to compile
            friction = _friction_force(I, P, v, z)
            rate = _lugre_rate(P, I[I_FRICTION_AT], v, z) if I[I_FRICTION] == FR_LUGRE else 0.0
        # each law written once (fork_force's sum, in its order): inlined, the kernel stays small
        return spring_force(I, P, x, v) + damper_force(I, P, v) + friction, rate

    # The dispatch above compiled into its callers (numba's inline="always"), for the loops that
    # evaluate the law thousands of times per run: the fast engine's Runge-Kutta steps and
    # ``fork_forces``, which scans the stroke for the step rule of every drop. Called as separately
    # compiled functions, one evaluation of S12's fork at random points cost 2.0 times as much as
    # inlined, of its main spring alone 5.1 times (benchmarks/law_kernels.py). The MuJoCo callbacks
    # keep the calls: inlined there, their first compile took 45 s instead of 2 s, for a law
    # evaluation that is a small part of a MuJoCo step.
    def _inlined(dispatchers):
        """Twins of ``dispatchers`` compiled into every kernel that calls them: the same code, each
        seeing the others' twins by name (a namespace of their own, as ``jit.law_function``)."""
        namespace = dict(globals())
        twins = {}
        for dispatcher in dispatchers:
            twins[dispatcher.__name__] = kernel(rebound(dispatcher.py_func, namespace), inline=True)
        namespace.update(twins)
        return types.SimpleNamespace(**twins), namespace

    inlined, _inlined_namespace = _inlined((
        spring_force, damper_force, sliding_level, sliding_viscous, _sticking_rate, _sticking_force, _lugre_rate,
        _friction_force, friction_force, fork_force, state_rate, fork_force_rate))

    def fork_forces(I, P, x, v, z, out):
        """``fork_force`` along a trace: out[i] = ForkLaw.force(x[i], v[i], z[i])."""
        I, P = borrow_i64(I), borrow_f64(P)
        for i in range(x.size):
            out[i] = fork_force(I, P, x[i], v[i], z[i])

    fork_forces = kernel(rebound(fork_forces, _inlined_namespace))  # calls the inlined fork_force

    @kernel
    def modal_filter(phi, g_in, g_new, r, w, u, out):
        """measure.logger_filter's recursion: y = 2 Re sum r (w + g_new u); w <- phi w + g_in u."""
        for s in range(u.shape[0]):
            for k in range(u.shape[1]):
                x = u[s, k]
                acc = 0.0
                for i in range(phi.size):
                    acc += (r[i] * (w[s, i] + g_new[i] * x)).real
                    w[s, i] = phi[i] * w[s, i] + g_in[i] * x
                out[s, k] = 2.0 * acc

    say_now_if_cold(_compile_notice, "the force laws", fork_force)
    COMPILE_SECONDS = time.perf_counter() - _compile_start
    _compile_notice.cancel()

__all__ = ["available", "COMPILE_SECONDS", "compiling"]

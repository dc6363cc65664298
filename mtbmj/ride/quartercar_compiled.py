"""The reconstruction's forward quarter car (``mtbmj.ride.reconstruct.forward``) compiled: the same
classical RK4 at the record's step, the same substeps where a step diverges, the fork or shock law
through the compiled kernel every engine runs (``controllers.kernels.fork_force_rate``) and the
leverage curve through the bike's own lookups (``mtbmj.bike.spec.leverage_ratio`` and
``leverage_stroke``, compiled from their source). ``run`` returns None where it cannot run
(numba missing, a law with no compiled form): ``forward`` then steps in Python. ``states`` integrates
a law's friction state along a record as ``reconstruct_inverse.law_along`` does (None: in Python).
"""
from __future__ import annotations

import numpy as np

from mtbmj.controllers import jit as _jit

FORK, LEVERAGE = 0, 1  # the stroke's geometry: along the steering axis, or through a leverage curve
_numba = _jit.numba

if _numba is not None:
    from mtbmj.bike import spec as _spec
    from mtbmj.controllers import kernels as _kernels
    from mtbmj.rolling.callback_compiled import piece_index as _piece_index

    _fork_force_rate = _kernels.fork_force_rate
    _jit.law_function(_spec.stroke_piece)
    _ratio = _jit.law_function(_spec.leverage_ratio)
    _stroke = _jit.law_function(_spec.leverage_stroke)

    _state_rate = _kernels.state_rate

    @_jit.kernel
    def _states(I, P, v, dt, z):
        """``reconstruct_inverse._states``' loop: the law's friction state along the rates ``v`` (explicit
        midpoint) into ``z`` (z[0] given)."""
        for i in range(1, v.size):
            half = z[i - 1] + 0.5 * dt * _state_rate(I, P, v[i - 1], z[i - 1])
            z[i] = z[i - 1] + dt * _state_rate(I, P, 0.5 * (v[i - 1] + v[i]), half)

    @_jit.kernel
    def _geometry(mode, sin_a, LW, LR, LS, w):
        """(stroke, wheel travel per stroke) at wheel rise ``w``: the piece holding w found as the
        bike's compiled callback finds it (the lookups handle w outside the table first)."""
        if mode == 0:
            return w / sin_a, sin_a
        i = _piece_index(LW, LW.size, w)
        return _stroke(LW, LR, LS, i, w), _ratio(LW, LR, i, w)

    @_jit.kernel
    def _rhs(I, P, stateful, q, mode, sin_a, LW, LR, LS, zb, zw, vb, vw, zs, g, push):
        """d(zb, zw, vb, vw, zs)/dt: ``reconstruct.forward``'s rhs. q = (sprung, unsprung, tyre
        rate, radius, gravity)."""
        w = zw - zb
        x, r = _geometry(mode, sin_a, LW, LR, LS, w)
        xd = (vw - vb) / r
        if stateful:
            f, rate = _fork_force_rate(I, P, x, xd, zs)
        else:
            f, rate = _fork_force_rate(I, P, x, xd, 0.0)
            rate = 0.0
        f = f / r
        tyre = q[2] * (g - (zw - q[3]))
        if tyre < 0.0:
            tyre = 0.0
        return vb, vw, (f - push) / q[0] - q[4], (tyre - f) / q[1] - q[4], rate

    @_jit.kernel
    def _steps(I, P, stateful, q, mode, sin_a, LW, LR, LS, y, g0, g1, p0, p1, dt, n):
        h = dt / n
        a0, a1, a2, a3, a4 = y[0], y[1], y[2], y[3], y[4]
        for j in range(n):
            fa, fb = j / n, (j + 1) / n
            ga, gb, gm = g0 + fa * (g1 - g0), g0 + fb * (g1 - g0), g0 + 0.5 * (fa + fb) * (g1 - g0)
            pa, pb, pm = p0 + fa * (p1 - p0), p0 + fb * (p1 - p0), p0 + 0.5 * (fa + fb) * (p1 - p0)
            k1 = _rhs(I, P, stateful, q, mode, sin_a, LW, LR, LS, a0, a1, a2, a3, a4, ga, pa)
            k2 = _rhs(I, P, stateful, q, mode, sin_a, LW, LR, LS, a0 + 0.5 * h * k1[0], a1 + 0.5 * h * k1[1],
                      a2 + 0.5 * h * k1[2], a3 + 0.5 * h * k1[3], a4 + 0.5 * h * k1[4], gm, pm)
            k3 = _rhs(I, P, stateful, q, mode, sin_a, LW, LR, LS, a0 + 0.5 * h * k2[0], a1 + 0.5 * h * k2[1],
                      a2 + 0.5 * h * k2[2], a3 + 0.5 * h * k2[3], a4 + 0.5 * h * k2[4], gm, pm)
            k4 = _rhs(I, P, stateful, q, mode, sin_a, LW, LR, LS, a0 + h * k3[0], a1 + h * k3[1], a2 + h * k3[2],
                      a3 + h * k3[3], a4 + h * k3[4], gb, pb)
            a0 = a0 + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
            a1 = a1 + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
            a2 = a2 + h / 6.0 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
            a3 = a3 + h / 6.0 * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])
            a4 = a4 + h / 6.0 * (k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4])
        return a0, a1, a2, a3, a4

    @_jit.kernel
    def _forward(I, P, stateful, q, mode, sin_a, LW, LR, LS, ground, load, dt, y, out):
        """The wheel's rise at every sample into ``out`` from the state ``y``; returns -1, or the
        sample where the quarter car diverged."""
        out[0] = y[1] - y[0]
        for i in range(ground.size - 1):
            n = 1
            b = (y[0], y[1], y[2], y[3], y[4])
            while n <= 1000:
                b = _steps(I, P, stateful, q, mode, sin_a, LW, LR, LS, y, ground[i], ground[i + 1], load[i],
                           load[i + 1], dt, n)
                ok = True
                for k in range(5):
                    if not np.isfinite(b[k]):
                        ok = False
                for k in range(4):
                    if abs(b[k] - y[k]) >= 1.0:
                        ok = False
                if ok:
                    break
                n *= 10
            for k in range(5):
                y[k] = b[k]
                if not np.isfinite(b[k]):
                    return i + 1
            out[i + 1] = y[1] - y[0]
        return -1


def run(law, stateful: bool, masses: tuple, mode: int, sin_a: float, leverage, ground, load, dt: float,
        y0) -> tuple[np.ndarray, int] | None:
    """(the wheel's rise at every sample, -1 or the sample where it diverged), or None where the
    compiled path cannot run. ``masses`` = (sprung, unsprung, tyre rate, radius, gravity);
    ``leverage`` a ``mtbmj.bike.spec.Leverage`` (``mode`` LEVERAGE) or None (FORK: the stroke along
    the steering axis, the wheel rising ``sin_a`` per stroke)."""
    if _numba is None:
        return None
    from mtbmj.controllers.lawcodes import UnsupportedLaw, law_arrays

    try:
        I, P = law_arrays(law)
    except UnsupportedLaw:
        return None
    if leverage is None:
        LW = LR = LS = np.zeros(2)
    else:
        LW, LR, LS = (np.asarray(v, dtype=np.float64) for v in leverage.table)
    ground = np.ascontiguousarray(ground, dtype=np.float64)
    load = np.ascontiguousarray(load, dtype=np.float64)
    out = np.empty(ground.size)
    y = np.array(y0, dtype=np.float64)
    bad = _forward(I, P, bool(stateful), np.asarray(masses, dtype=np.float64), int(mode), float(sin_a), LW, LR, LS,
                   ground, load, float(dt), y, out)
    return out, int(bad)


def states(law, v, dt: float) -> np.ndarray | None:
    """The law's friction state along a record's stroke rates ``v`` (m/s, step ``dt``), from 0, as
    ``reconstruct_inverse._states`` integrates it; None where the compiled path cannot run."""
    if _numba is None:
        return None
    from mtbmj.controllers.lawcodes import UnsupportedLaw, law_arrays

    try:
        I, P = law_arrays(law)
    except UnsupportedLaw:
        return None
    v = np.ascontiguousarray(v, dtype=np.float64)
    z = np.zeros(v.size)
    _states(I, P, v, float(dt), z)
    return z


__all__ = ["FORK", "LEVERAGE", "run", "states"]

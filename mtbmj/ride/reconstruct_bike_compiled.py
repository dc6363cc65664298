"""The reconstruction's whole bike (``mtbmj.ride.reconstruct_bike.ride``) compiled: the same equations,
the same classical RK4 at the record's step with the same substeps (1, 10, 100, 1000) where a step
leaves the finite numbers, moves a position by a metre or changes a rate by more than
``reconstruct_bike.RATE_JUMP``, the same outputs. The fork's and the
shock's laws run through the compiled kernel every engine runs (``controllers.kernels.fork_force_rate``),
the leverage curve through the bike's own lookups (``mtbmj.bike.spec.leverage_ratio`` and
``leverage_stroke``, compiled from their source), as ``quartercar_compiled`` does for the quarter
cars. ``run`` returns None where it cannot run (numba missing, a law with no compiled form):
``ride`` then steps in Python, its specification.

The state is one layout for both modes: z, th, zr, tr, zq, zw, vz, om, vr, orr, vq, vw, sr, sf (the
frame's heave and pitch, the rider's, the rear wheel's centre, the front wheel's centre, their
rates, the shock's and the fork's law states); with the fork's stroke prescribed, zw, vw and sf stay
0 (their rates 0), which leaves every other number as the Python loop's.
"""
from __future__ import annotations

import numpy as np

from mtbmj.controllers import jit as _jit

_numba = _jit.numba
# the numbers of the whole bike in the float row ``q`` the kernels take (``run`` fills it)
(Q_FA, Q_FB, Q_FM, Q_LA, Q_RA, Q_LR, Q_RR, Q_SA, Q_K, Q_R, Q_G, Q_ZF, Q_ZR, Q_KS, Q_CS, Q_BOUND, Q_PLEG, Q_KLEG,
 Q_CLEG, Q_PARM, Q_KARM, Q_CARM, Q_M, Q_I, Q_MR, Q_IR, Q_MREAR) = range(27)
SIZE, POSITIONS = 14, 6

if _numba is not None:
    from mtbmj.bike import spec as _spec
    from mtbmj.controllers import kernels as _kernels
    from mtbmj.rolling.callback_compiled import piece_index as _piece_index

    _fork_force_rate = _kernels.fork_force_rate
    _jit.law_function(_spec.stroke_piece)
    _ratio = _jit.law_function(_spec.leverage_ratio)
    _stroke = _jit.law_function(_spec.leverage_stroke)

    @_jit.kernel
    def _rhs(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top, ref,
             vref, last, y, i0, i1, s, d):
        """``reconstruct_bike.ride``'s rhs: d/dt of ``y`` into ``d``; returns the slow load (prescribed)
        or the push (free) there. The same expressions in the same order as the Python one."""
        fa, fb, fm = q[Q_FA], q[Q_FB], q[Q_FM]
        la, ra, lr, rr = q[Q_LA], q[Q_RA], q[Q_LR], q[Q_RR]
        sa, k, R, g = q[Q_SA], q[Q_K], q[Q_R], q[Q_G]
        z, th, zr, tr, zq, zw = y[0], y[1], y[2], y[3], y[4], y[5]
        vz, om, vr, orr, vq, vw = y[6], y[7], y[8], y[9], y[10], y[11]
        sr, sf = y[12], y[13]
        ptF, ptR = z + fa * th, z + fb * th
        vptF, vptR = vz + fa * om, vz + fb * om
        wR = zq - (q[Q_ZR] + ptR)
        j = _piece_index(LW, LW.size, wR)
        r_ = _ratio(LW, LR, j, wR)
        xr, xrd = _stroke(LW, LR, LS, j, wR), (vq - vptR) / r_
        if stateful_r:
            fr, dsr = _fork_force_rate(IS, PS, xr, xrd, sr)
        else:
            fr, dsr = _fork_force_rate(IS, PS, xr, xrd, 0.0)
            dsr = 0.0
        fr = fr / r_
        tR = k * (gR[i0] + s * (gR[i1] - gR[i0]) - (zq - R))
        tR = tR if tR > 0.0 else 0.0
        leg = q[Q_PLEG] + q[Q_KLEG] * (z + la * th - zr - lr * tr) + q[Q_CLEG] * (vz + la * om - vr - lr * orr)
        arm = q[Q_PARM] + q[Q_KARM] * (z + ra * th - zr - rr * tr) + q[Q_CARM] * (vz + ra * om - vr - rr * orr)
        dsf = 0.0
        tF = 0.0
        if free:
            xf, xfd = (zw - (q[Q_ZF] + ptF)) / sa, (vw - vptF) / sa
            if stateful_f:
                ff, dsf = _fork_force_rate(IF, PF, xf, xfd, sf)
            else:
                ff, dsf = _fork_force_rate(IF, PF, xf, xfd, 0.0)
                dsf = 0.0
            ff = ff / sa
            tF = k * (gF[i0] + s * (gF[i1] - gF[i0]) - (zw - R))
            tF = tF if tF > 0.0 else 0.0
            u = pushed[i0] + s * (pushed[i1] - pushed[i0])
        else:
            if top[i0] and top[i1]:  # hanging on the top-out stop: the wheel moves with the frame's front
                ff = -fm * (last[0] + aF[i0] + s * (aF[i1] - aF[i0]) + g)
            else:
                ff = fFrame[i0] + s * (fFrame[i1] - fFrame[i0])
            u = -q[Q_KS] * (ptF - ref[i0] - s * (ref[i1] - ref[i0])) - q[Q_CS] * (vptF - vref[i0] - s * (vref[i1] - vref[i0]))
            bound = q[Q_BOUND]
            u = -bound if -bound > u else u  # min(max(u, -bound), bound), as Python's max and min read them
            u = bound if bound < u else u
        M = q[Q_M]
        Fz = ff + u + fr - leg - arm - M * g
        Mo = fa * (ff + u) + fb * fr - la * leg - ra * arm
        d[0], d[1], d[2], d[3], d[4] = vz, om, vr, orr, vq
        d[6], d[7], d[8], d[9], d[10] = Fz / M, Mo / q[Q_I], (leg + arm) / q[Q_MR] - g, (lr * leg + rr * arm) / q[Q_IR], \
            (tR - fr) / q[Q_MREAR] - g
        d[12] = dsr
        if free:
            d[5], d[11], d[13] = vw, (tF - ff) / fm - g, dsf
        else:
            d[5], d[11], d[13] = 0.0, 0.0, 0.0
        return u

    @_jit.kernel
    def _rk4(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top, ref, vref,
             last, y, i, m, dt, out, k1, k2, k3, k4, tmp):
        """``m`` RK4 substeps of sample ``i`` from ``y`` into ``out``."""
        h = dt / m
        for a in range(SIZE):
            out[a] = y[a]
        for j in range(m):
            s0, s1 = j / m, (j + 1) / m
            sm = 0.5 * (s0 + s1)
            _rhs(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top, ref,
                 vref, last, out, i, i + 1, s0, k1)
            for a in range(SIZE):
                tmp[a] = out[a] + 0.5 * h * k1[a]
            _rhs(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top, ref,
                 vref, last, tmp, i, i + 1, sm, k2)
            for a in range(SIZE):
                tmp[a] = out[a] + 0.5 * h * k2[a]
            _rhs(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top, ref,
                 vref, last, tmp, i, i + 1, sm, k3)
            for a in range(SIZE):
                tmp[a] = out[a] + h * k3[a]
            _rhs(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top, ref,
                 vref, last, tmp, i, i + 1, s1, k4)
            for a in range(SIZE):
                out[a] = out[a] + h / 6.0 * (k1[a] + 2 * k2[a] + 2 * k3[a] + k4[a])

    @_jit.kernel
    def _ride(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, wF, aF, fFrame, fTyre,
              top, ref, vref, maxdef, dt, zmax_r, zmax_f, jump, y, rear_rise, out_front, tyre_front, slow):
        """``reconstruct_bike.ride``'s loop: the series into the four arrays from the state ``y``;
        returns -1, or the sample where the run diverged."""
        n = gR.size
        last = np.zeros(1)
        d, nxt = np.empty(SIZE), np.empty(SIZE)
        k1, k2, k3, k4, tmp = np.empty(SIZE), np.empty(SIZE), np.empty(SIZE), np.empty(SIZE), np.empty(SIZE)
        fa, fb, fm, g, k, R = q[Q_FA], q[Q_FB], q[Q_FM], q[Q_G], q[Q_K], q[Q_R]
        half = POSITIONS if free else POSITIONS - 1
        for i in range(n):
            if i > 0:  # the step from i - 1 to i
                m = 1
                while True:
                    _rk4(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top,
                         ref, vref, last, y, i - 1, m, dt, nxt, k1, k2, k3, k4, tmp)
                    ok = True
                    for a in range(SIZE):
                        if not np.isfinite(nxt[a]):
                            ok = False
                    for a in range(half):
                        if not abs(nxt[a] - y[a]) < 1.0:
                            ok = False
                        if not abs(nxt[POSITIONS + a] - y[POSITIONS + a]) < jump:  # its rate (ride's RATE_JUMP)
                            ok = False
                    if not (abs(nxt[12]) <= zmax_r and abs(nxt[13]) <= zmax_f):  # a friction state unstable
                        ok = False
                    if ok:
                        break
                    m *= 10
                    if m > 1000:
                        break
                if m > 1000:
                    return i
                for a in range(SIZE):
                    y[a] = nxt[a]
            # the sample recorded (``ride``'s record)
            u = _rhs(free, IS, PS, stateful_r, IF, PF, stateful_f, q, LW, LR, LS, gR, gF, pushed, aF, fFrame, top,
                     ref, vref, last, y, i, i, 0.0, d)
            last[0] = d[6] + fa * d[7]  # the frame front's acceleration
            ptF, ptR = y[0] + fa * y[1], y[0] + fb * y[1]
            rear_rise[i] = y[4] - (q[Q_ZR] + ptR)
            if free:
                out_front[i] = y[5] - (q[Q_ZF] + ptF)
                continue
            tyre = 0.0 if top[i] else fm * (last[0] + aF[i] + g) + fTyre[i]
            tyre_front[i] = tyre
            slow[i] = u
            lift = 0.0 if 0.0 > tyre else tyre  # min(max(tyre, 0.0) / k, max_deflection), as Python reads it
            lift = lift / k
            lift = maxdef if maxdef < lift else lift
            out_front[i] = q[Q_ZF] + ptF + wF[i] - R + lift  # the rim stops it
        return -1


def _f64(a, n):
    return np.zeros(n) if a is None else np.ascontiguousarray(a, dtype=np.float64)


def run(b, free: bool, numbers: dict, rear_ground, front_ground=None, pushed=None, front=None, ref=None,
        vref=None) -> tuple[dict, int] | None:
    """(the four series of ``reconstruct_bike.ride``: "rear_rise", "front", "tyre", "slow", and -1 or
    the sample where the run diverged), or None where the compiled path cannot run. ``b`` the
    ``WholeBike``, ``numbers`` the values ``ride`` derives from it (fa fb fm la ra lr rr zF_pt0
    zR_pt0 K C bound), ``front`` ``ride``'s (wF, aF, fFrame, fTyre, top) where prescribed."""
    if _numba is None:
        return None
    from mtbmj.controllers.lawcodes import UnsupportedLaw, law_arrays

    try:
        IS, PS = law_arrays(b.shock)
        IF, PF = law_arrays(b.fork) if free else law_arrays(b.shock)  # prescribed: the fork's law is not run
    except UnsupportedLaw:
        return None
    LW, LR, LS = (np.asarray(v, dtype=np.float64) for v in b.lev.table)
    gR = _f64(rear_ground, 0)
    n = gR.size
    v = numbers
    q = np.array([v["fa"], v["fb"], v["fm"], v["la"], v["ra"], v["lr"], v["rr"], b.sin_a, b.tyre, b.radius, b.g,
                  v["zF_pt0"], v["zR_pt0"], v["K"], v["C"], v["bound"], b.P_leg, b.k_leg, b.c_leg, b.P_arm, b.k_arm,
                  b.c_arm, b.M, b.I, b.mr, b.Ir, b.mR], dtype=np.float64)
    if free:
        wF = aF = fFrame = fTyre = ref = vref = np.zeros(n)
        top = np.zeros(n, dtype=np.bool_)
        gF, pushed = _f64(front_ground, n), _f64(pushed, n)
    else:
        wF, aF, fFrame, fTyre = (_f64(a, n) for a in front[:4])
        top = np.ascontiguousarray(front[4], dtype=np.bool_)
        ref, vref = _f64(ref, n), _f64(vref, n)
        gF = pushed = np.zeros(n)
    y = np.zeros(SIZE)
    y[4] = v["zR_pt0"] + b.wR0  # the rear wheel's centre at rest
    if free:
        y[5] = v["zF_pt0"] + b.wF0
    rear_rise, out_front = np.empty(n), np.empty(n)
    tyre_front, slow = np.zeros(n), np.zeros(n)
    bad = _ride(bool(free), IS, PS, bool(b.shock.has_state), IF, PF, bool(b.fork.has_state), q, LW, LR, LS, gR, gF,
                pushed, wF, aF, fFrame, fTyre, top, ref, vref, float(b.max_deflection), float(v["dt"]),
                float(v["zmax_r"]), float(v["zmax_f"]), float(v["jump"]), y, rear_rise, out_front, tyre_front, slow)
    return {"rear_rise": rear_rise, "front": out_front, "tyre": tyre_front, "slow": slow}, int(bad)


def unavailable(b, free: bool) -> str | None:
    """Why ``run`` cannot run the whole bike ``b`` here (the warning ``ride`` gives as it falls back
    to Python), or None."""
    if _numba is None:
        return f"{_jit.FALLBACK_MESSAGE} (the reconstruction's whole bike steps in Python)"
    from mtbmj.controllers.lawcodes import UnsupportedLaw, law_arrays

    for name, law in (("shock", b.shock),) + ((("fork", b.fork),) if free else ()):
        try:
            law_arrays(law)
        except UnsupportedLaw as error:
            return f"the {name}'s law has no compiled form ({error}): the reconstruction's whole bike steps in Python"
    return None


__all__ = ["run", "unavailable", "SIZE", "POSITIONS"]

"""The reconstruction's whole bike (mtbmj/ride/reconstruct.py's module doc says how it is used): the
frame heaving and pitching, the rider on his legs and arms (vertical springs and dampers at the pedals
and the bars, preloaded by the lever rule) heaving and pitching on it, the fork's lower and wheel
along the steering axis, the rear wheel through the leverage curve, point-contact tyres that leave
the ground; small pitch angles, vertical motion only (the wheelbase fixed at the ride's sag) except
that the frame's pitch carries the bike's masses fore and aft (:func:`carried_inertia`: the rider on
his limbs and the wheels are held fore and aft by the frame, as in the MuJoCo bike), the
frame body's and the rider's masses, centres and inertias from the bike file
(``mtbmj.bike.model.frame_body``), the rear's unsprung mass the wheel and half the swingarm.

:func:`ride` integrates it (classical RK4 at the record's step, a step that leaves the finite numbers
redone in 10, 100 and 1000 substeps) in one of two ways: with the fork's stroke *prescribed* by its record
(the fork's force on the frame read from its law along the recorded stroke, the ground under the
front wheel found at every sample as the wheel's height less the tyre's loaded radius: the inverse,
pitch-coupled), or *free* (both wheels over given grounds: a forward run). The rear wheel rides the
ground it is given in both.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtbmj.ride.reconstruct_share import met_at_once

SLOW_HZ = 0.3  # the rider's slow load: the loop that keeps the frame's front on its slow reference closes here
SLOW_BOUND = 0.5  # ... bounded by this share of the rider's weight (what a rider can push or pull)
MAX_PASSES = 8  # the terrain found again over the rear's ground of the pass before, at most this often
SETTLED_M = 0.2e-3  # ... until the rear predicted moves less than this (RMS) from one pass to the next
RATE_JUMP = 20.0  # m/s (rad/s): no body of a bike moves at this (a 20 m fall): a step changing a rate by more is unstable
COMPILED = True  # ``ride`` steps compiled where it can (``reconstruct_bike_compiled``); False: in Python


def _law_force(law, x, v, z):
    return law.force(x, v, z) if law.has_state else law.force(x, v)


@dataclass(frozen=True)
class WholeBike:
    """The whole bike's numbers (SI): the frame body, the rider, each end, the tyres."""

    M: float  # kg, frame body (frame and the rider's on-bike segments)
    cx: float  # m, its centre of mass, frame x
    I: float  # kg m^2 about it
    mr: float  # kg, the rider on his limbs
    rx: float
    Ir: float
    leg_x: float
    arm_x: float
    k_leg: float
    c_leg: float
    k_arm: float
    c_arm: float
    P_leg: float  # N, the limbs' preloads at rest
    P_arm: float
    xF: float  # m, frame x of the front axle
    xR: float
    mF: float  # kg, unsprung
    mR: float
    sin_a: float
    fork: object  # the fork's law (along its stroke)
    shock: object  # the shock's law
    lev: object  # the leverage curve (wheel travel -> stroke, ratio)
    fork_travel: float
    tyre: float  # N/m
    radius: float
    g: float
    max_deflection: float  # m, the tyre's deflection where the rim strikes (inf: no rim)
    fF0: float  # N, the fork's vertical force at rest
    fR0: float
    wF0: float  # m, each wheel's rise in the frame at rest
    wR0: float


def carried_inertia(spec, M: float, cz: float) -> float:
    """The pitch inertia (kg m^2) the frame's pitch adds by carrying the bike's masses fore and aft:
    sum m_i (z_i - z_bar)^2 over the frame body (``M`` at height ``cz``), the rider (his centre of mass),
    the fork's lower and front wheel (the front axle), the rear wheel (the rear axle) and the swingarm
    (midway between the pivot and the axle), heights in the frame, z_bar their mass-weighted mean.

    The frame holds each of them fore and aft (the rider on his limbs slides along the frame's z only,
    the wheels on the fork's axis and the swingarm), so a pitch theta moves each by -z_i theta; with
    the bike's horizontal momentum free of the pitch (the tyres' forces near vertical, the drive
    holding the speed), the frame's origin moves by z_bar theta and the horizontal kinetic energy is
    1/2 sum m_i (z_i - z_bar)^2 theta'^2. Left out (the pitch inertia the frame body's alone), the
    tests' bike pitched about an axis with a quarter of its inertia: the MuJoCo bike's fork moved 4.3
    mm over a 5 mm, 2 m washboard at 6 m/s where this bike's moved 1.6 (3.5 with it)."""
    r = spec.rider
    mid = 0.5 * (spec.pivot[1] + spec.rear_axle[1])
    parts = [(M, cz), (r.mass, r.com[1]), (spec.fork_lower_mass + spec.front_wheel_mass, spec.front_axle[1]),
             (spec.rear_wheel_mass, spec.rear_axle[1]), (spec.swingarm_mass, mid)]
    z_bar = sum(m * z for m, z in parts) / sum(m for m, _ in parts)
    return float(sum(m * (z - z_bar) ** 2 for m, z in parts))


def whole_bike(spec, fork_setup, shock_setup) -> WholeBike:
    """The bike file's whole bike at rest on level ground."""
    from scipy.optimize import brentq

    from mtbmj.bike.model import frame_body

    M, (cx, cz), I = frame_body(spec)
    I = I + carried_inertia(spec, M, cz)
    r = spec.rider
    g = fork_setup.gravity
    xF, xR = spec.front_axle[0], spec.rear_axle[0]
    span = r.arm_x - r.leg_x
    P_leg, P_arm = r.mass * g * (r.arm_x - r.com[0]) / span, r.mass * g * (r.com[0] - r.leg_x) / span
    fF0 = (M * (cx - xR) + r.mass * (r.com[0] - xR)) * g / (xF - xR)  # moments about the rear axle
    fR0 = (M + r.mass) * g - fF0
    sa = math.sin(spec.head_angle)
    fork, shock, lev = fork_setup.fork, shock_setup.fork, spec.leverage

    def rest(f, target, top):
        lo, hi = 0.0, top
        if f(hi) < target:
            return hi
        return brentq(lambda w: f(w) - target, lo, hi, xtol=1e-9)

    wF0 = rest(lambda w: _law_force(fork, w / sa, 0.0, 0.0) / sa, fF0, fork_setup.travel * sa)
    wR0 = rest(lambda w: _law_force(shock, lev.stroke(w), 0.0, 0.0) / lev.ratio_at(w), fR0, lev.full_travel)
    return WholeBike(M, cx, I, r.mass, r.com[0], r.pitch_inertia, r.leg_x, r.arm_x, r.leg_stiffness, r.leg_damping,
                     r.arm_stiffness, r.arm_damping, P_leg, P_arm, xF, xR,
                     spec.fork_lower_mass + spec.front_wheel_mass, spec.rear_wheel_mass + 0.5 * spec.swingarm_mass,
                     sa, fork, shock, lev, fork_setup.travel, fork_setup.tire.values(1).rate, fork_setup.tire_radius,
                     g, fork_setup.tire.rim.max_deflection if fork_setup.tire.rim is not None else math.inf,
                     fF0, fR0, wF0, wR0)


STATE_MARGIN = 2.0  # a friction state past this many times its largest steady deflection is integrated unstably


def state_bound(law) -> float:
    """The largest |state| a law's friction state reaches when integrated stably, with a margin
    (``STATE_MARGIN`` times its largest level over its bristles' stiffness: LuGre's and the sticking
    law's deflections stay within level / stiffness), or infinity for a law without one. A step
    that leaves it is taken again in substeps: a sliding bristle's equation is stiff (its rate
    |v| / (level / stiffness), 2e4 1/s at 9 m/s through a 40 N, 1e5 N/m fork), and one classical RK4
    step of a record's millisecond past 2.8 / rate grows it without bound while the positions stay
    finite for a while (the shared ride 00092 diverged so, at 48.48 s)."""
    f = getattr(law, "friction", None)
    if f is None or not getattr(f, "has_state", False):
        return math.inf
    inner = getattr(f, "inner", f)
    level = max(float(getattr(inner, "coulomb", 0.0)), float(getattr(inner, "breakaway", 0.0) or 0.0))
    stiffness = float(getattr(f, "stiffness", 0.0))
    return STATE_MARGIN * level / stiffness if level > 0.0 and stiffness > 0.0 else math.inf


def ride(t, b: WholeBike, rear_ground, front=None, front_ground=None, reference=None, push=None,
         compiled: bool | None = None) -> dict:
    """The whole bike ``b`` on ``t`` from rest, its rear wheel over ``rear_ground`` (m).

    Prescribed (``front`` = (the front wheel's rise in the frame m, its acceleration, the fork's
    vertical force on the frame N, the fork's vertical force N, the top-out mask), each on ``t``): the
    fork's force on the frame is read from the record; where the fork hangs on its top-out stop (whose
    force is not in the record) the wheel moves with the frame's front and adds its weight and
    inertia there. The frame's front is held near ``reference`` (its slow height, m; None: level) by a
    load closing at ``SLOW_HZ``, bounded by ``SLOW_BOUND`` of the rider's weight (the rider's slow load,
    estimated). Returns {"front_ground" (m: the front wheel's height less the tyre's loaded radius),
    "front_tyre" (N), "rear_rise", "slow_load" (N, the load the loop gave)}.

    Free (``front_ground`` given, ``push`` the load on the frame's front, N, or None): both wheels on
    their grounds; returns {"front_rise", "rear_rise"}. Rises are the wheels' in the frame (m, 0 at
    full extension). A step that leaves the finite numbers, moves a position by a metre or changes a rate
    by more than ``RATE_JUMP`` is taken again in 10, 100, 1000 substeps; one that still does in 1000 ends the run: "diverged_s"
    its time (None where it ran to the end), every series not a number from there.

    ``compiled`` (default ``COMPILED``): the same steps compiled (``mtbmj.ride.reconstruct_bike_compiled``)
    where they can run (numba present, both laws with a compiled form; else one warning and the
    Python loop below, which is their specification); False: the Python loop."""
    dt = float(t[1] - t[0])
    n = t.size
    gR = np.asarray(rear_ground, float)
    free = front is None
    fa, fb, fm = b.xF - b.cx, b.xR - b.cx, b.mF
    la, ra = b.leg_x - b.cx, b.arm_x - b.cx
    lr, rr = b.leg_x - b.rx, b.arm_x - b.rx
    sa, lev, shock, fork = b.sin_a, b.lev, b.shock, b.fork
    stateful_r, stateful_f = bool(shock.has_state), bool(fork.has_state)
    k, R, g = b.tyre, b.radius, b.g
    # the frame's axle points' heights at rest with the wheels fully out: the wheel's centre less its rise
    zF_pt0 = R - (b.fF0 + b.mF * g) / k - b.wF0
    zR_pt0 = R - (b.fR0 + b.mR * g) / k - b.wR0
    m_front = b.fF0 / g
    K, C = m_front * (2 * math.pi * SLOW_HZ) ** 2, 2.0 * m_front * 2 * math.pi * SLOW_HZ
    bound = SLOW_BOUND * b.mr * g
    zmax_r, zmax_f = state_bound(shock), state_bound(fork)  # past them a friction state is integrated unstably
    jump = RATE_JUMP  # a rate changing by more in one step (any step): an unstable step (a stiff stop), substepped
    if free:
        gF = np.asarray(front_ground, float)
        pushed = np.zeros(n) if push is None else np.asarray(push, float)
    else:
        wF, aF, fFrame, fTyre, top = front
        ref = np.zeros(n) if reference is None else np.asarray(reference, float)
        vref = np.gradient(ref, dt)
    if COMPILED if compiled is None else compiled:
        from mtbmj.ride import reconstruct_bike_compiled

        numbers = {"fa": fa, "fb": fb, "fm": fm, "la": la, "ra": ra, "lr": lr, "rr": rr, "zF_pt0": zF_pt0,
                   "zR_pt0": zR_pt0, "K": K, "C": C, "bound": bound, "dt": dt, "zmax_r": zmax_r, "zmax_f": zmax_f,
                   "jump": jump}
        done = reconstruct_bike_compiled.run(b, free, numbers, gR, front_ground=gF if free else None,
                                             pushed=pushed if free else None, front=None if free else front,
                                             ref=None if free else ref, vref=None if free else vref)
        if done is not None:
            series, bad = done
            diverged = None
            if bad >= 0:  # the run ends there, the rest not a number
                diverged = float(t[bad])
                for a in series.values():
                    a[bad:] = math.nan
            if free:
                return {"front_rise": series["front"], "rear_rise": series["rear_rise"], "diverged_s": diverged}
            return {"front_ground": series["front"], "front_tyre": series["tyre"], "rear_rise": series["rear_rise"],
                    "slow_load": series["slow"], "diverged_s": diverged}
        from mtbmj.controllers.compiled import warn_once

        warn_once(reconstruct_bike_compiled.unavailable(b, free) or "the reconstruction's whole bike steps in Python")
    last = [0.0, 0.0]  # the frame front's acceleration at the last sample, the slow load there

    def rhs(y, i0, i1, s):
        """d/dt of y: z, th, zr, tr, zq, (zw), their rates, the shock's state, (the fork's state)."""
        if free:
            z, th, zr, tr, zq, zw, vz, om, vr, orr, vq, vw, sr, sf = y
        else:
            z, th, zr, tr, zq, vz, om, vr, orr, vq, sr = y
        ptF, ptR = z + fa * th, z + fb * th
        vptF, vptR = vz + fa * om, vz + fb * om
        wR = zq - (zR_pt0 + ptR)
        r_ = lev.ratio_at(wR)
        xr, xrd = lev.stroke(wR), (vq - vptR) / r_
        fr = _law_force(shock, xr, xrd, sr) / r_
        dsr = shock.state_rate(xrd, sr) if stateful_r else 0.0
        tR = k * (gR[i0] + s * (gR[i1] - gR[i0]) - (zq - R))
        tR = tR if tR > 0.0 else 0.0
        leg = b.P_leg + b.k_leg * (z + la * th - zr - lr * tr) + b.c_leg * (vz + la * om - vr - lr * orr)
        arm = b.P_arm + b.k_arm * (z + ra * th - zr - rr * tr) + b.c_arm * (vz + ra * om - vr - rr * orr)
        if free:
            xf, xfd = (zw - (zF_pt0 + ptF)) / sa, (vw - vptF) / sa
            ff = _law_force(fork, xf, xfd, sf) / sa
            dsf = fork.state_rate(xfd, sf) if stateful_f else 0.0
            tF = k * (gF[i0] + s * (gF[i1] - gF[i0]) - (zw - R))
            tF = tF if tF > 0.0 else 0.0
            u = pushed[i0] + s * (pushed[i1] - pushed[i0])
        else:
            if top[i0] and top[i1]:  # hanging on the top-out stop: the wheel moves with the frame's front
                ff = -fm * (last[0] + aF[i0] + s * (aF[i1] - aF[i0]) + g)
            else:
                ff = fFrame[i0] + s * (fFrame[i1] - fFrame[i0])
            u = -K * (ptF - ref[i0] - s * (ref[i1] - ref[i0])) - C * (vptF - vref[i0] - s * (vref[i1] - vref[i0]))
            u = min(max(u, -bound), bound)
        Fz = ff + u + fr - leg - arm - b.M * g
        Mo = fa * (ff + u) + fb * fr - la * leg - ra * arm
        acc = (Fz / b.M, Mo / b.I, (leg + arm) / b.mr - g, (lr * leg + rr * arm) / b.Ir, (tR - fr) / b.mR - g)
        if free:
            return (vz, om, vr, orr, vq, vw) + acc + ((tF - ff) / fm - g, dsr, dsf), u
        return (vz, om, vr, orr, vq) + acc + (dsr,), u

    size = 14 if free else 11
    half = 6 if free else 5  # the positions come first
    y = [0.0] * size
    y[4] = zR_pt0 + b.wR0  # the rear wheel's centre at rest
    if free:
        y[5] = zF_pt0 + b.wF0
    rear_rise, out_front = np.empty(n), np.empty(n)
    tyre_front, slow = np.zeros(n), np.zeros(n)

    def record(i, y):
        d, u = rhs(y, i, i, 0.0)
        last[0] = d[half] + fa * d[half + 1]  # the frame front's acceleration
        ptF, ptR = y[0] + fa * y[1], y[0] + fb * y[1]
        rear_rise[i] = y[4] - (zR_pt0 + ptR)
        if free:
            out_front[i] = y[5] - (zF_pt0 + ptF)
            return
        tyre = 0.0 if top[i] else fm * (last[0] + aF[i] + g) + fTyre[i]
        tyre_front[i] = tyre
        slow[i] = u
        out_front[i] = zF_pt0 + ptF + wF[i] - R + min(max(tyre, 0.0) / k, b.max_deflection)  # the rim stops it

    def rk4(y, i, m):
        h = dt / m
        for j in range(m):
            s0, s1 = j / m, (j + 1) / m
            sm = 0.5 * (s0 + s1)
            k1 = rhs(y, i, i + 1, s0)[0]
            k2 = rhs([a + 0.5 * h * d for a, d in zip(y, k1)], i, i + 1, sm)[0]
            k3 = rhs([a + 0.5 * h * d for a, d in zip(y, k2)], i, i + 1, sm)[0]
            k4 = rhs([a + h * d for a, d in zip(y, k3)], i, i + 1, s1)[0]
            y = [a + h / 6.0 * (d1 + 2 * d2 + 2 * d3 + d4) for a, d1, d2, d3, d4 in zip(y, k1, k2, k3, k4)]
        return y

    record(0, y)
    diverged = None
    for i in range(n - 1):
        m = 1
        while True:
            try:
                with np.errstate(all="ignore"):
                    nxt = rk4(y, i, m)
            except (ArithmeticError, ValueError, IndexError):  # a state past the finite numbers (a lookup of NaN)
                nxt = [math.nan] * size
            if all(math.isfinite(a) for a in nxt) and all(abs(a - c) < 1.0 for a, c in zip(nxt[:half], y[:half])) \
                    and all(abs(a - c) < jump for a, c in zip(nxt[half:2 * half], y[half:2 * half])) \
                    and abs(nxt[half * 2]) <= zmax_r and (not free or abs(nxt[-1]) <= zmax_f):
                break
            m *= 10  # a hard stop stiffer than the record's step resolves: substeps
            if m > 1000:
                break
        if m > 1000:  # diverged: the run ends here, the rest not a number
            diverged = float(t[i + 1])
            for a in (rear_rise, out_front, tyre_front, slow):
                a[i + 1:] = math.nan
            break
        y = nxt
        record(i + 1, y)
    if free:
        return {"front_rise": out_front, "rear_rise": rear_rise, "diverged_s": diverged}
    return {"front_ground": out_front, "front_tyre": tyre_front, "rear_rise": rear_rise, "slow_load": slow,
            "diverged_s": diverged}


def rear_ground(t, lag, ground, at_once: float = 0.0, spectral: bool = False, air=None):
    """The ground the rear wheel rides (m on ``t``): the ground found under the front ``lag`` (s) earlier,
    its share ``at_once`` taken at the same moment instead (what the fork felt as a load on both ends
    at once, a turn or a compression, rather than as the terrain a wheelbase ahead). ``spectral``: of
    that, the share the found ground's spectrum says is not terrain met at the front's moment too
    (``reconstruct_share.met_at_once``, ``air`` the flights whose level changes stay a wheelbase later)."""
    behind = met_at_once(t, lag, ground, air) if spectral else np.interp(t - lag, t, ground)
    behind = behind if at_once == 0.0 else (1.0 - at_once) * behind + at_once * np.asarray(ground, float)
    return behind


def terrain_and_rear(t, b: WholeBike, fork_stroke, lag, first_ground, reference, fork_travel: float,
                     stops=None, at_once: float = 0.0, air=None, spectral: bool = False) -> dict:
    """The terrain under the front wheel and the rear's travel predicted, from the fork's record alone
    (``fork_stroke`` m on ``t``): the whole bike rides with its fork's stroke prescribed, its rear
    wheel over the ground found under the front ``lag`` (s, on ``t``) earlier; the ground of one pass
    is the rear's in the next, from ``first_ground`` (the quarter car's), until the rear predicted
    settles (``SETTLED_M``) or ``MAX_PASSES``. The fork's slow load (below the quarter car's high-pass)
    is the rider's, taken off the frame as the quarter car takes it (the tyre carries it;
    ``reconstruct_inverse.lowpass`` at the quarter car's corner, through the flights: keeping them out was
    tried and removed, docs/rolling.md, "pit"); the frame's
    front is held near ``reference`` (the quarter car's body, its drift removed) by the bounded slow
    load of :func:`ride`. ``stops`` (N at the wheel, or None): the fork's hard-stop force across each
    bottom-out (not in the record; the quarter car's, keeping its body level after it, at first, then
    the whole bike's own, ``reconstruct_flight.stop_kicks``). ``at_once``: the
    share of the rear's ground taken at the front's moment, ``spectral`` the found ground's own share of a
    load on both ends at once too (:func:`rear_ground`). Flights: where the tyre's force is not positive or the fork hangs on its
    top-out stop, merged and bridged (``reconstruct_inverse.bridge``). Returns {"ground", "airborne",
    "tyre", "rear_rise", "slow_load" (N on the frame's front: the rider's and the loop's),
    "rider_slow_load" (the rider's alone), "passes", "settled_m", "diverged_s" (where a pass diverged:
    the passes end there, the rear not a number past it)}."""
    from mtbmj.ride.reconstruct_inverse import bridge, derivatives, hanging, law_along, lowpass, unloaded

    dt = float(t[1] - t[0])
    x = np.asarray(fork_stroke, float)
    _, acc = derivatives(x, dt)
    force = law_along(b.fork, x, dt, fork_travel) / b.sin_a
    top = hanging(x, dt)
    slow = lowpass(force - b.fF0, dt)  # the rider's slow load at the front, as the quarter car's (through the flights)
    # the fork's hard stop across each bottom-out: at first as the quarter car found it, then the whole
    # bike's own (reconstruct_flight.stop_kicks)
    first = np.zeros(x.size) if stops is None else np.asarray(stops, float)
    kicks = first

    def front_with(kicks):  # the fork's side of the whole bike with the hard stop's force ``kicks``
        return (x * b.sin_a, acc * b.sin_a, force + kicks - slow, force + kicks, top)

    front = front_with(kicks)
    from mtbmj.ride import reconstruct_flight as flight

    ground = np.asarray(first_ground, float)
    before, change, passes = None, math.inf, 0
    chosen, kept, left, ref, most = None, [], [], reference, flight.pivot_acceleration(b)
    while passes < MAX_PASSES:
        out = ride(t, b, rear_ground(t, lag, ground, at_once, spectral, air), front=front, reference=ref)
        passes += 1
        ok = np.isfinite(out["front_ground"])
        found, air = bridge(np.where(ok, out["front_ground"], ground[-1] if not ok.all() else 0.0),
                            (unloaded(out["front_tyre"], b.fF0 + b.mF * b.g, dt) | top) & ok, dt)
        if not ok.all():  # diverged: past it the ground of the pass before, level past that
            last = int(np.argmin(ok))
            found[last:] = found[last - 1] if last else 0.0
        ground = found - found[0]
        if out["diverged_s"] is not None:
            break
        if first.any():  # the whole bike's own hard-stop impulses, kept level after each hit, never pulling
            kicks = flight.stop_kicks(first, kicks, ground, air, dt, b.fF0 / b.g)
            front = front_with(kicks)
        if chosen is None:  # the flights whose level is read: those of the first pass that left at a drop's edge
            chosen = flight.edge_flights(found, air, dt)
        levels = kept
        kept, left = flight.read(found, air, front[0], chosen, dt, most)
        ref = flight.reference(reference, front[0], kept, dt)
        if before is not None:
            change = float(np.sqrt(np.mean((out["rear_rise"] - before) ** 2)))
            if change < SETTLED_M and flight.settled(levels, kept):
                break
        before = out["rear_rise"]
    return {"ground": ground, "airborne": air, "tyre": out["front_tyre"], "rear_rise": out["rear_rise"],
            "slow_load": out["slow_load"] - slow, "rider_slow_load": -slow, "passes": passes, "settled_m": change,
            "diverged_s": out["diverged_s"], "levels": flight.described(t, kept, left)}


__all__ = ["SLOW_HZ", "SLOW_BOUND", "COMPILED", "MAX_PASSES", "WholeBike", "carried_inertia", "whole_bike", "ride", "rear_ground",
           "terrain_and_rear"]

"""The reconstruction's quarter cars (mtbmj/ride/reconstruct.py's module doc says how they are used):
the inverse (:func:`ground_under`: the ground under a wheel from its end's travel record, take-offs
and flights found and bridged) and the forward run (:func:`forward`: an end's travel over a ground).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtbmj.ride.reconstruct_speed import ReconstructError

DERIVATIVE_WINDOW_S = 0.02  # the Savitzky-Golay window of the records' derivatives (_derivatives)
HIGHPASS_HZ = 0.3  # the body height's drift removed below this
JUMP_GAP_S = 0.05  # the tyre's force found back above 0 for less than this within a jump (its noise): one jump
TOP_OUT_MARGIN_M = 0.5e-3  # a stroke this close to full extension hangs on the top-out stop (its force unseen)
EDGE_FLIGHT_S = 0.1  # a flight this long that lands lower than it took off left the ground at an edge (bridge)
EDGE_DROP_M = 0.15  # ... lower by more than this (a rock's back falls less)
EDGE_RISE_M = 0.05  # ... and the ground rose less than this into the take-off over EDGE_RISE_S (else thrown)
EDGE_RISE_S = 0.1
TAKE_OFF_SHARE = 0.1  # such a flight left where the tyre's force last fell below this share of its static load
MAX_FLIGHT_S = 1.5  # a fork fully out longer than this is not flying (a bike standing unweighted): the law's force at 0
BOTTOM_OUT_MARGIN_M = 0.5e-3  # a stroke this close to full travel is a bottom-out (the hard stop's force unseen)
PAST_TRAVEL_M = 2e-3  # the most an end passes its travel into its hard stop (controllers/stops.py: a hard landing)
BOTTOM_OUT_WINDOW_S = 1.0  # after a bottom-out the body's speed is set so its height stays level over this
V2_LOWPASS_HZ = 100.0  # a version-2 record (5 kHz, coarse steps) is low-passed here before anything is differentiated
G = 9.81


@dataclass(frozen=True)
class QuarterCar:
    """One end: sprung and unsprung mass (kg), its law (force along the stroke for (stroke, rate,
    state)), the stroke per wheel travel, the tyre's rate (N/m) and radius (m), the gravity."""

    sprung: float
    unsprung: float
    law: object
    tyre_rate: float
    radius: float
    gravity: float
    travel: float = math.inf  # m, the law's full stroke: the inverse reads its force within 0..travel
    max_deflection: float = math.inf  # m, the tyre's deflection where the rim strikes: the ground no deeper



def _law_force(law, x, v, z):
    return law.force(x, v, z) if law.has_state else law.force(x, v)



def _derivatives(x, dt):
    from scipy.signal import savgol_filter

    # a 20 ms window, odd: a recorder's counts step the travel by 0.1-0.4 mm, and over 10 ms the
    # second derivative of those steps buried the ground's (a ride written as SST counts aligned its
    # two ends' grounds at a correlation of 0.3 where its travel CSV gave 0.8; over 20 ms 0.7 and
    # 0.95); a cubic over 20 ms still passes the tyre's hop (15-20 Hz) whole
    n = max(5, int(round(DERIVATIVE_WINDOW_S / dt)) | 1)
    return (savgol_filter(x, n, 3, deriv=1, delta=dt, mode="interp"),
            savgol_filter(x, n, 3, deriv=2, delta=dt, mode="interp"))


def lowpass(x, dt, hz=HIGHPASS_HZ):
    """``x`` low-passed at ``hz`` (2nd-order Butterworth, forward and back: no delay); by default at
    the high-pass's corner, the slow part the high-pass takes out."""
    from scipy.signal import butter, sosfiltfilt

    return sosfiltfilt(butter(2, hz, btype="lowpass", fs=1.0 / dt, output="sos"), x)


def wheelbase_at(spec, fork: float, rear: float) -> float:
    """The wheelbase (m) with the fork ``fork`` (m of stroke) and the rear wheel ``rear`` (m of
    travel) in: the front axle moves back along the steering axis by fork cos(a), the rear axle on
    its arc about the main pivot (the frame's pitch left out)."""
    from mtbmj.bike.spec import rear_axle_in_frame

    phi = np.linspace(-0.3, 0.9, 2401)
    x, z = rear_axle_in_frame(spec, phi)
    rise = z - spec.rear_axle[1]
    up = np.concatenate(([True], np.diff(rise) > 0))  # the arc's rising part (rear wheel up)
    rear_x = float(np.interp(rear, rise[up], x[up]))
    return float(spec.front_axle[0] - fork * math.cos(spec.head_angle) - rear_x)


def highpass(x, dt):
    """``x`` high-passed at ``HIGHPASS_HZ`` (2nd-order Butterworth, forward and back): the drift's removal."""
    from scipy.signal import butter, sosfiltfilt

    sos = butter(2, HIGHPASS_HZ, btype="highpass", fs=1.0 / dt, output="sos")
    return sosfiltfilt(sos, x)


def _states(law, x, v, dt, compiled: bool = True):
    """The law's friction state along the measured stroke (explicit midpoint), or zeros; the same loop
    compiled (``quartercar_compiled.states``) where it can run and ``compiled``."""
    z = np.zeros_like(x)
    if not law.has_state:
        return z
    if compiled:
        from mtbmj.ride import quartercar_compiled

        done = quartercar_compiled.states(law, v, dt)
        if done is not None:
            return done
    for i in range(1, x.size):
        half = z[i - 1] + 0.5 * dt * law.state_rate(v[i - 1], z[i - 1])
        z[i] = z[i - 1] + dt * law.state_rate(0.5 * (v[i - 1] + v[i]), half)
    return z


def law_along(law, stroke, dt: float, travel: float) -> np.ndarray:
    """The law's force (N, along its stroke) along a recorded ``stroke`` (m, step ``dt``): its rate by
    a Savitzky-Golay filter, its friction state integrated along it; the hard stops' force cannot be
    read from a travel record (a tenth of a millimetre past full travel is kilonewtons there), so the
    force is the law's at the stroke within 0..``travel``."""
    x = np.asarray(stroke, float)
    v, _ = _derivatives(x, dt)
    z = _states(law, x, v, dt)
    xf = np.clip(x, 0.0, travel)
    from mtbmj.controllers.compiled import fork_forces_along

    f = fork_forces_along(law, xf, v, z)  # the compiled kernel (None where it cannot run)
    if f is None:
        f = np.array([_law_force(law, xi, vi, zi) for xi, vi, zi in zip(xf, v, z)])
    return f


def within_stops(ride: str, end: str, stroke, travel: float, dt: float) -> tuple[np.ndarray, dict | None]:
    """An end's ``stroke`` (m, step ``dt``) read at most ``PAST_TRAVEL_M`` past its ``travel`` (m): a
    record further past it carries its calibration's error (a version-2 record's approximate
    amplitudes, or a calibrated one within ``telemetry.TRAVEL_MARGIN_PERCENT``), not an end deeper in
    its stop, and a ground found from it asks the whole bike to press the stop's stiffening that far
    (00100.SST's fork at 191 mm of 180: the whole bike diverged at 15.9 s). Returns (the stroke so
    read, None or what was cut: {"end", "deepest_mm", "read_at_most_mm", "seconds"}), one
    ``ConfigWarning`` naming the ``ride`` and the ``end`` ("fork", "shock") where it cut."""
    import warnings

    from mtbmj.errors import ConfigWarning

    x = np.asarray(stroke, float)
    top = travel + PAST_TRAVEL_M
    past = x > top
    if not past.any():
        return x, None
    cut = {"end": end, "deepest_mm": 1e3 * float(x.max()), "read_at_most_mm": 1e3 * top,
           "seconds": float(past.sum() * dt)}
    warnings.warn(f"{ride}: the {end}'s record passes its travel ({travel * 1e3:g} mm) by {cut['deepest_mm'] - travel * 1e3:.1f} "
                  f"mm: read at {cut['read_at_most_mm']:g} mm (an end passes its travel by at most "
                  f"{PAST_TRAVEL_M * 1e3:g} mm into its stop; the rest is the record's calibration) over "
                  f"{cut['seconds']:.3f} s", ConfigWarning, stacklevel=2)
    return np.minimum(x, top), cut


def hanging(stroke, dt: float) -> np.ndarray:
    """Where an end hangs on its top-out stop in the air: its stroke within ``TOP_OUT_MARGIN_M`` of
    full extension, for no longer than ``MAX_FLIGHT_S`` and not where the record starts or ends
    (there the bike stands unweighted on the wheel, a rider getting on or off: the stop's force unseen
    there too, the law's at full extension read instead)."""
    top = np.asarray(stroke, float) <= TOP_OUT_MARGIN_M
    for a, b in runs(top):
        if (b - a) * dt > MAX_FLIGHT_S or a == 0 or b == top.size:  # too long, or where the record starts or ends
            top[a:b] = False
    return top


def derivatives(x, dt: float):
    """(rate, acceleration) of a record ``x`` on step ``dt``: a cubic Savitzky-Golay filter over
    ``DERIVATIVE_WINDOW_S``."""
    return _derivatives(np.asarray(x, float), dt)


def bridge(ground, off, dt: float, edges: bool = True):
    """(the ground with each flight bridged, the airborne mask): the stretches of ``off`` (the tyre
    carrying nothing) closer than ``JUMP_GAP_S`` merged into one flight. The wheel does not see the
    ground under a flight; it is put where a wheel leaves and meets it: a flight of at least
    ``EDGE_FLIGHT_S`` that lands more than ``EDGE_DROP_M`` lower than it took off, the ground having
    risen less than ``EDGE_RISE_M`` into the take-off over the ``EDGE_RISE_S`` before it, left at an
    edge (a drop's: a wheel leaves one level or falling), so the landing's level from the take-off on
    (``edges``); a wheel the ground threw up into its flight (off a rock's face, a kicker) flies over
    ground the landing does not give, and a long flight lets the found wheel's height drift, so it is a
    chord like the rest; a shorter hop (off a bump's
    crest, whose back falls away gently), one landing less lower, or one landing higher, the chord
    from take-off to landing (landing higher the wheel meets a face: a step there would be a wall a
    forward run hits). Kept below the wheel's path either way."""
    ground = np.array(ground, float)
    air = np.zeros(ground.size, bool)
    for a, b in flights(off, dt):
        air[a:b] = True
        a0, b0 = max(a - 1, 0), min(b, ground.size - 1)  # the last sample on the ground, the first back on it
        if edges and edge(ground, a, b, dt):  # fell away at an edge
            under = np.full(b0 - a0 + 1, ground[b0])
            under[0] = ground[a0]
        else:
            under = np.linspace(ground[a0], ground[b0], b0 - a0 + 1)
        ground[a0:b0 + 1] = np.minimum(ground[a0:b0 + 1], under)
    return ground, air


def edge(ground, a: int, b: int, dt: float, approach=None) -> bool:
    """Whether the flight of samples ``a``..``b`` (end exclusive) over ``ground`` left it at a drop's
    edge: at least ``EDGE_FLIGHT_S`` long, landing more than ``EDGE_DROP_M`` lower than it took off,
    the ground not thrown into the take-off (``EDGE_RISE_M`` over ``EDGE_RISE_S``, read on
    ``approach(a0, b0)`` where given, asked only of a flight long and falling enough:
    ``reconstruct_flight.edge_flights`` takes off the ground what the drift's removal lifts ahead of the
    flight's own fall)."""
    a0, b0 = max(a - 1, 0), min(b, len(ground) - 1)
    return bool(ground[b0] < ground[a0] - EDGE_DROP_M and (b - a) * dt >= EDGE_FLIGHT_S
                and not _thrown(ground if approach is None else approach(a0, b0), a0, dt))


def _thrown(ground, a0: int, dt: float) -> bool:
    """The ground rose ``EDGE_RISE_M`` or more into the take-off at ``a0`` over the ``EDGE_RISE_S``
    before it: the wheel was thrown into its flight (a rock's face, a kicker), not left at an edge."""
    before = ground[max(a0 - int(round(EDGE_RISE_S / dt)), 0):a0 + 1]
    return ground[a0] - before.min() >= EDGE_RISE_M


def unloaded(tyre, static: float, dt: float) -> np.ndarray:
    """Where a tyre carries nothing: its force ``tyre`` (N) not positive (a tyre light but above zero,
    as 00642.SST's and 00643.SST's forks 6-7 mm short of their top-out in hops, is not read as a flight:
    tried and removed, docs/rolling.md, "A light tyre"); and before a flight of at
    least ``EDGE_FLIGHT_S`` back to where its force last rose above ``TAKE_OFF_SHARE`` of ``static``
    (its load at rest): the inverse follows a wheel down as it unloads off an edge (the force within a
    few tens of newtons of zero for up to 0.1 s before it reads zero), which put the take-off that
    late and the ground under it falling with the wheel. A shorter flight keeps its start. Two stretches
    of zero with a force between them that averages no more than ``TAKE_OFF_SHARE`` of ``static`` are one
    flight (the inverse's force, two derivatives of the record, flickers by tens of newtons about
    nothing: read stretch by stretch, a 0.19 s fall off a 0.35 m drop was two hops of 0.09 s and its
    ground followed the wheel down); any other touch between two flights is a landing, even one that
    never carries half the static load (reading that as none was tried and removed: docs/rolling.md,
    "Wheelies' arcs")."""
    tyre = np.asarray(tyre, float)
    off = tyre <= 0.0
    low = tyre <= TAKE_OFF_SHARE * static
    zeros = runs(off)
    for (_, b), (a, _) in zip(zeros[:-1], zeros[1:]):
        if np.mean(tyre[b:a]) <= TAKE_OFF_SHARE * static:  # between two zeros the force carried next to nothing: one flight
            off[b:a] = True
    out = off.copy()
    for a, b in flights(off, dt):
        if (b - a) * dt >= EDGE_FLIGHT_S:
            k = a
            while k > 0 and low[k - 1]:
                k -= 1
            out[k:a] = True
    return out


def ground_under(t, rise, stroke, car: QuarterCar, ratio):
    """(ground height m, tyre force N, airborne mask, the rider's slow load N, the body's height m, its
    drift removed, the hard stop's force N at the wheel found across each bottom-out) under a quarter
    car whose
    wheel rose ``rise`` (m) in the frame while its law's stroke was ``stroke`` (m), both on ``t``: the
    law's force acts on the wheel divided by ``ratio(rise)`` (wheel travel per stroke; virtual work).

    Where the stroke is within ``TOP_OUT_MARGIN_M`` of full extension the wheel hangs on the top-out
    stop, whose force is not in the record: the body and the wheel fly together there (their centre
    of mass falls at g, the body's acceleration -g less the wheel's relative one in the share m / (M +
    m)) and the tyre carries nothing. Airborne is where the tyre's force is not positive, stretches
    closer than ``JUMP_GAP_S`` merged (one flight); the ground under a flight is not seen by the
    wheel: it is bridged by the chord from take-off to landing (``bridge`` without edges: the whole bike
    puts a drop's edge where the quarter car's slow reference would put it late), kept below the wheel's
    path; a long flight's take-off where the tyre's force first fell toward zero (``unloaded``). The
    rider's slow load is the force beyond the static load low-passed through the flights too."""
    dt = float(t[1] - t[0])
    w, x = np.asarray(rise, float), np.asarray(stroke, float)
    f = law_along(car.law, x, dt, car.travel) / ratio(w)
    top = hanging(x, dt)  # hanging on the top-out stop: its force unseen, the end in the air
    weight = car.sprung * car.gravity
    _, w_acc = _derivatives(w, dt)
    excess = np.where(top, weight, f) - weight
    extra = lowpass(excess, dt)  # the rider's slow load shifts (braking, weight)
    ground, tyre, body, stops = _found(dt, x, w, f, top, w_acc, car, extra)
    static = (car.sprung + car.unsprung) * car.gravity
    ground, air = bridge(ground, unloaded(tyre, static, dt), dt, edges=False)
    return ground - ground[0], tyre, air, extra, body, stops


def _found(dt, x, w, f, top, w_acc, car: QuarterCar, extra):
    """(ground m, tyre force N, the body's height m, the hard stop's force N) of :func:`ground_under`
    with the rider's slow load ``extra`` (N), the flights not yet bridged."""
    acc = np.where(top, -car.gravity - car.unsprung / (car.sprung + car.unsprung) * w_acc,
                   (f - extra) / car.sprung - car.gravity)
    vel = np.cumsum(acc) * dt
    # each bottom-out's impulse (the hard stop's) is not in the record: the body's speed changes
    # across it by what keeps the body's height level, by least squares, over the next
    # BOTTOM_OUT_WINDOW_S (a bike on its wheels does not rise or sink for seconds after a hit)
    stops = np.zeros(x.size)  # N at the wheel: the hard stop's force so found, spread over each bottom-out
    for start, end in runs(x >= car.travel - BOTTOM_OUT_MARGIN_M):
        k = min(int(end), x.size - 1)
        n = min(int(BOTTOM_OUT_WINDOW_S / dt), x.size - k)
        if n < 3:
            continue
        tau = np.arange(n) * dt
        body = np.cumsum(vel[k:k + n]) * dt
        kick = float(body @ tau / (tau @ tau))
        vel[k:] -= kick
        stops[start:k + 1] -= kick * car.sprung / ((k + 1 - start) * dt)
    vel = highpass(vel - vel.mean(), dt)
    body = np.cumsum(vel) * dt
    body = highpass(body - body.mean(), dt)
    wheel = body + w
    _, wheel_acc = _derivatives(wheel, dt)
    tyre = np.where(top, 0.0, car.unsprung * (wheel_acc + car.gravity) + f)
    deflection = np.minimum(np.maximum(tyre, 0.0) / car.tyre_rate, car.max_deflection)  # the rim stops it
    return wheel - car.radius + deflection, tyre, body, stops


def flights(off, dt: float):
    """(start, end) index pairs of the stretches of ``off`` (the tyre carrying nothing), those closer
    than ``JUMP_GAP_S`` merged: one flight where its force's noise touches zero again."""
    out = []
    for a, b in runs(off):
        if out and (a - out[-1][1]) * dt < JUMP_GAP_S:
            out[-1] = (out[-1][0], b)
        else:
            out.append((a, b))
    return out


def forward(t, ground, car: QuarterCar, stroke_of, ratio, w0: float, extra=None, native=None):
    """The wheel's rise (m) of the quarter car run over ``ground`` (m, on ``t``) from rest at rise
    ``w0``, its body pressed by ``extra`` (N, on ``t``; the rider's load shifts) where given: the
    law's stroke is ``stroke_of(w)``, its rate the wheel's over ``ratio(w)``; classical RK4 at the
    record's step (a step that diverges, on a hard stop stiffer than that step resolves, redone in
    10, 100 or 1000 substeps), the ground and the load linear between samples. ``native`` (mode,
    sin a, leverage) runs the same steps compiled (``mtbmj.ride.quartercar_compiled``) where it
    can; without it, or where it cannot, in Python."""
    dt = float(t[1] - t[0])
    gr = np.asarray(ground, float)
    load = np.zeros_like(gr) if extra is None else np.asarray(extra, float)
    k = car.tyre_rate
    stateful = bool(car.law.has_state)

    def rhs(y, g, push):
        zb, zw, vb, vw, zs = y
        w = zw - zb
        r = float(ratio(w))
        x, xd = float(stroke_of(w)), (vw - vb) / r
        f = _law_force(car.law, x, xd, zs) / r
        tyre = max(0.0, k * (g - (zw - car.radius)))
        return np.array([vb, vw, (f - push) / car.sprung - car.gravity, (tyre - f) / car.unsprung - car.gravity,
                         car.law.state_rate(xd, zs) if stateful else 0.0])

    f0 = _law_force(car.law, float(stroke_of(w0)), 0.0, 0.0) / float(ratio(w0))
    zw0 = car.radius - (car.unsprung * car.gravity + f0) / k + gr[0]
    y = np.array([zw0 - w0, zw0, 0.0, 0.0, 0.0])
    if native is not None:  # (mode, sin_a, leverage): the same steps compiled (mtbmj.ride.quartercar_compiled)
        from mtbmj.ride import quartercar_compiled

        done = quartercar_compiled.run(car.law, stateful, (car.sprung, car.unsprung, k, car.radius, car.gravity),
                                       native[0], native[1], native[2], gr, load, dt, y)
        if done is not None:
            out, bad = done
            if bad >= 0:
                raise ReconstructError(f"the forward quarter car diverged at {t[bad]:.3f} s")
            return out
    out = np.empty(gr.size)
    out[0] = w0
    def step(y, g0, g1, p0, p1, n):
        h = dt / n
        for j in range(n):
            a, b = j / n, (j + 1) / n
            ga, gb, gm = g0 + a * (g1 - g0), g0 + b * (g1 - g0), g0 + 0.5 * (a + b) * (g1 - g0)
            pa, pb, pm = p0 + a * (p1 - p0), p0 + b * (p1 - p0), p0 + 0.5 * (a + b) * (p1 - p0)
            k1 = rhs(y, ga, pa)
            k2 = rhs(y + 0.5 * h * k1, gm, pm)
            k3 = rhs(y + 0.5 * h * k2, gm, pm)
            k4 = rhs(y + h * k3, gb, pb)
            y = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return y

    for i in range(gr.size - 1):
        g0, g1, p0, p1 = gr[i], gr[i + 1], load[i], load[i + 1]
        # a step that leaves the finite numbers (a hard stop far stiffer than the record's step
        # resolves) is redone in 10, 100, 1000 substeps
        n, nxt = 1, None
        while n <= 1000:
            with np.errstate(all="ignore"):
                nxt = step(y, g0, g1, p0, p1, n)
            if np.all(np.isfinite(nxt)) and np.all(np.abs(nxt[:4] - y[:4]) < 1.0):
                break
            n *= 10
        y = nxt
        if not np.all(np.isfinite(y)):
            raise ReconstructError(f"the forward quarter car diverged at {t[i + 1]:.3f} s")
        out[i + 1] = y[1] - y[0]
    return out



def runs(mask):
    """(start, end) index pairs of the True runs of ``mask``."""
    m = np.concatenate(([False], mask, [False]))
    d = np.diff(m.astype(int))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))



__all__ = ["QuarterCar", "ground_under", "flights", "bridge", "edge", "unloaded", "law_along", "derivatives", "highpass", "hanging", "forward", "wheelbase_at", "lowpass", "runs",
           "within_stops"]

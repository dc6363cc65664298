"""A drop's level kept by the reconstruction (issue 51 item 2; ``reconstruct_bike.terrain_and_rear``
uses it).

The whole bike (``reconstruct_bike.ride``, its fork's stroke prescribed) holds its frame's front near
a slow reference, the quarter car's body with its drift removed below
``reconstruct_inverse.HIGHPASS_HZ``; that removal takes a drop's level with it, so the ground found
returned to the level above a drop within seconds. Here:

- **Which flights.** The flights of the whole bike's first pass that left at a drop's edge
  (``reconstruct_inverse.edge``: at least ``EDGE_FLIGHT_S`` long, landing more than ``EDGE_DROP_M``
  lower, the ground not rising into the take-off: a wheel thrown off a kicker's lip or a rock's face
  is not read, its level left as it was; the rise judged on the ground less what the drift's removal
  lifts ahead of the flight's own fall, ``edge_flights``).
- **The level change read** across each, in every pass: the ground found where the wheel is back on
  it less where it left (the whole bike falls across the flight under its own forces: the fork's
  from the record, the rear wheel still on top until it too leaves the edge, gravity).
- **The guard** (what the flight's duration allows): a front wheel that leaves an edge level falls
  at most ``pivot_acceleration`` (the frame pitching about its rear axle under its own weight and
  the rider's preloads, his inertia left out: the fastest its front falls unless he pushes it down
  harder than he rests on it, or it leaves the edge already falling) for the flight's
  duration T, plus what the fork extends in the air: a drop read deeper than
  ``1/2 a T^2 + (rise at take-off - rise at landing)`` is not kept (the flight is left, the level
  as it was), and neither is one that reads no drop.
- **Kept in the reference**: the quarter car's body less its own response to the level change it
  fell from the take-off to the fork's deepest point after the landing (the body stops falling
  there; ``response``: what the drift's removal makes of a level change over the flight), plus the
  level change read, ramped across the flight. The next pass reads the flights again over the
  reference so made, until the levels settle (``LEVEL_SETTLED_M``).
- **A hard landing's stop** (``stop_kicks``): the fork's hard-stop impulse across each bottom-out,
  from the quarter car's, found again pass by pass as what keeps the whole bike's ground level after
  the hit, never pulling; a hit the wheel leaves for a flight covering more than half of that window
  (``SEEN_SHARE``: a rock's face that throws it) keeps the quarter car's.
- **The speed found again** leaves out each kept drop's landing with the rear's flight (``landed``).
"""
from __future__ import annotations

import math

import numpy as np

DEEPEST_S = 0.3  # the fork's deepest point after a landing (where the body stops falling) looked for within this
LEVEL_SETTLED_M = 2e-3  # the passes go on until no level change read moves more than this from one pass to the next
SEEN_SHARE = 0.5  # a hard stop's impulse is read from the ground seen after the hit: at least this share of its window
LANDED_S = 0.1  # a kept drop's landing: its compression (to its deepest point, 0.08 s on the made 0.5 m drop)


def pivot_acceleration(b) -> float:
    """The largest downward acceleration (m/s^2) of the frame's front axle point from rest with the
    front unsupported and the rear wheel on top (``b`` a ``reconstruct_bike.WholeBike``): the frame
    body and the front's unsprung mass pitching about the rear axle under their weight and the
    rider's limbs' preloads, the rider's own inertia left out (with it the front falls slower: 1.23 g
    where this gives 2.28 g on the tests' bike)."""
    wb = b.xF - b.xR
    moment = b.g * (b.M * (b.cx - b.xR) + b.mF * wb) + b.P_leg * (b.leg_x - b.xR) + b.P_arm * (b.arm_x - b.xR)
    inertia = b.I + b.M * (b.cx - b.xR) ** 2 + b.mF * wb ** 2
    return moment / inertia * wb


def edge_flights(found, air, dt: float) -> list:
    """(start, end) index pairs of the flights of ``air`` that left the ground ``found`` at a drop's
    edge (``reconstruct_inverse.edge``), each judged for a throw into its take-off on ``found`` less
    the drift's removal's :func:`response` to the flight's own level change: that removal, forward and
    back, lifts the ground found ahead of a fall (on the made 1.5 m drop at 6 m/s by 0.073 m over the
    0.1 s before the take-off, a kicker's lip's 0.088; 1.0 m: 0.051), which read as a throw left every
    drop of 1 m or more out."""
    from mtbmj.ride.reconstruct_inverse import edge, flights

    found = np.asarray(found, float)

    def approach(a0: int, b0: int) -> np.ndarray:  # asked by edge only of a flight long and falling enough
        return found - float(found[b0] - found[a0]) * response(found.size, a0, b0, dt)

    return [(int(a), int(b)) for a, b in flights(air, dt) if edge(found, a, b, dt, approach)]


def read(found, air, rise, chosen, dt: float, most: float) -> tuple[list, list]:
    """(kept, left): for each flight (start, end) of ``chosen``, stretched over the flights of this
    pass's ``air`` that overlap it, the level change across it on the ground ``found`` (m: where the
    wheel is back on it less where it left) and what its duration allows (``most`` m/s^2 for its
    duration, plus the front wheel's rise in the frame ``rise`` at take-off less at landing);
    (start, end, change, allowed), kept where the change is a drop no deeper than allowed."""
    from mtbmj.ride.reconstruct_inverse import flights

    now = flights(air, dt)
    kept, left = [], []
    n = len(found)
    for a, b in chosen:
        over = [(c, d) for c, d in now if c < b and d > a]
        a, b = min([a] + [c for c, _ in over]), max([b] + [d for _, d in over])
        a0, b0 = max(a - 1, 0), min(b, n - 1)
        T = (b0 - a0) * dt
        change = float(found[b0] - found[a0])
        allowed = 0.5 * most * T * T + max(float(rise[a0] - rise[b0]), 0.0)
        (kept if -allowed <= change < 0.0 else left).append((a, b, change, allowed))
    return kept, left


def response(n: int, a0: int, b0: int, dt: float) -> np.ndarray:
    """What the quarter car's drift removal (``reconstruct_inverse.ground_under``: the body's speed
    high-passed, integrated, high-passed again) makes of a body that rises 1 m, evenly, from sample
    ``a0`` to ``b0`` (``n`` samples of step ``dt``)."""
    from mtbmj.ride.reconstruct_inverse import highpass

    v = np.zeros(n)
    v[a0:b0] = 1.0 / (max(b0 - a0, 1) * dt)
    v = highpass(v - v.mean(), dt)
    body = np.cumsum(v) * dt
    return highpass(body - body.mean(), dt)


def reference(body, rise, kept, dt: float) -> np.ndarray:
    """The whole bike's slow reference with the level changes ``kept`` (``read``'s): ``body`` (the
    quarter car's, its drift removed) less its own response to what it fell from each take-off to the
    fork's deepest point (``rise`` the front wheel's in the frame) within ``DEEPEST_S`` after the
    landing, plus the level change read, ramped across the flight."""
    body = np.asarray(body, float)
    out = body.copy()
    n = body.size
    for a, b, change, _ in kept:
        a0, b0 = max(a - 1, 0), min(b, n - 1)
        k = b0 + int(np.argmax(rise[b0:b0 + max(int(round(DEEPEST_S / dt)), 1)]))
        ramp = np.ones(n)
        ramp[:a0] = 0.0
        ramp[a0:b0] = (np.arange(a0, b0) - a0) / max(b0 - a0, 1)
        out += (change - (body[k] - body[a0])) * ramp + (body[k] - body[a0]) * (ramp - response(n, a0, b0, dt))
    return out


def settled(before: list, now: list) -> bool:
    """Whether no level change of ``now`` moved more than ``LEVEL_SETTLED_M`` from ``before``'s (the
    same flights, the same order)."""
    return len(before) == len(now) and all(abs(p[2] - q[2]) <= LEVEL_SETTLED_M for p, q in zip(before, now))


def landed(levels) -> list:
    """(start s, end s) of each kept drop's flight (``described``'s rows) and ``LANDED_S`` of its
    landing, which the speed found again leaves out with the flights (``reconstruct_speed.refine``'s
    ``flights``): the rear predicted lands off a drop whose level is kept a few hundredths of a second
    late (the whole bike's pitch in the air), and with its landing's compression in, the made whole-bike
    ride's window over its 0.5 m drop read 5.0 % off (1.6 % with it out)."""
    return [(r["start_s"], r["end_s"] + LANDED_S) for r in levels or [] if r["kept"]]


def stop_kicks(first, now, ground, air, dt: float, front_mass: float) -> np.ndarray:
    """The fork's hard-stop force (N at the wheel) across each bottom-out of ``first`` (the quarter car's,
    ``reconstruct_inverse.ground_under``) found again for the whole bike: ``now`` (the pass before's)
    changed by what keeps the ``ground`` the whole bike found level after the hit (its slope there by
    least squares, times ``front_mass``, kg: the frame's front's share), never pulling (a stop pushes).
    The slope is read over ``reconstruct_inverse.BOTTOM_OUT_WINDOW_S`` after the hit; a hit after which
    the wheel is on the ground less than ``SEEN_SHARE`` of that window (``air``: the pass's flights,
    whose chords are not ground seen; a rock's face that throws the wheel into a long flight) keeps
    ``now``. Read over the chord, level with the rock's top, the carried bike's made
    ride's 0.24 m rock got 64 N s (the quarter car's 1.4) and became a ledge 0.25 m high and 4 m long
    that looped the recorded setting out. The quarter car's impulse stops its own body, which fell
    freely through a flight where the whole bike's frame is held near its reference: given to the
    whole bike, the one it found after 00100.SST's 0.5 s flight (316 N s) threw the frame up a 3.1 m
    hill (0.87 m without it; levelled, the whole bike asks for -157 N s there, a stop that pulls:
    none)."""
    from mtbmj.ride.reconstruct_inverse import BOTTOM_OUT_WINDOW_S, runs

    out = np.array(now, float)
    air = np.asarray(air, bool)
    for a, k in runs(np.asarray(first) != 0.0):
        n = min(int(BOTTOM_OUT_WINDOW_S / dt), out.size - k)
        seen = ~air[k:k + n]
        if seen.sum() < max(3.0, SEEN_SHARE * n):
            continue
        tau = np.arange(n) * dt
        slope = float((ground[k:k + n] - ground[k]) @ tau / (tau @ tau))
        impulse = max(float(out[a:k].sum() * dt) - slope * front_mass, 0.0)
        out[a:k] = impulse / ((k - a) * dt)
    return out


def described(t, kept, left) -> list:
    """Each flight read as ``reconstruction.json`` lists it: {"start_s", "end_s", "level_change_m",
    "allowed_m", "kept"}, by time."""
    rows = [{"start_s": float(t[a]), "end_s": float(t[min(b, len(t) - 1)]), "level_change_m": round(float(change), 4),
             "allowed_m": round(float(allowed), 4) if math.isfinite(allowed) else None, "kept": k}
            for k, group in ((True, kept), (False, left)) for a, b, change, allowed in group]
    return sorted(rows, key=lambda r: r["start_s"])


__all__ = ["DEEPEST_S", "LEVEL_SETTLED_M", "SEEN_SHARE", "LANDED_S", "landed", "stop_kicks", "pivot_acceleration", "edge_flights", "read",
           "response", "reference",
           "settled", "described"]

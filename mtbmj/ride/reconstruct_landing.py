"""A flight's fall bounded by how fast the bike landed (issue 51 items 2 and 4; ``reconstruct.reconstruct``
uses it for the terrain it writes for riding, never for the ground the check predicts the rear from).

**Which flights.** A flight of the front (``Reconstruction.jumps``: its tyre's force found near zero)
during which the rear's record also hangs within ``HANG_MM`` of full extension for at least
``BOTH_S``: both ends in the air together, the bike and its rider thrown free; not one whose rear hangs
from the record's first sample or either end to its last (no take-off or no landing in the record).

**The bound.** Both wheels cross the same level change (the lip's level to the landing's). While both
ends are in the air each axle falls with the frame at g less the pitch's pull toward the centre of
mass (omega^2 H, H the bike's centre of mass above its axles), and before (the front pivoting about a
rear still on the lip) faster than g; from a take-off rising, level or falling, an axle that reaches
its landing at vertical speed V has fallen at most V^2 / (2 a), a the least of those accelerations, plus
what its suspension extended after the tyre left (its travel at the take-off). V is read from the
record of **the end that lands first** (the rear only where it touched down past the front's take-off: a rear
taking load back on the lip, hanging unweighted there, never fell; the fork's then): its wheel stops on the ground within the tyre's few
millimetres, so its travel's speed just after the touchdown (the largest over ``READ_S``; the fork's
along its axis times the sine of the head angle, the rear's wheel travel vertical as recorded) is the
frame's falling speed at that axle (read low: the uncertainty), and nothing but gravity and the rider has acted on it since the
take-off. The other end's speed is read the same way after its own touchdown, later: the first end's
landing has pitched the frame by then (on 00100.SST the rear landed first at 3.7 m/s, the fork 24 ms
later at 4.9; off the tests' made drops the fork first at 3.7 and 4.6, the rear after it at 0.3), so it
is not the bound's, only its uncertainty's. On a landing sloping down (the ground found
over ``SLOPE_M`` past the first end's touchdown, under that end) the wheel meets the slope at V less the
speed times the slope: that is added back to V.

**The uncertainty** (``uncertainty_m``: the bound at the upper ends of both, less the bound). (a) The
reading: the travel's fastest after a touchdown is slower than the frame was at the touchdown, which its
suspension decelerates while the tyre stops the wheel; on the independent whole bike of the tests off a
1.0 and a 1.5 m drop (``tests/test_reconstruct_landing.py``) the fork's reading was 0.83 of the frame's
speed at the front axle both times (3.68 for 4.42 m/s, 4.59 for 5.56), so V / ``READ_SHARE`` is its upper
end (0.8: a version-2 record's 100 Hz low-pass smooths the rise further, not measured). (b) The pitch:
the pitch rate at the landing moves one end's speed against the other's; the largest the two readings
allow, omega = |V_fork - V_rear| / wheelbase, lowers the axle's acceleration by omega^2 H.

**The duration** (issue 51 item 4: flight51). The same axle, landing at V after T in free flight, has fallen
at most V T - a T^2/2 (a the least downward acceleration at every moment: g less omega^2 H as above, and
never less than g/2 in the code, ``a_least``; omega read from the two ends' later readings), which is at most V^2/(2a)
and rises with T up to T = V/a: so with the reading's upper end (V / ``READ_SHARE``), the least acceleration
and the longest T the record allows, the fall is at most that, and V^2/(2a) past V/a (``in_air``); no
take-off speed is needed. The longest T: the first end's tyre left after its travel last compressed (a tyre
off the ground cannot load it; a rise of more than ``EXTEND_TOL_M`` counts) and no later than the hang began
(``_left``); its hang alone starts late, since the suspension goes on extending after the tyre left (a take-off
at 50 mm extending over 80 ms in the air: counted from the hang the bound would cut the real fall, in the
tests). Each sample of that window is a take-off it may have made: the ground under that end there less
under its touchdown (its own fall, the tyre's unloaded radius the same at both ends) against what that time
allows plus the travel it could still extend; the records rule a fall out only where every take-off in the
window does, and the ground is raised by the least such excess where it is more than the speed's. On
00100.SST's pit (115.9 m) the rear's window is 15.300-15.404 s: T 0.434 s allows 1.22 m for its own fall of
1.23 (the hang alone, 0.33 s, would allow 1.03), so the speed's 0.033 m stays the cut.

**Cut.** Where the fall found across the front's flight (the ground where the front lands less where it
left: ``reconstruct_flight.read``'s level change) exceeds the bound plus its uncertainty, the ground
from that landing on is raised by the excess (the fall cut to the bound plus its uncertainty; by the
duration's excess where that is the larger), its shape kept; across the flight each sample is raised by the share of the fall it lies below the take-off, so a
drop's face stays where it was found, only shallower. ``reconstruction.json`` lists each flight judged
(``landings``: with ``left_s`` the window the first end left in, ``in_air_s`` its longest time in the air,
``own_fall_m`` and ``duration_bound_m`` at the take-off that allows most, ``smaller`` which allowance is the
smaller, ``cut_by`` which set the cut), one ``ConfigWarning`` says where a fall was cut (:func:`warn`), and the line says how many.
Assumed: the bike and its rider free in the air (a rider who pulls the bike up under him lands it slower
than its fall gives: the bound then cuts a real drop; one who pushes it down and is still pushing at the
touchdown lands it faster, which both bounds allow; one who pushed it away early and holds it there has
lowered the frame by his share of the mass (0.72 on ``sst``) times his limbs' stroke without landing it
faster, which neither bound allows: about 0.2 m for a 0.3 m stroke, not in the uncertainty), both wheels
across the same level change (the ground's roughness over a wheelbase is not in
the uncertainty), the rear's wheel travel vertical.
"""
from __future__ import annotations

import numpy as np

HANG_MM = 5.0  # an end within this of full extension hangs (in the air or unweighted)
BOTH_S = 0.1  # both ends hang together at least this long: a flight of the whole bike (the front's shortest flight)
READ_S = 0.03  # an end's landing speed: its travel's fastest within this after its touchdown
SLOPE_M = 0.5  # the landing's slope read over this much ground past the first end's touchdown
READ_SHARE = 0.8  # the travel's fastest after a touchdown reads at least this share of the frame's speed (0.83 measured)
EXTEND_TOL_M = 1e-3  # an end's travel compressed where it rose more than this to its most before the hang


def com_height(spec) -> float:
    """The bike and rider's centre of mass above the line of its axles (m, at full extension)."""
    from mtbmj.bike.model import centre_of_mass

    _, (_, cz) = centre_of_mass(spec)
    return float(cz - 0.5 * (spec.front_axle[1] + spec.rear_axle[1]))


def _touchdown(travel_m, k0: int, dt: float) -> tuple[int, float] | None:
    """(the first sample at or after ``k0`` where ``travel_m`` leaves its hang, the travel's largest
    speed m/s over ``READ_S`` from there); None where it hangs to the record's end (no landing: the
    rider off the bike at the end of 00642.SST and 00649.SST read a landing at 0 m/s there)."""
    up = np.flatnonzero(travel_m[k0:] > HANG_MM * 1e-3)
    if not up.size:
        return None
    k = k0 + int(up[0])
    n = max(int(round(READ_S / dt)), 2)
    part = travel_m[max(k - 1, 0):k + n + 1]
    return k, float(np.max(np.diff(part)) / dt) if part.size > 1 else 0.0


def _left(travel_m, k_down: int) -> tuple[int, int]:
    """(the sample the end's travel last stopped compressing before its hang, the first of the hang) for the
    hang ending at ``k_down``: the tyre left between them (compressing takes its load; in the air the
    suspension extends to its hang after the tyre left, so the hang alone starts late)."""
    k = k_down
    while k > 0 and travel_m[k - 1] <= HANG_MM * 1e-3:
        k -= 1
    j = top = k
    while j > 0 and travel_m[j - 1] + EXTEND_TOL_M >= travel_m[top]:
        j -= 1
        top = j if travel_m[j] >= travel_m[top] else top
    return top, k


def in_air(v_max: float, a_min: float, t_s) -> np.ndarray:
    """The most an axle falls in ``t_s`` s of free flight landing at ``v_max`` m/s, its downward acceleration
    at least ``a_min``: v T - a T^2/2 up to T = v/a, v^2/(2a) past it (the take-off's speed unknown)."""
    t_s = np.minimum(np.asarray(t_s, float), v_max / a_min)
    return v_max * t_s - 0.5 * a_min * t_s * t_s


def judged(t, distance, ground, fork_mm, rear_mm, jumps, speed, wheelbase: float, sin_a: float, height: float,
           g: float = 9.81) -> tuple[np.ndarray, list]:
    """(the ground to ride, m on ``t``; each flight of both ends judged, as ``reconstruction.json`` lists
    it): ``ground`` (the ground found, m) with each fall deeper than its landing allows cut (module doc).
    ``fork_mm`` the fork's stroke, ``rear_mm`` the rear wheel's travel (records), ``jumps`` the front's
    flights ((start s, end s)), ``speed`` m/s on ``t``, ``sin_a`` the head angle's sine, ``height`` the
    centre of mass above the axles (:func:`com_height`)."""
    from mtbmj.ride.reconstruct_inverse import runs

    t, x, z = np.asarray(t, float), np.asarray(distance, float), np.asarray(ground, float)
    dt = float(t[1] - t[0])
    fork, rear = np.asarray(fork_mm, float) * 1e-3 * sin_a, np.asarray(rear_mm, float) * 1e-3
    hang = rear <= HANG_MM * 1e-3
    ridden, rows = z.copy(), []
    for a_s, b_s in jumps or []:
        a, b = int(np.searchsorted(t, a_s)), min(int(np.searchsorted(t, b_s)), t.size - 1)
        both = [(p + a, q + a) for p, q in runs(hang[a:b])]
        if not both:
            continue
        p, q = max(both, key=lambda pq: pq[1] - pq[0])
        if (q - p) * dt < BOTH_S:
            continue
        down_rear, down_fork = _touchdown(rear, q, dt), _touchdown(fork, b, dt)
        if hang[:p + 1].all() or down_rear is None or down_fork is None:
            continue  # hanging from the record's start (the rider getting on) or to its end: no flight read whole
        (kr, v_rear), (kf, v_fork) = down_rear, down_fork
        # the rear's reading bounds the fall only where it touched down past the front's take-off (it crossed the
        # edge); one taking load back on the lip (hanging unweighted, not flying) did not fall it: the fork's then
        crossed = x[kr] - wheelbase > x[max(a - 1, 0)]
        first, k, v, extended = (("rear", kr, v_rear, rear[max(p - 1, 0)]) if kr <= kf and crossed else
                                 ("fork", kf, v_fork, fork[max(a - 1, 0)]))
        place = x[k] - (wheelbase if first == "rear" else 0.0)
        down = (np.interp(place, x, z) - np.interp(place + SLOPE_M, x, z)) / SLOPE_M
        v_down = max(v, 0.0) + max(float(down), 0.0) * float(speed[k])
        omega = abs(v_fork - v_rear) / wheelbase
        a_least = max(g - omega * omega * height, 0.5 * g)
        bound = v_down * v_down / (2.0 * g) + max(float(extended), 0.0)
        spread = (v_down / READ_SHARE) ** 2 / (2.0 * a_least) - v_down * v_down / (2.0 * g)
        # the duration: the first end's tyre left between its travel's last compression and its hang (_left)
        # (each sample it may have left at: the ground under that end there less under its touchdown, against
        # what that time in the air allows); the records rule out the fall only where every such take-off does
        own_travel = rear if first == "rear" else fork
        j, h = _left(own_travel, k)
        ks = np.arange(j, h + 1)
        travel = own_travel[ks]
        timed = in_air(v_down / READ_SHARE, a_least, (k - ks) * dt) + travel
        under = x[ks] - (x[k] - place)  # that end's place at each sample (the rear a wheelbase behind the front)
        own = np.interp(under, x, z) - np.interp(place, x, z)
        i = int(np.argmin(own - timed))
        a0, b0 = max(a - 1, 0), b
        fall = float(z[a0] - z[b0])
        by_speed, by_time = fall - (bound + spread), float(own[i] - timed[i])
        # the cut lowers the front's fall only: never below its take-off's level (the duration reads the first end's
        # own fall, over other ground, which can exceed it), nothing where the front found no fall at all
        excess = min(max(by_speed, by_time), max(fall, 0.0))
        if excess > 0.0:
            share = np.clip((z[a0] - z[a0:b0 + 1]) / fall, 0.0, 1.0)
            ridden[a0:b0 + 1] += excess * share
            ridden[b0 + 1:] += excess
        rows.append({"start_s": float(t[a0]), "end_s": float(t[b0]), "both_in_air_s": [float(t[p]), float(t[q])],
                     "at_m": round(float(x[b0]), 2), "first_down": first,
                     "landing_speed_m_per_s": round(v_down, 3), "fork_speed_m_per_s": round(v_fork, 3),
                     "rear_speed_m_per_s": round(v_rear, 3), "pitch_rate_rad_per_s": round(omega, 3),
                     "fall_m": round(fall, 4), "bound_m": round(bound, 4), "uncertainty_m": round(spread, 4),
                     "left_s": [float(t[j]), float(t[h])], "in_air_s": round(float((k - j) * dt), 4),
                     "own_fall_m": round(float(own[i]), 4), "duration_bound_m": round(float(timed[i]), 4),
                     "smaller": "duration" if timed[i] < bound + spread else "speed",
                     "cut_by": "duration" if by_time > max(by_speed, 0.0) else "speed" if by_speed > 0.0 else None,
                     "raised_m": round(max(excess, 0.0), 4)})
    return ridden, rows


def words(rows) -> str:
    """The line's clause: how many falls were cut to what their landing allows."""
    cut = [r for r in rows or [] if r["raised_m"] > 0.0]
    return (f", {len(cut)} fall(s) in the terrain to ride cut to what the landing's speed or time in the air allows"
            if cut else "")


def warn(ride: str, rows) -> None:
    """One ``ConfigWarning`` naming each fall cut in the terrain to ride (not in the check's ground)."""
    import warnings

    from mtbmj.errors import ConfigWarning

    cut = [r for r in rows or [] if r["raised_m"] > 0.0]
    if cut:
        where = ", ".join(f"{r['at_m']:.0f} m ({r['start_s']:.2f}-{r['end_s']:.2f} s: {r['fall_m']:.2f} m down, the "
                          f"{r['first_down']} landing first at {r['landing_speed_m_per_s']:.1f} m/s allows "
                          f"{r['bound_m']:.2f}, {r['bound_m'] + r['uncertainty_m']:.2f} with its uncertainty"
                          + (f"; its own fall {r['own_fall_m']:.2f} m in at most {r['in_air_s']:.2f} s in the air "
                             f"allows {r['duration_bound_m']:.2f}" if r.get("cut_by") == "duration" else "") + ")"
                          for r in cut)
        warnings.warn(f"{ride}: a fall found deeper than the bike's landing speed allows (V^2/2g or its time in the "
                      f"air, both ends in the air) at {where}: the terrain to ride raised from there by the excess (terrain.csv; the "
                      f"check's ground keeps the fork's)", ConfigWarning, stacklevel=2)


def attach(result, t, wheelbase: float, sin_a: float, spec, g: float, ride: str) -> None:
    """``result`` (a ``Reconstruction``) given its ground to ride and its landings judged (:func:`judged` on its
    own ground, records and speed), the landings' line said (:func:`warn`); the check's ground untouched."""
    result.ridden, result.landings = judged(t, result.distance, result.ground, result.front, result.rear, result.jumps,
                                            result.speed["speed_at"](t), wheelbase, sin_a, com_height(spec), g)
    warn(ride, result.landings)


__all__ = ["HANG_MM", "BOTH_S", "READ_S", "SLOPE_M", "READ_SHARE", "EXTEND_TOL_M", "attach", "com_height", "in_air", "judged",
           "words", "warn"]

"""The summary of a simulated drop (what ``DropResult.summary`` holds): its events (found by
``events.detect``, the detector that reads sled records too), lift-off and landing from the tire
force, rest, the end of travel and the energy balance."""
from __future__ import annotations

import numpy as np

from mtbmj.compose import Setup
from mtbmj.drop.events import REST_TOLERANCE_MM, REST_WINDOW_S, detect
from mtbmj.readout.endtravel import end_of_travel
from mtbmj.trace import RawTrace

# the rest window and tolerance are the detector's (REST_WINDOW_S, REST_TOLERANCE_MM): a simulated
# run is at rest when its sled moves less than that in the last REST_WINDOW_S
MIN_CONTACT_LOSS_S = 0.002  # shorter losses of the tire force are not a lift-off (the detector, on a
# smoothed and noisy record, asks for events.MIN_AIRTIME_S)


def _contact_changes(t, tire_force):
    """Lift-off and landing times from the tire force (not geometric overlap)."""
    contact = tire_force > 0.0
    start = int(np.argmax(contact)) if contact.any() else None
    if start is None:
        return None, None
    loss = np.flatnonzero(~contact[start:]) + start
    for i in loss:
        back = np.flatnonzero(contact[i:])
        duration = (t[i + back[0]] - t[i]) if back.size else t[-1] - t[i]
        if duration >= MIN_CONTACT_LOSS_S:
            landing = i + back[0] if back.size else None
            return i, landing
    return None, None


def energy(setup: Setup, trace: RawTrace) -> dict[str, float]:
    """Energy balance (J) with the tread-touch position as the height datum: input kinetic energy
    at impact, mechanical energy left at the end, and their difference, the energy dissipated."""
    mb, mw, g = setup.body_mass, setup.wheel_mass, setup.gravity
    e_in = 0.5 * (mb + mw) * setup.impact_speed**2

    def mechanical(i):
        s, x, sd, xd = trace.sled[i], trace.fork[i], trace.sled_velocity[i], trace.fork_velocity[i]
        w, wd = s - x, sd - xd
        kinetic = 0.5 * mb * sd**2 + 0.5 * mw * wd**2
        gravity = -mb * g * s - mw * g * w
        tire = setup.tire.values(int(trace.tire_phase[i]))
        stored = setup.fork.elastic_energy(x) + (0.5 * tire.rate * w * w if w > 0 else 0.0)
        if setup.tire.rim is not None:
            stored += setup.tire.rim.energy(w)
        friction = setup.fork.friction
        if friction.has_state:
            stored += 0.5 * friction.stiffness * trace.friction_state[i] ** 2
        return kinetic + gravity + stored

    e_end = mechanical(len(trace.time) - 1)
    return {"input_J": float(e_in), "mechanical_end_J": float(e_end), "dissipated_J": float(e_in - e_end)}


def summarize(setup: Setup, trace: RawTrace, logged: dict[str, np.ndarray], raw: dict[str, np.ndarray]) -> dict:
    """JSON-ready summary. Events come from the logged (1 kHz) signals through
    ``events.detect`` (robust to noise; a missing event is None, never forced; the same detector
    that reads sled records), contact times from the raw tire force; a run that never lifts off or
    never settles says so."""
    lift_raw, land_raw = _contact_changes(raw["time_s"], raw["tire_force_N"])
    t = logged["time_s"]
    try:
        found = detect(logged)
        events = {name: {e: (ev.to_dict() if ev else None) for e, ev in per.items() if e != "rest"}
                  for name, per in found.signals.items()}
        flags = list(found.flags)
    except ValueError as exc:  # a run too short to hold any event
        events, flags = {}, [str(exc)]
    window = t >= t[-1] - REST_WINDOW_S
    rest = {name: float(np.mean(logged[f"{name}_mm"][window])) for name in ("sled", "fork", "tire")}
    motion = float(np.ptp(logged["sled_mm"][window]))
    return {
        "impact_speed_m_per_s": setup.impact_speed,
        "lift_off_s": None if lift_raw is None else float(raw["time_s"][lift_raw]),
        "landing_s": None if land_raw is None else float(raw["time_s"][land_raw]),
        "lifts_off": lift_raw is not None,
        "fork_tops_out": bool(np.any(raw["fork_mm"][np.searchsorted(raw["time_s"], 0.01, side="right"):] <= 0.0)),
        "events": events,
        "event_flags": flags,
        "rest_mm": rest,
        "rest_motion_mm": motion,
        "at_rest": motion < REST_TOLERANCE_MM,
        "max_fork_mm": float(np.max(raw["fork_mm"])),
        **end_of_travel(setup, raw["fork_mm"], raw["fork_velocity_mm_per_s"], raw["tire_mm"],
                        raw["tire_velocity_mm_per_s"]),
        "max_tire_mm": float(np.max(raw["tire_mm"])),
        "energy": energy(setup, trace),
    }

"""What a bike run reports (``BikeResult.raw`` and ``summary.json``), from the states and sensors of
its run (``mtbmj.bike.run``): the signals by column, the geometry a chart gives and the same at sag,
the feature's comfort and grip, the drive's work and a pedalling rider's cadence, power and bob, the
ends of travel and the rider metrics of telemetry. ``p`` is the run's ``mtbmj.bike.run.Prepared``."""
from __future__ import annotations

import math

import numpy as np

from mtbmj.bike import spec as spec_mod
from mtbmj.controllers.drive import CRANK_LENGTH_M
from mtbmj.readout.endtravel import end_of_travel

# The feature window's end: this long after the rear tyre has left the feature (the ride settles)
SETTLE_S = 0.5


def default_duration(p) -> float:
    """Both wheels from where the front axle starts across the rest of the terrain and ``SETTLE_S``
    more, so the summary's window over the feature (to ``SETTLE_S`` after the rear tyre left it)
    closes within the run (it ended before it at 5 m/s over every fixed feature when the settling
    was left out; a start before the terrain's was not counted, so from 5 m before a rock the rear
    never reached it); at least 1 s. ``p``: a ``mtbmj.bike.run.Prepared``."""
    wheelbase = p.spec.front_axle[0] - p.spec.rear_axle[0]
    ahead = p.terrain.start_x + p.terrain.length - (p.bike.x0 + p.spec.front_axle[0])  # from the front axle's start
    return max(1.0, (ahead + wheelbase) / p.speed + SETTLE_S)


def signals(p, states, sensors) -> dict:
    """A run's signals by column (``COLUMNS`` and more) from the states and sensors ``loop.chunked`` returned."""
    model = p.bike.model
    n = sensors.shape[0]
    nq, nv = model.nq, model.nv
    qpos = states[:n, 1:1 + nq]
    qvel = states[:n, 1 + nq:1 + nq + nv]
    sens = lambda name: sensors[:, model.sensor_adr[model.sensor(name).id]]
    b = p.bike
    # framelinacc carries MuJoCo's gravity offset (it reads +g at rest): the rider's own acceleration
    rider_acc = sensors[:, model.sensor_adr[model.sensor("rider_acceleration").id] + 2] - p.gravity
    phi = qpos[:, b.qpos_index("swingarm")]
    front = np.hypot(sens("front_tire_x"), sens("front_tire_z"))
    rear = np.hypot(sens("rear_tire_x"), sens("rear_tire_z"))
    th = qpos[:, b.qpos_index("pitch")]
    X = b.x0 + qpos[:, b.qpos_index("bike_x")]
    fx, fz = b.spec.front_axle
    qf = qpos[:, b.qpos_index("fork")]
    u = (-math.cos(b.spec.head_angle), math.sin(b.spec.head_angle))
    lx, lz = fx + qf * u[0], fz + qf * u[1]
    front_x = X + np.cos(th) * lx - np.sin(th) * lz
    rear_lx, rear_lz = spec_mod.rear_axle_in_frame(b.spec, phi)
    w = rear_lz - b.spec.rear_axle[1]  # the rear wheel's travel; the shock's stroke through the leverage curve
    stroke = b.spec.leverage.strokes(w)
    rear_x = X + np.cos(th) * rear_lx - np.sin(th) * rear_lz
    # the ground's tangential forces on both tyres (the drive at the rear, the brakes at both), forward positive
    drive = (np.hypot(sens("drive_x"), sens("drive_z")) * np.where(sens("drive_x") >= 0.0, 1.0, -1.0)
             + np.hypot(sens("front_ground_x"), sens("front_ground_z")) * np.where(sens("front_ground_x") >= 0.0, 1.0, -1.0))
    return {
        "time_s": states[:n, 0],
        "x_m": X,
        "speed_m_per_s": sensors[:, model.sensor_adr[model.sensor("com_velocity").id]],
        "front_travel_mm": qf * 1e3,
        "rear_travel_mm": w * 1e3,
        "stroke_mm": stroke * 1e3,
        "pitch_deg": np.degrees(th),
        "front_tire_N": front,
        "rear_tire_N": rear,
        "front_tire_mm": sens("front_deflection") * 1e3,
        # no rear tire (``rear_tire=False``): no deflection, so no rim strike (the CSV's marker for
        # no ground within 10 mm); the probe measured the rim's depth into the ground instead
        "rear_tire_mm": sens("rear_deflection") * 1e3 if p.rear_tire_on else np.full(n, -10.0),
        "rider_acc_z_m_per_s2": rider_acc,
        "fork_force_N": -sens("fork_force"),
        "shock_force_N": sens("shock_force"),
        "drive_force_N": drive,
        "terrain_front_mm": p.terrain.height(front_x) * 1e3,
        "terrain_rear_mm": p.terrain.height(rear_x) * 1e3,
        # the bottom bracket's height above the ground under it (the at_bb framepos sensor)
        "bb_height_mm": (sensors[:, model.sensor_adr[model.sensor("at_bb").id] + 2]
                         - p.terrain.height(sensors[:, model.sensor_adr[model.sensor("at_bb").id]])) * 1e3,
        "front_axle_x_m": front_x,
        "rear_axle_x_m": rear_x,
        "fork_velocity_mm_per_s": qvel[:, b.dof_index("fork")] * 1e3,
        "stroke_velocity_mm_per_s": np.gradient(stroke, states[:n, 0]) * 1e3 if n > 1 else np.zeros(n),
    }


def _variation(f) -> float | None:
    return float(f.std() / f.mean()) if f.size and f.mean() > 0 else None


def feature_span(terrain) -> tuple[float, float] | None:
    """(start, end) x (m) of the terrain's feature: where its profile leaves the lead-in's height
    and where it last differs from the run-out's; None on a flat profile."""
    x, z = np.asarray(terrain.x, float), np.asarray(terrain.z, float)
    off_in = np.flatnonzero(np.abs(z - z[0]) > 1e-9)
    off_out = np.flatnonzero(np.abs(z - z[-1]) > 1e-9)
    if not off_in.size:
        return None
    return float(x[max(off_in[0] - 1, 0)]), float(x[min(off_out[-1] + 1, x.size - 1)]) if off_out.size else float(x[-1])


def _feature_window(p, raw: dict, dt: float) -> dict:
    """Comfort and grip over the feature: from the front tyre reaching the feature (its axle a
    tyre radius before its start) to ``SETTLE_S`` after the rear tyre has left it (its axle a
    radius past its end), within the run; ``closed`` false where the run ended before that."""
    t = raw["time_s"]
    span = feature_span(p.terrain)
    r = p.front_tire.radius
    if span is None or not t.size:
        i0, i1, closed = 0, t.size, True
    else:
        reached = np.flatnonzero(raw["front_axle_x_m"] >= span[0] - r)
        i0 = int(reached[0]) if reached.size else t.size
        past = np.flatnonzero(raw["rear_axle_x_m"] >= span[1] + r)
        closed = bool(past.size and t[past[0]] + SETTLE_S <= t[-1] + 0.5 * dt)
        i1 = int(np.searchsorted(t, t[past[0]] + SETTLE_S - 0.5 * dt)) + 1 if past.size else t.size
        i1 = min(i1, t.size)
    if i0 >= i1:
        return {"window_s": None, "closed": False, "rider_acceleration_rms_m_per_s2": None,
                "tire_load_variation": {"front": None, "rear": None}}
    acc = raw["rider_acc_z_m_per_s2"][i0:i1]
    return {"window_s": [float(t[i0]), float(t[i1 - 1] + dt)], "closed": closed,
            "rider_acceleration_rms_m_per_s2": float(np.sqrt(np.mean(acc * acc))),
            "tire_load_variation": {end: _variation(raw[f"{end}_tire_N"][i0:i1]) for end in ("front", "rear")}}


def _trail(radius: float, head_angle: float, offset: float) -> float:
    """A front wheel's trail (m) on flat ground: from its contact patch forward to where the steering
    axis meets the ground, for a loaded radius, a head angle from the horizontal and the fork offset."""
    return (radius * math.cos(head_angle) - offset) / math.sin(head_angle)


def geometry(p, raw: dict) -> dict:
    """The geometry a chart gives (both wheels on flat ground at full extension, unloaded tyres)
    and the same at sag (the run's first sample: the bike at rest under its rider)."""
    spec, radius = p.spec, p.front_tire.radius
    beta = spec_mod.level_pitch(spec.front_axle, spec.rear_axle)
    (fx, fz), (rx, rz) = spec.front_axle, spec.rear_axle
    chart_head = spec.head_angle - beta
    chart = {"head_angle_deg": math.degrees(chart_head), "wheelbase_mm": math.hypot(fx - rx, fz - rz) * 1e3,
             "bb_height_mm": (radius - (rx * math.sin(beta) + rz * math.cos(beta))) * 1e3,
             "trail_mm": _trail(radius, chart_head, spec.fork_offset) * 1e3}
    head = spec.head_angle - math.radians(raw["pitch_deg"][0])
    loaded = radius - max(raw["front_tire_mm"][0], 0.0) * 1e-3
    sag = {"head_angle_deg": math.degrees(head),
           "wheelbase_mm": (raw["front_axle_x_m"][0] - raw["rear_axle_x_m"][0]) * 1e3,
           "bb_height_mm": float(raw["bb_height_mm"][0]), "trail_mm": _trail(loaded, head, spec.fork_offset) * 1e3}
    return {"chart": chart, "at_sag": sag}


def gear_speed(spec, cadence_rpm: float, radius: float) -> float:
    """The speed (m/s) the bike's chain gear gives at ``cadence_rpm`` on wheels of ``radius`` (m)."""
    ring, cog = spec.drive["chain_m"]
    return cadence_rpm * 2.0 * math.pi / 60.0 * ring / cog * radius


def crank_turns(p, x) -> np.ndarray:
    """A pedalling run's crank turns at the frame's positions ``x`` (m) from the first: the distance
    rolled through the gear, as ``controllers.drive.pedal_drive`` turns the crank."""
    ring, cog = p.spec.drive["chain_m"]
    x = np.asarray(x, float)
    return (x - x[0]) * cog / (ring * p.rear_tire.radius) / (2.0 * math.pi)


def _drive_summary(p, raw: dict) -> dict:
    """The drive's limits and work; for a pedalling rider also the cadence, the power asked and the
    mean power at the rear contact over the whole crank turns after the first second, and both
    ends' bob over the run's second half (``mtbmj.measured.bob.run_stretch``) when the run is long
    enough to read one."""
    dt = p.timestep
    speed = raw["speed_m_per_s"]
    out = {"mode": p.drive.mode, "push_limit_N": p.drive.push, "power_limit_W": p.drive.power,
           "brake_limit_N": p.drive.brake, "traction": p.traction,
           "work_J": float(np.sum(raw["drive_force_N"] * speed) * dt)}
    if p.drive.mode != "pedal":
        return out
    from mtbmj.measured import bob

    t = raw["time_s"]
    turns = crank_turns(p, raw["x_m"])
    pedal = {"cadence_rpm": p.drive.cadence * 60.0 / (2.0 * math.pi), "power_W": p.drive.power,
             "crank_length_mm": CRANK_LENGTH_M * 1e3,
             "gear": "{}x{}".format(*p.spec.drive["teeth"]),
             "mean_cadence_rpm": float(turns[-1] / (t[-1] + dt) * 60.0) if t[-1] > 0 else None}
    first, last = math.floor(float(np.interp(1.0, t, turns))) + 1, math.floor(float(turns[-1]))
    if last > first:  # whole turns from the first second on
        sel = (turns >= first) & (turns < last)
        pedal["rear_power_W"] = float(np.mean(raw["drive_force_N"][sel] * speed[sel]))
    for end in ("front", "rear"):
        try:
            pedal[f"{end}_bob"] = bob.bob(t, raw[f"{end}_travel_mm"], *bob.run_stretch(t)).to_dict()
        except bob.BobError as error:
            pedal[f"{end}_bob"] = {"unread": str(error)}
    out["pedal"] = pedal
    return out


def summary(p, raw: dict) -> dict:
    """A run's summary (``summary.json``): statics, travel, the ends of travel, tyre loads, the feature's
    comfort and grip, the drive, the rider metrics of telemetry and the crash."""
    dt = p.timestep
    t = raw["time_s"]
    acc = raw["rider_acc_z_m_per_s2"]
    front_end = end_of_travel(p.fork_setup, raw["front_travel_mm"], raw["fork_velocity_mm_per_s"], raw["front_tire_mm"],
                              time_s=t)
    rear_end = end_of_travel(p.shock_setup, raw["stroke_mm"], raw["stroke_velocity_mm_per_s"], raw["rear_tire_mm"],
                             time_s=t)
    loads = {}
    for name in ("front", "rear"):
        f = raw[f"{name}_tire_N"]
        loads[name] = {"mean_N": float(f.mean()), "max_N": float(f.max()), "min_N": float(f.min()),
                       "std_N": float(f.std()), "variation": float(f.std() / f.mean()) if f.mean() > 0 else None,
                       "off_ground_s": float(np.sum(f <= 0.0) * dt)}
    speed = raw["speed_m_per_s"]
    feature = _feature_window(p, raw, dt)
    from mtbmj.measured import metrics

    rear_velocity = np.gradient(raw["rear_travel_mm"], t) if t.size > 1 else np.zeros_like(t)
    ride = {"front": metrics.summarize(t, raw["front_travel_mm"], p.fork_setup.travel * 1e3,
                                       velocity_mm_per_s=raw["fork_velocity_mm_per_s"]),
            "rear": metrics.summarize(t, raw["rear_travel_mm"], p.spec.leverage.full_travel * 1e3,
                                      velocity_mm_per_s=rear_velocity)}
    return {
        "bike": p.spec.name,
        "scenario": p.terrain.describe(),
        # the rider's mass is the whole rider (rider.mass_kg); the bike's all the rest
        "mass_kg": {"rider": p.spec.rider.mass + p.spec.rider.on_bike_mass,
                    "bike": p.spec.total_mass - p.spec.rider.mass - p.spec.rider.on_bike_mass,
                    "total": p.spec.total_mass},
        "speed_m_per_s": p.speed,
        # the set speed along the terrain (mtbmj.bike.schedule): its range, None where one speed was held
        "speed_profile_m_per_s": None if getattr(p, "speed_profile", None) is None else
        [float(p.speed_profile.v.min()), float(p.speed_profile.v.max())],
        "start_m": float(p.bike.x0 + p.spec.front_axle[0]),  # the front axle's start along the terrain
        "duration_s": float(t[-1] + dt),
        "timestep_s": dt,
        "geometry": geometry(p, raw),
        "static_front_travel_mm": float(raw["front_travel_mm"][0]),
        "static_rear_travel_mm": float(raw["rear_travel_mm"][0]),
        "static_stroke_mm": float(raw["stroke_mm"][0]),
        "static_front_load_N": float(raw["front_tire_N"][0]),
        "static_rear_load_N": float(raw["rear_tire_N"][0]),
        "max_front_travel_mm": float(raw["front_travel_mm"].max()),
        "max_rear_travel_mm": float(raw["rear_travel_mm"].max()),
        "max_stroke_mm": float(raw["stroke_mm"].max()),
        "rear_wheel_travel_mm": p.spec.leverage.full_travel * 1e3,
        "pitch_deg": {"min": float(raw["pitch_deg"].min()), "max": float(raw["pitch_deg"].max())},
        "front": front_end,
        "rear": rear_end,
        "rim_strikes": {"front": front_end["rim_strikes"]["count"], "rear": rear_end["rim_strikes"]["count"]},
        "tire_load": loads,
        # comfort and grip over the terrain's feature (independent of how long the run goes on);
        # the whole run's beside them
        "feature": feature,
        "rider_acceleration_rms_m_per_s2": float(np.sqrt(np.mean(acc * acc))),
        "rider_acceleration_peak_m_per_s2": float(np.max(np.abs(acc))),
        "min_speed_m_per_s": float(speed.min()),
        "max_speed_m_per_s": float(speed.max()),
        "drive": _drive_summary(p, raw),
        # what riders read from telemetry (mtbmj.measured.metrics), each end in its own travel
        "ride_metrics": ride,
        # the run ended here (mtbmj.bike.crash): a part other than a tyre on the ground, or the pitch
        # past what a rider recovers from; the time series stop at it
        "crash": p.watch.crash.to_dict() if p.watch is not None and p.watch.crash is not None else None,
    }

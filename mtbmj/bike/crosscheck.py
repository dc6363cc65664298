"""``mtbmj crosscheck --bike PRESET --roll SCENARIO --speed V``: a bike run on MuJoCo against the
bike's own ODE reference (``mtbmj.bike.reference``) from the same initial state, sample by sample:
front and rear wheel travel within 0.1 mm, each tire's load within 1 % of the reference's peak
both at its peak and at every sample of the series (each sample with its own time stamp); the
shock's stroke and the pitch are reported beside them. The result is the cross-check of every
rig, ``mtbmj.runpath.crosscheck.CrosscheckResult``."""
from __future__ import annotations

from mtbmj.bike.reference import Reference
from mtbmj.bike.run import run_bike
from mtbmj.errors import ConfigError
from mtbmj.runpath.crosscheck import CrosscheckResult, compare_series

# column -> (signal, unit, judged at TOLERANCE_MM)
DISPLACEMENTS = {"front_travel_mm": ("front_travel", "mm", True), "rear_travel_mm": ("rear_travel", "mm", True),
                 "stroke_mm": ("shock_stroke", "mm", False), "pitch_deg": ("pitch", "deg", False)}
TIRES = {"front_tire_N": "front_tire_load", "rear_tire_N": "rear_tire_load"}
TOLERANCE_MM = 0.1
FORCE_TOLERANCE = 0.01
MAX_STEP_S = 1e-3


def crosscheck(bike, scenario, speed_m_per_s: float | None, duration: float | None = None, drive: str = "rider",
               start_x: float | None = None, reference_rtol: float = 1e-8, pedal=None, overrides=None,
               seated: bool = False, rider: str = "passive") -> CrosscheckResult:
    """``mtbmj bike``'s run against this reference from the same state: front and rear wheel
    travel (judged), shock stroke (mm) and pitch (deg), and both tire loads (N; peak and series
    judged relative to the reference's peak). ``reference_rtol``: the reference's relative
    tolerance (scipy's RK45). ``pedal`` (cadence_rpm, power_W), ``overrides`` and ``seated`` as
    ``run_bike``'s. ``rider`` "active": the articulated rider on both sides (the reference
    ``mtbmj.bike.reference_rider.ReferenceRider``)."""
    if rider == "active" and seated:
        raise ConfigError("rider: the reference with the active rider has no saddle (cross-check the active rider "
                          "standing)")
    engine = run_bike(bike, scenario, speed_m_per_s, duration=duration, drive=drive, start_x=start_x, pedal=pedal,
                      overrides=overrides, seated=seated, rider=rider)
    speed_m_per_s = engine.prepared.speed
    if pedal is not None:
        drive = f"pedal {pedal[0]:g} rpm {pedal[1]:g} W" + (" seated" if seated else "")
    if engine.prepared.articulated is not None:
        from mtbmj.bike.reference_rider import ReferenceRider

        ref = ReferenceRider(engine.prepared)
    else:
        ref = Reference(engine.prepared)
    raw = engine.raw
    times = raw["time_s"]
    y0 = ref.y0(engine.prepared.initial_qpos, engine.prepared.initial_qvel, engine.prepared.initial_act)
    got = ref.run(y0, times, MAX_STEP_S, rtol=reference_rtol)
    signals = [compare_series(name, unit, times, raw[column], got[column], TOLERANCE_MM if judged else None)
               for column, (name, unit, judged) in DISPLACEMENTS.items()]
    signals += [compare_series(name, "N", times, raw[column], got[column], FORCE_TOLERANCE, relative=True,
                               judged=("peak", "series")) for column, name in TIRES.items()]
    if engine.prepared.articulated is not None:
        drive += ", active rider"
    crash = engine.summary.get("crash")  # a crash ends the run: what follows it is compared nowhere, so the line says so
    ended = f"; {crash['line']}: the run ended there and is compared up to it" if crash else ""
    return CrosscheckResult("bike", f"{engine.name} over {scenario} at {float(speed_m_per_s):g} m/s (drive {drive}{ended})",
                            "mujoco", "bike's ODE reference", signals, engine.wall_time_s, got["wall_time_s"],
                            {"bike": engine.name, "scenario": str(scenario), "speed_m_per_s": float(speed_m_per_s),
                             "drive": drive, "reference_rtol": reference_rtol, "crash": crash,
                             # the engine's chunks stepped at the fine step (a stop or rim near)
                             "refined_fraction": engine.info["refined_fraction"]})


__all__ = ["crosscheck", "TOLERANCE_MM", "FORCE_TOLERANCE"]

"""``mtbmj crosscheck --bike PRESET --roll SCENARIO --speed V``: a bike run on MuJoCo against the
bike's own ODE reference (``mtbmj.bike.reference``) from the same initial state: front and rear
wheel travel within 0.1 mm, the tire-load peaks within 1 %, and the tire-load series within 1 % of
its peak at every sample (the series, not only its peaks: each sample with its own time stamp)."""
from __future__ import annotations

import numpy as np

from mtbmj.bike.reference import Reference
from mtbmj.bike.run import run_bike

DISPLACEMENTS = {"front_travel_mm": "front travel", "rear_travel_mm": "rear travel"}
TOLERANCE_MM = 0.1
FORCE_TOLERANCE = 0.01
MAX_STEP_S = 1e-3


class BikeCheck:
    def __init__(self, scenario, speed, name, differences, peaks, engine_wall_s, reference_wall_s,
                 refined_fraction=0.0, series=None):
        self.scenario, self.speed, self.name = scenario, speed, name
        self.refined_fraction = refined_fraction  # the engine's chunks stepped at the fine step (a stop or rim near)
        self.differences, self.peaks = differences, peaks
        self.series = series or {}  # tire -> the largest difference of the load series over the reference's peak
        self.engine_wall_s, self.reference_wall_s = engine_wall_s, reference_wall_s

    @property
    def passed(self) -> bool:
        return (all(self.differences[k]["max_abs_mm"] <= TOLERANCE_MM for k in DISPLACEMENTS)
                and all(p["relative"] <= FORCE_TOLERANCE for p in self.peaks.values())
                and all(q["relative_to_peak"] <= FORCE_TOLERANCE for q in self.series.values()))

    def line(self) -> str:
        d, p, q = self.differences, self.peaks, self.series
        series = (f", series front {100 * q['front_tire']['relative_to_peak']:.2f} %, rear "
                  f"{100 * q['rear_tire']['relative_to_peak']:.2f} % of the peak" if q else "")
        return (f"bike {self.name} over {self.scenario} at {self.speed:g} m/s: MuJoCo vs the bike's ODE reference, "
                f"max |diff| front travel {d['front_travel_mm']['max_abs_mm']:.4f} mm, rear travel "
                f"{d['rear_travel_mm']['max_abs_mm']:.4f} mm, shock {d['stroke_mm']['max_abs_mm']:.4f} mm, pitch "
                f"{d['pitch_deg']['max_abs']:.5f} deg; tire load peaks front {100 * p['front_tire']['relative']:.2f} %, "
                f"rear {100 * p['rear_tire']['relative']:.2f} %{series}; {'within' if self.passed else 'NOT within'} "
                f"{TOLERANCE_MM:g} mm and {100 * FORCE_TOLERANCE:g} % (engine {self.engine_wall_s:.1f} s, reference "
                f"{self.reference_wall_s:.1f} s)")

    def to_dict(self) -> dict:
        return {"scenario": self.scenario, "speed_m_per_s": self.speed, "bike": self.name,
                "differences": self.differences, "tire_load_peaks": self.peaks,
                "tire_load_series": self.series, "passed": self.passed,
                "tolerance_mm": TOLERANCE_MM, "force_tolerance": FORCE_TOLERANCE,
                "refined_fraction": self.refined_fraction}


def crosscheck(bike, scenario, speed_m_per_s: float, duration: float | None = None, drive: str = "rider",
               start_x: float | None = None, reference_rtol: float = 1e-8) -> BikeCheck:
    """``mtbmj bike``'s run against this reference from the same state: the largest differences of
    front and rear wheel travel and shock stroke (mm), pitch (deg), and of the tire-load peaks.
    ``reference_rtol``: the reference's relative tolerance (scipy's RK45)."""
    engine = run_bike(bike, scenario, speed_m_per_s, duration=duration, drive=drive, start_x=start_x)
    ref = Reference(engine.prepared)
    raw = engine.raw
    y0 = ref.y0(engine.prepared.initial_qpos, engine.prepared.initial_qvel, engine.prepared.initial_act)
    got = ref.run(y0, raw["time_s"], MAX_STEP_S, rtol=reference_rtol)
    differences = {}
    for column in ("front_travel_mm", "rear_travel_mm", "stroke_mm"):
        gap = np.abs(raw[column] - got[column])
        i = int(np.argmax(gap))
        differences[column] = {"max_abs_mm": float(gap[i]), "at_time_s": float(raw["time_s"][i])}
    gap = np.abs(raw["pitch_deg"] - got["pitch_deg"])
    differences["pitch_deg"] = {"max_abs": float(gap.max()), "at_time_s": float(raw["time_s"][int(np.argmax(gap))])}
    peaks = {}
    for name in ("front_tire", "rear_tire"):
        e, r = float(raw[name + "_N"].max()), float(got[name + "_N"].max())
        peaks[name] = {"engine_N": e, "reference_N": r, "relative": abs(e - r) / r if r > 0 else float(e != 0.0)}
    series = {}
    for name in ("front_tire", "rear_tire"):
        gap = np.abs(raw[name + "_N"] - got[name + "_N"])
        i = int(np.argmax(gap))
        r = float(np.max(got[name + "_N"]))
        series[name] = {"max_abs_N": float(gap[i]), "at_time_s": float(raw["time_s"][i]),
                        "relative_to_peak": float(gap[i]) / r if r > 0 else float(gap[i] != 0.0)}
    return BikeCheck(str(scenario), float(speed_m_per_s), engine.name, differences, peaks, engine.wall_time_s,
                     got["wall_time_s"], engine.info["refined_fraction"], series)


__all__ = ["crosscheck", "BikeCheck", "TOLERANCE_MM", "FORCE_TOLERANCE"]

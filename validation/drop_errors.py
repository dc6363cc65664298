"""Errors of a simulated drop against a measured one (or against the reference run).

Signs: error = simulated - measured. A positive amplitude error over-predicts the displacement at
that event (the paper's Fig. 10 convention); a positive timing error means the model's event comes
late. RMS errors compare the histories on the measurement's time grid (the simulation
interpolated onto it) over the whole common record and per phase, the phases taken from the
measurement: impact (touch to lift-off), air (lift-off to landing), settling (landing to the end).
A measurement that never lifts off has no air phase; its impact phase then ends at twice the time
of the sled's Peak 1 (compression and rebound of the first impact) and settling is the rest.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from mtbmj.drop.events import EVENTS, LABELS, SIGNALS, Events, detect

PHASES = ("all", "impact", "air", "settling")


@dataclass
class Metrics:
    """One configuration against the measurement."""

    name: str
    measured: Events
    simulated: Events
    events: dict   # signal -> event -> {measured_*, simulated_*, amplitude_error_mm, timing_error_s, status}
    rms_mm: dict   # signal -> phase -> RMS error (mm) or None
    phases: dict   # phase -> [start_s, end_s] or None
    group: str = "other"
    engine: str = "mujoco"
    measurement: str = "data"
    notes: list[str] = field(default_factory=list)

    def amplitude_errors(self) -> dict[str, dict[str, float | None]]:
        return {s: {e: self.events[s][e]["amplitude_error_mm"] for e in EVENTS} for s in SIGNALS}

    def timing_errors(self) -> dict[str, dict[str, float | None]]:
        return {s: {e: self.events[s][e]["timing_error_s"] for e in EVENTS} for s in SIGNALS}

    def worst_amplitude(self) -> tuple[str, str, float] | None:
        """(signal, event, error) of the largest |amplitude error|, or None when there is none."""
        pairs = [(s, e, v) for s, per in self.amplitude_errors().items() for e, v in per.items() if v is not None]
        return max(pairs, key=lambda p: abs(p[2])) if pairs else None

    def rows(self) -> list[dict]:
        """Long table: one row per signal and event, then one per signal and RMS phase."""
        rows = []
        base = {"config": self.name, "group": self.group, "engine": self.engine, "measurement": self.measurement}
        for s in SIGNALS:
            for e in EVENTS:
                d = self.events[s][e]
                rows.append({**base, "signal": s, "kind": "event", "name": e,
                             "measured_time_s": d["measured_time_s"], "measured_mm": d["measured_mm"],
                             "simulated_time_s": d["simulated_time_s"], "simulated_mm": d["simulated_mm"],
                             "amplitude_error_mm": d["amplitude_error_mm"], "timing_error_s": d["timing_error_s"],
                             "rms_error_mm": None, "phase_start_s": None, "phase_end_s": None, "status": d["status"]})
            for p in PHASES:
                span = self.phases.get(p)
                rows.append({**base, "signal": s, "kind": "rms", "name": p,
                             "measured_time_s": None, "measured_mm": None, "simulated_time_s": None,
                             "simulated_mm": None, "amplitude_error_mm": None, "timing_error_s": None,
                             "rms_error_mm": self.rms_mm[s][p],
                             "phase_start_s": span[0] if span else None, "phase_end_s": span[1] if span else None,
                             "status": "ok" if self.rms_mm[s][p] is not None else "no such phase"})
        return rows

    def to_dict(self) -> dict:
        return {
            "group": self.group, "engine": self.engine, "measurement": self.measurement,
            "simulated_flags": list(self.simulated.flags), "measured_flags": list(self.measured.flags),
            "lifts_off": self.simulated.lifts_off, "at_rest": self.simulated.at_rest,
            "amplitude_error_mm": self.amplitude_errors(), "timing_error_s": self.timing_errors(),
            "rms_error_mm": self.rms_mm, "phases_s": self.phases,
            "events": self.simulated.to_dict()["events"], "notes": list(self.notes),
        }


def phases(measured: Events) -> dict[str, list[float] | None]:
    end = measured.end_s
    if measured.lifts_off:
        air_end = measured.landing_s if measured.landing_s is not None else end
        return {"all": [0.0, end], "impact": [0.0, measured.lift_off_s], "air": [measured.lift_off_s, air_end],
                "settling": [air_end, end] if measured.landing_s is not None else None}
    peak1 = measured.get("sled", "peak1")
    impact_end = min(2.0 * peak1.time_s, end) if peak1 is not None else end
    return {"all": [0.0, end], "impact": [0.0, impact_end], "air": None,
            "settling": [impact_end, end] if impact_end < end else None}


def _status(m, s) -> str:
    if m is None and s is None:
        return "missing in both"
    if m is None:
        return "missing in measurement"
    if s is None:
        return "missing in simulation"
    return "ok"


def compare(measured: Mapping[str, np.ndarray], simulated: Mapping[str, np.ndarray], name: str = "model",
            measured_events: Events | None = None, simulated_events: Events | None = None,
            group: str = "other", engine: str = "mujoco", measurement: str = "data") -> Metrics:
    """Errors of ``simulated`` against ``measured`` (both: ``time_s``, ``sled_mm``, ``fork_mm``,
    ``tire_mm``, t = 0 at touch)."""
    me = measured_events or detect(measured)
    se = simulated_events or detect(simulated)
    events = {}
    for s in SIGNALS:
        events[s] = {}
        for e in EVENTS:
            m, x = me.get(s, e), se.get(s, e)
            both = m is not None and x is not None
            events[s][e] = {
                "measured_time_s": m.time_s if m else None, "measured_mm": m.value_mm if m else None,
                "simulated_time_s": x.time_s if x else None, "simulated_mm": x.value_mm if x else None,
                "amplitude_error_mm": (x.value_mm - m.value_mm) if both else None,
                "timing_error_s": (x.time_s - m.time_s) if both else None,
                "status": _status(m, x),
            }
    tm = np.asarray(measured["time_s"], float)
    ts = np.asarray(simulated["time_s"], float)
    end = min(me.end_s, float(ts[-1]))
    spans = phases(me)
    notes = []
    if end < me.end_s - 1e-9:
        notes.append(f"simulation ends at {end:.3f} s, before the measurement ({me.end_s:.3f} s): RMS up to {end:.3f} s")
    rms: dict[str, dict[str, float | None]] = {}
    for s in SIGNALS:
        rms[s] = {}
        ym = np.asarray(measured[f"{s}_mm"], float)
        ys = np.interp(tm, ts, np.asarray(simulated[f"{s}_mm"], float))
        for p in PHASES:
            span = spans[p]
            if span is None:
                rms[s][p] = None
                continue
            keep = (tm >= span[0] - 1e-12) & (tm <= min(span[1], end) + 1e-12)
            if p != "all" and span[1] < span[0]:
                keep[:] = False
            rms[s][p] = float(np.sqrt(np.mean((ys[keep] - ym[keep]) ** 2))) if keep.sum() >= 2 else None
    for side, ev in (("measurement", me), ("simulation", se)):
        if not ev.lifts_off:
            notes.append(f"{side} never lifts off: no topping event")
        if not ev.at_rest:
            notes.append(f"{side} never comes to rest within the record")
    return Metrics(name=name, measured=me, simulated=se, events=events, rms_mm=rms, phases=spans, group=group,
                   engine=engine, measurement=measurement, notes=notes)


__all__ = ["Metrics", "compare", "phases", "PHASES", "EVENTS", "LABELS", "SIGNALS"]

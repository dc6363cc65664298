"""The bike pedalled as recorded rides were (``mtbmj bob RECORD... --bike BIKE``): each record's
pedal bob (``mtbmj.measured.bob``) beside a run of the bike at that record's cadence, standing or
seated, through a climbing gear, up the climb the rider's power holds at the gear's speed; the
table (bob.json), the figure (bob.png) and a line per record."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.measured.bob import MIN_STRETCH_S, BobError, bob, high_passed, run_stretch

GEAR = (32, 42)  # assumed: a 1x climbing gear (the records do not say theirs)
RUN_S = 14.0


def check_run_s(value, label: str = "duration_s") -> float:
    """The simulated seconds of one record's run (``against``'s ``duration_s``, ``mtbmj bob --duration``): a
    positive finite number long enough for its second half, where the bob is read, to be a stretch
    (``MIN_STRETCH_S``); else one ConfigError line naming ``label``."""
    from mtbmj.errors import ConfigError
    from mtbmj.limits import check_duration

    check_duration(label, value)
    if value < 2.0 * MIN_STRETCH_S:
        raise ConfigError(f"{label}: {value:g} s is too short to read a bob over its second half "
                          f"({2.0 * MIN_STRETCH_S:g} s at least)")
    return float(value)


@dataclass
class Against:
    """Recorded pedalling rides and the bike pedalled as each was (``against``)."""

    bike: str
    rows: list  # one dict per record
    series: list  # per record: (record time, fork, rear), (run time, front, rear)

    def to_dict(self) -> dict:
        return {"bike": self.bike, "gear": "{}x{}".format(*GEAR), "records": self.rows}

    def lines(self) -> list[str]:
        out = []
        for r in self.rows:
            rec, sim = r["ride"]["rear"], r["simulated"]["rear"]
            out.append(f"{r['record']} ({r['stance']}): rear bob ridden {rec['frequency_Hz']:.2f} Hz "
                       f"{rec['amplitude_mm']:.1f} mm, simulated {sim['frequency_Hz']:.2f} Hz {sim['amplitude_mm']:.1f} mm "
                       f"({r['simulated_cadence_rpm']:.0f} rpm for the record's {r['cadence_rpm']:.0f}, "
                       f"{r['power_W']:g} W, {r['grade_percent']:.1f} % climb)")
        return out

    def figure(self):
        """Per record, the rear wheel's bob frequency and peak to peak, ridden and simulated (the
        bars span each amplitude's interquartile range over the strokes), and the first record's
        four seconds of bob."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=(12, 8), layout="constrained")
        ax = fig.subplots(2, 2)
        names = [f"{r['record']}\n{r['stance']}" for r in self.rows]
        k = np.arange(len(self.rows))
        for key, shift, color, label in (("ride", -0.18, "C1", "ridden"), ("simulated", 0.18, "C0", "simulated")):
            freq = [r[key]["rear"]["frequency_Hz"] for r in self.rows]
            amp = np.array([r[key]["rear"]["amplitude_mm"] for r in self.rows])
            iqr = np.array([r[key]["rear"]["amplitude_iqr_mm"] for r in self.rows])
            ax[0, 0].bar(k + shift, freq, width=0.34, color=color, label=label)
            ax[0, 1].bar(k + shift, amp, width=0.34, color=color, label=label,
                         yerr=np.abs(iqr.T - amp), capsize=3)
        ax[0, 0].set(xticks=k, xticklabels=names, ylabel="rear bob frequency (Hz)",
                     title="Rear bob frequency (twice the cadence)")
        ax[0, 1].set(xticks=k, xticklabels=names, ylabel="rear bob, peak to peak (mm)",
                     title="Rear bob amplitude (median stroke; bars: quartiles)")
        for a in ax[0]:
            a.legend(fontsize=8)
            a.grid(alpha=0.3, axis="y")
        for col, i in enumerate((0, len(self.rows) - 1)):
            (tr, _, xr), (ts, _, xs) = self.series[i]
            for (t, x), window, color, label in (((tr, xr), self.rows[i]["ride"]["rear"]["window_s"], "C1", "ridden"),
                                                 ((ts, xs), self.rows[i]["simulated"]["rear"]["window_s"], "C0",
                                                  "simulated")):
                tt, y = high_passed(t, x, window)
                show = tt <= 4.0
                ax[1, col].plot(tt[show], y[show], color=color, label=label)
            ax[1, col].set(xlabel="time in the pedalling stretch (s)", ylabel="rear travel, high-passed (mm)",
                           title=f"{self.rows[i]['record']} ({self.rows[i]['stance']}): four seconds", xlim=(0, 4))
            ax[1, col].legend(fontsize=8)
            ax[1, col].grid(alpha=0.3)
        rider = self.rows[0].get("rider", "passive") if self.rows else "passive"
        fig.suptitle(f"Pedal bob: bike {self.bike}, the {rider} rider, pedalled at each record's cadence ({'{}x{}'.format(*GEAR)}, "
                     f"the climb its power holds) beside the records (their amplitudes carry the records' "
                     f"calibration)", fontsize=9)
        return fig

    def write(self, out_dir) -> list:
        import json

        from mtbmj import output
        from mtbmj.readout import quicklook  # the one figure writer: a "$" in a name drawn as written

        return output.write_atomically(out_dir, {"bob.json": (json.dumps(self.to_dict(), indent=2) + "\n").encode(),
                                                 "bob.png": quicklook.png(self.figure(), dpi=100)})


CADENCE_TOLERANCE = 0.02  # the run's cadence over its stretch within 2 % of the record's, or the climb is set again
ATTEMPTS = 4  # at most this many runs per record (the closest kept)
# A record whose rear strokes' interquartile range spans more than this factor holds no steady pedalling
# (measured on the shared records: pedalling 1.6-2.5, trail rides 2.0-3.5, seat slams 5.6-18.6)
UNSTEADY = 4.0
# A record whose fork's strokes reach further than this share of its travel above its median (99th
# percentile less median over the stretch, so a deep sag is none) is moved by the terrain, not by pedal
# strokes (measured on the shared records, the SST preset's decoding: pedalling 00088-00091 7-14 %, the
# climbs 00096 and 00098 5-7 %, the descents 00092-00095, 00097, 00099-00101, 00642, 00643, 00649
# 27-36 %): a trail ride's strokes spread as a pedalling record's (2.0-3.5x), so the spread alone passes it
DESCENDING_FORK_PERCENT = 20.0


def run_cadence(run, window) -> float:
    """A pedalling run's mean cadence (rpm) over ``window`` (s): the crank's turns (the distance
    rolled through the gear) over the time."""
    from mtbmj.bike.summary import crank_turns

    t = run.raw["time_s"]
    keep = (t >= window[0]) & (t <= window[1])
    turns = crank_turns(run.prepared, run.raw["x_m"][keep])
    return float(turns[-1] / (t[keep][-1] - t[keep][0]) * 60.0)


def not_pedalling(ride, rear) -> str | None:
    """Why the record ``ride`` (a read SST record) is no steady pedalling, read from its rear's bob
    ``rear`` (``bob``): its strokes spread past ``UNSTEADY`` (a seat slam's ring-down), or its fork's
    reaching further than ``DESCENDING_FORK_PERCENT`` of its travel above its median over the same
    stretch (a descent: the terrain's strokes); None where neither holds."""
    low, high = rear.amplitude_iqr_mm
    if high > UNSTEADY * low:  # a seat slam's ring-down read as strokes: 8.5x (00083); pedalling 1.6-2.5x
        return (f"its rear strokes spread {low:.1f}-{high:.1f} mm (interquartile): no steady pedalling (a "
                f"pedalling record's spread within {UNSTEADY:g}x); a seat slam or a trail ride read as a bob?")
    if ride.fork_mm is None:
        return None
    keep = (ride.time_s >= rear.window_s[0]) & (ride.time_s <= rear.window_s[1])
    median, deep = (float(v) for v in np.percentile(ride.fork_mm[keep], [50.0, 99.0]))
    reach = 100.0 * (deep - median) / ride.fork_max_mm
    if reach <= DESCENDING_FORK_PERCENT:
        return None
    return (f"its fork strokes to {deep:.0f} mm from {median:.0f} mm ({reach:.0f} % of its {ride.fork_max_mm:g} mm "
            f"above its median, 99th percentile): the terrain moves it, no steady pedalling (a pedalling record's "
            f"within {DESCENDING_FORK_PERCENT:g} %); a trail ride read as a bob? its rear's {rear.frequency_Hz:.2f} Hz "
            f"is then no cadence")


def against(records, bike: str = "sst", stances=None, power_W: float = 250.0, overrides=None,
            duration_s: float = RUN_S, rider: str = "passive") -> Against:
    """Each record's bob (``bob``), and the bike pedalled as it was: at the cadence its rear bob
    implies (half its frequency), standing or seated (``stances``, one per record; default
    standing), through ``GEAR`` at ``power_W``, up the climb whose grade that power holds at the
    gear's speed (sin a = P / (m g v)), for ``duration_s``, its bob read over its second half. Where
    the run's own cadence over that half misses the record's by more than 2 % (the stroke's uneven
    torque and the bob change the power the climb takes), the climb is set again: a first step of
    its sine by the miss (at most 5 %), then secant steps, at most four runs, the closest kept."""
    import math
    import warnings

    from mtbmj.bike import spec as spec_mod
    from mtbmj.bike.run import run_bike, setups
    from mtbmj.bike.summary import gear_speed
    from mtbmj.errors import ConfigError
    from mtbmj.measured import telemetry

    duration_s = check_run_s(duration_s)  # the rule of bob's --duration too
    stances = list(stances or ["standing"] * len(records))
    if len(stances) != len(records):
        raise ConfigError(f"stance: one per record ({len(records)}), got {len(stances)}")
    bad = [s for s in stances if s not in ("standing", "seated")]
    if bad:
        raise ConfigError(f"stance: {bad[0]!r} is not standing or seated")
    over = dict(overrides or {})
    over.setdefault("drive.chainring_teeth", GEAR[0])
    over.setdefault("drive.cog_teeth", GEAR[1])
    resolved = spec_mod.resolve(str(bike), over)  # the runs take it as read (a rider.height_m said of the rider's kind)
    spec = resolved.spec
    radius = setups(spec)[0].tire_radius
    rows, series = [], []
    read = []  # every record read and its bob found before any run: a bad one refused before another's runs
    for path in records:
        ride = telemetry.read_sst(path, **spec_mod.ride_decoding(spec))  # read as the recorded bike reads it
        if ride.rear_mm is None:
            raise BobError(f"{path}: has no shock sensor: no rear bob to compare")
        try:
            read.append((ride, bob(ride.time_s, ride.rear_mm)))
        except BobError as error:  # the record's own stretch: named by its file and its length
            raise BobError(f"{path}: {ride.duration_s:.1f} s of record; the rear's "
                           f"{str(error).removeprefix('bob: the ')}") from None
    for path, stance, (ride, rear) in zip(records, stances, read):
        notes = list(ride.notes)
        unsteady = not_pedalling(ride, rear)
        if unsteady:
            from mtbmj.config import warn

            notes.append(unsteady)
            warn([f"{ride.name}: {unsteady}"])
        try:
            front = bob(ride.time_s, ride.fork_mm) if ride.fork_mm is not None else None
        except BobError:
            front = None
        cadence = min(max(rear.cadence_rpm, 30.0), 130.0)
        v = gear_speed(spec, cadence, radius)
        sine = power_W / (spec.total_mass * 9.81 * v)
        if sine >= 0.4:
            raise ConfigError(f"{path}: {power_W:g} W at {cadence:.0f} rpm in {'{}x{}'.format(*GEAR)} needs a climb "
                              f"steeper than 40 %: give less power")
        tried = []  # (sine, cadence the run had, run): the climb set again while its cadence misses
        for attempt in range(ATTEMPTS):
            grade = 100.0 * math.tan(math.asin(sine))
            with warnings.catch_warnings(record=True) as said:  # said of the run kept only (a stall of a
                warnings.simplefilter("always")  # climb set again and left is no stall of the bob reported)
                run = run_bike(resolved, f"climb:grade_percent={grade:.3f},length_m={v * duration_s * 1.5 + 10:.1f},"
                                     f"at_m=0.5", None, duration_s, pedal=(cadence, power_W),
                               seated=stance == "seated", rider=rider)
            had = run_cadence(run, run_stretch(run.raw["time_s"]))
            tried.append((sine, had, run, grade, said))
            if abs(had / cadence - 1.0) <= CADENCE_TOLERANCE:
                break
            if len(tried) == 1:  # the speed the power holds goes as 1 / sin a; a step of at most 5 %
                sine *= min(max(had / cadence, 0.95), 1.05)
            else:  # the secant through the last two, within 10 % of the last
                (s0, c0, *_), (s1, c1, *_) = tried[-2], tried[-1]
                step = (cadence - c1) * (s1 - s0) / (c1 - c0) if c1 != c0 else 0.0
                sine = s1 + min(max(step, -0.1 * s1), 0.1 * s1)
            sine = min(sine, 0.4)
        sine, had, run, grade, said = min(tried, key=lambda r: abs(r[1] - cadence))
        for w in said:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        t = run.raw["time_s"]
        window = run_stretch(t)
        if window[1] - window[0] < MIN_STRETCH_S - 0.01:  # the run ended early: its crash named, not the record's stretch
            ended = (run.summary.get("crash") or {}).get("line") or f"ended at {float(t[-1]):.2f} s"
            raise BobError(f"{path}: the bike pedalled as this record implies ({cadence:.0f} rpm from its rear's "
                           f"{rear.frequency_Hz:.2f} Hz, {power_W:g} W in {GEAR[0]}x{GEAR[1]} up a {grade:.1f} % climb) "
                           f"{ended}, before {MIN_STRETCH_S:g} s of its second half: no simulated bob (a record that is "
                           f"not steady pedalling reads as a slow cadence; less --power climbs less steeply)")
        sim = {"rear": bob(t, run.raw["rear_travel_mm"], *window).to_dict(),
               "front": bob(t, run.raw["front_travel_mm"], *window).to_dict()}
        rows.append({"record": ride.name, "stance": stance, "rider": rider, "notes": notes, "cadence_rpm": cadence,
                     "simulated_cadence_rpm": had, "power_W": power_W, "grade_percent": grade, "speed_m_per_s": v,
                     "ride": {"rear": rear.to_dict(), "front": front.to_dict() if front else None},
                     "simulated": sim, "min_speed_m_per_s": run.summary["min_speed_m_per_s"],
                     "crash": run.summary.get("crash")})
        series.append(((ride.time_s, ride.fork_mm, ride.rear_mm), (t, run.raw["front_travel_mm"],
                                                                   run.raw["rear_travel_mm"])))
    return Against(str(bike), rows, series)


__all__ = ["Against", "against", "not_pedalling", "run_cadence", "GEAR", "RUN_S", "CADENCE_TOLERANCE", "UNSTEADY",
           "DESCENDING_FORK_PERCENT"]

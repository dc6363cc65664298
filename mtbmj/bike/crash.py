"""A crash ends a bike's run.

A run ends, at the sample it happens, when a part of the bike or rider other than a tyre reaches
the ground (the bottom bracket, the main pivot, the bars, the rider's hips, shoulders or centre of
mass below the terrain's surface under it: frame and rider have no contact with the ground, so
past that moment the model no longer describes what happens), or when the frame pitches past what
a rider recovers from: nose down beyond ``OVER_THE_BARS_DEG`` (over the bars) or nose up beyond
``LOOP_OUT_DEG`` (looped out). Both limits are *assumed* (no source measured a rider's limit; a
steep roll-in or landing, 30-40 deg, stays inside them).

:class:`Watch` is the run path's ``stop`` (``mtbmj.runpath.loop.stepped``): it looks at each
stretch of states as it is made, so a run ends at its crash before the physics after it can
diverge.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

OVER_THE_BARS_DEG = 45.0  # assumed
LOOP_OUT_DEG = 60.0  # assumed
# the sites that are not a tyre: frame (bottom bracket, main pivot, bars) and rider
PARTS = {"bb": "the bottom bracket", "main_pivot": "the main pivot", "bars": "the bars",
         "hips": "the rider's hips", "shoulders": "the rider's shoulders", "rider_com": "the rider's body"}


@dataclass(frozen=True)
class Crash:
    kind: str  # "over the bars", "looped out", "ground"
    time_s: float
    pitch_deg: float
    part: str | None = None  # the part that reached the ground

    def line(self) -> str:
        what = f"{self.part} hit the ground" if self.kind == "ground" else self.kind
        return f"crashed: {what} at {self.time_s:.3f} s (pitch {self.pitch_deg:.1f} deg)"

    def to_dict(self) -> dict:
        return {"kind": self.kind, "time_s": self.time_s, "pitch_deg": self.pitch_deg, "part": self.part,
                "line": self.line()}


class Watch:
    """The crash check of one run (see the module doc); ``crash`` holds the first one found. The
    parts' world positions are the model's ``at_<site>`` framepos sensors: sensor row j is the
    state at the start of output step j, so a part found on the ground there ends the run with
    that step."""

    def __init__(self, model, terrain, pitch_qpos: int, pitch_locked: bool = False):
        self.terrain = terrain
        self.pitch_col = 1 + pitch_qpos
        self.pitch_locked = pitch_locked
        adr = [int(model.sensor_adr[model.sensor(f"at_{name}").id]) for name in PARTS]
        self.x_cols, self.z_cols = adr, [a + 2 for a in adr]
        self.names = list(PARTS.values())
        self.crash: Crash | None = None

    def reset(self) -> None:
        self.crash = None

    def __call__(self, first: int, states: np.ndarray, sensors: np.ndarray) -> int | None:
        n = min(len(states), len(sensors))
        if not n:
            return None
        deg = np.degrees(states[:n, self.pitch_col])
        tipped = np.flatnonzero((deg < -OVER_THE_BARS_DEG) | (deg > LOOP_OUT_DEG))
        end = int(tipped[0]) if tipped.size and not self.pitch_locked else n
        xs, zs = sensors[:n, self.x_cols], sensors[:n, self.z_cols]
        below = zs < self.terrain.height(xs)
        rows = np.flatnonzero(below[:end + 1 if end < n else n].any(axis=1))
        if rows.size:
            j = int(rows[0])
            before = j - 1 if j else None  # the state at the sensor row's time: the end of the step before
            t = float(states[before, 0]) if before is not None else float(states[0, 0]) - (states[1, 0] - states[0, 0]
                                                                                          if n > 1 else 0.0)
            pitch = float(deg[before]) if before is not None else float(deg[0])
            self.crash = Crash("ground", t, pitch, self.names[int(np.flatnonzero(below[j])[0])])
            return j
        if end < n:
            kind = "over the bars" if deg[end] < 0 else "looped out"
            self.crash = Crash(kind, float(states[end, 0]), float(deg[end]))
            return end
        return None

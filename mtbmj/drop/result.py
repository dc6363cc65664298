"""The result of one drop: one object that holds the numbers, plots itself and exports."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mtbmj import output
from mtbmj.config import Config
from mtbmj.drop.measure import COLUMNS
from mtbmj.result import RunOutput, versions
from mtbmj.trace import RawTrace

DISPLACEMENTS = ("sled_mm", "fork_mm", "tire_mm")


@dataclass
class DropResult(RunOutput):
    """A drop run: ``signals`` as the sled logger records them (1 kHz, mm, N; see
    ``measure.COLUMNS``), ``raw`` at the engine rate, ``summary`` (events, rest, energy)."""

    COLUMNS = COLUMNS  # not a field: the columns written and exported
    COMPARED = DISPLACEMENTS  # difference(): sled, fork and tire, in mm
    DIFFERENCE_KEY = "max_abs_mm"

    name: str
    engine: str
    config: Config
    signals: dict[str, np.ndarray]
    raw: dict[str, np.ndarray]
    trace: RawTrace
    summary: dict
    wall_time_s: float
    info: dict = field(default_factory=dict)

    def csv_chunks(self, raw: bool = False):
        data = self.raw if raw else self.signals
        rate = "engine rate" if raw else "1 kHz after a 400 Hz anti-aliasing low-pass"
        header = (f"mtbmj drop {self.name}, engine {self.engine}, {rate}\n"
                  "sled zero at tire touch, fork zero at unloaded full extension, tire = sled - fork, compression positive")
        return output.csv_chunks({k: data[k] for k in COLUMNS}, header)

    def csv_bytes(self, raw: bool = False) -> bytes:
        return b"".join(self.csv_chunks(raw))

    def manifest(self) -> dict:
        return {
            "name": self.name,
            "engine": self.engine,
            "config_sha256": self.config.digest(),
            "config_sources": list(self.config.sources),
            "versions": versions(),
            "wall_time_s": self.wall_time_s,
            "engine_info": {k: v for k, v in self.trace.info.items() if k != "events"},
        }

    def headline(self) -> str:
        """The run in one line: peaks, lift-off, rest and any bottom-out or rim strike."""
        from mtbmj.readout.endtravel import line

        s = self.summary
        lift = f"{s['lift_off_s']:.3f} s" if s["lift_off_s"] is not None else "never"
        return (f"{self.name} ({self.engine}): fork peak {s['max_fork_mm']:.1f} mm ({s['travel_used_percent']:.0f} % of "
                f"travel), tire peak {s['max_tire_mm']:.1f} mm, lift-off {lift}, "
                f"{'at rest' if s['at_rest'] else 'still moving'} at the end{line(s)}")

    def quicklook(self):
        """The quick-look figure (``mtbmj.readout.quicklook``) on the engine-rate signals, titled
        by the run's headline and, for a configuration file, what the file is."""
        from mtbmj.readout import quicklook

        r = self.raw
        return quicklook.figure(r["time_s"], r["fork_mm"], r["tire_mm"],
                                {"fork_force_N": r["fork_force_N"], "tire_force_N": r["tire_force_N"]},
                                self.summary, quicklook.run_title(self.config, self.headline()))

    def plot(self, axes=None, label: str | None = None, **line_kwargs):
        """Sled, fork and tire displacement histories on three stacked axes; returns the figure."""
        return self.plot_stacked([(c, c.replace("_mm", " [mm]")) for c in DISPLACEMENTS], self.signals, axes,
                                 label or f"{self.name} ({self.engine})", {"fontsize": "small", "ncol": 2},
                                 **line_kwargs)

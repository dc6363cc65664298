"""Drop-sled records in: the two potentiometer readings (or the three displacements), zeroed and
aligned so that time zero is the moment the tire tread touches the ground.

A record is a CSV (or .mat) read by ``mtbmj.measured.records.read_record``: units in the column
names, ``#`` comment lines, any of ``,`` ``;`` tab as delimiter. Columns:

- ``time_s`` (or ``time_ms``);
- ``sled_mm`` and ``fork_mm``: the sled and fork potentiometers (``sled_displacement_mm``,
  ``fork_travel_mm`` ... are accepted too); ``tire_mm`` (``tire_deflection_mm``) is optional and
  otherwise computed as sled - fork (the paper's definition); any two of the three suffice.

Conventions are the paper's: sled zero when the tread just touches the ground, fork zero at
unloaded full extension, compression positive. Readings taken against another zero are corrected
with ``sled_offset_mm`` / ``fork_offset_mm`` (the reading at the true zero, subtracted).

Time zero is found from the data by the one rule of ``validation.time_zero`` (free fall then
impact, a record that starts at impact, or a logger clock with a pre-trigger), or given as
``touch_s`` on the record's clock; ``SledRecord.touch`` says which and where.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Mapping

import numpy as np

from mtbmj.measured.records import Record, RecordError, read_record
from mtbmj.measured import time_zero
from mtbmj.measured.peaks import noise_sigma
from mtbmj.measured.time_zero import antialias_delay_s
from mtbmj.textfile import read_bytes

DISPLACEMENTS = ("sled", "fork", "tire")
ALIASES = {
    "time": ("time", "t"),
    "sled": ("sled", "sled_displacement", "sled_position", "sled_pot", "sled_potentiometer"),
    "fork": ("fork", "fork_displacement", "fork_travel", "fork_pot", "fork_potentiometer"),
    "tire": ("tire", "tire_displacement", "tire_deflection", "tyre", "tyre_deflection"),
}
LENGTH_UNITS = ("mm", "m")
TIME_UNITS = ("s", "ms")
GAP_FACTOR = 1.5         # a step longer than 1.5 x the typical step is a gap
MIN_AFTER_TOUCH_S = time_zero.MIN_AFTER_TOUCH_S  # a record must go on at least this long after touch
EXAMPLE = Path(str(resources.files("mtbmj") / "data" / "sled_example.csv"))


class SledDataError(RecordError):
    """A sled record cannot be used: one line naming the file and the cause."""


def example_path() -> Path:
    """The shipped synthetic example record (``mtbmj/data/sled_example.csv``)."""
    try:
        from importlib import resources

        candidate = Path(str(resources.files("mtbmj") / "data" / "sled_example.csv"))
        if candidate.exists():
            return candidate
    except (ModuleNotFoundError, TypeError):  # pragma: no cover
        pass
    return EXAMPLE


@dataclass(frozen=True)
class SledRecord:
    """A sled record on the paper's conventions, aligned: ``time_s`` is 0 at tire touch."""

    name: str
    time_s: np.ndarray
    sled_mm: np.ndarray
    fork_mm: np.ndarray
    tire_mm: np.ndarray
    touch_s: float                 # touch on the file's own clock (s)
    noise_mm: dict                 # estimated sensor noise (standard deviation) per signal
    path: str | None = None
    comments: tuple[str, ...] = field(default=())
    tire_computed: bool = True     # tire = sled - fork (not a column of the file)
    touch: time_zero.Touch | None = None  # how time zero was found (None: given aligned)

    @property
    def synthetic(self) -> bool:
        return any("synthetic" in c.lower() for c in self.comments)

    @property
    def sample_rate_Hz(self) -> float:
        return float(1.0 / np.median(np.diff(self.time_s)))

    @property
    def duration_s(self) -> float:
        """Recorded time after touch."""
        return float(self.time_s[-1])

    def signals(self, start_s: float | None = 0.0, end_s: float | None = None) -> dict[str, np.ndarray]:
        """Columns ``time_s, sled_mm, fork_mm, tire_mm`` between ``start_s`` and ``end_s`` (inclusive)."""
        keep = np.ones(self.time_s.size, bool)
        if start_s is not None:
            keep &= self.time_s >= start_s - 1e-12
        if end_s is not None:
            keep &= self.time_s <= end_s + 1e-12
        return {"time_s": self.time_s[keep], "sled_mm": self.sled_mm[keep],
                "fork_mm": self.fork_mm[keep], "tire_mm": self.tire_mm[keep]}

    def info(self) -> dict:
        return {"name": self.name, "path": self.path, "synthetic": self.synthetic,
                "touch_in_file_s": self.touch_s,
                "time_zero": self.touch.describe() if self.touch else "t = 0 at touch (simulated run)", "sample_rate_Hz": self.sample_rate_Hz,
                "duration_after_touch_s": self.duration_s, "points": int(self.time_s.size),
                "noise_mm": self.noise_mm, "tire": "sled - fork" if self.tire_computed else "column of the file",
                "comments": list(self.comments)}


def find_touch(time_s: np.ndarray, tire_mm: np.ndarray, name: str = "record",
               antialias_Hz: float | None = 400.0) -> float:
    """Time of tire touch on the record's clock (``validation.time_zero.find_touch``)."""
    try:
        return time_zero.find_touch(time_s, tire_mm, name, antialias_Hz).touch_s
    except time_zero.TouchError as exc:
        raise SledDataError(str(exc)) from None


def _pick(record: Record, quantity: str) -> str | None:
    for alias in ALIASES[quantity]:
        if alias in record.columns:
            return alias
    return None


def _check_time(name: str, t: np.ndarray) -> None:
    if t.size < 20:
        raise SledDataError(f"{name}: too few points ({t.size}) for a drop record")
    steps = np.diff(t)
    if np.any(steps == 0):
        i = int(np.argmax(steps == 0))
        raise SledDataError(f"{name}: duplicated time stamp t = {t[i]:.6g} s at data rows {i + 1} and {i + 2}")
    if np.any(steps < 0):
        i = int(np.argmax(steps < 0))
        raise SledDataError(f"{name}: time goes backwards at data row {i + 2} ({t[i]:.6g} s -> {t[i + 1]:.6g} s)")
    typical = float(np.median(steps))
    if np.any(steps > GAP_FACTOR * typical):
        i = int(np.argmax(steps > GAP_FACTOR * typical))
        raise SledDataError(f"{name}: gap in time of {steps[i] * 1e3:.3g} ms after t = {t[i]:.6g} s (data row {i + 1}; "
                            f"the sampling step is {typical * 1e3:.3g} ms)")


def from_arrays(time_s, sled_mm=None, fork_mm=None, tire_mm=None, *, sled_offset_mm: float = 0.0,
                fork_offset_mm: float = 0.0, name: str = "record", path: str | None = None,
                comments=(), align: bool = True, antialias_Hz: float | None = 400.0,
                touch_s: float | None = None) -> SledRecord:
    """A ``SledRecord`` from arrays in s and mm (any two of sled, fork, tire), zeroed and aligned."""
    t = np.asarray(time_s, float)
    given = {k: None if v is None else np.asarray(v, float) for k, v in
             (("sled", sled_mm), ("fork", fork_mm), ("tire", tire_mm))}
    present = [k for k, v in given.items() if v is not None]
    if len(present) < 2:
        missing = [k for k in DISPLACEMENTS if given[k] is None]
        raise SledDataError(f"{name}: missing column {missing[0]}_mm (need sled_mm and fork_mm, or two of "
                            f"sled_mm, fork_mm, tire_mm; have {', '.join(k + '_mm' for k in present) or 'none'})")
    for k in present:
        if given[k].shape != t.shape:
            raise SledDataError(f"{name}: {k}_mm has {given[k].size} values for {t.size} time stamps")
        if not np.all(np.isfinite(given[k])):
            raise SledDataError(f"{name}: {k}_mm holds NaN or infinite values")
    if not np.all(np.isfinite(t)):
        raise SledDataError(f"{name}: time holds NaN or infinite values")
    for key, value in (("sled_offset_mm", sled_offset_mm), ("fork_offset_mm", fork_offset_mm)):
        if not np.isfinite(value):
            raise SledDataError(f"{name}: {key} must be a finite number, got {value}")
    _check_time(name, t)
    sled = given["sled"] - sled_offset_mm if given["sled"] is not None else None
    fork = given["fork"] - fork_offset_mm if given["fork"] is not None else None
    tire = given["tire"]
    tire_computed = tire is None
    if tire is None:
        tire = sled - fork
    elif sled is None:
        sled = fork + tire
    elif fork is None:
        fork = sled - tire
    found = None
    if align or touch_s is not None:
        try:
            found = time_zero.find_touch(t, tire, name, antialias_Hz, touch_s=touch_s)
        except time_zero.TouchError as exc:
            raise SledDataError(str(exc)) from None
    touch = found.touch_s if found else 0.0
    noise = {k: float(noise_sigma(v)) for k, v in (("sled", sled), ("fork", fork), ("tire", tire))}
    return SledRecord(name=name, time_s=t - touch, sled_mm=sled, fork_mm=fork, tire_mm=tire, touch_s=float(touch),
                      noise_mm=noise, path=path, comments=tuple(comments), tire_computed=tire_computed,
                      touch=found)


def read_sled(path: str | Path, *, sled_offset_mm: float = 0.0, fork_offset_mm: float = 0.0,
              antialias_Hz: float | None = 400.0, touch_s: float | None = None) -> SledRecord:
    """Read, check, zero and align a sled record (CSV or .mat). Raises ``SledDataError`` /
    ``RecordError`` (``MtbmjError``) with one line naming the file and the cause."""
    path = Path(path)
    if path.is_dir():
        raise SledDataError(f"{path}: is a directory, not a sled record")
    if path.suffix.lower() != ".mat" and path.exists():
        raw = read_bytes(path, SledDataError, str(path), "record")[:4096]
        if b"\x00" in raw:
            raise SledDataError(f"{path}: not a CSV file (binary content)")
    try:
        record = read_record(path)
    except SledDataError:
        raise
    except RecordError as exc:
        text = str(exc)
        if path.exists() and ("line" in text or "no unit" in text or "no header" in text):
            text += " (not a CSV sled record: expected columns like time_s, sled_mm, fork_mm)"
        raise SledDataError(text) from None
    return from_record(record, sled_offset_mm=sled_offset_mm, fork_offset_mm=fork_offset_mm,
                       antialias_Hz=antialias_Hz, touch_s=touch_s)


def from_record(record: Record, *, sled_offset_mm: float = 0.0, fork_offset_mm: float = 0.0,
                antialias_Hz: float | None = 400.0, touch_s: float | None = None) -> SledRecord:
    """A ``SledRecord`` from a ``Record`` already read (``identify.records.read_record``): the sled,
    fork and tire columns picked by name, zeroed and aligned to the touch."""
    name = str(record.path)
    time_key = _pick(record, "time")
    if time_key is None:
        have = ", ".join(f"{q}_{record.units[q]}" for q in record.columns) or "none"
        raise SledDataError(f"{name}: missing column time_s (columns: {have})")
    if record.units[time_key] not in TIME_UNITS:
        raise SledDataError(f"{name}: column {time_key}_{record.units[time_key]} is a time and needs the unit s or ms")
    columns = {}
    for quantity in DISPLACEMENTS:
        key = _pick(record, quantity)
        if key is None:
            continue
        unit = record.units[key]
        if unit not in LENGTH_UNITS:
            raise SledDataError(f"{name}: column {key}_{unit} is a displacement and needs a length unit "
                                f"(mm or m), not {unit}")
        columns[quantity] = record.columns[key] * 1e3  # records are SI
    if len(columns) < 2:
        have = ", ".join(f"{q}_{record.units[q]}" for q in record.columns) or "none"
        missing = next(q for q in ("sled", "fork", "tire") if q not in columns)
        raise SledDataError(f"{name}: missing column {missing}_mm (need sled_mm and fork_mm, or two of sled_mm, "
                            f"fork_mm, tire_mm; columns: {have})")
    return from_arrays(record.columns[time_key], columns.get("sled"), columns.get("fork"), columns.get("tire"),
                       sled_offset_mm=sled_offset_mm, fork_offset_mm=fork_offset_mm, name=name, path=name,
                       comments=record.comments, antialias_Hz=antialias_Hz, touch_s=touch_s)


def from_result(result, name: str | None = None) -> SledRecord:
    """A simulated run (``DropResult``) seen as a sled record: its logged signals, already aligned
    (t = 0 is touch in every simulation)."""
    s = result.signals
    return SledRecord(name=name or f"{result.name} ({result.engine})", time_s=np.asarray(s["time_s"], float),
                      sled_mm=np.asarray(s["sled_mm"], float), fork_mm=np.asarray(s["fork_mm"], float),
                      tire_mm=np.asarray(s["tire_mm"], float), touch_s=0.0,
                      noise_mm={k: 0.0 for k in DISPLACEMENTS}, path=None,
                      comments=(f"simulated: {result.name} on {result.engine}",), tire_computed=False)


def load(data, touch_s: float | None = None) -> SledRecord:
    """A ``SledRecord`` from a path, a ``Record``, a ``SledRecord``, or a mapping of columns
    (time_s, sled_mm ...); ``touch_s``: time zero on the record's clock (default: found)."""
    if isinstance(data, SledRecord):
        return data
    if isinstance(data, (str, Path)):
        return read_sled(data, touch_s=touch_s)
    if isinstance(data, Record):
        return from_record(data, touch_s=touch_s)
    if isinstance(data, Mapping):
        return from_arrays(data["time_s"], data.get("sled_mm"), data.get("fork_mm"), data.get("tire_mm"),
                           touch_s=touch_s)
    raise SledDataError(f"sled data: expected a file path or a SledRecord, got {type(data).__name__}")


__all__ = ["SledRecord", "SledDataError", "read_sled", "from_record", "from_arrays", "from_result", "find_touch", "load",
           "example_path", "antialias_delay_s"]

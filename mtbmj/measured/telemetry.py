"""Real ride telemetry: Sufni Suspension Telemetry (SST) files into fork and rear travel.

SST version 3, little-endian (format in ``mtbmj/data/sst/README.md``): a 16-byte header (magic
``SST``, version uint8, sample rate uint16 in Hz, padding uint16, Unix timestamp int64), then
4-byte records of two uint16 AS5600 encoder counts (fork, shock; 0..4095). 0xFFFF in the first
record marks an absent sensor; a trailing partial record is ignored.

Counts become travel through the sensor linkages of the recorded bike ("Clash 2022", the
defaults here; pass your own ``IsoscelesTriangle``/``Triangle``/leverage curve (``LeverageCurve``
gives one: the one leverage class, ``mtbmj.measured.leverage.Leverage``) and travel maxima for
another bike):

- fork ("as5600-isosceles-triangle"): travel = max - 2 arm cos(2 pi s / 4096 + a0),
  a0 = acos(max / (2 arm)); counts above 1024 are the sensor wrapping just below zero -> 0;
- shock ("as5600-triangle"): stroke = max - sqrt(arm1^2 + arm2^2 - 2 arm1 arm2 cos(a0 - 2 pi s / 4096)),
  a0 = acos((arm1^2 + arm2^2 - max^2) / (2 arm1 arm2)); counts above 2048 wrap -> 0;
- rear wheel travel from the stroke through the leverage curve (wheel travel, leverage ratio):
  stroke(w) = integral of dw / ratio(w), inverted by interpolation.

SST version 2 (the older recordings, e.g. the rebound-click seat slams): a 6-byte header (magic
``SST``, version uint8 = 2, sample rate uint16 in Hz; no timestamp), then the same 4-byte records.
Both ends were decoded then through an isosceles triangle at pi/4096 rad per count
(``HalfTurnIsosceles``: travel = max - 2 arm cos(pi s / 4096 + a0), a0 = acos(max / (2 arm))),
with that time's defaults: fork arm 120 mm, max 218 mm; shock arm 88 mm, max 138 mm. The recording
project called those values placeholders: a version-2 record's timing is exact, its amplitudes
are approximate (the record's ``notes`` say so), so an analysis of it should rest on periods and
ratios, not on millimetres.
"""
from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

import numpy as np

from mtbmj.measured import metrics as ride_metrics
from mtbmj.measured.leverage import Leverage
from mtbmj.errors import MtbmjError
from mtbmj.textfile import delimiter_of, parses_as_number, read_bytes

MAGIC = b"SST"
VERSION = 3
VERSIONS = (2, 3)
HEADER = struct.Struct("<3sBHHq")  # magic, version, sample rate (Hz), padding, Unix time (s)
HEADER_V2 = struct.Struct("<3sBH")  # magic, version, sample rate (Hz)
V2_AMPLITUDE_NOTE = ("SST version 2: travel decoded with the recording project's placeholder calibration of that "
                     "time (fork arm 120 mm, max 218 mm; shock arm 88 mm, max 138 mm); timing is exact, amplitudes "
                     "are approximate")
RECORD_BYTES = 4
ABSENT = 0xFFFF
COUNTS = 4096

FORK_TRAVEL_MAX_MM = 180.0  # data/sst/notes.txt: front_stroke
SHOCK_STROKE_MAX_MM = 65.0  # data/sst/notes.txt: rear_stroke
HEAD_ANGLE_DEG = 63.5  # data/sst/notes.txt: head_angle (recorded for reference; travel is along the fork)


class TelemetryError(MtbmjError, ValueError):
    """A telemetry file cannot be read: names the file and the cause. An input error: a ``ValueError``
    too, as ``ConfigError`` is."""


class NotAnSST(TelemetryError):
    """A file given as an SST recording that does not start as one; ``text``: it starts as text (a
    travel CSV renamed .SST, which ``read_ride`` then reads as one)."""

    def __init__(self, message: str, text: bool):
        super().__init__(message)
        self.text = text


# What a suspension logger records at: Sufni's v3 files at 1000 Hz, its v2 files at 5000 Hz. Below
# 100 Hz the velocity's 51 ms Savitzky-Golay window (``ride.metrics``) holds fewer than the 5
# samples its cubic needs and a 1-5 Hz pedal bob is a few samples a stroke; above 20 kHz (four
# times the fastest recording known) a rate is a damaged header or a time column in other units.
SAMPLE_RATE_HZ = (100.0, 20000.0)


def check_sample_rate(rate: float, where: str) -> float:
    """``rate`` (Hz) if a suspension logger records at it (``SAMPLE_RATE_HZ``), else one
    ``TelemetryError`` line naming ``where`` it came from."""
    low, high = SAMPLE_RATE_HZ
    if not (math.isfinite(rate) and low <= rate <= high):
        raise TelemetryError(f"{where} gives a sample rate of {rate:g} Hz, outside what a suspension logger records "
                             f"({low:g}-{high:g} Hz)")
    return float(rate)


@dataclass(frozen=True)
class IsoscelesTriangle:
    """Front sensor "as5600-isosceles-triangle": two equal arms, the fork stroke as the base."""

    arm_mm: float = 134.9375
    max_mm: float = 234.15625

    def travel_mm(self, counts: np.ndarray) -> np.ndarray:
        s = np.asarray(counts, dtype=float)
        s = np.where(s > COUNTS / 4, 0.0, s)
        start = math.acos(self.max_mm / (2.0 * self.arm_mm))
        return self.max_mm - 2.0 * self.arm_mm * np.cos(2.0 * np.pi / COUNTS * s + start)


@dataclass(frozen=True)
class Triangle:
    """Rear sensor "as5600-triangle": arms ``arm1``, ``arm2``; the shock's eye-to-eye as the third side."""

    arm1_mm: float = 98.9
    arm2_mm: float = 202.8
    max_mm: float = 230.0

    def stroke_mm(self, counts: np.ndarray) -> np.ndarray:
        s = np.asarray(counts, dtype=float)
        s = np.where(s > COUNTS / 2, 0.0, s)
        a, b = self.arm1_mm, self.arm2_mm
        start = math.acos((a * a + b * b - self.max_mm ** 2) / (2.0 * a * b))
        return self.max_mm - np.sqrt(a * a + b * b - 2.0 * a * b * np.cos(start - 2.0 * np.pi / COUNTS * s))


@dataclass(frozen=True)
class HalfTurnIsosceles:
    """SST version 2 sensor: two equal arms joined at the encoder, pi/4096 rad per count (the
    version-2 decoding; defaults: the fork's placeholder values of that time)."""

    arm_mm: float = 120.0
    max_mm: float = 218.0

    @property
    def start_rad(self) -> float:
        return math.acos(self.max_mm / (2.0 * self.arm_mm))

    @property
    def counts_max(self) -> float:
        """The count at which the arms lie straight (travel = max): beyond it, no geometry."""
        return (math.pi / 2.0 - self.start_rad) * COUNTS / math.pi

    def travel_mm(self, counts: np.ndarray) -> np.ndarray:
        s = np.asarray(counts, dtype=float)
        return self.max_mm - 2.0 * self.arm_mm * np.cos(math.pi / COUNTS * s + self.start_rad)

    def counts(self, travel_mm: np.ndarray) -> np.ndarray:
        """The inverse: the (real-valued) count that decodes to ``travel_mm``."""
        x = np.asarray(travel_mm, dtype=float)
        return (np.arccos((self.max_mm - x) / (2.0 * self.arm_mm)) - self.start_rad) * COUNTS / math.pi


V2_FORK = HalfTurnIsosceles(120.0, 218.0)
V2_SHOCK = HalfTurnIsosceles(88.0, 138.0)


# Clash 2022 leverage ratio against rear wheel travel (mm), 1 mm steps, from data/sst/notes.txt. The row
# for 25 mm is garbled there ("3.clash2022_lr_sensitive.csv008"); 3.008 is read from it and lies
# between its neighbours 3.014 and 3.002.
CLASH_2022_LEVERAGE_RATIO = (
    3.18, 3.173, 3.165, 3.157, 3.149, 3.142, 3.134, 3.126, 3.119, 3.113, 3.106, 3.1, 3.093, 3.087, 3.08,
    3.073, 3.067, 3.06, 3.053, 3.047, 3.04, 3.033, 3.027, 3.02, 3.014, 3.008, 3.002, 2.995, 2.989, 2.983,
    2.977, 2.971, 2.965, 2.958, 2.952, 2.946, 2.94, 2.934, 2.928, 2.922, 2.916, 2.91, 2.905, 2.899, 2.893,
    2.888, 2.882, 2.876, 2.871, 2.865, 2.859, 2.854, 2.849, 2.844, 2.838, 2.833, 2.828, 2.823, 2.817, 2.812,
    2.807, 2.801, 2.796, 2.791, 2.786, 2.78, 2.775, 2.77, 2.766, 2.761, 2.756, 2.751, 2.746, 2.741, 2.736,
    2.731, 2.726, 2.722, 2.717, 2.712, 2.707, 2.703, 2.698, 2.694, 2.689, 2.685, 2.68, 2.676, 2.671, 2.667,
    2.662, 2.658, 2.653, 2.649, 2.644, 2.64, 2.635, 2.631, 2.626, 2.622, 2.618, 2.613, 2.609, 2.605, 2.601,
    2.597, 2.593, 2.589, 2.585, 2.581, 2.577, 2.573, 2.569, 2.565, 2.561, 2.557, 2.553, 2.549, 2.544, 2.54,
    2.536, 2.533, 2.529, 2.525, 2.522, 2.518, 2.514, 2.511, 2.507, 2.503, 2.499, 2.496, 2.492, 2.488, 2.485,
    2.481, 2.478, 2.475, 2.471, 2.468, 2.465, 2.462, 2.458, 2.455, 2.452, 2.448, 2.445, 2.442, 2.439, 2.436,
    2.433, 2.43, 2.427, 2.424, 2.421, 2.418, 2.415, 2.411, 2.408, 2.405, 2.402, 2.4, 2.397, 2.395, 2.392,
    2.389, 2.387, 2.384, 2.381, 2.379, 2.376, 2.374, 2.371, 2.368, 2.366,
)


def LeverageCurve(wheel_mm=tuple(float(i) for i in range(len(CLASH_2022_LEVERAGE_RATIO))),
                  ratio=CLASH_2022_LEVERAGE_RATIO) -> Leverage:
    """The recorded bike's leverage ratio against rear wheel travel (mm; the Clash 2022's by default)
    as the one leverage class, ``mtbmj.measured.leverage.Leverage`` (SI; ``stroke_mm`` and
    ``wheel_travel_mm`` read it in mm); a curve that is not increasing and positive is refused."""
    w, r = np.asarray(wheel_mm, float), np.asarray(ratio, float)
    if w.ndim != 1 or w.shape != r.shape or w.size < 2 or np.any(np.diff(w) <= 0) or np.any(r <= 0):
        raise TelemetryError("leverage curve: needs increasing wheel travel and positive ratios of equal length")
    return Leverage(tuple(float(x) / 1e3 for x in w), tuple(float(x) for x in r))


@dataclass(frozen=True)
class TelemetryRecord:
    """One ride: fork travel, shock stroke and rear wheel travel (mm, zero at full extension,
    compression positive) on a uniform time grid from 0 s; a series is None when its sensor is absent."""

    path: str
    version: int
    sample_rate_Hz: float
    timestamp: int  # Unix time of the recording start (s)
    time_s: np.ndarray
    fork_mm: np.ndarray | None
    shock_mm: np.ndarray | None
    rear_mm: np.ndarray | None
    fork_max_mm: float = FORK_TRAVEL_MAX_MM
    shock_max_mm: float = SHOCK_STROKE_MAX_MM
    rear_max_mm: float = field(default=float("nan"))
    counts: np.ndarray | None = field(default=None, repr=False)  # raw (n, 2) uint16
    notes: tuple = ()  # what a reader of the record should know (a version-2 file: approximate amplitudes)
    columns: tuple = ()  # a travel CSV's travel columns as its header names them (fork_mm, shock_mm, rear_mm)

    @property
    def duration_s(self) -> float:
        return self.time_s.size / self.sample_rate_Hz

    def decimated(self, max_rate_Hz: float) -> "TelemetryRecord":
        """This ride at no more than ``max_rate_Hz``: each travel low-passed (a 4th-order Butterworth
        run forward and back, at 0.8 of the new Nyquist frequency, so nothing aliases and nothing
        is delayed) and every k-th sample kept; the record itself where its rate is that or less.
        A version-2 record's 5 kHz carries the sensor's count steps as noise that two derivatives
        amplify; what a suspension does lies well below 100 Hz."""
        k = math.ceil(self.sample_rate_Hz / max_rate_Hz - 1e-9)
        if k <= 1:
            return self
        from scipy.signal import butter, sosfiltfilt

        rate = self.sample_rate_Hz / k
        sos = butter(4, 0.8 * (rate / 2.0), fs=self.sample_rate_Hz, output="sos")
        keep = lambda x: None if x is None else np.ascontiguousarray(sosfiltfilt(sos, np.asarray(x, float))[::k])
        return replace(self, sample_rate_Hz=rate, time_s=np.ascontiguousarray(self.time_s[::k]),
                       fork_mm=keep(self.fork_mm), shock_mm=keep(self.shock_mm), rear_mm=keep(self.rear_mm),
                       counts=None, notes=self.notes + (f"read at {rate:g} Hz (low-passed and every {k}th sample "
                                                        f"of its {self.sample_rate_Hz:g} Hz)",))

    @property
    def name(self) -> str:
        return Path(self.path).name

    def airtime(self, **rule) -> ride_metrics.Airtime:
        """Airborne periods over both ends (the fork alone, or the rear alone, without the other)."""
        if self.fork_mm is not None:
            return ride_metrics.airtime(self.fork_mm, self.fork_max_mm, self.time_s,
                                        self.rear_mm, self.rear_max_mm if self.rear_mm is not None else None, **rule)
        return ride_metrics.airtime(self.rear_mm, self.rear_max_mm, self.time_s, **rule)

    def metrics(self, threshold_mm_per_s: float = 100, bin_percent: float = 5, margin_mm: float = 3.0,
                velocity_edges=None, balance: bool = True) -> dict:
        """Fork and rear metrics (``ride_metrics.summarize``) with shared airtime; JSON-ready.
        ``velocity_edges``: the velocity histogram's bins (shared with simulated runs beside the
        ride); ``balance``: the ends' mean travel side by side."""
        air = self.airtime()
        out = {"file": self.name, "path": self.path, "version": self.version, "sample_rate_Hz": self.sample_rate_Hz,
               "timestamp": self.timestamp, "duration_s": self.duration_s, "samples": int(self.time_s.size)}
        for end, travel, top in (("fork", self.fork_mm, self.fork_max_mm), ("rear", self.rear_mm, self.rear_max_mm)):
            if travel is not None:
                out[end] = ride_metrics.summarize(self.time_s, travel, top, threshold_mm_per_s=threshold_mm_per_s,
                                                  bin_percent=bin_percent, velocity_edges=velocity_edges,
                                                  margin_mm=margin_mm, airborne=air)
        if self.shock_mm is not None:
            out["rear"]["shock_stroke_max_mm"] = float(np.max(self.shock_mm))
            out["rear"]["shock_stroke_limit_mm"] = self.shock_max_mm
        if balance and self.fork_mm is not None and self.rear_mm is not None:
            out["balance"] = {"fork_mean_percent": out["fork"]["travel"]["mean_percent"],
                              "rear_mean_percent": out["rear"]["travel"]["mean_percent"]}
        return out


def read_sst(path: str | Path, fork_max_mm: float = FORK_TRAVEL_MAX_MM, shock_max_mm: float = SHOCK_STROKE_MAX_MM,
             front: IsoscelesTriangle = IsoscelesTriangle(), rear: Triangle = Triangle(),
             leverage: Leverage = LeverageCurve(), front_v2: HalfTurnIsosceles = V2_FORK,
             rear_v2: HalfTurnIsosceles = V2_SHOCK) -> TelemetryRecord:
    """Read an SST v3 or v2 file into travel time series; every problem is one ``TelemetryError``
    line. A v2 file (no timestamp: 0) is decoded with ``front_v2``/``rear_v2`` and its ``notes``
    say that its amplitudes are approximate."""
    path = Path(path)
    name = str(path)
    blob = read_bytes(path, TelemetryError, name, "telemetry")
    if len(blob) >= 3 and blob[:3] != MAGIC:
        raise NotAnSST(f"{name}: not an SST file (starts with {blob[:3]!r}, expected {MAGIC!r})",
                       all(32 <= b < 127 or b in b"\t\r\n" for b in blob[:64]) or blob.startswith(b"\xef\xbb\xbf"))
    if len(blob) < 4:
        raise TelemetryError(f"{name}: truncated header ({len(blob)} of at least {HEADER_V2.size} bytes)")
    version = blob[3]
    if version not in VERSIONS:
        raise TelemetryError(f"{name}: unknown SST version {version} (this reader knows versions "
                             f"{', '.join(map(str, VERSIONS))})")
    header = HEADER if version == 3 else HEADER_V2
    if len(blob) < header.size:
        raise TelemetryError(f"{name}: truncated header ({len(blob)} of {header.size} bytes)")
    if version == 3:
        _, _, rate, _, timestamp = HEADER.unpack_from(blob)
    else:
        _, _, rate = HEADER_V2.unpack_from(blob)
        timestamp = 0
    if rate == 0:
        raise TelemetryError(f"{name}: sample rate is 0 Hz in the header")
    check_sample_rate(rate, f"{name}: the header")
    for label, value in (("fork_max_mm", fork_max_mm), ("shock_max_mm", shock_max_mm)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise TelemetryError(f"{name}: {label} must be a positive number of mm, got {value!r}")
    n = (len(blob) - header.size) // RECORD_BYTES
    if n < 2:
        raise TelemetryError(f"{name}: truncated: {n} sample{'s' if n != 1 else ''} after the header")
    counts = np.frombuffer(blob, dtype="<u2", count=2 * n, offset=header.size).reshape(n, 2)
    present = counts[0] != ABSENT
    if not present.any():
        raise TelemetryError(f"{name}: both sensors are marked absent (0xFFFF in the first record)")
    limits = (COUNTS - 1, COUNTS - 1) if version == 3 else \
        (math.floor(front_v2.counts_max), math.floor(rear_v2.counts_max))
    for column, label in ((0, "fork"), (1, "shock")):
        if present[column]:
            bad = np.flatnonzero(counts[:, column] > limits[column])
            if bad.size:
                _refuse_joined(name, blob, header.size, int(bad[0]), rate)
                raise TelemetryError(f"{name}: {label} count {int(counts[bad[0], column])} at sample {int(bad[0])} "
                                     f"is outside 0..{limits[column]}")
    moving = [int(np.ptp(counts[:, k])) > 0 for k in (0, 1) if present[k]]
    if not any(moving):
        held = ", ".join(f"{label} count {int(counts[0, k])}" for k, label in ((0, "fork"), (1, "shock")) if present[k])
        raise TelemetryError(f"{name}: no sensor moved ({held} over all {n} samples): missing or stuck, nothing to read")
    if version == 3:
        fork = front.travel_mm(counts[:, 0]) if present[0] else None
        shock = rear.stroke_mm(counts[:, 1]) if present[1] else None
        notes = ()
    else:
        fork = front_v2.travel_mm(counts[:, 0]) if present[0] else None
        shock = rear_v2.travel_mm(counts[:, 1]) if present[1] else None
        notes = (V2_AMPLITUDE_NOTE,)
    partial = (len(blob) - header.size) % RECORD_BYTES
    if partial:  # a recorder writes whole samples: a file cut short in copying or at a power loss
        notes += (f"ends inside a sample ({partial} of its {RECORD_BYTES} bytes): a truncated file? its {n} whole "
                  f"samples ({n / float(rate):.1f} s) are read",)
    wheel = leverage.wheel_travel_mm(shock) if shock is not None else None
    return TelemetryRecord(
        path=name, version=int(version), sample_rate_Hz=float(rate), timestamp=int(timestamp),
        time_s=np.arange(n) / float(rate), fork_mm=fork, shock_mm=shock, rear_mm=wheel,
        fork_max_mm=float(fork_max_mm), shock_max_mm=float(shock_max_mm),
        rear_max_mm=float(leverage.wheel_travel_mm(shock_max_mm)), counts=counts.copy(), notes=notes,
    )


def _refuse_joined(name: str, blob: bytes, start: int, bad: int, rate: int) -> None:
    """Where the first count out of range (sample ``bad``) is a second file's header (``SST`` and a version:
    the magic's ``S`` as a count's high byte is out of range however the bytes fall), the cause in one line:
    two recordings joined into one file (``cat a.SST b.SST``), not a sensor gone wild."""
    at = blob.find(MAGIC, start, start + RECORD_BYTES * (bad + 1) + len(MAGIC))
    if at < 0 or at + len(MAGIC) >= len(blob) or blob[at + len(MAGIC)] not in VERSIONS:
        return
    whole = (at - start) // RECORD_BYTES
    raise TelemetryError(f"{name}: a second SST header (version {blob[at + len(MAGIC)]}) at byte {at}, after "
                         f"{whole} samples ({whole / float(rate):.1f} s): two recordings joined into one file? "
                         f"read each on its own")


CSV_COLUMNS = ("time_s", "fork_mm", "shock_mm", "rear_mm")
CSV_JITTER = 0.01  # a time step may differ from the median step by at most this share
# shock_mm and rear_mm both given: they may differ through the leverage by this much (mm, share of the
# wheel's travel) before a note says so (a logger's own leverage curve rounds differently)
CSV_BOTH_MM, CSV_BOTH_SHARE = 2.0, 0.03


def read_travel_csv(path: str | Path, fork_max_mm: float = FORK_TRAVEL_MAX_MM,
                    shock_max_mm: float = SHOCK_STROKE_MAX_MM, leverage: Leverage = LeverageCurve()
                    ) -> TelemetryRecord:
    """A ride given as a CSV of travel (any logger's export): a header naming ``time_s`` and one or
    more of ``fork_mm`` (fork travel), ``shock_mm`` (shock stroke) and ``rear_mm`` (rear wheel
    travel), mm from full extension, compression positive, one row per sample on a uniform time
    grid (each step within 1 % of the median; the sample rate is its inverse). Rear wheel travel
    comes from the shock's stroke through ``leverage`` when only ``shock_mm`` is given, and the
    shock's stroke from the wheel's when only ``rear_mm`` is. Lines starting with ``#`` are comments.
    Every problem is one ``TelemetryError`` line naming the file and the line."""
    import csv

    from mtbmj.textfile import read_text

    name = str(path)
    text = read_text(Path(path), TelemetryError, name, "not a text file, so not a travel CSV", kind="telemetry")
    rows = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise TelemetryError(f"{name}: no header (expected time_s and one or more of fork_mm, shock_mm, rear_mm)")
    # the separator as the record reader finds it (a comma, or a spreadsheet's semicolon or tab); names
    # in any case (Fork_mm); a separator closing every row (a spreadsheet's empty last column) dropped
    delimiter = delimiter_of(rows[0][1])
    header_line, header = rows[0][0], [h.strip() for h in next(csv.reader([rows[0][1]], delimiter=delimiter))]
    closed = len(header) > 1 and header[-1] == ""
    header = [h.lower() if h.lower() in CSV_COLUMNS else h for h in header[:len(header) - closed]]
    unknown = [h for h in header if h not in CSV_COLUMNS]
    if unknown:
        from mtbmj.output import read_record

        wrote = read_record(Path(path).parent) or {}  # a file of an mtbmj output folder (reconstruct's series.csv)
        ours = Path(path).name in wrote.get("files", ())
        raise TelemetryError(f"{name}: line {header_line}: unknown column {unknown[0]!r} (known: {', '.join(CSV_COLUMNS)})"
                             + (f"; it is what mtbmj {wrote.get('command')} wrote, not a ride" if ours else ""))
    if len(set(header)) != len(header):
        twice = next(column for column in header if header.count(column) > 1)
        raise TelemetryError(f"{name}: line {header_line}: the column {twice} is named twice")
    if "time_s" not in header or len(header) < 2:
        raise TelemetryError(f"{name}: line {header_line}: needs time_s and one or more of fork_mm, shock_mm, rear_mm")
    values = np.empty((len(rows) - 1, len(header)))
    for k, (line_no, line) in enumerate(rows[1:]):
        cells = next(csv.reader([line], delimiter=delimiter))
        if closed and len(cells) == len(header) + 1 and not cells[-1].strip():
            cells = cells[:-1]
        if len(cells) != len(header):
            raise TelemetryError(f"{name}: line {line_no}: {len(cells)} values for {len(header)} columns")
        for j, cell in enumerate(cells):
            try:
                x = float(cell)
            except ValueError:
                comma = "," in cell and parses_as_number(cell.replace(",", "."))
                raise TelemetryError(f"{name}: line {line_no}: {header[j]} is not a number: {cell.strip()!r}"
                                     + (" (a decimal comma? write the point: " + cell.strip().replace(",", ".") + ")"
                                        if comma else "")) from None
            if not math.isfinite(x):
                raise TelemetryError(f"{name}: line {line_no}: {header[j]} is not finite: {cell.strip()!r}")
            values[k, j] = x
    if values.shape[0] < 2:
        raise TelemetryError(f"{name}: fewer than 2 samples")
    t = values[:, header.index("time_s")]
    dt = np.diff(t)
    step = float(np.median(dt))
    if not step > 0.0:
        raise TelemetryError(f"{name}: time_s does not increase")
    off = np.flatnonzero(np.abs(dt - step) > CSV_JITTER * step)
    if off.size:
        i = int(off[0])
        raise TelemetryError(f"{name}: line {rows[i + 2][0]}: time_s steps {dt[i]:g} s where the record steps "
                             f"{step:g} s (a uniform time grid is needed)")
    _check_csv_time(name, step)
    for label, value in (("fork_max_mm", fork_max_mm), ("shock_max_mm", shock_max_mm)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise TelemetryError(f"{name}: {label} must be a positive number of mm, got {value!r}")
    column = {h: values[:, j] for j, h in enumerate(header)}
    travel_max = {"fork_mm": float(fork_max_mm), "shock_mm": float(shock_max_mm),
                  "rear_mm": float(leverage.wheel_travel_mm(shock_max_mm))}
    travel_columns = tuple(h for h in header if h != "time_s")
    for h in travel_columns:
        _check_csv_travel(name, h, column[h], travel_max[h])
    if all(np.ptp(column[h]) == 0.0 for h in travel_columns):
        held = ", ".join(f"{h} {column[h][0]:g}" for h in travel_columns)
        raise TelemetryError(f"{name}: no column moved ({held} mm over all {t.size} samples): a missing or stuck "
                             f"sensor, nothing to read")
    fork, shock, rear = column.get("fork_mm"), column.get("shock_mm"), column.get("rear_mm")
    notes = ("a travel CSV (version 0): the logger's own calibration",)
    if rear is None and shock is not None:
        rear = leverage.wheel_travel_mm(shock)
    elif shock is None and rear is not None:
        shock = leverage.stroke_mm(rear)
    elif shock is not None:  # both given: each is read as given, so they should be one motion through the leverage
        miss = np.abs(leverage.wheel_travel_mm(shock) - rear)
        worst = int(np.argmax(miss))
        if miss[worst] > max(CSV_BOTH_MM, CSV_BOTH_SHARE * travel_max["rear_mm"]):
            notes += (f"shock_mm and rear_mm disagree through the leverage curve they are read with: at "
                      f"{t[worst]:g} s the shock's {shock[worst]:.1f} mm is {leverage.wheel_travel_mm(shock[worst]):.1f} "
                      f"mm of wheel travel where rear_mm says {rear[worst]:.1f}; each end is read from its own column "
                      f"(give one of them to have the other follow the bike's leverage)",)
    rate = 1.0 / step
    return TelemetryRecord(
        path=name, version=0, sample_rate_Hz=rate, timestamp=0, time_s=np.arange(t.size) / rate, fork_mm=fork,
        shock_mm=shock, rear_mm=rear, fork_max_mm=float(fork_max_mm), shock_max_mm=float(shock_max_mm),
        rear_max_mm=float(leverage.wheel_travel_mm(shock_max_mm)), notes=notes, columns=travel_columns)


MILLI = 1000.0


def _check_csv_time(name: str, step: float) -> None:
    """A travel CSV's time step as a suspension logger's (``SAMPLE_RATE_HZ``), or one line naming
    time_s, its step, and the unit it most likely is in (milliseconds where seconds are read)."""
    rate = 1.0 / step
    low, high = SAMPLE_RATE_HZ
    if low <= rate <= high:
        return
    hint = ""
    if low <= rate * MILLI <= high:
        hint = f": time in milliseconds? (time_s is in seconds: {rate * MILLI:g} Hz if so)"
    elif low <= rate / MILLI <= high:
        hint = f": time in kiloseconds? ({rate / MILLI:g} Hz if so)"
    raise TelemetryError(f"{name}: time_s steps {step:g} s, a sample rate of {rate:g} Hz, outside what a suspension "
                         f"logger records ({low:g}-{high:g} Hz){hint}")


METRES_MM = 1.0  # a travel column all within +-1 mm: no ride moves a suspension so little; metres, read as mm
FLIPPED_PERCENT = 5.0  # below -5 % of the travel: not a sensor's offset at full extension, but rebound read as compression


def _check_csv_travel(name: str, column: str, values: np.ndarray, travel_max_mm: float) -> None:
    """One ``TelemetryError`` line naming the column and the evidence for a travel column in metres
    (moving, but never beyond +-1 mm) or sign-flipped (more than half of it below -5 % of its
    travel). A constant column (a stuck sensor) is said by ``quality``."""
    span = float(np.ptp(values))
    largest = float(np.max(np.abs(values)))
    if 0.0 < span and largest <= METRES_MM:
        raise TelemetryError(f"{name}: {column} never leaves +-{METRES_MM:g} (largest {largest:.4g}, over "
                             f"{values.size} samples): metres? (the column is mm of travel)")
    floor = -FLIPPED_PERCENT / 100.0 * travel_max_mm
    below = float(np.mean(values < floor))
    if below > 0.5:
        raise TelemetryError(f"{name}: {column} is below {floor:.1f} mm for {100 * below:.0f} % of the samples "
                             f"(down to {float(np.min(values)):.1f} mm): sign-flipped? (travel is mm from full "
                             f"extension, compression positive)")


def read_ride(path: str | Path, **decoding) -> TelemetryRecord:
    """An SST file (versions 2 and 3) or a travel CSV: by its ``.csv`` suffix, or by its text where
    another name was given to one (``ride.SST`` holding ``time_s,fork_mm,...``: it was refused as
    "not an SST file")."""
    if Path(path).suffix.lower() != ".csv":
        try:
            return read_sst(path, **decoding)
        except NotAnSST as exc:
            if not exc.text:
                raise
    keep = {k: v for k, v in decoding.items() if k in ("fork_max_mm", "shock_max_mm", "leverage")}
    return read_travel_csv(path, **keep)


def both_ends(record) -> str | None:
    """Why ``record`` cannot be read end against end (the fork's travel giving the terrain the rear is checked on:
    ``reconstruct``, ``advise``), in words; None where it can. An end missing from the file, or one whose travel
    never moves (a sensor unplugged, stuck or saturated: 0 mm all the ride reads as no terrain at all)."""
    if record.fork_mm is None or record.rear_mm is None:
        return "needs both ends' records (the rear meets what the front met)"
    for column, label, travel in ((0, "fork", record.fork_mm), (1, "rear", record.rear_mm)):  # rear: the wheel's mm
        if np.ptp(travel) == 0.0:
            counts = getattr(record, "counts", None)
            count = f", count {int(counts[0, column])}" if counts is not None else ""
            return (f"the {label}'s travel never moves ({float(travel[0]):g} mm{count} over all {travel.size} "
                    f"samples): its sensor unplugged, stuck or saturated; the terrain is read from the fork and "
                    f"checked on the rear, both moving")
    return None


SHORT_RIDE_S = 30.0  # a ride shorter than this has histograms that have not settled
SATURATED_FRACTION = 0.005  # samples at an encoder's end beyond this share: the sensor saturated


def quality(record: TelemetryRecord) -> list[str]:
    """One line for each thing about the ride a reader of its metrics should know: too short, a
    sensor missing or stuck, a sensor at its end of range for more than 0.5 % of the ride."""
    out = [f"{record.name}: {note}" for note in record.notes]
    if record.duration_s < SHORT_RIDE_S:
        out.append(f"{record.name}: the ride is {record.duration_s:.1f} s, shorter than {SHORT_RIDE_S:g} s: its "
                   f"histograms and percentiles rest on few compressions")
    for column, label, travel in ((0, "fork", record.fork_mm), (1, "shock", record.shock_mm)):
        if travel is None:
            out.append(f"{record.name}: no {label} sensor in this file: its end is left out")
            continue
        counts = record.counts[:, column] if record.counts is not None else None
        if counts is not None and int(counts.max()) == int(counts.min()):
            out.append(f"{record.name}: the {label} sensor never moved: missing or stuck; its end's metrics say nothing")
            continue
        # a travel CSV: the column its end was given as (the rear as rear_mm or shock_mm)
        given = [c for c in record.columns if c == f"{label}_mm" or (label == "shock" and c == "rear_mm")]
        held = [c for c in given if np.ptp(getattr(record, c)) == 0.0]
        if held:
            c = held[0]
            out.append(f"{record.name}: {c} is constant at {float(getattr(record, c)[0]):g} mm over all "
                       f"{record.time_s.size} samples: a missing or stuck sensor; its end's metrics say nothing")
            continue
        if counts is not None and record.version == 3:
            # count 0 is full extension (topped out, a normal place to be); the encoder's last count
            # is where a sensor that runs out of range stays
            at_end = float(np.mean(counts >= COUNTS - 1))
            if at_end > SATURATED_FRACTION:
                out.append(f"{record.name}: the {label} sensor sits at the end of its range for {100 * at_end:.1f} % "
                           f"of the ride: saturated (its calibration or mounting?)")
    return out + held_tail(record)


# An end's travel held at one value over at least this long at the end of a ride, while the other end moves, is a
# sensor unplugged (or stuck) partway. The shipped rides' longest such tails are 4.05 s (00098.SST's shock, the fork
# moving for 2 s of it) and 3.52 s (00643.SST's shock, version 3): a rider rolling to a stop before the recording
# ends; a stop with the rider off the bike holds both ends (00094.SST: 25 s at 0 mm mid-ride), not warned about.
HELD_TAIL_S = 5.0
# ... while the other end moves on this long into it: a rider who stops settles one end a second or two after the
# other (00094's first 50 s: 1.3 s; the shipped rides' other ends move at most 2.75 s into a held tail)
HELD_MOVING_S = 3.0


def held_tail(record: TelemetryRecord) -> list[str]:
    """One line for each end whose travel reads one value from some time to the end of the ride, for at least
    ``HELD_TAIL_S``, while the other end moves on ``HELD_MOVING_S`` into that stretch or more: its sensor
    unplugged or stuck partway, what the ride reads of that end after then false. (An end that never moves is ``quality``'s line and ``both_ends``'
    refusal; a record of one end is not judged: a stop cannot be told from a sensor held.)"""
    rear = ("shock", record.shock_mm) if record.shock_mm is not None else ("rear", record.rear_mm)
    ends = [("fork", record.fork_mm), rear]
    out = []
    for k, (label, travel) in enumerate(ends):
        other = ends[1 - k][1]
        if travel is None or other is None or travel.size < 2 or np.ptp(travel) == 0.0:
            continue
        start = int(np.flatnonzero(np.diff(travel) != 0.0)[-1]) + 1  # the first sample of the held stretch
        seconds = (travel.size - start) / record.sample_rate_Hz
        moved = np.flatnonzero(np.diff(other) != 0.0)  # the other end moving on HELD_MOVING_S into the stretch or
        # more: two ends that settle a second apart as the rider stops are a stop, not a sensor (00094's first 50 s)
        if seconds >= HELD_TAIL_S and moved.size and (moved[-1] + 2 - start) / record.sample_rate_Hz >= HELD_MOVING_S:
            out.append(f"{record.name}: the {label}'s travel holds at {float(travel[start]):.1f} mm from "
                       f"{float(record.time_s[start]):.1f} s to the end (the last {seconds:.1f} s, "
                       f"{100.0 * seconds / record.duration_s:.0f} % of the ride) while the "
                       f"{ends[1 - k][0]}'s moves: its sensor unplugged or stuck partway; what the ride reads of "
                       f"the {label} after {float(record.time_s[start]):.1f} s is false")
    return out


TRAVEL_MARGIN_PERCENT = 5.0  # a calibrated record (v3, a CSV) may read this far past the bike's travel
# A version-2 record's amplitudes rest on the recording project's placeholder calibration: the
# shipped 00100.SST reads its own bike's 180 mm fork to 191 mm (6 % beyond); up to this far past,
# the record is read with a warning, beyond it refused like any other.
V2_TRAVEL_MARGIN_PERCENT = 15.0


def beyond_travel(record: TelemetryRecord, fork_key: str = "fork_max_mm", shock_key: str = "shock_max_mm") -> list[str]:
    """The record against the travel it is read with (``fork_max_mm``, ``shock_max_mm``, named in
    messages as ``fork_key``/``shock_key``: the key the user set): a fork or shock that travels
    further than ``TRAVEL_MARGIN_PERCENT`` past it is another bike's ride (or another calibration),
    and every percentage of travel, bottom-out count and reconstruction from it would be false, so
    it is one ``TelemetryError`` line. A version-2 record within ``V2_TRAVEL_MARGIN_PERCENT`` gets a
    warning (returned) instead: its amplitudes are known approximate."""
    out = []
    for label, travel, limit, key in (("fork", record.fork_mm, record.fork_max_mm, fork_key),
                                      ("shock", record.shock_mm, record.shock_max_mm, shock_key)):
        if travel is None:
            continue
        deepest = float(np.max(travel))
        over = 100.0 * (deepest / limit - 1.0)
        if over <= TRAVEL_MARGIN_PERCENT:
            continue
        wheel = f" (rear wheel {float(np.max(record.rear_mm)):.1f} mm)" if label == "shock" and \
            record.rear_mm is not None else ""
        what = (f"{record.name}: the {label} {'travels' if label == 'fork' else 'strokes'} {deepest:.1f} mm{wheel}, "
                f"{over:.1f} % beyond {limit:g} mm ({key})")
        if record.version == 2 and over <= V2_TRAVEL_MARGIN_PERCENT:
            out.append(f"{what}: within the version-2 calibration's uncertainty; its percentages of travel are "
                       f"approximate")
            continue
        raise TelemetryError(f"{what}: a ride of another bike or another calibration; read it with the recorded "
                             f"bike's travel")
    return out


def repeated_samples(records) -> tuple[int, int] | None:
    """(first, k): the first record of ``records`` (read SST records) whose samples (rate and counts)
    repeat an earlier one's, the file given twice or copied under another name; None where none does."""
    seen = {}
    for k, record in enumerate(records):
        first = seen.setdefault((record.sample_rate_Hz, record.counts.tobytes()), k)
        if first != k:
            return first, k
    return None


def example_path() -> Path:
    """The shipped ride recording (00649.SST, MIT, from the Sufni Suspension Telemetry project)."""
    return Path(str(resources.files("mtbmj") / "data" / "sst" / "00649.SST"))


def ride_path(ride) -> Path:
    """The file a user's ride name means: "example" in any case (when no such file exists) is the
    shipped ride, anything else a path as given. The one place commands resolve the name."""
    text = str(ride)
    if text.lower() == "example" and not Path(text).exists():
        return example_path()
    return Path(text)

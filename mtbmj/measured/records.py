"""Bench and drop records: CSV with units in the column names, or a MATLAB .mat export.

A CSV record has optional comment lines starting with ``#`` (a line ``# synthetic ...`` marks a
generated record), one header row, then numbers; the delimiter is ``,``, ``;`` or a tab, found
from the header (a trailing one on the header, as a spreadsheet writes on every line, is no column).
Every column name ends in its unit (``displacement_mm``, ``force_N``, ``velocity_mm_per_s``,
``time_s``); values are converted to SI on reading. A .mat file holds one
1-D numeric variable per column under the same unit-suffixed names.
"""
from __future__ import annotations

import csv
import io
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mtbmj.errors import MtbmjError
from mtbmj.textfile import delimiter_of, other_case, parses_as_number, read_bytes, read_text

# unit suffix -> factor to SI
UNITS = {
    "s": 1.0, "ms": 1e-3,
    "mm": 1e-3, "m": 1.0,
    "N": 1.0, "kN": 1e3,
    "mm_per_s": 1e-3, "m_per_s": 1.0,
    "N_per_mm": 1e3, "N_per_m": 1.0,
    "kg": 1.0, "Hz": 1.0,
}
# longest first, so "mm_per_s" wins over "s"
_SUFFIXES = sorted(UNITS, key=len, reverse=True)


class RecordError(MtbmjError, ValueError):
    """A record file cannot be used: says which file, line or column. An input error: a ``ValueError``
    too, as ``ConfigError`` is."""


def split_unit(name: str) -> tuple[str, str] | None:
    """``displacement_mm`` -> (``displacement``, ``mm``); None when no known unit ends the name. A
    name in another case (``Displacement_MM``, ``force_n``: a spreadsheet's) is read as the known one
    (quantity in lower case, the unit as :data:`UNITS` spells it): no two units differ only in case."""
    for unit in _SUFFIXES:  # a rate's tail is no unit of its own (speed_ft_per_s is not a speed_ft_per in s)
        if (name.endswith("_" + unit) and len(name) > len(unit) + 1
                and not name[: -len(unit) - 1].lower().endswith("_per")):
            return name[: -len(unit) - 1], unit
    for unit in _SUFFIXES:
        if (name.lower().endswith("_" + unit.lower()) and len(name) > len(unit) + 1
                and not name[: -len(unit) - 1].lower().endswith("_per")):
            return name[: -len(unit) - 1].lower(), unit
    return None


@dataclass(frozen=True)
class Record:
    """Columns in SI keyed by quantity (``displacement``, ``force``, ``time`` ...)."""

    path: str
    columns: dict[str, np.ndarray]
    units: dict[str, str]  # quantity -> unit as written in the file
    comments: tuple[str, ...] = field(default=())

    @property
    def synthetic(self) -> bool:
        return any("synthetic" in c.lower() for c in self.comments)

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def __getitem__(self, quantity: str) -> np.ndarray:
        return self.columns[quantity]

    def require(self, *quantities: str, min_points: int = 10) -> "Record":
        """Check the quantities are present; the message names what the file has instead."""
        missing = [q for q in quantities if q not in self.columns]
        if missing:
            have = ", ".join(f"{q}_{self.units[q]}" for q in self.columns) or "none"
            raise RecordError(f"{self.path}: missing column {missing[0]}_<unit> (columns: {have})")
        if len(self) < min_points:
            raise RecordError(f"{self.path}: too few points ({len(self)}, need at least {min_points})")
        if "time" in self.columns:
            steps = np.diff(self.columns["time"])
            if np.any(steps <= 0):
                i = int(np.argmax(steps <= 0)) + 1
                raise RecordError(f"{self.path}: time is not increasing at row {i + 1} of the data")
        return self


def _unit_written(name: str) -> str:
    """The unit a column name ends in as written, a rate whole (``speed_km_per_h``: ``km_per_h``, not ``h``)."""
    parts = name.strip("_").split("_")
    per = [k for k, p in enumerate(parts) if p.lower() == "per" and 1 < k < len(parts) - 1]
    return "_".join(parts[per[-1] - 1:]) if per else parts[-1]


def _convert(path: str, names: list[str], data: np.ndarray, comments=()) -> Record:
    columns, units = {}, {}
    for j, name in enumerate(names):
        parsed = split_unit(name)
        if parsed is None and "_" in name.strip("_"):
            raise RecordError(f"{path}: column {name!r}: unit {_unit_written(name)!r} is not one mtbmj reads "
                              f"({', '.join(UNITS)}); convert the column and name it so")
        if parsed is None:
            raise RecordError(f"{path}: column {name!r} has no unit in its name (e.g. displacement_mm, force_N)")
        quantity, unit = parsed
        if quantity in columns:
            raise RecordError(f"{path}: column {quantity} appears twice")
        values = np.asarray(data[:, j], dtype=float) * UNITS[unit]
        columns[quantity] = values
        units[quantity] = unit
    return Record(path, columns, units, tuple(comments))


def read_csv(path: str | Path) -> Record:
    path = Path(path)
    text = read_text(path, RecordError, str(path), "not a text file, so not a CSV record", "record")
    comments, lines = [], []
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped.lstrip("#").strip())
            continue
        lines.append((number, line))
    if not lines:
        raise RecordError(f"{path}: no header row and no data")
    header_line = lines[0][1]
    delimiter = delimiter_of(header_line)
    if header_line.count(delimiter) == 0 and len(header_line.split()) > 1:
        raise RecordError(f"{path}: line {lines[0][0]}: columns must be separated by ',', ';' or a tab")
    names = [n.strip() for n in next(csv.reader([header_line], delimiter=delimiter))]
    if len(names) > 1 and names[-1] == "":  # a spreadsheet's trailing delimiter on every line: no column
        names = names[:-1]
        lines = lines[:1] + [(n, _without_trailing(line, delimiter)) for n, line in lines[1:]]
    table = _numbers(lines[1:], delimiter, len(names))
    if table is not None:
        return _convert(str(path), names, table, comments)
    rows = []  # a record the fast reader refuses: read line by line, to name the line at fault
    for number, line in lines[1:]:
        cells = [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]
        if len(cells) != len(names):
            raise RecordError(f"{path}: line {number}: {len(cells)} cells for {len(names)} columns")
        try:
            values = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not parses_as_number(c))
            raise RecordError(f"{path}: line {number}: {bad!r} is not a number") from None
        if not all(math.isfinite(v) for v in values):
            raise RecordError(f"{path}: line {number}: NaN or infinite value")
        rows.append(values)
    if not rows:
        raise RecordError(f"{path}: header but no data rows")
    return _convert(str(path), names, np.array(rows), comments)


def _without_trailing(line: str, delimiter: str) -> str:
    """A data line without one trailing delimiter (and what blank follows it): a row's empty last cell."""
    text = line.rstrip(" \r\n")
    return text[:-1] if text.endswith(delimiter) else line


def _numbers(lines: list[tuple[int, str]], delimiter: str, width: int) -> np.ndarray | None:
    """The data rows as a (rows, width) float array, parsed at once by numpy's reader (a dyno record
    of 29 000 lines in about 50 ms instead of 0.56 s line by line); None when it would need a word about
    a line: no rows, a row of another width, a cell numpy does not read as a plain number (quoted,
    ``1_000``, text), NaN or infinity. The line-by-line reader then finds that line and says what
    is wrong with it; every record this returns, it reads to the same values."""
    if not lines:
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy warns on an empty input instead of raising
            table = np.loadtxt(io.StringIO("\n".join(line for _, line in lines)), dtype=float,
                               delimiter=delimiter, comments=None, ndmin=2, quotechar=None)
    except (ValueError, Warning):  # any warning made an error above: the line-by-line reader decides
        return None
    if table.shape != (len(lines), width) or not np.isfinite(table).all():
        return None
    return table


def read_mat(path: str | Path) -> Record:
    from scipy.io import loadmat

    path = Path(path)
    blob = read_bytes(path, RecordError, str(path), "record")
    try:
        content = loadmat(io.BytesIO(blob), squeeze_me=True)
    except Exception as exc:  # scipy raises several types for a file that is not MAT
        raise RecordError(f"{path}: not a readable MATLAB .mat file ({type(exc).__name__})") from None
    names = [k for k in content if not k.startswith("__")]
    comments = []
    arrays = {}
    for name in names:
        value = content[name]
        if isinstance(value, str):
            comments.append(value)
            continue
        array = np.asarray(value)
        if array.dtype.kind not in "fiu" or array.ndim != 1:
            continue
        arrays[name] = array.astype(float)
    if not arrays:
        raise RecordError(f"{path}: no 1-D numeric variables")
    lengths = {len(a) for a in arrays.values()}
    if len(lengths) != 1:
        raise RecordError(f"{path}: variables have different lengths {sorted(lengths)}")
    if not all(np.all(np.isfinite(a)) for a in arrays.values()):
        raise RecordError(f"{path}: NaN or infinite value")
    names = list(arrays)
    return _convert(str(path), names, np.column_stack([arrays[n] for n in names]), comments)


def read_record(path: str | Path) -> Record:
    """Read a CSV or .mat record (by extension; anything but .mat is read as CSV)."""
    path = Path(path)
    if not path.exists():
        raise RecordError(f"{path}: no such file{other_case(path)}")
    return read_mat(path) if path.suffix.lower() == ".mat" else read_csv(path)


def write_csv_text(columns: dict[str, np.ndarray], comments=()) -> str:
    """CSV text of unit-suffixed columns (values already in the unit of each name)."""
    out = io.StringIO()
    for c in comments:
        out.write(f"# {c}\n")
    names = list(columns)
    out.write(",".join(names) + "\n")
    np.savetxt(out, np.column_stack([np.asarray(columns[n], float) for n in names]), delimiter=",", fmt="%.9g")
    return out.getvalue()

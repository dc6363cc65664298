"""Reading a user's input file (configuration, record, variant table, telemetry) or failing with
one line that names the file and the cause.

Only regular files are read: a FIFO, a device (``/dev/zero``) or a socket is refused without
waiting on it (the file is opened non-blocking and checked before any byte is read), and so is a
file larger than the limit of its kind (:data:`LIMITS`), before it is read into memory.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

MiB = 1 << 20

# The largest file of each kind that is read, in bytes: far above any real one (a 10-minute
# 1 kHz sled record is a few MB of CSV, ten minutes of a 10 kHz dyno about 200 MB; an hour of
# SST telemetry at 1 kHz about 15 MB), and small enough that what is built from it fits in memory.
LIMITS = {
    "config": 1 * MiB,
    "table": 64 * MiB,     # --from-csv variant tables
    "record": 256 * MiB,   # CSV or .mat records for fits, validation and terrain profiles
    "telemetry": 256 * MiB,
}


def other_case(path: Path) -> str:
    """`` (there is NAME)`` where the name, or a folder on its way, is there in another case (``ride.sst``
    typed for ``ride.SST``, ``REC/TERRAIN.CSV`` for ``rec/terrain.csv``); where the name is a symbolic link that
    leads nowhere, `` (NAME is a symbolic link to TARGET, a loop of links)`` or ``…, which is not there)``; else
    ``""``."""
    path = Path(path)
    if path.is_symlink():  # a loop was "no such file", the file a user made in plain sight
        try:
            os.stat(path)
        except OSError as exc:
            import errno

            why = "a loop of links" if exc.errno == errno.ELOOP else "which is not there"
            return f" ({path} is a symbolic link to {os.readlink(path)}, {why})"
    found = Path(path.anchor) if path.anchor else Path()
    for part in path.parts[len(Path(path.anchor).parts) if path.anchor else 0:]:
        if part in ("", ".", "..") or (found / part).exists():
            found = found / part
            continue
        try:
            names = sorted(p.name for p in found.iterdir() if p.name.lower() == part.lower())
        except OSError:
            return ""
        if not names:
            return ""
        found = found / names[0]
    return f" (there is {found})" if found != path else ""


def read_bytes(path: Path, error: type[Exception], label: str, kind: str) -> bytes:
    """The bytes of a regular file of at most ``LIMITS[kind]`` bytes, or ``error(one line)``."""
    limit = LIMITS[kind]
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except IsADirectoryError:
        raise error(f"{label}: is a directory, not a file") from None
    except FileNotFoundError as exc:
        raise error(f"{label}: cannot read ({exc.strerror}){other_case(Path(path))}") from None
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror})") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise error(f"{label}: is a directory, not a file")
        if not stat.S_ISREG(info.st_mode):
            raise error(f"{label}: not a regular file (a pipe, device or socket is not read)")
        if info.st_size > limit:
            raise error(f"{label}: too large ({info.st_size / MiB:.1f} MiB; the limit for a {kind} file is "
                        f"{limit / MiB:g} MiB)")
        chunks, size = [], 0
        while True:
            chunk = os.read(fd, min(limit + 1 - size, 1 << 24))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
            if size > limit:  # grew while being read
                raise error(f"{label}: too large (over the limit of {limit / MiB:g} MiB for a {kind} file)")
        return b"".join(chunks)
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror})") from None
    finally:
        os.close(fd)


def read_text(path: Path, error: type[Exception], label: str, not_text: str, kind: str = "config") -> str:
    """The file's text; ``error(f"{label}: cannot read (...)")`` when it cannot be read (see
    :func:`read_bytes` for what is refused) and ``error(f"{label}: {not_text}")`` when it is not
    text (not UTF-8, or holding NUL bytes). A UTF-8 byte-order mark at the start (Excel's and
    Notepad's "UTF-8" saving) is not part of the text: it would otherwise stick to the first column's
    name or the first TOML key."""
    blob = read_bytes(Path(path), error, label, kind)
    try:
        text = blob.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise error(f"{label}: {not_text}") from None
    if "\x00" in text:
        raise error(f"{label}: {not_text}")
    return text.replace("\r\n", "\n").replace("\r", "\n")  # universal newlines, as open() reads


def run_file_text(path: Path, error: type[Exception], kind: str) -> str:
    """A file of a run folder that mtbmj wrote (manifest, summary, time series), read as
    :func:`read_text` reads a user's file: a FIFO or device in its place is refused, not waited on."""
    return read_text(Path(path), error, str(path), "not a text file", kind)


def number_table(text: str, label: str, error: type[Exception]) -> tuple:
    """(column names, rows) of a comma-separated table that mtbmj wrote (a run folder's
    ``timeseries.csv``; ``#`` lines and blank lines skipped), or ``error`` in one line naming the
    line at fault: a file edited or cut short since (a spreadsheet's semicolons, a value that is not
    a number, a row cut off) is said as such, not as numpy's or Python's own message."""
    import numpy as np

    lines = [(n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip() and not line.startswith("#")]
    if not lines:
        raise error(f"{label}: empty")
    names = [c.strip() for c in lines[0][1].split(",")]
    try:  # numpy's reader at once; line by line only to name the line it stopped at
        rows = np.loadtxt([line for _, line in lines[1:]], delimiter=",", ndmin=2, comments=None)
    except ValueError:
        rows = None
    if rows is not None and (rows.shape[1] == len(names) or rows.size == 0):
        return names, rows.reshape(-1, len(names))
    for number, line in lines[1:]:
        cells = line.split(",")
        if len(cells) != len(names):
            raise error(f"{label}: line {number}: {len(cells)} values for {len(names)} columns")
        bad = [c for c in cells if not parses_as_number(c)]
        if bad:
            raise error(f"{label}: line {number}: {bad[0].strip()!r} is not a number")
    raise error(f"{label}: not a table of numbers")  # not reached: a line above is at fault


def delimiter_of(header: str) -> str:
    """A table's separator as its header line shows it: a comma, or a spreadsheet's semicolon or tab."""
    return max((",", ";", "\t"), key=header.count)


def parses_as_number(text: str) -> bool:
    """Whether ``float(text)`` reads ``text`` (a table's cell)."""
    try:
        float(text)
        return True
    except ValueError:
        return False

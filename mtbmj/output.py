"""Writing results atomically: every file goes to a temporary name in the target directory and
is renamed into place only once all of them are written, so a failed run leaves nothing behind."""
from __future__ import annotations

import io
import json
import os
import tempfile
from pathlib import Path
from typing import Mapping

import numpy as np

from mtbmj.errors import MtbmjError


CSV_CHUNK_ROWS = 20000  # rows formatted at a time when a CSV is streamed to its file


def csv_chunks(columns: Mapping[str, np.ndarray], header: str = "", rows: int = CSV_CHUNK_ROWS):
    """The CSV text of ``columns`` (name -> values) as bytes chunks of ``rows`` rows each, so a
    long run is written without its whole text in memory; joined, they are ``csv_bytes``."""
    names = list(columns)
    arrays = [np.asarray(columns[n], dtype=float) for n in names]
    lines = [f"# {line}\n" for line in header.splitlines()] if header else []
    yield ("".join(lines) + ",".join(names) + "\n").encode()
    n = len(arrays[0]) if arrays else 0
    for start in range(0, n, rows):
        buffer = io.StringIO()
        np.savetxt(buffer, np.column_stack([a[start: start + rows] for a in arrays]), delimiter=",", fmt="%.9g")
        text = buffer.getvalue()
        buffer.close()  # savetxt leaves a reference cycle to the buffer: free its text now, not at the next GC
        yield text.encode()


def csv_bytes(columns: Mapping[str, np.ndarray], header: str = "") -> bytes:
    return b"".join(csv_chunks(columns, header))


def json_bytes(data) -> bytes:
    return (json.dumps(data, indent=2, sort_keys=False) + "\n").encode()


def write_atomically(out_dir: str | Path, files: Mapping[str, bytes]) -> list[Path]:
    """Write ``files`` (name -> content) into ``out_dir``: all of them or none. A content is
    bytes or an iterable of bytes chunks (written as they come, e.g. ``csv_chunks``)."""
    out = Path(out_dir)
    created_dir = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MtbmjError(f"{out}: cannot create output directory ({exc.strerror})") from None
    staged: list[tuple[str, Path]] = []
    try:
        for name, content in files.items():
            target = out / name
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
            staged.append((tmp, target))  # before writing: a failed write must be cleaned up too
            with os.fdopen(fd, "wb") as handle:
                if isinstance(content, (bytes, bytearray, memoryview)):
                    handle.write(content)
                else:
                    for chunk in content:
                        handle.write(chunk)
        for tmp, target in staged:
            os.replace(tmp, target)
    except OSError as exc:
        for tmp, _ in staged:
            Path(tmp).unlink(missing_ok=True)
        if created_dir:
            _remove_empty(out)
        raise MtbmjError(f"{out}: cannot write results ({exc.strerror})") from None
    return [target for _, target in staged]


def _remove_empty(path: Path) -> None:
    try:
        path.rmdir()
    except OSError:
        pass

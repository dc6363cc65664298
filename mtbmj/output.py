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


def csv_bytes(columns: Mapping[str, np.ndarray], header: str = "") -> bytes:
    names = list(columns)
    table = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    buffer = io.StringIO()
    if header:
        for line in header.splitlines():
            buffer.write(f"# {line}\n")
    buffer.write(",".join(names) + "\n")
    np.savetxt(buffer, table, delimiter=",", fmt="%.9g")
    return buffer.getvalue().encode()


def json_bytes(data) -> bytes:
    return (json.dumps(data, indent=2, sort_keys=False) + "\n").encode()


def write_atomically(out_dir: str | Path, files: Mapping[str, bytes]) -> list[Path]:
    """Write ``files`` (name -> content) into ``out_dir``: all of them or none."""
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
                handle.write(content)
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

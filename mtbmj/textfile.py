"""Reading a user's text input file (configuration, record, variant table) or failing with one
line that names the file and the cause."""
from __future__ import annotations

from pathlib import Path


def read_text(path: Path, error: type[Exception], label: str, not_text: str) -> str:
    """The file's text; ``error(f"{label}: cannot read (...)")`` when it cannot be read and
    ``error(f"{label}: {not_text}")`` when it is not text (not UTF-8)."""
    try:
        return Path(path).read_text()
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise error(f"{label}: {not_text}") from None

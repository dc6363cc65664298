"""Optional dependencies, grouped by the ``pip install 'mtbmj[EXTRA]'`` extra that brings them.

A command that needs an extra checks for it before it does any work (``require``), so a core
install gets one line naming the extra instead of a traceback after the computation."""
from __future__ import annotations

import importlib.util

from mtbmj.errors import MtbmjError

# import name -> distribution name, per extra (the extras of pyproject.toml)
EXTRAS: dict[str, dict[str, str]] = {
    "sweep": {"pandas": "pandas", "pyarrow": "pyarrow", "h5py": "h5py", "SALib": "SALib"},
    "dask": {"distributed": "dask[distributed]"},
    "video": {"imageio_ffmpeg": "imageio-ffmpeg"},
    "rl": {"dm_control": "dm-control"},
    "pandas": {"pandas": "pandas"},
}


class MissingExtra(MtbmjError):
    """An optional dependency is not installed; the message names the extra to install."""


def missing(modules) -> list[str]:
    """Those of ``modules`` (import names) that cannot be imported here."""
    out = []
    for name in modules:
        try:
            found = importlib.util.find_spec(name) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            out.append(name)
    return out


def require(extra: str, what: str, modules=None, otherwise: str | None = None) -> None:
    """Raise ``MissingExtra`` (one line: what needs it, the missing packages, the install command,
    and ``otherwise``, a way around it, if given) unless ``modules`` (default: all of ``extra``'s)
    can be imported."""
    table = EXTRAS[extra]
    absent = missing(table if modules is None else modules)
    if absent:
        names = ", ".join(table.get(m, m) for m in absent)
        tail = f", or {otherwise}" if otherwise else ""
        raise MissingExtra(f"{what} needs {names} (not installed): pip install 'mtbmj[{extra}]'{tail}")

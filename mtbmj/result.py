"""What every run result shares (signals by column, pandas export, the output folder) and the
versions written into each manifest."""
from __future__ import annotations

import platform
from pathlib import Path

import numpy as np

from mtbmj import output

def versions() -> dict[str, str]:
    from importlib.metadata import version

    import mujoco
    import scipy

    from mtbmj._version import __version__

    # matplotlib's version from its metadata: importing it only for that would make it look for a
    # writable config directory (a warning on stderr for a user without a home)
    return {"mtbmj": __version__, "mujoco": mujoco.__version__, "scipy": scipy.__version__,
            "numpy": np.__version__, "matplotlib": version("matplotlib"), "python": platform.python_version()}


class RunOutput:
    """What every run result shares: signals by column, pandas export, and the output directory
    (time series, raw trace, summary, manifest, configuration) written all at once. A subclass
    sets ``COLUMNS`` and provides ``csv_bytes`` and ``manifest``."""

    COLUMNS: tuple[str, ...] = ()

    @property
    def time(self) -> np.ndarray:
        return self.signals["time_s"]

    def __getitem__(self, column: str) -> np.ndarray:
        return self.signals[column]

    def to_pandas(self, raw: bool = False):
        """The logged (or raw) signals as a ``pandas.DataFrame`` indexed by time."""
        try:
            import pandas as pd
        except ImportError:  # pragma: no cover - pandas is an optional extra
            raise ImportError("to_pandas needs pandas: pip install 'mtbmj[pandas]'") from None
        data = self.raw if raw else self.signals
        return pd.DataFrame({k: data[k] for k in self.COLUMNS}).set_index("time_s")

    def files(self) -> dict[str, bytes]:
        """Everything ``write`` puts in an output directory."""
        return {
            "timeseries.csv": self.csv_bytes(),
            "timeseries_raw.csv": self.csv_bytes(raw=True),
            "summary.json": output.json_bytes(self.summary),
            "manifest.json": output.json_bytes(self.manifest()),
            "config.toml": self.config.to_toml().encode(),
        }

    def write(self, out_dir: str | Path) -> list[Path]:
        return output.write_atomically(out_dir, self.files())

"""What every run result shares (signals by column, pandas export, the output folder) and the
versions written into each manifest."""
from __future__ import annotations

import platform
from pathlib import Path

import numpy as np

from mtbmj import output

def versions() -> dict[str, str]:
    """Versions of mtbmj and the packages that shape its numbers. Read from the installed
    distributions' metadata: importing matplotlib only to read its version costs 0.1 s."""
    from importlib import metadata

    import mujoco
    import scipy

    from mtbmj._package import __version__

    try:
        matplotlib = metadata.version("matplotlib")
    except metadata.PackageNotFoundError:  # an optional extra
        matplotlib = None
    return {"mtbmj": __version__, "mujoco": mujoco.__version__, "scipy": scipy.__version__,
            "numpy": np.__version__, "matplotlib": matplotlib, "python": platform.python_version()}


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

    def csv_chunks(self, raw: bool = False):
        """The CSV as bytes chunks (``csv_bytes`` in one chunk unless a subclass streams it)."""
        yield self.csv_bytes(raw)

    def files(self, stream: bool = False, figure: bool = True) -> dict:
        """Everything ``write`` puts in an output directory (name -> bytes; with ``stream`` the
        engine-rate CSV is an iterable of chunks, so a long run is never all text in memory);
        ``figure``: the quick-look PNG (``quicklook``) too."""
        files = {
            "timeseries.csv": self.csv_bytes(),
            "timeseries_raw.csv": self.csv_chunks(raw=True) if stream else self.csv_bytes(raw=True),
            "summary.json": output.json_bytes(self.summary),
            "manifest.json": output.json_bytes(self.manifest()),
            "config.toml": self.config.to_toml().encode(),
        }
        if figure and hasattr(self, "quicklook"):
            from mtbmj.readout import quicklook

            files["quicklook.png"] = quicklook.png(self.quicklook())
        return files

    def write(self, out_dir: str | Path, figure: bool = True) -> list[Path]:
        """Write the output folder whole (``figure``: with ``quicklook.png``)."""
        return output.write_atomically(out_dir, self.files(stream=True, figure=figure))

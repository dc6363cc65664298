"""What every run result shares (signals by column, pandas export, the output folder) and the
versions written into each manifest."""
from __future__ import annotations

import functools
import hashlib
import platform
from pathlib import Path

import numpy as np

from mtbmj import limits, output
from mtbmj.errors import ConfigError

def _optional_version(name: str) -> str | None:
    from importlib import metadata

    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:  # an optional extra
        return None


# the packages whose sources make a result: installed from four folders of the repository
_SOURCE_PACKAGES = ("mtbmj", "mtbmj.controllers", "mtbmj.validation", "mtbmj.mjcf")


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """SHA-256 over the sources of mtbmj's packages (``_SOURCE_PACKAGES``: Python, the MJCF scenes,
    the presets), each file named by its package and path inside it, in sorted order: the code
    that made a result. Two installs with the same digest ran the same code; the version alone
    does not say so for an editable install or a checkout between releases. Read once a process
    (about 20 ms)."""
    from importlib import util

    h = hashlib.sha256()
    for name in _SOURCE_PACKAGES:
        spec = util.find_spec(name)
        for folder in (spec.submodule_search_locations or []) if spec else []:
            root = Path(folder)
            files = sorted(p for p in root.rglob("*") if p.suffix in (".py", ".xml", ".toml")
                           and "__pycache__" not in p.parts and p.is_file())
            for path in files:
                h.update(f"{name}/{path.relative_to(root).as_posix()}".encode() + b"\0")
                h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


def versions() -> dict[str, str]:
    """Versions of mtbmj and the packages that shape its numbers, and the digest of mtbmj's own
    sources (:func:`source_digest`). Read from the installed distributions' metadata: importing
    matplotlib or numba only to read its version costs 0.1-0.5 s."""
    import mujoco
    import scipy

    from mtbmj._package import __version__

    return {"mtbmj": __version__, "mtbmj_source_sha256": source_digest(), "mujoco": mujoco.__version__,
            "scipy": scipy.__version__, "numpy": np.__version__, "numba": _optional_version("numba"),
            "matplotlib": _optional_version("matplotlib"), "python": platform.python_version()}


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

    # the columns ``difference`` compares, and the key its largest |a - b| is given under
    COMPARED: tuple[str, ...] = ()
    DIFFERENCE_KEY = "max_abs"

    def csv_chunks(self, raw: bool = False):
        """The CSV as bytes chunks (``csv_bytes`` in one chunk unless a subclass streams it)."""
        yield self.csv_bytes(raw)

    def to_csv(self, path: str | Path, raw: bool = False) -> Path:
        """The time series (``timeseries.csv``'s content, or ``raw``: the engine-rate one where a rig
        keeps both) written to ``path`` whole, or not at all."""
        return output.write_file_atomically(Path(path), self.csv_chunks(raw))

    def difference(self, other: "RunOutput", raw: bool = True) -> dict[str, dict[str, float]]:
        """Largest |self - other| per compared column (``COMPARED``, in the column's unit) and when,
        over the samples both runs share at the engine rate (``raw``: the rows on the coarse grid
        where a run keeps finer rows in its fine stretches, ``grid_rows``) or the logged one; runs on
        different grids raise ValueError."""
        def on_grid(result):
            rows = getattr(result, "grid_rows", None)
            if rows is None:
                return result.raw
            return {k: np.asarray(v)[rows] for k, v in result.raw.items()}

        if not isinstance(other, RunOutput):  # None met "'NoneType' object has no attribute 'raw'"
            raise ConfigError(f"other: must be a run's result to difference with ({type(self).__name__}), got "
                              f"{limits.described(other)}")
        missing = [c for c in self.COMPARED if c not in other.raw]
        if missing:  # a RollResult beside a DropResult was "results are not on the same time grid"
            raise ConfigError(f"other: a {type(other).__name__} has no {missing[0]} to difference with this "
                              f"{type(self).__name__}'s; give a result of the same rig")
        a, b = (on_grid(self), on_grid(other)) if raw else (self.signals, other.signals)
        n = min(len(a["time_s"]), len(b["time_s"]))
        if not np.allclose(a["time_s"][:n], b["time_s"][:n], atol=1e-9):
            raise ValueError("results are not on the same time grid")
        out = {}
        for column in self.COMPARED:
            diff = np.abs(np.asarray(a[column][:n]) - np.asarray(b[column][:n]))
            i = int(np.argmax(diff)) if n else 0
            out[column] = {self.DIFFERENCE_KEY: float(diff[i]) if n else 0.0,
                           "at_time_s": float(a["time_s"][i]) if n else 0.0}
        return out

    def plot_stacked(self, panels, data: dict, axes=None, label: str = "", legend: dict | None = None,
                     **line_kwargs):
        """``panels`` ((column, y label) each) of ``data`` against time on stacked axes (given, or a
        new figure's, 7 in wide and 7 in high for up to three panels, 2.2 in per panel beyond): several runs drawn on the same axes compare them. The
        first axis holds the legend (``legend``: its keywords). Returns the figure; every rig's
        ``plot`` draws through it."""
        if axes is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(7, max(7.0, 2.2 * len(panels))), layout="constrained")
            axes = fig.subplots(len(panels), 1, sharex=True)
        else:
            fig = axes[0].figure
        for ax, (column, text) in zip(axes, panels):
            ax.plot(self.time, data[column], label=label, **line_kwargs)
            ax.set_ylabel(text)
            ax.grid(True, alpha=0.3)
        axes[-1].set_xlabel("time [s]")
        if legend is not None:
            axes[0].legend(**legend)
        return fig

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

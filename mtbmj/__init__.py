"""mtbmj: a mountain-bike front suspension (coil fork + tire) on MuJoCo, with an independent
scipy ODE reference, reproducing the drop-sled study S1-S14 of Schoeneck, Sadauckas & Nagurka
(BMD 2023).

    >>> import mtbmj
    >>> result = mtbmj.run_drop("S12")              # MuJoCo engine
    >>> reference = mtbmj.run_drop("S12", engine="ode")
    >>> result.difference(reference)["fork_mm"]["max_abs_mm"] < 0.1
    True
"""
__version__ = "0.1.0"

from .config import Config, load as load_config, preset_names, study_presets  # noqa: E402
from .drop import run_drop  # noqa: E402
from .errors import ConfigError, MtbmjError, RunError  # noqa: E402
from .result import DropResult  # noqa: E402
from .study import run_study, write_study  # noqa: E402
from mtbmj.validation import crosscheck  # noqa: E402

__all__ = ["__version__", "Config", "load_config", "preset_names", "study_presets", "run_drop",
           "run_study", "write_study", "crosscheck", "DropResult", "MtbmjError", "ConfigError", "RunError"]

"""What one run may ask for, checked before anything is allocated: a duration that is a finite
number of seconds, at least one logger sample long, and a number of steps whose arrays fit in
the memory this machine has available (the message says how much would be needed)."""
from __future__ import annotations

import math
import os

from mtbmj.errors import ConfigError

# Memory one simulated step holds until a run is written: the engine's state record and trace,
# the derived signals and the CSV text of the raw trace. Measured with tracemalloc at about
# 200-270 bytes per step for a drop on either engine; the CSV text of ``timeseries_raw.csv``
# (about 100 bytes a row) and a margin for copies make it 1 KiB.
BYTES_PER_STEP = 1024


def available_memory() -> int:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``; else the physical
    memory)."""
    try:
        with open("/proc/meminfo", "rb") as handle:
            for line in handle:
                if line.startswith(b"MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):  # pragma: no cover - not a POSIX system
        return 1 << 34


def size_text(nbytes: float) -> str:
    for unit, scale in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{nbytes / 1024:.3g} KiB"


def check_duration(label: str, duration) -> None:
    """A duration given by the user: a finite positive number of seconds."""
    if duration is None:
        return
    if isinstance(duration, bool) or not isinstance(duration, (int, float)):
        raise ConfigError(f"{label}: must be a number of seconds, got {duration!r}")
    if not (math.isfinite(duration) and duration > 0):
        raise ConfigError(f"{label}: must be a positive finite number of seconds, got {duration}")


def check_run(duration: float, timestep: float, sample_rate_Hz: float, label: str = "duration",
              runs: int = 1) -> int:
    """The number of steps of ``runs`` runs of ``duration`` s at ``timestep`` s, or ``ConfigError``
    when the duration is not finite, shorter than one logger sample, or the steps would need more
    memory than is available."""
    check_duration(label, duration)
    shortest = 1.0 / sample_rate_Hz
    if duration < shortest:
        raise ConfigError(f"{label}: {duration:g} s is shorter than one logger sample "
                          f"({shortest:g} s at {sample_rate_Hz:g} Hz)")
    steps = duration / timestep
    need = steps * BYTES_PER_STEP * runs
    have = available_memory()
    if need > have:
        raise ConfigError(f"{label}: {duration:g} s in steps of {timestep:g} s is {steps:.3g} steps"
                          f"{f' x {runs} runs' if runs > 1 else ''}, needing about {size_text(need)} of memory; "
                          f"{size_text(have)} is available (shorten the duration or lengthen solver.timestep_s)")
    return int(round(steps))

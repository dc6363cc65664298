"""Synthetic sled drop records from a known configuration, for testing ``fit_drop``.

A drop of the configuration (e.g. S12 with some values changed: the "truth") is logged the way the
sled's instruments do (``run_drop``'s 1 kHz signals, already behind the 400 Hz anti-aliasing
filter), then each potentiometer reading gets white noise and ADC quantisation: the sled pot
(275 mm range) and the fork pot (150 mm) on a 16-bit converter by default. The tire column is
sled - fork of the noisy readings, as in the paper. Time zero is tire touch. The first comment line
says the record is synthetic and lists the true values.

Generating with the ODE reference (``engine="ode"``) and fitting with MuJoCo avoids fitting a
model to its own output (the engines agree to about 0.05 mm, benchmarks/results/accuracy.json).
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from mtbmj.drop.run import resolve, run_drop

from mtbmj.identify.records import Record, read_record, write_csv_text


def drop_record_columns(config="S12", overrides: Mapping | None = None, noise_mm: float = 0.05,
                        sled_range_mm: float = 275.0, fork_range_mm: float = 150.0, adc_bits: int = 16,
                        duration: float | None = None, engine: str = "ode", seed: int = 0) -> tuple[dict, list[str]]:
    """(columns in record units, comment lines) of a synthetic sled drop record."""
    cfg = resolve(config, overrides)
    result = run_drop(cfg, engine, duration=duration)
    rng = np.random.default_rng(seed)
    s = result.signals

    def pot(values, full_range):
        q = full_range / 2**adc_bits
        return np.round((values + rng.normal(0.0, noise_mm, values.size)) / q) * q

    sled = pot(s["sled_mm"], sled_range_mm)
    fork = pot(s["fork_mm"], fork_range_mm)
    columns = {"time_s": s["time_s"], "sled_mm": sled, "fork_mm": fork, "tire_mm": sled - fork}
    truth = ", ".join(f"{k} = {v:g}" for k, v in (overrides or {}).items() if isinstance(v, (int, float)))
    comments = [
        f"synthetic sled drop record (mtbmj.identify.drop_synthetic): {cfg.name}"
        + (f" with true values {truth}" if truth else ""),
        f"engine {engine}; 1 kHz after the 400 Hz anti-aliasing low-pass; pot noise {noise_mm:g} mm rms, "
        f"{adc_bits}-bit over {sled_range_mm:g} mm (sled) and {fork_range_mm:g} mm (fork); seed {seed}",
        "time zero at tire touch; sled zero at tread touch, fork zero at full extension, tire = sled - fork",
    ]
    return columns, comments


def make_drop_record(config="S12", overrides: Mapping | None = None, noise_mm: float = 0.05,
                     duration: float | None = None, engine: str = "ode", seed: int = 0,
                     path: str | Path | None = None, **kwargs) -> Record:
    """A synthetic sled drop record as a ``Record`` (written to ``path`` as CSV when given)."""
    columns, comments = drop_record_columns(config, overrides, noise_mm, duration=duration, engine=engine,
                                            seed=seed, **kwargs)
    text = write_csv_text(columns, comments)
    if path is not None:
        Path(path).write_text(text)
        return read_record(path)
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        file = Path(tmp) / "synthetic_drop.csv"
        file.write_text(text)
        record = read_record(file)
    return Record("synthetic_drop.csv", record.columns, record.units, record.comments)


__all__ = ["drop_record_columns", "make_drop_record"]

"""Synthetic sled drop records from a known configuration, for testing ``fit_drop``.

A drop of the configuration (e.g. S12 with some values changed: the "truth") is logged the way the
sled's instruments do: the engine-rate trace (optionally with a free fall in front of the touch and
potentiometer noise) through the 400 Hz anti-aliasing filter, sampled at 1 kHz, then white noise
and ADC quantisation: the sled pot (275 mm range) and the fork pot (150 mm) on a 16-bit converter
by default. The tire column is sled - fork of the noisy readings, as in the paper. Time zero is
tire touch, on a clock that may be offset (``clock_offset_s``). The first comment line says the
record is synthetic and lists the true values. Without a fall, offset or sensor noise the record
is ``run_drop``'s logged signals plus noise.

Generating with the ODE reference (``engine="ode"``) and fitting with MuJoCo avoids fitting a
model to its own output (the engines agree to about 0.05 mm, benchmarks/results/accuracy.json).
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from mtbmj.drop.measure import antialias_filter
from mtbmj.drop.chain import resolve
from mtbmj.drop.run import run_drop

from mtbmj.measured.records import Record, read_record, write_csv_text


def drop_record_columns(config="S12", overrides: Mapping | None = None, noise_mm: float = 0.05,
                        sled_range_mm: float = 275.0, fork_range_mm: float = 150.0, adc_bits: int = 16,
                        duration: float | None = None, engine: str = "ode", seed: int = 0,
                        fall_s: float = 0.0, clock_offset_s: float = 0.0,
                        sensor_noise_mm: float = 0.0) -> tuple[dict, list[str]]:
    """(columns in record units, comment lines) of a synthetic sled drop record.

    ``fall_s``: free fall recorded before touch (longer than the fall from the drop height: the
    sled hangs still before its release); ``clock_offset_s``: the logger's clock at touch (time
    zero is then wherever the fall puts it, not on a sample unless ``fall_s`` is a whole number of
    samples); ``sensor_noise_mm``: white potentiometer noise at the engine rate, before the
    anti-aliasing filter (coloured in the record); ``noise_mm``: white noise on the logged samples.
    The engine-rate trace passes through the logger's filter (the same 4th-order Butterworth as
    ``mtbmj.drop.measure``) with the whole fall in front of it (from the sled hanging still), then
    the last ``fall_s`` before touch are kept: what a logger running through the release records."""
    from scipy import signal

    cfg = resolve(config, overrides)
    result = run_drop(cfg, engine, duration=duration)
    rng = np.random.default_rng(seed)
    raw = result.raw
    dt = float(raw["time_s"][1] - raw["time_s"][0])
    ratio = int(round(1.0 / (cfg["solver.sample_rate_Hz"] * dt)))
    g = cfg["sled.gravity_m_per_s2"]
    height = cfg["sled.drop_height_mm"] * 1e-3
    v_i = float(np.sqrt(2 * g * height))
    pre = int(round(max(fall_s, 0.0) / dt))
    if pre:  # the logger runs through the release: filter from the sled hanging still, keep the last fall_s
        pre += ratio * int(np.ceil((v_i / g + 0.02) / (ratio * dt)))
    tau = (np.arange(-pre, 0)) * dt  # engine-rate times before touch
    release = -v_i / g
    fall_mm = np.where(tau < release, -height, v_i * tau + 0.5 * g * tau**2) * 1e3
    true = {"sled": np.concatenate([fall_mm, raw["sled_mm"]]),
            "fork": np.concatenate([np.zeros(pre), raw["fork_mm"]])}
    time = np.concatenate([tau, raw["time_s"]])
    sos, zi = antialias_filter(cfg["solver.antialias_Hz"], dt)
    q = {"sled": sled_range_mm / 2**adc_bits, "fork": fork_range_mm / 2**adc_bits}
    columns = {"time_s": time[::ratio] + clock_offset_s}
    for name in ("sled", "fork"):
        reading = true[name] + (rng.normal(0.0, sensor_noise_mm, time.size) if sensor_noise_mm > 0 else 0.0)
        filtered, _ = signal.sosfilt(sos, reading, zi=zi * reading[0])
        logged = filtered[::ratio] + rng.normal(0.0, noise_mm, columns["time_s"].size)
        columns[f"{name}_mm"] = np.round(logged / q[name]) * q[name]
    if pre:
        keep = columns["time_s"] >= clock_offset_s - fall_s - 1e-9
        columns = {k: v[keep] for k, v in columns.items()}
    columns["tire_mm"] = columns["sled_mm"] - columns["fork_mm"]
    truth = ", ".join(f"{k} = {v:g}" for k, v in (overrides or {}).items() if isinstance(v, (int, float)))
    touch = clock_offset_s
    comments = [
        f"synthetic sled drop record (mtbmj.identify.drop_synthetic): {cfg.name}"
        + (f" with true values {truth}" if truth else ""),
        f"engine {engine}; 1 kHz after the 400 Hz anti-aliasing low-pass; pot noise {noise_mm:g} mm rms on the "
        f"samples, {sensor_noise_mm:g} mm rms before the filter; {adc_bits}-bit over {sled_range_mm:g} mm (sled) "
        f"and {fork_range_mm:g} mm (fork); seed {seed}",
        (f"{fall_s * 1e3:.1f} ms of free fall before touch; true touch at t = {touch:.6f} s on this clock"
         if pre else f"the record starts at touch, t = {touch:.6f} s on this clock")
        + "; sled zero at tread touch, fork zero at full extension, tire = sled - fork",
    ]
    return columns, comments


def make_drop_record(config="S12", overrides: Mapping | None = None, noise_mm: float = 0.05,
                     duration: float | None = None, engine: str = "ode", seed: int = 0,
                     path: str | Path | None = None, **kwargs) -> Record:
    """A synthetic sled drop record as a ``Record`` (written to ``path`` as CSV when given);
    ``kwargs``: ``fall_s``, ``clock_offset_s``, ``sensor_noise_mm``, pot ranges (see
    ``drop_record_columns``)."""
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

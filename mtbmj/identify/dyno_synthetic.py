"""Synthetic shock-dyno records from known parameters, for testing the spring and damper fits.

No public dyno data exist for the paper's fork, so these records are generated from the library's
own force laws (built by ``mtbmj.compose`` from configuration keys, so the truth is stated in the
same keys and units a fit returns) and then degraded the way a bench logs them: sampling rate,
Gaussian sensor noise, and ADC quantisation over each sensor's range.

* ``spring_record``: the paper's Fig. 3 stroke. A slow triangle stroke (rounded at the turns) from
  mid-travel into compression near full travel, back, and pulled into extension past the top-out
  spring, repeated. Friction opposes the stroke, so compression and rebound form a loop.
* ``damper_record``: the paper's Fig. 6 test. Sinusoidal strokes at several peak speeds (fixed
  stroke at high speed, fixed frequency at low speed), with a short rest between tests; the time
  series of displacement, the dyno's velocity (differentiated displacement) and force.
  ``peak_points`` reduces any such time series to the peak force vs peak velocity points a dyno
  reports (one per full half-cycle, compression positive, rebound negative).

Every record carries a first comment line ``synthetic shock-dyno ... record`` and a line with the
true parameters; ``write_csv`` / ``write_mat`` store it (``.mat`` with unit-suffixed variables
and a ``description`` string).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np
from scipy.signal import savgol_filter

from mtbmj.config import Config, load as load_config
from mtbmj.errors import MtbmjError
from mtbmj import compose
from mtbmj.measured.records import UNITS, Record, RecordError, write_csv_text

# --- true parameter sets (configuration keys and units) ------------------------------------------

#: The reference "true fork" spring (S12): progressive main spring, top-out spring, preload, with
#: the reference Coulomb friction making the loop.
SPRING_PROGRESSIVE: dict[str, Any] = {
    "fork.spring.model": "progressive",
    "fork.spring.progressive_rate_N_per_mm": 11.37,
    "fork.spring.progressive_cubic_N_per_mm3": 0.000326,
    "fork.spring.top_out": True,
    "fork.spring.top_out_rate_N_per_mm": 35.3,
    "fork.spring.preload": True,
    "fork.spring.preload_N": 211.1,
    "fork.friction.model": "coulomb",
    "fork.friction.coulomb_N": 34.2,
}

#: A bilinear spring (paper eq. 4, knee 67 mm) with top-out and preload (S6-like).
SPRING_BILINEAR: dict[str, Any] = {
    "fork.spring.model": "bilinear",
    "fork.spring.rate_below_knee_N_per_mm": 12.0,
    "fork.spring.rate_above_knee_N_per_mm": 22.0,
    "fork.spring.knee_mm": 67.0,
    "fork.spring.top_out": True,
    "fork.spring.top_out_rate_N_per_mm": 35.3,
    "fork.spring.preload": True,
    "fork.spring.preload_N": 150.0,
    "fork.friction.model": "coulomb",
    "fork.friction.coulomb_N": 34.2,
}

#: Separate compression and rebound rates (paper Fig. 3a), no top-out or preload, with friction.
SPRING_COMPRESSION_REBOUND: dict[str, Any] = {
    "fork.spring.model": "compression_rebound",
    "fork.spring.compression_rate_N_per_mm": 17.0,
    "fork.spring.rebound_rate_N_per_mm": 15.0,
    "fork.spring.top_out": False,
    "fork.spring.preload": False,
    "fork.friction.model": "coulomb",
    "fork.friction.coulomb_N": 34.2,
}

#: The reference damper: the S10-S14 table (compression linear, rebound digressive) + Coulomb.
DAMPER_TABLE: dict[str, Any] = {
    "fork.damper.model": "table",
    "fork.damper.velocity_mm_per_s": [-1500.0, -800.0, -400.0, -150.0, -50.0, 0.0, 50.0, 150.0, 400.0, 800.0, 1500.0],
    "fork.damper.force_N": [-391.4, -225.2, -128.0, -58.1, -21.9, 0.0, 6.7, 20.0, 53.3, 106.6, 199.8],
    "fork.friction.model": "coulomb",
    "fork.friction.coulomb_N": 34.2,
}

#: Separate compression and rebound coefficients (paper Fig. 6 left, S9) + Coulomb.
DAMPER_BILINEAR: dict[str, Any] = {
    "fork.damper.model": "bilinear",
    "fork.damper.compression_N_s_per_m": 133.2,
    "fork.damper.rebound_N_s_per_m": 269.4,
    "fork.friction.model": "coulomb",
    "fork.friction.coulomb_N": 34.2,
}

#: Bilinear damper with Stribeck friction (Olsson plot d); needs the low-speed tests to show.
DAMPER_STRIBECK: dict[str, Any] = {
    "fork.damper.model": "bilinear",
    "fork.damper.compression_N_s_per_m": 133.2,
    "fork.damper.rebound_N_s_per_m": 269.4,
    "fork.friction.model": "stribeck",
    "fork.friction.coulomb_N": 34.2,
    "fork.friction.breakaway_N": 45.0,
    "fork.friction.viscous_N_s_per_m": 0.0,
    "fork.friction.stribeck_velocity_mm_per_s": 25.0,
    "fork.friction.stribeck_exponent": 2.0,
}

#: Dyno test speeds (mm/s): the usual ladder, and the extra low speeds that show stiction.
TEST_SPEEDS_MM_PER_S = (25.0, 50.0, 100.0, 150.0, 250.0, 400.0, 600.0, 800.0, 1000.0, 1250.0, 1500.0)
LOW_SPEEDS_MM_PER_S = (6.0, 10.0, 15.0, 20.0, 30.0, 40.0)

# Sensor ranges (unit of the column) quantised by a 16-bit ADC.
DISPLACEMENT_RANGE_MM = (-20.0, 130.0)  # a 150 mm potentiometer, as on the sled
FORCE_RANGE_N = (-5000.0, 5000.0)  # a +/- 5 kN load cell
ADC_BITS = 16

# Model-choice keys of the reference that a truth must not inherit (they select other laws).
_MODEL_SPECIFIC = ("fork.spring.rate_N_per_mm", "fork.spring.compression_rate_N_per_mm",
                   "fork.spring.rebound_rate_N_per_mm", "fork.spring.knee_mm",
                   "fork.spring.rate_below_knee_N_per_mm", "fork.spring.rate_above_knee_N_per_mm")


def truth_fork(truth: Mapping[str, Any]):
    """The ``controllers.ForkLaw`` of a truth given in configuration keys (reference for the rest).

    Keys that select another spring law in the reference (e.g. its S2 rebound rate, which would
    turn a bilinear spring directional) are dropped unless ``truth`` names them."""
    base = load_config("reference")
    values = {k: v for k, v in base.values.items() if k not in _MODEL_SPECIFIC}
    config = Config("synthetic truth", values, base.sources).with_overrides(dict(truth))
    fork = compose.fork_law(config)
    # A dyno strokes the fork within its travel at steady speeds: the end stops do not engage and
    # a sticking friction law slides at its static level (the wrapped law).
    spring = getattr(fork.spring, "main", fork.spring)
    friction = getattr(fork.friction, "inner", fork.friction)
    if friction.has_state:
        raise MtbmjError("synthetic dyno: a stateful friction law (lugre) is not supported by the generator")
    return type(fork)(spring, fork.damper, friction)


def _describe(truth: Mapping[str, Any]) -> str:
    parts = []
    for key, value in truth.items():
        if isinstance(value, (list, tuple)) and value and isinstance(value[0], (list, tuple)):
            value = "[" + " ".join("[" + " ".join(f"{v:g}" for v in row) + "]" for row in value) + "]"
        elif isinstance(value, (list, tuple)):
            value = "[" + " ".join(f"{v:g}" for v in value) + "]"
        elif isinstance(value, bool):
            value = "true" if value else "false"
        elif isinstance(value, float):
            value = f"{value:g}"
        parts.append(f"{key}={value}")
    return "true parameters: " + "; ".join(parts)


def quantise(values: np.ndarray, span: tuple[float, float], bits: int = ADC_BITS) -> np.ndarray:
    """Round to the ADC step of ``span`` and clip to it (what a ``bits``-bit logger stores)."""
    lo, hi = span
    step = (hi - lo) / (2 ** bits)
    return np.clip(lo + np.round((np.asarray(values) - lo) / step) * step, lo, hi)


def _force(fork, x: np.ndarray, v: np.ndarray, spring: bool = True, damper: bool = True) -> np.ndarray:
    out = np.zeros_like(x)
    for i, (xi, vi) in enumerate(zip(x.tolist(), v.tolist())):
        f = fork.friction.force(vi)
        if spring:
            f += fork.spring.force(xi, vi)
        if damper:
            f += fork.damper.force(vi)
        out[i] = f
    return out


def _record(columns_si: dict[str, np.ndarray], units: dict[str, str], comments: list[str], path: str) -> Record:
    return Record(path, {k: np.asarray(v, float) for k, v in columns_si.items()}, dict(units), tuple(comments))


def spring_record(truth: Mapping[str, Any] | None = None, *, start_mm: float = 60.0, deepest_mm: float = 112.0,
                  extension_mm: float = -12.0, speed_mm_per_s: float = 50.0, cycles: int = 2,
                  sample_Hz: float = 1000.0, noise_mm: float = 0.05, noise_N: float = 5.0,
                  with_damper: bool = False, seed: int = 0) -> Record:
    """A force-displacement stroke as in the paper's Fig. 3 (see the module doc).

    The stroke goes ``start_mm`` -> ``deepest_mm`` -> ``extension_mm`` -> ``start_mm`` at
    ``speed_mm_per_s``, ``cycles`` times, with the turns rounded over 0.2 s (which cuts each
    corner by about speed x 0.05 s: the defaults reach about 110 and -10 mm). The force is the
    truth's spring plus its friction (plus its damper if ``with_damper``; a spring curve is
    normally measured slowly with the damper's share small). Columns: time_s, displacement_mm,
    force_N. Pass ``extension_mm >= 0`` for a stroke that never reaches extension.
    """
    truth = dict(SPRING_PROGRESSIVE if truth is None else truth)
    fork = truth_fork(truth)
    rng = np.random.default_rng(seed)
    corners = [start_mm] + [deepest_mm, extension_mm, start_mm] * cycles
    dt = 1.0 / sample_Hz
    path = [np.array([start_mm])]
    for a, b in zip(corners[:-1], corners[1:]):
        n = max(int(round(abs(b - a) / speed_mm_per_s * sample_Hz)), 2)
        path.append(np.linspace(a, b, n + 1)[1:])
    x_mm = np.concatenate(path)
    width = max(int(0.2 * sample_Hz) | 1, 3)
    pad = width // 2
    padded = np.concatenate([np.full(pad, x_mm[0]), x_mm, np.full(pad, x_mm[-1])])
    x_mm = np.convolve(padded, np.ones(width) / width, mode="valid")
    t = np.arange(len(x_mm)) * dt
    v_mm = np.gradient(x_mm, dt)
    force = _force(fork, x_mm * 1e-3, v_mm * 1e-3, damper=with_damper)
    x_meas = quantise(x_mm + rng.normal(0.0, noise_mm, x_mm.shape), DISPLACEMENT_RANGE_MM)
    f_meas = quantise(force + rng.normal(0.0, noise_N, force.shape), FORCE_RANGE_N)
    if with_damper:
        truth["damper"] = "included at the stroke speed"
    comments = [
        f"synthetic shock-dyno spring record (generated by mtbmj from known parameters, not measured); "
        f"{sample_Hz:g} Hz, noise {noise_mm:g} mm / {noise_N:g} N, {ADC_BITS}-bit ADC over "
        f"{DISPLACEMENT_RANGE_MM[0]:g}..{DISPLACEMENT_RANGE_MM[1]:g} mm and {FORCE_RANGE_N[0]:g}..{FORCE_RANGE_N[1]:g} N, "
        f"stroke {start_mm:g} -> {deepest_mm:g} -> {extension_mm:g} mm at {speed_mm_per_s:g} mm/s, seed {seed}",
        _describe(truth),
    ]
    return _record({"time": t, "displacement": x_meas * 1e-3, "force": f_meas},
                   {"time": "s", "displacement": "mm", "force": "N"}, comments, "<synthetic spring record>")


def damper_record(truth: Mapping[str, Any] | None = None, *, speeds_mm_per_s=TEST_SPEEDS_MM_PER_S,
                  low_speeds: bool = False, stroke_mm: float = 25.0, min_frequency_Hz: float = 1.0,
                  cycles: int = 4, rest_s: float = 0.5, mid_mm: float = 60.0, sample_Hz: float = 1000.0,
                  noise_mm: float = 0.05, noise_N: float = 5.0, with_spring: bool = False,
                  seed: int = 0) -> Record:
    """Sinusoidal dyno strokes at several peak speeds (paper Fig. 6), as a time series.

    Each test runs ``cycles`` sine cycles about ``mid_mm`` starting and ending at rest at the
    bottom of the stroke: amplitude ``stroke_mm`` where that gives at least ``min_frequency_Hz``,
    otherwise ``min_frequency_Hz`` with a smaller amplitude (the low-speed tests). A pause of
    ``rest_s`` (a slow move to the next stroke's start) separates the tests. The force is the truth's
    damper plus friction (plus the spring if ``with_spring``; by default the spring is out, as in
    a damper test). The velocity column is the dyno's: the logged displacement differentiated.
    Columns: time_s, displacement_mm, velocity_mm_per_s, force_N.
    """
    truth = dict(DAMPER_TABLE if truth is None else truth)
    fork = truth_fork(truth)
    rng = np.random.default_rng(seed)
    speeds = sorted(set(float(s) for s in speeds_mm_per_s) | (set(LOW_SPEEDS_MM_PER_S) if low_speeds else set()))
    dt = 1.0 / sample_Hz
    n_rest = max(int(rest_s * sample_Hz), 2)
    here = mid_mm
    xs, vs = [], []
    for speed in speeds:
        freq = max(speed / (2.0 * np.pi * stroke_mm), min_frequency_Hz)
        amp = speed / (2.0 * np.pi * freq)
        # rest, moving gently (raised cosine) to the bottom of the next stroke, v = 0 at both ends
        s = 0.5 * (1.0 - np.cos(np.pi * np.arange(n_rest) / (n_rest - 1)))
        target = mid_mm - amp
        xs.append(here + (target - here) * s)
        vs.append(np.gradient(xs[-1], dt))
        n = int(round(cycles / freq * sample_Hz))
        tt = np.arange(1, n + 1) * dt
        xs.append(mid_mm - amp * np.cos(2 * np.pi * freq * tt))
        vs.append(speed * np.sin(2 * np.pi * freq * tt))
        here = xs[-1][-1]
    x_mm, v_mm = np.concatenate(xs), np.concatenate(vs)
    t = np.arange(len(x_mm)) * dt
    force = _force(fork, x_mm * 1e-3, v_mm * 1e-3, spring=with_spring)
    x_meas = quantise(x_mm + rng.normal(0.0, noise_mm, x_mm.shape), DISPLACEMENT_RANGE_MM)
    f_meas = quantise(force + rng.normal(0.0, noise_N, force.shape), FORCE_RANGE_N)
    v_meas = savgol_filter(x_meas, 31, 4, deriv=1, delta=dt)
    if with_spring:
        truth["spring"] = "included (reference spring)"
    comments = [
        f"synthetic shock-dyno damper record (generated by mtbmj from known parameters, not measured); "
        f"{sample_Hz:g} Hz, noise {noise_mm:g} mm / {noise_N:g} N, {ADC_BITS}-bit ADC, sine strokes at "
        f"{', '.join(f'{s:g}' for s in speeds)} mm/s, {cycles} cycles each, seed {seed}",
        _describe(truth),
    ]
    return _record({"time": t, "displacement": x_meas * 1e-3, "velocity": v_meas * 1e-3, "force": f_meas},
                   {"time": "s", "displacement": "mm", "velocity": "mm_per_s", "force": "N"}, comments,
                   "<synthetic damper record>")


def _odd(n: int, lo: int, hi: int) -> int:
    n = int(min(max(n, lo), hi))
    return n if n % 2 else n + 1


class _Velocity:
    """Velocity of a dyno time series by Savitzky-Golay differentiation of the displacement (or
    smoothing of a velocity column), with the window chosen per stroke: wide for slow strokes
    (noise), narrow for fast ones (no attenuation of the peak)."""

    def __init__(self, record: Record):
        t = record["time"]
        self.dt = float(np.median(np.diff(t)))
        self.n = len(t)
        if "displacement" in record.columns:
            self.signal, self.deriv = record["displacement"], 1
        else:
            self.signal, self.deriv = record["velocity"], 0
        self._cache: dict[int, np.ndarray] = {}

    def detect(self) -> np.ndarray:
        """A heavily smoothed velocity (quadratic, 41 samples) for finding the strokes."""
        w = min(41, self.n - 1 if self.n % 2 == 0 else self.n)
        return savgol_filter(self.signal, w, 2, deriv=self.deriv, delta=self.dt)

    def window(self, w: int) -> np.ndarray:
        w = min(w, self.n - 1 if self.n % 2 == 0 else self.n)
        if w not in self._cache:
            order = min(4 if self.deriv else 2, w - 1)
            self._cache[w] = savgol_filter(self.signal, w, order, deriv=self.deriv, delta=self.dt)
        return self._cache[w]


def peak_points(record: Record, *, window: float = 0.95, min_speed_mm_per_s: float = 4.0,
                threshold_mm_per_s: float = 2.0, discard_ends: bool = True) -> Record:
    """Peak force vs peak velocity, one point per full half-cycle of a dyno time series.

    Half-cycles are the runs of one stroke direction: the sign of a smoothed velocity with a
    hysteresis of +/- ``threshold_mm_per_s`` (so noise at rest or near a turn does not split a
    stroke). A run counts when its peak speed reaches ``min_speed_mm_per_s``; a run below it (a
    rest) separates tests. Consecutive runs of alternating direction with peaks within 20 % and
    durations within 30 % form one test, whose first and last runs (partial strokes, rests) are dropped when
    ``discard_ends``. The velocity of each run is then re-derived with a Savitzky-Golay window a
    quarter of the run long, and its point is the mean velocity and force over the samples at or
    above ``window`` x the run's peak speed (around mid-stroke). Columns: velocity, force (SI;
    units mm_per_s and N), compression positive, rebound negative.
    """
    if "time" not in record.columns or "force" not in record.columns or not (
            "velocity" in record.columns or "displacement" in record.columns):
        raise RecordError(f"{record.path}: a dyno time series needs time_s, force_N and "
                          "velocity_mm_per_s or displacement_mm columns")
    record.require("time", "force", min_points=50)
    vel_of = _Velocity(record)
    f = record["force"]
    detect = vel_of.detect()
    thr = threshold_mm_per_s * 1e-3
    state = np.zeros(len(f), dtype=int)
    s = 0
    for i, value in enumerate(detect.tolist()):
        if value > thr:
            s = 1
        elif value < -thr:
            s = -1
        state[i] = s
    edges = np.flatnonzero(np.diff(state) != 0) + 1
    bounds = np.concatenate([[0], edges, [len(f)]])
    tests, current = [], []
    for a, b in zip(bounds[:-1], bounds[1:]):
        peak = float(np.max(np.abs(detect[a:b]))) if state[a] != 0 else 0.0
        if peak * 1e3 < min_speed_mm_per_s or b - a < 10:
            if current:
                tests.append(current)
            current = []
            continue
        first = current[0] if current else None
        if current and (abs(peak - first[2]) > 0.2 * first[2] or abs((b - a) - (first[1] - first[0])) > 0.3 * (first[1] - first[0])
                        or state[a] == state[current[-1][0]]):
            tests.append(current)
            current = []
        current.append((a, b, peak))
    if current:
        tests.append(current)
    vel, force = [], []
    for test in tests:
        if discard_ends:
            if len(test) < 3:
                continue
            test = test[1:-1]
        for a, b, _ in test:
            v = vel_of.window(_odd((b - a) // 4, 7, 201))[a:b]
            sel = np.abs(v) >= window * np.max(np.abs(v))
            vel.append(float(np.mean(v[sel])))
            force.append(float(np.mean(f[a:b][sel])))
    if not vel:
        raise RecordError(f"{record.path}: no dyno strokes found (no repeated half-cycles above "
                          f"{min_speed_mm_per_s:g} mm/s)")
    order = np.argsort(vel)
    comments = list(record.comments) + ["peak force vs peak velocity, one point per half-cycle (mtbmj peak_points)"]
    return Record(record.path, {"velocity": np.asarray(vel)[order], "force": np.asarray(force)[order]},
                  {"velocity": "mm_per_s", "force": "N"}, tuple(comments))


# --- writers --------------------------------------------------------------------------------------

def _unit_columns(record: Record) -> dict[str, np.ndarray]:
    return {f"{q}_{record.units[q]}": np.asarray(record[q]) / UNITS[record.units[q]] for q in record.columns}


def write_csv(path: str | Path, record: Record) -> Path:
    """CSV with the record's comment lines first (the first says ``synthetic``), units in the names."""
    path = Path(path)
    path.write_text(write_csv_text(_unit_columns(record), record.comments))
    return path


def write_mat(path: str | Path, record: Record) -> Path:
    """MATLAB .mat: one variable per column (``displacement_mm`` ...) and a ``description`` string."""
    from scipy.io import savemat

    path = Path(path)
    content = dict(_unit_columns(record))
    content["description"] = " | ".join(record.comments)
    savemat(path, content)
    return path


def write_record(path: str | Path, record: Record) -> Path:
    """``write_mat`` for a ``.mat`` path, ``write_csv`` otherwise."""
    return write_mat(path, record) if Path(path).suffix.lower() == ".mat" else write_csv(path, record)


def config_truth(config: Config, part: str) -> dict[str, Any]:
    """The keys of ``config`` that define its fork ``part`` ("spring" or "damper") and friction:
    the truth a synthetic record of that configuration is generated from."""
    prefixes = (f"fork.{part}.", "fork.friction.")
    return {k: v for k, v in config.values.items() if k.startswith(prefixes) or k == "fork.travel_mm"}


def write_spring_record(path: str | Path, truth: Mapping[str, Any] | None = None, **kwargs) -> Path:
    """Generate a spring record (``spring_record`` arguments) and write it (.csv or .mat)."""
    return write_record(path, spring_record(truth, **kwargs))


def write_damper_record(path: str | Path, truth: Mapping[str, Any] | None = None, *, peaks: bool = False,
                        **kwargs) -> Path:
    """Generate a damper time series (``damper_record`` arguments) and write it, or its peak
    points if ``peaks``."""
    record = damper_record(truth, **kwargs)
    return write_record(path, peak_points(record) if peaks else record)


__all__ = ["SPRING_PROGRESSIVE", "SPRING_BILINEAR", "SPRING_COMPRESSION_REBOUND", "DAMPER_TABLE",
           "DAMPER_BILINEAR", "DAMPER_STRIBECK", "TEST_SPEEDS_MM_PER_S", "LOW_SPEEDS_MM_PER_S",
           "truth_fork", "config_truth", "quantise", "spring_record", "damper_record", "peak_points", "write_csv",
           "write_mat", "write_record", "write_spring_record", "write_damper_record"]

"""The numbers riders read from suspension telemetry, for measured and simulated travel alike.

Conventions: travel in mm, zero at full extension, compression positive; velocity in mm/s,
compression positive, rebound negative. Histograms give the share of time (in %) per bin.

- Travel histogram: time per ``bin_percent`` band of the travel (0-5 %, 5-10 % ... of
  ``travel_max_mm``); readings below 0 % or above 100 % fall in the first or last bin.
- Velocity: the Savitzky-Golay derivative of travel (``scipy.signal.savgol_filter``, cubic over
  51 ms by default). A plain difference would turn one encoder count (about 0.2 mm on the fork
  sensor) into 200 mm/s of noise at 1 kHz.
- Velocity histogram with the high/low-speed split at ``threshold_mm_per_s`` (100 mm/s by
  default): high-speed compression v > thr, low-speed compression 0 <= v <= thr, low-speed
  rebound -thr <= v < 0, high-speed rebound v < -thr (v = 0, a fork at rest, counts as low-speed
  compression, so the four shares add up to 100 %).
- Bottom-outs: distinct events with travel within ``margin_mm`` of ``travel_max_mm``; an event
  ends only when the travel has dropped ``release_mm`` further, so sensor chatter at the end stop
  is one event, not many.
- Airtime (the rule, and why): the bike is in the air while both ends are within
  ``extension_percent`` (3 %) of full extension — the fork alone when there is no rear sensor —
  for at least ``min_s`` (50 ms) and at most ``max_s`` (5 s); the period must neither touch the
  start nor the end of the record and must end in a landing, the fork or the rear compressing
  past ``landing_percent`` (35 %, above the usual 20-30 % sag) of its travel within ``landing_window_s`` (250 ms). A fork
  that only tops out on rebound stays extended for a few ms; a bike standing, carried or laid
  down is also fully extended but for long, at the ends of a recording, and without a landing.
  Airborne samples are left out of the histograms by ``summarize`` (a fork hanging in the air is
  not working travel).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtbmj.errors import MtbmjError

VELOCITY_WINDOW_S = 0.051
VELOCITY_POLYORDER = 3
VELOCITY_BIN_MM_PER_S = 50.0
VELOCITY_LIMIT_MM_PER_S = 3000.0
SPLIT_NAMES = ("high_speed_compression", "low_speed_compression", "low_speed_rebound", "high_speed_rebound")


TRAVEL_MIN_MM = 10.0  # no suspension end travels less (a short shock strokes 15 mm: limits' --shock-max-mm)
TRAVEL_OVER = 2.0  # travel past this many times its end's travel is no bottom-out: units or another end's


class MetricsError(MtbmjError, ValueError):
    """Signals the metrics cannot use: empty, not finite, unevenly sampled, mismatched."""


AIRTIME_RULE = ("both ends (the fork alone without a rear sensor) within {extension_percent:g} % of full extension "
                "for {min_s:g}..{max_s:g} s, not at the start or end of the record, ending in a landing: "
                "a compression past {landing_percent:g} % of travel within {landing_window_s:g} s")


def _array(values, name: str) -> np.ndarray:
    if values is None or isinstance(values, (str, bytes)):  # None was "not finite at sample 0", "x" numpy's own line
        raise MetricsError(f"{name}: must be a sequence of numbers, got {values!r}")
    try:
        a = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError) as exc:
        raise MetricsError(f"{name}: must be a sequence of numbers ({exc})") from None
    if a.size == 0:
        raise MetricsError(f"{name}: no samples")
    if not np.all(np.isfinite(a)):
        raise MetricsError(f"{name}: not finite at sample {int(np.argmax(~np.isfinite(a)))}")
    return a


def _positive(value: float, name: str) -> float:
    if value is None or isinstance(value, (str, bytes, bool)):  # "180" was taken, None met float()
        raise MetricsError(f"{name}: must be a number, got {value!r}")
    value = float(value)
    if not value > 0:
        raise MetricsError(f"{name}: must be positive, got {value:g}")
    return value


def sample_interval(time_s) -> float:
    """The uniform sampling interval of ``time_s`` (s); raises on a non-uniform grid."""
    t = _array(time_s, "time_s")
    if t.size < 2:
        raise MetricsError("time_s: needs at least two samples")
    steps = np.diff(t)
    dt = float(np.median(steps))
    back = np.flatnonzero(steps <= 0.0)
    if back.size:  # a clock going back (or held) is its own cause, not an uneven grid to resample
        i = int(back[0]) + 1
        raise MetricsError(f"time_s: sample {i} ({t[i]:g} s) does not come after sample {i - 1} ({t[i - 1]:g} s): "
                           f"the time must increase")
    if np.max(np.abs(steps - dt)) > 0.01 * dt:
        raise MetricsError("time_s: samples are not uniformly spaced (resample first)")
    return dt


def velocity(time_s, travel_mm, window_s: float = VELOCITY_WINDOW_S, polyorder: int = VELOCITY_POLYORDER) -> np.ndarray:
    """Travel velocity in mm/s (compression positive): Savitzky-Golay derivative of travel."""
    x = _array(travel_mm, "travel_mm")
    dt = sample_interval(time_s)
    if len(np.asarray(time_s).ravel()) != x.size:
        raise MetricsError("time_s and travel_mm differ in length")
    window = int(round(_positive(window_s, "window_s") / dt)) | 1  # odd
    if window <= polyorder:  # the sampling, not the record's length, is short of samples
        need = polyorder + 2 if (polyorder + 2) % 2 else polyorder + 1
        raise MetricsError(f"time_s: a sample every {dt:g} s ({1.0 / dt:g} Hz) puts {window} in the velocity's "
                           f"{1e3 * window_s:g} ms window, fewer than the {need} a polynomial of order {polyorder} "
                           f"needs ({need / window_s:.0f} Hz or more)")
    window = min(window, x.size if x.size % 2 else x.size - 1)
    if window <= polyorder:
        raise MetricsError(f"travel_mm: {x.size} samples are too few for a velocity (its Savitzky-Golay fit of order "
                           f"{polyorder} needs {polyorder + 2 if polyorder % 2 else polyorder + 1} or more)")
    from scipy import signal  # scipy.signal takes ~0.7 s to import: only when a velocity is needed

    return signal.savgol_filter(x, window, polyorder, deriv=1, delta=dt, mode="interp")


@dataclass(frozen=True)
class TravelHistogram:
    """Share of time (%) per band of travel (% of ``travel_max_mm``)."""

    edges_percent: np.ndarray
    time_percent: np.ndarray
    travel_max_mm: float

    @property
    def peak_bin_percent(self) -> tuple[float, float]:
        i = int(np.argmax(self.time_percent))
        return float(self.edges_percent[i]), float(self.edges_percent[i + 1])

    def to_dict(self) -> dict:
        return {"travel_max_mm": self.travel_max_mm, "bin_edges_percent": _list(self.edges_percent),
                "time_percent": _list(self.time_percent), "peak_bin_percent": list(self.peak_bin_percent)}


MIN_BIN_PERCENT = 0.01  # 10 000 travel bins: far finer than any sensor resolves


def travel_histogram(travel_mm, travel_max_mm: float, bin_percent: float = 5) -> TravelHistogram:
    """Travel histogram in % of travel, ``bin_percent`` wide bins, normalised to % of time."""
    x = _array(travel_mm, "travel_mm")
    top = _positive(travel_max_mm, "travel_max_mm")
    width = _positive(bin_percent, "bin_percent")
    if width > 100:
        raise MetricsError(f"bin_percent: must be at most 100, got {width:g}")
    if width < MIN_BIN_PERCENT:
        raise MetricsError(f"bin_percent: must be at least {MIN_BIN_PERCENT:g} (at most {100 / MIN_BIN_PERCENT:g} bins), "
                           f"got {width:g}")
    n = int(np.ceil(100.0 / width - 1e-9))
    edges = np.minimum(np.arange(n + 1) * width, 100.0)
    percent = np.clip(x / top * 100.0, 0.0, 100.0)
    counts, _ = np.histogram(percent, bins=edges)
    return TravelHistogram(edges, counts / x.size * 100.0, top)


@dataclass(frozen=True)
class VelocityHistogram:
    """Share of time (%) per velocity bin (mm/s, compression positive) and the high/low split."""

    edges_mm_per_s: np.ndarray
    time_percent: np.ndarray
    threshold_mm_per_s: float
    split_percent: dict  # SPLIT_NAMES -> % of time
    compression: dict  # mean_mm_per_s, max_mm_per_s over compression samples
    rebound: dict  # mean_mm_per_s, max_mm_per_s (as negative numbers) over rebound samples

    @property
    def high_speed_percent(self) -> float:
        return self.split_percent["high_speed_compression"] + self.split_percent["high_speed_rebound"]

    def to_dict(self) -> dict:
        return {"threshold_mm_per_s": self.threshold_mm_per_s, "split_percent": dict(self.split_percent),
                "high_speed_percent": self.high_speed_percent, "compression": dict(self.compression),
                "rebound": dict(self.rebound), "bin_edges_mm_per_s": _list(self.edges_mm_per_s),
                "time_percent": _list(self.time_percent)}


MAX_VELOCITY_BINS = 100_000


def velocity_bins(velocities, step_mm_per_s: float = VELOCITY_BIN_MM_PER_S,
                  limit_mm_per_s: float = VELOCITY_LIMIT_MM_PER_S) -> np.ndarray:
    """Symmetric bin edges, ``step`` wide, wide enough for every given signal up to ``limit``."""
    step = _positive(step_mm_per_s, "step_mm_per_s")
    peak = max((float(np.max(np.abs(_array(v, "velocity_mm_per_s")))) for v in velocities), default=step)
    half = min(max(peak, step), _positive(limit_mm_per_s, "limit_mm_per_s"))
    n = int(np.ceil(half / step - 1e-9))
    if n > MAX_VELOCITY_BINS:
        raise MetricsError(f"step_mm_per_s: {step:g} mm/s makes {2 * n} velocity bins (at most {2 * MAX_VELOCITY_BINS})")
    return np.arange(-n, n + 1) * step


def velocity_histogram(velocity_mm_per_s, threshold_mm_per_s: float = 100, bins=None) -> VelocityHistogram:
    """Velocity histogram (compression positive) in % of time, with the high/low-speed split.

    ``bins``: edges in mm/s, or a bin width (a number), or None for 50 mm/s bins covering the
    signal up to +-3000 mm/s. Velocities beyond the outer edges count in the outer bins.
    """
    v = _array(velocity_mm_per_s, "velocity_mm_per_s")
    thr = _positive(threshold_mm_per_s, "threshold_mm_per_s")
    if bins is None:
        edges = velocity_bins([v])
    elif np.ndim(bins) == 0:
        edges = velocity_bins([v], float(bins))
    else:
        edges = np.asarray(bins, dtype=float)
        if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0):
            raise MetricsError("bins: edges must be an increasing 1-D sequence of at least two values")
    counts, _ = np.histogram(np.clip(v, edges[0], edges[-1]), bins=edges)
    n = v.size
    split = {
        "high_speed_compression": np.count_nonzero(v > thr) / n * 100.0,
        "low_speed_compression": np.count_nonzero((v >= 0) & (v <= thr)) / n * 100.0,
        "low_speed_rebound": np.count_nonzero((v < 0) & (v >= -thr)) / n * 100.0,
        "high_speed_rebound": np.count_nonzero(v < -thr) / n * 100.0,
    }
    comp, reb = v[v > 0], v[v < 0]
    return VelocityHistogram(
        edges, counts / n * 100.0, thr, {k: float(x) for k, x in split.items()},
        {"mean_mm_per_s": float(comp.mean()) if comp.size else 0.0, "max_mm_per_s": float(comp.max()) if comp.size else 0.0},
        {"mean_mm_per_s": float(reb.mean()) if reb.size else 0.0, "max_mm_per_s": float(reb.min()) if reb.size else 0.0},
    )


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) indices of the True runs of ``mask``."""
    d = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1)


def bottom_out_indices(travel_mm, travel_max_mm: float, margin_mm: float = 3.0, release_mm: float = 5.0) -> np.ndarray:
    """Sample indices where each bottom-out event starts (see ``bottom_outs``)."""
    x = _array(travel_mm, "travel_mm")
    top = _positive(travel_max_mm, "travel_max_mm")
    for name, given in (("margin_mm", margin_mm), ("release_mm", release_mm)):
        if given is None or isinstance(given, (str, bytes, bool)) or not given >= 0:  # nan counted no bottom-out
            raise MetricsError(f"{name}: must be a number of mm, not negative, got {given!r}")
    enter = x >= top - margin_mm
    leave = x < top - margin_mm - release_mm
    # only the samples where the state can change (enter and leave exclude each other): an event
    # starts at an entering sample whose last such sample before it left (or that is the first)
    idx = np.flatnonzero(enter | leave)
    if idx.size == 0:
        return idx.astype(int)
    entering = enter[idx]
    first = entering & np.concatenate(([True], ~entering[:-1]))
    return idx[first].astype(int)


def bottom_outs(travel_mm, travel_max_mm: float, margin_mm: float = 3.0, release_mm: float = 5.0) -> int:
    """Number of distinct bottom-outs: travel reaching within ``margin_mm`` of ``travel_max_mm``;
    a new event needs the travel to have dropped below max - margin - ``release_mm`` first."""
    return int(bottom_out_indices(travel_mm, travel_max_mm, margin_mm, release_mm).size)


@dataclass(frozen=True)
class Airtime:
    """Airborne periods (start, end) in s and the rule that found them."""

    periods_s: tuple[tuple[float, float], ...]
    duration_s: float  # of the record
    rule: str

    @property
    def count(self) -> int:
        return len(self.periods_s)

    @property
    def total_s(self) -> float:
        return float(sum(b - a for a, b in self.periods_s))

    def mask(self, time_s) -> np.ndarray:
        """True at the samples of ``time_s`` that fall in an airborne period."""
        t = np.asarray(time_s, dtype=float)
        out = np.zeros(t.shape, dtype=bool)
        for a, b in self.periods_s:
            out |= (t >= a) & (t < b)
        return out

    def to_dict(self) -> dict:
        return {"count": self.count, "total_s": self.total_s,
                "percent": self.total_s / self.duration_s * 100.0 if self.duration_s > 0 else 0.0,
                "periods_s": [[a, b] for a, b in self.periods_s], "rule": self.rule}


def airtime(travel_mm, travel_max_mm: float, time_s, rear_travel_mm=None, rear_travel_max_mm: float | None = None,
            extension_percent: float = 3.0, min_s: float = 0.05, max_s: float = 5.0,
            landing_percent: float = 35.0, landing_window_s: float = 0.25) -> Airtime:
    """Airborne periods by the rule in the module docstring (fork travel, optionally the rear)."""
    x = _array(travel_mm, "travel_mm")
    t = _array(time_s, "time_s")
    dt = sample_interval(t)
    if t.size != x.size:
        raise MetricsError("time_s and travel_mm differ in length")
    ends = [(x, _positive(travel_max_mm, "travel_max_mm"))]
    if rear_travel_mm is not None:
        r = _array(rear_travel_mm, "rear_travel_mm")
        if r.size != x.size:
            raise MetricsError("rear_travel_mm and travel_mm differ in length")
        if rear_travel_max_mm is None:
            raise MetricsError("rear_travel_max_mm: needed with rear_travel_mm")
        ends.append((r, _positive(rear_travel_max_mm, "rear_travel_max_mm")))
    extended = np.ones(x.size, dtype=bool)
    loaded = np.zeros(x.size, dtype=bool)
    for values, top in ends:
        extended &= values <= top * extension_percent / 100.0
        loaded |= values >= top * landing_percent / 100.0
    window = max(1, int(round(landing_window_s / dt)))
    periods = []
    for a, b in zip(*_runs(extended)):
        length = (b - a) * dt
        if a == 0 or b >= x.size or not (min_s <= length <= max_s):
            continue
        if np.any(loaded[b: b + window]):
            periods.append((round(float(t[a]), 9), round(float(t[a] + length), 9)))
    rule = AIRTIME_RULE.format(extension_percent=extension_percent, min_s=min_s, max_s=max_s,
                               landing_percent=landing_percent, landing_window_s=landing_window_s)
    return Airtime(tuple(periods), float(x.size * dt), rule)


def summarize(time_s, travel_mm, travel_max_mm: float, velocity_mm_per_s=None, threshold_mm_per_s: float = 100,
              bin_percent: float = 5, velocity_edges=None, margin_mm: float = 3.0, airborne: Airtime | None = None,
              exclude_airtime: bool = True) -> dict:
    """All the metrics of one suspension end as a JSON-ready dict.

    ``velocity_mm_per_s``: given (e.g. a simulation's own velocity) or None for the
    Savitzky-Golay derivative of travel. ``airborne``: periods found over both ends (see
    ``airtime``), or None to find them from this travel alone; airborne samples are left out of
    the histograms and the travel statistics unless ``exclude_airtime`` is False.
    """
    t = _array(time_s, "time_s")
    x = _array(travel_mm, "travel_mm")
    if t.size != x.size:
        raise MetricsError("time_s and travel_mm differ in length")
    top = _positive(travel_max_mm, "travel_max_mm")
    if top < TRAVEL_MIN_MM:  # 0.18 for a 180 mm fork: metres, and every percentage of travel 1000 times off
        raise MetricsError(f"travel_max_mm: {top:g} mm: no suspension end travels under {TRAVEL_MIN_MM:g} mm; metres? "
                           f"({1000.0 * top:g} mm if so: travel_mm and travel_max_mm in mm)")
    deepest = float(np.max(x))
    if deepest > TRAVEL_OVER * top:  # beyond any bottom-out: the two in different units, or another end's travel
        raise MetricsError(f"travel_mm reaches {deepest:.4g} mm, {deepest / top:.3g} times travel_max_mm ({top:g} mm): "
                           f"the two in different units, or another end's travel")
    dt = sample_interval(t)
    v = velocity(t, x) if velocity_mm_per_s is None else _array(velocity_mm_per_s, "velocity_mm_per_s")
    if v.size != x.size:
        raise MetricsError("velocity_mm_per_s and travel_mm differ in length")
    air = airtime(x, top, t) if airborne is None else airborne
    from mtbmj.limits import switch

    keep = ~air.mask(t) if switch("exclude_airtime", exclude_airtime) else np.ones(x.size, dtype=bool)
    if not np.any(keep):
        keep[:] = True
    xs, vs = x[keep], v[keep]
    travel = travel_histogram(xs, top, bin_percent)
    vel = velocity_histogram(vs, threshold_mm_per_s, velocity_edges)
    bottoms = bottom_out_indices(x, top, margin_mm)
    return {
        "duration_s": float(x.size * dt),
        "samples": int(x.size),
        "sample_rate_Hz": float(1.0 / dt),
        "travel_max_mm": top,
        "travel": {
            "max_mm": float(x.max()),
            "max_percent": float(x.max() / top * 100.0),
            "mean_mm": float(xs.mean()),
            "mean_percent": float(xs.mean() / top * 100.0),
            "p95_percent": float(np.percentile(xs, 95) / top * 100.0),
        },
        "travel_histogram": travel.to_dict(),
        "velocity": vel.to_dict(),
        "bottom_outs": {"count": int(bottoms.size), "margin_mm": float(margin_mm),
                        "times_s": [float(t[i]) for i in bottoms]},
        "airtime": air.to_dict(),
        "histograms_exclude_airtime": bool(exclude_airtime),
    }


def _list(a: np.ndarray) -> list[float]:
    return [float(x) for x in np.asarray(a).ravel()]

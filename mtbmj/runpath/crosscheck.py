"""The one result of a cross-check, for every rig: an engine's run (MuJoCo, or the drop's fast
engine) against the rig's ODE reference from the same initial state (``mtbmj crosscheck``; the
drop in ``mtbmj.drop.crosscheck``, the rolling front end in ``mtbmj.rolling.reference``, the
bike in ``mtbmj.bike.crosscheck``).

Each rig names the signals it compares. A signal is compared over its whole series, sample by
sample on the engine's time grid (``compare_series``): its largest absolute difference and the
time it occurs, and its peak (its largest value) in both runs. A signal is judged against a
tolerance, or reported beside the judged ones (no tolerance):

* in its own unit (``relative=False``; the displacements): the series' largest difference
  (``series_difference``), and, if the rig asks, the difference of the peaks;
* relative to the reference's peak (``relative=True``; the forces): the difference of the peaks
  over the reference's peak (``peak_difference``) and, if the rig asks, the series' largest
  difference over the reference's peak.

A measure that is not finite fails; equal to its tolerance passes. The check passes when every
judged measure of every signal does. ``CrosscheckResult.line`` is the terminal's one line,
``CrosscheckResult.to_dict`` the JSON (``CrosscheckResult.from_dict`` reads it back).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

MEASURES = ("series", "peak")
ENGINE_LABELS = {"mujoco": "MuJoCo", "fast": "fast engine"}


def number(value: float) -> str:
    """A difference for the terminal: four decimals, or two significant digits below a thousandth
    (``nan`` and ``inf`` as such)."""
    return f"{value:.4f}" if value >= 1e-3 or value == 0.0 else f"{value:.1e}"


def percent(fraction: float) -> str:
    """A relative difference in per cent: two decimals, or two significant digits below 0.01 %."""
    p = 100.0 * fraction
    return f"{p:.2f}" if p >= 0.01 or p == 0.0 else f"{p:.1e}"


# A relative measure is over the reference's peak, but never over less than this (per unit): a
# force below 1 N is no load, and a round-off of 3e-14 N against a peak of exactly 0 (the rolling
# front end's backward force on flat ground) is no difference.
RELATIVE_FLOOR = {"N": 1.0}


def _over(value: float, peak: float, unit: str = "") -> float:
    """``value`` over ``|peak|`` (at least the unit's ``RELATIVE_FLOOR``); against a zero scale,
    0 for no difference and infinity for any."""
    scale = max(abs(peak), RELATIVE_FLOOR.get(unit, 0.0))
    if scale == 0.0:
        return 0.0 if value == 0.0 else math.inf
    return value / scale


def _finite_or_none(value):
    return value if value is None or math.isfinite(value) else None


def _float(value) -> float:
    """A JSON number back to a float (``None``, written for a value that was not finite: nan)."""
    return math.nan if value is None else float(value)


@dataclass(frozen=True)
class SignalCheck:
    """One signal of a cross-check: the largest |engine - reference| over the series (``max_abs``,
    in ``unit``) and its time, the series' peaks in both runs, and how it is judged
    (``tolerance``; ``None``: reported, not judged)."""

    name: str
    unit: str
    max_abs: float
    at_time_s: float
    engine_peak: float
    reference_peak: float
    tolerance: float | None = None
    relative: bool = False  # the tolerance and the measures are fractions of the reference's peak
    judged: tuple[str, ...] = ()  # which of MEASURES the tolerance holds

    def __post_init__(self):
        object.__setattr__(self, "judged", tuple(self.judged))
        unknown = [m for m in self.judged if m not in MEASURES]
        if unknown or len(set(self.judged)) != len(self.judged):
            raise ValueError(f"{self.name}: judged must name each of {', '.join(MEASURES)} at most once, "
                             f"got {self.judged}")
        if (self.tolerance is None) != (not self.judged):
            raise ValueError(f"{self.name}: a tolerance needs the measures it judges, and judged measures a tolerance")
        if self.tolerance is not None and not (math.isfinite(self.tolerance) and self.tolerance > 0.0):
            raise ValueError(f"{self.name}: the tolerance must be a positive number, got {self.tolerance}")

    @property
    def label(self) -> str:
        return self.name.replace("_", " ")

    @property
    def series_difference(self) -> float:
        """The series' largest difference: in ``unit``, or over the reference's peak when relative."""
        return _over(self.max_abs, self.reference_peak, self.unit) if self.relative else self.max_abs

    @property
    def peak_difference(self) -> float:
        """|engine peak - reference peak|: in ``unit``, or over the reference's peak when relative."""
        gap = abs(self.engine_peak - self.reference_peak)
        return _over(gap, self.reference_peak, self.unit) if self.relative else gap

    def measure(self, which: str) -> float:
        return {"series": self.series_difference, "peak": self.peak_difference}[which]

    def within(self, which: str) -> bool:
        """Is the measure ``which`` finite and within the tolerance?"""
        value = self.measure(which)
        return math.isfinite(value) and value <= self.tolerance

    @property
    def passed(self) -> bool | None:
        """Every judged measure within the tolerance; ``None`` for a signal only reported."""
        return all(self.within(m) for m in self.judged) if self.judged else None

    @property
    def ratio(self) -> float | None:
        """The largest judged measure over the tolerance (infinity for one not finite)."""
        if not self.judged:
            return None
        ratios = [self.measure(m) / self.tolerance for m in self.judged]
        return max(r if math.isfinite(r) else math.inf for r in ratios)

    def _tolerance_text(self) -> str:
        return f"{100 * self.tolerance:g} %" if self.relative else f"{self.tolerance:g} {self.unit}"

    def _mark(self, which: str) -> str:
        if which not in self.judged:
            return ""
        return f" ({'tol.' if self.within(which) else 'EXCEEDS'} {self._tolerance_text()})"

    def text(self) -> str:
        """The signal in the line: its differences and, for each judged one, its tolerance."""
        if self.relative:
            return (f"{self.label} peak {percent(self.peak_difference)} %{self._mark('peak')} and series "
                    f"{percent(self.series_difference)} % of the peak{self._mark('series')}")
        out = f"{self.label} {number(self.series_difference)} {self.unit}{self._mark('series')}"
        if "peak" in self.judged:
            out += f" and peak {number(self.peak_difference)} {self.unit}{self._mark('peak')}"
        return out

    def to_dict(self) -> dict:
        return {"unit": self.unit, "max_abs": _finite_or_none(self.max_abs),
                "at_time_s": _finite_or_none(self.at_time_s), "engine_peak": _finite_or_none(self.engine_peak),
                "reference_peak": _finite_or_none(self.reference_peak), "relative": self.relative,
                "series_difference": _finite_or_none(self.series_difference),
                "peak_difference": _finite_or_none(self.peak_difference), "tolerance": self.tolerance,
                "judged": list(self.judged), "passed": self.passed}

    @classmethod
    def from_dict(cls, name: str, d: Mapping) -> "SignalCheck":
        return cls(name, d["unit"], _float(d["max_abs"]), _float(d["at_time_s"]), _float(d["engine_peak"]),
                   _float(d["reference_peak"]), d["tolerance"], bool(d["relative"]), tuple(d["judged"]))


def compare_series(name: str, unit: str, times, engine, reference, tolerance: float | None = None,
                   relative: bool = False, judged: Sequence[str] | None = None) -> SignalCheck:
    """A signal compared sample by sample: ``engine`` and ``reference`` on the grid ``times`` (s).
    ``judged`` defaults to the series when a tolerance is given."""
    t = np.asarray(times, dtype=float)
    e, r = np.asarray(engine, dtype=float), np.asarray(reference, dtype=float)
    if not (t.shape == e.shape == r.shape) or t.ndim != 1 or t.size == 0:
        raise ValueError(f"{name}: the engine's and the reference's series must share one non-empty time grid, "
                         f"got {e.shape}, {r.shape} on {t.shape}")
    gap = np.abs(e - r)
    i = int(np.argmax(gap))  # the first nan, if any: a series that is not finite is a difference that is not
    if judged is None:
        judged = ("series",) if tolerance is not None else ()
    return SignalCheck(name, unit, float(gap[i]), float(t[i]), float(np.max(e)), float(np.max(r)), tolerance,
                       relative, tuple(judged))


@dataclass(frozen=True)
class CrosscheckResult:
    """A rig's cross-check: ``rig`` ("drop", "roll", "bike") and ``case`` (what ran, as the line
    names it), the ``engine`` under test against ``reference``, the compared ``signals`` (in the
    rig's order), both wall times, and ``context`` (the rig's own details: configuration,
    scenario, speed, drive, ...)."""

    rig: str
    case: str
    engine: str
    reference: str
    signals: tuple[SignalCheck, ...]
    engine_wall_s: float
    reference_wall_s: float
    context: Mapping = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "signals", tuple(self.signals))
        object.__setattr__(self, "context", dict(self.context))
        names = [s.name for s in self.signals]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.rig} {self.case}: signal names repeat: {names}")
        if not self.judged:
            raise ValueError(f"{self.rig} {self.case}: a cross-check judges at least one signal")

    def __getitem__(self, name: str) -> SignalCheck:
        for s in self.signals:
            if s.name == name:
                return s
        raise KeyError(f"{name!r}: not a signal of this cross-check ({', '.join(s.name for s in self.signals)})")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.signals)

    @property
    def judged(self) -> tuple[SignalCheck, ...]:
        return tuple(s for s in self.signals if s.judged)

    @property
    def passed(self) -> bool:
        return all(s.passed for s in self.judged)

    @property
    def worst(self) -> SignalCheck:
        """The judged signal nearest its tolerance, or furthest beyond it (the first of equals)."""
        return max(self.judged, key=lambda s: s.ratio)

    def line(self) -> str:
        worst = self.worst
        verdict = "within the tolerances" if self.passed else "NOT within the tolerances"
        return (f"{self.rig} {self.case}: {ENGINE_LABELS.get(self.engine, self.engine)} vs the {self.reference}, "
                f"max |diff| {', '.join(s.text() for s in self.signals)}; {verdict} (worst {worst.label}, its largest "
                f"difference at t = {worst.at_time_s:.4f} s; engine {self.engine_wall_s:.2f} s, reference "
                f"{self.reference_wall_s:.2f} s)")

    def to_dict(self) -> dict:
        return {"rig": self.rig, "case": self.case, "engine": self.engine, "reference": self.reference,
                "passed": self.passed, "worst": self.worst.name,
                "signals": {s.name: s.to_dict() for s in self.signals},
                "engine_wall_s": self.engine_wall_s, "reference_wall_s": self.reference_wall_s,
                "context": dict(self.context)}

    @classmethod
    def from_dict(cls, d: Mapping) -> "CrosscheckResult":
        """The result ``to_dict`` wrote (its derived entries, ``passed``, ``worst`` and each
        signal's differences and verdict, are computed again)."""
        return cls(d["rig"], d["case"], d["engine"], d["reference"],
                   tuple(SignalCheck.from_dict(n, s) for n, s in d["signals"].items()),
                   float(d["engine_wall_s"]), float(d["reference_wall_s"]), dict(d.get("context", {})))


__all__ = ["CrosscheckResult", "SignalCheck", "compare_series", "number", "percent", "ENGINE_LABELS", "MEASURES"]

"""A ride reconstructed through the bike (``mtbmj reconstruct``): the speed along the ride from the lag
between the two ends, the terrain under the front wheel from the fork's record through the bike
file's whole bike, and the rear's record predicted from that terrain and compared with the measured
one, beside two naive baselines.

**Speed** (:mod:`mtbmj.ride.reconstruct_speed`). The rear wheel meets what the front met a wheelbase
later: per window of ``WINDOW_S`` seconds, the lag that best aligns the grounds each end's own
quarter-car inverse finds (high-passed at 1 Hz: each end's suspension delays its travel by a phase of
its own, the grounds carry none), or where those give no speed in that window, the ends' travel
velocities (high-passed at 5 Hz), gives v = wheelbase / lag, the wheelbase at the ride's sag
(:func:`wheelbase_at`, the median travel of each end). A window's rejections and standard error are
that module's; the windows start every half window (overlapping), the speed between the accepted
windows' centres is linear (held past the first and last), a sample in no accepted window left out
of the checks (between these strict windows, within 20 s of one, a speed tracked through the windows'
correlograms: :func:`mtbmj.ride.reconstruct_speed.tracked`, each window marked strict or tracked), the distance along the ride its integral, the rear's lag wheelbase / v(t). Then the speed is found
again (``REFINE_PASSES`` times, :func:`mtbmj.ride.reconstruct_speed.refine`), on a ride whose first
pass predicts the rear better than both naive baselines (below; elsewhere the rear predicted's timing
is the model's more than the ride's, and the first estimate stands): the rear predicted
through the whole bike over the terrain laid at those lags and the rear's record are the same kind
of series, so the shift left between them (searched within half the lag, per 2.5 s window) says
how far each lag is off; where they align, that speed replaces the first, and the terrain is found
again at it (the rear's record sets when the rear met what the front met, never a height). A
version-2
record (5 kHz of coarse encoder steps) is low-passed at ``V2_LOWPASS_HZ`` and read at ``RATE_HZ``. A
ride with no window that gives a speed, or whose windows with one lie wholly where nothing can be
checked, is refused: no speed estimate, one line, nothing written. A speed given by the rider (``speed=``:
:mod:`mtbmj.ride.reconstruct_given`) is used in place of all this, the lag's sought and compared beside it.

**Terrain** (:mod:`mtbmj.ride.reconstruct_bike`, from the fork's record alone: the rear's record is
never used to make it). A first guess from the front's quarter car (:mod:`mtbmj.ride.
reconstruct_inverse`: closed form, the body's drift removed below 0.3 Hz, a fork hanging on its
top-out stop flying with its wheel, flights merged and bridged by the chord); then the whole bike
(the frame pitching, the rider on his legs and arms, both wheels, the fork's and shock's laws, the
tyres) rides with its fork's stroke prescribed by the record, the ground under the front wheel found
at every sample, its rear wheel over the ground of the pass before a wheelbase later, until the rear
predicted settles. The fork's slow load (below 0.3 Hz) is the rider's; the frame's front is held
near the quarter car's slow height by a load bounded by half the rider's weight (the rider's slow
load, estimated). Take-offs: where the tyre's force falls to zero or the fork hangs on its top-out
stop (a tyre light but above zero is not: docs/rolling.md, "A light tyre"; two such
stretches one flight where the force between them averages under 10 % of its load at rest), a
flight of 0.1 s or more from where the force last fell below 10 % of its load at rest
(``reconstruct_inverse.unloaded``); a flight that long landing more than 0.15 m lower bridged by the
landing's level from the take-off on (a drop's edge), any other by the chord; the landing where the
force returns. Each drop's edge flight's level change is read by the whole bike and kept in its slow
reference where its duration allows it (:mod:`mtbmj.ride.reconstruct_flight`), else left. The terrain written to ride
(``terrain.csv``, advise's runs) has a fall its landing's speed cannot give cut (:mod:`mtbmj.ride.reconstruct_landing`).

**Checks.** The whole bike free over the terrain found (the rider's slow load on its front)
reproduces the front record (its RMS difference); the rear predicted (the whole bike's rear in the last
pass; its rear wheel meets at the front's moment the share of the ground found that its own spectrum says
is a load on both ends at once, :mod:`mtbmj.ride.reconstruct_share`) is compared with the rear record beside
two naive baselines on the same samples: the fork's record delayed by wheelbase / v(t) with a least-squares
scale and offset, and the rear's mean.
The reconstruction passes only if its rear's RMS error is ``BEAT_MARGIN`` (40 %) below the better, and
its line says in words whether the model describes the ride. Reported beside, never judged by: the
fork's record at the same moment with its own least-squares scale and offset (``fork_at_once_rms_mm``:
on the shared rides the rear follows the fork at once more than a wheelbase later), and per band
(:mod:`mtbmj.ride.reconstruct_bands`) when the rear moves against the prediction and the fork; with
``reconstruct(..., at_once=True)`` also the rear with a share of its ground met at the front's moment
(a load on both ends at once, a turn or a compression, rather than the terrain a wheelbase ahead),
that share fitted on the rear's record (:func:`at_once_share`: the timing alone, one number, never a
height; ``Reconstruction.at_once_fit``). Fitted, it would let a wrong bike pass (the made ride read
with the fork spring 1.5 times did), so it is never judged. Also beside, never judged by: what the
fork's record holds about the rear (:mod:`mtbmj.ride.reconstruct_bound`: a linear filter from the
fork's record fitted on the rear's itself, tested where it was not fitted); where the reconstruction
fails, that bound misses the pass mark too and in 0.5-2 Hz the rear moves with the fork at once more
than a wheelbase later, the line says the fork's record holds too little about the ride's rear to
check the model (a load on both ends, which the front's record alone cannot tell from terrain).
Where the whole bike diverges (finding
the terrain or riding it) the line says where, and the ride is not described. Also the RMS in % of
the rear travel the ride used and the distance between the two travel histograms.

Assumed: the whole bike in the plane with small pitch angles and vertical motion only (the wheelbase
at sag; fore and aft the frame's pitch carries the rider and the wheels, the bike's horizontal momentum
free: ``reconstruct_bike.carried_inertia``), point-contact tyres without damping, the fork's slow load the rider's (the rear given
none), the ground under a flight of 0.1 s or more the landing's level from the take-off on where
the wheel lands more than 0.15 m lower (a drop's edge where it left), else the chord. Measured numbers:
docs/rolling.md and docs/measured.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from mtbmj.measured.telemetry import both_ends
from mtbmj.ride.reconstruct_inverse import QuarterCar, forward, ground_under, lowpass, runs, wheelbase_at
from mtbmj.ride.reconstruct_inverse import HIGHPASS_HZ, V2_LOWPASS_HZ, within_stops
from mtbmj.ride.reconstruct_bands import BANDS, BEAT_MARGIN, band_checks  # noqa: F401 (BANDS: this module's name too)
from mtbmj.ride.reconstruct_bands import at_once_share, timing_error
from mtbmj.ride.reconstruct_bound import fork_filter_bound
from mtbmj.ride.reconstruct_share import described
from mtbmj.ride import reconstruct_envelope as envelope
from mtbmj.ride import reconstruct_given as given_mod
from mtbmj.ride import reconstruct_landing as landing
from mtbmj.ride.reconstruct_flight import landed
from mtbmj.ride.reconstruct_speed import (GROUND_HIGHPASS_HZ, LAG_HIGHPASS_HZ, WINDOW_S, ReconstructError,
                                          check_length, merged, min_seconds, refine, speed_from_either,
                                          speed_from_lag, tracked, TRACK_ANCHOR_S, TRACK_MARGIN, TRACK_SD)
# The rate a ride is read at (the version-3 recorder's): a faster record is low-passed and decimated
# to it (``TelemetryRecord.decimated``), so two derivatives do not amplify its count steps and a
# 100 s ride at 5 kHz costs what it costs at 1 kHz
RATE_HZ = 1000.0
STAND_MM = 0.5  # both ends this close to full extension for longer than a flight: the bike stands unweighted


def histogram_distance(a, b, top: float, bins: int = 20) -> float:
    """Sum of |time share differences| (%) of two travel histograms over 0..top in ``bins`` bins."""
    edges = np.linspace(0.0, top, bins + 1)
    ha = np.histogram(np.clip(a, 0, top), edges)[0] / max(a.size, 1)
    hb = np.histogram(np.clip(b, 0, top), edges)[0] / max(b.size, 1)
    return float(100.0 * np.sum(np.abs(ha - hb)))


TERRAIN_LEAD_IN_M = 3.0  # terrain.csv starts on this much level ground before the ride's first metre
REFINE_PASSES = 2  # the speed found again from the rear predicted, and the terrain at it, this many times
LEFT_OUT_S = 0.2  # around an airborne stretch, this much either side is left out of the checks


def _statics(spec):
    """(total mass kg, the front wheel's share of the weight) at rest, level (moments about the rear axle)."""
    from mtbmj.bike.model import centre_of_mass

    total, (x, _) = centre_of_mass(spec)
    return total, (x - spec.rear_axle[0]) / (spec.front_axle[0] - spec.rear_axle[0])


@dataclass
class Reconstruction:
    """A ride through a bike's laws (``reconstruct``); SI units inside, see the module doc."""

    name: str
    bike: str
    t: np.ndarray
    speed: dict
    distance: np.ndarray  # m along the ride at each sample
    ground: np.ndarray  # m, under the front wheel
    valid: np.ndarray  # samples the checks count (the front on the ground, and a wheelbase later the rear)
    front: np.ndarray  # fork travel measured (mm)
    front_again: np.ndarray  # fork travel of the front quarter car over the terrain found (mm)
    rear: np.ndarray  # rear wheel travel measured (mm)
    rear_predicted: np.ndarray  # rear wheel travel predicted (mm)
    rear_top: float  # the rear wheel's full travel (mm)
    jumps: list  # (start s, end s) the front wheel was off the ground
    unaligned: list = None  # (start s, end s) windows with no speed (standing, or the ends do not align)
    fork_delayed: np.ndarray = None  # fork travel measured (mm) delayed by wheelbase / speed(t): a baseline's input
    wheelbase: float = math.nan  # m, at the ride's sag
    passes: int = 0  # the whole bike's passes over the terrain (reconstruct_bike.terrain_and_rear)
    settled_m: float = math.nan  # the rear predicted's RMS change in the last pass
    diverged_s: float | None = None  # where the whole bike diverged (finding the terrain or riding it), or None
    part_s: tuple | None = None  # (start, end) s of the record reconstructed where it stood unweighted mid-ride, or None
    stands: list = None  # (start s, end s) of the record: the bike standing unweighted mid-ride (its rider off it)
    at_once: float = 0.0  # the share of the rear's ground met at the front's moment (at_once_share), 0..1
    at_once_fit: dict | None = None  # reconstruct(at_once=True): the rear with that share fitted (fitted_summary)
    spectral: dict | None = None  # the found ground's share met at once (reconstruct_share.described), None: not used
    cut: list = None  # an end's record read at most PAST_TRAVEL_M past its travel (within_stops), what was cut
    levels: list = None  # each drop's edge flight's level change read, kept or left (reconstruct_flight.described)
    beyond: list = None  # where the ground found rises more than the bike could climb (reconstruct_envelope.beyond)
    ridden: np.ndarray = None  # m, the ground to ride (terrain.csv, advise): a fall its landing cannot give cut; None: ground
    landings: list = None  # each flight of both ends judged by its landing's speed (reconstruct_landing.judged)
    _bound: dict | None = field(default=None, init=False, repr=False, compare=False)  # fork_bound's, once

    ridden_ground = property(lambda self: self.ground if self.ridden is None else self.ridden)  # terrain.csv's

    def fork_bound(self) -> dict | None:
        """What the fork's record holds about the rear on the samples checked
        (``reconstruct_bound.fork_filter_bound``: a linear filter from the fork's record fitted on the
        rear's itself, cross-validated), computed once."""
        if self._bound is None:
            self._bound = fork_filter_bound(self.t, self.front, self.rear, self.valid, self.lags) or {}
        return self._bound or None

    @property
    def fork_delayed_or_front(self) -> np.ndarray:
        """The delayed-fork baseline's input: the fork's record delayed by wheelbase / speed(t), or as
        recorded where no delay was given."""
        return self.fork_delayed if self.fork_delayed is not None else self.front

    @property
    def lags(self) -> np.ndarray | None:
        """The rear's lag behind the front at each sample (s): wheelbase / speed(t); None without a speed."""
        at = self.speed.get("speed_at")
        return None if at is None or not math.isfinite(self.wheelbase) else self.wheelbase / at(self.t)

    def baselines(self) -> dict:
        """The two naive predictions of the rear the model must beat, on the samples checked: (a) the
        fork's record delayed by wheelbase / speed(t) with a least-squares scale and offset (fitted
        on those very samples), (b) the rear's mean. {"delayed_fork_mm": series, "delayed_fork_scale",
        "delayed_fork_offset_mm", "mean_mm"}."""
        v = self.valid
        fd = self.fork_delayed_or_front
        A = np.column_stack((fd[v], np.ones(int(v.sum()))))
        (a, b), *_ = np.linalg.lstsq(A, self.rear[v], rcond=None)
        return {"delayed_fork_mm": a * fd + b, "delayed_fork_scale": float(a), "delayed_fork_offset_mm": float(b),
                "mean_mm": float(np.mean(self.rear[v]))}

    def checks(self) -> dict:  # noqa: D401 (the checks reported with every reconstruction)
        """The checks (:meth:`_checked`), worked out once for the fields as they are (again where a field
        was set anew); a copy each call, so a caller's change to it stays the caller's."""
        import copy

        now = tuple(getattr(self, f.name) for f in fields(self) if f.compare)  # not the memos (_bound)
        memo = self.__dict__.get("_checks_memo")
        if memo is None or len(memo[0]) != len(now) or any(a is not b for a, b in zip(memo[0], now)):
            memo = self.__dict__["_checks_memo"] = (now, self._checked())
        return copy.deepcopy(memo[1])

    def _checked(self) -> dict:
        v = self.valid
        if not v.any():  # ``reconstruct`` refuses such a ride; no mean of nothing is taken here either
            nan = float("nan")
            return {"front_reproduced_rms_mm": nan, "rear_predicted_rms_mm": nan, "rear_travel_used_mm": nan,
                    "baseline_delayed_fork_rms_mm": nan, "baseline_rear_mean_rms_mm": nan, "passes": False,
                    "verdict": "the model does not describe this ride: " + (
                        f"the whole bike diverged at {self.diverged_s:.2f} s (finding the terrain or riding it): "
                        if self.diverged_s is not None else "") + "no sample of it can be checked",
                    "rear_predicted_rms_percent_of_used": nan, "rear_histogram_distance_percent": nan,
                    "samples_checked_percent": 0.0, "bands": [], "bound_fork_filter_rms_mm": None,
                    "bound_misses_mark": False, "front_holds_too_little": False}
        used = float(np.ptp(self.rear[v]))
        rms_front = float(np.sqrt(np.mean((self.front_again[v] - self.front[v]) ** 2)))
        rms_rear = float(np.sqrt(np.mean((self.rear_predicted[v] - self.rear[v]) ** 2)))
        base = self.baselines()
        rms_fork = float(np.sqrt(np.mean((base["delayed_fork_mm"][v] - self.rear[v]) ** 2)))
        rms_mean = float(np.sqrt(np.mean((base["mean_mm"] - self.rear[v]) ** 2)))
        need = (1.0 - BEAT_MARGIN) * min(rms_fork, rms_mean)
        passes = bool(rms_rear <= need) and self.diverged_s is None
        bands = band_checks(self.t, self.rear, self.rear_predicted, self.fork_delayed_or_front, v, fork=self.front,
                            lags=self.lags)
        bound = self.fork_bound()  # reported beside, never judged by
        rms_bound = bound["rms_mm"] if bound else None  # None (JSON null): too few samples checked for its folds
        misses = bool(rms_bound is not None and rms_bound > need)
        # the rear moving with the fork at once in the body's band: what the front's record cannot tell from terrain
        body = next((b["timing"] for b in bands if b["band_Hz"] == [0.5, 2.0] and "timing" in b), None)
        at_once = body is not None and body["fork_now_correlation"] > body["fork_at_lag_correlation"]
        too_little = misses and at_once and not passes and self.diverged_s is None
        if self.diverged_s is not None:
            verdict = (f"the model does not describe this ride: the whole bike diverged at {self.diverged_s:.2f} s "
                       f"(finding the terrain or riding it); before it the rear predicted {rms_rear:.1f} mm RMS "
                       f"against {min(rms_fork, rms_mean):.1f} mm of the better naive baseline")
        elif passes:
            verdict = (f"the model describes this ride: the rear predicted within {rms_rear:.1f} mm RMS, "
                       f"{100.0 * (1.0 - rms_rear / min(rms_fork, rms_mean)):.0f} % below the better naive baseline")
        else:
            which = ("a delayed copy of the fork" if rms_fork <= rms_mean else "the rear's mean travel")
            verdict = (f"the model does not describe this ride: it does not beat {which} by "
                       f"{100 * BEAT_MARGIN:.0f} %: the rear predicted "
                       f"{rms_rear:.1f} mm RMS against {min(rms_fork, rms_mean):.1f} mm (the delayed fork "
                       f"{rms_fork:.1f}, the mean {rms_mean:.1f}; a pass needs {100 * BEAT_MARGIN:.0f} % below "
                       f"the better, {need:.1f} mm)")
        if too_little:
            verdict += (f"; the fork's record holds too little about this ride's rear to check the model (a linear "
                        f"filter from the fork's record fitted on the rear itself reaches {rms_bound:.1f} mm RMS where "
                        f"it was not fitted, the mark is {need:.1f} mm): in 0.5-2 Hz the rear moves with the fork at "
                        f"once (correlation {body['fork_now_correlation']:.2f}, a wheelbase later "
                        f"{body['fork_at_lag_correlation']:.2f}), a load on both ends, which the front's record alone "
                        f"cannot tell from terrain")
        A = np.column_stack((self.front[v], np.ones(int(v.sum()))))  # reported beside, not judged by
        rms_now = float(np.sqrt(np.mean((A @ np.linalg.lstsq(A, self.rear[v], rcond=None)[0] - self.rear[v]) ** 2)))
        return {"front_reproduced_rms_mm": rms_front, "rear_predicted_rms_mm": rms_rear,
                "baseline_delayed_fork_rms_mm": rms_fork, "baseline_rear_mean_rms_mm": rms_mean,
                "fork_at_once_rms_mm": rms_now,
                "baseline_delayed_fork_scale": base["delayed_fork_scale"],
                "beat_margin_percent": 100.0 * BEAT_MARGIN, "pass_mark_rms_mm": need, "passes": passes,
                "verdict": verdict, "bound_fork_filter_rms_mm": rms_bound, "bound_fork_filter": bound,
                "bound_misses_mark": misses, "front_holds_too_little": too_little,
                "rear_travel_used_mm": used, "rear_predicted_rms_percent_of_used": 100.0 * rms_rear / used,
                "rear_histogram_distance_percent": histogram_distance(self.rear[v], self.rear_predicted[v],
                                                                        self.rear_top),
                "samples_checked_percent": 100.0 * float(np.mean(v)),
                "bands": bands}

    def fitted_summary(self, valid) -> dict:
        """This reconstruction's rear on the ``valid`` samples of another (the one judged): its share of the
        rear's ground met at once, the rear predicted's RMS error and correlation, and per band its error
        and correlation (``reconstruct_bands.band_checks``)."""
        v = valid & np.isfinite(self.rear_predicted)
        e = self.rear_predicted[v] - self.rear[v]
        bands = band_checks(self.t, self.rear, self.rear_predicted, self.fork_delayed_or_front, v)
        return {"share": self.at_once, "rear_predicted_rms_mm": float(np.sqrt(np.mean(e * e))),
                "rear_predicted_rms_less_mean_mm": float(np.std(e)),
                "rear_correlation": float(np.corrcoef(self.rear_predicted[v], self.rear[v])[0, 1]),
                "samples_percent_of_judged": 100.0 * float(v.sum()) / max(int(valid.sum()), 1),
                "bands": [{k: b[k] for k in ("band_Hz", "predicted_error_rms_mm", "predicted_correlation")}
                          for b in bands],
                "diverged_s": self.diverged_s, "fitted_on": "the rear's record (its timing alone: one number)",
                "judged": False}

    def speed_cover(self) -> dict:
        """How much of the ride lies within a window with a speed: any (strict or tracked, the refined
        estimate's and the first's) and strict alone, in % of its duration; and the windows tracked."""
        covered = {"any": np.zeros(self.t.size, bool), "strict": np.zeros(self.t.size, bool)}
        dt = float(self.t[1] - self.t[0])
        tracked = 0
        for stage in (self.speed, self.speed.get("first")):
            kinds = (stage or {}).get("kinds") or [None] * len((stage or {}).get("windows", []))
            for (start, v, _), kind in zip((stage or {}).get("windows", []), kinds):
                if v is None:
                    continue
                i, n = int(round(start / dt)), int(round(stage.get("window_s", WINDOW_S) / dt))
                covered["any"][max(i, 0):i + n] = True
                if kind not in ("tracked", "given"):
                    covered["strict"][max(i, 0):i + n] = True
                tracked += kind == "tracked"
        return {"speed_covers_percent": 100.0 * float(np.mean(covered["any"])),
                "strict_covers_percent": 100.0 * float(np.mean(covered["strict"])), "windows_tracked": tracked}

    def summary(self) -> dict:
        def listed(stage):
            sds = stage.get("sd") or [None] * len(stage["windows"])
            whys = stage.get("why") or [None] * len(stage["windows"])
            width = stage.get("window_s", WINDOW_S)
            kinds = stage.get("kinds") or [None if v is None else "strict" for _, v, _ in stage["windows"]]
            return [{"start_s": float(a), "end_s": float(a + width), "speed_m_per_s": None if v is None else float(v),
                     "speed_sd_m_per_s": None if sd is None else float(sd), "correlation": float(c) if c == c else None, "kind": kind,
                     "rejected": None if v is not None else (why or "no speed")}
                    for (a, v, c), sd, why, kind in zip(stage["windows"], sds, whys, kinds)]

        speeds = [s for _, s, _ in self.speed["windows"] if s is not None]
        windows = listed(self.speed)
        first = self.speed.get("first")
        profile = {"median_m_per_s": self.speed["speed_m_per_s"],
                   "min_m_per_s": min(speeds) if speeds else None,
                   "max_m_per_s": max(speeds) if speeds else None,
                   "windows_accepted": len(speeds),
                   "windows_rejected": len(windows) - len(speeds),
                   "window_s": float(self.speed.get("window_s", WINDOW_S)),
                   "found_from": self.speed.get("found_from") or ("the lag left between the rear's record and the rear predicted over the terrain "
                                  "found (its timing only), the two ends' lag kept where those do not align"
                                  if first is not None else "the lag between the two ends"),
                   "between_windows": "linear between the accepted windows' centres, held past the "
                                      "first and last; the distance integrated from it",
                   "kinds": "each window's kind: strict (its own lag, every rejection) or tracked (between strict "
                            f"windows, within {TRACK_ANCHOR_S:g} s of one and {100 * TRACK_MARGIN:.0f} % of their "
                            f"speeds, its standard error {100 * TRACK_SD:.0f} % of its speed)",
                   **self.speed_cover()}
        if first is not None:
            firsts = [s for _, s, _ in first["windows"] if s is not None]
            profile["first_estimate"] = {"from": "the lag between the two ends", "window_s": float(first["window_s"]),
                                         "windows_accepted": len(firsts),
                                         "windows_rejected": len(first["windows"]) - len(firsts),
                                         "windows_kept": int(self.speed.get("first_kept", 0)),
                                         "windows_tracked": sum(1 for k in first.get("kinds") or [] if k == "tracked"),
                                         "windows": listed(first)}
        part = {} if self.part_s is None else {
            "record_part_s": [float(self.part_s[0]), float(self.part_s[1])],
            "stood_unweighted_s": [[float(a), float(b)] for a, b in self.stands],
            "record_part_why": "the bike stood unweighted mid-ride (both ends fully out, its rider off it), which the "
                               "whole bike with its rider on cannot ride: the longest part ridden is reconstructed, "
                               "its times from its own start"}
        part.update({"read_within_stops": self.cut} if self.cut else {})  # past an end's stop: its calibration
        return {"ride": self.name, "bike": self.bike, "duration_s": float(self.t[-1] - self.t[0]), **part,
                "speed_m_per_s": self.speed["speed_m_per_s"], "lag_s": self.speed["lag_s"],
                "speed_from": self.speed.get("from"), "wheelbase_at_sag_m": float(self.wheelbase),
                "speed_profile": profile, **given_mod.summary(self.speed),
                **({} if self.at_once_fit is None else {"at_once_fit": self.at_once_fit}),
                **({} if self.spectral is None else {"at_once_spectral": self.spectral}),
                "windows": windows,
                "window_speeds_m_per_s": [None if s is None else float(s) for _, s, _ in self.speed["windows"]],
                "window_speed_range_m_per_s": [min(speeds), max(speeds)] if speeds else None,
                "terrain_length_m": float(self.distance[-1]),
                "terrain_csv_lead_in_m": TERRAIN_LEAD_IN_M,
                "flights": [{"start_s": float(a), "end_s": float(b)} for a, b in self.jumps],
                "drop_levels": self.levels or [], "beyond_trail": self.beyond or [], "landings": self.landings or [],
                "left_out": [{"start_s": a, "end_s": b, "why": "no speed: standing, or the two ends do not align here"}
                             for a, b in (self.unaligned or [])],
                "whole_bike": {"passes": int(self.passes),
                               "settled_mm": 1e3 * float(self.settled_m) if math.isfinite(self.settled_m) else None,
                               "diverged_s": self.diverged_s},
                "checks": self.checks(),
                "assumed": "the whole bike of the bike file in the plane (frame pitch, the rider on vertical legs and "
                           "arms), vertical motion only, the frame's pitch carrying the rider and wheels fore and aft, "
                           "the wheelbase at sag, point-contact tyres without damping, "
                           "the fork's slow load the rider's (the rear given none), the ground under a flight of "
                           "0.1 s or more the landing's level from the take-off on where the wheel lands more than "
                           "0.15 m lower (a drop's edge; its level change kept where the flight's duration allows it), "
                           "else the chord from take-off to landing, the speed linear "
                           "between the windows that gave one (mtbmj/ride/reconstruct.py)"}

    def speed_along(self) -> tuple:
        """(x m, v m/s): the ride's speed at each place of the terrain found (the distance's rate on the ride's
        time: the speed profile, linear between its windows), for a run that rides it as it was ridden
        (``run_bike(..., speed_profile=)``); clipped to 0.5-30 m/s."""
        keep = np.concatenate(([True], np.diff(self.distance) > 1e-9))
        x, t = self.distance[keep], self.t[keep]
        return x, np.clip(np.gradient(x, t), 0.5, 30.0)

    def line(self) -> str:
        s = self.summary()
        c = s["checks"]
        rng = s["window_speed_range_m_per_s"]
        spread = f" (windows {rng[0]:.2f}-{rng[1]:.2f})" if rng else ""
        kept = sum(r["kept"] for r in self.levels or [])
        p = s["speed_profile"]
        f = p.get("first_estimate")
        refined = ("" if f is None else f" of {p['window_s']:g} s aligning the rear predicted (and "
                   f"{f['windows_kept']} of the ends' lag)")
        part = ("" if self.part_s is None else
                f" (the record's {self.part_s[0]:.1f}-{self.part_s[1]:.1f} s, its times from there: the bike stood "
                f"unweighted at " + ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in self.stands) + ")")
        said = given_mod.words(self.speed) if "given" in self.speed else (
            f"speed {s['speed_m_per_s']:.2f} m/s median from a {1e3 * s['lag_s']:.0f} ms lag{spread}, "
            f"{p['windows_accepted']} of {p['windows_accepted'] + p['windows_rejected']} windows{refined}, "
            f"{p['windows_tracked']} tracked between strict ones: a speed over {p['speed_covers_percent']:.0f} % of "
            f"the ride ({p['strict_covers_percent']:.0f} % from strict windows)")
        return (f"{self.name}{part} through {self.bike}: {c['verdict']}; {said}; terrain {s['terrain_length_m']:.0f} m; "
                f"check: front reproduced within "
                f"{c['front_reproduced_rms_mm']:.2f} mm RMS, rear predicted {c['rear_predicted_rms_mm']:.1f} mm RMS "
                f"({c['rear_predicted_rms_percent_of_used']:.0f} % of the {c['rear_travel_used_mm']:.0f} mm used; "
                f"baselines: delayed fork {c['baseline_delayed_fork_rms_mm']:.1f}, rear's mean "
                f"{c['baseline_rear_mean_rms_mm']:.1f} mm; the fork at once {c['fork_at_once_rms_mm']:.1f}, a linear "
                f"filter from the fork fitted on the rear itself " + (
                    "none (too few samples checked)" if c['bound_fork_filter_rms_mm'] is None
                    else f"{c['bound_fork_filter_rms_mm']:.1f}") + f" (what the fork's "
                f"record holds about the rear), neither judged by; the mark {c['pass_mark_rms_mm']:.1f}), "
                + ("" if not self.at_once_fit else f"with {100 * self.at_once_fit['share']:.0f} % of the rear's ground "
                   f"met at the front's moment (fitted on the rear's record, not judged) the rear "
                   f"{self.at_once_fit['rear_predicted_rms_mm']:.1f} mm, ")
                + ("" if not self.spectral else f"the rear meeting {self.spectral['at_once_rms_mm']:.1f} mm RMS of the "
                   f"ground found at the front's moment (its spectral share of a load on both ends), ")
                + f"histograms {c['rear_histogram_distance_percent']:.0f} % apart"
                + ("" if not c["bands"] else "; the rear by band (correlation, described): " + ", ".join(
                    f"{b['band_Hz'][0]:g}-{b['band_Hz'][1]:g} Hz {b['predicted_correlation']:.2f} "
                    f"{'yes' if b['described'] else 'no'}" for b in c["bands"]))
                + f"; {len(self.jumps)} flight(s) bridged, {kept} drop level(s) kept, {len(self.levels or []) - kept} "
                f"left (no drop, or deeper than its flight allows){landing.words(self.landings)}, "
                f"{len(self.unaligned or [])} stretch(es) without a speed left out ({c['samples_checked_percent']:.0f} % "
                f"of the ride checked)")

    def terrain_csv(self) -> bytes:
        """The terrain as ``mtbmj roll`` and ``mtbmj bike`` read a profile (distance_m, height_mm): a
        level lead-in of ``TERRAIN_LEAD_IN_M`` at the ride's first height, then the ride's terrain
        (its distance along the ride plus the lead-in), so both take it at their default start (the
        front wheel at 0 m, both wheels on level ground)."""
        from mtbmj import output

        keep = np.concatenate(([True], np.diff(self.distance) > 1e-9))
        x, z = self.distance[keep] + TERRAIN_LEAD_IN_M, self.ridden_ground[keep] * 1e3
        return output.csv_bytes({"distance_m": np.concatenate(([0.0], x)), "height_mm": np.concatenate(([z[0]], z))})

    def speed_csv(self) -> bytes:
        """The ride's speed along ``terrain_csv``'s distance (distance_m, speed_m_per_s: :meth:`speed_along`,
        the lead-in at the first speed), which ``mtbmj bike BIKE terrain.csv --speed-profile speed.csv`` holds."""
        from mtbmj import output

        x, v = self.speed_along()
        return output.csv_bytes({"distance_m": np.concatenate(([0.0], x + TERRAIN_LEAD_IN_M)),
                                 "speed_m_per_s": np.concatenate(([v[0]], v))})

    def figure(self):
        from matplotlib.figure import Figure

        fig = Figure(figsize=(11, 10.5), layout="constrained")
        ax = fig.subplots(4, 1, sharex=False)
        ax[0].plot(self.distance, self.ground * 1e3, color="0.3")
        ax[0].set(xlabel="distance (m)", ylabel="height (mm)",
                  title=f"Terrain under the front wheel (median speed {self.speed['speed_m_per_s']:.2f} m/s)")
        for a, b in self.jumps:
            ax[0].axvspan(float(np.interp(a, self.t, self.distance)), float(np.interp(b, self.t, self.distance)),
                          color="C3", alpha=0.2)
        ax[1].plot(self.t, self.front, color="C0", label="fork, measured")
        ax[1].plot(self.t, self.front_again, color="C1", linestyle="--", label="fork, over the terrain found")
        ax[1].set(xlabel="time (s)", ylabel="fork travel (mm)", title="Front: the record reproduced (the check)")
        c = self.checks()
        ax[2].plot(self.t, self.rear, color="C0", label="rear wheel, measured")
        ax[2].plot(self.t, self.rear_predicted, color="C2", linestyle="--",
                   label=f"rear wheel, predicted ({c['rear_predicted_rms_mm']:.1f} mm RMS)")
        ax[2].plot(self.t, self.baselines()["delayed_fork_mm"], color="0.45", linestyle=":",
                   label=f"baseline: the fork delayed, scaled ({c['baseline_delayed_fork_rms_mm']:.1f} mm RMS)")
        ax[2].set(xlabel="time (s)", ylabel="rear wheel travel (mm)",
                  title="Rear: predicted from the front's terrain, beside the naive baseline (RMS over the checked samples)")
        given_mod.speed_panel(ax[3], self)
        for a, along in zip(ax, "msss"):  # where the ground found leaves what the bike could climb
            envelope.shade(a, self.beyond, along)
            if a is not ax[0] or self.beyond:
                a.legend(loc="best" if a is ax[3] else "upper right")
        for a in ax[1:]:
            a.set_xlim(float(self.t[0]), float(self.t[-1]))
            for s0, s1 in self.jumps:
                a.axvspan(s0, s1, color="C3", alpha=0.2)
            for s0, s1 in self.unaligned or []:
                a.axvspan(s0, s1, color="0.6", alpha=0.2)
        for a in ax:
            a.grid(alpha=0.3)
        verdict = c["verdict"].split(":", 1)[0]  # "the model (does not) describe(s) this ride"
        fig.suptitle(f"{self.name} through {self.bike}: {verdict}\nred, the front wheel off the ground (bridged, "
                     f"checked); grey, no speed (left out)")
        return fig

    def write(self, out_dir) -> list:
        import json

        from mtbmj import output
        from mtbmj.readout import quicklook  # the one figure writer: a "$" in a name drawn as written

        png = quicklook.png(self.figure(), dpi=100)
        series = output.csv_bytes({"time_s": self.t, "fork_mm": self.front, "fork_again_mm": self.front_again,
                                   "rear_mm": self.rear, "rear_predicted_mm": self.rear_predicted,
                                   "rear_baseline_delayed_fork_mm": self.baselines()["delayed_fork_mm"],
                                   "speed_m_per_s": self.speed["speed_at"](self.t),
                                   "checked": self.valid.astype(int)})
        return output.write_atomically(out_dir, {"terrain.csv": self.terrain_csv(), "speed.csv": self.speed_csv(),
                                                 "series.csv": series,
                                                 "reconstruction.png": png,
                                                 "reconstruction.json": (json.dumps(self.summary(), indent=2) + "\n").encode()})



def ridden_part(record):
    """(the record, None, []) where it never stands unweighted mid-ride; else (its longest part between
    such stands, its times from 0 there; (start, end) s of that part in the record; the stands' (start,
    end) s). Standing unweighted: both ends within ``STAND_MM`` of full extension for longer than
    ``reconstruct_inverse.MAX_FLIGHT_S``, not at the record's start or end (a rider getting on or off,
    which the checks leave out by their filters' start and the windows). The whole bike rides with its
    rider on: over a stand it pressed the bike to its sag where the record stood fully out, and the
    fork's slow load then read as the rider lifting the front by its whole static load, which the free
    run carried for seconds past the stand (00094, 23.5 s standing, diverged there)."""
    from dataclasses import replace

    from mtbmj.ride.reconstruct_inverse import MAX_FLIGHT_S

    if record.fork_mm is None or record.rear_mm is None:
        return record, None, []
    t = np.asarray(record.time_s, float)
    dt = float(t[1] - t[0])
    out = (np.asarray(record.fork_mm, float) <= STAND_MM) & (np.asarray(record.rear_mm, float) <= STAND_MM)
    stands = [(a, b) for a, b in runs(out) if (b - a) * dt > MAX_FLIGHT_S and a > 0 and b < t.size]
    if not stands:
        return record, None, []
    edges = [0] + [k for ab in stands for k in ab] + [t.size]
    a, b = max(zip(edges[0::2], edges[1::2]), key=lambda ab: ab[1] - ab[0])
    cut = lambda x: None if x is None else np.ascontiguousarray(np.asarray(x)[a:b])  # noqa: E731
    part = replace(record, time_s=np.ascontiguousarray(t[a:b] - t[a]), fork_mm=cut(record.fork_mm),
                   shock_mm=cut(record.shock_mm), rear_mm=cut(record.rear_mm), counts=cut(record.counts))
    return part, (float(t[a]), float(t[b - 1])), [(float(t[i]), float(t[min(j, t.size - 1)])) for i, j in stands]


def require_both_ends(record) -> None:
    """One ``ReconstructError`` line for a record whose two ends cannot be read (``telemetry.both_ends``)."""
    if why := both_ends(record):
        raise ReconstructError(f"{record.name}: {why}")


def reconstruct(record, bike, overrides=None, at_once: bool = False, speed=None, spectral: bool = True) -> Reconstruction:
    """``record`` (a ``mtbmj.measured.telemetry.TelemetryRecord`` with both ends) through the bike
    ``bike`` (preset, file or ``mtbmj.bike.spec.ResolvedBike``, which is not read again; ``overrides``
    its keys): see the module doc. ``at_once``: also the rear with the share of its ground met at the
    front's moment fitted on the rear's record (``Reconstruction.at_once_fit``, reported, not judged).
    ``speed``: the ride's speed given (m/s, a CSV's path or (time_s, speed_m_per_s) on the record's clock:
    :mod:`mtbmj.ride.reconstruct_given`), used in place of the lag's, the lag's reported beside it. ``spectral``
    (the check's): the rear meets the found ground's spectral share at once (False: all a wheelbase later)."""
    from mtbmj.bike import run as bike_run
    from mtbmj.bike import spec as spec_mod

    given = None if speed is None else given_mod.given(speed)  # a bad speed: one line before any work
    require_both_ends(record)
    record = record.decimated(RATE_HZ)  # a 5 kHz version-2 record read at 1 kHz, low-passed first
    if given is not None:
        given.check_covers(float(record.time_s[0]), float(record.time_s[-1]), record.name)
    record, part_s, stands = ridden_part(record)
    spec = spec_mod.load(bike, overrides)  # a ResolvedBike is derived again, not read
    t = np.asarray(record.time_s, float)
    if given is None:  # before any work; the speed given: the lag's refusal reported beside it, one window needed
        check_length(t, spec.front_axle[0] - spec.rear_axle[0], WINDOW_S, record.name)
    else:
        given.check_length(t, record.name)
    dt = float(t[1] - t[0])
    fork_mm, rear_mm = np.asarray(record.fork_mm, float), np.asarray(record.rear_mm, float)
    shock_mm = np.asarray(record.shock_mm, float) if record.shock_mm is not None else None
    if getattr(record, "version", 0) == 2:  # 5 kHz of coarse encoder steps: low-passed before any derivative
        fork_mm, rear_mm = lowpass(fork_mm, dt, V2_LOWPASS_HZ), lowpass(rear_mm, dt, V2_LOWPASS_HZ)
        shock_mm = None if shock_mm is None else lowpass(shock_mm, dt, V2_LOWPASS_HZ)
    # the wheelbase at the ride's sag (the median travel of each end): the fork shortens it along the
    # steering axis, the rear axle moves on its arc about the pivot
    wheelbase = wheelbase_at(spec, float(np.median(fork_mm)) * 1e-3, float(np.median(rear_mm)) * 1e-3)
    fork_setup, shock_setup = bike_run.setups(spec)
    g = fork_setup.gravity
    total, share = _statics(spec)
    m_front = spec.fork_lower_mass + spec.front_wheel_mass
    m_rear = spec.rear_wheel_mass + 0.5 * spec.swingarm_mass
    rate = fork_setup.tire.values(1).rate
    radius = fork_setup.tire_radius
    rim = fork_setup.tire.rim.max_deflection if fork_setup.tire.rim is not None else math.inf
    front_car = QuarterCar(total * share - m_front, m_front, fork_setup.fork, rate, radius, g, fork_setup.travel, rim)
    rear_car = QuarterCar(total * (1.0 - share) - m_rear, m_rear, shock_setup.fork, rate, radius, g, shock_setup.travel, rim)
    sin_a = math.sin(spec.head_angle)
    fork, cut_fork = within_stops(record.name, "fork", fork_mm * 1e-3, fork_setup.travel, dt)
    ground, tyre, air, extra, body, stops = ground_under(t, fork * sin_a, fork, front_car, lambda w: sin_a)
    lev = spec.leverage
    rear = rear_mm * 1e-3
    shock, cut_shock = within_stops(record.name, "shock", shock_mm * 1e-3 if shock_mm is not None else
                                    lev.strokes(rear), shock_setup.travel, dt)
    ratios = lev.ratios
    # the speed from the lag between the grounds each end's own inverse finds (each end's suspension
    # delays its travel behind its ground by its own phase; the grounds carry none)
    ground_back, *_ = ground_under(t, rear, shock, rear_car, ratios)
    travel = (fork_mm, rear_mm)  # a window where either end stands still gives no speed
    pairs = ((ground, ground_back, GROUND_HIGHPASS_HZ), (fork_mm, rear_mm, LAG_HIGHPASS_HZ))
    try:  # per window: the grounds' lag where they align, else the travels' (high-passed at 5 Hz)
        speed = speed_from_either(t, *pairs, wheelbase, names=("the two ends' grounds", "the two ends' travel"),
                                  travel=travel)
        speed = tracked(t, pairs, speed, wheelbase, travel=travel)  # the gaps near strict windows tracked
        speed["from"] = ", ".join(sorted({s for s in speed["sources"] if s})) or None
    except ReconstructError as exc:
        if given is None:
            raise ReconstructError(f"{record.name}: {exc}") from None
        speed = exc  # the given speed is used; the lag's refusal reported beside it
    if given is not None:
        speed = given_mod.profile(given, t, part_s[0] if part_s else 0.0, wheelbase, speed)
    from mtbmj.ride import reconstruct_bike

    whole = reconstruct_bike.whole_bike(spec, fork_setup, shock_setup)

    def through(speed, at_once=0.0):
        """The terrain and the rear from the fork's record through the whole bike at ``speed``'s lags
        (the rear's record unused; ``at_once`` of the rear's ground taken at the front's moment), the
        whole bike free over it again, and the samples checked."""
        pad = int(round(LEFT_OUT_S / dt))
        lags = wheelbase / speed["speed_at"](t)  # s, the rear's lag behind the front at each moment
        bad = np.zeros(t.size, bool)
        bad[:int(round(float(np.max(lags)) / dt)) + pad] = True  # the rear's first wheelbase has no terrain from the front
        bad[:int(round(2.0 / (HIGHPASS_HZ * 2 * math.pi) / dt))] = True  # the filters' start
        covered = np.zeros(t.size, bool)  # within a window that gave a speed (the windows overlap)
        for stage in (speed, speed.get("first")):
            for start, v_window, _ in (stage or {}).get("windows", []):
                if v_window is not None:
                    i = int(round(start / dt))
                    covered[max(i, 0): i + int(round(stage["window_s"] / dt))] = True
        # standing, or the ends do not align there, or past the last window: no terrain the rear can be checked on
        unaligned = [(float(t[i]), float(t[min(j, t.size - 1)])) for i, j in runs(~covered)]
        bad |= ~covered
        if bad.all() or not np.ptp(rear[~bad]) > 0.0:
            # the windows that gave a speed lie wholly in jumps, the first wheelbase or the filters' start
            n = sum(1 for _, s, _ in speed["windows"] if s is not None)
            raise ReconstructError(f"{record.name}: no speed estimate that can be checked: the {n} window(s) of "
                                   f"{len(speed['windows'])} whose two ends aligned lie wholly where the front wheel was "
                                   f"off the ground, or in the ride's first wheelbase or its filters' start (or the rear "
                                   f"does not move there): no sample of the ride can be checked")
        found = reconstruct_bike.terrain_and_rear(t, whole, fork, lags, ground, body, fork_setup.travel, stops,
                                                  at_once=at_once, air=air, spectral=spectral)
        # the check: the whole bike free over the terrain found, the rider's slow load on its front
        behind = reconstruct_bike.rear_ground(t, lags, found["ground"], at_once, spectral, found["airborne"])
        again = reconstruct_bike.ride(t, whole, behind,
                                      front_ground=found["ground"], push=found["rider_slow_load"])
        return {"lags": lags, "bad": bad, "unaligned": unaligned, "found": found, "again": again}

    def built(done, speed, at_once=0.0) -> Reconstruction:
        found, again = done["found"], done["again"]
        rear_predicted, front_again = found["rear_rise"], again["front_rise"] / sin_a
        bad = done["bad"] | ~(np.isfinite(rear_predicted) & np.isfinite(front_again))  # past a divergence: unchecked
        diverged = [d for d in (found["diverged_s"], again["diverged_s"]) if d is not None]
        jumps = [(float(t[i]), float(t[min(j, t.size - 1)])) for i, j in runs(found["airborne"])]
        v = speed["speed_at"](t)
        distance = np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)))
        beyond = envelope.beyond(t, distance, found["ground"], v, total, g)  # no trail is so: not checked
        bad = bad | envelope.mask(t, beyond)
        return Reconstruction(record.name, spec.name, t, speed, distance, found["ground"], ~bad, fork * 1e3,
                              front_again * 1e3, rear * 1e3, rear_predicted * 1e3, float(lev.full_travel * 1e3), jumps,
                              done["unaligned"], np.interp(t - done["lags"], t, fork * 1e3), wheelbase,
                              found["passes"], found["settled_m"], min(diverged) if diverged else None, part_s,
                              stands, at_once, cut=[c for c in (cut_fork, cut_shock) if c], levels=found["levels"],
                              beyond=beyond, spectral=described(found["ground"], dt, ~bad, found["airborne"]) if spectral else None)

    done = through(speed)
    result = built(done, speed)
    # the speed found again where the rear predicted and the rear's record align (its timing only: the
    # terrain's heights still come from the fork's record alone), and the terrain found again at it; only
    # where the first pass's rear predicted beats the better naive baseline: where it does not, its
    # timing is the model's more than the ride's, and would pull the speed
    first = speed
    c = result.checks()
    if given is None and c["rear_predicted_rms_mm"] < min(c["baseline_delayed_fork_rms_mm"],
                                                          c["baseline_rear_mean_rms_mm"]):  # a given speed stands
        for _ in range(REFINE_PASSES):
            try:
                again = merged(first, refine(t, rear * 1e3, done["found"]["rear_rise"] * 1e3, done["lags"],
                                             wheelbase, flights=result.jumps + landed(result.levels)))
                again["from"] = ", ".join(sorted({s for s in first["sources"] if s} | {"the rear predicted"}))
                done, speed = through(again), again
            except ReconstructError:
                break  # no refining window aligned, or none left to check: the estimate before stands
            result = built(done, speed)
    if at_once:  # reported beside, not judged: the share of the rear's ground met at once, from the rear's record
        ends = built(through(speed, 1.0), speed, 1.0)
        a = at_once_share(ends.rear, result.rear_predicted, ends.rear_predicted, result.valid)
        tried = [result, ends] + ([built(through(speed, a), speed, a)] if 0.0 < a < 1.0 else [])
        # the one whose rear predicted, less its mean, is closest to the record's on the samples checked
        # without it; one that diverges earlier than the bike without it is not taken
        kept = [r for r in tried if r.diverged_s is None or (result.diverged_s is not None
                                                             and r.diverged_s >= result.diverged_s)]
        best = min(kept, key=lambda r: timing_error(r.rear, r.rear_predicted, result.valid))
        result.at_once_fit = best.fitted_summary(result.valid)
    envelope.warn(record.name, result.beyond)
    landing.attach(result, t, wheelbase, sin_a, spec, g, record.name)  # the terrain to ride only: the check's is the fork's
    return result


__all__ = ["min_seconds", "speed_from_lag", "ground_under", "forward", "histogram_distance", "reconstruct", "Reconstruction",
           "QuarterCar", "ReconstructError"]

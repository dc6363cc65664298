"""The slam's first rebound read off the trace with no model (``bounce.first_rebound``) and the check
of the replayed dampers against it (``bounce.rebound_check``, ``fit bounce --replay``'s "replay_check").

(a) A record made here in closed form: at rest, a quick compression, then from rest at the peak the
free motion of one linear damped oscillator, x = rest + A e^(-zeta wn t) (cos wd t + zeta / sqrt(1 -
zeta^2) sin wd t), sampled at 5 kHz with noise. Its largest extension speed, A wn / sqrt(1 - zeta^2)
e^(-zeta wn t*) sin(wd t*) at tan(wd t*) = sqrt(1 - zeta^2) / zeta, its trough at pi / wd and its
speed through the rebound's middle (from 75 % to 25 % of A above rest, the crossings solved here
with brentq) are given back; more damping, a slower rebound. (b) The check on entries written here.
(c) The shared slams (00083, 00085, 00087 at 0, 8, 17 rebound clicks): read off the records, no replay.
"""
from __future__ import annotations

import math
import os

import numpy as np
import pytest
from scipy.optimize import brentq

from mtbmj.identify.bounce import BounceError, first_rebound, rebound_check

FS = 5000.0


def closed_form(zeta, hz=1.5, amp=40.0, rest=10.0, noise=0.05, seed=3):
    """(time_s, x_mm, peak index, x(t) after the peak) of a slam whose rebound is the closed form."""
    wn = 2 * math.pi * hz
    wd = wn * math.sqrt(1 - zeta ** 2)

    def free(t):
        return rest + amp * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta ** 2) * np.sin(wd * t))

    t = np.arange(0.0, 4.0, 1 / FS)
    t_peak, rise = 2.0, 0.12
    x = np.full(t.size, rest)
    up = (t > t_peak - rise) & (t <= t_peak)
    x[up] = rest + amp * np.sin(0.5 * np.pi * (t[up] - (t_peak - rise)) / rise) ** 2
    after = t > t_peak
    x[after] = free(t[after] - t_peak)
    x = x + noise * np.random.default_rng(seed).standard_normal(t.size)
    return t, x, int(np.argmin(np.abs(t - t_peak))), free, wn, wd


@pytest.mark.parametrize("zeta", [0.1, 0.25, 0.4])
def test_first_rebound_of_a_closed_form(zeta):
    """Rest 30 mm, 25 mm above it: the trough stays clear of full extension at every zeta."""
    t, x, peak, free, wn, wd = closed_form(zeta, amp=25.0, rest=30.0)
    got = first_rebound(t, x, peak, 30.0)
    t_star = math.atan(math.sqrt(1 - zeta ** 2) / zeta) / wd
    v_max = 25.0 * wn / math.sqrt(1 - zeta ** 2) * math.exp(-zeta * wn * t_star) * math.sin(wd * t_star)
    a = brentq(lambda s: free(s) - (30.0 + 0.75 * 25.0), 1e-6, math.pi / wd)
    b = brentq(lambda s: free(s) - (30.0 + 0.25 * 25.0), 1e-6, math.pi / wd)
    assert got["rebound_speed_mm_per_s"] == pytest.approx(v_max, rel=0.01)
    assert got["mid_rebound_speed_mm_per_s"] == pytest.approx(0.5 * 25.0 / (b - a), rel=0.01)
    assert got["trough_s"] == pytest.approx(math.pi / wd, abs=0.005)
    assert got["trough_mm"] == pytest.approx(float(free(math.pi / wd)), abs=0.1)
    assert got["topped_out"] is False
    assert got["peak_above_rest_mm"] == pytest.approx(25.0, abs=0.2)


def test_more_damping_a_slower_rebound():
    speeds = [first_rebound(*closed_form(z)[:3], 10.0)["mid_rebound_speed_mm_per_s"] for z in (0.1, 0.25, 0.4)]
    assert speeds[0] > speeds[1] > speeds[2]


def test_a_rebound_to_full_extension_is_topped_out():
    """The trace clipped at 0 mm (the shock at full extension) on its first rebound: topped_out."""
    t, x, peak, *_ = closed_form(0.1, rest=5.0)
    got = first_rebound(t, np.maximum(x, 0.0), peak, 5.0)
    assert got["topped_out"] is True and got["trough_mm"] < 1.0


def test_a_peak_below_rest_is_refused():
    t, x, peak, *_ = closed_form(0.2)
    with pytest.raises(BounceError, match="not above the rest"):
        first_rebound(t, x, peak, 80.0)


def _entry(clicks, speed, damper=None):
    e = {"clicks": clicks, "record_rebound": {"mid_rebound_speed_mm_per_s": speed}}
    if damper is not None:
        e["damper_N_s_per_m"] = damper
    return e


def test_check_says_which_orders():
    """(b) Records slowing with the clicks and dampers rising: both order. Dampers not rising: the line
    says the replay does not read the damper. Records not slowing: the line says the records do not show
    it. One click setting: no check. A refused record (no damper) is compared on its record only."""
    ok = rebound_check([_entry(8, 300.0, 2000.0), _entry(0, 350.0, 1500.0), _entry(17, 230.0, 2600.0)])
    assert ok["records_order"] is True and ok["replay_orders"] is True and "rise with them" in ok["line"]
    assert ok["clicks"] == [0, 8, 17] and ok["mid_rebound_speed_mm_per_s"] == [350.0, 300.0, 230.0]
    bad = rebound_check([_entry(0, 350.0, 2012.0), _entry(8, 290.0, 1364.0), _entry(17, 227.0)])
    assert bad["records_order"] is True and bad["replay_orders"] is False
    assert "do not rise with them: the replay does not read the rebound damper" in bad["line"]
    flat = rebound_check([_entry(0, 300.0, 1000.0), _entry(8, 310.0, 2000.0)])
    assert flat["records_order"] is False and "the records themselves do not show" in flat["line"]
    assert rebound_check([_entry(4, 300.0, 1000.0), _entry(4, 250.0, 2000.0)]) is None
    one = rebound_check([_entry(0, 350.0, 1500.0), _entry(8, 290.0)])
    assert one["replay_orders"] is None and "fewer than two replays" in one["line"]


@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_records_slow_with_the_clicks():
    """(c) The shared slams, read off the records: all three rise 44-45 mm above their rest, so one
    spring pushes them alike through the rebound's middle; there they slow as the clicks rise (the
    records do show the rebound adjuster), the 0- and 8-click rebounds reach full extension, the
    17-click one turns before it."""
    from conftest import SHARED_DATA

    from mtbmj.identify.bounce import QUIET_BEFORE_S, find_slam
    from mtbmj.measured.telemetry import read_sst

    entries = []
    for f, k in (("00083", 0), ("00085", 8), ("00087", 17)):
        rec = read_sst(os.path.join(SHARED_DATA, "sst_v2", f + ".SST"))
        t, s = np.asarray(rec.time_s), np.asarray(rec.shock_mm)
        p = find_slam(t, s, f)
        w = (t >= t[p] - QUIET_BEFORE_S[0]) & (t <= t[p] - QUIET_BEFORE_S[1])
        entries.append({"clicks": k, "record_rebound": first_rebound(t, s, p, float(np.median(s[w])))})
    heights = [e["record_rebound"]["peak_above_rest_mm"] for e in entries]
    assert max(heights) - min(heights) < 0.05 * min(heights)
    check = rebound_check(entries)
    assert check["records_order"] is True
    speeds = [e["record_rebound"]["rebound_speed_mm_per_s"] for e in entries]
    assert speeds[0] > speeds[1] > speeds[2]
    assert [e["record_rebound"]["topped_out"] for e in entries] == [True, True, False]


@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_shared_forks_are_refused_with_the_reason():
    """``fit bounce --replay`` does not replay the fork: per shared record one reason naming how few free
    half cycles it has (the decay reading's note) and where it rests after the slam against before,
    beside the shock: the fork less compressed after, the shock more (the rider's weight moved)."""
    from conftest import SHARED_DATA

    from mtbmj.identify import bounce_decay as bd
    from mtbmj.identify.bounce_fit import fork_refusals
    from mtbmj.measured.telemetry import read_sst

    records = [read_sst(os.path.join(SHARED_DATA, "sst_v2", f + ".SST")) for f in ("00083", "00085", "00087")]
    summaries = [{"fork": {"decay": bd.fit_record(r)["fork"].summary()}} for r in records]
    got = fork_refusals(records, summaries)
    assert len(got) == 3
    for e in got:
        assert "free half cycle" in e["refused"] or "no free extremum" in e["refused"]
        assert e["rest_after_mm"] < e["rest_before_mm"] - 5.0
        assert "opposite ways, the rider's weight moved" in e["refused"]
        assert e["refused"].endswith("the fork's spring, damper and friction are not replayed")


def test_rebound_dampers_spring_from_the_ring_down_period_else_the_replay():
    """``bounce_rebound.spring_given``: the ring-down fit's or the ring-down's period reading's spring and
    interval where it was read, said so; the best whole-trace replay's where the reading was refused (its
    reason kept) or not given; a wrong source (the replay's spring where a reading exists) is told apart."""
    from mtbmj.identify.bounce_rebound import RING_FROM, spring_given

    best = {"file": "00083.SST", "spring_scale": 0.49, "spring_scale_ci95": [0.14, 0.85]}
    ring = {"spring_scale": 0.47, "spring_scale_ci95": [0.35, 0.62]}
    (s, ci), src = spring_given(ring, best)
    assert (s, ci, src) == (0.47, [0.35, 0.62], RING_FROM)
    assert (s, ci) != (best["spring_scale"], best["spring_scale_ci95"])
    refused = {"refused": "the spring from the ring-down's period not read: 1 free half period(s) in the records"}
    (s, ci), src = spring_given(refused, best)
    assert (s, ci) == (0.49, [0.14, 0.85])
    assert src.startswith("the whole-trace replay of 00083.SST") and "1 free half period(s)" in src
    (s, ci), src = spring_given(None, best)
    assert s == 0.49 and src.endswith("(the ring-down: not given)")
    # the ring-down fit (bounce_ring: a friction and compression of its own) is said as such, and its friction
    # and compression are the ones the rebound dampers take (_is_fit); the period's reading has neither
    from mtbmj.identify.bounce_rebound import _is_fit
    from mtbmj.identify.bounce_ring import SPRING_FROM

    fitted = {**ring, "friction_N": 18.0, "compression_N_s_per_m": 2860.0}
    (s, ci), src = spring_given(fitted, best)
    assert (s, ci, src) == (0.47, [0.35, 0.62], SPRING_FROM)
    assert _is_fit(fitted) and not _is_fit(ring) and not _is_fit({**fitted, "refused": "x"}) and not _is_fit(None)


def test_ring_period_halves_matched_by_their_turning_point_from_the_slam():
    """``bounce_slam_rebound._matched``: the period reading pairs the record's and the simulation's half
    cycles that start at the same turning point after the slam. A made ring-down whose half periods
    lengthen (phase 2 pi (1.5 t - 0.12 t^2)) as the record (its first trough clipped at the top-out, a
    stop the reading leaves out: its first free extremum is the 2nd turning point) and, as the
    simulation, the same motion 15 mm higher (its first trough free: the 1st): every pair is the same
    half cycle (log ratio under 1e-3), where pairing the k-th free half of each direction (written here)
    pairs the record's first compression with the simulation's one a cycle earlier (log ratio over 0.1)."""
    from mtbmj.identify.bounce_slam_rebound import _halves, _matched

    t = np.arange(-1.5, 2.5, 1 / 500)

    def made(rest):
        return np.where(t < 0, rest + 30 * np.exp(-(t / 0.08) ** 2),
                        rest + 30 * np.exp(-1.2 * t) * np.cos(2 * np.pi * (1.5 * t - 0.12 * t * t)))

    noise = 0.02 * np.random.default_rng(3).standard_normal(t.size)
    peak = int(np.argmin(np.abs(t)))
    rec = _halves(t, np.maximum(made(20.0), 0.0) + noise, peak)
    sim = _halves(t, made(35.0) + noise, peak)
    assert [q[0] for q in rec][:1] == [2] and [q[0] for q in sim][:1] == [1] and len(rec) >= 3
    got = _matched(rec, sim)
    assert len(got) == len(rec) and max(abs(g) for g in got) < 1e-3

    def kth_of_each_direction(rec, sim):
        out = []
        for d in ("rebound", "compression"):
            r, s = ([q[4] for q in h if q[1] == d] for h in (rec, sim))
            out += [math.log(b / a) for a, b in zip(r, s)]
        return out

    assert max(abs(g) for g in kth_of_each_direction(rec, sim)) > 0.1
    # a simulation without the record's later halves gives None for them (that spring scale is not used)
    assert _matched(rec, sim[:2])[-1] is None


def test_ring_period_reading_leaves_out_a_half_the_simulation_lacks():
    """``spring_from_periods`` on made ring-downs (x = rest + 30 exp(-1.2 t) cos(2 pi f t) mm after the slam's
    peak, f = 1.5 sqrt(scale / 0.5) Hz: the period alone says the scale) through a stand-in bike that runs the
    same law at each scale tried from a 20 mm rest, its first trough clipped at the top-out (a stop). Two
    records at 0.5 x: one resting at 20 mm (the same stop), one at 25 mm whose first trough is free (as the
    17-click shared slam's: its first free half starts a turning point earlier than any simulation's).
    The reading is 0.5 x within 1 % from the halves simulated at both neighbouring scales, saying how many
    were left out; the same records at 0.4 x read 0.4 x (the reading follows the periods, not the stand-in)."""
    from types import SimpleNamespace

    from mtbmj.identify.bounce_slam_rebound import spring_from_periods

    def made(t, rest, scale, floor=None):
        f = 1.5 * math.sqrt(scale / 0.5)
        x = np.where(t < 0, rest + 30 * np.exp(-(t / 0.08) ** 2), rest + 30 * np.exp(-1.2 * t) * np.cos(2 * np.pi * f * t))
        return x if floor is None else np.maximum(x, floor)

    class StandIn:
        def set_rest(self, *_):
            pass

        def run(self, p, after_s=2.5):
            t = np.arange(-0.6, after_s, 1 / 2000)
            return {"time_s": t, "stroke_mm": made(t, 20.0, p["spring_scale"], 0.0)}

    t = np.arange(-1.5, 2.5, 1 / 500)
    noise = 0.02 * np.random.default_rng(4).standard_normal(t.size)
    for truth in (0.5, 0.4):
        rings = [(f"made {rest:g}", t, made(t, rest, truth, 0.0) + noise, SimpleNamespace(sr=StandIn(), rest=rest), {})
                 for rest in (25.0, 20.0)]
        got = spring_from_periods(rings)
        assert got["spring_scale"] == pytest.approx(truth, rel=0.01)
        lo, hi = got["spring_scale_ci95"]
        assert lo <= truth <= hi
        assert got["halves_matched"] < got["halves"] and "left out" in got["line"]


class _MadeCurve:
    """A rate-against-coefficient curve made here (``bounce_rebound.solve_on`` takes it as a ``_Curve``):
    r(c) = R / (1 + c / C) 1/s, and above ``stall`` N s/m a first rebound with no middle (NaN: it turns
    before 25 % of the slam's height, as the shared 8- and 17-click slams' replays do at 0.33 x and 30000
    N s/m)."""

    def __init__(self, R=7.0, C=800.0, stall=1500.0):
        self.R, self.C, self.stall = R, C, stall
        self.sl = type("Slam", (), {"name": "made.SST"})()

    def __call__(self, c):
        return float("nan") if c > self.stall else self.R / (1.0 + c / self.C)


def test_solve_on_refuses_a_bike_slower_than_the_record_undamped():
    """The refusal that holds: at 50 N s/m the made curve gives 6.58 /s, a record at 6.8 /s has no
    coefficient, said as slower even undamped; a record at 4 /s is solved (closed form; the curve read at every
    coefficient, no stall)."""
    from mtbmj.identify.bounce_rebound import XTOL, solve_on

    cv = _MadeCurve(stall=math.inf)
    with pytest.raises(BounceError, match="slower than the record even undamped"):
        solve_on(cv, 6.8, 0.33)
    assert solve_on(cv, 4.0, 0.33) == pytest.approx(cv.C * (cv.R / 4.0 - 1.0), abs=2 * XTOL)


def test_solve_on_reads_below_a_rebound_that_stalls_at_the_largest_coefficient():
    """The made curve stalls above 1500 N s/m; a record at 3 /s has its root, 1066.7 N s/m, below the
    stall: it is read (the NaN above it is a rebound slower than any, not a faster one)."""
    from mtbmj.identify.bounce_rebound import XTOL, solve_on

    cv = _MadeCurve()
    assert solve_on(cv, 3.0, 0.33) == pytest.approx(cv.C * (cv.R / 3.0 - 1.0), abs=2 * XTOL)
    # a record at 5 /s: its root, 320 N s/m, lies below the first bisection's 1225; read too
    assert solve_on(_MadeCurve(), 5.0, 0.33) == pytest.approx(800.0 * (7.0 / 5.0 - 1.0), abs=2 * XTOL)
    # the wrong way round: a curve that has no rate at 50 N s/m already is refused as such, not solved
    with pytest.raises(BounceError, match="no middle even undamped"):
        solve_on(_MadeCurve(stall=10.0), 3.0, 0.33)


def test_solve_on_refuses_a_rebound_that_stalls_while_still_faster_than_the_record():
    """The made curve stalls above 100 N s/m, where it still rebounds at 6.22 /s: a record at 3 /s has its
    closed-form root (1066.7 N s/m) in the stall, where no rebound has a middle; refused, naming the
    largest coefficient read faster (bisected to just below 100) and the stall above it, not solved."""
    from mtbmj.identify.bounce_rebound import solve_on

    cv = _MadeCurve(stall=100.0)
    with pytest.raises(BounceError, match=r"still faster than the record \(6\.2\d /s\) at (9\d|100) N s/m and has "
                                          r"no middle from 10\d N s/m up"):
        solve_on(cv, 3.0, 0.33)

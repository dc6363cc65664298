"""The bike's own spring along the stroke and the held-out frequency carried to a record's centre
(``mtbmj.identify.bounce_stroke``).

The wheel rate is checked against its closed form for a leverage ratio linear in wheel travel,
LR(w) = R0 - b w (a falling, progressive curve) on a preloaded linear coil: the stroke
s(w) = -ln(1 - b w / R0) / b, the wheel force F_w = (P + k s) / LR and its rate
k_w = k / LR^2 + (P + k s) b / LR^2, written here, not taken from the module.

The made records come from a model written here with its own integrator (solve_ivp with events):
one mass in wheel coordinates on that spring, viscous damping set by the clicks, Coulomb friction with
a stick condition, and a constant push (the rider's weight on the bars) that sets each record's
centre in the stroke (20, 30, 40 mm); the slam is a half-sine push. The mass is the same in every
record, so the deeper centre rings faster by the rate alone.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from mtbmj.identify import bounce_decay as bd
from mtbmj.identify import bounce_predict as bp
from mtbmj.identify import bounce_stroke as bs
from mtbmj.measured.leverage import Leverage

from conftest import SHARED_DATA

R0, B = 3.2, 5.0  # LR(w) = R0 - B w (w in m): 3.2 at full extension, 2.3 at 180 mm of wheel travel
K, P = 80e3, 250.0  # the coil: N/m and preload N
RATE, NOISE = 5000, 0.15
M = 80.0  # kg, the sprung mass in wheel coordinates
CENTRES_MM = (20.0, 30.0, 40.0)
CLICKS = (0, 8, 17)


def lr(w):
    return R0 - B * w


def stroke(w):
    return -np.log(1.0 - B * w / R0) / B


def travel(s):
    return R0 * (1.0 - np.exp(-B * s)) / B


def wheel_force(w):
    return (P + K * stroke(w)) / lr(w)


def closed_rate(s_mm):
    w = travel(s_mm * 1e-3)
    return K / lr(w) ** 2 + (P + K * s_mm * 1e-3) * B / lr(w) ** 2


def linear_leverage(r0=R0, b=B):
    w = np.arange(0, 181) * 1e-3
    return Leverage(tuple(w), tuple(r0 - b * w))


SPRING = bs.BikeSpring(linear_leverage(), lambda s: P + K * s)


@pytest.mark.parametrize("s_mm", [5.0, 15.0, 25.0, 35.0, 50.0])
def test_wheel_rate_is_the_closed_form_not_the_coil_through_the_leverage_squared(s_mm):
    got = SPRING.wheel_rate(s_mm)
    assert got == pytest.approx(closed_rate(s_mm), rel=1e-4)
    naive = K / lr(travel(s_mm * 1e-3)) ** 2  # the geometric term of the static force left out
    assert abs(naive / got - 1) > 100 * 1e-4


def test_frequency_ratio_is_the_square_root_of_the_rates():
    q = SPRING.frequency_ratio(35.0, 15.0)
    assert q == pytest.approx(math.sqrt(closed_rate(35.0) / closed_rate(15.0)), rel=1e-4)
    assert q > 1.05  # a falling leverage stiffens
    flat = bs.BikeSpring(linear_leverage(b=0.0), lambda s: P + K * s)
    assert flat.frequency_ratio(35.0, 15.0) == pytest.approx(1.0, abs=1e-9)


def test_the_sst_bike_stiffens_with_stroke():
    """The sst preset (a linear 80 N/mm coil, its leverage falling from 3.18 to 2.37): 10.80 N/mm at the
    wheel about 16.5 mm of stroke, 11.32 about 19.6 mm, 13.60 about 35 mm."""
    sp = bs.BikeSpring.of_bike("sst")
    assert sp.wheel_rate(16.5) / 1e3 == pytest.approx(10.80, abs=0.02)
    assert sp.wheel_rate(19.6) / 1e3 == pytest.approx(11.32, abs=0.02)
    assert sp.wheel_rate(35.0) / 1e3 == pytest.approx(13.60, abs=0.02)


# --- made records: one mass on the progressive spring, centred at three depths -------------------------

def zeta_of(clicks):
    return 0.05 + 0.008 * clicks


def made_record(centre_mm, clicks, seed, seconds=9.0, t_push=2.0, push_s=0.25, push_n=300.0, fc=6.0):
    """Shock stroke (mm) at RATE: at rest at ``centre_mm`` until ``t_push``, the push, the free motion."""
    from scipy.integrate import solve_ivp

    w_c = travel(centre_mm * 1e-3)
    load = wheel_force(w_c)  # the constant push that holds the centre there (the mass is the same)
    c = 2 * zeta_of(clicks) * math.sqrt(closed_rate(25.0) * M)  # the damper: clicks only, not the centre

    def net(t, w, v):
        f = load - wheel_force(w) - c * v
        if t_push <= t <= t_push + push_s:
            f += push_n * math.sin(math.pi * (t - t_push) / push_s)
        return f

    t = np.arange(int(seconds * RATE)) / RATE
    t_move = t_push + push_s / math.pi * math.asin(fc / push_n)  # the push overcomes the friction
    ts, ws = [t[t < t_move]], [np.full(int(np.sum(t < t_move)), w_c)]
    y, t0, mode = np.array([w_c, 0.0]), t_move, 1
    while t0 < seconds - 1e-9:
        def rhs(tt, q, s=mode):
            return [q[1], (net(tt, q[0], q[1]) - fc * s) / M]

        def rev(tt, q):
            return q[1]
        rev.terminal, rev.direction = True, -mode
        sol = solve_ivp(rhs, (t0, seconds), y, events=(rev,), rtol=1e-10, atol=1e-12, dense_output=True)
        grid = t[(t >= t0) & (t < sol.t[-1])]
        if grid.size:
            ts.append(grid)
            ws.append(sol.sol(grid)[0])
        t0, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        y[1] = 0.0
        f = net(t0, y[0], 0.0)
        if abs(f) <= fc:  # stuck (the push is over by then: it drives the mass one way throughout)
            assert t0 > t_push + push_s
            break
        mode = 1 if f > 0 else -1
    ts.append([t0])
    ws.append([y[0]])  # at rest there from the last reversal on
    tt, ww = np.concatenate(ts), np.concatenate(ws)
    w = np.interp(t, tt, ww, right=ww[-1])
    x = 1e3 * stroke(w) + np.random.default_rng(seed).normal(0, NOISE, t.size)
    return t, np.round(np.clip(x, 0, None) / 0.02) * 0.02


@pytest.fixture(scope="module")
def made():
    recs, xs, seqs = [], [], []
    for j, (c, k) in enumerate(zip(CENTRES_MM, CLICKS)):
        t, x = made_record(c, k, seed=j + 1)
        recs.append(SimpleNamespace(time_s=t, name=f"{k} clicks"))
        xs.append(x)
        seqs.append(bd.extrema(t, x, "shock", int(np.argmax(x))))
    return recs, xs, seqs


def true_fd(centre_mm, clicks):
    z = zeta_of(clicks) * math.sqrt(closed_rate(25.0) / closed_rate(centre_mm))
    return math.sqrt(closed_rate(centre_mm) / M) * math.sqrt(1 - z * z) / (2 * math.pi)


def test_made_records_ring_at_their_own_centres(made):
    """The generator's centres and frequencies: each record's fitted x_eq within 0.5 mm of its centre,
    and its timed frequency within 1 % of the linear frequency at that centre (measured 0.11, 0.37,
    0.58 % below it; the rate's rise from 20 to 40 mm gives 13 % in frequency)."""
    recs, xs, seqs = made
    pl = bs.placements(seqs, CLICKS, recs, xs)
    for p, c, k, r, x, s in zip(pl, CENTRES_MM, CLICKS, recs, xs, seqs):
        assert p.centre_mm == pytest.approx(c, abs=0.5)
        assert abs(p.rest_before_mm - c) < 3 * NOISE
        tm = bp.timing(s, r.time_s, x)
        assert tm.frequency_hz == pytest.approx(true_fd(c, k), rel=0.01)
    assert true_fd(40.0, 17) / true_fd(20.0, 17) > 1.10


def _stiffened_within_2_sd(made, i):
    recs, xs, seqs = made
    ho = bs.held_out(seqs, list(CLICKS), recs, xs, i, SPRING)
    assert ho["centre_mm"] == pytest.approx(CENTRES_MM[i], abs=0.5)
    assert ho["frequency_stiffened_misses_by_sd"] <= 2.0


# measured (these seeds), each record's frequency with the half periods' pooled scatter (0.86 % per half,
# 12 dof; bounce_predict.half_scatter): with the stiffening the held-out frequency misses by 1.21, 0.21, 0.38 sd
# at 20, 30, 40 mm (0, 8, 17 clicks); without it by 2.82, 0.05, 3.15 sd (10 %, 0 %, 11 %). With the vertex
# timing's sd alone (the error model before, which held the truth 2 times in 18 in
# tests/test_bounce_predict.py's coverage test) the 20 mm miss was 2.22 sd, a strict xfail.
@pytest.mark.parametrize("i", [0, 1, 2])
def test_held_out_frequency_with_the_stiffening_within_2_sd(made, i):
    _stiffened_within_2_sd(made, i)


@pytest.mark.parametrize("i", range(3))
def test_held_out_frequency_with_the_stiffening_within_1_percent(made, i):
    """In Hz rather than in sd: the stiffened prediction within 1 % of the record's timed frequency; at
    the outer centres the common spring's misses by more than 5 %."""
    recs, xs, seqs = made
    ho = bs.held_out(seqs, list(CLICKS), recs, xs, i, SPRING)
    f = ho["frequency_measured"]
    assert abs(ho["frequency_stiffened_hz"] - f) < 0.01 * f
    if i != 1:
        assert abs(ho["frequency_hz"] - f) > 0.05 * f


@pytest.mark.parametrize("i", [0, 2])
def test_a_common_spring_or_a_wrong_leverage_misses_the_outer_centres(made, i):
    """The law without the stiffening (one f_n for every centre) and the law with the leverage turned
    round (rising: a softening rate) both miss the records held out at the outer centres by more than 2 sd
    and 5 % (measured 2.91 and 3.13 sd, 2.71 and 3.36 sd)."""
    recs, xs, seqs = made
    ho = bs.held_out(seqs, list(CLICKS), recs, xs, i, SPRING)
    assert ho["frequency_misses_by_sd"] > 2.0
    rising = bs.BikeSpring(linear_leverage(r0=2.3, b=-5.0), lambda s: P + K * s)
    wrong = bs.held_out(seqs, list(CLICKS), recs, xs, i, rising)
    assert wrong["frequency_stiffened_misses_by_sd"] > 2.0
    assert abs(wrong["frequency_stiffened_hz"] / wrong["frequency_measured"] - 1) > 0.05


# --- the shared seat slams (0, 8, 17 clicks) ---------------------------------------------------------

SLAMS = ("00083.SST", "00085.SST", "00087.SST")
SHARED_CLICKS = [0, 8, 17]


@pytest.fixture(scope="module")
def shared():
    from mtbmj.measured.telemetry import read_sst

    recs = [read_sst(f"{SHARED_DATA}/sst_v2/{n}") for n in SLAMS]
    return recs, [r.shock_mm for r in recs], [bd.extrema(r.time_s, r.shock_mm, "shock", bd.slam_index(r)) for r in recs]


@pytest.mark.shared_data("sst_v2", *SLAMS)
def test_shared_slams_sit_alike_and_ring_about_alike_centres(shared):
    """Measured: the rest before the slam (as the rider sat) 11.37, 9.70, 10.07 mm at 0, 8, 17 clicks;
    the ring-downs' centres (x_eq) 16.64, 16.54, 19.58 mm; their first free swings 30.7, 24.0, 17.7 mm.
    The sag differs by 1.7 mm at most and the 17-click centre lies 3 mm deeper than the others'."""
    recs, xs, seqs = shared
    pl = bs.placements(seqs, SHARED_CLICKS, recs, xs)
    rests = [p.rest_before_mm for p in pl]
    centres = [p.centre_mm for p in pl]
    assert rests == pytest.approx([11.37, 9.70, 10.07], abs=0.05)
    assert centres == pytest.approx([16.64, 16.54, 19.58], abs=0.05)
    assert max(rests) - min(rests) < 2.0 and max(centres) - min(centres) < 3.5


@pytest.mark.shared_data("sst_v2", *SLAMS)
def test_shared_17_clicks_rings_faster_on_both_of_its_half_cycles(shared):
    """The 17-click slam's one timed half cycle (a compression, 7.6 -> 25.4 mm) takes 0.280 s; the
    rebound after it, to where it sticks at 17.3 mm, about 0.28 s too (the first time the 10 ms mean
    comes within 0.05 mm of the stuck level, read here, not by the package). The 0- and 8-click
    slams' free half cycles take 0.290-0.350 s (compression 0.309, 0.290; rebound 0.339, 0.350, 0.331,
    0.290): the 17-click slam rings about 15 % faster in both directions."""
    recs, xs, seqs = shared
    pl = bs.placements(seqs, SHARED_CLICKS, recs, xs)
    (d17, a, b, h17), = pl[2].half_periods
    assert d17 == "compression" and h17 == pytest.approx(0.280, abs=0.002)
    others = [h for p in pl[:2] for _, _, _, h in p.half_periods]
    assert len(others) == 6 and min(others) > 0.288 and np.mean(others) > 1.1 * h17
    t, x = np.asarray(recs[2].time_s), np.asarray(xs[2])
    xm = bd.moving_average(x, int(0.010 * RATE))
    t_peak = float(seqs[2].times_s[1])
    after = np.flatnonzero((t > t_peak) & (np.abs(xm - seqs[2].levels_mm[-1]) < 0.05))
    rebound = float(t[after[0]]) - t_peak
    assert 0.25 < rebound < 0.30


@pytest.mark.shared_data("sst_v2", *SLAMS)
def test_shared_stiffening_moves_the_17_click_prediction_by_2_6_percent(shared):
    """The bike's own spring (sst preset) at the 17-click slam's centre (19.9 mm with the law's zeta and
    d held) against the 0- and 8-click slams' (16.6, 16.5 mm): rates 11.37 against 10.82 N/mm at the
    wheel, f_n x 1.026; the held-out frequency 1.566 -> 1.606 Hz (each record's frequency the mean of its
    half periods with the rebound's shift taken out, bounce_predict.honest_timing). The record's one
    compression half, shifted, gives 1.709 Hz: x 1.091 of the plain law's, which the stiffening's 1.026
    does not reach (it explains 0.040 of the 0.143 Hz; 1.492 -> 1.531 of 1.786 with the timings before)."""
    recs, xs, seqs = shared
    sp = bs.BikeSpring.of_bike("sst")
    ho = bs.held_out(seqs, SHARED_CLICKS, recs, xs, 2, sp)
    assert ho["stiffening_ratio"] == pytest.approx(1.026, abs=0.002)
    assert ho["frequency_hz"] == pytest.approx(1.566, abs=0.002)
    assert ho["frequency_stiffened_hz"] == pytest.approx(1.606, abs=0.002)
    needed = ho["frequency_measured"] / ho["frequency_hz"]
    assert needed == pytest.approx(1.091, abs=0.003) and ho["stiffening_ratio"] < needed


@pytest.mark.shared_data("sst_v2", *SLAMS)
def test_shared_17_clicks_frequency_with_the_stiffening_within_2_sd(shared):
    """1.606 +- 0.090 Hz predicted, 1.709 +- 0.106 measured: 0.74 sd (1.05 without the stiffening).
    Each record's frequency carries the half periods' scatter pooled over the three slams (5.7 % per
    half, 3 dof), the error model the coverage test in tests/test_bounce_predict.py checks on made
    records. With the vertex timing's sd alone (0.002 Hz) this was 5.9 sd, a strict xfail."""
    recs, xs, seqs = shared
    ho = bs.held_out(seqs, SHARED_CLICKS, recs, xs, 2, bs.BikeSpring.of_bike("sst"))
    assert ho["frequency_stiffened_misses_by_sd"] <= 2.0


def test_fit_bounce_writes_placements_and_the_stiffened_held_out(made, tmp_path):
    """``mtbmj fit bounce --bike``: the made records written as SST files, the bike the sst preset with
    this file's leverage (its shock is the same preloaded 80 N/mm coil). fit.json gives each record's
    placement (the generator's centres within 0.5 mm) and, held out, the frequency carried to each
    centre: its ratio to the common law's that of the closed form, n sqrt(k_i) / sum_j sqrt(k_j) over
    the two records fitted (within 0.5 %), and without a bike no stiffened entry."""
    import json
    import re
    import struct
    from pathlib import Path

    from helpers import FORK, SHOCK, counts_of
    from mtbmj import cli
    from mtbmj.bike import presets

    recs, xs, _ = made
    paths = []
    for (k, x) in zip(CLICKS, xs):
        shock = np.clip(np.rint(counts_of(x, *SHOCK)), 0, None).astype("<u2")
        p = tmp_path / f"{k}.SST"
        p.write_bytes(struct.pack("<3sBH", b"SST", 2, RATE) + np.column_stack((np.full_like(shock, 300), shock))
                      .astype("<u2").tobytes())
        paths.append(str(p))
    text = Path(presets.__file__).with_name("sst.toml").read_text()
    w = np.arange(0, 175)
    text = re.sub(r"(?m)^wheel_travel_mm = \[.*\]$", "wheel_travel_mm = [" + ", ".join(map(str, w)) + "]", text)
    text = re.sub(r"(?m)^ratio = \[.*\]$", "ratio = [" + ", ".join(repr(float(R0 - B * v * 1e-3)) for v in w) + "]",
                  text)
    (tmp_path / "bike.toml").write_text(text)
    for bike, out in (([ "--bike", str(tmp_path / "bike.toml")], tmp_path / "with"), ([], tmp_path / "without")):
        assert cli.main(["fit", "bounce", *paths, "--clicks", "0,8,17", *bike, "--out", str(out)]) == 0
    law = json.loads((tmp_path / "with" / "fit.json").read_text())["decay_law"]["shock"]
    assert [p["centre_mm"] for p in law["placements"]] == pytest.approx(list(CENTRES_MM), abs=0.5)
    for i, ho in enumerate(law["held_out"]):
        others = [CENTRES_MM[j] for j in range(3) if j != i]
        closed = 2 * math.sqrt(closed_rate(CENTRES_MM[i])) / sum(math.sqrt(closed_rate(c)) for c in others)
        assert ho["stiffening_ratio"] == pytest.approx(closed, rel=0.005)
    plain = json.loads((tmp_path / "without" / "fit.json").read_text())["decay_law"]["shock"]
    assert len(plain["placements"]) == 3 and all("frequency_stiffened_hz" not in h for h in plain["held_out"])

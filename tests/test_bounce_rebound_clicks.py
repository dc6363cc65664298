"""The rebound dampers read off the slams' first rebounds with their intervals, the law in clicks, each
record held out, and the answer in clicks (``bounce_rebound``, ``bounce_rebound_clicks``; ``fit bounce
--replay``'s ``"rebound_dampers"``).

(a) Closed forms, no replay: a damped rebound made here (x = rest + A e^(-zeta wn t) (cos wd t +
zeta / sqrt(1 - zeta^2) sin wd t) after a sin^2 rise) with white noise of a known sd: the spread
``rate_spread`` reads from the record alone matches the spread of the rate over 60 independent noise
draws made here. A law and curves made here in closed form (coefficients on a line in clicks, a
rate falling with the coefficient as r(c) = R / (1 + c / C)): the law, each record held out and the
answer for a target the test sets come back; labels shuffled and a record that does not rise are
refused in one line; an open side of the interval is said. Landings of the nuisance fit made here
(each bending the middle record off the line by a known amount, the records' curves shifted so their
own rates stay): the reproducibility part of each coefficient's interval and of the held-out sd is the
test's own (a line through two points), with it every record holds where the noise alone misses, and
a record off by 3 of the widened sd or with its clicks mislabelled misses (issue 53).

(b) Slams made here by an independent model at four rebound settings (``slam``: its own fixed-step
integrator, three masses on one line in the shock's stroke: the rider on a 5 Hz saddle, the body on
the shock, the wheel on a tyre spring; a coil with preload, the stiffness beside it, the top-out
spring, compression 2500 N s/m and rebound 1500 + 250 x clicks N s/m, Coulomb friction smoothed over
1 mm/s, noise 0.05 mm; the lumped values are those measured for ``tests/test_bounce_replay.py``'s
generator, which this one does not import) replayed with the spring (its interval 0.45-0.65 x),
friction and compression given: each click's rebound coefficient with its interval, the law, each
slam held out, and the answer for the rate a fifth slam at 6 clicks has (read by the test's own
reader). Measured: the coefficients read 2055, 2951, 3893 and 4794 N s/m for 1500, 2500, 3500 and
4500 (high by an offset that shrinks from 555 to 294 N s/m: the 0-click one is 37 % high, a strict
xfail; outside the record's noise alone, a strict xfail; inside the interval with the spring's), the
law's slope 229 N s/m per click for 250, and the answer 6 clicks (6.2 on the law, range 6-7; 6 at
both of the spring's ends): the offset is the same reading's at every click, so it cancels in the
answer.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mtbmj.identify.bounce import BounceError

FS = 5000.0


# (a) closed forms ------------------------------------------------------------------------------
def rebound_record(zeta=0.25, hz=1.6, amp=40.0, noise=0.05, seed=0):
    """(time_s, x_mm, peak): at rest at 0, a sin^2 rise of ``amp`` over 0.12 s, then the damped free motion."""
    wn = 2 * math.pi * hz
    wd = wn * math.sqrt(1 - zeta ** 2)
    t = np.arange(0.0, 3.0, 1 / FS)
    tp = 1.0
    x = np.zeros(t.size)
    up = (t > tp - 0.12) & (t <= tp)
    x[up] = amp * np.sin(0.5 * np.pi * (t[up] - (tp - 0.12)) / 0.12) ** 2
    a = t > tp
    s = t[a] - tp
    x[a] = amp * np.exp(-zeta * wn * s) * (np.cos(wd * s) + zeta / math.sqrt(1 - zeta ** 2) * np.sin(wd * s))
    return t, x + noise * np.random.default_rng(seed).standard_normal(t.size), int(np.argmin(np.abs(t - tp)))


def own_rate(t, x, peak) -> float:
    """The test's own reading of the first rebound's rate (1/s): a 10 ms moving average, the times it
    falls through 75 % and 25 % of the peak's height (linear between samples), the height's half over
    that time, per mm of the height."""
    n = int(round(0.010 * FS))
    xs = np.convolve(np.concatenate((np.full(n // 2, x[0]), x, np.full(n - 1 - n // 2, x[-1]))), np.ones(n) / n,
                     "valid")
    h = xs[peak]
    times = []
    for f in (0.75, 0.25):
        j = peak + int(np.flatnonzero(xs[peak:] <= f * h)[0])
        times.append(t[j - 1] + (f * h - xs[j - 1]) / (xs[j] - xs[j - 1]) / FS)
    return 0.5 * h / (times[1] - times[0]) / h


def test_rate_spread_is_the_noise_carried_into_the_rate():
    """The spread read from one record (its left-over over a 10 ms average, resampled) against the
    spread over 60 records made with fresh noise of the same sd: within 35 % (the spread of 60 draws'
    sd alone is about 9 %, and the left-over of a 10 ms average is not all the noise)."""
    from mtbmj.identify.bounce_rebound import rate_spread

    t, x, peak = rebound_record(noise=0.3, seed=1)
    got = rate_spread(t, x, peak, 0.0)
    truth = np.std([own_rate(*rebound_record(noise=0.3, seed=s)[:2], peak) for s in range(100, 160)], ddof=1)
    assert got["sd_per_s"] == pytest.approx(truth, rel=0.35)
    assert got["noise_mm"] == pytest.approx(0.3, rel=0.35)
    assert got["rate_per_s"] == pytest.approx(own_rate(t, x, peak), rel=0.01)


R, C_HALF = 12.0, 4000.0  # the closed-form curve: r(c) = R / (1 + c / C_HALF)


def rate_of(c):
    return R / (1.0 + np.asarray(c, float) / C_HALF)


def law_entries(clicks=(0, 5, 10, 15), c0=1000.0, slope=300.0, sd=60.0, seed=0, shuffle=None):
    """Entries as ``rebound_dampers`` gives them: coefficients on the line (with noise of ``sd``), their
    noise intervals +-1.96 sd, the record's rate from the curve, and the curve."""
    rng = np.random.default_rng(seed)
    cs = np.array([c0 + slope * k for k in clicks]) + sd * rng.standard_normal(len(clicks))
    curve = [[c, float(rate_of(c))] for c in np.geomspace(50.0, 30000.0, 40)]
    labels = list(clicks) if shuffle is None else [clicks[i] for i in shuffle]
    return [{"file": f"r{k}", "clicks": lab, "rebound_N_s_per_m": float(c),
             "rebound_noise_ci95": [float(c - 1.96 * sd), float(c + 1.96 * sd)],
             "rebound_N_s_per_m_ci95": [float(c - 1.96 * sd), float(c + 1.96 * sd)], "interval_open": [],
             "record_mid_rebound_per_s": float(rate_of(c)), "record_rate_sd_per_s": float(
                 abs(R / C_HALF / (1 + c / C_HALF) ** 2) * sd), "rate_curve": curve}
            for k, lab, c in zip(clicks, labels, cs)]


def test_law_comes_back_within_its_interval():
    from mtbmj.identify.bounce_rebound_clicks import fit_law

    hits = 0
    for seed in range(40):
        law = fit_law(law_entries(seed=seed))
        lo, hi = law["slope_ci95"]
        hits += lo <= 300.0 <= hi
        assert law["records_rates_fall"]
    assert hits >= 34  # 95 % of 40 is 38; 34 is its binomial 1 % lower limit


def test_held_out_holds_on_a_line_and_misses_a_kink():
    """Records on the line (50 sets of four, fresh noise): the held-out z (prediction less the record,
    over their combined sd) has a spread near 1 and about 95 % hold (at least 90 % of 200; a z that is
    all noise). The last record moved 2500 N s/m off the line (41 of its sd): held out, it misses."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    zs = np.array([r["z"] for s in range(50) for r in held_out(law_entries(seed=s))])
    assert zs.size == 200 and 0.75 < np.std(zs) < 1.25
    assert np.mean(np.abs(zs) <= 2.0) >= 0.90
    bent = law_entries(seed=3)
    bent[-1]["rebound_N_s_per_m"] += 2500.0
    bent[-1]["rebound_noise_ci95"] = [v + 2500.0 for v in bent[-1]["rebound_noise_ci95"]]
    bent[-1]["record_mid_rebound_per_s"] = float(rate_of(bent[-1]["rebound_N_s_per_m"]))
    rows = held_out(bent)
    assert rows[-1]["holds"] is False and abs(rows[-1]["z"]) > 2


TRUE_C = {0: 1000.0, 8: 3400.0, 17: 6100.0}  # made coefficients on the line 1000 + 300 x clicks
BENDS = ([0.0, 60.0, 0.0], [0.0, -40.0, 0.0], [0.0, 20.0, 0.0], [0.0, -30.0, 0.0])  # N s/m: the reading's, then
# three restarts': each landing bends the middle record off the line (as a landing of the nuisance fit does)
SD_C = 5.0  # N s/m: each record's noise, small beside the bends (as on the shared slams)


def landing(bend, labels=(0, 8, 17), off=(0.0, 0.0, 0.0)):
    """Entries as ``rebound_dampers`` reads them at one landing of the nuisance fit: each record's curve is
    the closed form shifted by its bend, rate(c) = rate_of(c - bend), so the record's own rate (fixed:
    the record does not change with the landing) reads the coefficient true + bend; ``off`` (1/s) moves a
    record's own rate, ``labels`` relabels its clicks."""
    out = []
    for (k, c), lab, b, o in zip(TRUE_C.items(), labels, bend, off):
        rate = float(rate_of(c)) + o
        read = float(C_HALF * (R / rate - 1.0)) + b  # the coefficient whose shifted curve gives that rate
        out.append({"file": f"r{k}", "clicks": lab, "rebound_N_s_per_m": read,
                    "rebound_noise_ci95": [read - 1.96 * SD_C, read + 1.96 * SD_C], "record_mid_rebound_per_s": rate,
                    "record_rate_sd_per_s": float(R / C_HALF / (1 + c / C_HALF) ** 2) * SD_C,
                    "rate_curve": [[x, float(rate_of(x - b))] for x in np.geomspace(50.0, 30000.0, 4000)]})
    return out


def own_residuals(j, labels=(0, 8, 17), off=(0.0, 0.0, 0.0)):
    """The test's own held-out residuals of record ``j`` at every landing: the straight line through the
    other two records' coefficients (two points: exact, no weights), at record j's clicks, through
    record j's shifted curve, less its rate."""
    out = []
    for bend in BENDS:
        e = landing(bend, labels, off)
        others = [i for i in range(3) if i != j]
        a, b = np.polyfit([e[i]["clicks"] for i in others], [e[i]["rebound_N_s_per_m"] for i in others], 1)
        c = a * e[j]["clicks"] + b
        out.append(float(rate_of(c - bend[j])) - e[j]["record_mid_rebound_per_s"])
    return out


def test_held_out_carries_the_nuisance_fits_reproducibility():
    """Three records whose coefficients bend off their line by a different amount at every landing of
    the nuisance fit (made here): the held-out sd's reproducibility part is the residuals' sd over the
    reading and its three restarts, as the test computes it (a line through two points); with it every
    record holds; with the noise alone (no restarts: the naive sd) the same reading misses."""
    from mtbmj.identify.bounce_rebound_clicks import held_out, held_out_line

    main, again = landing(BENDS[0]), [landing(b) for b in BENDS[1:]]
    rows = held_out(main, again)
    for j, row in enumerate(rows):
        own = own_residuals(j)
        assert row["residual_per_s"] == pytest.approx(own[0], rel=1e-3, abs=1e-6)
        assert row["restart_residuals_per_s"] == pytest.approx(own[1:], rel=1e-3, abs=1e-6)
        assert row["reproducibility_sd_per_s"] == pytest.approx(np.std(own, ddof=1), rel=1e-3)
        assert row["sd_per_s"] > 3 * math.hypot(row["predicted_rate_sd_per_s"], row["record_rate_sd_per_s"])
    assert all(r["holds"] for r in rows)
    assert "reproducibility over 3 restart(s)" in held_out_line(rows)
    naive = held_out(main)
    assert naive[1]["reproducibility_sd_per_s"] is None and naive[1]["holds"] is False and abs(naive[1]["z"]) > 5
    assert "reproducibility not measured" in held_out_line(naive)


def test_each_coefficients_interval_carries_the_restarts():
    """``bounce_rebound.reproducibility`` on the made landings: each record's coefficients at the
    restarts listed, their sd with the reading's (the test's own: the true coefficient plus each
    landing's bend) and its interval's half-width the noise's and 1.96 of that sd in quadrature; a
    restart that read no coefficient for a record is left out of its sd; no restarts, no part."""
    from mtbmj.identify.bounce_rebound import reproducibility

    main, again = landing(BENDS[0]), [landing(b) for b in BENDS[1:]]
    reproducibility(main, again)
    for j, e in enumerate(main):
        own = [TRUE_C[int(e["clicks"])] + b[j] for b in BENDS]
        assert e["rebound_restarts_N_s_per_m"] == pytest.approx(own[1:], abs=0.5)
        sd = float(np.std(own, ddof=1))
        assert e["rebound_reproducibility_sd_N_s_per_m"] == pytest.approx(sd, abs=0.5)
        half = math.hypot(1.96 * SD_C, 1.959963984540054 * e["rebound_reproducibility_sd_N_s_per_m"])
        assert e["rebound_N_s_per_m_ci95"] == pytest.approx([e["rebound_N_s_per_m"] - half,
                                                             e["rebound_N_s_per_m"] + half], rel=1e-9)
    main, again = landing(BENDS[0]), [landing(b) for b in BENDS[1:]]
    del again[0][1]["rebound_N_s_per_m"]
    reproducibility(main, again)
    assert main[1]["rebound_restarts_N_s_per_m"][0] is None
    assert main[1]["rebound_reproducibility_sd_N_s_per_m"] == pytest.approx(
        np.std([3400.0 + b[1] for b in (BENDS[0], BENDS[2], BENDS[3])], ddof=1), abs=0.5)
    main = landing(BENDS[0])
    reproducibility(main, [])
    assert main[1]["rebound_reproducibility_sd_N_s_per_m"] is None
    assert main[1]["rebound_N_s_per_m_ci95"] == pytest.approx(main[1]["rebound_noise_ci95"], rel=1e-9)


@pytest.mark.parametrize("j", [0, 1, 2])
def test_held_out_with_restarts_misses_a_record_off_by_3_sd(j):
    """The reading on the line (the restarts bent as above) with record ``j``'s rate moved by 3 of its
    widened sd (at every landing: the record is what is off), so its coefficient is read off by as
    much: held out, it misses; consistent (not moved) it holds at z 0, and moved by 0.75 sd it holds."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    straight = [0.0, 0.0, 0.0]
    rows = held_out(landing(straight), [landing(b) for b in BENDS[1:]])
    assert rows[j]["holds"] and rows[j]["z"] == pytest.approx(0.0, abs=1e-3)
    sd = rows[j]["sd_per_s"]
    for k, holds in ((3.0, False), (-3.0, False), (0.75, True)):
        off = tuple(k * sd if i == j else 0.0 for i in range(3))
        rows = held_out(landing(straight, off=off), [landing(b, off=off) for b in BENDS[1:]])
        assert rows[j]["holds"] is holds, (k, rows[j]["z"])
        assert abs(rows[j]["z"]) > 2.5 if not holds else abs(rows[j]["z"]) < 1.0


def test_held_out_with_restarts_misses_mislabelled_clicks():
    """The 8-click record labelled 12 (its coefficients still rise with the labels, so the law is
    fitted): held out, it misses by far more than the widened sd, at every landing alike."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    labels = (0, 12, 17)
    rows = held_out(landing(BENDS[0], labels), [landing(b, labels) for b in BENDS[1:]])
    assert rows[1]["holds"] is False and abs(rows[1]["z"]) > 10
    assert rows[1]["residual_per_s"] == pytest.approx(own_residuals(1, labels)[0], rel=1e-3)


# the nuisance values' ends (issue 53): the records read again at each end of the friction's and the
# compression's 95 % intervals bend the middle record off the line by a known amount (the test's own)
ENDS = {"friction_N": ([0.0, -25.0, 0.0], [0.0, 35.0, 0.0]), "compression_N_s_per_m": ([0.0, 80.0, 0.0],
                                                                                   [0.0, -70.0, 0.0])}


def at_ends(labels=(0, 8, 17), off=(0.0, 0.0, 0.0)):
    return {k: [landing(b, labels, off) for b in pair] for k, pair in ENDS.items()}


def own_nuisance_sd(j, bend, labels=(0, 8, 17), off=(0.0, 0.0, 0.0)):
    """The test's own nuisance part of record ``j``'s held-out sd: its residual (a line through the other
    two) at each end less at the reading, the mean move per value / 1.96, the values in quadrature."""
    def residual(b):
        e = landing(b, labels, off)
        others = [i for i in range(3) if i != j]
        a, c0 = np.polyfit([e[i]["clicks"] for i in others], [e[i]["rebound_N_s_per_m"] for i in others], 1)
        return float(rate_of(a * e[j]["clicks"] + c0 - b[j])) - e[j]["record_mid_rebound_per_s"]

    r0 = residual(bend)
    return math.sqrt(sum((np.mean([abs(residual(b) - r0) for b in pair]) / 1.959963984540054) ** 2
                         for pair in ENDS.values()))


def test_held_out_carries_the_nuisance_values_intervals():
    """A reading bent off the line (60 N s/m at the middle record) with the records read again at the
    ends of the friction's and compression's intervals (made here): the held-out sd's nuisance part is
    the test's own (a line through two points at each end); with it every record holds, with the noise
    alone the same reading misses; an end that read nothing is left out of its value's part."""
    from mtbmj.identify.bounce_rebound_clicks import held_out, held_out_line

    rows = held_out(landing(BENDS[0]), (), at_ends())
    for j, row in enumerate(rows):
        assert row["nuisance_sd_per_s"] == pytest.approx(own_nuisance_sd(j, BENDS[0]), rel=1e-3)
        assert row["reproducibility_sd_per_s"] is None
    assert all(r["holds"] for r in rows), [r["z"] for r in rows]
    assert "the compression and friction given at their 95 % ends" in held_out_line(rows)
    naive = held_out(landing(BENDS[0]))
    assert naive[1]["holds"] is False and abs(naive[1]["z"]) > 5 and naive[1]["nuisance_sd_per_s"] is None
    half = at_ends()
    half["friction_N"][1] = None
    row = held_out(landing(BENDS[0]), (), half)[1]
    assert row["nuisance_residuals_per_s"]["friction_N"][1] is None
    r0, got = row["residual_per_s"], row["nuisance_residuals_per_s"]
    assert got["friction_N"][0] == pytest.approx(rows[1]["nuisance_residuals_per_s"]["friction_N"][0], rel=1e-9)
    z95 = 1.959963984540054
    assert row["nuisance_sd_per_s"] == pytest.approx(math.hypot(
        abs(got["friction_N"][0] - r0) / z95, np.mean([abs(v - r0) for v in got["compression_N_s_per_m"]]) / z95))


@pytest.mark.parametrize("j", [0, 1, 2])
def test_held_out_with_nuisance_ends_misses_a_record_off_by_3_sd(j):
    """The reading on the line, the records bent at the nuisance ends as above, record ``j``'s rate moved
    by 3 of its widened sd (at every end: the record is what is off): held out, it misses; moved by
    0.75 sd it holds."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    straight = [0.0, 0.0, 0.0]
    rows = held_out(landing(straight), (), at_ends())
    assert rows[j]["holds"] and rows[j]["nuisance_sd_per_s"] > 3 * rows[j]["record_rate_sd_per_s"]
    sd = rows[j]["sd_per_s"]
    for k, holds in ((3.0, False), (-3.0, False), (0.75, True)):
        off = tuple(k * sd if i == j else 0.0 for i in range(3))
        row = held_out(landing(straight, off=off), (), at_ends(off=off))[j]
        assert row["holds"] is holds, (k, row["z"])


def test_held_out_with_nuisance_ends_misses_mislabelled_clicks():
    """The 8-click record labelled 12, read at the nuisance ends alike: held out, it misses by far more
    than the widened sd."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    labels = (0, 12, 17)
    rows = held_out(landing(BENDS[0], labels), (), at_ends(labels))
    assert rows[1]["nuisance_sd_per_s"] == pytest.approx(own_nuisance_sd(1, BENDS[0], labels), rel=1e-3)
    assert rows[1]["holds"] is False and abs(rows[1]["z"]) > 10


def test_spring_ends_are_the_records_as_read_there():
    """``bounce_rebound.at_spring_ends``: each read record at the spring interval's ends as
    ``rebound_dampers`` read it there (its coefficient and curve there, its noise interval moved with the
    coefficient); an end where one record read none is None; held out there, the residual is the test's
    own at that end's bend."""
    from mtbmj.identify.bounce_rebound import at_spring_ends
    from mtbmj.identify.bounce_rebound_clicks import held_out

    lo, hi = landing([0.0, 50.0, 0.0]), landing([0.0, -45.0, 0.0])
    main = landing(BENDS[0])
    for e, a, b in zip(main, lo, hi):
        e["at_spring_ci95"] = [a["rebound_N_s_per_m"], b["rebound_N_s_per_m"]]
        e["rate_curve_at_spring_ci95"] = [a["rate_curve"], b["rate_curve"]]
    got = at_spring_ends(main)
    for e, a in zip(got[1], hi):
        assert e["rebound_N_s_per_m"] == pytest.approx(a["rebound_N_s_per_m"])
        assert e["rebound_noise_ci95"] == pytest.approx(a["rebound_noise_ci95"])
    row = held_out(main, (), {"spring_scale": got})[1]
    e = landing([0.0, -45.0, 0.0])
    a, c0 = np.polyfit([0, 17], [e[0]["rebound_N_s_per_m"], e[2]["rebound_N_s_per_m"]], 1)
    own = float(rate_of(a * 8 + c0 + 45.0)) - e[1]["record_mid_rebound_per_s"]
    assert row["nuisance_residuals_per_s"]["spring_scale"][1] == pytest.approx(own, rel=1e-3)
    main[0]["at_spring_ci95"][0] = None
    assert at_spring_ends(main)[0] is None and at_spring_ends(main)[1] is not None


def test_each_coefficients_interval_carries_the_nuisance_ends():
    """``bounce_rebound.combine`` with the coefficients at the nuisance values' ends: each side's half-width
    the noise's and, per value, the larger move of its ends on that side in quadrature (an end moving
    the coefficient down widens the low side only); an end that read none opens both sides."""
    from mtbmj.identify.bounce_rebound import combine

    c, noise = 1000.0, [990.0, 1010.0]
    got, why = combine(c, noise, None, None, {"friction_N": [900.0, 1050.0], "compression_N_s_per_m": [1200.0, 1100.0]})
    assert got == pytest.approx([c - math.hypot(10.0, 100.0), c + math.sqrt(10.0 ** 2 + 50.0 ** 2 + 200.0 ** 2)])
    assert why == []
    got, why = combine(c, noise, None, None, {"friction_N": [900.0, None]})
    assert got == [None, None] and all("friction_N" in w for w in why)


@pytest.mark.parametrize("k_true", [3.0, 7.0, 12.0])
def test_answer_for_a_target_the_test_sets(k_true):
    """The target: the rate the closed-form curve has at the line's coefficient for ``k_true`` clicks;
    the answer is that click, within the range."""
    from mtbmj.identify.bounce_rebound_clicks import answer, answer_line

    target = float(rate_of(1000.0 + 300.0 * k_true))
    ans = answer(law_entries(sd=30.0, seed=5), target)
    assert ans["set_clicks"] == round(k_true)
    lo, hi = ans["clicks_range95"]
    assert lo <= k_true <= hi and hi - lo <= 3
    assert f"set {round(k_true)} clicks" in answer_line(ans)
    assert ans["records_clicks"] == pytest.approx(k_true, abs=1.0)  # the rates joined by chords: near the curve


def test_answer_past_the_records_is_refused_with_its_side():
    from mtbmj.identify.bounce_rebound_clicks import answer

    ans = answer(law_entries(), float(rate_of(1000.0 + 300.0 * 22)))
    assert ans["set_clicks"] is None and "more than 15 clicks" in ans["note"]
    ans = answer(law_entries(), None)
    assert ans["set_clicks"] is None and "no target given" in ans["note"]


def test_shuffled_labels_are_refused_in_one_line():
    """The clicks' labels shuffled (the records are at 0, 5, 10, 15; labelled 10, 0, 15, 5): the
    coefficients do not rise with the labels: refused, one line, no answer."""
    from mtbmj.identify.bounce_rebound import law_in_clicks

    got = law_in_clicks(law_entries(shuffle=[2, 0, 3, 1]), 6.0)
    assert "refused" in got["law"] and "mislabelled" in got["law"]["refused"]
    assert "\n" not in got["law"]["refused"]
    assert got["answer"]["set_clicks"] is None and got["held_out"] == []
    assert got["lines"][0].startswith("rebound law refused: no law in clicks")


def test_a_record_without_its_noise_is_refused():
    from mtbmj.identify.bounce_rebound_clicks import fit_law

    e = law_entries()
    e[2]["rebound_noise_ci95"] = [None, None]
    with pytest.raises(BounceError, match="the noise of r10 was not read"):
        fit_law(e)


def test_records_that_do_not_slow_are_flagged():
    """The coefficients rise but the records' own rates do not fall with the clicks (one swapped): the
    law is fitted and flagged."""
    from mtbmj.identify.bounce_rebound import law_in_clicks

    e = law_entries()
    e[1]["record_mid_rebound_per_s"], e[2]["record_mid_rebound_per_s"] = (e[2]["record_mid_rebound_per_s"],
                                                                          e[1]["record_mid_rebound_per_s"])
    got = law_in_clicks(e, None)
    assert got["law"]["records_rates_fall"] is False
    assert "flagged: the records' own first rebounds do not slow" in got["lines"][0]


def test_interval_open_where_an_end_is_missing():
    from mtbmj.identify.bounce_rebound import combine

    ends, why = combine(1000.0, [900.0, 1100.0], [None, 1400.0])
    assert ends[0] is None and ends[1] == pytest.approx(1000.0 + math.hypot(100.0, 400.0))
    assert why == ["open below: no coefficient within 50-30000 N s/m at the spring interval's lower end"]
    ends, why = combine(1000.0, [900.0, 1100.0], [700.0, 1400.0])
    assert ends == pytest.approx([1000.0 - math.hypot(100.0, 300.0), 1000.0 + math.hypot(100.0, 400.0)]) and not why


def test_figure_shows_the_law_the_answer_and_open_sides():
    """rebound.png: the law's line through its two values, the answer's star at its clicks, one
    dashed line per open side, and on the right one held-out marker per record."""
    from mtbmj.identify.bounce_rebound import law_in_clicks
    from mtbmj.identify.bounce_rebound_clicks import figure, figure_png

    e = law_entries(sd=30.0, seed=5)
    for x in e:
        x["rebound_N_s_per_m_ci95"] = [None, x["rebound_noise_ci95"][1] + 500.0]
    got = {"records": e, **law_in_clicks(e, float(rate_of(1000.0 + 300.0 * 7)))}
    ax, bx = figure(got).axes
    law = got["law"]
    line = [ln for ln in ax.get_lines() if ln.get_label().startswith("law ")][0]
    xs, ys = line.get_data()
    assert ys[0] == pytest.approx(law["c0_N_s_per_m"] + law["slope_N_s_per_m_per_click"] * xs[0])
    star = [ln for ln in ax.get_lines() if ln.get_label().startswith("set 7 clicks")][0]
    assert star.get_xdata()[0] == pytest.approx(got["answer"]["clicks_exact"])
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--" and len(ln.get_xdata()) == 2]
    assert len(dashed) == len(e)
    assert figure_png(got)[:4] == b"\x89PNG"
    assert len(bx.containers) == 2 * len(e)  # the records' and the held-out error bars
    assert "\n" not in ax.get_title()  # nothing to say: no spring source given, none refused
    assert "(95 %: noise, spring)" in ax.get_title()  # no restarts read: their part not claimed
    again = {**got, "records": [r | {"rebound_reproducibility_sd_N_s_per_m": 50.0} for r in e]}
    assert "(95 %: noise, spring, restarts)" in figure(again).axes[0].get_title()
    # the friction's and compression's ends carried: the title and the held-out legend say so, and no
    # restarts are claimed where none were read
    given = [r | {"at_nuisance_ci95": {"friction_N": [None, 2000.0], "compression_N_s_per_m": [1500.0, 2500.0]}}
             for r in e]
    carried = {**got, "records": given,
               "held_out": [h | {"nuisance_sd_per_s": 0.2} for h in got["held_out"]]}
    ax2, bx2 = figure(carried).axes
    assert "(95 %: noise, spring, compression, friction)" in ax2.get_title()
    labels = [h.get_label() for h in bx2.get_legend().legend_handles]
    assert any(t.endswith("(95 %: law, values given)") for t in labels), labels
    assert any(t.endswith("(95 %: law)") for t in (h.get_label() for h in bx.get_legend().legend_handles))
    # the spring's source and a refused record said in the title
    said = {**got, "spring_scale": 0.46, "spring_from": "the ring-down's period",
            "records": [{"clicks": -4, "refused": "no coefficient"}] + e}
    assert figure(said).axes[0].get_title().endswith("spring 0.46 x from the ring-down's period; refused at -4 clicks")


def test_cli_target_needs_replay_and_a_positive_rate(tmp_path, capsys):
    from helpers import one_line

    one_line(capsys, ["fit", "bounce", "a.SST", "--clicks", "0", "--rebound-target-per-s", "7",
                      "--out", str(tmp_path / "o")], "--rebound-target-per-s", "--replay")
    one_line(capsys, ["fit", "bounce", "a.SST", "--clicks", "0", "--replay", "--bike", "sst",
                      "--rebound-target-per-s", "-1", "--out", str(tmp_path / "o")], "positive")
    assert not (tmp_path / "o").exists()


# (b) slams of an independent model ----------------------------------------------------------------
from helpers import (SLAM_K_OTHER as K_OTHER, SLAM_K_TYRE as K_TYRE, SLAM_TOP_OUT as TOP_OUT,  # noqa: E402
                     SLAM_W_SHOCK as W_SHOCK, slam_parts)
SCALE, COMPRESSION, FRICTION = 0.55, 2500.0, 30.0


def rebound_at(clicks):
    return 1500.0 + 250.0 * clicks  # N s/m: the generator's rebound per click


def slam(rebound, seed=0, dt=2e-5, quiet=2.0, after=1.6, noise=0.05, rest_mm=14.0):
    """(time_s, stroke_mm): at rest, a lift (0.6 x the static force over 0.35 s) and a slam (1.0 x over
    0.2 s) on the rider, then free. State y = (body, wheel, saddle) positions and speeds, down positive;
    stepped with the midpoint rule (velocities and positions from the half step's forces)."""
    k, m_r, m_b, m_w, k_r, c_r, g_r, g_b, x_rest, preload = slam_parts(SCALE, rest_mm)

    def acc(t, p, v):
        zb, zw, y = p
        vb, vw, vy = v
        f = 0.0
        if quiet - 0.55 < t < quiet - 0.2:
            f -= 0.6 * W_SHOCK * math.sin(math.pi * (t - quiet + 0.55) / 0.35)
        if quiet - 0.2 < t < quiet:
            f += W_SHOCK * math.sin(math.pi * (t - quiet + 0.2) / 0.2)
        x, xv = zb - zw, vb - vw
        saddle = k_r * y + c_r * vy
        spring = preload + k * x + K_OTHER * (x - x_rest) - TOP_OUT * max(0.0, preload / TOP_OUT - x)
        damper = (COMPRESSION if xv > 0 else rebound) * xv + FRICTION * math.tanh(xv / 1e-3)
        tyre = max(0.0, W_SHOCK + K_TYRE * zw)
        ab = (g_b + saddle - spring - damper) / m_b
        aw = (spring + damper - tyre) / m_w
        return np.array([ab, aw, (g_r + f - saddle) / m_r - ab])

    p = np.array([x_rest, 0.0, g_r / k_r])
    v = np.zeros(3)
    every = int(round(1 / (FS * dt)))
    out = []
    for i in range(int(round((quiet + after) / dt))):
        t = i * dt
        a1 = acc(t, p, v)
        ph, vh = p + 0.5 * dt * v, v + 0.5 * dt * a1
        a2 = acc(t + 0.5 * dt, ph, vh)
        p, v = p + dt * vh, v + dt * a2
        if i % every == 0:
            out.append(p[0] - p[1])
    x = np.array(out) * 1e3
    return np.arange(x.size) / FS, x + noise * np.random.default_rng(seed).standard_normal(x.size)


GEN_CLICKS = (0, 4, 8, 12)
SPRING_CI95 = (SCALE - 0.10, SCALE + 0.10)  # the spring's interval given (the shared replays' is +-0.34)


@pytest.fixture(scope="module")
def generated():
    from mtbmj.identify.bounce_rebound import rebound_dampers
    from mtbmj.identify.bounce_replay import SeatedReplay, prepare_slam

    sr = SeatedReplay("sst")
    slams = []
    for k in GEN_CLICKS:
        t, x = slam(rebound_at(k), seed=k)
        slams.append(prepare_slam(t, x, None, f"clicks {k}", sr))
    entries = rebound_dampers(slams, list(GEN_CLICKS), SCALE, FRICTION, COMPRESSION, spring_ci95=SPRING_CI95)
    t, x = slam(rebound_at(6), seed=6)
    peak = int(np.argmax(x))
    target = own_rate(t, x - np.median(x[(t > 0.5) & (t < 1.5)]), peak)
    return entries, target


@pytest.mark.slow
def test_generator_rebound_per_click(generated):
    """Each click's rebound coefficient read, inside its own interval, and rising with the clicks; at
    4, 8 and 12 clicks (2500-4500 N s/m) within 30 % of the generator's (the method's stated tolerance
    on an independent generator, ``test_bounce_replay``); 0 clicks: the next test."""
    entries, _ = generated
    assert [e.get("refused") for e in entries] == [None] * len(GEN_CLICKS)
    for e in entries:
        lo, hi = e["rebound_N_s_per_m_ci95"]
        assert lo < e["rebound_N_s_per_m"] < hi and not e["interval_open"]
        if e["clicks"] > 0:
            assert e["rebound_N_s_per_m"] == pytest.approx(rebound_at(e["clicks"]), rel=0.30)
    cs = [e["rebound_N_s_per_m"] for e in entries]
    assert all(b > a for a, b in zip(cs, cs[1:]))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="measured: the replay reads the generator 294-555 N s/m high (2055, 2951, 3893, "
                                       "4794 for 1500, 2500, 3500, 4500): 37 % at 0 clicks, past the 30 % tolerance")
def test_generator_lowest_click_within_tolerance(generated):
    entries, _ = generated
    assert entries[0]["rebound_N_s_per_m"] == pytest.approx(rebound_at(0), rel=0.30)


@pytest.mark.slow
def test_generator_truth_within_the_interval(generated):
    """With the spring's interval 0.45-0.65 x given, every click's 95 % interval (the record's noise and
    the spring's ends) holds the generator's rebound coefficient, and none is open."""
    entries, _ = generated
    for e in entries:
        lo, hi = e["rebound_N_s_per_m_ci95"]
        assert not e["interval_open"] and lo <= rebound_at(e["clicks"]) <= hi


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the record's noise alone: +-25-30 N s/m, while the replay reads the generator "
                                       "294-555 N s/m high (model error: the generator is not the bike)")
def test_generator_truth_within_the_noise_alone(generated):
    entries, _ = generated
    for e in entries:
        lo, hi = e["rebound_noise_ci95"]
        assert lo <= rebound_at(e["clicks"]) <= hi


@pytest.mark.slow
def test_generator_held_out(generated):
    """Each of the four slams predicted from the other three's law, carried to its first-rebound rate:
    within 2 sd of the record's (the reading's offset is the same at every click, so it cancels)."""
    from mtbmj.identify.bounce_rebound_clicks import held_out

    rows = held_out(generated[0])
    assert len(rows) == 4 and all(r["holds"] for r in rows)


@pytest.mark.slow
def test_generator_answer_in_clicks(generated):
    """The target: the first-rebound rate of a fifth slam at 6 clicks (not among the four fitted),
    read by the test's own reader; the answer is 6 clicks, 6 within its range."""
    from mtbmj.identify.bounce_rebound import law_in_clicks

    entries, target = generated
    got = law_in_clicks(entries, target)
    assert "refused" not in got["law"] and got["law"]["slope_N_s_per_m_per_click"] > 0
    ans = got["answer"]
    assert ans["set_clicks"] == 6
    assert ans["clicks_range95"][0] <= 6 <= ans["clicks_range95"][1]
    assert [end["set_clicks"] for end in ans["at_spring_ci95"]] == [6, 6]  # the spring's ends: the same answer


@pytest.mark.shared_data("sst_v2", "00083.SST", "00085.SST", "00087.SST")
def test_cli_writes_and_prints_the_answer(tmp_path, monkeypatch, capsys):
    """``fit bounce --replay --rebound-target-per-s``'s wiring, the replays (minutes) replaced by this
    file's closed-form entries at the records' clicks: fit.json's "rebound_dampers" has the law, the
    held-out rows and the answer for the target, the lines are printed and rebound.png is written."""
    import json
    import os

    from conftest import SHARED_DATA

    from mtbmj.cli import main
    from mtbmj.identify import bounce_rebound, bounce_replay

    monkeypatch.setattr(bounce_replay, "replay_records", lambda records, clicks, bike, rider_hz: {
        "summary": [], "csv": {}, "replays": [], "lines": [], "check": None})

    def read(records, clicks, replayed, bike, rider_hz, target, ring="unset"):
        assert ring is None  # fit bounce gives the slam-and-first-rebound's "ring_fit": none here, nothing replayed
        e = law_entries(clicks=tuple(int(k) for k in clicks), sd=30.0, seed=5)
        return {"from": "test", "records": e, "rises": True, "line": "dampers",
                **bounce_rebound.law_in_clicks(e, target)}

    monkeypatch.setattr(bounce_rebound, "read_records", read)
    files = [os.path.join(SHARED_DATA, "sst_v2", f) for f in ("00083.SST", "00085.SST", "00087.SST")]
    target = float(rate_of(1000.0 + 300.0 * 7))
    assert main(["fit", "bounce", *files, "--clicks", "0,8,17", "--bike", "sst", "--replay",
                 "--rebound-target-per-s", str(target), "--out", str(tmp_path / "o")]) == 0
    printed = capsys.readouterr().out
    got = json.loads((tmp_path / "o" / "fit.json").read_text())["rebound_dampers"]
    assert got["answer"]["set_clicks"] == 7 and got["answer"]["target_per_s"] == pytest.approx(target)
    assert len(got["held_out"]) == 3 and "c0_N_s_per_m" in got["law"]
    assert "rebound answer (first rebound at" in printed and "set 7 clicks" in printed
    assert (tmp_path / "o" / "rebound.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_generator_shuffled_labels_refused(generated):
    """The four slams read with their clicks labels shuffled (0, 4, 8, 12 labelled 8, 0, 12, 4): the
    coefficients do not rise with the labels: the law refused in one line, no answer."""
    from mtbmj.identify.bounce_rebound import law_in_clicks

    entries, target = generated
    wrong = [{**e, "clicks": k} for e, k in zip(entries, (8, 0, 12, 4))]
    got = law_in_clicks(wrong, target)
    assert "mislabelled" in got["law"]["refused"] and "\n" not in got["law"]["refused"]
    assert got["answer"]["set_clicks"] is None and got["held_out"] == []


# the friction and compression carried jointly, and the answer's range with them (issue 53): a world made
# here in which the replay's rate of record k at coefficient c, friction f, compression q and spring s is
# R / (1 + (c + A_k (f - F) + B_k (q - Q) + S_k (s - 0.5)) / C_HALF), the records' own rates those of the
# line 1000 + 300 x clicks at the true F, Q and 0.5 x; the values given are off the truth along their trade
F_TRUE, Q_TRUE, RHO = 60.0, 1800.0, -0.8
A_K, B_K, S_K = (0.0, 4.0, 0.0), (0.0, -0.3, 0.0), (0.0, 3000.0, 0.0)  # N s/m per N, per N s/m, per x
H_F, H_Q, H_S = 150.0, 1200.0, 0.1  # the values' 95 % half-widths


def world(f, q, s=0.5, labels=(0, 8, 17)):
    """Entries as ``rebound_dampers`` reads them with friction f, compression q and spring s given: each
    record's coefficient solved on its own curve for its own (true) rate, the curve and the noise."""
    out = []
    for j, ((k, c), lab) in enumerate(zip(TRUE_C.items(), labels)):
        shift = A_K[j] * (f - F_TRUE) + B_K[j] * (q - Q_TRUE) + S_K[j] * (s - 0.5)
        rate = float(rate_of(c))
        read = c - shift
        out.append({"file": f"r{k}", "clicks": lab, "rebound_N_s_per_m": read,
                    "rebound_noise_ci95": [read - 1.96 * SD_C, read + 1.96 * SD_C], "record_mid_rebound_per_s": rate,
                    "record_rate_sd_per_s": float(R / C_HALF / (1 + c / C_HALF) ** 2) * SD_C,
                    "rate_curve": [[x, float(rate_of(x + shift))] for x in np.geomspace(50.0, 30000.0, 4000)]})
    return out


def given_world(f, q, labels=(0, 8, 17)):
    """The reading at the values given (f, q), the spring's ends read as well; the replay's summary as
    ``bounce_replay`` gives it (its intervals and the friction's and damper's correlation)."""
    from mtbmj.identify.bounce_ends import CORRELATION

    main = world(f, q, labels=labels)
    ends = [world(f, q, s, labels) for s in (0.5 - H_S, 0.5 + H_S)]
    for j, e in enumerate(main):
        e["at_spring_ci95"] = [x[j]["rebound_N_s_per_m"] for x in ends]
        e["rate_curve_at_spring_ci95"] = [x[j]["rate_curve"] for x in ends]
    best = {"friction_N": f, "friction_N_ci95": [max(f - H_F, 0.0), f + H_F], "damper_N_s_per_m": q,
            "damper_N_s_per_m_ci95": [q - H_Q, q + H_Q], CORRELATION: RHO}
    return main, best


def test_joint_ends_carry_the_correlation():
    """``bounce_ends.joint_ends``: for a reading linear in the friction and compression (g = u f + v q),
    its moves at the two axes' ends, in quadrature, are 1.96 of g's standard deviation with their
    correlation (the test's own: u^2 sf^2 + v^2 sq^2 + 2 rho u v sf sq); each value's own ends (the
    correlation left out) miss it; a summary without the correlation gives None."""
    from mtbmj.identify.bounce_ends import JOINT, joint_ends

    f, q = 400.0, 3000.0
    _, best = given_world(f, q)
    ends = joint_ends(best)
    assert sorted(ends) == sorted(JOINT)
    for u, v in ((1.0, 0.125), (1.0, -0.125)):
        sf, sq = H_F / 1.959963984540054, H_Q / 1.959963984540054
        truth = 1.959963984540054 * math.sqrt(u * u * sf * sf + v * v * sq * sq + 2 * RHO * u * v * sf * sq)
        moved = math.sqrt(sum(np.mean([abs(u * (a - f) + v * (b - q)) for a, b in pair]) ** 2 for pair in ends.values()))
        assert moved == pytest.approx(truth, rel=1e-9)
        alone = math.hypot(u * H_F, v * H_Q)
        assert abs(alone - truth) > 0.1 * truth
    assert joint_ends({k: v for k, v in best.items() if k != "friction_compression_correlation"}) is None
    low = joint_ends({**best, "friction_N": 10.0, "friction_N_ci95": [0.0, 160.0]})
    assert min(p[0] for pair in low.values() for p in pair) == 0.0  # cut at 0


def test_answer_range_carries_the_values_given():
    """The values given off the truth along their trade (half of the traded axis' 95 % end): the answer's
    range with the friction's and compression's (jointly) and the spring's ends holds the true answer (the
    test's own: where the line's rate reaches the target) and is the test's own quadrature of the law's
    half-widths and the larger move of each value's ends per side (the answers at each end read from the
    world's records there); the range made without them is narrower. Read at the truth, the bare range
    is 7-8 clicks and the carried 6-9. Measured here: the values' bend of the middle record widens the
    law itself (chi^2 / dof), so the bare range holds the truth as well off it (5-11 at 0.8 of the axis)."""
    from mtbmj.identify.bounce_ends import joint_ends
    from mtbmj.identify.bounce_rebound import at_spring_ends, law_in_clicks

    k_true = 7.4
    target = float(rate_of(1000.0 + 300.0 * k_true))
    assert law_in_clicks(world(F_TRUE, Q_TRUE), target)["answer"]["clicks_exact"] == pytest.approx(k_true, abs=0.06)
    w = math.sqrt((1.0 - RHO) / 2.0)
    for frac, bare_range, carried_range in ((0.0, [7, 8], [6, 9]), (0.5, [6, 10], [5, 10])):
        f, q = F_TRUE - frac * w * H_F, Q_TRUE + frac * w * H_Q
        main, best = given_world(f, q)
        pairs = joint_ends(best)
        nuisance = {name: [world(a, b) for a, b in pair] for name, pair in pairs.items()}
        nuisance["spring_scale"] = at_spring_ends(main)
        got = law_in_clicks(main, target, (), nuisance)
        ans, bare = got["answer"], law_in_clicks(main, target)["answer"]
        assert bare["clicks_range95"] == bare_range and ans["clicks_range95"] == carried_range
        assert ans["clicks_range95"][0] <= k_true <= ans["clicks_range95"][1]
        assert ans["clicks_range95_law"] == bare["clicks_range95"] and ans["range_open"] == []
        # the test's own range: the answer at each end from the world's records there
        own_ends = [[law_in_clicks(world(a, b), target)["answer"]["clicks_exact"] for a, b in pair]
                    for pair in pairs.values()]
        own_ends.append([law_in_clicks(world(f, q, s), target)["answer"]["clicks_exact"]
                         for s in (0.5 - H_S, 0.5 + H_S)])
        k = ans["clicks_exact"]
        lo_law, hi_law = ans["law_half_clicks"]
        below = math.sqrt(lo_law ** 2 + sum(max([0.0] + [k - v for v in e if v < k]) ** 2 for e in own_ends))
        above = math.sqrt(hi_law ** 2 + sum(max([0.0] + [v - k for v in e if v > k]) ** 2 for e in own_ends))
        assert ans["clicks_range95"] == [max(math.floor(k - below), 0), min(math.ceil(k + above), 17)]
        assert "with the friction and compression (jointly), spring given at their 95 % ends" in got["lines"][-1]

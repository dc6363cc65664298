"""The event detector's vectorised helpers give exactly (bitwise) what the sample-by-sample
definitions they replace give: the walks of ``_refine_all`` (one extreme and all together), the contact
search, the noise level, the parabola's two ways of summing, the peak finder's two ways of finding
each peak's reach on long noisy records, and ``detect``'s two ways of cutting a record (a slice of
time that never goes back, the boolean mask otherwise)."""
import math

import numpy as np
import pytest

from mtbmj.drop import events
from mtbmj.measured import peaks
from mtbmj.drop.events import MIN_AIRTIME_S, Event, detect


# -- the definitions (sample by sample) ----------------------------------------------------------
def parabola_reference(tt, yy):
    scale = float(max(abs(tt[0]), abs(tt[-1]))) or 1.0
    u = tt / scale
    u2 = u * u
    s0, s1, s2, s3, s4 = float(u.size), float(u.sum()), float(u2.sum()), float(u2 @ u), float(u2 @ u2)
    t0, t1, t2 = float(yy.sum()), float(u @ yy), float(u2 @ yy)
    det = s4 * (s2 * s0 - s1 * s1) - s3 * (s3 * s0 - s1 * s2) + s2 * (s3 * s1 - s2 * s2)
    a = (t2 * (s2 * s0 - s1 * s1) - s3 * (t1 * s0 - s1 * t0) + s2 * (t1 * s1 - s2 * t0)) / det
    b = (s4 * (t1 * s0 - s1 * t0) - t2 * (s3 * s0 - s1 * s2) + s2 * (s3 * t0 - t1 * s2)) / det
    c = (s4 * (s2 * t0 - t1 * s1) - s3 * (s3 * t0 - t1 * s2) + t2 * (s3 * s1 - s2 * s2)) / det
    return a / scale ** 2, b / scale, c


def refine_reference(t, y, i, raw=None, sigma=0.0):
    data = y if raw is None else raw
    height = max(0.2, 10.0 * sigma)
    lo = hi = i
    while lo > 0 and abs(y[lo - 1] - y[i]) <= height:
        lo -= 1
    while hi < y.size - 1 and abs(y[hi + 1] - y[i]) <= height:
        hi += 1
    lo, hi = max(0, min(lo, i - 2)), min(y.size - 1, max(hi, i + 2))
    if hi - lo >= 4:
        tt = t[lo:hi + 1] - t[i]
        a, b, c = parabola_reference(tt, data[lo:hi + 1])
        if a != 0:
            vertex = -b / (2 * a)
            if tt[0] <= vertex <= tt[-1]:
                return Event(float(t[i] + vertex), float(c - b * b / (4 * a)))
    return Event(float(t[i]), float(y[i]))


def contact_reference(t, tire_s, sigma, start):
    level = max(0.3, 5.0 * sigma)
    air = tire_s < -level
    air[:start] = False
    need = max(1, int(np.ceil(MIN_AIRTIME_S / (t[1] - t[0]))))
    i, n = start, t.size
    while i < n:
        run = np.flatnonzero(air[i:])
        if not run.size:
            return None, None, None, None
        a = i + int(run[0])
        back = np.flatnonzero(~air[a:])
        b = a + int(back[0]) if back.size else n
        if b - a >= need or b == n and b - a >= min(need, 2):
            k = a
            while k > start and tire_s[k - 1] < 0:
                k -= 1
            lift_t = events._crossing(t, tire_s, k - 1, k) if k > 0 else float(t[k])
            up = np.flatnonzero(tire_s[b:] >= 0) if b < n else np.array([], int)
            if not up.size:
                return k, lift_t, None, None
            m = b + int(up[0])
            return k, lift_t, m, events._crossing(t, tire_s, m - 1, m)
        i = b
    return None, None, None, None


def noise_reference(y):
    if y.size < 8:
        return 0.0
    d3 = np.diff(y, 3)
    return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0))


def prominent_reference(x, prominence):
    """scipy's definition, one scan each way per candidate peak."""
    change = np.flatnonzero(np.diff(x) != 0.0)
    if x.size < 3 or change.size < 2:
        return np.zeros(0, dtype=np.intp)
    rises = x[change + 1] > x[change]
    at = np.flatnonzero(rises[:-1] & ~rises[1:])
    found = (change[at] + 1 + change[at + 1]) // 2
    keep = []
    for i in found:
        above = np.flatnonzero(x[:i] > x[i])
        lo = above[-1] + 1 if above.size else 0
        above = np.flatnonzero(x[i + 1:] > x[i])
        hi = i + above[0] if above.size else x.size - 1
        if x[i] - max(x[lo:i + 1].min(), x[i:hi + 1].min()) >= prominence:
            keep.append(i)
    return np.array(keep, dtype=np.intp)


# -- records -------------------------------------------------------------------------------------
def record(seed, n=2000, noise=0.1, lsb=None, plateau=True):
    """A drop-like record: a damped bounce with a flight (tire below zero), a fork plateau at full
    extension, sensor noise and quantisation."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    w = 2 * np.pi * rng.uniform(1.5, 3.5)
    sled = 40 * np.exp(-rng.uniform(1, 4) * t) * np.cos(w * t) + 30
    fork = 30 * np.exp(-rng.uniform(1, 4) * t) * np.cos(w * t + rng.uniform(0, 0.5)) + 25
    if plateau:
        fork = np.maximum(fork, rng.uniform(-2, 10))
    sled = sled + rng.normal(0, noise, n)
    fork = fork + rng.normal(0, noise, n)
    if lsb:
        sled, fork = np.round(sled / lsb) * lsb, np.round(fork / lsb) * lsb
    return {"time_s": t, "sled_mm": sled, "fork_mm": fork, "tire_mm": sled - fork - rng.uniform(0, 12)}


def same(a, b):
    assert a == b and all(math.copysign(1.0, x) == math.copysign(1.0, y) for x, y in
                          zip((a.time_s, a.value_mm), (b.time_s, b.value_mm))), (a, b)


# -- tests ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(8))
def test_refine_walks_equal_the_sample_by_sample_walk(seed):
    """Every sample of noisy and of clean (long flat runs past NEAR samples) signals, the ends
    included; alone and all together. Odd seeds walk the raw signals on a binary grid of 0.25 mm,
    where samples lie exactly the walk's height (0.5 mm) away."""
    rec = record(seed, n=400, noise=(0.0, 0.02, 0.3)[seed % 3], lsb=0.25 if seed % 2 else None)
    t = rec["time_s"]
    raw = np.stack([rec[k] for k in ("sled_mm", "fork_mm", "tire_mm")])
    ys = raw if seed % 2 else np.stack([peaks.smooth(row, 1e-3, events.SMOOTH_S) for row in raw])
    sigma = [0.0, 0.05, 0.3]
    jobs = [(r, i) for r in range(3) for i in range(t.size)]
    together = events._refine_all(t, ys, raw, sigma, jobs)
    for (r, i), got in zip(jobs, together):
        expected = refine_reference(t, ys[r], i, raw[r], sigma[r])
        same(got, expected)
    for lo in range(-3, t.size, 37):  # windows, the record's ends included
        for hi in (lo + 1, lo + 2, lo + 60, t.size + 5):
            for kind in ("max", "min"):
                k = events._window_index(ys[0], lo, hi, kind)
                got = None if k is None else events._refine_all(t, ys, raw, sigma, [(0, k)])[0]
                a, b = max(lo, 0), min(hi, t.size - 1)
                seg = ys[0][a:b + 1]
                k = int(np.argmax(seg) if kind == "max" else np.argmin(seg)) if b - a >= 2 else None
                if k is None or (k == 0 and a > 0) or k == seg.size - 1:
                    assert got is None
                else:
                    same(got, refine_reference(t, ys[0], a + k, raw[0], sigma[0]))


@pytest.mark.parametrize("seed", range(8))
def test_contact_equals_the_sample_by_sample_search(seed):
    rec = record(seed, noise=0.05 * seed)
    t = rec["time_s"]
    tire = peaks.smooth(rec["tire_mm"], 1e-3, events.SMOOTH_S)
    for start in (0, 1, 30, 500):
        for sigma in (0.0, 0.1, 1.0):
            assert events._contact(t, tire.copy(), sigma, start) == contact_reference(t, tire.copy(), sigma, start)


@pytest.mark.parametrize("n", [8, 9, 10, 11, 57, 1000, 2001])
def test_noise_sigma_equals_the_two_medians(n):
    rng = np.random.default_rng(n)
    rows = np.cumsum(rng.normal(size=(4, n)), axis=1) + rng.normal(0, 0.1, (4, n))
    rows[1] = np.round(rows[1] * 5) / 5  # quantised: ties in the medians
    rows[3, n // 2] = np.nan
    together = peaks.noise_sigmas(rows[:3])
    for k, row in enumerate(rows):
        expected = noise_reference(row)
        got = peaks.noise_sigma(row)
        assert (math.isnan(expected) and math.isnan(got)) or got == expected
        if k < 3:
            assert together[k] == expected
    assert peaks.noise_sigmas(rows)[3] != peaks.noise_sigmas(rows)[3]  # NaN, as np.median says


@pytest.mark.parametrize("seed", range(20))
def test_parabola_equals_its_definition(seed):
    """Contiguous float vectors (summed row by row) and the rest (strided, float32) alike."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(5, 120))
    tt = np.sort(rng.uniform(-1, 1, m)) * rng.uniform(1e-4, 1)
    yy = rng.uniform(-200, 200) - rng.uniform(1, 1e3) * tt ** 2 + rng.normal(size=m) * 0.1
    for a, b in ((tt, yy), (tt, np.repeat(yy, 2)[::2]), (tt.astype(np.float32), yy), (tt[::-1], yy[::-1])):
        assert peaks.parabola(a, b) == parabola_reference(a, b)


@pytest.mark.parametrize("seed", range(12))
def test_find_peaks_walk_and_jumps_on_long_noisy_records(seed):
    """Long records with hundreds of candidate peaks (and plateaus): the stack walk, the pointer
    jumping and scipy's per-peak scans find the same peaks, and the valleys are -x's peaks."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(500, 4000))
    x = np.cumsum(rng.normal(size=n)) * 0.2 + rng.normal(size=n)
    if seed % 2:
        x = np.round(x * 2) / 2
    limit = peaks.DIRECT_SCAN_LIMIT
    try:
        for prominence in (0.0, 0.3, 1.0, 4.0):
            expected = prominent_reference(x, prominence)
            below = prominent_reference(-x, prominence)
            for peaks.DIRECT_SCAN_LIMIT in (limit, 0, n):
                assert np.array_equal(peaks.find_peaks(x, prominence), expected)
                found, valleys = peaks.peaks_and_valleys(x, prominence)
                assert np.array_equal(found, expected) and np.array_equal(valleys, below)
    finally:
        peaks.DIRECT_SCAN_LIMIT = limit


@pytest.mark.parametrize("seed", range(6))
def test_detect_cuts_a_record_the_same_by_slice_and_by_mask(seed):
    """Time that goes back before start_s sends detect down the boolean mask; what is left is
    the same record, so every event, flag and level comes out bitwise the same."""
    rec = record(seed, noise=(0.0, 0.1, 0.2)[seed % 3], lsb=275 / 65535 if seed % 2 else None)
    start = float(rec["time_s"][37])
    cut = {k: v[37:] for k, v in rec.items()}
    bent = {k: v.copy() for k, v in rec.items()}
    bent["time_s"][5] = bent["time_s"][7]  # goes back (before start_s)
    reference = detect(cut).to_dict()
    assert detect(rec, start_s=start).to_dict() == reference
    assert detect(bent, start_s=start).to_dict() == reference

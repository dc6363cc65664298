"""Ring-downs with a compliant seated rider, and predictions at other clicks
(``mtbmj.identify.bounce_decay``, ``mtbmj.identify.bounce_predict``).

The ring-downs here come from a model written in this file, with its own integrator (solve_ivp,
events): three masses on one vertical line, the bike's sprung share on the suspension (a spring,
viscous damping that the clicks set, Coulomb friction with a stick condition: at a velocity reversal
the bike stays stuck while the other forces on it do not exceed the friction), the rider's torso on
the saddle (5 Hz, damping ratio 0.35) and legs on the pedals (6 Hz, 0.40) (a seated body's vertical
resonance is 4-6 Hz: Griffin, Handbook of Human Vibration, 1990; ISO 2631-1; the damping ratios are
this test's assumption), and a stiff, damped top-out bumper (elastic: 200 x the suspension's
rate, 0.9 of critical on the bike's mass). The slam is a half-sine push of 260 N on the torso over
0.25 s. Noise of 0.15 mm, 5 kHz, rounding to 0.02 mm and clipping at 0 mm (the sensor reads no
travel past full extension). The package's law is one mass with a plastic stop: nothing here
replays it.

With a compliant rider the suspension's mode is not the rigid rider's: its damping ratio is the
low mode's (undamped mode shape phi with phi_bike = 1: zeta = phi' C phi / 2 sqrt(phi' K phi phi' M
phi)), computed here from the three-mass matrices; the friction band where the bike sticks is
F_c / k (at rest the rider's springs carry only the rider's weight, already in x_eq)."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from mtbmj.identify import bounce_decay as bd
from mtbmj.identify import bounce_predict as bp

from conftest import SHARED_DATA

RATE = 5000
NOISE = 0.15
M_BIKE, M_TORSO, M_LEGS = 12.0, 50.0, 15.0  # kg: the frame's share, torso on the saddle, legs on the pedals
F_TORSO, Z_TORSO = 5.0, 0.35
F_LEGS, Z_LEGS = 6.0, 0.40
M_ALL = M_BIKE + M_TORSO + M_LEGS
K = M_ALL * (2 * math.pi * 1.5) ** 2  # 1.5 Hz with the rider rigid
K_T = M_TORSO * (2 * math.pi * F_TORSO) ** 2
K_L = M_LEGS * (2 * math.pi * F_LEGS) ** 2
C_T = 2 * Z_TORSO * math.sqrt(K_T * M_TORSO)
C_L = 2 * Z_LEGS * math.sqrt(K_L * M_LEGS)
K_STOP = 200 * K
X_EQ = 0.020  # m
T_PUSH, PUSH_S, PUSH_N = 3.0, 0.25, 260.0
F_C = 0.5e-3 * K  # Coulomb friction: a 0.5 mm friction band
FIVE = [(0, 0.08), (4, 0.14), (8, 0.20), (12, 0.26), (17, 0.33)]  # clicks, the rigid rider's damping ratio


def c_of(zeta_rigid):
    return 2 * zeta_rigid * math.sqrt(K * M_ALL)


def matrices(c, k=K, k_t=K_T):
    M = np.diag([M_BIKE, M_TORSO, M_LEGS])
    Km = np.array([[k + k_t + K_L, -k_t, -K_L], [-k_t, k_t, 0.0], [-K_L, 0.0, K_L]])
    C = np.array([[c + C_T + C_L, -C_T, -C_L], [-C_T, C_T, 0.0], [-C_L, 0.0, C_L]])
    return M, Km, C


def modal_zeta(c):
    M, Km, C = matrices(c)
    w2, v = np.linalg.eig(np.linalg.solve(M, Km))
    i = int(np.argmin(w2.real))
    phi = v[:, i].real / v[0, i].real
    return float(phi @ C @ phi / (2 * math.sqrt((phi @ Km @ phi) * (phi @ M @ phi))))


def ring_down(c, fc=F_C, seconds=9.0, seed=0, c_comp=None, push=PUSH_N, k=K, k_t=K_T, noise=NOISE, raw=False,
              stall_limit=None):
    """Travel (mm, compression positive) at RATE of the three-mass model: seated at rest, the push,
    the free motion with stick-slip friction and the bumper. ``c_comp``: the suspension's damping while
    it compresses (None: ``c`` both ways; the clicks set rebound only); ``raw``: the exact travel, without
    noise, rounding or clipping; ``stall_limit``: raise RuntimeError after that many switches in a row
    that do not advance the time (a stick-slip switch can chatter for good in the bumper; None: never)."""
    from scipy.integrate import solve_ivp

    M, Km, C = matrices(c, k, k_t)
    C2 = C if c_comp is None else matrices(c_comp, k, k_t)[2]
    Minv = np.linalg.inv(M)
    c_stop = 2 * 0.9 * math.sqrt(K_STOP * M_BIKE)

    def forces(t, q):  # every force but the friction's (displacements down from static equilibrium)
        f = -Km @ q[:3] - (C2 if q[3] > 0 else C) @ q[3:]
        if T_PUSH <= t <= T_PUSH + PUSH_S:
            f[1] += push * math.sin(math.pi * (t - T_PUSH) / PUSH_S)
        pen = -(X_EQ + q[0])
        if pen > 0:
            f[0] += K_STOP * pen - (c_stop * q[3] if q[3] < 0 else 0.0)
        return f

    t = np.arange(int(seconds * RATE)) / RATE
    y, t0, mode = np.zeros(6), 0.0, 0  # mode 0: the bike stuck; +1 / -1: slipping that way
    ts, xs = [], []
    stalls = 0
    while t0 < seconds - 1e-9:
        if mode == 0:
            def rhs(tt, q):
                a = Minv @ forces(tt, q)
                a[0] = 0.0
                return np.concatenate(([0.0], q[4:], a))

            def event(tt, q):
                return abs(forces(tt, q)[0]) - fc
            event.direction = 1
        else:
            def rhs(tt, q, s=mode):
                f = forces(tt, q)
                f[0] -= fc * s
                return np.concatenate((q[3:], Minv @ f))

            def event(tt, q):
                return q[3]
            event.direction = -mode
        event.terminal = True
        sol = solve_ivp(rhs, (t0, seconds), y, events=(event,), max_step=2e-3, rtol=1e-9, atol=1e-12,
                        dense_output=True)
        grid = t[(t >= t0) & (t < sol.t[-1])]
        if grid.size:
            ts.extend(grid)
            xs.extend(sol.sol(grid)[0])
        stalls = stalls + 1 if sol.t[-1] <= t0 else 0
        if stall_limit is not None and stalls > stall_limit:
            raise RuntimeError(f"the stick-slip switch chatters at {t0:.4f} s")
        t0, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        f0 = forces(t0, y)[0]
        if mode == 0:
            mode = 1 if f0 > 0 else -1
        else:
            y[3] = 0.0
            mode = 0 if abs(f0) <= fc else (1 if f0 > 0 else -1)
    exact = 1e3 * (X_EQ + np.interp(t, ts, xs))
    if raw:
        return t, exact
    travel = exact + np.random.default_rng(seed).normal(0, noise, t.size)
    return t, np.round(np.clip(travel, 0, None) / 0.02) * 0.02


@pytest.fixture(scope="module")
def five():
    recs, xs, seqs = [], [], []
    for k, z in FIVE:
        t, x = ring_down(c_of(z), seed=k + 1)
        recs.append(SimpleNamespace(time_s=t, name=f"{k} clicks"))
        xs.append(x)
        seqs.append(bd.extrema(t, x, "shock", int(np.argmax(x))))
    return recs, xs, seqs


def test_the_generator_sticks_within_the_band_and_rings_at_its_low_mode():
    t, x = ring_down(c_of(0.14), seed=3)
    assert abs(np.median(x[t > 8.0]) - 1e3 * X_EQ) <= 1e3 * F_C / K + 3 * NOISE / math.sqrt(5000)
    M, Km, _ = matrices(0.0)
    f_low = math.sqrt(float(np.min(np.linalg.eigvals(np.linalg.solve(M, Km)).real))) / (2 * math.pi)
    assert 1.40 < f_low < 1.47  # the compliant rider lowers the rigid rider's 1.5 Hz
    assert x[(t > 3.3) & (t < 3.8)].min() == 0.0  # the bumper is reached (the sensor reads 0 there)


def test_compliant_rider_five_clicks_friction_and_damping_within_5_percent(five):
    """Measured: friction band 0.502 mm (F_c / k = 0.5); zeta 0.0769, 0.1337, 0.1843, 0.2376, 0.3129
    against the modal 0.0789, 0.1329, 0.1869, 0.2410, 0.3040 (within 3 %); the rigid rider's
    0.08 ... 0.33 would be missed by up to 8.6 %: the rider's compliance is what the fit reads."""
    _, _, seqs = five
    ks = [k for k, _ in FIVE]
    fits = {m: bd.fit_common(seqs, ks, m, law=False) for m in bd.MODELS}
    assert bd.choose(fits) == "both"
    f = fits["both"]
    assert f.value("friction_band_mm")[0] == pytest.approx(1e3 * F_C / K, rel=0.05)
    misses_rigid = []
    for i, (_, z) in enumerate(FIVE):
        assert f.value(f"zeta[{i}]")[0] == pytest.approx(modal_zeta(c_of(z)), rel=0.05)
        misses_rigid.append(abs(f.value(f"zeta[{i}]")[0] / z - 1))
    assert max(misses_rigid) > 0.05  # the rigid rider's zeta is not what a compliant rider's slam shows


def test_top_out_is_excluded_with_a_compliant_rider(five):
    _, _, seqs = five
    assert any("top-out stop" in e for e in seqs[0].excluded)
    assert seqs[0].levels_mm.min() > 1.0


_HELD = {}  # the held-out predictions, each fitted once (the body's fit takes seconds)


def _held(five, i):
    if (id(five), i) in _HELD:
        return _HELD[(id(five), i)]
    recs, xs, seqs = five
    ks = [k for k, _ in FIVE]
    keep = [j for j in range(5) if j != i]
    law = bp.decay_law("shock", [seqs[j] for j in keep], [ks[j] for j in keep], [recs[j] for j in keep],
                       [xs[j] for j in keep])
    p = law.predict(ks[i], recs[i], seqs[i], law.x_eq_of(seqs[i], ks[i]), ks[i], xs[i], 80.0)
    rec = np.interp(p.time_s, recs[i].time_s, xs[i])
    w = (p.time_s > p.slam_s) & (p.time_s < p.slam_s + 3.0)
    _HELD[(id(five), i)] = p, float(np.sqrt(np.mean((rec[w] - p.travel_mm[w]) ** 2))), bp.held_out(seqs, ks, recs, xs, i)
    return _HELD[(id(five), i)]


def _plastic(five, i):
    """The trace RMS of the law's plastic stop (no seated body): the baseline the body's trace must beat."""
    recs, xs, seqs = five
    ks = [k for k, _ in FIVE]
    keep = [j for j in range(5) if j != i]
    law = bp.decay_law("shock", [seqs[j] for j in keep], [ks[j] for j in keep], [recs[j] for j in keep],
                       [xs[j] for j in keep])
    law.body = bp.Body(math.nan, math.nan, 0, math.nan)  # no record to fit the body on: the plastic stop
    p = law.predict(ks[i], recs[i], seqs[i], law.x_eq_of(seqs[i], ks[i]), ks[i], xs[i], 80.0)
    rec = np.interp(p.time_s, recs[i].time_s, xs[i])
    w = (p.time_s > p.slam_s) & (p.time_s < p.slam_s + 3.0)
    assert p.body is None
    return float(np.sqrt(np.mean((rec[w] - p.travel_mm[w]) ** 2)))


# measured (held out in turn, fitted on the other four): trace RMS 0.313, 0.322, 0.19, 0.36, 0.27 mm (the
# first two through the top-out stop with the seated body, its share and damping ratio fitted on 4 and 8
# clicks (0.95 at its bound, 0.342), then on 0 clicks (0.95, 0.370); with the literature's 0.475 held and the
# share alone fitted 0.565 and 0.361; with the law's plastic stop 1.65 and 1.05 mm, its first rebound's top 3.6 and 1.7 mm
# short and its timing 10 and 17 ms early: scaled x1.23 / x1.14 about x_eq after the stop alone the plastic
# trace would miss by 0.90 / 0.81 mm, shifted alone by 1.61 / 0.68, both 0.81 / 0.35);
# first half cycle's decay misses by 0.08, 0.07, 0.22, 0.53, 0.47 sd with the measured decay's scatter
# (0.008, pooled over 0 and 4 clicks, 5 dof; 0.09, 0.17, 0.25, 0.63, 0.53 with its read error alone); frequency by 0.13, 0.89, 0.83,
# 0.00, 1.00 sd (0.08, 1.02, 2.08, 0.48, 1.44 with the vertex timing's sd alone)
TRACE_RMS = 2.5 * NOISE


@pytest.mark.parametrize("i", [2, 3, 4])
def test_held_out_trace_within_the_noise_where_the_stop_is_not_reached(five, i):
    p, rms, _ = _held(five, i)
    assert p.inside_stroke()
    assert p.body is None  # the closed form: no stop reached
    assert rms <= TRACE_RMS


@pytest.mark.parametrize("i", range(5))
def test_a_trace_that_reaches_the_stop_says_it_leaves_the_envelope(five, i):
    """The law reaches the top-out stop after the slam at 0 and 4 clicks (the generator's records reach
    0.0 mm there, 0.4 mm at 8 clicks), not at 8, 12 and 17; where it does, the summary says so, and that
    the trace there is the seated body's."""
    p, _, _ = _held(five, i)
    reached = p.stop_reached_s() is not None
    assert reached == (i <= 1)
    note = p.summary().get("note", "")
    assert ("outside the law's envelope" in note) == reached
    assert ("held on its stop by the seated rider's body" in note) == reached


@pytest.mark.parametrize("i", [0, 1])
def test_the_seated_body_beats_the_plastic_stop_by_half(five, i):
    """Measured: 0.313 / 0.322 mm RMS with the body against 1.65 / 1.05 with the plastic stop (whose
    misses the 2.5 x noise check fails)."""
    p, rms, _ = _held(five, i)
    plastic = _plastic(five, i)
    assert p.inside_stroke() and p.body is not None
    assert plastic > TRACE_RMS
    assert rms <= 0.5 * plastic


def test_held_out_trace_within_the_noise_through_the_stop_at_4_clicks(five):
    """4 clicks held out: 0.322 mm RMS through the stop (the body's share and damping fitted on 0 clicks'
    record: 0.95, 0.370)."""
    p, rms, _ = _held(five, 1)
    assert p.inside_stroke() and p.body is not None and p.body.records == 1
    assert rms <= TRACE_RMS


def test_held_out_trace_within_the_noise_where_the_stop_is_reached(five):
    """0 clicks held out reaches the top-out bumper after the slam: 0.313 mm RMS with the seated body's share
    and damping ratio fitted on 4 and 8 clicks (0.95 at its bound, 0.342; 0.31 mm RMS there). The generator's
    rider is 0.84 of the moving mass on two springs damped 0.35 and 0.40: the fitted damping is below the
    literature's 0.475, as the generator's is."""
    p, rms, _ = _held(five, 0)
    assert p.inside_stroke() and p.body is not None and p.body.records == 2
    assert p.body.zeta < 0.475
    assert rms <= TRACE_RMS


def test_the_literatures_body_damping_held_misses_where_the_stop_is_reached(five, monkeypatch):
    """The baseline the fitted damping must beat: the body's damping held at Fairley and Griffin's 0.475 (its
    share alone fitted, as before) misses 0 clicks held out by 0.565 mm RMS, past the 2.5 x noise check."""
    from mtbmj.identify import bounce_body as bb

    monkeypatch.setattr(bb, "BODY_ZETA_BOUNDS", (bb.BODY_ZETA - 1e-6, bb.BODY_ZETA + 1e-6))
    recs, xs, seqs = five
    ks = [k for k, _ in FIVE]
    law = bp.decay_law("shock", seqs[1:], ks[1:], recs[1:], xs[1:])
    p = law.predict(ks[0], recs[0], seqs[0], law.x_eq_of(seqs[0], ks[0]), ks[0], xs[0], 80.0)
    rec = np.interp(p.time_s, recs[0].time_s, xs[0])
    w = (p.time_s > p.slam_s) & (p.time_s < p.slam_s + 3.0)
    assert p.body is not None and p.body.zeta == pytest.approx(0.475, abs=1e-5)
    assert float(np.sqrt(np.mean((rec[w] - p.travel_mm[w]) ** 2))) > TRACE_RMS


def _body_of(z_torso, z_legs, monkeypatch):
    """The seated body (share, RMS, records, damping ratio) fitted on this file's generator at 0, 4 and 8
    clicks with its torso and legs damped ``z_torso`` and ``z_legs``."""
    monkeypatch.setitem(globals(), "C_T", 2 * z_torso * math.sqrt(K_T * M_TORSO))
    monkeypatch.setitem(globals(), "C_L", 2 * z_legs * math.sqrt(K_L * M_LEGS))
    recs, xs, seqs, ks = [], [], [], []
    for k, z in FIVE[:3]:
        t, x = ring_down(c_of(z), seed=k + 1)
        recs.append(SimpleNamespace(time_s=t, name=f"{k} clicks"))
        xs.append(x)
        seqs.append(bd.extrema(t, x, "shock", int(np.argmax(x))))
        ks.append(k)
    return bp.decay_law("shock", seqs, ks, recs, xs).body_share()


@pytest.mark.slow
def test_the_bodys_fitted_damping_tells_two_generators_apart(monkeypatch):
    """Measured: the generator's body damped 0.35 (torso) and 0.40 (legs) reads 0.350, damped 0.55 and 0.55
    reads 0.481 (the share at its bound 0.95 both times); a body held at the literature's 0.475 would read
    the same for both. (Damped 0.20 it reads 0.276, at the search's lower bound 0.275.)"""
    base = _body_of(Z_TORSO, Z_LEGS, monkeypatch)
    stiff = _body_of(0.55, 0.55, monkeypatch)
    assert base is not None and stiff is not None
    assert stiff[3] - base[3] > 0.05
    assert abs(base[3] - Z_TORSO) < 0.1 and abs(stiff[3] - 0.55) < 0.1


def test_the_two_masses_ring_at_the_laws_frequency_and_damping():
    """The two masses made from the law (fn 1.44 Hz, zeta 0.13, share 0.8): the low mode's undamped
    frequency and its modal damping ratio, from the matrices' eigenvectors written here, are the law's;
    the body rings alone at 5 Hz, 0.475 (bounce_bike's and the replay's seated body)."""
    from mtbmj.identify import bounce_bike, bounce_body as bb, bounce_replay

    assert bb.BODY_ZETA == bounce_bike.RIDER_ZETA and bb.BODY_HZ == bounce_replay.RIDER_HZ
    m = bb.TwoMass.of_law(0.8, 1.44, 0.13, 0.5)
    M = np.diag([0.2, 0.8])
    Km = np.array([[m.k + m.kr, -m.kr], [-m.kr, m.kr]])
    C = np.array([[m.c + m.cr, -m.cr], [-m.cr, m.cr]])
    w2, v = np.linalg.eig(np.linalg.solve(M, Km))
    j = int(np.argmin(w2.real))
    phi = v[:, j].real / v[0, j].real
    assert math.sqrt(w2[j].real) / (2 * math.pi) == pytest.approx(1.44, rel=1e-9)
    assert phi @ C @ phi / (2 * math.sqrt((phi @ Km @ phi) * (phi @ M @ phi))) == pytest.approx(0.13, rel=1e-9)
    assert math.sqrt(m.kr / 0.8) / (2 * math.pi) == pytest.approx(5.0) and m.cr / (2 * math.sqrt(m.kr * 0.8)) == 0.475
    wrong = bb.TwoMass.of_law(0.8, 1.60, 0.13, 0.5)  # another law's masses do not ring at 1.44 Hz
    assert abs(math.sqrt(np.min(np.linalg.eigvals(np.linalg.solve(M, np.array(
        [[wrong.k + wrong.kr, -wrong.kr], [-wrong.kr, wrong.kr]]))).real)) / (2 * math.pi) - 1.44) > 0.1


def test_the_body_trace_stays_in_the_stroke_and_holds_on_the_stop():
    """From rest at full travel (30 mm; x_eq 12 mm) the two masses reach full extension: the trace stays
    within 0-30 mm, rests on the stop for a while (held by the body: 44 ms measured, more than 20 asked) and
    comes to rest within the friction band of x_eq."""
    from mtbmj.identify import bounce_body as bb

    m = bb.TwoMass.of_law(0.85, 1.45, 0.05, 0.5)
    t, x = bb.trace(m, 30.0, 12.0, 30.0, 3.0, 2e-4)
    assert x.min() >= 0.0 and x.max() <= 30.0
    on = t[x <= 1e-6]
    assert on.size and on[-1] - on[0] > 0.02  # held on the stop, not bounced off it
    assert abs(x[-1] - 12.0) <= 0.5 + 1e-6  # at rest within the friction band of x_eq


@pytest.mark.parametrize("i", range(5))
def test_held_out_first_half_cycle_decay_within_2_sd(five, i):
    ho = bp.held_out(five[2], [k for k, _ in FIVE], five[0], five[1], i)
    assert ho["decay_misses_by_sd"] <= 2.0


@pytest.mark.parametrize("i", range(5))
def test_held_out_frequency_within_2_sd(five, i):
    """Measured, each record's frequency with the half periods' pooled scatter (0.34 % per half, 8 dof):
    0.13, 0.89, 0.83, 0.00, 1.00 sd. With the vertex timing's sd alone 8 clicks missed by 2.08 sd
    (1.423 Hz predicted, 1.417 measured: a strict xfail then)."""
    ho = bp.held_out(five[2], [k for k, _ in FIVE], five[0], five[1], i)
    assert ho["frequency_misses_by_sd"] <= 2.0


# --- a record's frequency: the half periods' own scatter (coverage) ----------------------------------

DIRECTED = [(0, 0.08), (8, 0.20), (17, 0.33)]  # clicks and the rebound's rigid-rider damping ratio
COVERAGE_DRAWS = 6


def turning_points(x) -> list:
    """The noise-free travel's turning points after the slam's peak (its velocity's sign changes), the
    peak first: sample indices, written here."""
    p = int(np.argmax(x))
    sgn = np.sign(np.diff(x[p:]))
    nz = np.flatnonzero(sgn != 0)
    tp, last = [p], sgn[nz[0]]
    for j in nz:
        if sgn[j] != last:
            tp.append(p + int(j))
            last = sgn[j]
    return tp


def free_halves(x, min_swing_mm: float) -> list:
    """The free half cycles between the turning points: (start, end) sample pairs with both ends 1 mm or
    more into the stroke (none into or out of the bumper) and a swing of at least ``min_swing_mm``, from
    the first such half cycle to the first that is not (the stick)."""
    tp = turning_points(x)
    out = []
    for a, b in zip(tp[:-1], tp[1:]):
        if min(x[a], x[b]) < 1.0 or abs(x[b] - x[a]) < min_swing_mm:
            if out:
                break
            continue
        out.append((a, b))
    return out


def true_frequency(t, x):
    """The exact record's frequency, written here: the noise-free travel's turning points after the slam's
    peak (its velocity's sign changes), the free half cycles (both ends more than 1 mm into the stroke,
    a swing of at least 1 mm: none into or out of the bumper, up to where it sticks), and
    1 / (2 H) with log H the mean of the rebound halves' and the compression halves' mean log period."""
    halves = [(x[b] < x[a], t[b] - t[a]) for a, b in free_halves(x, 1.0)]
    reb = [math.log(h) for r, h in halves if r]
    com = [math.log(h) for r, h in halves if not r]
    return 0.5 * math.exp(-(np.mean(reb) + np.mean(com)) / 2)


def directed_draw(seed):
    """One set's push (N), torso stiffness, friction (N) and compression damping ratio."""
    rng = np.random.default_rng(100 + seed)
    push, f_t = rng.uniform(200, 320), rng.uniform(4.0, 6.0)
    fc, z_c = K * 1e-3 * rng.uniform(0.3, 0.8), rng.uniform(0.08, 0.16)
    return push, M_TORSO * (2 * math.pi * f_t) ** 2, fc, z_c


def directed_set(seed, stiff_at=None, stiff=1.0):
    """Three records (DIRECTED) of one rider and shock: the clicks set the rebound's damping only, the
    compression's is the shock's own; push, torso resonance, friction and compression damping drawn
    per set; ``stiff_at``: that record's spring ``stiff`` times stiffer (a wrong law's record)."""
    push, k_t, fc, z_c = directed_draw(seed)
    recs, xs, seqs, truth = [], [], [], []
    for i, (k, z) in enumerate(DIRECTED):
        kk = K * (stiff if i == stiff_at else 1.0)
        kw = dict(c_comp=c_of(z_c), push=push, k_t=k_t, fc=fc, k=kk)
        t, x = ring_down(c_of(z), seed=31 * seed + k + 1, **kw)
        recs.append(SimpleNamespace(time_s=t, name=f"{k} clicks"))
        xs.append(x)
        seqs.append(bd.extrema(t, x, "shock", int(np.argmax(x))))
        truth.append(true_frequency(*ring_down(c_of(z), raw=True, **kw)))
    return recs, xs, seqs, truth


@pytest.fixture(scope="module")
def coverage():
    """Each record's (truth, honest timing, the pool's t95, the vertex-only timing) over the draws."""
    rows = []
    for seed in range(COVERAGE_DRAWS):
        recs, xs, seqs, truth = directed_set(seed)
        tms, sc = bp.record_timings(seqs, recs, xs)
        for i in range(len(DIRECTED)):
            rows.append((truth[i], tms[i], sc.t95, bp.timing(seqs[i], recs[i].time_s, xs[i])))
    return rows


@pytest.mark.slow
def test_a_records_frequency_interval_holds_the_truth_at_its_nominal_rate(coverage):
    """Measured over 6 draws x 3 records: the half periods scatter 1.2-2.1 % about their record's mean
    (rebound halves 0.5-0.9 % longer); the honest 95 % interval (Student's t at the pool's 4-9 dof)
    holds the exact frequency 16 times in 18 (z from -0.08 to 2.69; the two misses, 2.69 and 2.31 sd,
    at 17 clicks, and nearly every z positive: the last halves before the stick, which the records
    time less often, lengthen); the vertex-only sd (0.7-21 mHz) holds it 2 times in 18 (z up to 18.8)."""
    honest = [abs(tm.frequency_hz - f) <= t95 * tm.sd for f, tm, t95, _ in coverage]
    vertex = [abs(old.frequency_hz - f) <= 1.96 * old.sd for f, _, _, old in coverage]
    assert np.mean(honest) >= 0.85
    assert np.mean(vertex) <= 0.4  # the error model replaced: it missed the truth most of the time


@pytest.mark.slow
def test_a_stiffer_held_out_record_is_still_told_apart():
    """The 17-click record's spring 1.3 x stiffer (its frequency ~14 % up), the law fitted on 0 and 8
    clicks: 1.404 +- 0.012 Hz predicted, 1.601 +- 0.011 measured, 12.6 sd; the same record on the common
    spring 1.421 +- 0.011, 1.04 sd."""
    recs, xs, seqs, _ = directed_set(0, stiff_at=2, stiff=1.3)
    wrong = bp.held_out(seqs, [k for k, _ in DIRECTED], recs, xs, 2)
    assert wrong["frequency_misses_by_sd"] > 2.0
    recs, xs, seqs, _ = directed_set(0)
    right = bp.held_out(seqs, [k for k, _ in DIRECTED], recs, xs, 2)
    assert right["frequency_misses_by_sd"] <= 2.0


# --- a record's measured first half cycle's decay: the decays' own scatter (coverage) ----------------

DECAY_PUSHES = (0.75, 1.0, 1.25)  # the pushes whose noise-free ring-downs define a click setting's smooth law


def free_swings(t, x):
    """The noise-free travel's free swings after the slam's peak, written here: its turning points
    (the velocity's sign changes), the swings between them with both ends 1 mm or more into the stroke
    (none into or out of the bumper) and at least 0.2 mm, from the first such swing to the first that
    is not (the stick)."""
    return [abs(x[b] - x[a]) for a, b in free_halves(x, 0.2)]


def setting_laws(z, kw):
    """The click setting's smooth law, fitted here: s_{n+1} / s_n = r - D / s_n (viscous + Coulomb in
    swings) by least squares over the noise-free ring-downs of the set's rider and shock at DECAY_PUSHES
    x its push, as (r, D); beside it the same swings' law with the friction left out (D = 0: r alone, the
    mean decay) as (r, 0). None when fewer than four decays (a run whose stick-slip chatters is left out)."""
    ys, ss = [], []
    for f in DECAY_PUSHES:
        try:
            t, x = ring_down(c_of(z), raw=True, stall_limit=200, **dict(kw, push=kw["push"] * f))
        except RuntimeError:
            continue
        sw = free_swings(t, x)
        ys += [b / a for a, b in zip(sw[:-1], sw[1:])]
        ss += sw[:-1]
    if len(ys) < 4:
        return None
    ss = np.array(ss)
    (r, D), *_ = np.linalg.lstsq(np.column_stack((np.ones_like(ss), -1.0 / ss)), np.array(ys), rcond=None)
    return (float(r), float(D)), (float(np.mean(ys)), 0.0)


@pytest.fixture(scope="module")
def decay_coverage():
    """Per record over the draws: the measured first decay, its sd, the pool's t95, the read-only sd, and
    at its first swing the truth (its setting's law), the law without friction and the neighbouring
    setting's law (the clicks doing nothing between them: a click law with the wrong slope)."""
    rows = []
    for seed in range(COVERAGE_DRAWS):
        push, k_t, fc, z_c = directed_draw(seed)
        seqs = []
        for k, z in DIRECTED:
            t, x = ring_down(c_of(z), seed=31 * seed + k + 1, c_comp=c_of(z_c), push=push, k_t=k_t, fc=fc)
            seqs.append(bd.extrema(t, x, "shock", int(np.argmax(x))))
        sc = bp.decay_scatter(seqs)
        laws = [setting_laws(z, dict(c_comp=c_of(z_c), push=push, k_t=k_t, fc=fc)) for _, z in DIRECTED]
        for i, s in enumerate(seqs):
            nb = laws[1] if i != 1 else laws[2]
            if laws[i] is None or nb is None:
                continue
            s0 = float(s.swings[0])
            at = [r - D / s0 for r, D in (laws[i][0], laws[i][1], nb[0])]
            val, sd = bp.measured_decay(s, sc)
            rows.append(dict(clicks=DIRECTED[i][0], value=val, sd=sd, t95=sc.t95, read_sd=bp.read_sd(s), truth=at[0],
                             no_friction=at[1], neighbour=at[2]))
    return rows


@pytest.mark.slow
def test_a_records_measured_decay_interval_holds_the_settings_law_at_its_nominal_rate(decay_coverage):
    """Measured over 6 draws x 3 records (DIRECTED: the clicks on the rebound only), the truth each
    record's setting's law fitted here on its noise-free ring-downs at three pushes: the decays scatter
    about their record's law by 0.016-0.050 (pooled over the records with 3 decays or more, 2-7 dof; the
    direction shift never told apart: -0.022 to +0.013); the measured first decay's 95 % interval
    (Student's t) holds its setting's law 17 times in 18 (z from -0.97 to 4.96), the read error alone
    (0.0013-0.0022) 2 times in 18 (z up to 75). The 17-click records' first decays (compression first)
    sit above their setting's law every time (z 1.55-4.96, the one miss among them): their rebound is
    damped 2-4 x their compression, which a law common to both directions and a pooled shift do not
    carry."""
    rows = decay_coverage
    assert len(rows) >= 15
    honest = [abs(r["value"] - r["truth"]) <= r["t95"] * r["sd"] for r in rows]
    read = [abs(r["value"] - r["truth"]) <= 1.96 * r["read_sd"] for r in rows]
    assert np.mean(honest) >= 0.85
    assert np.mean(read) <= 0.5  # the read error alone (the error model replaced) misses the law most of the time


@pytest.mark.slow
def test_a_click_law_with_the_wrong_slope_is_still_told_apart_from_a_records_measured_decay(decay_coverage):
    """The neighbouring setting's law (8 clicks' at 0 and 17 clicks, 17 clicks' at 8: the clicks doing
    nothing between them, a click law with the wrong slope) lies more than 2 sd from the measured first
    decay at all 12 records at 0 and 8 clicks (2.33-8.01 sd). At 17 clicks it does in 1 of 6 (left out
    here, and said: the direction bias above puts the measurement nearer 8 clicks' law than its own)."""
    rows = [r for r in decay_coverage if r["clicks"] != 17]
    assert len(rows) >= 10
    assert np.mean([abs(r["value"] - r["neighbour"]) > 2.0 * r["sd"] for r in rows]) >= 0.8


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the law with the friction left out (D = 0, fitted on the same noise-free "
                                         "swings) lies more than 2 sd from the measured first decay in 8 of 18 "
                                         "records only (0.61-5.75 sd): one first half cycle's decay, with the "
                                         "decays' own scatter, is no test of the friction; the friction band is "
                                         "read from the whole ring-down")
def test_a_law_without_friction_is_told_apart_from_a_records_measured_decay(decay_coverage):
    assert np.mean([abs(r["value"] - r["no_friction"]) > 2.0 * r["sd"] for r in decay_coverage]) >= 0.8


def made_sequence(levels):
    """An Extrema of given levels (mm), peak first when the second is lower."""
    lv = np.asarray(levels, float)
    return bd.Extrema("shock", 0.0, lv, np.arange(lv.size, dtype=float), bool(lv[1] < lv[0]), False,
                      floor_mm=0.01, noise_mm=0.1)


def test_decay_scatter_recovers_a_made_scatter_and_shift():
    """Swings written here: 60 records of 5 swings, s_{n+1} = (r - D / s_n + shift x dir_n + N(0, 0.03)) s_n
    with r and D per record: the pooled sd comes back, the shift is kept where it is 0.08 and left out
    where it is 0; a record with fewer than 3 decays is not pooled, and with no pool the measured decay
    carries its read error alone."""
    rng = np.random.default_rng(7)

    def records(shift):
        out = []
        for _ in range(60):
            r, D = rng.uniform(0.5, 0.8), rng.uniform(0.3, 1.0)
            sw, lv = [rng.uniform(25, 35)], [40.0]
            for n in range(4):
                dirn = 1.0 if n % 2 == 0 else -1.0  # peak first: swing 0 is a rebound
                sw.append(sw[-1] * (r - D / sw[-1] + shift * dirn + rng.normal(0, 0.03)))
            for n, w in enumerate(sw):
                lv.append(lv[-1] - w if n % 2 == 0 else lv[-1] + w)
            out.append(made_sequence(lv))
        return out

    sc = bp.decay_scatter(records(0.08))
    assert sc.sd == pytest.approx(0.03, rel=0.15)
    assert sc.shift == pytest.approx(0.08, abs=3 * sc.shift_sd) and sc.shift_sd > 0
    seq = records(0.08)[0]
    val, sd = bp.measured_decay(seq, sc)
    assert val == pytest.approx(seq.first_decay() - sc.shift)  # a rebound-first decay, shifted back
    assert sd == pytest.approx(math.sqrt(sc.sd ** 2 + sc.shift_sd ** 2 + bp.read_sd(seq) ** 2))
    none = bp.decay_scatter(records(0.0))
    assert none.shift == 0.0 and none.shift_sd == 0.0 and abs(none.shift_tried) < 3 * none.shift_tried_sd
    short = made_sequence([40.0, 10.0, 30.0, 15.0])  # 2 decays: not pooled
    assert bp.decay_scatter([short]) is None
    assert bp.measured_decay(short, None) == (short.first_decay(), bp.read_sd(short))


def test_half_scatter_recovers_a_made_scatter_and_shift():
    """Half periods written here: 40 records of 4 halves, log h = a_i + 0.05 s + N(0, 0.03): the pooled
    sd and the shift come back; a single compression half's frequency is corrected by the shift."""
    rng = np.random.default_rng(5)
    recs = []
    for _ in range(40):
        a = math.log(0.3) + rng.normal(0, 0.05)
        recs.append([("rebound" if j % 2 == 0 else "compression", 0.0, 0.0,
                      math.exp(a + (0.05 if j % 2 == 0 else -0.05) + rng.normal(0, 0.03)), 1e-4) for j in range(4)])
    sc = bp.half_scatter(recs)
    assert sc.rel_sd == pytest.approx(0.03, rel=0.15)
    assert sc.shift == pytest.approx(0.05, abs=3 * sc.shift_sd)
    tm = bp.honest_timing([("compression", 0.0, 0.0, 0.3 * math.exp(-0.05), 1e-4)], sc)
    assert tm.frequency_hz == pytest.approx(0.5 / 0.3, rel=0.01)
    assert tm.sd / tm.frequency_hz == pytest.approx(math.hypot(sc.rel_sd, sc.shift_sd), rel=0.05)
    assert bp.half_scatter([recs[0][:1]]) is None  # no record with two halves: no pool


# --- the law's motion against an integrator of its own ---------------------------------------------

def one_mass(x0, x_eq, d, zeta, fn, stroke, seconds, e=0.0):
    """solve_ivp of x'' = -2 zeta wn x' - wn^2 (x - x_eq) - wn^2 d sign(x'), stops at 0 and ``stroke``
    returning ``e`` of the speed, stuck at a rest within d of x_eq."""
    from scipy.integrate import solve_ivp

    wn = 2 * math.pi * fn
    dt = 1.0 / RATE
    t = np.arange(int(seconds * RATE) + 1) * dt
    y, t0, ts, xs = np.array([x0, 0.0]), 0.0, [], []
    while t0 < seconds:
        if y[1] == 0.0 and abs(y[0] - x_eq) <= d:
            break
        s = math.copysign(1.0, y[1]) if y[1] else (1.0 if x_eq > y[0] else -1.0)

        def rhs(_, q, s=s):
            return [q[1], -2 * zeta * wn * q[1] - wn ** 2 * (q[0] - x_eq) - wn ** 2 * d * s]

        def rev(_, q):
            return q[1]
        rev.terminal, rev.direction = True, -s

        def low(_, q):
            return q[0]
        low.terminal, low.direction = True, -1

        def high(_, q):
            return q[0] - stroke
        high.terminal, high.direction = True, 1
        sol = solve_ivp(rhs, (t0, seconds), y, events=(rev, low, high), rtol=1e-11, atol=1e-11, dense_output=True)
        grid = t[(t >= t0) & (t < sol.t[-1])]
        ts.extend(grid)
        xs.extend(sol.sol(grid)[0])
        t0, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        y[1] = 0.0 if sol.t_events[0].size else -e * y[1]
    x = np.interp(t, ts, xs, right=xs[-1])
    return t, x


@pytest.mark.parametrize("zeta,d,e", [(0.1, 0.7, 0.0), (0.25, 0.0, 0.0), (0.05, 0.3, 0.5), (0.0, 2.0, 0.0)])
def test_free_motion_matches_an_integrator_and_stays_in_the_stroke(zeta, d, e):
    t, x = one_mass(60.0, 18.0, d, zeta, 1.6, 65.0, 4.0, e)
    tt, xx = bp.free_motion(60.0, 18.0, d, zeta, 1.6, 65.0, 4.0, 1.0 / RATE, restitution=e)
    assert tt.size == t.size
    assert np.max(np.abs(xx - x)) < 0.02
    assert xx.min() >= 0.0 and xx.max() <= 65.0


# --- the shared seat slams ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def shared():
    from mtbmj.measured.telemetry import read_sst

    recs = [read_sst(f"{SHARED_DATA}/sst_v2/{n}.SST") for n in ("00083", "00085", "00087")]
    return recs, [r.shock_mm for r in recs], [bd.extrema(r.time_s, r.shock_mm, "shock", bd.slam_index(r)) for r in recs]


SLAMS = ("00083.SST", "00085.SST", "00087.SST")


@pytest.mark.shared_data("sst_v2", *SLAMS)
def test_shared_17_clicks_comes_to_rest_after_two_free_half_cycles(shared):
    """00087's shock stops dead at 17.3 mm for 0.22 s (smoothed travel within 0.005 mm), then steps
    to 18.7 mm: at rest, whatever follows (its hold used to be refused as not flat, because its
    spread took in the step)."""
    s = shared[2][2]
    assert s.stuck and s.levels_mm.size == 3
    assert s.levels_mm[-1] == pytest.approx(17.32, abs=0.05)
    assert s.first_decay() == pytest.approx(0.454, abs=0.005)


@pytest.mark.shared_data("sst_v2", *SLAMS)
@pytest.mark.parametrize("i,what", [(1, "decay"), (2, "decay"), (0, "frequency"), (1, "frequency"),
                                    (2, "frequency")])
def test_shared_held_out_within_2_sd(shared, i, what):
    """Measured: decay held out at 0 / 8 / 17 clicks misses by 5.26 / 1.19 / 1.22 sd (10.19 / 1.27 / 1.25
    with the measured decay's read error alone); frequency by 1.95 / 0.51 / 1.05 sd (fitted on the other
    two; combined sd of prediction and measurement; each record's frequency with the half periods'
    scatter pooled over the three records: 5.7 % per half, rebound halves 4.4 +- 2.5 % longer, 3 dof;
    each record's first decay with the decays' scatter about their record's law, 0.027, pooled over 0 and
    8 clicks, 2 dof). With the vertex timing's sd alone (the error model before, which held the
    generator's truth 3 times in 18) the 17-click miss was 7.03 sd."""
    recs, xs, seqs = shared
    ho = bp.held_out(seqs, [0, 8, 17], recs, xs, i)
    assert ho[f"{what}_misses_by_sd"] <= 2.0


@pytest.mark.shared_data("sst_v2", *SLAMS)
@pytest.mark.xfail(strict=True, reason="0 clicks held out (an extrapolation from 8 and 17): first decay 0.411 "
                                         "+- 0.016 predicted, 0.578 +- 0.027 measured (the decays' own scatter about "
                                         "their record's law, pooled over 0 and 8 clicks, 2 dof; 95 % interval "
                                         "0.461-0.695 with t = 4.30): 5.26 sd combined, outside the t interval too "
                                         "(10.2 sd with the read error alone): fitted on 8 and 17 the law's zeta "
                                         "falls with the clicks (0.255 - 0.0024 / click, the 17-click slam decays "
                                         "per half cycle no faster than the 8-click one: 0.454 and 0.431); a law "
                                         "with the clicks on the rebound halves only has 6 parameters for the 6 "
                                         "relations of 8 and 17 clicks (4 for the 4 decays): no degree of freedom")
@pytest.mark.parametrize("i,what", [(0, "decay")])
def test_shared_held_out_misses(shared, i, what):
    recs, xs, seqs = shared
    ho = bp.held_out(seqs, [0, 8, 17], recs, xs, i)
    assert ho[f"{what}_misses_by_sd"] <= 2.0


@pytest.mark.shared_data("sst_v2", *SLAMS)
def test_shared_predicted_traces_stay_in_the_stroke(shared):
    recs, xs, seqs = shared
    law = bp.decay_law("shock", seqs, [0, 8, 17], recs, xs)
    per = bd.fit_common(seqs, [0, 8, 17], "both", law=False)
    for k in (0, 2, 4, 8, 12, 17):
        for i, r in enumerate(recs):
            p = law.predict(k, r, seqs[i], per.value(f"x_eq_mm[{i}]")[0], [0, 8, 17][i], xs[i], r.shock_max_mm)
            assert p.inside_stroke() and p.travel_mm.min() >= 0.0 and p.travel_mm.max() <= r.shock_max_mm
            assert p.frequency_hz.low < p.frequency_hz.value < p.frequency_hz.high
            assert p.rebound_speed_mm_per_s.low <= p.rebound_speed_mm_per_s.value <= p.rebound_speed_mm_per_s.high
            # the record itself up to the slam's peak: the compression stroke the rider made
            head = p.time_s <= p.slam_s
            assert np.array_equal(p.travel_mm[head], np.clip(xs[i][: head.sum()], 0, r.shock_max_mm))


# --- the answer in clicks (mtbmj.identify.bounce_clicks) ---------------------------------------------

from mtbmj.identify import bounce_clicks as bc  # noqa: E402


def true_window(hit):
    """The generator's own window of clicks meeting one overshoot: its modal zeta at each click (its
    damper linear in clicks) and its friction band F_c / k."""
    return bc.window(lambda k: modal_zeta(c_of(0.08 + 0.015 * k)), 1e3 * F_C / K, hit, 0.0, 17.0)


def count_overshoots(zeta, d, hit):
    """Overshoots counted on this file's one-mass integrator: extrema beyond the band after the hit."""
    t, x = one_mass(20.0 + hit, 20.0, d, zeta, 1.5, 200.0, 8.0)
    v = np.diff(x)
    turns = np.flatnonzero(np.sign(v[1:]) * np.sign(v[:-1]) < 0) + 1
    return int(sum(1 for i in turns if abs(x[i] - 20.0) > d + 1e-6))


@pytest.mark.parametrize("zeta,d,hit", [(0.1, 0.5, 10.0), (0.3, 0.5, 10.0), (0.2, 0.3, 4.0), (0.05, 1.0, 12.0)])
def test_overshoots_counted_as_an_integrator_counts_them(zeta, d, hit):
    assert bc.overshoots(zeta, d, hit) == count_overshoots(zeta, d, hit)


@pytest.fixture(scope="module")
def law5(five):
    recs, xs, seqs = five
    return bp.decay_law("shock", seqs, [k for k, _ in FIVE], recs, xs)


@pytest.mark.parametrize("hit", [3.0, 5.0, 8.0])
def test_answer_meets_the_generators_own_window(law5, hit):
    """Measured: windows 0-14.6, 6.2-17, 12.9-17 clicks against the generator's 0-14.85, 6.25-17,
    13.0-17; set 7, 12, 15 clicks; 95 % ranges 6-9, 10-13, 14-16."""
    lo, hi, where = true_window(hit)
    ans = bc.answer(law5, hit)
    assert ans.clicks is not None and where == "inside"
    assert abs(ans.window[0] - lo) <= 0.5 and abs(ans.window[1] - hi) <= 0.5
    assert lo <= ans.clicks <= hi
    assert ans.range95[0] <= 0.5 * (lo + hi) <= ans.range95[1]
    assert f"set {ans.clicks} clicks" in ans.line()


def test_answer_refused_beyond_the_records(law5):
    assert true_window(20.0)[2] == "above"  # the generator too needs more than 17 clicks for a 20 mm hit
    ans = bc.answer(law5, 20.0)
    assert ans.clicks is None and "more than 17 clicks" in ans.note and "record a slam" in ans.note


def test_fit_bounce_answers_in_clicks_on_the_cli_and_in_the_figure(five, tmp_path, capsys):
    import json
    import struct

    from helpers import SHOCK, counts_of
    from mtbmj import cli
    from mtbmj.identify.bounce_fit import figure, fit_bounce

    recs, xs, _ = five
    paths = []
    four = FIVE[:4]  # 17 clicks: the linear ring-down fit finds one turning point there and refuses the run
    for (k, _), x in zip(four, xs):
        shock = np.clip(np.rint(counts_of(x, *SHOCK)), 0, None).astype("<u2")
        fork = np.full_like(shock, 300)
        p = tmp_path / f"{k}.SST"
        p.write_bytes(struct.pack("<3sBH", b"SST", 2, RATE) + np.column_stack((fork, shock)).astype("<u2").tobytes())
        paths.append(str(p))
    out = tmp_path / "out"
    clicks = ",".join(str(k) for k, _ in four)
    assert cli.main(["fit", "bounce", *paths, "--clicks", clicks, "--predict-clicks", "6",
                     "--hit-mm", "5", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    fit = json.loads((out / "fit.json").read_text())
    ans = fit["answer"]["shock"]
    lo, hi, _ = true_window(5.0)
    assert lo <= ans["set_clicks"] <= hi and ans["hit_mm"] == 5.0 and "whafi.com" in ans["source"]
    assert f"shock answer (one overshoot after a 5.0 mm hit): set {ans['set_clicks']} clicks" in printed
    pred = fit["predicted"][0]["shock"]["decay"]
    assert pred["inside_stroke"] and pred["first_half_cycle_decay_ci95"][0] < pred["first_half_cycle_decay"]
    assert len(fit["decay_law"]["shock"]["held_out"]) == 4
    table = np.genfromtxt(out / "ringdown_6_clicks.csv", delimiter=",", names=True)
    assert table["shock_mm"].min() >= 0.0
    # the figure: the answer's panel says it and shades the window of clicks that meet the target
    result = fit_bounce(paths, [float(k) for k, _ in four], [6.0], hit_mm=5.0)
    fig = figure(result)
    panel = next(ax for ax in fig.axes if f"set {ans['set_clicks']} clicks" in ax.get_title())
    spans = [p.get_x() for p in panel.patches]
    assert any(abs(x - ans["window_clicks"][0]) < 1e-9 for x in spans)
    assert any(abs(ln.get_xdata()[0] - ans["set_clicks"]) < 1e-9 for ln in panel.lines)
    trace_panel = next(ax for ax in fig.axes if ax.get_title().startswith("predicted ring-downs"))
    assert any("at 6 clicks" in t.get_text() for t in trace_panel.get_legend().get_texts())


def test_a_click_to_predict_given_twice_is_refused_in_one_line(tmp_path, capsys):
    """--predict-clicks 4,4: refused before the records are read (it gave two entries in fit.json
    and one ringdown_4_clicks.csv written over the other); 4,6 reaches the records (a missing file)."""
    from mtbmj import cli

    for predict, says in (("4,4", "--predict-clicks 4,4: 4 clicks given twice"), ("4,6", "a.SST")):
        rc = cli.main(["fit", "bounce", str(tmp_path / "a.SST"), str(tmp_path / "b.SST"), "--clicks", "0,8",
                       "--predict-clicks", predict, "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and says in err[0], err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("bad", ["0", "-3", "nan"])
def test_a_bad_hit_is_refused_in_one_line(tmp_path, capsys, bad):
    from mtbmj import cli

    rc = cli.main(["fit", "bounce", str(tmp_path / "a.SST"), "--clicks", "0", "--hit-mm", bad, "--out",
                   str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--hit-mm" in err[0]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("hit,says", [("80", "not less than the shock's whole stroke as the records are read (65 mm)"),
                                       ("150", "in shock mm (not the rear wheel's travel)"), ("60", None)])
def test_a_hit_past_the_whole_stroke_is_refused_in_one_line(five, tmp_path, capsys, hit, says):
    """--hit-mm in the rear wheel's travel (150 mm) or past the shock's 65 mm stroke: no law answers for
    a hit the shock cannot take; one line naming the stroke, nothing written (it was answered, "one
    overshoot after a 500.0 mm hit"). A hit within the stroke is answered."""
    import struct

    from helpers import SHOCK, counts_of
    from mtbmj import cli

    _, xs, _ = five
    paths = []
    for (k, _), x in zip(FIVE[:2], xs):
        shock = np.clip(np.rint(counts_of(x, *SHOCK)), 0, None).astype("<u2")
        p = tmp_path / f"{k}.SST"
        p.write_bytes(struct.pack("<3sBH", b"SST", 2, RATE) + np.column_stack((np.full_like(shock, 300), shock))
                      .astype("<u2").tobytes())
        paths.append(str(p))
    out = tmp_path / "out"
    rc = cli.main(["fit", "bounce", *paths, "--clicks", "0,4", "--hit-mm", hit, "--out", str(out)])
    captured = capsys.readouterr()
    if says is None:
        assert rc == 0 and f"after a {float(hit):.1f} mm hit" in captured.out
        return
    err = captured.err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith(f"mtbmj: error: --hit-mm {hit}:") and says in err[0], err
    assert not out.exists()


def test_the_fork_gets_its_law_prediction_and_answer_where_it_rings(five, tmp_path):
    """Item 5: the fork's clicks where it rings at two or more settings (the shared forks do not):
    both ends made by the three-mass model, the fork's damper 0.8 x the shock's, friction alike."""
    import json
    import struct

    from helpers import FORK, SHOCK, counts_of
    from mtbmj import cli

    _, xs, _ = five
    four = FIVE[:4]
    paths = []
    for j, ((k, z), x) in enumerate(zip(four, xs)):
        _, xf = ring_down(c_of(0.8 * z), seed=100 + k)
        shock = np.clip(np.rint(counts_of(x, *SHOCK)), 0, None).astype("<u2")
        fork = np.clip(np.rint(counts_of(xf, *FORK)), 0, None).astype("<u2")
        p = tmp_path / f"{k}.SST"
        p.write_bytes(struct.pack("<3sBH", b"SST", 2, RATE) + np.column_stack((fork, shock)).astype("<u2").tobytes())
        paths.append(str(p))
    out = tmp_path / "out"
    assert cli.main(["fit", "bounce", *paths, "--clicks", "0,4,8,12", "--predict-clicks", "6", "--hit-mm", "5",
                     "--out", str(out)]) == 0
    fit = json.loads((out / "fit.json").read_text())
    assert fit["decay_law"]["fork"]["friction_band_mm"] == pytest.approx(1e3 * F_C / K, rel=0.05)
    assert fit["predicted"][0]["fork"]["decay"]["inside_stroke"]
    ans = fit["answer"]["fork"]
    lo, hi, _ = bc.window(lambda k: modal_zeta(c_of(0.8 * (0.08 + 0.015 * k))), 1e3 * F_C / K, 5.0, 0.0, 12.0)
    assert ans["set_clicks"] is not None and lo <= ans["set_clicks"] <= hi
    table = np.genfromtxt(out / "ringdown_6_clicks.csv", delimiter=",", names=True)
    assert table.dtype.names == ("time_s", "shock_mm", "fork_mm")  # one grid: the source record's (the ends'
    assert np.allclose(np.diff(table["time_s"]), 1 / RATE) and table["time_s"][0] == 0.0  # slam peaks differ)
    assert table["fork_mm"].min() >= 0.0 and table["shock_mm"].min() >= 0.0

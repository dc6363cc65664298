"""The ring-down's turning points and residuals the spring, friction and dampers are read from
(``mtbmj.identify.bounce_ring``; the fit through the MuJoCo bike is checked on the independent slams of
``tests/test_bounce_replay.py``).

(a) Ring-downs made here by a model of this file's own: one mass on a spring with a linear damper and
Coulomb friction (a stick condition), released from a slam's height above rest, stepped by
semi-implicit Euler at 20 us and sampled at 5 kHz. Viscous damping alone keeps a constant share of the
swing each half cycle (exp(-pi zeta / sqrt(1 - zeta^2)), Den Hartog); friction alone takes a constant
4 F / k off it (Feeny and Liang, J. Sound Vib. 195(1), 1996). ``turning_points`` gives those back, so
the swing ratios ``residuals`` compares carry the difference between the two.
(b) ``residuals`` on turning points written here: zero on the record itself, log(1.05) / sd for half
periods 5 % longer, as many entries when the simulation sticks a half cycle sooner (a missing half against
its nearest, a missing pair's ratio from its swing decrement law, 0 with no pair at all), and a sum of
squares that moves smoothly there.
(c) The fit with the bike replaced by a closed form (below). (d) The model chosen (viscous only, friction
only, both) on (a)'s ring-downs, the simulation (c)'s closed form at (a)'s mass.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mtbmj.identify.bounce_ring import PERIOD_SD, RATIO_SD, residuals, turning_points

FS = 5000.0
M_KG, K_N_PER_M = 100.0, 9000.0  # 1.51 Hz


def ring_down(c=0.0, fc=0.0, drop_mm=40.0, rest_mm=60.0, quiet=1.0, after=3.0, dt=2e-5, noise=0.02, seed=5):
    """(time_s, x_mm, peak index): at rest, a quick rise (0.1 s, sin^2) to ``drop_mm`` above rest, then free
    from rest there: m x'' = -k x - c x' - friction (friction up to ``fc`` holding it when still)."""
    n_quiet = int(round(quiet * FS))
    t_rise = np.arange(int(round(0.1 * FS))) / FS
    rise = drop_mm * np.sin(0.5 * np.pi * t_rise / 0.1) ** 2
    x, v = drop_mm * 1e-3, 0.0
    out = []
    every = int(round(1 / (FS * dt)))
    for i in range(int(round(after / dt))):
        if i % every == 0:
            out.append(x)
        f = -K_N_PER_M * x - c * v
        if abs(v) < 1e-5 and abs(f) <= fc:
            v = 0.0
            continue
        f -= fc * math.copysign(1.0, v if abs(v) >= 1e-5 else f)
        v += f / M_KG * dt
        x += v * dt
    xs = np.concatenate((np.zeros(n_quiet), rise, 1e3 * np.array(out))) + rest_mm
    xs += noise * np.random.default_rng(seed).standard_normal(xs.size)
    return np.arange(xs.size) / FS, xs, n_quiet + rise.size


def _swings(tp):
    lv = [q[1] for q in tp]
    return np.abs(np.diff(lv))


def test_viscous_ring_down_keeps_a_share_of_each_swing():
    """(a) Viscous only (zeta 0.12): the half cycles' swing ratios within 0.01 of the closed form's
    exp(-pi zeta / sqrt(1 - zeta^2)), and the half periods within 1 % of pi / wd."""
    zeta = 0.12
    c = 2 * zeta * math.sqrt(K_N_PER_M * M_KG)
    t, x, peak = ring_down(c=c)
    tp = turning_points(t, x, peak)
    assert [q[0] for q in tp][:4] == [0, 1, 2, 3]
    sw = _swings(tp)
    ratios = sw[1:5] / sw[:4]
    share = math.exp(-math.pi * zeta / math.sqrt(1 - zeta ** 2))
    assert np.all(np.abs(ratios - share) < 0.01)
    wd = math.sqrt(K_N_PER_M / M_KG) * math.sqrt(1 - zeta ** 2)
    halves = np.diff([q[2] for q in tp[1:5]])
    assert np.all(np.abs(halves / (math.pi / wd) - 1.0) < 0.01)


def test_friction_ring_down_loses_a_constant_swing():
    """(a) Friction only (40 N): each half cycle's swing 4 F / k (17.8 mm) less than the one before, within
    0.3 mm (to where it sticks), so its swing ratios fall half by half where the viscous one's stay: the
    last more than 0.1 below the first, which no one constant ratio (a viscous reading) gives."""
    fc = 40.0
    t, x, peak = ring_down(fc=fc)
    tp = turning_points(t, x, peak)
    sw = _swings(tp)
    loss = 4 * fc / K_N_PER_M * 1e3
    assert sw.size >= 4 and np.all(np.abs(-np.diff(sw) - loss) < 0.3)
    ratios = sw[1:] / sw[:-1]
    assert np.all(np.diff(ratios) < 0.0) and ratios[-1] < ratios[0] - 0.1


def test_residuals_zero_on_the_record_and_its_period_shift():
    """(b) The record against itself: every residual 0; against itself with every time 5 % later from the
    peak: the periods log(1.05) / PERIOD_SD, the swing ratios 0."""
    rec = [(0, 50.0, 0.0), (1, 5.0, 0.33), (2, 30.0, 0.66), (3, 10.0, 0.99), (4, 20.0, 1.32)]
    r, n = residuals(rec, rec)
    assert n == {"periods": 3, "ratios": 3, "missing": 0} and np.all(r == 0.0)
    slow = [(k, lv, 1.05 * ti) for k, lv, ti in rec]
    r, n = residuals(rec, slow)
    assert r[:3] == pytest.approx([math.log(1.05) / PERIOD_SD] * 3)
    assert r[3:] == pytest.approx([0.0] * 3, abs=1e-12)


def test_residuals_keep_their_number_when_the_simulation_sticks_sooner():
    """(b) A simulation that stops at turning point 3 (stuck) against a record with two more: as many
    residuals as the record gives, a missing half period against the simulation's nearest half (its own
    2-3: 0 here, log(1.05) / PERIOD_SD where that half is 5 % longer), the swing ratios it lacks read as 0
    swing (no pair at all: the record's ratio over RATIO_SD below 0), and the missing counted."""
    rec = [(0, 50.0, 0.0), (2, 30.0, 0.66), (3, 10.0, 0.99), (4, 20.0, 1.32), (5, 14.0, float("nan"))]
    sim = [(0, 50.0, 0.0), (2, 30.0, 0.66), (3, 10.0, 0.99)]
    r_full, n_full = residuals(rec, rec)
    r, n = residuals(rec, sim)
    assert r.size == r_full.size and n["missing"] == 3
    assert r[n["periods"] - 1] == pytest.approx(0.0, abs=1e-9)
    assert r[-1] == pytest.approx(-(6.0 / 10.0) / RATIO_SD)
    longer = [(0, 50.0, 0.0), (2, 30.0, 0.66), (3, 10.0, 0.66 + 1.05 * 0.33)]
    r, _ = residuals(rec, longer)
    assert r[n["periods"] - 1] == pytest.approx(math.log(1.05) / PERIOD_SD)


def test_swing_ratio_beyond_the_simulations_pairs_follows_its_decrement_law():
    """(b) Beyond the simulation's own pairs the ratio follows its swing decrement law s2 = alpha s1 - beta
    (written here: alpha 0.9, beta 6 mm, a viscous share and a friction's constant loss), down to 0 where
    the law leaves no swing; inside them it interpolates; with no pair, 0. The old hold at the nearest
    pair's ratio (0.7 at 20 mm) would read 0.9 - 6 / 8 = 0.15 at 8 mm as 0.7."""
    from mtbmj.identify.bounce_ring import swing_ratio_at

    pairs = [(s1, 0.9 - 6.0 / s1, 1 if j % 2 else -1, j) for j, s1 in enumerate((40.0, 30.0, 20.0))]
    assert swing_ratio_at(pairs, 8.0, 1) == pytest.approx(0.9 - 6.0 / 8.0, abs=1e-9)
    assert swing_ratio_at(pairs, 60.0, -1) == pytest.approx(0.9 - 6.0 / 60.0, abs=1e-9)
    assert swing_ratio_at(pairs, 5.0, 1) == 0.0
    assert swing_ratio_at(pairs, 30.0, 1) == pytest.approx(0.9 - 6.0 / 30.0)
    assert swing_ratio_at([], 30.0, 1) == 0.0


def test_residual_moves_smoothly_where_the_simulation_sticks_a_half_sooner():
    """(b) The closed form below (c) at 0.55 x and the damper's scale 0.05 against its own record at 150 N:
    between 150 and 155 N the simulation sticks a half cycle sooner (measured: a missing half), and the
    residual's sum of squares there moves by less than 10 (measured 0 to 2.2; with the missing pair's ratio
    held at the previous pair's and the missing half 0, as before, 0 to 349)."""
    rec = closed_points(0.55, 150.0, 0.05)
    cost = {}
    for f in (150.0, 155.0):
        r, n = residuals(rec, closed_points(0.55, f, 0.05))
        cost[f] = (float(r @ r), n["missing"])
    assert cost[150.0][1] == 0 and cost[155.0][1] >= 1
    assert abs(cost[155.0][0] - cost[150.0][0]) < 10.0


# (c) the fit itself (``bounce_ring.fit``) with the bike replaced by a closed form written here: one mass on a
# spring (80 N/mm x the spring scale, 529 kg: 1.45 Hz at 0.55 x), a damper (1000 N s/m x the damper scale) and Coulomb friction F,
# its turning points half a damped period apart, each about the centre the friction shifts to, sign(a) F / k:
# a' - e = -r (a - e), r = exp(-pi zeta / sqrt(1 - zeta^2)), stuck where |a'| <= F / k (Den Hartog).
K0, C0, M0 = 80000.0, 1000.0, 529.0


def closed_points(scale, friction, damper, start_mm=40.0, rest=20.0, time_noise=0.0, level_noise=0.0, seed=0,
                  k0=K0, c0=C0, m0=M0):
    k, m = k0 * scale, m0
    c = c0 * damper
    zeta = c / (2.0 * math.sqrt(k * m))
    wd = math.sqrt(k / m) * math.sqrt(1.0 - zeta ** 2)
    r = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta ** 2))
    band = 1e3 * friction / k
    rng = np.random.default_rng(seed)
    a, out = start_mm, [(0, rest + start_mm, 0.0)]
    for j in range(1, 12):
        if abs(a) <= band:  # the spring cannot overcome the friction: it stays (no further turning point)
            break
        e = math.copysign(band, a)
        a = e - r * (a - e)
        stuck = abs(a) <= band
        t = float("nan") if stuck else j * math.pi / wd + time_noise * rng.standard_normal()
        out.append((j, rest + a + level_noise * rng.standard_normal(), t))
        if stuck:
            break
    return out


@pytest.fixture()
def closed_form_bike(monkeypatch):
    """``bounce_ring``'s record and simulation replaced by the closed form: each ring's "record" its turning
    points given, the simulation's those of the closed form at the values tried."""
    from mtbmj.identify import bounce_ring

    monkeypatch.setattr(bounce_ring, "_record_points", lambda ring: ring[3])
    monkeypatch.setattr(bounce_ring, "_run", lambda ring, v: closed_points(v["spring_scale"], v["friction_N"],
                                                                            v.get("damper_scale", 1.0)))
    return bounce_ring


def test_fit_recovers_spring_friction_and_damper(closed_form_bike):
    """(c) A record of the closed form at 0.55 x, 30 N and the damper's scale 1 (vertex times within 0.5 ms,
    levels within 0.05 mm): the fit from 0.5 x, 30 N, 1 gives the spring within 2 %, the friction within 5 N,
    the damper's scale within 10 %, each interval holding it, not refused."""
    rec = closed_points(0.55, 30.0, 1.0, time_noise=5e-4, level_noise=0.05, seed=1)
    got = closed_form_bike.fit([("made", None, None, rec)], fitted=("spring_scale", "friction_N", "damper_scale"))
    assert "refused" not in got
    assert got["spring_scale"] == pytest.approx(0.55, rel=0.02)
    assert got["friction_N"] == pytest.approx(30.0, abs=5.0)
    assert got["damper_scale"] == pytest.approx(1.0, rel=0.10)
    for k, truth in (("spring_scale", 0.55), ("friction_N", 30.0), ("damper_scale", 1.0)):
        lo, hi = got[k + "_ci95"]
        assert lo <= truth <= hi


def test_fit_reads_a_viscous_ring_down_without_friction(closed_form_bike):
    """(c) Wrong input told apart: viscous only (0 N, the damper's scale 1) reads a friction under 3 N, its interval
    from below 1 N (measured 1 [0, 1]), the spring and the damper within 2 %; a dry ring-down (150 N, the
    damper's scale 0.05) read with the friction held at 0 (the viscous reading) cannot be followed: refused."""
    visc = closed_points(0.55, 0.0, 1.0, time_noise=5e-4, level_noise=0.05, seed=2)
    got = closed_form_bike.fit([("made", None, None, visc)], fitted=("spring_scale", "friction_N", "damper_scale"))
    assert "refused" not in got
    assert got["friction_N"] < 3.0 and got["friction_N_ci95"][0] < 1.0
    assert got["spring_scale"] == pytest.approx(0.55, rel=0.02) and got["damper_scale"] == pytest.approx(1.0, rel=0.02)
    dry = closed_points(0.55, 150.0, 0.05, time_noise=5e-4, level_noise=0.05, seed=3)
    held = closed_form_bike.fit([("made", None, None, dry)], fitted=("spring_scale", "damper_scale"),
                                held={"friction_N": 0.0})
    assert "refused" in held and "does not follow" in held["refused"]


def test_fit_reads_a_dry_ring_down_without_damping(closed_form_bike):
    """(c) A dry ring-down (150 N, the damper's scale 0.05: 50 N s/m; 4 half periods and 5 swing ratios
    before it sticks) read with the three values free: the friction within 10 N and the damper's scale
    under 0.3 (measured 150 N [147, 153], 0.06 [0.03, 0.10], spring 0.55 x, 0.12 sd RMS; before the
    residual moved smoothly where the simulation sticks sooner, refused at 3.1 sd, 0.58 x, 61 N), and the
    criterion does not take it for viscous (measured: both, AICc -19.9; friction only -12.6, viscous
    44.2: at this noise 50 N s/m is seen)."""
    dry = closed_points(0.55, 150.0, 0.05, time_noise=5e-4, level_noise=0.05, seed=3)
    got = closed_form_bike.fit([("made", None, None, dry)], fitted=("spring_scale", "friction_N", "damper_scale"))
    assert "refused" not in got
    assert got["friction_N"] == pytest.approx(150.0, abs=10.0) and got["damper_scale"] < 0.3
    assert got["model"] != "viscous"


# (d) the model chosen (``bounce_ring.fit``'s "model", by AICc) on ring-downs of (a)'s integrator, the
# simulation the closed form of (c) with (a)'s mass and spring (K_N_PER_M at the scale 0.55) and a damper of
# C_REF x the damper's scale: 60 mm above rest, 6 s, so each has 7 or more free turning points.
C_REF, S_TRUE = 200.0, 0.55


@pytest.fixture()
def generator_bike(monkeypatch):
    """``bounce_ring``'s record the turning points of an (a) ring-down given as the ring's fourth item, the
    simulation (d)'s closed form started 60 mm (the ring's fifth item) above rest."""
    from mtbmj.identify import bounce_ring

    monkeypatch.setattr(bounce_ring, "_record_points", lambda ring: ring[3])
    monkeypatch.setattr(bounce_ring, "_run", lambda ring, v: closed_points(
        v["spring_scale"], v["friction_N"], v.get("damper_scale", 1.0), start_mm=ring[4],
        k0=K_N_PER_M / S_TRUE, c0=C_REF, m0=M_KG))
    return bounce_ring


def _generated_fit(bounce_ring, c, fc, drop_mm=60.0, after=6.0):
    t, x, peak = ring_down(c=c, fc=fc, drop_mm=drop_mm, after=after)
    rec = turning_points(t, x, peak)
    return bounce_ring.fit([("made", None, None, rec, drop_mm)], fitted=("spring_scale", "friction_N", "damper_scale"))


@pytest.mark.parametrize("c, fc, model", [(189.7, 0.0, "viscous"), (0.0, 40.0, "friction"), (95.0, 20.0, "both")],
                         ids=["viscous", "friction", "both"])
def test_model_chosen_and_values_recovered_on_made_ring_downs(generator_bike, c, fc, model):
    """(d) Viscous only (189.7 N s/m, zeta 0.1), friction only (40 N) and both (95 N s/m and 20 N): the
    criterion chooses that model (measured AICc viscous / friction / both: -152 / 95 / -150; 47 / 2 / 8;
    35 / 24 / -12), and the chosen model's friction and damper within 5 % (measured 0 N and 0.949 x 200 for
    0.949; 39.3 N; 19.8 N and 0.474 x for 0.475), its spring within 2 % (0.540-0.550 for 0.55). The
    models that leave out what the record has are the wrong inputs: each misses (its RMS over 1.5 sd,
    measured 1.9-5.4, where the right one's is under 0.8, measured 0.05-0.7)."""
    got = _generated_fit(generator_bike, c, fc)
    assert "refused" not in got
    assert got["model"] == model
    ch = got["models"][model]
    assert ch["spring_scale"] == pytest.approx(S_TRUE, rel=0.02)
    assert ch["friction_N"] == (pytest.approx(fc, rel=0.05) if fc else 0.0)
    assert ch["damper_scale"] == (pytest.approx(c / C_REF, rel=0.05) if c else 0.0)
    assert ch["rms_scaled"] < 0.8
    wrong = ([got["models"]["viscous"]] if fc else []) + ([got["models"]["friction"]] if c else [])
    assert wrong and all(e["rms_scaled"] > 1.5 for e in wrong)
    assert f"model by AICc: {generator_bike.MODEL_WORDS[model]}" in got["line"]


@pytest.mark.xfail(strict=True, reason="a short ring-down (both: 95 N s/m and 20 N, 40 mm above rest, 4 s: 5 turning "
                                       "points, 3 half periods and 3 swing ratios) is read as viscous only: AICc "
                                       "viscous 19.2, friction 21.2, both 29.6 (both's RMS 0.22 sd against viscous's "
                                       "1.1, but 6 residuals for 3 values and the variance carry AICc's small-sample "
                                       "penalty of 40)")
def test_model_chosen_on_a_short_mixed_ring_down(generator_bike):
    got = _generated_fit(generator_bike, 95.0, 20.0, drop_mm=40.0, after=4.0)
    assert got["model"] == "both"


def test_a_model_with_too_few_residuals_has_no_criterion_and_fit_json_writes(generator_bike):
    """(d) Friction only (40 N) from 40 mm for 4 s: 5 turning points, 5 residuals, too few for both's AICc
    (n - k - 1 = 0): its "aicc" is null, the line says so, the choice is among the others (friction), and
    fit.json's strict writer takes the result (an inf would be refused)."""
    from mtbmj.identify.bounce_fit import json_bytes

    got = _generated_fit(generator_bike, 0.0, 40.0, drop_mm=40.0, after=4.0)
    assert got["models"]["both"]["aicc"] is None and got["model"] == "friction"
    assert "both none (too few residuals)" in got["line"]
    assert b'"aicc": null' in json_bytes(got)


def test_a_value_the_residual_does_not_move_with_is_not_determined(monkeypatch):
    """(c) With a simulation that ignores the friction (the closed form at friction 0 whatever is tried),
    the friction's Jacobian column is 0: its interval is its whole range (0-400 N) and it is named
    undetermined, not given a 0-wide interval (as the shared slams' friction-only model had: [15, 15]); the
    spring's interval is still its own (holding 0.55 x)."""
    from mtbmj.identify import bounce_ring

    monkeypatch.setattr(bounce_ring, "_record_points", lambda ring: ring[3])
    monkeypatch.setattr(bounce_ring, "_run", lambda ring, v: closed_points(v["spring_scale"], 0.0, 1.0))
    rec = closed_points(0.55, 0.0, 1.0, time_noise=5e-4, level_noise=0.05, seed=2)
    got = bounce_ring.fit([("made", None, None, rec)], fitted=("spring_scale", "friction_N"))
    assert got["undetermined"] == ["friction_N"] and got["friction_N_ci95"] == [0.0, 400.0]
    assert "not determined" in got["line"]
    lo, hi = got["spring_scale_ci95"]
    assert lo <= 0.55 <= hi and hi - lo < 0.05

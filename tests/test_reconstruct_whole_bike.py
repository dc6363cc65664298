"""A ride reconstructed (mtbmj/ride/reconstruct.py, issue 51 item 5) against a ride made here by a whole
bike integrated in this file (scipy's solve_ivp, its own equations, not the package's engines or laws'
code): a frame that heaves and pitches, a rider on legs and arms (vertical springs and dampers at the
pedals and the bars) who heaves and pitches on it and shifts a slow load fore and aft (a force pair
at the bars and pedals, 80 N, 7 s period), the fork's lower and wheel sliding along the steering axis,
the rear wheel on a constant leverage ratio, point-contact tyres that leave the ground, at a speed
that varies along the ride (6.5 +- 1 m/s over 25 s), over terrain made here: ISO 8608 class C
roughness (sum of sines, 0.05-8 cycles/m), a rock garden, a G-out, drops of 0.3 and 0.5 m and a
tabletop jump of 0.4 m, written as SST version 3 integer counts through the bike file's [sensors]
(tests/helpers.write_v3: the law of cosines inverted).

Shared with the package, and so not tested here: the laws' form and values (helpers.law: a linear
spring, a bumper, stiff stops and a damper of one rate each way, the values the bike file gives),
the masses and geometry read from the same bike file (inputs), point-contact tyres of the bike file's
rate without damping, vertical-only motion (no horizontal motion of the axles: the wheelbase fixed at
its sag), the rear unsprung mass lumped at the axle (the wheel and half the swingarm). Not shared:
the pitch coupling between the ends, the rider on his limbs (the package's inverse takes each end's
sprung mass as rigid, its static share of bike and rider), the rider's slow load (the inverse takes
the slow part of the fork's force as the rider's and gives the rear none), the split of the rider's
on-bike mass (half at the pedals, half at the bars here).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve
from scipy.signal import butter, sosfiltfilt

from mtbmj.cli import main

from helpers import RATIO, bike_text, law, write_v3

RATE = 1000.0
RESIDUAL = []  # the rest state's largest acceleration (m/s2), per ride made
SECONDS = 40.0
V0, DV, PERIOD = 6.5, 1.0, 25.0  # m/s: the speed V0 + DV sin(2 pi t / PERIOD)
SLOW_LOAD_N, SLOW_PERIOD_S = 80.0, 7.0  # the rider's fore-aft load shift


def speed(t):
    return V0 + DV * np.sin(2 * np.pi * t / PERIOD)


def along(t):
    return V0 * t - DV * PERIOD / (2 * np.pi) * (np.cos(2 * np.pi * t / PERIOD) - 1.0)


def smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def terrain(length, seed=21):
    """h(s) m on a 5 mm grid: ISO 8608 class C roughness (G_d(n0) = 256e-6 m^3 at n0 = 0.1 cycles/m,
    w = 2) as a sum of sines of random phase, a rock garden, a G-out, two drops, a tabletop; and
    the places of the features (m)."""
    rng = np.random.default_rng(seed)
    s = np.arange(-5.0, length + 5.0, 0.005)
    n = np.linspace(0.05, 8.0, 800)  # cycles/m
    dn = n[1] - n[0]
    amp = np.sqrt(2.0 * 256e-6 * (n / 0.1) ** -2.0 * dn)
    h = (amp[:, None] * np.sin(2 * np.pi * n[:, None] * s[None, :] + rng.uniform(0, 2 * np.pi, n.size)[:, None])).sum(0)
    h *= smoothstep((s - 3.0) / 5.0)  # the first metres level: the bike starts at rest
    features = {"rocks": 45.0, "g_out": 95.0, "drop_0.3": 130.0, "jump": 165.0, "drop_0.5": 215.0}
    for c in rng.uniform(45.0, 60.0, 12):  # rocks 20-60 mm, 0.4-1 m long
        a, L = rng.uniform(0.02, 0.06), rng.uniform(0.4, 1.0)
        h += a * np.sin(np.pi * np.clip((s - c) / L + 0.5, 0.0, 1.0)) ** 2
    g = features["g_out"]
    h -= 0.25 * np.sin(np.pi * np.clip((s - g) / 8.0, 0.0, 1.0)) ** 2  # a dip 0.25 m deep, 8 m long
    h -= 0.3 * smoothstep((s - features["drop_0.3"]) / 0.05)
    j = features["jump"]  # up 0.4 m over 2.5 m, a 2 m table, down over 3 m
    h += 0.4 * (smoothstep((s - j) / 2.5) - smoothstep((s - j - 4.5) / 3.0))
    h -= 0.5 * smoothstep((s - features["drop_0.5"]) / 0.05)
    return (lambda x: np.interp(x, s, h)), features


def make_ride(tmp_path, fork_rate=12.0, seconds=SECONDS):
    """The bike file (helpers.bike_text), the SST v3 file, and the truth: t, the ground under each
    wheel, the fork and rear travel (mm), the wheelbase, the terrain."""
    from mtbmj.bike import run, spec as spec_mod

    path = tmp_path / "bike.toml"
    path.write_text(bike_text(fork_rate))
    spec = spec_mod.load(str(path))  # the bike file's numbers (inputs)
    fork_setup, _ = run.setups(spec)
    tyre_k, radius, g = fork_setup.tire.values(1).rate, fork_setup.tire_radius, 9.81
    sa = math.sin(spec.head_angle)
    r = spec.rider
    # the frame body: the frame and the rider's on-bike segments, half at the pedals, half at the bars
    parts = [(spec.frame_mass, spec.frame_com, spec.frame_inertia), (0.5 * r.on_bike_mass, (r.leg_x, r.leg_z), 0.0),
             (0.5 * r.on_bike_mass, (r.arm_x, r.arm_z), 0.0)]
    M = sum(p[0] for p in parts)
    cx, cz = (sum(p[0] * p[1][i] for p in parts) / M for i in (0, 1))
    I = sum(p[2] + p[0] * ((p[1][0] - cx) ** 2 + (p[1][1] - cz) ** 2) for p in parts)
    mr_, Ir, rx = r.mass, r.pitch_inertia, r.com[0]
    mF = spec.fork_lower_mass + spec.front_wheel_mass
    mR = spec.rear_wheel_mass + 0.5 * spec.swingarm_mass
    xF, xR = spec.front_axle[0], spec.rear_axle[0]
    # the wheelbase at sag, fixed (the generator's rear contact this far behind the front's)
    wb = xF - xR
    fork_law = law(fork_rate * 1e3, 0.130, 500.0, 700.0)
    shock_law = law(90e3, 0.050, 2500.0, 3500.0)
    span = r.arm_x - r.leg_x
    P_leg, P_arm = mr_ * g * (r.arm_x - rx) / span, mr_ * g * (rx - r.leg_x) / span  # the limbs' preloads

    h, features = terrain(along(seconds) + 10.0)
    shift = lambda t: SLOW_LOAD_N * math.sin(2 * math.pi * t / SLOW_PERIOD_S)  # noqa: E731 (+: onto the bars)

    def forces(t, y):
        zf, th, zr, tr, zw, zq, vf, om, vr, orr, vw, vq = y
        front_pt, rear_pt = zf + (xF - cx) * th, zf + (xR - cx) * th  # the frame at each axle (its height change)
        wF, wR = zw - front_pt, zq - rear_pt  # each wheel's rise in the frame (from the static heights below)
        dF = vw - (vf + (xF - cx) * om)
        dR = vq - (vf + (xR - cx) * om)
        fF = fork_law((wF + base[0]) / sa, dF / sa) / sa  # vertical at the wheel (virtual work)
        fR = shock_law((wR + base[1]) / RATIO, dR / RATIO) / RATIO
        legs, arms = [], []
        for x, k, c, P, out in ((r.leg_x, r.leg_stiffness, r.leg_damping, P_leg, legs),
                                (r.arm_x, r.arm_stiffness, r.arm_damping, P_arm, arms)):
            e = (zf + (x - cx) * th) - (zr + (x - rx) * tr)  # frame point up relative to the rider's: compresses
            ed = (vf + (x - cx) * om) - (vr + (x - rx) * orr)
            out.append(P + k * e + c * ed)
        u = shift(t)
        leg, arm = legs[0] - u, arms[0] + u  # the rider's slow load: onto the bars, off the pedals
        s = along(t)
        tF = max(0.0, tyre_k * (float(h(s)) - (zw + base[2] - radius)))
        tR = max(0.0, tyre_k * (float(h(s - wb)) - (zq + base[3] - radius)))
        return fF, fR, leg, arm, tF, tR

    def rhs(t, y):
        zf, th, zr, tr, zw, zq, vf, om, vr, orr, vw, vq = y
        fF, fR, leg, arm, tF, tR = forces(t, y)
        Fz = fF + fR - leg - arm - M * g
        Mo = (xF - cx) * fF + (xR - cx) * fR - (r.leg_x - cx) * leg - (r.arm_x - cx) * arm
        Rz = leg + arm - mr_ * g
        Ro = (r.leg_x - rx) * leg + (r.arm_x - rx) * arm
        return [vf, om, vr, orr, vw, vq, Fz / M, Mo / I, Rz / mr_, Ro / Ir, (tF - fF) / mF - g, (tR - fR) / mR - g]

    # the static heights: each wheel's rise at sag (its law carrying the static share), the tyres' deflection
    share = ((M * cx + mr_ * rx + mF * xF + mR * xR) / (M + mr_ + mF + mR) - xR) / wb
    total = M + mr_ + mF + mR
    from scipy.optimize import brentq

    wF0 = brentq(lambda w: fork_law(w / sa, 0.0) / sa - (total * share - mF) * g, 0.0, 0.12)
    wR0 = brentq(lambda w: shock_law(w / RATIO, 0.0) / RATIO - (total * (1 - share) - mR) * g, 0.0, 0.12)
    base = [wF0, wR0, radius - total * share * g / tyre_k, radius - total * (1 - share) * g / tyre_k]
    # the rest state solved (the share above is the rigid statics; the limbs settle it a little)
    y0 = np.zeros(12)
    rest, info, ok, msg = fsolve(lambda q: rhs(0.0, np.concatenate((q, np.zeros(6))))[6:], np.zeros(6), xtol=1e-10,
                                 full_output=True)
    RESIDUAL.append(float(np.max(np.abs(info["fvec"]))))
    y0[:6] = rest
    t = np.arange(int(seconds * RATE)) / RATE
    sol = solve_ivp(rhs, (0.0, t[-1]), y0, t_eval=t, method="RK45", rtol=1e-5, atol=1e-7, max_step=1e-3)
    assert sol.success, sol.message
    y = sol.y
    wF = y[4] - (y[0] + (xF - cx) * y[1]) + base[0]
    wR = y[5] - (y[0] + (xR - cx) * y[1]) + base[1]
    fork_mm, rear_mm = wF / sa * 1e3, wR * 1e3
    sst = write_v3(tmp_path / "ride.SST", np.clip(fork_mm, 0, None), np.clip(rear_mm, 0, None) / RATIO,
                   spec.sensors, int(RATE))
    tyres = np.array([forces(ti, yi)[4:] for ti, yi in zip(t[::10], y.T[::10])])
    return {"bike": path, "sst": sst, "t": t, "h": h, "features": features, "wb": wb, "fork_mm": fork_mm,
            "rear_mm": rear_mm, "airborne_front": float(np.mean(tyres[:, 0] <= 0.0)),
            "dynamic_index": I / (M * (xF - cx) * (cx - xR))}


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return make_ride(tmp_path_factory.mktemp("whole_bike"))


@pytest.fixture(scope="module")
def rebuilt(made, tmp_path_factory):
    out = tmp_path_factory.mktemp("rebuilt") / "rec"
    assert main(["reconstruct", str(made["sst"]), "--bike", str(made["bike"]), "--out", str(out)]) == 0
    return out


def test_the_made_ride_has_what_it_must(made):
    """The ride made here leaves the ground (the jump, the drops) and uses the travel."""
    assert made["airborne_front"] > 0.005
    assert np.ptp(made["fork_mm"]) > 60.0 and np.ptp(made["rear_mm"]) > 50.0


def test_the_speed_along_the_ride_comes_back(made, rebuilt):
    """Every window's speed within 5 % of the made speed at its centre (within 3 % is issue 51's
    target, below: one window of 7 is 3.2 % off); the profile (linear between the windows' centres)
    within 3 % RMS over the samples checked."""
    import csv as csv_mod

    s = json.loads((rebuilt / "reconstruction.json").read_text())
    accepted = [w for w in s["windows"] if w["speed_m_per_s"] is not None]
    assert len(accepted) >= 0.6 * len(s["windows"])
    for w in accepted:
        assert w["speed_m_per_s"] == pytest.approx(float(speed(0.5 * (w["start_s"] + w["end_s"]))), rel=0.05), w
    with open(rebuilt / "series.csv") as f:
        rows = list(csv_mod.DictReader(f))
    t = np.array([float(r["time_s"]) for r in rows])
    v = np.array([float(r["speed_m_per_s"]) for r in rows])
    checked = np.array([r["checked"] == "1" for r in rows])
    assert np.sqrt(np.mean((v[checked] / speed(t[checked]) - 1.0) ** 2)) < 0.03


def terrain_error_mm(made, rec) -> float:
    """The terrain found under the front wheel against the made one, both high-passed at 5 m (at the
    mean speed: V0 / 5 Hz in time), RMS over the samples the checks count (mm)."""
    sos = butter(2, V0 / 5.0, btype="highpass", fs=RATE, output="sos")
    truth = made["h"](along(made["t"]))
    e = sosfiltfilt(sos, rec.ground) - sosfiltfilt(sos, truth)
    return 1e3 * float(np.sqrt(np.mean(e[rec.valid] ** 2)))


@pytest.fixture(scope="module")
def reconstruction(made):
    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    record = telemetry.read_ride(made["sst"], **decoding(SimpleNamespace(bike=str(made["bike"]), fork_max_mm=None,
                                                                         shock_max_mm=None)))
    return reconstruct.reconstruct(record, str(made["bike"]))


def test_the_right_bike_describes_the_ride(rebuilt, reconstruction):
    """The rear predicted from the fork's record alone beats both naive baselines by the stated margin
    (40 %: the checks' pass), at a correlation above 0.8, and the headline says so in words."""
    c = json.loads((rebuilt / "reconstruction.json").read_text())["checks"]
    assert c["passes"] is True, c
    assert c["beat_margin_percent"] == 40.0
    assert c["rear_predicted_rms_mm"] <= 0.6 * min(c["baseline_delayed_fork_rms_mm"], c["baseline_rear_mean_rms_mm"])
    assert c["verdict"].startswith("the model describes this ride")
    v = reconstruction.valid
    assert np.corrcoef(reconstruction.rear_predicted[v], reconstruction.rear[v])[0, 1] > 0.8


@pytest.mark.xfail(strict=True, reason="issue 51's targets, not reached: on this ride the terrain is found within "
                                       "about 21 mm RMS after a 5 m high-pass (target 15), the rear within about "
                                       "0.51 of the delayed fork's RMS (target 0.5) at a correlation of about 0.88 "
                                       "(target 0.9), one window's speed 3.2 % off (target 3 %)")
def test_issue_51_targets(made, reconstruction):
    c = reconstruction.checks()
    v = reconstruction.valid
    for (start, found, _) in reconstruction.speed["windows"]:
        assert found is None or found == pytest.approx(float(speed(start + 2.5)), rel=0.03)
    assert terrain_error_mm(made, reconstruction) < 15.0
    assert c["rear_predicted_rms_mm"] <= 0.5 * c["baseline_delayed_fork_rms_mm"]
    assert np.corrcoef(reconstruction.rear_predicted[v], reconstruction.rear[v])[0, 1] >= 0.9


def test_the_terrain_is_found_under_the_jumps_and_drops(made, reconstruction):
    """The terrain within 25 mm RMS after a 5 m high-pass (the made one spans 1.2 m: drops of 0.3 and
    0.5 m, a 0.4 m tabletop, a 0.25 m G-out), the flights found: one starts within the first 0.5 m past
    each drop's edge and one over the tabletop (its 7.5 m), and none is longer than 0.5 s (no flight
    runs on past a landing)."""
    assert terrain_error_mm(made, reconstruction) < 25.0
    rec = reconstruction
    where = lambda m: float(np.interp(m, along(made["t"]), made["t"]))  # noqa: E731 (s at m along the ride)
    for name, span in (("jump", 7.5), ("drop_0.3", 0.5), ("drop_0.5", 0.5)):
        a, b = where(made["features"][name]), where(made["features"][name] + span)
        assert any(a <= start <= b for start, _ in rec.jumps), (name, a, b, rec.jumps)
    assert max(end - start for start, end in rec.jumps) < 0.5


@pytest.mark.parametrize("wrong", ["fork_spring_x1.5", "rider_25kg_heavier"])
def test_a_wrong_bike_fails_the_checks_and_says_why(made, tmp_path, capsys, wrong):
    """The same ride read through a bike that did not make it: its fork spring 1.5 times the made one,
    or its rider 25 kg heavier. The rear predicted from the fork's record must lose to a naive
    baseline by the stated margin, and the line says so in words."""
    text = bike_text(18.0 if wrong == "fork_spring_x1.5" else 12.0)
    if wrong == "rider_25kg_heavier":
        from mtbmj.bike import spec as spec_mod

        text += f"[rider]\nmass_kg = {spec_mod.load(str(made['bike'])).rider.mass + 25.0:g}\n"
    bike = tmp_path / "wrong.toml"
    bike.write_text(text)
    assert main(["reconstruct", str(made["sst"]), "--bike", str(bike), "--out", str(tmp_path / "rec")]) == 0
    line = capsys.readouterr().out
    c = json.loads((tmp_path / "rec" / "reconstruction.json").read_text())["checks"]
    assert c["passes"] is False, c
    assert "the model does not describe this ride: it does not beat " in line


def test_the_whole_bike_rides_its_reconstruction(made, rebuilt, tmp_path, capsys):
    """`mtbmj bike` at the recorded setting rides the reconstructed terrain.csv as written, from its
    level lead-in over the G-out, the drops and the tabletop, without a crash (exit 0, no 'crashed')."""
    s = json.loads((rebuilt / "reconstruction.json").read_text())
    length = s["terrain_length_m"] + s["terrain_csv_lead_in_m"]
    code = main(["bike", str(made["bike"]), str(rebuilt / "terrain.csv"), "--speed", f"{V0:g}",
                 "--duration", f"{0.9 * length / V0:.1f}", "--no-figure", "--quiet", "--out", str(tmp_path / "bike")])
    out = capsys.readouterr()
    assert code == 0 and "crashed" not in out.out + out.err, out

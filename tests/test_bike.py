"""The whole bike: its mass matrix and equations against MuJoCo's, the static sag of both ends
against a closed-form equilibrium written here from the preset's numbers, the weight split, the
quick-look figure, and bad bike descriptions on the command line.

The closed form below reads the SST preset's TOML and the reference fork preset directly (not
through mtbmj.bike): geometry, masses, the leverage table, the spring laws' constants and the tire
rate, and solves the statics of the planar bike on flat ground by itself.
"""
from __future__ import annotations

import math
import tomllib
from importlib import resources

import mujoco
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import fsolve

G = 9.81
MM = 1e-3


def _toml(package, name):
    return tomllib.loads((resources.files(package) / f"{name}.toml").read_text())


def _rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def closed_form_sag(bike_name="sst"):
    """(front travel m, rear wheel travel m, pitch rad, front load N, rear load N) at rest on flat
    ground, from the preset's numbers only."""
    b = _toml("mtbmj.bike.presets", bike_name)
    ref = _toml("mtbmj.presets", "reference")
    geo, rider, lev = dict(b["bike"]), b["rider"], b["leverage"]
    chart = b["geometry"]  # the preset's geometry chart: both axles level at the BB's drop above it
    drop = chart["bb_drop_mm"]
    geo["rear_axle_mm"] = [-math.sqrt(chart["chainstay_mm"] ** 2 - drop ** 2), drop]
    geo["front_axle_mm"] = [chart["wheelbase_mm"] + geo["rear_axle_mm"][0], drop]
    alpha = math.radians(chart["head_angle_deg"])
    front0 = np.array(geo["front_axle_mm"]) * MM
    rear0 = np.array(geo["rear_axle_mm"]) * MM
    pivot = np.array(geo["pivot_mm"]) * MM
    fork = b["fork"]["set"]
    k_f = fork["fork.spring.progressive_rate_N_per_mm"] * 1e3
    c_f = fork["fork.spring.progressive_cubic_N_per_mm3"] * 1e9
    p_f = fork["fork.spring.preload_N"]
    shock = b["shock"]["set"]
    k_s = shock["fork.spring.rate_N_per_mm"] * 1e3
    p_s = shock["fork.spring.preload_N"]
    tire_rate = ref["tire"]["contact_rate_N_per_mm"] * 1e3
    w_tab = np.array(lev["wheel_travel_mm"]) * MM
    r_tab = np.array(lev["ratio"], float)
    ratio = lambda w: float(np.interp(w, w_tab, r_tab))
    stroke = lambda w: quad(lambda x: 1.0 / ratio(x), 0.0, w, points=[x for x in w_tab if x < w], limit=400,
                            epsabs=1e-14, epsrel=1e-12)[0]
    # masses (kg) at frame-coordinate points; the rider's on-bike segments in de Leva's proportions
    # (feet + shanks 2 x (1.37 + 4.33) %, hands + forearms 2 x (0.61 + 1.62) %) at pedals and bars
    share = (1.37 + 4.33) / (1.37 + 4.33 + 0.61 + 1.62)
    # rider.mass_kg is the whole rider; de Leva's male segments (the ones above, both sides) ride on the bike
    on_bike = rider["mass_kg"] * 2 * (1.37 + 4.33 + 0.61 + 1.62) / 100
    fixed = [(geo["frame_mass_kg"], np.array(geo["frame_com_mm"]) * MM),
             (on_bike * share, np.array(rider["pedals_mm"]) * MM),
             (on_bike * (1 - share), np.array(rider["bars_mm"]) * MM)]
    m_front = geo["fork_lower_mass_kg"] + geo["front_wheel_mass_kg"]
    m_arm, m_rear, m_rider = geo["swingarm_mass_kg"], geo["rear_wheel_mass_kg"], rider["mass_kg"] - on_bike
    com = np.array(rider["com_mm"]) * MM
    weight = (sum(m for m, _ in fixed) + m_front + m_arm + m_rear + m_rider) * G
    u = np.array([-math.cos(alpha), math.sin(alpha)])

    def turned(phi, point):  # a swingarm point after phi about the pivot (rear wheel up)
        c, s = math.cos(phi), math.sin(phi)
        d = point - pivot
        return pivot + np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])

    def rider_point(th):
        # the legs and arms carry cos(th) of the rider's weight along the frame's z: the rider
        # rises by the springs' extension (micrometres; its own pitch is smaller still)
        span = rider["bars_mm"][0] * MM - rider["pedals_mm"][0] * MM
        f_legs = m_rider * G * (rider["bars_mm"][0] * MM - com[0]) / span
        return com + np.array([0.0, f_legs * (1 - math.cos(th)) / (rider["leg_stiffness_N_per_mm"] * 1e3)])

    def state(v):
        qf, phi, th = v
        R = _rot(th)
        fa = R @ (front0 + qf * u)
        ra = R @ turned(phi, rear0)
        points = [(m, R @ p) for m, p in fixed] + [(m_front, fa), (m_arm, R @ turned(phi, (pivot + rear0) / 2)),
                                                    (m_rear, ra), (m_rider, R @ rider_point(th))]
        n_front = sum(m * G * (p[0] - ra[0]) for m, p in points) / (fa[0] - ra[0])
        return fa, ra, n_front, weight - n_front

    def residual(v):
        qf, phi, th = v
        fa, ra, nf, nr = state(v)
        fork_eq = p_f + k_f * qf + c_f * qf ** 3 - (nf - m_front * G) * math.sin(alpha - th)
        h = 1e-6
        z_of = lambda p, a: (_rot(th) @ turned(a, p))[1]
        dz_axle = (z_of(rear0, phi + h) - z_of(rear0, phi - h)) / (2 * h)
        dz_arm = (z_of((pivot + rear0) / 2, phi + h) - z_of((pivot + rear0) / 2, phi - h)) / (2 * h)
        w = turned(phi, rear0)[1] - rear0[1]
        dw = (turned(phi + h, rear0)[1] - turned(phi - h, rear0)[1]) / (2 * h)
        shock_eq = (nr - m_rear * G) * dz_axle - m_arm * G * dz_arm - (p_s + k_s * stroke(w)) * dw / ratio(w)
        # both treads on the same flat ground: each axle stands radius - deflection above it
        level = (fa[1] + nf / tire_rate) - (ra[1] + nr / tire_rate)
        return [fork_eq, shock_eq, level]

    qf, phi, th = fsolve(residual, [0.04, 0.1, 0.0], xtol=1e-14)
    assert max(abs(r) for r in residual([qf, phi, th])) < 1e-7
    _, _, nf, nr = state([qf, phi, th])
    return qf, turned(phi, rear0)[1] - rear0[1], th, nf, nr


def test_static_sag_front_and_rear_equal_the_closed_form_and_the_engine_holds_it():
    from mtbmj.bike.run import run_bike

    qf, w, th, nf, nr = closed_form_sag("sst")
    r = run_bike("sst", "flat", 2.0, duration=0.3)
    raw = r.raw
    assert raw["front_travel_mm"][0] == pytest.approx(qf * 1e3, abs=1e-3)
    assert raw["rear_travel_mm"][0] == pytest.approx(w * 1e3, abs=1e-3)
    assert raw["pitch_deg"][0] == pytest.approx(math.degrees(th), abs=1e-5)
    # the weight split the geometry gives (N), each tire's load
    assert raw["front_tire_N"][0] == pytest.approx(nf, abs=0.05)
    assert raw["rear_tire_N"][0] == pytest.approx(nr, abs=0.05)
    # sag is a plausible share of the travel (the preset was tuned for 20-30 %)
    assert 0.15 < qf / 0.180 < 0.30 and 0.15 < w / 0.174 < 0.35
    # rolling on at the set speed, MuJoCo stays at that equilibrium
    assert np.max(np.abs(raw["front_travel_mm"] - qf * 1e3)) < 0.05
    assert np.max(np.abs(raw["rear_travel_mm"] - w * 1e3)) < 0.05
    assert np.max(np.abs(raw["speed_m_per_s"] - 2.0)) < 1e-3


def _schur(model, data, keep, spin):
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, M, data.qM) if hasattr(data, "qM") else mujoco.mj_fullM(model, data, M)
    return M[np.ix_(keep, keep)] - M[np.ix_(keep, spin)] @ np.linalg.solve(M[np.ix_(spin, spin)], M[np.ix_(spin, keep)])


def test_mass_matrix_and_accelerations_match_mujoco_at_random_states():
    """The closed-form mass matrix equals MuJoCo's with the free spin joints eliminated (Schur
    complement), and the reference's accelerations equal MuJoCo's (all forces and velocity terms)."""
    from mtbmj.bike.reference import NQ, Reference
    from mtbmj.bike.run import prepare
    from mtbmj.controllers import installed

    p = prepare("sst", "root:at_m=0.4", 4.0)
    ref = Reference(p)
    b, m = p.bike, p.bike.model
    names = ("bike_x", "bike_z", "pitch", "fork", "swingarm", "rider_z", "rider_pitch")
    keep = [b.dof_index(n) for n in names]
    spin = [b.dof_index("front_spin"), b.dof_index("rear_spin")]
    rng = np.random.default_rng(7)
    d = mujoco.MjData(m)
    checked = 0
    while checked < 6:
        q = np.array([rng.uniform(0.0, 0.6), rng.uniform(-0.08, 0.0), rng.uniform(-0.2, 0.2), rng.uniform(0.0, 0.17),
                      rng.uniform(0.0, 0.4), rng.uniform(-0.05, 0.05), rng.uniform(-0.2, 0.2)])
        v = rng.normal(0.0, 1.0, NQ)
        d.qpos[:] = 0.0
        d.qvel[:] = 0.0
        for i, n in enumerate(names):
            d.qpos[b.qpos_index(n)] = q[i]
            d.qvel[b.dof_index(n)] = v[i]
        d.qvel[spin[0]] = d.qvel[spin[1]] = 7.0
        d.act[:] = 0.0
        d.time = 0.0
        mujoco.mj_kinematics(m, d)
        if any(p.front_tire.radius - (d.xpos[m.body(w).id][2] - p.terrain.height(d.xpos[m.body(w).id][0])) > 0.045
               for w in ("front_wheel", "rear_wheel")):
            continue  # a tyre driven through its rim (48.7 mm): no state a run reaches, its force past 1e10 N
        checked += 1
        p.callback.reset()
        with installed(p.callback):
            mujoco.mj_forward(m, d)
        S = _schur(m, d, keep, spin)
        M = ref.planar.mass_matrix(q)
        assert np.max(np.abs(S - M)) <= 1e-10 * np.max(np.abs(M))
        qdd, _ = ref.accelerations(0.0, np.concatenate((q, v, [0.0] * (ref.nf + ref.ns))))
        assert np.allclose(d.qacc[keep], qdd, rtol=1e-8, atol=1e-8 * np.max(np.abs(qdd)))


def test_quicklook_figure_labels_and_ranges():
    from mtbmj.bike.figure import figure
    from mtbmj.bike.run import run_bike

    r = run_bike("trail", "root:at_m=0.4", 5.0, duration=0.12)
    fig = figure(r)
    axes = fig.axes
    labels = [ax.get_ylabel() for ax in axes]
    assert labels == ["terrain [mm]", "travel [mm]", "pitch, nose up [deg]", "tire load [N]",
                      "rider vertical\nacceleration [m/s²]", "speed [m/s]"]
    assert axes[-1].get_xlabel() == "time [s]"
    travel = axes[1].get_lines()
    assert [l.get_label() for l in travel] == ["front travel (of 130 mm)", "rear wheel travel (of 120 mm)",
                                               "shock stroke (of 50 mm)"]
    assert np.max(travel[0].get_ydata()) == pytest.approx(r.summary["max_front_travel_mm"])
    lo, hi = axes[3].get_ylim()
    assert lo <= min(r.raw["front_tire_N"].min(), r.raw["rear_tire_N"].min()) and hi >= r.raw["front_tire_N"].max()
    assert r.raw["terrain_front_mm"].max() == pytest.approx(50.0, abs=0.1)  # the root under the front axle


BAD = [
    ("[leverage]\nratio = [3.0, -1.0, 2.5, 2.4, 2.3]\nwheel_travel_mm = [0.0, 40.0, 80.0, 120.0, 174.0]\n",
     "leverage.ratio"),
    ("[leverage]\nratio = [3.0, 2.8, 2.6, 2.5, 2.4]\nwheel_travel_mm = [0.0, 40.0, 30.0, 120.0, 174.0]\n",
     "leverage.wheel_travel_mm"),
    ("[bike]\npivot_mm = [-400.0, 40.0]\n", "bike.pivot_mm"),
    ("[shock]\nstroke_mm = 50.0\n", "shock.stroke_mm"),
    ("[rider]\nmass_kg = -70.0\n", "rider.mass_kg"),
    ("[bike]\nframe_mass_kg = -1.0\n", "bike.frame_mass_kg"),
    ("[bike]\nhead_angle_deg = 95.0\n", "bike.head_angle_deg"),
    ("[bike]\nhead_angle_deg = 40.0\n", "bike.head_angle_deg"),
]


@pytest.mark.parametrize("text,key", BAD)
def test_bad_bike_one_line_naming_the_key_exit_2_nothing_written(tmp_path, capsys, monkeypatch, text, key):
    from mtbmj.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.toml").write_text('base = "sst"\n' + text)
    out = tmp_path / "out"
    assert main(["bike", "bad.toml", "flat", "--speed", "3", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0], err
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_bike_command_writes_its_folder(tmp_path, capsys):
    import csv
    import json

    from mtbmj.cli import main

    out = tmp_path / "run"
    assert main(["bike", "trail", "root:at_m=0.4", "--speed", "4", "--duration", "0.1", "--out", str(out),
                 "--quiet", "--no-figure"]) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    assert len(printed) == 1 and printed[0].startswith("bike trail (rider 85.0 kg, bike 14.8 kg) over root:at_m=0.4 at 4 m/s "
                                                       "set (")
    assert "m/s): front travel peak" in printed[0]
    assert {"timeseries.csv", "summary.json", "manifest.json", "fork_config.toml", "shock_config.toml"} <= {
        p.name for p in out.iterdir()}
    summary = json.loads((out / "summary.json").read_text())
    for end, travel in (("front", 130.0), ("rear", 50.0)):  # the rear's end of travel is in shock stroke
        assert summary[end]["travel_mm"] == pytest.approx(travel)
        assert {"bumper", "hard_stop", "rim_strikes", "travel_used_mm", "bottomed_out"} <= set(summary[end])
    assert set(summary["rim_strikes"]) == {"front", "rear"}
    assert summary["rider_acceleration_rms_m_per_s2"] > 0.0
    assert set(summary["tire_load"]["front"]) >= {"mean_N", "max_N", "min_N", "std_N", "variation"}
    with open(out / "timeseries.csv") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header = rows[0]
    for column in ("front_travel_mm", "rear_travel_mm", "stroke_mm", "pitch_deg", "front_tire_N", "rear_tire_N",
                   "rider_acc_z_m_per_s2", "speed_m_per_s"):
        assert column in header
    step = json.loads((out / "manifest.json").read_text())["engine_info"]["timestep_s"]
    assert step == pytest.approx(5e-4)  # the bike's coarse step: no stop or rim within reach on the root
    assert len(rows) - 1 == 200  # 0.1 s at 0.5 ms
    times = np.array([float(r[0]) for r in rows[1:]])
    assert np.allclose(np.diff(times), step, atol=1e-9)


def test_bike_crosscheck_needs_a_terrain_and_a_speed(capsys):
    from mtbmj.cli import main

    assert main(["crosscheck", "sst", "--bike", "--speed", "4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--roll" in err[0]


def test_video_of_a_run(tmp_path, monkeypatch):
    from mtbmj.errors import MtbmjError
    from mtbmj.rolling.render import gl_backend

    monkeypatch.delenv("MUJOCO_GL", raising=False)  # conftest disables GL for dm_control; rendering asks for it
    try:
        gl_backend()
    except MtbmjError as exc:
        pytest.skip(f"no headless OpenGL here: {exc}")
    from PIL import Image

    from mtbmj.bike.run import run_bike

    r = run_bike("trail", "flat", 4.0, duration=0.1)
    info = r.video(tmp_path / "bike.gif", fps=30.0, width=160, height=120)
    with Image.open(tmp_path / "bike.gif") as im:
        assert im.size == (160, 120) and im.n_frames == info["frames"] == 3  # 0, 1/30 and 2/30 s of 0.1 s


def test_a_start_on_an_obstacle_is_refused(tmp_path, capsys):
    """The static equilibrium is the bike's on level ground; a wheel starting on the root would
    balance the bike on it (the horizontal force unbalanced), so it is refused in one line."""
    from mtbmj.cli import main

    out = tmp_path / "out"
    assert main(["bike", "sst", "root:at_m=0.1", "--speed", "4", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "start:" in err[0] and "front wheel" in err[0]
    assert not out.exists()


def test_a_csv_that_starts_on_its_feature_is_refused_without_naming_at_m(tmp_path, capsys):
    """A user's CSV rising from its first row: a CSV has no at_m, which the refusal told to move; it
    names the file and the level stretch it needs instead. The same profile begun with 1 m of level
    ground passes the check (the run is a tenth of a second)."""
    from mtbmj.cli import main

    rising, level = tmp_path / "rising.csv", tmp_path / "level.csv"
    rising.write_text("distance_m,height_mm\n0,0\n1,10\n2,0\n6,0\n")
    level.write_text("distance_m,height_mm\n0,0\n1,0\n2,10\n3,0\n7,0\n")
    out = tmp_path / "out"
    assert main(["bike", "trail", str(rising), "--speed", "4", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "front wheel" in err[0] and f"{rising} is not level within" in err[0], err
    assert "at_m" not in err[0] and "begin the profile with a level stretch" in err[0]
    assert not out.exists()
    assert main(["bike", "trail", str(level), "--speed", "4", "--duration", "0.1", "--no-figure", "--out", str(out),
                 "--quiet"]) == 0


def test_beside_the_real_sst_ride():
    """Both ends' travel histograms, simulated and from the shipped SST ride of the same bike, each
    in % of its own travel; the ride's own numbers come from its file (mtbmj.measured.telemetry)."""
    from mtbmj.ride import beside as ride
    from mtbmj.bike.run import run_bike
    from mtbmj.measured import telemetry

    r = run_bike("sst", "flat", 4.0, duration=0.1)
    c = ride.compare(r, "example")
    real = telemetry.read_sst(telemetry.example_path())
    for end, sim, top, rec, rec_top in (("front", r.raw["front_travel_mm"], 180.0, real.fork_mm, real.fork_max_mm),
                                        ("rear", r.raw["rear_travel_mm"], 174.0, real.rear_mm, real.rear_max_mm)):
        entry = c[end]
        assert sum(entry["simulated"]["time_percent"]) == pytest.approx(100.0)
        assert sum(entry["ride"]["time_percent"]) == pytest.approx(100.0)
        assert entry["simulated_mean_percent"] == pytest.approx(np.mean(sim) / top * 100.0)
        assert entry["ride_mean_percent"] == pytest.approx(np.mean(rec) / rec_top * 100.0)
    # at rest on the flat the simulated bike sits at its sag: one 5 % band per end
    assert max(c["front"]["simulated"]["time_percent"]) == pytest.approx(100.0)
    fig = ride.figure(c)
    assert [ax.get_ylabel() for ax in fig.axes] == ["front (fork)\n% of time", "rear (wheel)\n% of time"]


def test_beside_a_ride_reads_it_through_the_bike_that_ran():
    """``bike BIKE ... --ride FILE`` reads the ride through BIKE (its leverage, stroke and sensors),
    as telemetry, advise and bob do; it read every ride through the shipped example's bike."""
    from mtbmj.bike import spec
    from mtbmj.bike.run import run_bike
    from mtbmj.measured import telemetry
    from mtbmj.ride import beside

    r = run_bike("trail", "flat", 4.0, duration=0.1)
    c = beside.compare(r, "example")
    decoding = spec.ride_decoding(spec.load("trail"))
    through_trail = telemetry.read_sst(telemetry.example_path(), **decoding)
    as_sst = telemetry.read_sst(telemetry.example_path())
    assert decoding["shock_max_mm"] != pytest.approx(as_sst.shock_max_mm)  # the two bikes read it otherwise
    assert c["rear"]["ride_mean_percent"] == pytest.approx(
        np.mean(through_trail.rear_mm) / through_trail.rear_max_mm * 100.0)
    assert c["rear"]["ride_mean_percent"] != pytest.approx(np.mean(as_sst.rear_mm) / as_sst.rear_max_mm * 100.0,
                                                           rel=1e-3)


def test_beside_the_example_named_in_any_case(tmp_path, capsys, monkeypatch):
    """``--ride EXAMPLE`` is the shipped ride, as ``mtbmj telemetry EXAMPLE`` is; it was refused as a
    missing file. A file that is really named so is read as the file it is (here refused: not a ride)."""
    import json

    from mtbmj.cli import main

    monkeypatch.chdir(tmp_path)
    args = ["bike", "sst", "flat", "--speed", "4", "--duration", "0.1", "--quiet", "--no-figure"]
    assert main(args + ["--ride", "EXAMPLE", "--out", "upper"]) == 0
    assert main(args + ["--ride", "example", "--out", "lower"]) == 0
    upper = json.loads((tmp_path / "upper" / "ride_comparison.json").read_text())
    assert upper == json.loads((tmp_path / "lower" / "ride_comparison.json").read_text())
    assert upper["front"]["ride_mean_percent"] > 10.0  # the shipped ride's fork travels
    (tmp_path / "Example").write_text("not a recording\n")
    capsys.readouterr()
    assert main(args + ["--ride", "Example", "--out", "file"]) == 2
    assert "Example" in capsys.readouterr().err
    assert not (tmp_path / "file").exists()


def test_bike_command_holds_parts_and_lifts_the_rear(tmp_path, capsys):
    import csv
    import json

    from mtbmj.cli import main

    out = tmp_path / "held"
    assert main(["bike", "sst", "root:at_m=0.4", "--speed", "4", "--duration", "0.3", "--lock", "rear, pitch",
                 "--out", str(out), "--quiet", "--no-figure"]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith("bike sst (held: rear, pitch) (rider 85.0 kg, bike 16.2 kg) over root:at_m=0.4")
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["engine_info"]["locked"] == ["rear", "pitch"]
    summary = json.loads((out / "summary.json").read_text())
    # held: the rear wheel stays at its sag and the frame level, while the fork works over the root
    with open(out / "timeseries.csv") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    cols = {name: i for i, name in enumerate(rows[0])}
    rear = np.array([float(r[cols["rear_travel_mm"]]) for r in rows[1:]])
    pitch = np.array([float(r[cols["pitch_deg"]]) for r in rows[1:]])
    assert np.ptp(rear) < 1e-6 and np.ptp(pitch) < 1e-6
    assert summary["max_front_travel_mm"] - summary["static_front_travel_mm"] > 20.0

    lifted = tmp_path / "lifted"
    assert main(["bike", "sst", "flat", "--speed", "4", "--duration", "0.05", "--lock", "rear,pitch,rider",
                 "--lift-rear", "--out", str(lifted), "--quiet", "--no-figure"]) == 0
    assert "(held: rear, pitch, rider; rear tire off)" in capsys.readouterr().out
    assert json.loads((lifted / "summary.json").read_text())["tire_load"]["rear"]["max_N"] == 0.0


@pytest.mark.parametrize("argv,key", [(["--lock", "fork"], "lock"), (["--lift-rear"], "pitch")])
def test_bike_command_refuses_bad_holds_in_one_line(tmp_path, capsys, argv, key):
    from mtbmj.cli import main

    out = tmp_path / "run"
    assert main(["bike", "sst", "flat", "--speed", "4", "--duration", "0.05", *argv, "--out", str(out),
                 "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0] and "Traceback" not in err[0]
    assert not out.exists()

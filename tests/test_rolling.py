"""Rolling front end: terrain library, the radial tire's stiffness on any terrain, runs, CLI, env."""
import json
import math
import os

os.environ.setdefault("MUJOCO_GL", "disable")

import numpy as np
import pytest

from mtbmj.rolling import frontend as R
from mtbmj.rolling import terrain as T
from mtbmj.errors import MtbmjError
from mtbmj.rolling.tire import RadialTire

from helpers import SETTLE_CASES, settle


# --- the tire's stiffness on any terrain -------------------------------------------------------


@pytest.mark.parametrize("case", list(SETTLE_CASES))
def test_static_deflection_equals_force_over_rate(case):
    ter, x = SETTLE_CASES[case]
    deflection, force, applied, rate = settle(ter, x)
    assert abs(deflection - force / rate) / (force / rate) < 0.02, (case, deflection, force / rate)
    assert abs(applied - force) / force < 0.02


def test_edge_contact_is_tilted_and_single():
    ter = T.step_down(height_mm=100, at_m=1.0)
    tire = RadialTire(ter, 0.37, 73.4e3, 150.0)
    cx, cz = 1.1, 0.1 + math.sqrt(0.37**2 - 0.1**2) - 0.005
    patches = tire.patches(cx, cz)
    assert len(patches) == 1
    qx, qz, nx, nz, *_ = patches[0]
    assert (qx, qz) == pytest.approx((1.0, 0.1))
    assert nx > 0.2 and nz > 0.9  # pushes the axle forward and up: the corner is behind it


def test_tire_never_pulls():
    tire = RadialTire(T.flat(), 0.37, 73.4e3, 150.0)
    patches = tire.patches(0.0, 0.36)
    # 10 mm deflection, but the axle leaves the ground fast: K d + B dd/dt < 0 -> no force
    fx, fz, d, rate, active = tire.force(0.0, 0.36, 0.0, 6.0, patches)
    assert d == pytest.approx(0.01) and rate == pytest.approx(-6.0)
    assert (fx, fz, active) == (0.0, 0.0, 0)
    rng = np.random.default_rng(0)
    for _ in range(200):
        cz, vz = rng.uniform(0.33, 0.39), rng.uniform(-5, 5)
        fx, fz, *_ = tire.force(0.0, cz, 0.0, vz, tire.patches(0.0, cz))
        assert fz >= 0.0 and abs(fx) < 1e-9


def test_gap_is_bridged_and_step_is_met_at_its_corner():
    # a 100 mm wide, 200 mm deep hole: the tire spans it, two patches (both rims)
    ter = T.Terrain("gap", np.array([-2.0, 0.0, 0.0, 0.1, 0.1, 3.0]), np.array([0, 0, -0.2, -0.2, 0, 0.0]), 0.0, 1.0)
    tire = RadialTire(ter, 0.37, 73.4e3, 150.0)
    patches = tire.patches(0.05, 0.36)
    assert len(patches) == 2
    fx, fz, d, _, active = tire.force(0.05, 0.36, 0.0, 0.0, patches)
    assert active == 2 and fz > 0 and abs(fx) < 1e-6
    # a 50 mm step 0.19 m ahead touches the loaded tire (8 mm on the ground) at its corner: a
    # second patch, pushing the axle back
    tire = RadialTire(T.step_up(50, at_m=0.19), 0.37, 73.4e3, 150.0)
    patches = tire.patches(0.0, 0.362)
    assert len(patches) == 2 and patches[1][:2] == pytest.approx((0.19, 0.05))
    fx, fz, _, _, active = tire.force(0.0, 0.362, 0.0, 0.0, patches)
    assert active == 2 and fx < -100.0


# --- terrain library -----------------------------------------------------------------------------

def test_terrain_shapes():
    t = T.step_up(height_mm=50, at_m=1.0)
    assert t.height(0.9) == pytest.approx(0.0) and t.height(1.1) == pytest.approx(0.05)
    t = T.step_down(height_mm=50, at_m=1.0)
    assert t.height(0.9) == pytest.approx(0.05) and t.height(1.1) == pytest.approx(0.0)
    t = T.square_edge(height_mm=40, width_mm=100, at_m=1.0)
    assert t.height([0.99, 1.05, 1.11]) == pytest.approx([0.0, 0.04, 0.0])
    t = T.root(radius_mm=50, at_m=1.0)
    assert t.height(1.05) == pytest.approx(0.05, abs=1e-6)
    assert t.height(1.05 + 0.03) == pytest.approx(math.sqrt(0.05**2 - 0.03**2), abs=1e-5)
    t = T.rock(height_mm=100, length_mm=300, at_m=1.0)
    assert t.height(1.15) == pytest.approx(0.1, abs=1e-6)
    t = T.drop(height_mm=300)
    assert t.start_height() == pytest.approx(0.3) and t.height(t.length) == pytest.approx(0.0)
    t = T.washboard(height_mm=20, wavelength_mm=300, length_m=3, at_m=1.0)
    xs = np.linspace(1.0, 4.0, 3001)
    assert t.height(xs).max() == pytest.approx(0.02, abs=1e-5) and t.height(1.0 + 0.15) == pytest.approx(0.02, abs=1e-5)
    assert t.height(1.3) == pytest.approx(0.0, abs=1e-9)


def test_iso8608_class_and_seed():
    a = T.iso8608("C", seed=3, length_m=200)
    b = T.iso8608("C", seed=3, length_m=200)
    c = T.iso8608("C", seed=4, length_m=200)
    assert np.array_equal(a.z, b.z) and not np.array_equal(a.z, c.z)
    d = T.iso8608("D", seed=3, length_m=200)
    # class D has 4x the PSD of C: twice the rms; rms from the PSD integral Gd(n0) n0^2 (1/n1 - 1/n2)
    mask = a.x > a.params["at_m"] + 2.0
    rms_c, rms_d = a.z[mask].std(), d.z[mask].std()
    assert rms_d / rms_c == pytest.approx(2.0, rel=1e-6)
    expected = math.sqrt(256e-6 * 0.01 * (1 / 0.011 - 1 / 2.83))
    assert 0.5 * expected < rms_c < 1.5 * expected


def test_drum_turns_the_cleat_under_the_wheel():
    drum = T.make("drum:radius_mm=500,cleat_height_mm=20,cleat_at_deg=30").with_speed(2.0)
    px, pz, *_ = drum.polyline(-0.4, 0.4, 0.0)
    assert np.hypot(px, pz + 0.5).max() == pytest.approx(0.52)  # the cleat, 30 deg ahead
    t_top = math.radians(30) * 0.5 / 2.0
    px, pz, *_ = drum.polyline(-0.05, 0.05, t_top)
    top = np.abs(px) < 0.015
    assert pz[top].max() == pytest.approx(0.02, abs=1e-3)
    vx, vz = drum.surface_velocity(0.0, 0.0, 0.0)
    assert (vx, vz) == pytest.approx((-2.0, 0.0))


def test_csv_profile(tmp_path):
    good = tmp_path / "trail.csv"
    good.write_text("distance_m,height_mm\n0,0\n1,0\n1.5,80\n3,0\n")
    t = T.make(str(good))
    assert t.height(1.5) == pytest.approx(0.08) and t.start_x == 0.0
    bad = tmp_path / "bad.csv"
    bad.write_text("distance_m,force_N\n0,0\n1,0\n")
    with pytest.raises(MtbmjError, match="distance_m, height_mm"):
        T.make(str(bad))
    back = tmp_path / "back.csv"
    back.write_text("distance_m,height_mm\n0,0\n1,0\n0.5,3\n")
    with pytest.raises(MtbmjError, match="decreases"):
        T.make(str(back))


def test_a_csv_in_the_wrong_units_is_named_in_one_warning(tmp_path, recwarn, capsys):
    """The docs' profile (a 40 mm ledge 2-4.5 m along) with its distances typed in millimetres ran
    silently over 8 km of what the run saw as flat ground (the default duration 2000 s at 4 m/s), and
    with its heights typed in metres over a 0.04 mm ledge: each is one warning naming the column. The
    profile as written, a flat one, a 90 m profile at 1 % and a 2 km one at 2 % draw none."""
    from mtbmj.errors import ConfigWarning

    rows = [(0, 0), (2, 0), (2.5, 40), (4, 40), (4.5, 0), (8, 0)]

    def said(name, scale_x=1.0, scale_z=1.0, points=rows):
        path = tmp_path / f"{name}.csv"
        path.write_text("distance_m,height_mm\n" + "".join(f"{x * scale_x:g},{z * scale_z:g}\n" for x, z in points))
        recwarn.clear()
        T.make(str(path))
        return [str(w.message) for w in recwarn.list if issubclass(w.category, ConfigWarning)]

    assert said("as_written") == []
    assert said("flat", points=[(0, 0), (8, 0)]) == []
    assert said("long_hill", points=[(0, 0), (10, 0), (2000, 2000 * 0.02 * 1000)]) == []
    assert said("gentle", points=[(0, 0), (3, 0), (90, 87 * 0.01 * 1000)]) == []
    mm = said("mm", scale_x=1000.0)
    assert len(mm) == 1 and "mm.csv: distance_m spans 8000 m" in mm[0] and "distances in millimetres?" in mm[0], mm
    m = said("m", scale_z=1e-3)
    assert len(m) == 1 and "m.csv: height_mm rises and falls by 0.04 mm" in m[0] and "heights in metres?" in m[0], m
    from mtbmj.cli import main

    out = tmp_path / "run"
    assert main(["roll", str(tmp_path / "mm.csv"), "--speed", "4", "--duration", "0.05", "--quiet",
                 "--no-figure", "--out", str(out)]) == 0
    lines = capsys.readouterr().err.splitlines()
    assert [line for line in lines if line.startswith("mtbmj: warning: ")] == [f"mtbmj: warning: {mm[0]}"], lines


def test_a_feature_typed_in_metres_is_named_in_one_warning(recwarn):
    """``drop:height_mm=1.5`` (a 1.5 m drop typed in metres) made a 1.5 mm drop the run passed over
    unnoticed; a feature's height or radius under 3 mm draws one warning naming the key and the value
    in millimetres. Real features (and a zero height, the terrain's own flat) draw none."""
    from mtbmj.errors import ConfigWarning

    def said(spec):
        recwarn.clear()
        T.make(spec)
        return [str(w.message) for w in recwarn.list if issubclass(w.category, ConfigWarning)]

    assert said("drop:height_mm=1.5") == ["terrain drop: height_mm = 1.5 mm is under 3 mm, smaller than any trail "
                                          "feature (a unit mistake? 1.5 m is height_mm=1500)"]
    assert said("root:radius_mm=0.06") == ["terrain root: radius_mm = 0.06 mm is under 3 mm, smaller than any trail "
                                           "feature (a unit mistake? 0.06 m is radius_mm=60)"]
    for spec in ("drop:height_mm=1500", "root:radius_mm=60", "step_up:height_mm=0", "square_edge:height_mm=3"):
        assert said(spec) == [], spec


@pytest.mark.parametrize("spec, match", [
    ("cobbles", "unknown scenario"),
    ("step_up:height_mm=-20", "must not be negative"),
    ("root:radius_mm=0", "must be positive"),
    ("root:diameter_mm=50", "unknown parameter"),
    ("iso8608:class=Z", "not one of"),
    ("step_up:height_mm", "expected key=value"),
    ("missing.csv", "no such file"),
])
def test_bad_terrain_specs(spec, match):
    with pytest.raises(MtbmjError, match=match) as info:
        T.make(spec)
    assert "\n" not in str(info.value)


# --- runs ----------------------------------------------------------------------------------------

def test_roll_over_root_completes_and_is_deterministic(tmp_path):
    a = R.run_roll("root:radius_mm=60,at_m=0.5", 4.0, duration=0.6)
    b = R.run_roll("root:radius_mm=60,at_m=0.5", 4.0, duration=0.6)
    for name in R.COLUMNS:
        assert np.array_equal(a.raw[name], b.raw[name]), name
        assert np.all(np.isfinite(a.raw[name])), name
    s = a.summary
    assert s["max_fork_mm"] > s["static_fork_mm"] + 10.0  # the root compresses the fork
    assert s["min_axle_force_x_N"] < -100.0  # and pushes the axle back
    assert np.all(a.raw["tire_force_N"] >= 0.0)
    assert a.raw["speed_m_per_s"].min() > 3.8
    written = a.write(tmp_path / "out")
    assert {p.name for p in written} == {"timeseries.csv", "timeseries_raw.csv", "summary.json", "manifest.json", "config.toml",
                                         "quicklook.png"}
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["scenario"]["name"] == "root"
    header = (tmp_path / "out" / "timeseries.csv").read_text().splitlines()[2]
    assert header.split(",") == list(R.COLUMNS)


def test_step_up_and_drum_run():
    r = R.run_roll("step_up:height_mm=80,at_m=0.4", 3.0, duration=0.5, head_angle_deg=70)
    assert r.raw["axle_z_mm"][-1] > 60.0  # up on the step
    d = R.run_roll("drum:radius_mm=400,cleat_height_mm=20,cleat_at_deg=20", 3.0, duration=0.3)
    assert d.summary["max_fork_mm"] > d.summary["static_fork_mm"] + 2.0


@pytest.mark.parametrize("kwargs, match", [
    ({"speed_m_per_s": 0.0}, "speed"),
    ({"speed_m_per_s": -2.0}, "speed"),
    ({"head_angle_deg": 45.0}, "head angle"),
    ({"head_angle_deg": 91.0}, "head angle"),
    ({"duration": -1.0}, "duration"),
])
def test_bad_run_inputs(kwargs, match):
    args = {"scenario": "flat", "speed_m_per_s": 5.0, **kwargs}
    with pytest.raises(MtbmjError, match=match):
        R.run_roll(**args)


def _cli(argv):
    from mtbmj.cli import roll as cli_roll
    from mtbmj.cli.common import Parser

    parser = Parser(prog="mtbmj")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    cli_roll.add_parser(sub)
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.mark.parametrize("argv, match", [
    (["roll", "cobbles", "--speed", "5"], "unknown scenario"),
    (["roll", "flat", "--speed", "0"], "speed"),
    (["roll", "flat", "--speed", "5", "--head-angle", "40"], "head-angle"),  # the gate holds the rig's (45, 90] since round 32b
    (["roll", "step_up:height_mm=-5", "--speed", "5"], "negative"),
])
def test_cli_bad_input_is_one_line(argv, match, tmp_path):
    with pytest.raises(MtbmjError, match=match) as info:
        _cli(argv + ["--out", str(tmp_path / "x"), "--quiet"])
    assert "\n" not in str(info.value)
    assert not (tmp_path / "x").exists()


def test_cli_roll_writes(tmp_path, capsys):
    assert _cli(["roll", "square_edge:height_mm=30,at_m=0.3", "--speed", "4", "--duration", "0.3",
                 "--out", str(tmp_path / "o"), "--quiet"]) == 0
    assert (tmp_path / "o" / "summary.json").exists()
    assert "fork peak" in capsys.readouterr().out


def test_trajectory_for_rendering():
    model, times, qpos = R.roll_trajectory("root", 5.0, duration=0.2, fps=50)
    assert qpos.shape == (times.size, model.nq) and times.size == 11
    import mujoco

    assert model.geom("terrain").type[0] == mujoco.mjtGeom.mjGEOM_HFIELD  # visual only
    assert model.geom_contype[model.geom("terrain").id] == 0


# --- dm_control ----------------------------------------------------------------------------------

@pytest.mark.rl
def test_env_episode_with_skyhook():
    import mujoco

    pytest.importorskip("dm_control", reason="dm_control is the [rl] extra")
    from mtbmj.rolling import env as E
    from mtbmj.controllers.skyhook import Skyhook

    e = E.load("root:at_m=0.3", 4.0, duration=0.4)
    spec = e.action_spec()
    assert spec.shape == (1,) and spec.minimum == 0.0 and spec.maximum == 1.0
    ts = e.reset()
    sky = Skyhook()
    rewards, commands = [], []
    while not ts.last():
        u = sky.command(ts.observation)
        commands.append(float(u[0]))
        ts = e.step(u)
        rewards.append(ts.reward)
        assert all(np.all(np.isfinite(v)) for v in ts.observation.values())
    assert len(rewards) == 200
    assert np.all(np.isfinite(rewards)) and 0.0 < min(rewards) <= max(rewards) <= 1.0
    assert 0.0 <= min(commands) and max(commands) <= 1.0 and max(commands) > min(commands)
    assert mujoco.get_mjcb_control() is None  # installed only while stepping


def test_the_rock_garden_has_seven_rocks_where_and_as_high_as_it_says():
    """``rock_garden``: flat to ``at_m``, then seven half-ellipse rocks whose tops are the listed
    heights times ``height_scale`` (read off the profile here, not from the builder's table), flat
    between them and after; a height scale that is not positive is refused in one line."""
    from mtbmj.rolling import terrain as T

    heights_mm = [80, 110, 60, 100, 70, 90, 50]
    for scale, at in ((1.0, T.LEAD_IN_M), (1.5, 2.0)):
        t = T.make(f"rock_garden:height_scale={scale:g},at_m={at:g}")
        x = np.linspace(-1.0, t.length, 200001)
        z = t.height(x)
        assert np.all(z[x < at] == 0.0) and np.all(z >= 0.0)
        on = z > 1e-9
        starts, ends = np.flatnonzero(np.diff(on.astype(int)) == 1), np.flatnonzero(np.diff(on.astype(int)) == -1)
        assert len(starts) == len(ends) == 7
        tops = [z[a:b + 1].max() * 1e3 for a, b in zip(starts, ends)]
        assert tops == pytest.approx([h * scale for h in heights_mm], rel=2e-3)
        assert x[starts[0]] == pytest.approx(at, abs=1e-4) and x[ends[-1]] < at + 2.76
    with pytest.raises(T.TerrainError, match="height_scale"):
        T.make("rock_garden:height_scale=-1")

"""The rear end from hardpoints (mtbmj/bike/linkage.py) against mechanisms solved here another way:
a single pivot in closed form, the four-bars (tests/helpers.py's FourBar) by scipy's root finder on
the loop-closure equations (angles as unknowns, where the package intersects circles), the chain's
upper run as the line whose distance from each sprocket's centre is its radius (found by a root
finder), the anti-squat and anti-rise lines and the pedal kickback from the chain's length written
out; the bike run from hardpoints against the same bike given a leverage table computed here; the
CLI and its refusals."""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from mtbmj.bike import linkage as lk
from mtbmj.bike import rear_end
from mtbmj.errors import ConfigError

from helpers import HORST, MM, P, FourBar, ang, find, independent, rot


DRIVEN = dict(main_pivot=P(-30, 75), rear_axle=P(-440, 25), swingarm_link=P(-120, 120), rocker_pivot=P(-20, 330),
              rocker_link=P(-110, 330), shock_rocker=P(80, 420), shock_frame=P(220, 180))
SINGLE = dict(main_pivot=P(-30, 75), rear_axle=P(-440, 25), shock_swingarm=P(-150, 150), shock_frame=P(120, 300))
SHORT = dict(lower_pivot=P(20, 60), lower_link=P(-40, 40), upper_pivot=P(-60, 260), upper_link=P(-140, 280),
             rear_axle=P(-440, 25), shock_upper_link=P(-120, 360), shock_frame=P(200, 150))


@pytest.mark.parametrize("kind,pts,stroke", [("single_pivot", SINGLE, 0.065), ("horst_link", HORST, 0.050),
                                             ("linkage_driven_single_pivot", DRIVEN, 0.050),
                                             ("short_link", SHORT, 0.050)])
def test_axle_path_and_leverage_ratio_match_a_mechanism_solved_here(kind, pts, stroke):
    link = lk.Linkage(kind, pts)
    c = lk.curves(link, stroke)
    w, s, axle = independent(kind, pts)
    sign = 1.0 if w(1e-3) > 0 else -1.0
    assert c.stroke[-1] == pytest.approx(stroke, abs=1e-9)
    turn = 0.0
    for i in range(0, c.travel.size, 7):
        target = c.travel[i]
        turn = find(w, target, sign)
        here = axle(turn)
        assert math.hypot(here[0] - c.axle_x[i], here[1] - c.axle_z[i]) < 1e-4  # 0.1 mm
        h = sign * 1e-6
        lo = turn - h if target > 0 else turn
        ratio = (w(turn + h) - w(lo)) / (s(turn + h) - s(lo))
        assert c.leverage_ratio[i] == pytest.approx(ratio, rel=5e-3)  # 0.5 %
        assert c.stroke[i] == pytest.approx(s(turn), abs=1e-7)


def test_single_pivot_in_closed_form():
    """The axle on a circle about the main pivot; LR = (dw/dphi) / (ds/dphi) differentiated by hand."""
    link = lk.Linkage("single_pivot", SINGLE)
    c = lk.curves(link, 0.065)
    A, S, F, R = SINGLE["main_pivot"], SINGLE["shock_swingarm"], SINGLE["shock_frame"], SINGLE["rear_axle"]
    a, b = R - A, S - A
    for i in range(0, c.travel.size, 11):
        # the axle's rise: A_z + sin(phi) a_x + cos(phi) a_z - R_z = w (phi the counter-clockwise turn)
        phi = brentq(lambda t: math.sin(t) * a[0] + math.cos(t) * a[1] - a[1] - c.travel[i], -1.0, 0.0)
        dw = math.cos(phi) * a[0] - math.sin(phi) * a[1]
        end = A + rot(b, phi)
        d_end = rot(np.array([-b[1], b[0]]), phi)
        length = float(np.hypot(*(end - F)))
        ds = -float(np.dot(end - F, d_end)) / length
        assert c.leverage_ratio[i] == pytest.approx(dw / ds, rel=1e-6)
        assert c.centre_x[i] == pytest.approx(A[0]) and c.centre_z[i] == pytest.approx(A[1])


def chain_line(ring_c, ring_r, cog_c, cog_r):
    """The upper run as z = m x + q: the line at signed distance r above each centre, by fsolve."""
    def eqs(u):
        m, q = u
        k = math.sqrt(1 + m * m)
        return [(q + m * ring_c[0] - ring_c[1]) / k - ring_r, (q + m * cog_c[0] - cog_c[1]) / k - cog_r]
    m, q = fsolve(eqs, [0.0, max(ring_r, cog_r)], xtol=1e-14)
    return m, q


def test_anti_squat_and_anti_rise_follow_the_construction():
    link = lk.Linkage("horst_link", HORST, chainring=32, cog=51, brake_on="seatstay")
    radius, front_x, h = 0.37, 0.815, 1.1
    c = lk.curves(link, 0.05, radius, front_x, h)
    w, s, axle = independent("horst_link", HORST)
    fb = FourBar(HORST, "main_pivot", "horst_pivot", "seatstay_rocker", "rocker_pivot")
    ring_r, cog_r = 12.7e-3 / (2 * math.sin(math.pi / 32)), 12.7e-3 / (2 * math.sin(math.pi / 51))
    for i in (0, 30, 60, c.travel.size - 1):
        t = find(w, c.travel[i], -1.0)
        A, D = HORST["main_pivot"], HORST["rocker_pivot"]
        B = fb.point("horst_pivot", "input", t)
        C = fb.point("seatstay_rocker", "output", t)
        ax_ = axle(t)
        # instant centre: where the lines A-B and D-C meet
        M = np.array([B - A, -(C - D)]).T
        k = np.linalg.solve(M, D - A)
        ic = A + k[0] * (B - A)
        m, q = chain_line(np.zeros(2), ring_r, ax_, cog_r)
        # the instant force centre: the chain line meets the line axle -> instant centre
        d = ic - ax_
        u = (m * ax_[0] + q - ax_[1]) / (d[1] - m * d[0])
        ifc = ax_ + u * d
        ground = ax_[1] - radius
        slope = (ifc[1] - ground) / (ifc[0] - ax_[0])
        assert c.anti_squat[i] == pytest.approx(100 * slope * (front_x - ax_[0]) / h, rel=1e-6)
        slope = (ic[1] - ground) / (ic[0] - ax_[0])
        assert c.anti_rise[i] == pytest.approx(100 * slope * (front_x - ax_[0]) / h, rel=1e-6)


def test_pedal_kickback_keeps_the_chain_s_length():
    """The taut upper chain from a link fixed on the cog (held) to one on the chainring: its length
    (wrap on the cog + span + wrap on the ring, the tangent points from the line found here) stays
    the same when the crank turns back by the kickback."""
    link = lk.Linkage("single_pivot", SINGLE, chainring=30, cog=42)
    c = lk.curves(link, 0.065)
    ring_r, cog_r = 12.7e-3 / (2 * math.sin(math.pi / 30)), 12.7e-3 / (2 * math.sin(math.pi / 42))

    def length(axle, crank):
        m, q = chain_line(np.zeros(2), ring_r, axle, cog_r)
        n = np.array([-m, 1.0]) / math.sqrt(1 + m * m)  # the line's upward normal
        t_ring, t_cog = ring_r * n, axle + cog_r * n
        theta = ang(n)
        # the chain wraps the cog from a fixed link at -90 deg (below, held) clockwise to the tangent
        # point, and the ring from the tangent point clockwise to a link at -90 deg + crank
        return cog_r * (-math.pi / 2 - theta + 2 * math.pi) + float(np.hypot(*(t_cog - t_ring))) + \
            ring_r * (theta - (-math.pi / 2 + crank))

    L0 = length(SINGLE["rear_axle"], 0.0)
    for i in (25, 80, c.travel.size - 1):
        axle = np.array([c.axle_x[i], c.axle_z[i]])
        assert length(axle, math.radians(c.kickback_deg[i])) == pytest.approx(L0, abs=1e-9)
    assert c.kickback_deg[-1] > 0.0  # backwards: the chain grows


def test_the_bike_from_hardpoints_runs_as_the_same_bike_from_a_leverage_table(tmp_path):
    """A linkage-driven single pivot (the Clash's layout): the bike from its hardpoints against the
    same bike given the leverage ratio every millimetre from the mechanism solved here."""
    from mtbmj.bike import run

    w, s, _ = independent("linkage_driven_single_pivot", DRIVEN)
    stroke = 0.050
    t_end = find(s, stroke, -1.0)
    travel = np.arange(0.0, w(t_end), 1e-3)
    ratios = []
    for x in travel:
        t = find(w, x, -1.0)
        h = -1e-6
        lo = t - h if x > 0 else t
        ratios.append((w(t + h) - w(lo)) / (s(t + h) - s(lo)))
    points = "\n".join(f"{k}_mm = [{v[0] / MM:.6f}, {v[1] / MM:.6f}]" for k, v in DRIVEN.items())
    common = 'base = "trail"\n[shock]\nstroke_mm = 50.0\n'
    (tmp_path / "hard.toml").write_text(common + '[linkage]\nkind = "linkage_driven_single_pivot"\n' + points + "\n")
    (tmp_path / "table.toml").write_text(
        common.replace('[shock]', '[bike]\npivot_mm = [-30.0, 75.0]\nrear_axle_mm = [-440.0, 25.0]\n[shock]')
        + f"[leverage]\nwheel_travel_mm = {[float(round(x / MM, 9)) for x in travel]}\nratio = {[float(r) for r in ratios]}\n")
    runs = [run.run_bike(str(tmp_path / f), "root:at_m=0.4", 5.0, duration=0.6) for f in ("hard.toml", "table.toml")]
    a, b = (r.raw for r in runs)
    assert np.max(np.abs(a["rear_travel_mm"] - b["rear_travel_mm"])) < 1e-6
    assert np.max(np.abs(a["stroke_mm"] - b["stroke_mm"])) < 1e-6
    assert np.ptp(a["rear_travel_mm"]) > 5.0  # the root moved the rear end


def test_virtual_work_of_the_bike_s_shock_through_the_linkage():
    """The bike's shock acts on the swingarm as F ds/dphi (``bike.spec`` leverage from the hardpoints):
    at every millimetre, ds/dphi equals the mechanism's here, so F ds = (F / LR) dw: the shock's
    power equals the wheel's."""
    from mtbmj.bike.spec import rear_axle_in_frame

    link = lk.Linkage("linkage_driven_single_pivot", DRIVEN)
    c = lk.curves(link, 0.050)
    from mtbmj.bike.spec import Leverage

    lev = Leverage(tuple(c.travel), tuple(c.leverage_ratio))
    _, s, _ = independent("linkage_driven_single_pivot", DRIVEN)

    class Spec:
        pivot, rear_axle = tuple(DRIVEN["main_pivot"]), tuple(DRIVEN["rear_axle"])

    for phi in np.linspace(0.0, 0.3, 13):
        _, z = rear_axle_in_frame(Spec, phi)
        w = float(z) - DRIVEN["rear_axle"][1]
        if w > c.travel[-1]:
            break
        h = 1e-6
        _, z2 = rear_axle_in_frame(Spec, phi + h)
        bike = (lev.stroke(float(z2) - DRIVEN["rear_axle"][1]) - lev.stroke(w)) / h  # ds/dphi the bike uses
        here = (s(-(phi + h)) - s(-phi)) / h
        assert bike == pytest.approx(here, rel=5e-3)


def test_refusals_name_the_key():
    with pytest.raises(ConfigError, match="linkage.kind: must be one of"):
        lk.from_table({"kind": "dw_link"})
    with pytest.raises(ConfigError, match="linkage.horst_pivot_mm: missing"):
        lk.from_table({"kind": "horst_link", **{k + "_mm": list(v / MM) for k, v in HORST.items() if k != "horst_pivot"}})
    with pytest.raises(ConfigError, match="linkage.upper_pivot_mm: not a point of a single_pivot"):
        lk.from_table({"kind": "single_pivot", "upper_pivot_mm": [0, 0]})
    with pytest.raises(ConfigError, match=r"linkage.rear_axle_mm: must be \[x, z\]"):
        lk.from_table({"kind": "single_pivot", **{k + "_mm": list(v / MM) for k, v in SINGLE.items()},
                       "rear_axle_mm": [1, "a"]})
    with pytest.raises(ConfigError, match="linkage.cog_teeth"):
        lk.from_table({"kind": "single_pivot", **{k + "_mm": list(v / MM) for k, v in SINGLE.items()}, "cog_teeth": 5})
    # past its longest stroke (the eye on the line from the frame end through the main pivot, in
    # closed form) the single pivot's shock lengthens again, short of a 500 mm stroke: said so, where
    A, S, F = SINGLE["main_pivot"], SINGLE["shock_swingarm"], SINGLE["shock_frame"]
    longest = float(np.hypot(*(S - F)) - (np.hypot(*(F - A)) - np.hypot(*(S - A))))
    with pytest.raises(ConfigError, match=r"the shock lengthens again past .* before its stroke reaches 500 mm "
                                          r"\(shock.stroke_mm\): check linkage.shock_frame_mm and "
                                          r"linkage.shock_swingarm_mm") as said:
        lk.curves(lk.Linkage("single_pivot", SINGLE), 0.5)
    import re

    past = float(re.search(r"past ([0-9.]+) mm of stroke", str(said.value)).group(1)) * MM
    assert abs(past - longest) < 0.5 * MM  # the last step before it turns back (0.005 rad of the swingarm)


def _write(tmp_path, text):
    f = tmp_path / "bike.toml"
    f.write_text(text)
    return f


def test_cli_writes_curves_and_figure_and_refuses_two_rear_ends(tmp_path):
    points = "\n".join(f"{k}_mm = [{v[0] / MM:g}, {v[1] / MM:g}]" for k, v in HORST.items())
    bike = _write(tmp_path, 'base = "trail"\n[linkage]\nkind = "horst_link"\nbrake_on = "chainstay"\n' + points + "\n")
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "mtbmj.cli", "linkage", str(bike), "--cog", "51", "--out", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "horst_link" in r.stdout and "32x51 T" in r.stdout
    assert "linkage.kind" not in r.stderr  # the bike's circle follows the path within 0.1 mm: nothing to say
    lines = (out / "linkage.csv").read_text().splitlines()
    header = [ln for ln in lines if ln.startswith("wheel_travel_mm")][0].split(",")
    for col in ("wheel_travel_mm", "leverage_ratio", "axle_x_mm", "axle_z_mm", "anti_squat_percent",
                "anti_rise_percent", "pedal_kickback_deg"):
        assert col in header
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert summary["brake_on"] == "chainstay" and summary["cog_teeth"] == 51
    assert summary["bike_axle_path_departure_mm"] < 0.01
    # the chainstay's instant centre is the main pivot
    rows = [ln.split(",") for ln in lines if ln[:1].isdigit()]
    assert len(rows) > 80
    fig = rear_end.for_bike(str(bike)).figure()
    titles = [a.get_title() for a in fig.axes]
    assert titles == ["Leverage ratio",
                      "Rear axle path\n(dashed: as the bike runs it, on the circle\nthat best fits the linkage's path)",
                      f"Anti-squat and anti-rise (centre of mass {summary['com_height_mm']:.0f} mm)",
                      "Pedal kickback (rear wheel held)"]
    for a in (fig.axes[0], fig.axes[2], fig.axes[3]):
        assert a.get_xlim() == pytest.approx((0.0, float(rows[-1][0])), abs=1e-6)
    off = summary["bike_axle_path_departure_mm"]
    assert [ln.get_label() for ln in fig.axes[1].get_lines()] == ["linkage", f"the bike's circle ({off:.3f} mm at "
                                                                              f"most from it)"]
    assert fig.axes[1].get_lines()[1].get_linestyle() == "--"
    # both ways in one file: one line, exit 2, nothing written
    both = _write(tmp_path, 'base = "trail"\n[leverage]\nwheel_travel_mm = [0, 100]\nratio = [2.5, 2.4]\n'
                  '[linkage]\nkind = "horst_link"\n' + points + "\n")
    out2 = tmp_path / "out2"
    r = subprocess.run([sys.executable, "-m", "mtbmj.cli", "linkage", str(both), "--out", str(out2)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "[linkage] and [leverage] give the rear end two ways" in r.stderr
    assert not out2.exists()
    r = subprocess.run([sys.executable, "-m", "mtbmj.cli", "linkage", "sst", "--out", str(out2)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "sst: has no [linkage]" in r.stderr


def test_the_documented_horst_example_runs_and_says_how_it_is_run():
    """docs/bikes/horst_link.toml (docs/bike.md): the bike runs its axle on the circle that best fits
    the linkage's path, which it follows within 0.1 mm (so no warning; the instant centre's circle
    left it by 7.0 mm)."""
    import warnings
    from pathlib import Path

    from mtbmj.bike import run, spec

    path = Path(__file__).resolve().parents[1] / "docs" / "bikes" / "horst_link.toml"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = spec.load(str(path))
    assert s.virtual_pivot
    said = [str(w.message) for w in caught]
    assert not any("linkage.kind" in m for m in said), said
    assert not any("bike.pivot_mm" in m for m in said)  # a derived centre is not a typed key
    b = rear_end.for_bike(str(path))
    assert s.pivot == pytest.approx(tuple(b.pivot))
    assert s.leverage.full_stroke == pytest.approx(0.050, abs=1e-6)
    r = run.run_bike(str(path), "root:at_m=0.4", 5.0, duration=0.5)
    assert np.ptp(r.raw["rear_travel_mm"]) > 5.0


def test_hardpoints_in_metres_are_refused_naming_the_mistake(tmp_path):
    """A careless user's metres: named as such, before the mechanism is solved in the wrong unit
    (it said "the shock's stroke never reaches 50 mm")."""
    from mtbmj.bike import spec

    points = "\n".join(f"{k}_mm = [{v[0]:g}, {v[1]:g}]" for k, v in SINGLE.items())  # metres
    path = _write(tmp_path, 'base = "trail"\n[linkage]\nkind = "single_pivot"\n' + points + "\n")
    with pytest.raises(ConfigError, match=r"linkage.main_pivot_mm, .*look like metres.*\[-30, 75\]"):
        spec.load(str(path))


def test_mtbmj_linkage_names_hardpoints_in_metres_not_a_link_without_length(tmp_path, capsys):
    """``mtbmj linkage`` on a Horst link typed in metres: the one line names the unit (it said "0.38 mm
    apart: the chainstay has no length", the mechanism checked in the wrong unit); the same file in
    millimetres runs (the check can pass)."""
    from mtbmj.cli import main

    from helpers import one_line

    def bike(scale):
        points = "\n".join(f"{k}_mm = [{v[0] / MM * scale:g}, {v[1] / MM * scale:g}]" for k, v in HORST.items())
        return _write(tmp_path, 'base = "trail"\n[linkage]\nkind = "horst_link"\n' + points + "\n")

    err = one_line(capsys, ["linkage", bike(1e-3), "--out", tmp_path / "m"], "look like metres",
                   "these keys are in millimetres", "[-40, 70]")
    assert "no length" not in err
    assert not (tmp_path / "m").exists()
    assert main(["linkage", str(bike(1.0)), "--out", str(tmp_path / "mm")]) == 0
    assert (tmp_path / "mm" / "summary.json").is_file()


@pytest.mark.parametrize("kind,pts,within", [("horst_link", HORST, 0.01e-3), ("short_link", SHORT, 0.3e-3)])
def test_the_bike_runs_the_axle_on_the_linkage_s_path(tmp_path, kind, pts, within):
    """A Horst link and a short link from their hardpoints: over a run across a root the MuJoCo
    bike's rear axle, read in the frame's coordinates from the run's poses, lies on the path of the
    mechanism solved here (at the same wheel travel) within 0.01 mm (the Horst link: its axle path
    is a circle about another centre than the instant centre) and 0.3 mm (the short link's S-shaped
    path, which the bike's circle follows within 0.25 mm and says so)."""
    import mujoco

    from mtbmj.bike import run

    w, s, axle = independent(kind, pts)
    points = "\n".join(f"{k}_mm = [{v[0] / MM:.6f}, {v[1] / MM:.6f}]" for k, v in pts.items())
    path = tmp_path / "bike.toml"
    path.write_text(f'base = "trail"\n[shock]\nstroke_mm = 50.0\n[linkage]\nkind = "{kind}"\n{points}\n')
    r = run.run_bike(str(path), "root:radius_mm=80,at_m=0.4", 5.0, duration=0.7)
    m = r.prepared.bike.model
    d = mujoco.MjData(m)
    frame, site = m.body("frame").id, m.site("rear_axle").id
    worst, deepest = 0.0, 0.0
    for q in r.motion[1][::8]:
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        rot = d.xmat[frame].reshape(3, 3)
        local = rot.T @ (d.site_xpos[site] - d.xpos[frame])
        travel = local[2] - pts["rear_axle"][1]
        deepest = max(deepest, travel)
        expected = axle(find(w, travel, -1.0))
        worst = max(worst, abs(local[0] - expected[0]))
    assert deepest > 0.03  # the root pushed the rear well into its travel
    assert worst < within, worst


def test_the_test_s_single_pivot_runs_on_the_trail_bike_s_own_stroke(tmp_path, capsys):
    """The single pivot above on the trail bike's 50 mm shock: the leverage table solved from it at
    that very stroke integrates (linear ratios between its millimetres) to 50.000006 mm, which the
    stroke check refused by its 1e-9 ("50 mm is shorter than the leverage curve needs ... (50.00 mm)");
    it runs, and its table is the closed form's (the test above) at its stroke. A table that does
    need more stroke than the shock has is still refused."""
    from mtbmj.bike import spec
    from mtbmj.cli import main

    points = "\n".join(f"{k}_mm = [{v[0] / MM:g}, {v[1] / MM:g}]" for k, v in SINGLE.items())
    bike = _write(tmp_path, 'base = "trail"\n[linkage]\nkind = "single_pivot"\n' + points + "\n")
    out = tmp_path / "out"
    assert main(["linkage", str(bike), "--out", str(out)]) == 0, capsys.readouterr().err
    assert (out / "linkage.csv").exists()
    s = spec.load(str(bike))
    assert s.shock_stroke == 0.050
    assert s.leverage.full_stroke == pytest.approx(0.050, rel=1e-6)
    # the wheel's rise at 50 mm of stroke in closed form: the swingarm's turn where the shock is 50 mm shorter
    A, S, F, R = SINGLE["main_pivot"], SINGLE["shock_swingarm"], SINGLE["shock_frame"], SINGLE["rear_axle"]
    L0 = float(np.hypot(*(S - F)))
    phi = brentq(lambda t: L0 - float(np.hypot(*(A + rot(S - A, t) - F))) - 0.050, -1.0, 0.0)
    assert s.leverage.full_travel == pytest.approx(float((A + rot(R - A, phi))[1] - R[1]), abs=1e-9)
    # a table needing 51.06 mm (a constant ratio of 2.35 over the chart's 120 mm) on the 50 mm shock:
    # refused, one line; one needing 50.01 mm (2.3995), a hundredth of a millimetre more, is not
    short = _write(tmp_path, 'base = "trail"\n[leverage]\nwheel_travel_mm = [0, 120]\nratio = [2.35, 2.35]\n')
    assert main(["bike", str(short), "flat", "--speed", "4", "--out", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mtbmj: error: {short}: shock.stroke_mm: 50 mm is shorter than the leverage curve needs over "
                   f"120 mm of wheel travel (51.06 mm)"], err  # the file whose curve it is named
    near = _write(tmp_path, 'base = "trail"\n[leverage]\nwheel_travel_mm = [0, 120]\nratio = [2.3995, 2.3995]\n')
    assert spec.load(str(near)).leverage.full_stroke == pytest.approx(0.120 / 2.3995, rel=1e-12)
    assert not (tmp_path / "o2").exists()


class FromOutput:
    """The four-bar solved from its output link's turn t3: the loop A + l1 e(t1) + l2 e(t2) = D + l3 e(t3)
    for (t1, t2) by fsolve, continued from the previous solution (the test's FourBar turns the input)."""

    def __init__(self, pts, a, b, c, d):
        self.p, self.names = pts, (a, b, c, d)
        A, B, C, D = (pts[n] for n in self.names)
        self.l1, self.l2, self.l3 = (float(np.hypot(*v)) for v in (B - A, C - B, C - D))
        self.t0 = (ang(B - A), ang(C - B), ang(C - D))
        self.guess = self.t0[:2]

    def solve(self, turn):
        A, D = self.p[self.names[0]], self.p[self.names[3]]
        e = lambda t: np.array([math.cos(t), math.sin(t)])  # noqa: E731
        t3 = self.t0[2] + turn

        def loop(u):
            return A + self.l1 * e(u[0]) + self.l2 * e(u[1]) - D - self.l3 * e(t3)

        sol = fsolve(loop, self.guess, xtol=1e-13)
        assert np.max(np.abs(loop(sol))) < 1e-12
        self.guess = tuple(sol)
        return sol[0] - self.t0[0], sol[1] - self.t0[1], turn


# A short link whose lower link turns back inside the travel (found by a search of random short links):
# driven from the lower link the loop cannot pass that point (the package said "the mechanism locks");
# the upper link turns one way all along.
REVERSING = dict(lower_pivot=P(-8, 37), lower_link=P(-45, 24), upper_pivot=P(-51, 243), upper_link=P(-107, 317),
                 rear_axle=P(-458, 16), shock_upper_link=P(-104, 377), shock_frame=P(110, 128))


def test_a_short_link_whose_lower_link_turns_back_is_solved_from_its_upper_link():
    pts = REVERSING
    fb = FromOutput(pts, "lower_pivot", "lower_link", "upper_link", "upper_pivot")
    A, B, D = pts["lower_pivot"], pts["lower_link"], pts["upper_pivot"]
    L0 = float(np.hypot(*(pts["shock_upper_link"] - pts["shock_frame"])))

    def state(turn):
        t1, t2, t3 = fb.solve(turn)
        b = A + rot(B - A, t1)
        axle = b + rot(pts["rear_axle"] - B, t2)
        eye = D + rot(pts["shock_upper_link"] - D, t3)
        return t1, axle, L0 - float(np.hypot(*(eye - pts["shock_frame"])))

    sign = 1.0 if state(1e-3)[1][1] > pts["rear_axle"][1] else -1.0
    fb.guess = fb.t0[:2]
    turns, lower, axles, strokes = [], [], [], []
    t = 0.0
    while True:  # the upper link turned in small steps until the shock has stroked 50 mm
        t1, axle, s = state(sign * t)
        turns.append(t), lower.append(t1), axles.append(axle), strokes.append(s)
        if s >= 0.050:
            break
        t += 2e-3
        assert t < 2.0
    lower = np.array(lower)
    assert np.any(np.diff(lower) > 0) and np.any(np.diff(lower) < 0)  # the lower link turns back
    c = lk.curves(lk.Linkage("short_link", pts), 0.050)
    assert c.driver == "upper link"
    assert c.stroke[-1] == pytest.approx(0.050, abs=1e-9)
    # the axle path and the leverage ratio against the mechanism solved here (the travel from the
    # stroke by interpolation on the fine steps; the ratio by a finite difference of the path)
    axles, strokes = np.array(axles), np.array(strokes)
    travel = axles[:, 1] - pts["rear_axle"][1]
    assert np.all(np.diff(travel) > 0)
    assert c.travel[-1] == pytest.approx(np.interp(0.050, strokes, travel), abs=2e-5)
    for i in range(0, c.travel.size, 5):
        x = np.interp(c.travel[i], travel, axles[:, 0])
        assert abs(x - c.axle_x[i]) < 1e-4  # 0.1 mm, as the other layouts
        assert c.stroke[i] == pytest.approx(np.interp(c.travel[i], travel, strokes), abs=2e-5)
    mid = (travel[1:] + travel[:-1]) / 2
    ratio = np.diff(travel) / np.diff(strokes)
    inside = (c.travel > mid[0]) & (c.travel < mid[-1])
    assert np.allclose(c.leverage_ratio[inside], np.interp(c.travel[inside], mid, ratio), rtol=5e-3)


def _points(pts):
    return "\n".join(f"{k}_mm = [{v[0] / MM:g}, {v[1] / MM:g}]" for k, v in pts.items())


def _moved(pts, **where):
    return {**pts, **{k: P(*v) for k, v in where.items()}}


SP_LINE = SINGLE["main_pivot"] + 1.7 * (SINGLE["main_pivot"] - SINGLE["shock_swingarm"])  # on the shock's line


@pytest.mark.parametrize("kind,pts,said", [
    ("single_pivot", _moved(SINGLE, rear_axle=(-30, 75)),
     "linkage.main_pivot_mm and linkage.rear_axle_mm: 0 mm apart: the swingarm has no length"),
    ("short_link", _moved(SHORT, lower_link=(-60, 260)),
     "linkage.lower_link_mm and linkage.upper_pivot_mm: 0 mm apart"),
    ("single_pivot", _moved(SINGLE, shock_frame=(-150, 150.5)),
     "linkage.shock_swingarm_mm and linkage.shock_frame_mm: 0.5 mm apart: the shock has no length"),
    ("horst_link", _moved(HORST, horst_pivot=(-40, 70)),
     "linkage.main_pivot_mm and linkage.horst_pivot_mm: 0 mm apart: the chainstay has no length"),
    ("horst_link", _moved(HORST, seatstay_rocker=(-50, 380)),
     "linkage.rocker_pivot_mm and linkage.seatstay_rocker_mm: 0 mm apart: the rocker has no length"),
    ("short_link", _moved(SHORT, lower_pivot=(0, 0), lower_link=(-20, 20), upper_link=(-80, 80),
                          upper_pivot=(-200, 200)),
     "linkage.lower_pivot_mm, linkage.lower_link_mm, linkage.upper_link_mm, linkage.upper_pivot_mm: on one line"),
    ("single_pivot", {**SINGLE, "shock_frame": SP_LINE},
     "linkage.shock_frame_mm, linkage.shock_swingarm_mm and linkage.main_pivot_mm: on one line"),
    ("single_pivot", _moved(SINGLE, rear_axle=(-30, -300)),
     "linkage.rear_axle_mm: straight above or below linkage.main_pivot_mm"),
    ("linkage_driven_single_pivot", _moved(DRIVEN, shock_rocker=(-20, 330)),
     "linkage.rocker_pivot_mm and linkage.shock_rocker_mm: 0 mm apart: the shock's eye on the pivot"),
    ("horst_link", _moved(HORST, seatstay_rocker=(-50 - 380 * 0.2, 380 - 60 * 0.2)),
     "linkage.main_pivot_mm to linkage.horst_pivot_mm and linkage.rocker_pivot_mm to linkage.seatstay_rocker_mm: "
     "parallel at full extension"),
])
def test_degenerate_points_are_refused_in_one_line_naming_the_keys(tmp_path, capsys, kind, pts, said):
    """Coincident points, zero-length members, collinear links (each was a 35-40 line traceback or a
    false reason): one line naming the keys, exit 2, nothing written, by ``mtbmj linkage`` and ``mtbmj bike``."""
    from mtbmj.cli import main

    bike = _write(tmp_path, f'base = "trail"\n[shock]\nstroke_mm = 50.0\n[linkage]\nkind = "{kind}"\n{_points(pts)}\n')
    for argv in (["linkage", str(bike)], ["bike", str(bike), "flat", "--speed", "4", "--duration", "0.1"]):
        out = tmp_path / "out"
        assert main(argv + ["--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("mtbmj: error: ") and said in err[0], err
        assert not out.exists()


def test_a_travel_under_a_millimetre_keeps_the_caliper_s_ratio():
    """A 0.1 mm stroke gives 0.3 mm of travel: two rows, where the caliper's ratio (a second-order
    gradient needing three) ended in a traceback; it is the ratio at full extension of the same
    Horst link solved over its whole travel."""
    c = lk.curves(lk.Linkage("horst_link", HORST, brake_on="seatstay"), 1e-4)
    assert c.travel.size == 2
    pivot = lk.fitted_pivot(lk.Linkage("horst_link", HORST), lk.curves(lk.Linkage("horst_link", HORST), 0.05))
    whole = lk.caliper_ratio(lk.curves(lk.Linkage("horst_link", HORST, brake_on="seatstay"), 0.05), pivot)
    tiny = lk.caliper_ratio(c, pivot)
    assert np.all(np.isfinite(tiny))
    assert tiny[0] == pytest.approx(whole[0], rel=2e-3)

"""A bike from a geometry chart (issue 40 item 1): [geometry] with head angle, wheelbase, chainstay,
BB drop and offset gives the frame's axles; reach, stack, head tube and axle-to-crown find the
front axle a second way and must agree. The chart's numbers are checked here on the built bike
through MuJoCo's own kinematics (test_bike_geometry's level-axle head angle) and the summary."""
from __future__ import annotations

import math

import pytest

import mtbmj
from mtbmj.bike import run as bike_run
from mtbmj.config import ConfigError
from helpers import level_head_angle

CHART = {"head_angle_deg": 64.5, "wheelbase_mm": 1240.0, "chainstay_mm": 440.0, "bb_drop_mm": 30.0,
         "fork_offset_mm": 44.0}


def _reach_stack(head_tube=110.0, crown=560.0):
    """Reach and stack that agree with CHART: the head tube's top, up the steering axis from the
    front axle CHART gives (its offset back, then head tube and axle-to-crown up the axis)."""
    a = math.radians(CHART["head_angle_deg"])
    front = (CHART["wheelbase_mm"] - math.sqrt(CHART["chainstay_mm"] ** 2 - CHART["bb_drop_mm"] ** 2),
             CHART["bb_drop_mm"])
    along, off = head_tube + crown, CHART["fork_offset_mm"]
    return (front[0] - along * math.cos(a) - off * math.sin(a), front[1] + along * math.sin(a) - off * math.cos(a))


def _file(tmp_path, chart: dict, extra: str = "", name: str = "chart.toml") -> str:
    lines = ['base = "trail"', extra, "[geometry]"] + [f"{k} = {v!r}" for k, v in chart.items()]
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_a_chart_builds_the_bike_it_describes(tmp_path):
    path = _file(tmp_path, CHART)
    p = bike_run.prepare(path, "flat", 4.0)
    assert level_head_angle(p) == pytest.approx(64.5, abs=1e-9)
    (fx, fz), (rx, rz) = p.spec.front_axle, p.spec.rear_axle
    assert math.hypot(fx - rx, fz - rz) * 1e3 == pytest.approx(1240.0, abs=1e-9)
    assert math.hypot(rx, rz) * 1e3 == pytest.approx(440.0, abs=1e-9) and rz * 1e3 == pytest.approx(30.0)
    g = mtbmj.run_bike(path, "flat", speed_m_per_s=4.0, duration=0.05).summary["geometry"]["chart"]
    assert g["wheelbase_mm"] == pytest.approx(1240.0) and g["head_angle_deg"] == pytest.approx(64.5)
    assert g["bb_height_mm"] == pytest.approx(p.front_tire.radius * 1e3 - 30.0)


def test_reach_and_stack_that_agree_are_taken_and_ones_that_do_not_are_refused(tmp_path):
    reach, stack = _reach_stack()
    full = {**CHART, "reach_mm": round(reach, 1), "stack_mm": round(stack, 1), "head_tube_mm": 110.0,
            "fork_length_mm": 560.0}
    mtbmj.bike.spec.load(_file(tmp_path, full))  # within 5 mm (the rounding: 0.1 mm)
    with pytest.raises(ConfigError, match=r"geometry: reach 472\.9, stack 635\.8, .* 20 mm from where wheelbase 1240"):
        mtbmj.bike.spec.load(_file(tmp_path, {**full, "stack_mm": round(stack, 1) + 20.0}))
    with pytest.raises(ConfigError, match="geometry.stack_mm: needed with"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "reach_mm": 470.0}))


def test_a_misspelt_chart_key_is_refused_naming_it(tmp_path):
    with pytest.raises(ConfigError, match=r"geometry.wheel_base_mm: unknown key \(known: head_angle_deg, wheelbase_mm"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "wheel_base_mm": 1240.0}))
    with pytest.raises(ConfigError, match=r"geometry.wheel_base_mm: unknown key"):
        mtbmj.bike.spec.load("trail", {"geometry.wheel_base_mm": 1240.0})


def test_a_chart_and_axles_in_one_file_are_refused(tmp_path):
    with pytest.raises(ConfigError, match="two ways"):
        mtbmj.bike.spec.load(_file(tmp_path, CHART, "[bike]\nfront_axle_mm = [800.0, 10.0]"))


# --- the rest of a chart (issue 40 item 1): the bottom bracket as a height, the wheels' size, the
# travels, the seat angle and saddle; and the presets written as charts


def _fork(path, overrides=None):
    return bike_run.setups(mtbmj.bike.spec.load(path, overrides))[0]


def test_a_bb_height_on_wheels_of_a_size_gives_the_drop_and_the_tyres(tmp_path):
    chart = {k: v for k, v in CHART.items() if k != "bb_drop_mm"}
    path = _file(tmp_path, {**chart, "bb_height_mm": 345.0, "wheel_diameter_mm": 760.0})
    spec = mtbmj.bike.spec.load(path)
    assert spec.rear_axle[1] * 1e3 == pytest.approx(380.0 - 345.0) == pytest.approx(spec.front_axle[1] * 1e3)
    assert _fork(path).tire_radius == pytest.approx(0.380)
    g = mtbmj.run_bike(path, "flat", speed_m_per_s=4.0, duration=0.02).summary["geometry"]["chart"]
    assert g["bb_height_mm"] == pytest.approx(345.0)
    # both given and agreeing (within 2 mm) are taken; apart, refused naming both
    mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "bb_height_mm": 351.0, "wheel_diameter_mm": 760.0}))
    with pytest.raises(ConfigError, match=r"bb_height_mm 340 on wheels of 760 mm puts the bottom bracket 40 mm below "
                                          r"the axles, but bb_drop_mm is 30"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "bb_height_mm": 340.0, "wheel_diameter_mm": 760.0}))
    with pytest.raises(ConfigError, match="geometry.bb_height_mm: needs geometry.wheel_diameter_mm"):
        mtbmj.bike.spec.load(_file(tmp_path, {**chart, "bb_height_mm": 345.0}))
    with pytest.raises(ConfigError, match="geometry.bb_drop_mm: missing"):
        mtbmj.bike.spec.load(_file(tmp_path, chart))


def test_the_chart_sets_the_forks_travel_and_length_as_the_file_would(tmp_path):
    path = _file(tmp_path, {**CHART, "fork_travel_mm": 150.0, "fork_length_mm": 555.0})
    fork = _fork(path)
    assert (fork.travel, fork.fork_length) == (pytest.approx(0.150), pytest.approx(0.555))
    with pytest.raises(ConfigError, match=r"geometry.fork_travel_mm and \[fork.set\] 'fork.travel_mm' give it two ways"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "fork_travel_mm": 150.0},
                                   '[fork.set]\n"fork.travel_mm" = 160.0', name="twice.toml"))
    # a file on it changes the fork again; --set geometry.fork_travel_mm is one more file
    later = tmp_path / "later.toml"
    later.write_text(f'base = "{path}"\n[fork.set]\n"fork.travel_mm" = 140.0\n')
    assert _fork(str(later)).travel == pytest.approx(0.140)
    assert _fork(path, {"geometry.fork_travel_mm": 160}).travel == pytest.approx(0.160)


def _travel_at_stroke_closed_form(r0, r1, w1, stroke):
    """A two-point leverage table, LR = r0 + (r1 - r0) w / w1: ds = dw / LR integrates to
    s = (w1 / (r1 - r0)) ln(LR(w) / r0), so w = r0 (exp(s (r1 - r0) / w1) - 1) w1 / (r1 - r0);
    past w1 the last ratio r1 carries on."""
    b = (r1 - r0) / w1
    s1 = math.log(r1 / r0) / b
    if stroke <= s1:
        return r0 * math.expm1(b * stroke) / b
    return w1 + (stroke - s1) * r1


@pytest.mark.filterwarnings("ignore:leverage. the table covers")  # the 56 mm stroke past the table's end, as meant
def test_the_rear_travel_is_checked_against_the_strokes_travel(tmp_path):
    lev = "[leverage]\nwheel_travel_mm = [0.0, 150.0]\nratio = [3.0, 2.5]\n[shock]\nstroke_mm = {}\n"
    for stroke in (54.7, 56.0):  # inside the table (54.69 mm covers it) and 1.3 mm past its end
        has = _travel_at_stroke_closed_form(3.0, 2.5, 150.0, stroke)
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "rear_travel_mm": round(has)}, lev.format(stroke)))
        with pytest.raises(ConfigError, match=rf"geometry.rear_travel_mm: {round(has) - 8} mm, but the shock's "
                                              rf"{stroke:g} mm stroke .* gives {has:.1f} mm of wheel travel"):
            mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "rear_travel_mm": round(has) - 8}, lev.format(stroke)))
    # the preset's table, inverted here by a root finder
    from scipy.optimize import brentq
    leverage = mtbmj.bike.spec.load("sst").leverage
    for s in (0.01, 0.0333, 0.0647):
        w = brentq(lambda w: leverage.stroke(w) - s, 0.0, 0.3, xtol=1e-12)
        assert leverage.travel_at_stroke(s) == pytest.approx(w, abs=1e-9)


def test_a_seat_angle_and_saddle_height_seat_the_rider(tmp_path):
    seat = {"seat_tube_angle_deg": 76.0, "saddle_height_mm": 750.0}
    path = _file(tmp_path, {**CHART, **seat}, "[rider]\nseated_com_from_saddle_mm = [70.0, 190.0]")
    a = math.radians(76.0)
    want = (-750.0 * math.cos(a) + 70.0, 750.0 * math.sin(a) + 190.0)
    assert [v * 1e3 for v in mtbmj.bike.spec.load(path).rider.seated_com] == pytest.approx(want, abs=1e-9)
    p = bike_run.prepare(path, "flat", 4.0, seated=True)
    assert [v * 1e3 for v in p.spec.rider.com] == pytest.approx(want, abs=1e-9)
    # the seated rider given twice in one file; a later file's own seated rider; --set
    with pytest.raises(ConfigError, match="give the seated rider two ways"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, **seat}, "[rider]\nseated_com_mm = [-90.0, 900.0]",
                                   name="twice.toml"))
    later = tmp_path / "later.toml"
    later.write_text(f'base = "{path}"\n[rider]\nseated_com_mm = [-80.0, 910.0]\n')
    assert mtbmj.bike.spec.load(str(later)).rider.seated_com == pytest.approx((-0.080, 0.910))
    assert mtbmj.bike.spec.load(path, {"rider.seated_com_mm": [-85, 905]}).rider.seated_com == pytest.approx(
        (-0.085, 0.905))
    # a chart of its own without a saddle keeps where the base's saddle seated the rider
    later.write_text(f'base = "{path}"\n[geometry]\n' + "\n".join(f"{k} = {v!r}" for k, v in CHART.items()) + "\n")
    assert [v * 1e3 for v in mtbmj.bike.spec.load(str(later)).rider.seated_com] == pytest.approx(want, abs=1e-9)
    with pytest.raises(ConfigError, match="geometry.saddle_height_mm: needed with geometry.seat_tube_angle_deg"):
        mtbmj.bike.spec.load(_file(tmp_path, {**CHART, "seat_tube_angle_deg": 76.0}))


def test_a_chart_bike_refuses_a_set_of_its_axles_and_takes_one_of_its_chart(tmp_path):
    with pytest.raises(ConfigError, match=r"--set bike.head_angle_deg: this bike's frame is given by its geometry chart"):
        mtbmj.bike.spec.load("sst", {"bike.head_angle_deg": 65.0})
    p = bike_run.prepare("sst", "flat", 4.0, overrides={"geometry.head_angle_deg": 65.0})
    assert level_head_angle(p) == pytest.approx(65.0, abs=1e-9)


# The presets before they were written as charts (frame coordinates with their axles at different
# heights): the charts must describe the same bikes, every point turned level about the bottom
# bracket, to the 0.1 mm the preset files are rounded to
OLD = {"sst": {"front": (815.0, 5.0), "rear": (-440.0, 25.0), "pivot": (-30.0, 75.0), "frame_com": (300.0, 300.0),
               "com": (80.0, 950.0), "seated": (-90.0, 920.0), "bars": (460.0, 660.0), "head": 63.5},
       "trail": {"front": (790.0, 10.0), "rear": (-435.0, 20.0), "pivot": (-20.0, 70.0), "frame_com": (300.0, 300.0),
                 "com": (80.0, 950.0), "seated": (-90.0, 920.0), "bars": (460.0, 660.0), "head": 65.5}}


@pytest.mark.parametrize("name", ["sst", "trail"])
def test_the_presets_are_charts_of_the_bikes_they_were(name):
    table, _ = mtbmj.bike.spec.read_table(name)
    assert set(table["geometry"]) >= {"head_angle_deg", "wheelbase_mm", "chainstay_mm", "reach_mm", "stack_mm",
                                      "seat_tube_angle_deg", "fork_travel_mm", "rear_travel_mm"}
    old = OLD[name]
    (fx, fz), (rx, rz) = old["front"], old["rear"]
    turn = math.atan2(rz - fz, fx - rx)  # the old frame's nose-up pitch standing on flat ground

    def level(p):
        return (p[0] * math.cos(turn) - p[1] * math.sin(turn), p[0] * math.sin(turn) + p[1] * math.cos(turn))

    spec = mtbmj.bike.spec.load(name)
    mm = lambda p: [v * 1e3 for v in p]  # noqa: E731
    for now, before, tol in ((spec.front_axle, old["front"], 0.15), (spec.rear_axle, old["rear"], 0.15),
                             (spec.pivot, old["pivot"], 0.06), (spec.frame_com, old["frame_com"], 0.06),
                             (spec.rider.com, old["com"], 0.06), (spec.rider.seated_com, old["seated"], 0.06),
                             ((spec.rider.arm_x, spec.rider.arm_z), old["bars"], 0.06)):
        assert mm(now) == pytest.approx(level(before), abs=tol)
    assert math.degrees(spec.head_angle) == pytest.approx(old["head"])  # the chart's, the frame now level


def test_axles_hardpoints_or_a_rear_end_on_a_chart_preset_take_its_frame(tmp_path):
    """A file on a chart preset that gives an axle keeps the chart's other axle and head angle; one
    that gives its own leverage curve is not held to the base chart's rear travel; one that gives
    hardpoints takes the chart's front axle (the linkage's own rear axle)."""
    sst = mtbmj.bike.spec.load("sst")
    axle = tmp_path / "axle.toml"
    axle.write_text('base = "sst"\n[bike]\nfront_axle_mm = [820.0, 18.0]\n')
    spec = mtbmj.bike.spec.load(str(axle))
    assert spec.front_axle == pytest.approx((0.820, 0.018)) and spec.rear_axle == pytest.approx(sst.rear_axle)
    assert spec.head_angle == pytest.approx(sst.head_angle) and spec.rider.seated_com == pytest.approx(sst.rider.seated_com)
    curve = tmp_path / "curve.toml"  # 150 mm of wheel travel where the trail chart says 120
    curve.write_text('base = "trail"\n[leverage]\nwheel_travel_mm = [0.0, 150.0]\nratio = [3.0, 3.0]\n')
    assert mtbmj.bike.spec.load(str(curve)).leverage.full_travel == pytest.approx(0.150)
    horst = mtbmj.bike.spec.load("docs/bikes/horst_link.toml")
    assert horst.front_axle == pytest.approx(mtbmj.bike.spec.load("trail").front_axle)
    assert horst.rear_axle == pytest.approx((-0.440, 0.025))


def test_a_set_of_a_charts_key_on_a_bike_given_by_its_axles(tmp_path):
    """A bike file of axles has no chart to change: --set geometry.fork_travel_mm still sets the
    fork's travel (what the key sets on a chart), a key that places a chart's frame is refused
    naming the axles' keys, on the command line in one line with exit status 2."""
    from mtbmj.cli import main

    axles = tmp_path / "axles.toml"
    axles.write_text('base = "sst"\n[bike]\nfront_axle_mm = [815.0, 18.0]\nrear_axle_mm = [-440.3, 18.0]\n'
                     'head_angle_deg = 63.5\nfork_offset_mm = 44.0\n')
    assert _fork(str(axles), {"geometry.fork_travel_mm": 160}).travel == pytest.approx(0.160)
    with pytest.raises(ConfigError, match=r"--set geometry.head_angle_deg: this bike's frame is given by its axles"):
        mtbmj.bike.spec.load(str(axles), {"geometry.head_angle_deg": 65})
    assert main(["bike", str(axles), "flat", "--speed", "3", "--set", "geometry.wheelbase_mm=1200",
                 "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()

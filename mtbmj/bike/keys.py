"""Every key of a bike file: its meaning, what is valid and what is plausible.

``KEYS`` maps a dotted key to (meaning, valid, plausible): ``plausible`` is a (low, high) range of
the number (for a point [x, z], ``((x_low, x_high), (z_low, z_high))``; for a list, the range of
its values), or None. A value outside its plausible range is most likely a unit mistake (metres
for millimetres) or outside what any bike has: :func:`warnings` gives one line for each,
``mtbmj.bike.spec.load`` issues them as warnings (the run proceeds). Geometry given in metres
where millimetres are meant is refused outright (:func:`metres_for_millimetres`): the geometry
checks would otherwise refuse it for a reason that does not name the mistake.

The ranges are *assumed*: what trail, enduro and downhill bikes and adult riders span, with room
(a 5 kg or a 500 kg rider, a 44 m fork offset fall outside). ``docs/configuration.md`` prints them
(``docs/configuration.py`` reads this table).
"""
from __future__ import annotations

import math

from mtbmj import limits
from mtbmj.bike.chart import RANGES as _CHART_RANGES
from mtbmj.config import unit_of

POINT_MM = "two numbers [x, z], mm"


def _chart_range(name: str) -> str:
    """A chart key's valid range as the configuration reference prints it (mtbmj.bike.chart.RANGES)."""
    low, high = _CHART_RANGES[name]
    return f"{low:g}-{high:g}"


KEYS: dict[str, tuple[str, str, object]] = {
    "description": ("One line saying what the bike is.", "text", None),
    "reading": ("Where the numbers come from; informational.", "text", None),
    "base": ("A bike preset (sst, trail) or another bike file whose keys this file overrides.", "text", None),
    "bike.head_angle_deg": ("Head angle from the horizontal, the frame at full extension; a [geometry] chart "
                            "sets it (the presets give one).", "45-90", (58.0, 76.0)),
    "bike.fork_offset_mm": ("Fork offset (rake): the axle ahead of the steering axis, perpendicular to it; a "
                            "[geometry] chart sets it.", ">= 0", (20.0, 70.0)),
    "bike.front_axle_mm": ("Front axle in frame coordinates (origin the bottom bracket, x forward, z up) at full "
                           "extension; a [geometry] chart sets it (the presets give one).", POINT_MM,
                           ((450.0, 1100.0), (-150.0, 250.0))),
    "bike.rear_axle_mm": ("Rear axle in frame coordinates at full extension; a [geometry] chart sets it.", POINT_MM,
                          ((-560.0, -380.0), (-150.0, 250.0))),
    "bike.pivot_mm": ("Main pivot in frame coordinates: the swingarm turns about it.", POINT_MM,
                      ((-250.0, 250.0), (-50.0, 400.0))),
    "bike.frame_mass_kg": ("Frame with shock, stanchions, crown, bars and drivetrain (all that moves with the "
                           "frame but the rider).", "> 0", (3.0, 25.0)),
    "bike.frame_com_mm": ("The frame's centre of mass in frame coordinates.", POINT_MM,
                          ((-300.0, 700.0), (-100.0, 800.0))),
    "bike.frame_inertia_kg_m2": ("The frame's pitch inertia about its centre of mass.", "> 0", (0.1, 10.0)),
    "bike.swingarm_mass_kg": ("Rear triangle, brake and cassette.", "> 0", (0.5, 8.0)),
    "bike.swingarm_inertia_kg_m2": ("The swingarm's inertia about its centre of mass (midway between pivot and "
                                    "axle).", "> 0", (0.005, 2.0)),
    "bike.fork_lower_mass_kg": ("Fork lower legs, caliper and axle (unsprung, at the front axle).", "> 0",
                                (0.3, 5.0)),
    "bike.front_wheel_mass_kg": ("Front wheel with tyre and rotor.", "> 0", (0.8, 5.0)),
    "bike.rear_wheel_mass_kg": ("Rear wheel with tyre, rotor and cassette.", "> 0", (0.8, 6.0)),
    "bike.wheel_inertia_kg_m2": ("A wheel's spin inertia (no effect on the planar motion).", "> 0", (0.02, 0.6)),
    "leverage.wheel_travel_mm": ("Rear wheel travel of the leverage table, from 0, strictly increasing.",
                                 "list of numbers", (0.0, 260.0)),
    "leverage.ratio": ("Leverage ratio (wheel travel per shock stroke) at each wheel travel of the table.",
                       "list of numbers > 0", (1.5, 4.5)),
    "leverage.csv": ("The leverage curve as a CSV instead of the two lists: wheel travel (mm) and leverage ratio, "
                     "two numbers a row (comma, semicolon or tab; header lines skipped), as linkage tools and "
                     "telemetry apps export it; a path relative to the bike file.", "text", None),
    "shock.stroke_mm": ("The shock's stroke; the leverage table must not need more.", "> 0", (25.0, 90.0)),
    "shock.config": ("The shock's laws: a configuration of the fork schema (preset or file), read in shock "
                     "coordinates.", "text", None),
    "shock.spring": ("The shock's spring as sold: \"coil\" or \"air\" (with the keys below; each replaces the same "
                     "setting in shock.set, and the other kind's spring keys there are dropped).", "coil, air", None),
    "shock.spring_rate_lb_per_in": ("coil: the spring's rate as printed on it (1 lb/in = 0.17513 N/mm).", "> 0",
                                    (150.0, 1000.0)),
    "shock.spring_rate_N_per_mm": ("coil: the spring's rate in N/mm (instead of lb/in).", "> 0", (25.0, 175.0)),
    "shock.preload_mm": ("coil: the preload collar's compression of the spring at full extension.", ">= 0",
                         (0.0, 10.0)),
    "shock.pressure_psi": ("air: the positive chamber's gauge pressure at full extension, as the pump reads it.",
                           "> 0", (50.0, 350.0)),
    "shock.piston_diameter_mm": ("air: the air can's bore (the piston's diameter).", "> 0", (20.0, 60.0)),
    "shock.positive_volume_cm3": ("air: the positive chamber at full extension without volume spacers.", "> 0",
                                  (20.0, 400.0)),
    "shock.negative_volume_cm3": ("air: the negative chamber at full extension (0: none).", ">= 0", (0.0, 400.0)),
    "shock.volume_spacers": ("air: volume spacers (bands, tokens) in the positive chamber.", "whole >= 0",
                             (0.0, 8.0)),
    "shock.spacer_volume_cm3": ("air: the volume one spacer takes out.", "> 0", (1.0, 30.0)),
    "shock.compression_N_s_per_m": ("The damper's compression coefficient at the shaft (a bilinear damper; with "
                                    "rebound_N_s_per_m).", ">= 0", (300.0, 30000.0)),
    "shock.rebound_N_s_per_m": ("The damper's rebound coefficient at the shaft.", ">= 0", (300.0, 40000.0)),
    "shock.set": ("Keys of the shock's configuration changed for this bike: fork.* but fork.length_mm.",
                  "table", None),
    "fork.config": ("The fork's laws, tyre and integrator: a configuration of the fork schema (preset or file).",
                    "text", None),
    "fork.set": ("Keys of the fork's configuration changed for this bike: fork.*, tire.*, sled.gravity_m_per_s2, "
                 "solver.integrator.", "table", None),
    "rider.mass_kg": ("The whole rider, kit included.", "> 0", (30.0, 150.0)),
    "rider.limbs_share_percent": ("The share of the rider's mass in feet, shanks, hands and forearms, which move "
                                  "with the bike (default de Leva's 15.86 %).", "0-50", (10.0, 25.0)),
    "rider.com_mm": ("The rider's centre of mass standing at rest, frame coordinates; between pedals and bars in x.",
                     POINT_MM, ((-250.0, 450.0), (500.0, 1400.0))),
    "rider.seated_com_mm": ("The rider's centre of mass seated on the saddle, frame coordinates (optional): the "
                            "seated rider of `fit bounce --bike` (a seat slam), held rigid on the frame.",
                            POINT_MM, ((-450.0, 300.0), (500.0, 1400.0))),
    "rider.seated_com_from_saddle_mm": ("With a chart's saddle (geometry.seat_tube_angle_deg): where the seated "
                                        "rider's centre of mass lies from the saddle; it sets rider.seated_com_mm "
                                        "(a file giving both is refused).", POINT_MM,
                                        ((-150.0, 250.0), (50.0, 400.0))),
    "rider.height_m": ("The whole rider's stature (default 1.78 m): the active rider's segment lengths (de Leva's "
                       "table scaled; `--rider active`). The passive rider does not read it; a run of it says so in "
                       "a warning line.", "1.2-2.3", (1.5, 2.05)),
    "rider.pitch_inertia_kg_m2": ("The rider's body's pitch inertia about its centre of mass.", "> 0", (1.0, 25.0)),
    "rider.pedals_mm": ("Where the legs meet the frame (the feet), frame coordinates.", POINT_MM,
                        ((-150.0, 150.0), (-100.0, 150.0))),
    "rider.bars_mm": ("Where the arms meet the frame (the grips), frame coordinates.", POINT_MM,
                      ((250.0, 700.0), (400.0, 900.0))),
    "rider.leg_length_mm": ("Pedals to hips, vertical, at rest.", "> 0", (500.0, 1200.0)),
    "rider.arm_length_mm": ("Bars to shoulders, vertical, at rest.", "> 0", (200.0, 800.0)),
    "rider.leg_stiffness_N_per_mm": ("Both legs' stiffness.", "> 0", (2.0, 150.0)),
    "rider.leg_damping_N_s_per_m": ("Both legs' damping.", ">= 0", (20.0, 5000.0)),
    "rider.arm_stiffness_N_per_mm": ("Both arms' stiffness.", "> 0", (0.5, 80.0)),
    "rider.arm_damping_N_s_per_m": ("Both arms' damping.", ">= 0", (5.0, 3000.0)),
    "geometry.head_angle_deg": ("A geometry chart's head angle (both wheels on flat ground at full extension); "
                                "with [geometry] the frame's axles and head angle come from the chart "
                                "(mtbmj/bike/chart.py).", _chart_range("head_angle_deg"), (58.0, 76.0)),
    "geometry.wheelbase_mm": ("The chart's wheelbase: axle to axle.", _chart_range("wheelbase_mm"), (1000.0, 1400.0)),
    "geometry.chainstay_mm": ("The chart's chainstay: bottom bracket to rear axle, straight.",
                              _chart_range("chainstay_mm"), (400.0, 480.0)),
    "geometry.bb_drop_mm": ("The chart's bottom-bracket drop below the axles (or give bb_height_mm).",
                            _chart_range("bb_drop_mm"), (-10.0, 60.0)),
    "geometry.bb_height_mm": ("The chart's bottom-bracket height above the ground, unloaded, with "
                              "wheel_diameter_mm (the drop is their radius less it; with bb_drop_mm too, within "
                              "2 mm of it).", _chart_range("bb_height_mm"), (300.0, 380.0)),
    "geometry.fork_offset_mm": ("The fork's offset.", _chart_range("fork_offset_mm"), (20.0, 70.0)),
    "geometry.reach_mm": ("The chart's reach (with stack, head tube and axle-to-crown: the front axle a second "
                          "way, checked within 5 mm; a --set of a key that places the frame drops this check).",
                          _chart_range("reach_mm"), (380.0, 560.0)),
    "geometry.stack_mm": ("The chart's stack.", _chart_range("stack_mm"), (560.0, 680.0)),
    "geometry.head_tube_mm": ("The chart's head tube length (top to the crown).",
                              _chart_range("head_tube_mm"), (80.0, 170.0)),
    "geometry.fork_length_mm": ("The fork's axle-to-crown along the steering axis; sets the fork's fork.length_mm "
                                "(a file giving both is refused).", _chart_range("fork_length_mm"), (480.0, 620.0)),
    "geometry.wheel_diameter_mm": ("The tyres' outer diameter (both wheels; 29 x 2.4 in: about 750 mm); sets the "
                                   "fork configuration's tire.radius_mm to half of it.",
                                   _chart_range("wheel_diameter_mm"), (600.0, 790.0)),
    "geometry.fork_travel_mm": ("The fork's travel; sets the fork's fork.travel_mm (a file giving both is "
                                "refused).", _chart_range("fork_travel_mm"), (80.0, 220.0)),
    "geometry.rear_travel_mm": ("The rear wheel's travel; checked against the travel the shock's stroke gives "
                                "through the leverage curve or the linkage, within 5 mm.",
                                _chart_range("rear_travel_mm"), (80.0, 220.0)),
    "geometry.seat_tube_angle_deg": ("The effective seat-tube angle from the horizontal, at saddle_height_mm: with it "
                                     "the saddle, and the seated rider's centre of mass "
                                     "rider.seated_com_from_saddle_mm from it.",
                                     _chart_range("seat_tube_angle_deg"), (70.0, 82.0)),
    "geometry.saddle_height_mm": ("Bottom bracket to the saddle's top along the effective seat angle.",
                                  _chart_range("saddle_height_mm"), (600.0, 900.0)),
    "linkage.kind": ("The rear end's layout from hardpoints: single_pivot, linkage_driven_single_pivot, horst_link "
                     "or short_link (docs/bike.md, 'The rear end from hardpoints'); its points set bike.pivot_mm, "
                     "bike.rear_axle_mm and the leverage table, so a file giving [leverage] or bike.pivot_mm beside "
                     "it is refused.", "one of the four", None),
    **{f"linkage.{name}_mm": (meaning, POINT_MM, ((-700.0, 700.0), (-200.0, 800.0))) for name, meaning in (
        ("main_pivot", "single pivot, linkage-driven single pivot, Horst link: where the swingarm or chainstay "
                       "turns on the frame."),
        ("rear_axle", "Every layout: the rear axle at full extension (with bike.rear_axle_mm or a chart: within "
                      "1 mm of it)."),
        ("shock_frame", "Every layout: the shock's eye on the front triangle."),
        ("shock_swingarm", "single pivot: the shock's eye on the swingarm."),
        ("swingarm_link", "linkage-driven single pivot: where the link meets the swingarm."),
        ("rocker_pivot", "linkage-driven single pivot, Horst link: where the rocker turns on the frame."),
        ("rocker_link", "linkage-driven single pivot: where the link meets the rocker."),
        ("shock_rocker", "linkage-driven single pivot, Horst link: the shock's eye on the rocker."),
        ("horst_pivot", "Horst link: the chainstay-seatstay pivot ahead of the axle."),
        ("seatstay_rocker", "Horst link: where the seatstay meets the rocker."),
        ("lower_pivot", "short link: where the lower link turns on the frame."),
        ("lower_link", "short link: where the lower link meets the rear triangle."),
        ("upper_pivot", "short link: where the upper link turns on the frame."),
        ("upper_link", "short link: where the upper link meets the rear triangle."),
        ("shock_upper_link", "short link: the shock's eye on the upper link."))},
    "linkage.chainring_teeth": ("Chainring teeth for anti-squat and pedal kickback (default 32).", "9-60",
                                (26.0, 40.0)),
    "linkage.cog_teeth": ("Cog teeth for anti-squat and pedal kickback (default 24, a middle cog; assumed).",
                          "9-60", (9.0, 52.0)),
    "linkage.brake_on": ("The link carrying the rear caliper, for anti-rise: swingarm (single pivots), seatstay "
                         "(default) or chainstay (Horst link), rear_triangle (short link).", "text", None),
    "linkage.com_height_mm": ("The centre of mass over the ground for anti-squat and anti-rise (default: the bike's "
                              "and rider's at full extension, frame level).", "300-2000", (700.0, 1400.0)),
    "sensors.fork_arm_mm": ("The fork sensor's arm (two equal arms, the fork's stroke as the base): the telemetry "
                            "recorder's calibration, read by mtbmj telemetry and reconstruct with --bike.", "> 0",
                            (30.0, 400.0)),
    "sensors.fork_max_mm": ("The fork sensor's base at full extension.", "> 0, < 2 x fork_arm_mm", (30.0, 700.0)),
    "sensors.shock_arm1_mm": ("The shock sensor's first arm (with the second, a triangle whose third side is the "
                              "shock's eye-to-eye).", "> 0", (20.0, 400.0)),
    "sensors.shock_arm2_mm": ("The shock sensor's second arm.", "> 0", (20.0, 400.0)),
    "sensors.shock_max_mm": ("The shock's eye-to-eye at full extension, as the sensor measures it.",
                             "> 0, a closing triangle", (100.0, 400.0)),
    "drive.push_N": ("The rider drive's largest forward force at the rear tyre.", ">= 0", (100.0, 2500.0)),
    "drive.power_W": ("The rider drive's largest power.", ">= 0", (100.0, 2500.0)),
    "drive.brake_N": ("The rider drive's largest braking force.", ">= 0", (100.0, 2500.0)),
    "drive.chainring_teeth": ("The chainring's teeth: with drive.cog_teeth, the drive goes through the chain (its "
                              "pull on the rear axle along the upper run, its reaction on the frame at the "
                              "chainring), so anti-squat acts; without them, a hub drive reacted by the swingarm.",
                              "20-60", (22.0, 52.0)),
    "drive.cog_teeth": ("The cog's teeth (with drive.chainring_teeth).", "9-60", (9.0, 52.0)),
    "drive.chain": ("false: the drive's couple on the swingarm (a hub drive, as a hub motor's) although the "
                    "sprockets are given (the presets drive through a 32 x 24 chain); true (the default): through "
                    "the chain.", "true, false", None),
    "drive.traction": ("The drive's force at most this times the rear tyre's load.", ">= 0", (0.3, 1.5)),
}

GEOMETRY_POINTS = ("bike.front_axle_mm", "bike.rear_axle_mm", "bike.pivot_mm")


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def metres_for_millimetres(table: dict) -> str | None:
    """The one-line refusal when the frame's points are given in metres (every coordinate of the
    axles and the pivot within 3 in size, where millimetres make them hundreds; likewise every
    point of a ``[linkage]``), else None."""
    points = [table.get("bike", {}).get(k.split(".")[1]) for k in GEOMETRY_POINTS]
    values = [x for p in points if isinstance(p, list) for x in p if _number(x)]
    if len(values) == 6 and max(abs(x) for x in values) < 3.0:
        return (f"bike.front_axle_mm, bike.rear_axle_mm, bike.pivot_mm: {points[0]}, {points[1]}, {points[2]} "
                f"look like metres; these keys are in millimetres (e.g. {[round(x * 1000) for x in points[0]]})")
    link = table.get("linkage")
    hard = {k: v for k, v in link.items() if k.endswith("_mm") and isinstance(v, list)} if isinstance(link, dict) else {}
    values = [x for v in hard.values() for x in v if _number(x)]
    if values and max(abs(x) for x in values) < 3.0:
        name, value = next(iter(hard.items()))
        return (f"{', '.join('linkage.' + k for k in hard)}: look like metres; these keys are in millimetres "
                f"(e.g. linkage.{name} = {[round(x * 1000) for x in value if _number(x)]})")
    return None


def warnings(table: dict) -> list[str]:
    """One line per value of ``table`` (a bike file, its base merged in) outside its plausible
    range, naming the key, the value and the range."""
    out = []
    for key, (_, _, rng) in KEYS.items():
        if rng is None or "." not in key:
            continue
        section, name = key.split(".", 1)
        value = table.get(section, {}).get(name) if isinstance(table.get(section), dict) else None
        if value is None:
            continue
        # the unit the name states (N/mm, N s/m, kg, ...), else its last part (deg, W, teeth)
        unit = unit_of(key) or ("kg m2" if key.endswith("_kg_m2") else key.rsplit("_", 1)[1] if "_" in name else "")
        if isinstance(rng[0], tuple):  # a point
            if isinstance(value, list) and len(value) == 2 and all(_number(x) for x in value):
                for axis, x, (lo, hi) in zip("xz", value, rng):
                    if not lo <= x <= hi:
                        out.append(f"{key} = {value}: {axis} = {x:g} mm is outside {lo:g}-{hi:g} mm, what bikes "
                                   f"have (a unit mistake?)")
            continue
        values = value if isinstance(value, list) else [value]
        lo, hi = rng
        odd = [x for x in values if _number(x) and not lo <= x <= hi]
        if odd:
            shown = f"{odd[0]:g}" if not isinstance(value, list) else f"{odd[0]:g} (of the list)"
            # one value a unit slip brings within the range (180 lb as 180 kg, 1.8 bar as 1.8 psi): said so
            meant = "" if isinstance(value, list) else limits.slip(odd[0], unit, rng)
            out.append(f"{key} = {shown} {unit} is outside {lo:g}-{hi:g} {unit}, what bikes and riders have "
                       f"(a unit mistake?{meant})".replace("  ", " "))
    return out

"""``mtbmj linkage``: a bike's rear end from its hardpoints: leverage ratio, axle path, anti-squat,
anti-rise and pedal kickback over the wheel travel (``mtbmj.bike.linkage``)."""
from __future__ import annotations

from mtbmj.cli.common import add_out, overrides, write_and_say


def cmd_linkage(args) -> int:
    from mtbmj.bike import rear_end as linkage

    result = linkage.for_bike(args.bike, overrides(args.set), args.chainring, args.cog, args.com_height_mm)
    return write_and_say(result, args.out)


def add_parser(sub) -> None:
    p = sub.add_parser("linkage", help="a bike's rear end from its [linkage] hardpoints: leverage ratio, axle path, "
                                       "anti-squat, anti-rise, pedal kickback (CSV, figure, summary)")
    p.add_argument("bike", help="a bike file with a [linkage] table (docs/configuration.md), or a preset that has one")
    p.add_argument("--chainring", type=int, help="chainring teeth for anti-squat and kickback (default: "
                                                 "linkage.chainring_teeth, else 32)")
    p.add_argument("--cog", type=int, help="cog teeth (default: linkage.cog_teeth, else 24)")
    p.add_argument("--com-height-mm", type=float, dest="com_height_mm",
                   help="centre of mass over the ground (default: linkage.com_height_mm, else the bike's and "
                        "rider's at full extension)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a bike key first, e.g. linkage.shock_frame_mm=[160,195] (repeatable)")
    add_out(p, "out/linkage")
    p.set_defaults(func=cmd_linkage)

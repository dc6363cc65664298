"""``mtbmj roll SCENARIO --speed ... --head-angle ... --out DIR``: one rolling run, written
atomically. Bad terrain specs, a speed <= 0 and a head angle outside (45, 90] raise MtbmjError
(one line, exit status 2 from ``mtbmj.cli.main``)."""
from __future__ import annotations


from mtbmj.cli.common import Progress, add_out, overrides


def cmd_roll(args) -> int:
    from mtbmj.rolling.frontend import run_roll

    result = Progress(f"roll {args.scenario}", not args.quiet).around(
        lambda progress: run_roll(args.scenario, args.speed, args.config, args.head_angle, args.duration,
                                  overrides(args.set), progress, drive=_drive(args)))
    written = result.write(args.out, figure=not args.no_figure)
    print(f"{result.headline()}; {result.info['real_time_factor']:.1f}x real time; "
          f"wrote {len(written)} files to {args.out}")
    return 0


def _drive(args):
    """The drive the options ask for: a mode, with a rider's limits where given."""
    from mtbmj.controllers.drive import Drive
    from mtbmj.errors import MtbmjError

    options = {"push": "--drive-push-N", "power": "--drive-power-W", "brake": "--drive-brake-N"}
    limits = {"push": args.drive_push_N, "power": args.drive_power_W, "brake": args.drive_brake_N}
    given = {k: v for k, v in limits.items() if v is not None}
    if given and args.drive != "rider":
        raise MtbmjError(f"{options[next(iter(given))]}: a rider's limit applies to --drive rider, not --drive "
                         f"{args.drive}")
    for name, value in given.items():
        if not (value >= 0.0 and value < float("inf")):
            raise MtbmjError(f"{options[name]}: must be a finite number >= 0, got {value:g}")
    return Drive(args.drive, **given) if given else args.drive


def add_parser(subparsers) -> None:
    from mtbmj.rolling.terrain import DEFAULT_HEAD_ANGLE_DEG, names

    p = subparsers.add_parser("roll", help="roll the front end over terrain at a set speed")
    p.add_argument("scenario", help=f"terrain: {', '.join(names())} (optionally name:key=value,...) or a CSV "
                                    "profile (distance_m, height_mm)")
    p.add_argument("--speed", type=float, required=True, help="speed in m/s (> 0)")
    p.add_argument("--head-angle", type=float, default=DEFAULT_HEAD_ANGLE_DEG,
                   help=f"head angle in degrees from the horizontal, in (45, 90] (default {DEFAULT_HEAD_ANGLE_DEG:g})")
    p.add_argument("--config", default="S12", help="preset or TOML file for the fork and tire (default S12)")
    add_out(p, "out/roll")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--no-figure", action="store_true", help="do not draw quicklook.png")
    from mtbmj.controllers.drive import MODES, RIDER_BRAKE_N, RIDER_POWER_W, RIDER_PUSH_N

    p.add_argument("--drive", choices=MODES, default="rider",
                   help="rider (default): a speed controller within a rider's push, power and braking; servo: the "
                        "ideal servo on x0 + v t, whatever force that takes; coast: no drive")
    p.add_argument("--drive-push-N", type=float, metavar="N", dest="drive_push_N",
                   help=f"rider: the most the drive pushes the front end forward (default {RIDER_PUSH_N} N)")
    p.add_argument("--drive-power-W", type=float, metavar="W", dest="drive_power_W",
                   help=f"rider: the most power it puts in (default {RIDER_POWER_W} W)")
    p.add_argument("--drive-brake-N", type=float, metavar="N", dest="drive_brake_N",
                   help=f"rider: the most it holds back (default {RIDER_BRAKE_N} N)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a configuration key (repeatable)")
    p.add_argument("--duration", type=float, help="simulated time in s (default: to cross the feature and settle)")
    p.set_defaults(func=cmd_roll)


__all__ = ["add_parser", "cmd_roll"]

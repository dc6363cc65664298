"""``mtbmj roll SCENARIO --speed ... --head-angle ... --out DIR``: one rolling run, written
atomically. Bad terrain specs, a speed <= 0 and a head angle outside (45, 90] raise MtbmjError
(one line, exit status 2 from ``mtbmj.cli.main``)."""
from __future__ import annotations

from pathlib import Path

from mtbmj.cli.common import Progress, add_out, overrides


def cmd_roll(args) -> int:
    from mtbmj.rolling.frontend import run_roll

    result = Progress(f"roll {args.scenario}", not args.quiet).around(
        lambda progress: run_roll(args.scenario, args.speed, args.config, args.head_angle, args.duration,
                                  overrides(args.set), progress))
    written = result.write(args.out, figure=not args.no_figure)
    print(f"{result.headline()}; {result.info['real_time_factor']:.1f}x real time; "
          f"wrote {len(written)} files to {args.out}")
    return 0


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
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a configuration key (repeatable)")
    p.add_argument("--duration", type=float, help="simulated time in s (default: to cross the feature and settle)")
    p.set_defaults(func=cmd_roll)


__all__ = ["add_parser", "cmd_roll"]

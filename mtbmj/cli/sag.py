"""``mtbmj sag``: the air pressure or coil preload for a sag in percent of travel under a load,
written as a configuration that ``mtbmj drop`` runs as is, and where the fork's friction lets it
rest around that sag."""
from __future__ import annotations

from mtbmj.cli.common import add_out, overrides


def cmd_sag(args) -> int:
    from mtbmj.drop.sag import solve_sag
    from mtbmj.errors import MtbmjError

    if args.bike:
        return _bike_sag(args)
    from mtbmj.cli.presets import is_bike

    if is_bike(args.config):  # a bike's sag is both ends' (it was "unknown preset (known: S1, ...)")
        raise MtbmjError(f"{args.config}: is a bike: give --bike with --front-sag-percent and --rear-sag-percent")
    if args.sag_percent is None:
        raise MtbmjError("--sag-percent: required (or --bike with --front-sag-percent and --rear-sag-percent)")
    from mtbmj.cli.common import given_options

    given = given_options(args, front_sag_percent=None, rear_sag_percent=None, fork_set=None, shock_set=None)
    if given:
        raise MtbmjError(f"{given}: only with --bike")
    setting = solve_sag(args.config, args.load_kg, args.sag_percent, overrides(args.set))
    written = setting.write(args.out)
    print(f"{setting.line()}; wrote {written[0]}; run it with: {setting.drop_command(written[0])}")
    return 0


def _bike_sag(args) -> int:
    import shlex

    from mtbmj.bike import sag
    from mtbmj.cli.bike import bike_overrides
    from mtbmj.errors import MtbmjError

    from mtbmj.cli.common import given_options

    given = given_options(args, sag_percent=None, load_kg=None)
    if given:  # before the two: what the user gave is named
        raise MtbmjError(f"{given}: not with --bike (the bike's rider is its load; "
                         "--front-sag-percent and --rear-sag-percent set the sag)")
    if args.front_sag_percent is None or args.rear_sag_percent is None:
        raise MtbmjError("--bike: give --front-sag-percent and --rear-sag-percent")
    result = sag.solve(args.config, args.front_sag_percent, args.rear_sag_percent, bike_overrides(args))
    written = result.write(args.out)
    print(f"{result.line()}; wrote {written[0]}; run it with: mtbmj bike {shlex.quote(str(written[0]))} "
          f"\"root:at_m=0.4\" --speed 5 --out out/bike_sagged")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("sag", help="air pressure (air spring) or preload (coil) for a static sag; writes config.toml")
    p.add_argument("config", help="preset name (air120, S12, ...) or a TOML file")
    p.add_argument("--load-kg", type=float,
                   help="mass the fork carries (on the sled: the body mass); or give the rider inputs instead: "
                        "--set sled.rider_mass_kg=... --set sled.bike_mass_kg=... --set sled.front_share_percent=... "
                        "(not both)")
    p.add_argument("--sag-percent", type=float, help="static sag in percent of the travel")
    p.add_argument("--bike", action="store_true",
                   help="CONFIG is a bike (preset sst, trail, or a bike file): solve the fork's and the shock's "
                        "springs together for --front-sag-percent and --rear-sag-percent; writes BIKE_sag.toml")
    p.add_argument("--front-sag-percent", type=float, dest="front_sag_percent",
                   help="with --bike: the fork's static sag in percent of its travel")
    p.add_argument("--rear-sag-percent", type=float, dest="rear_sag_percent",
                   help="with --bike: the rear wheel's static sag in percent of its travel")
    p.add_argument("--fork-set", action="append", metavar="KEY=VALUE", dest="fork_set",
                   help="with --bike: change a key of the fork's configuration first (repeatable)")
    p.add_argument("--shock-set", action="append", metavar="KEY=VALUE", dest="shock_set",
                   help="with --bike: change a key of the shock's configuration first (repeatable)")
    add_out(p, "out/sag")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a configuration key before solving, e.g. fork.spring.tokens=2 (repeatable); with "
                        "--bike a bike key, e.g. rider.mass_kg=78")
    p.set_defaults(func=cmd_sag)

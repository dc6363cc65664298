"""``mtbmj sag``: the air pressure or coil preload for a sag in percent of travel under a load,
written as a configuration that ``mtbmj drop`` runs as is, and where the fork's friction lets it
rest around that sag."""
from __future__ import annotations

from mtbmj.cli.common import add_out, overrides


def cmd_sag(args) -> int:
    from mtbmj.drop.sag import solve_sag

    setting = solve_sag(args.config, args.load_kg, args.sag_percent, overrides(args.set))
    written = setting.write(args.out)
    print(f"{setting.line()}; wrote {written[0]}; run it with: {setting.drop_command(written[0])}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("sag", help="air pressure (air spring) or preload (coil) for a static sag; writes config.toml")
    p.add_argument("config", help="preset name (air120, S12, ...) or a TOML file")
    p.add_argument("--load-kg", type=float,
                   help="mass the fork carries (on the sled: the body mass); or give the rider inputs instead: "
                        "--set sled.rider_mass_kg=... --set sled.bike_mass_kg=... --set sled.front_share_percent=... "
                        "(not both)")
    p.add_argument("--sag-percent", type=float, required=True, help="static sag in percent of the travel")
    add_out(p, "out/sag")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a configuration key before solving, e.g. fork.spring.tokens=2 (repeatable)")
    p.set_defaults(func=cmd_sag)

"""``mtbmj curve CONFIG --out DIR``: the fork's spring curve (force against travel: main spring,
preload, top-out spring, bumper, an air fork's spacer progression, the static sag) and damper
curve (force against velocity, friction, one line per click), as PNG and CSV."""
from __future__ import annotations

from mtbmj.cli.common import add_out, overrides, write_and_say


def cmd_curve(args) -> int:
    from mtbmj.readout.curves import fork_curves

    curves = fork_curves(args.config, overrides(args.set), args.max_velocity_mm_per_s)
    return write_and_say(curves, args.out)


def add_parser(sub) -> None:
    p = sub.add_parser("curve", help="draw the fork's spring curve (sag marked) and damper curve (per click); "
                                     "PNG and CSV",
                       description="Draw a configuration's fork spring curve, force (N) against travel (mm) from the "
                                   "top stop to full travel at rest (main spring with its preload, top-out spring, "
                                   "bottom-out bumper, their sum, the static sag under sled.body_mass_kg; an air fork's "
                                   "0-3 volume spacers beside it), and its damper curve, force against velocity "
                                   "(mm/s, compression positive): hydraulic, friction while sliding, their sum, and "
                                   "one line per click of each adjuster of a clicks damper. Writes spring_curve.png, "
                                   "spring_curve.csv, damper_curve.png, damper_curve.csv (damper_clicks.csv with "
                                   "clicks), curve.json and config.toml.")
    p.add_argument("config", help="preset name (S1..S14, air120, reference) or a TOML file")
    add_out(p, "out/curve")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a configuration key, e.g. fork.spring.tokens=2 (repeatable)")
    p.add_argument("--max-velocity-mm-per-s", type=float, metavar="MM_PER_S",
                   help="damper curve from -this to +this (default: a lookup table's range, else 1500)")
    p.set_defaults(func=cmd_curve)

"""``mtbmj presets``: the bundled configurations with their descriptions; ``--show NAME``: every
value of one of them, resolved through its base."""
from __future__ import annotations

from mtbmj.config import preset_names


def cmd_presets(args) -> int:
    from mtbmj.config import load

    if args.show is not None:
        if not args.show.strip():
            from mtbmj.errors import MtbmjError

            raise MtbmjError("--show: no preset named (known: " + ", ".join(preset_names()) + ")")
        for key, value in load(args.show).lines():
            print(f"{key} = {value}")
        return 0
    for name in preset_names():
        print(f"{name:10s} {load(name).get('description', '')}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("presets", help="list the bundled presets, or show one's values (--show NAME)",
                       description="List the bundled presets with their descriptions; with --show NAME, print every "
                                   "value of the preset NAME (or of a TOML configuration file), resolved through its "
                                   "base, one 'key = value' line each in the units of the key names.")
    p.add_argument("--show", metavar="NAME", help="print every key of the preset NAME (or a TOML file) with its value")
    p.set_defaults(func=cmd_presets)

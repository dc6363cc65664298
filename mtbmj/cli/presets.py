"""``mtbmj presets``: the bundled configurations with their descriptions."""
from __future__ import annotations

from mtbmj.config import preset_names


def cmd_presets(args) -> int:
    from mtbmj.config import load

    for name in preset_names():
        print(f"{name:10s} {load(name).get('description', '')}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("presets", help="list the bundled presets")
    p.set_defaults(func=cmd_presets)

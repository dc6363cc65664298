"""``mtbmj presets``: the bundled configurations with their descriptions; ``--show NAME``: every
value of one of them, resolved through its base."""
from __future__ import annotations

from mtbmj.presets import locate, preset_names


def _bike_lines(ref: str) -> list[str]:
    """Every key of a bike preset or file, resolved through its base: 'section.key = value'."""
    import json
    import math

    from mtbmj.bike import spec

    _toml_value = json.dumps  # numbers, lists, strings and booleans are written alike in TOML
    resolved = spec.resolve(ref)  # read once, checked as a run would check it
    table, bike = resolved.read, resolved.spec
    lines = []
    for section, values in table.items():
        if not isinstance(values, dict):
            lines.append(f"{section} = {_toml_value(values)}")
            continue
        for key, value in values.items():
            if isinstance(value, dict):  # [fork.set], [shock.set]: the configurations' keys
                lines += [f"{section}.{key}.{k} = {_toml_value(v)}" for k, v in value.items()]
            else:
                lines.append(f"{section}.{key} = {_toml_value(value)}")
    if isinstance(table.get("geometry"), dict):  # what the chart gives, as comments (the output stays TOML)
        mm = lambda p: f"[{p[0] * 1e3:.1f}, {p[1] * 1e3:.1f}]"  # noqa: E731
        lines.append("# derived from [geometry] (frame coordinates, mm: origin the bottom bracket, level):")
        lines += [f"#   bike.front_axle_mm = {mm(bike.front_axle)}", f"#   bike.rear_axle_mm = {mm(bike.rear_axle)}",
                  f"#   bike.head_angle_deg = {math.degrees(bike.head_angle):.2f}"]
        if bike.rider.seated_com is not None and "seated_com_mm" not in table.get("rider", {}):
            lines.append(f"#   rider.seated_com_mm = {mm(bike.rider.seated_com)}")
    return lines


def is_bike(ref: str, depth: int = 0) -> bool:
    """A bike preset, or a bike file: one with a section only bike files have, or whose ``base`` is a
    bike (a file of ``base = "trail"`` and a [drive] or [fork.set] alone was taken for a fork's)."""
    from pathlib import Path

    from mtbmj.bike import spec

    if any(ref.lower() == n.lower() for n in spec.preset_names()):
        return True
    path = Path(ref)
    if path.suffix.lower() == ".toml" and path.is_file():
        import tomllib

        try:
            table = tomllib.loads(path.read_text(encoding="utf-8-sig"))
        except (tomllib.TOMLDecodeError, OSError, UnicodeDecodeError):
            return False
        base = table.get("base")
        if isinstance(base, str) and any(base.lower() == n.lower() for n in preset_names()):
            return False  # a fork preset as its base: a fork's file (a bike's [rider] in it is then named as an unknown key)
        if any(k in table for k in ("bike", "leverage", "rider", "shock", "geometry", "linkage", "drive", "sensors")):
            return True
        return isinstance(base, str) and depth < 20 and is_bike(str(path.parent / base) if base.lower().endswith(
            ".toml") else base, depth + 1)
    return False


def cmd_presets(args) -> int:
    from mtbmj.bike import spec
    from mtbmj.config import load

    if args.show is not None:
        if not args.show.strip():
            from mtbmj.errors import MtbmjError

            raise MtbmjError("--show: no preset named (known: " + ", ".join(preset_names() + spec.preset_names()) + ")")
        if is_bike(args.show):
            for line in _bike_lines(args.show):
                print(line)
            return 0
        locate(args.show, bikes=True)  # neither kind's: the one unknown-preset message, naming both kinds
        lines = list(load(args.show).lines())
        if not lines:  # an empty file (or comments only): no keys and no base, said rather than nothing printed
            from mtbmj.errors import ConfigError

            raise ConfigError(f"{args.show}: holds no keys (an empty file?): nothing to show; a configuration "
                              f"names its base, e.g. base = \"S12\", and the keys it changes")
        for key, value in lines:
            print(f"{key} = {value}")
        return 0
    print("configurations (mtbmj drop, roll, sweep, fit; the fork schema):")
    for name in preset_names():
        print(f"  {name:10s} {load(name).get('description', '')}")
    print("bikes (mtbmj bike, crosscheck --bike; docs/bike.md):")
    for name in spec.preset_names():
        print(f"  {name:10s} {spec.read_table(name)[0].get('description', '')}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("presets", help="list the bundled presets, or show one's values (--show NAME)",
                       description="List the bundled presets (configurations and bikes) with their descriptions; with "
                                   "--show NAME, print every value of the preset NAME (or of a TOML configuration or "
                                   "bike file), resolved through its base, one 'key = value' line each in the units of "
                                   "the key names.")
    p.add_argument("--show", metavar="NAME", help="print every key of the preset NAME (or a TOML file) with its value")
    p.set_defaults(func=cmd_presets)

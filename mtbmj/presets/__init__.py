"""The bundled fork configurations (this folder's TOML files), and where a fork's configuration named on
the command line lies: a bundled preset (named in any case) or a TOML file; a bike preset's name
(``mtbmj/bike/presets``) given where a fork's configuration goes is said to be one, not an unknown name."""
from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from mtbmj.errors import ConfigError


def preset_names() -> list[str]:
    """The bundled fork configurations, S1-S14 in order, then the rest by name."""
    files = resources.files("mtbmj.presets").iterdir()
    names = [f.name[:-5] for f in files if f.name.endswith(".toml")]
    return sorted(names, key=lambda n: (not n.startswith("S"), int(n[1:]) if n[1:].isdigit() else 0, n))


def study_presets() -> list[str]:
    return [f"S{i}" for i in range(1, 15)]


def bike_preset_names() -> list[str]:
    """The bundled bikes' names (``mtbmj/bike/presets``), sorted, read as files (no bike code imported here)."""
    return sorted(b.name[:-5] for b in resources.files("mtbmj.bike.presets").iterdir() if b.name.endswith(".toml"))


def locate(ref: str, bikes: bool = False) -> tuple[str, Path | Any]:
    """Resolve a preset name (case-insensitive) or a TOML path: (its name, where it lies). An
    unknown name is refused naming the known ones, with ``bikes`` the bike presets too (where either
    kind is taken: ``mtbmj presets --show``)."""
    for name in preset_names():
        if ref.lower() == name.lower():
            return name, resources.files("mtbmj.presets") / f"{name}.toml"
    path = Path(ref)
    if path.suffix.lower() == ".toml" or path.exists():
        if not path.exists():
            named = is_preset(path.stem) and path.suffix.lower() == ".toml"  # base = "S12.toml" for the preset
            from mtbmj.textfile import other_case

            raise ConfigError(f"{ref}: no such configuration file" + (
                f" (the preset is named without .toml: {path.stem})" if named else other_case(path)))
        return path.stem, path
    known = ", ".join(preset_names())
    if ref.lower() in bike_preset_names():
        raise ConfigError(f"{ref}: a bike preset (mtbmj bike, sag --bike), not a fork's configuration (known: {known})")
    if bikes:
        known = f"configurations {known}; bikes {', '.join(bike_preset_names())}"
    raise ConfigError(f"{ref}: unknown preset (known: {known}) and no such file")


def is_preset(name: str) -> bool:
    return any(name.lower() == n.lower() for n in preset_names())

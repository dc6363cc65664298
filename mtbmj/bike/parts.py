"""A bike's two parts composed: the fork's and the shock's configurations with the bike's ``set`` tables
(``setups``), and the keys of those tables the bike file named writes itself (``own_set_keys``), so that
one its part's model does not read is said in a warning line naming the key and the file
(``mtbmj.compose``), and one a person typed (``--fork-set``, ``--shock-set``) is refused."""
from __future__ import annotations

import dataclasses
import functools
import os
import tomllib
from pathlib import Path

from mtbmj import compose
from mtbmj.errors import ConfigError
from mtbmj.presets import bike_preset_names


def own_set_keys(source: str) -> dict[str, frozenset]:
    """{"fork.set": keys, "shock.set": keys} the bike file ``source`` writes in its own ``[fork.set]`` and
    ``[shock.set]`` (not its bases', which other files may build on; none for a preset)."""
    if source in bike_preset_names():
        return {}
    try:
        stat = os.stat(source)
    except OSError:
        return {}
    return _own(str(Path(source).resolve()), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=32)
def _own(path: str, mtime_ns: int, size: int) -> dict[str, frozenset]:
    from mtbmj.textfile import read_text

    try:  # read and checked already (mtbmj.bike.bikefile.read_table): here only its own set tables' keys
        table = tomllib.loads(read_text(Path(path), ConfigError, path, "not a text file"))
    except (ConfigError, tomllib.TOMLDecodeError):
        return {}
    out = {}
    for section in ("fork", "shock"):
        given = table.get(section, {}).get("set", {}) if isinstance(table.get(section), dict) else {}
        out[f"{section}.set"] = frozenset(str(k) for k in given) if isinstance(given, dict) else frozenset()
    return out


def setups(spec) -> tuple[compose.Setup, compose.Setup]:
    """(fork, shock) setups: each configuration with the bike's overrides, composed by ``mtbmj.compose``."""
    from mtbmj.bike.shock import judged_as_sold
    from mtbmj.config import ALTERNATIVES, load

    own = own_set_keys(spec.source) if spec.source else {}

    def part(section, config, over):  # a person's keys (--fork-set) refused if unread, the file's own said
        mine = spec.overrides.get(section) or {}
        try:
            with judged_as_sold(spec.shock_sold if section == "shock.set" else ()):
                c = load(config, over or None)
        except ConfigError as exc:  # a key of the file's own set table at fault: name the file and the table
            if str(exc).partition(":")[0] in own.get(section, ()) and str(exc).partition(":")[0] not in mine:
                raise ConfigError(f"{spec.source} [{section}] {exc}") from None
            raise
        typed = {ALTERNATIVES.get(k, (k,))[0] for k in mine} if getattr(mine, "typed", False) else set()
        filed = {ALTERNATIVES.get(k, (k,))[0]: f"{spec.source} [{section}]" for k in own.get(section, ())
                 if k not in mine}
        try:
            return compose.setup(dataclasses.replace(c, given=typed, filed={**c.filed, **filed}))
        except compose.NotRead as exc:
            raise ConfigError(f"--{section.replace('.', '-')} {exc}") from None

    fork = part("fork.set", spec.fork_config, spec.fork_overrides)
    shock = part("shock.set", spec.shock_config, {"fork.travel_mm": spec.shock_stroke * 1e3, **spec.shock_overrides})
    if abs(shock.travel - spec.shock_stroke) > 1e-9:
        raise ConfigError(f"shock.stroke_mm: {spec.shock_stroke * 1e3:g} mm, but the shock configuration's "
                          f"fork.travel_mm is {shock.travel * 1e3:g} mm")
    return fork, shock

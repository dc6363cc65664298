"""Reading a bike file: its ``base`` chain merged, a geometry chart over its bases, a shock as
sold, hardpoints replacing a leverage table, every number through the numeric-input gate, the
overrides applied (:func:`overridden`), and the schema of its sections (``KNOWN``). What the file
reads becomes a bike in ``mtbmj.bike.spec`` (:func:`mtbmj.bike.spec.resolve`: derive and check);
nothing here derives or checks a bike."""
from __future__ import annotations

import copy
import math
from importlib import resources
from pathlib import Path

from mtbmj import limits
from mtbmj.bike import chart as _chart
from mtbmj.bike import linkage as _linkage
from mtbmj.bike import shock as _shock
from mtbmj.errors import ConfigError
from mtbmj.presets import bike_preset_names, is_preset as is_fork_preset


def preset_names() -> list[str]:
    return bike_preset_names()


def _locate(ref: str):
    for name in preset_names():
        if ref.lower() == name.lower():
            return name, resources.files("mtbmj.bike.presets") / f"{name}.toml"
    path = Path(ref)
    if not path.exists() and path.suffix.lower() == ".toml" and _is_preset(path.stem):  # base = "sst.toml"
        raise ConfigError(f"{ref}: no such bike file (the preset is named without .toml: {path.stem})")
    if not path.exists():
        fork = is_fork_preset(ref)  # a fork's name where a bike is read
        from mtbmj.textfile import other_case

        raise ConfigError(f"{ref}: not a bike preset (known: {', '.join(preset_names())})" + (
            " but a fork's configuration (mtbmj drop, curve, sag without --bike)" if fork else
            f" and no such file{other_case(path)}"))
    return path.stem, path


def _is_preset(name: str) -> bool:
    return any(name.lower() == n.lower() for n in preset_names())


def read_leverage_csv(path) -> tuple[list[float], list[float]]:
    """(wheel travel mm, leverage ratio) of a leverage-ratio CSV as linkage tools and telemetry apps
    export it: two numbers a row, wheel travel first, separated by a comma, a semicolon or a tab
    (Sufni's "0.0,3.18"; Linkage's "0;3.18"); header lines before the first number row are skipped."""
    import re

    from mtbmj.textfile import read_text

    if not isinstance(path, str):
        raise ConfigError(f"leverage.csv: must be a file's path, got {path!r}")
    # the one reader of a user's files: a FIFO, a device or a directory refused without waiting, a
    # file over 1 MiB (60 000 rows; a tool's export every 0.1 mm of 260 mm is 2 600) before it is read
    text = read_text(Path(path), ConfigError, f"leverage.csv: {path}", "not a text file (wheel travel and leverage "
                     "ratio, two numbers a row)", "config")
    w, r = [], []
    for number, line in enumerate(text.splitlines(), 1):
        cells = [c.strip() for c in re.split(r"[,;\t]", line) if c.strip()]
        if not cells:
            continue
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not w:
                continue  # a header
            raise ConfigError(f"{path}, line {number}: not two numbers ({line.strip()!r})") from None
        if len(values) != 2 or not all(math.isfinite(v) for v in values):
            raise ConfigError(f"{path}, line {number}: expected wheel travel and leverage ratio, got {line.strip()!r}")
        w.append(values[0])
        r.append(values[1])
    if len(w) < 2:
        raise ConfigError(f"leverage.csv: {path} holds {len(w)} row(s) of wheel travel and leverage ratio (at least 2)")
    return w, r


def _chart_over_bases(table: dict, part: dict, location) -> tuple[dict, dict]:
    """One file's geometry chart over its bases' ``table`` (``read_table``): the chart replaces
    the axles and head angle its bases gave (and their chart), its fork keys are set in the file's
    ``[fork.set]`` as if written there, and its saddle replaces their seated rider. A file whose own
    ``rider.seated_com_mm`` follows a chart with a saddle replaces that saddle; a chart without a
    saddle after one with a saddle keeps the seated rider the old saddle gave."""
    for name in ("bike", "rider"):  # read here before the sections are checked (a section given as a value)
        if part.get(name) is not None and not isinstance(part[name], dict):
            raise ConfigError(f"{location}: {name}: must be a table")
    geo, bike, rider = part.get("geometry"), part.get("bike") or {}, part.get("rider") or {}
    old = table.get("geometry") if isinstance(table.get("geometry"), dict) else {}
    old_saddle = _chart.saddle(old)
    part = dict(part)

    def keep_old_seat(table: dict) -> None:  # the bases' saddle placed the seated rider: it stays there
        if old_saddle is not None and "seated_com_mm" not in rider:
            from_saddle = {**(table.get("rider") or {}), **rider}.get("seated_com_from_saddle_mm")
            table.setdefault("rider", {})["seated_com_mm"] = _chart.seated_com(old, from_saddle)

    if isinstance(geo, dict):
        try:  # the chart's own keys (misspelt, outside a bike's range): the line names the file that gives them
            _chart.check_keys(geo)
            fork = _chart.fork_keys(geo)
        except ConfigError as exc:
            raise ConfigError(f"{location}: {exc}") from None
        given = [k for k in _chart.SETS if k in bike]
        if given:
            raise ConfigError(f"{location}: bike.{given[0]} and [geometry] give the frame's geometry two ways; give one")
        mine = part.get("fork", {}).get("set", {}) if isinstance(part.get("fork"), dict) else {}
        mine = mine if isinstance(mine, dict) else {}
        both = [k for k in fork if k in mine]
        if both:
            chart_key = next(k for k, v in _chart.FORK.items() if v == both[0])
            raise ConfigError(f"{location}: geometry.{chart_key} and [fork.set] {both[0]!r} give it two ways; give one")
        if fork:
            part["fork"] = {**(part.get("fork") or {}), "set": {**mine, **fork}}
        new_saddle = _chart.saddle(geo)
        if new_saddle is not None and "seated_com_mm" in rider:
            raise ConfigError(f"{location}: rider.seated_com_mm and the chart's saddle (geometry.seat_tube_angle_deg) "
                              f"give the seated rider two ways; give one")
        if isinstance(table.get("bike"), dict):
            table["bike"] = {k: v for k, v in table["bike"].items() if k not in _chart.SETS}
        if new_saddle is None:
            keep_old_seat(table)
        elif isinstance(table.get("rider"), dict):  # this chart's saddle places the seated rider
            table["rider"] = {k: v for k, v in table["rider"].items() if k != "seated_com_mm"}
        table.pop("geometry", None)
    elif old and ("linkage" in part or [k for k in _chart.SETS if k in bike]):
        # axles or hardpoints over a base's chart: the chart becomes the axles it gave, then these replace them
        table = merge(table, {"bike": _chart.frame_keys(old)})
        keep_old_seat(table)
        table.pop("geometry")
    else:
        if old_saddle is not None and "seated_com_mm" in rider:  # the file's own seated rider wins
            table["geometry"] = old = {k: v for k, v in old.items() if k not in _chart.SEAT}
        shock = part.get("shock") if isinstance(part.get("shock"), dict) else {}
        if "rear_travel_mm" in old and ("leverage" in part or "stroke_mm" in shock):
            # the base chart's rear travel described the base's rear end, not this one
            table["geometry"] = {k: v for k, v in old.items() if k != "rear_travel_mm"}
    return table, part


def read_table(ref: str) -> tuple[dict, str]:
    """A bike file's table with its ``base`` chain merged in (read by ``mtbmj.config.read_chain``,
    the drop configurations' reader: the same base rules)."""
    from mtbmj.config import read_chain

    table: dict = {}
    for _, location, part in read_chain(ref, _locate, _is_preset, "a bike description"):
        part = gated(part, location)  # every number through the numeric-input gate before any is used
        lev = part.get("leverage")
        if isinstance(lev, dict):
            if isinstance(lev.get("csv"), str) and isinstance(location, Path):
                lev["csv"] = str((location.resolve().parent / lev["csv"]))  # relative to the file that names it
            # a curve replaces its bases' curve, given as a CSV or as the two lists
            if isinstance(table.get("leverage"), dict):
                drop = ("wheel_travel_mm", "ratio") if "csv" in lev else ("csv",) if lev.keys() & {"wheel_travel_mm", "ratio"} else ()
                table["leverage"] = {k: v for k, v in table["leverage"].items() if k not in drop}
        table, part = _chart_over_bases(table, part, location)
        if isinstance(part.get("linkage"), dict):  # hardpoints replace the rear end its bases gave
            if "leverage" in part or "pivot_mm" in (part.get("bike") or {}):
                raise ConfigError(f"{location}: [linkage] and {'[leverage]' if 'leverage' in part else 'bike.pivot_mm'} "
                                  f"give the rear end two ways; give one (the linkage's pivot and leverage ratio "
                                  f"follow from its points)")
            table.pop("leverage", None)
            table.pop("linkage", None)
            if isinstance(table.get("bike"), dict):
                table["bike"] = {k: v for k, v in table["bike"].items() if k not in ("pivot_mm", "rear_axle_mm")}
        elif "leverage" in part or "pivot_mm" in (part.get("bike") or {}):
            table.pop("linkage", None)  # a table or a pivot replaces the hardpoints its bases gave
        table = merge(table, part)
        mine = part.get("shock")
        if isinstance(mine, dict) and mine.keys() & set(_shock.KEYS):  # a shock as sold: its keys set this
            # file's [shock.set] over its bases' (mtbmj.bike.shock), so a later file's [shock.set] wins
            table["shock"]["set"] = _shock.schema_keys(mine, table["shock"].get("set", {}), table["shock"].get("spring"))
    return table, str(ref)


# A telemetry recorder's sensors on this bike (Sufni's AS5600 angle sensors): the fork's isosceles
# triangle (two equal arms, the stroke as its base) and the shock's triangle (two arms, the shock's
# eye-to-eye as the third side), in mm, as its setup record gives them (``mtbmj telemetry --bike``)
SENSOR_KEYS = ("fork_arm_mm", "fork_max_mm", "shock_arm1_mm", "shock_arm2_mm", "shock_max_mm")


def merge(a: dict, b: dict) -> dict:
    """``a`` with ``b`` over it, nested tables merged key by key (neither is changed)."""
    out = dict(a)
    for k, v in b.items():
        out[k] = merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


KNOWN = {
    "description": None, "reading": None,
    "bike": {"head_angle_deg", "fork_offset_mm", "front_axle_mm", "rear_axle_mm", "pivot_mm", "frame_mass_kg",
             "frame_com_mm", "frame_inertia_kg_m2", "swingarm_mass_kg", "swingarm_inertia_kg_m2",
             "fork_lower_mass_kg", "front_wheel_mass_kg", "rear_wheel_mass_kg", "wheel_inertia_kg_m2"},
    "leverage": {"wheel_travel_mm", "ratio", "csv"},
    "linkage": _linkage.known_keys(),
    "shock": {"stroke_mm", "config", "set", *_shock.KEYS},
    "fork": {"config", "set"},
    "rider": {"mass_kg", "limbs_share_percent", "com_mm", "pitch_inertia_kg_m2", "pedals_mm", "bars_mm",
              "seated_com_mm", "seated_com_from_saddle_mm", "height_m", "leg_length_mm", "arm_length_mm", "leg_stiffness_N_per_mm", "leg_damping_N_s_per_m",
              "arm_stiffness_N_per_mm", "arm_damping_N_s_per_m"},
    "drive": {"push_N", "power_W", "brake_N", "traction", "chainring_teeth", "cog_teeth", "chain"},
    "sensors": set(SENSOR_KEYS),
    "geometry": set(_chart.KEYS),
}


def part_key(key: str) -> str | None:
    """The key of the fork's or the shock's configuration that a bike key ``key`` not in the bike
    file's tables reads as (``fork.spring.rate_N_per_mm``, ``shock.damper.rebound_N_s_per_m``: a
    configuration's keys are ``fork.*``, the shock's too), else None: what a refusal points to."""
    from mtbmj.config import ALTERNATIVES, SCHEMA

    section, _, name = str(key).partition(".")
    meant = f"fork.{name}"
    if section not in ("fork", "shock") or (meant not in SCHEMA and meant not in ALTERNATIVES):
        return None
    return meant if section == "fork" or meant != "fork.length_mm" else None


# The keys of the fork's and the shock's configurations the bike reads: the fork's laws, tire,
# gravity and integrator; the shock's laws (the fork schema read in shock coordinates; its length,
# tire, sled and solver keys have no part in the bike). A key set in [fork.set] or [shock.set]
# outside these changed nothing and is refused.
USED = {"fork": ("fork.*", "tire.*", "sled.gravity_m_per_s2", "solver.integrator"),
        "shock": ("fork.* but fork.length_mm",)}


def reads_key(section: str, key: str) -> bool:
    """Whether the bike reads ``key`` of the ``section`` (fork or shock) part's configuration (``USED``)."""
    if section == "fork":
        return key.startswith(("fork.", "tire.")) or key in ("sled.gravity_m_per_s2", "solver.integrator")
    return key.startswith("fork.") and key != "fork.length_mm"


def configuration_option(key: str) -> str:
    """Where a key that is no bike key but a fork's or shock's configuration key (``tire.pressure_psi``)
    goes, as a refusal of ``--set`` ends: the option that takes it; "" for any other key."""
    from mtbmj.config import ALTERNATIVES, SCHEMA

    if (key not in SCHEMA and key not in ALTERNATIVES) or not reads_key("fork", str(key)):
        return ""
    both = " (its [tire] sets both tyres)" if str(key).startswith("tire.") else ""
    return f"; a key of the fork's configuration goes with --fork-set {key}=VALUE{both}"


def bike_key(key: str) -> str | None:
    """``key`` (a key given in a part's ``set`` table) as the bike key ``SECTION.NAME`` it names,
    else None."""
    section, _, name = str(key).partition(".")
    return key if KNOWN.get(section) and name in KNOWN[section] and name not in ("set", "config") else None


def gated(table: dict, location=None) -> dict:
    """``table`` (a bike file's, or overrides by key) with every number in it passed through the
    numeric-input gate (``mtbmj.limits.numbers_in``): a value that is NaN, infinite, an integer too
    large for a float or beyond ``limits.MAX_MAGNITUDE`` is refused in one line naming its key
    (and the file), before any key is converted or used. The plausible ranges are warned about
    when the bike is loaded (``mtbmj.bike.keys.warnings``)."""
    try:
        return {key: limits.numbers_in(str(key), value) for key, value in table.items()}
    except ConfigError as exc:
        raise ConfigError(f"{location}: {exc}" if isinstance(location, Path) else str(exc)) from None


def over_set(old: dict, new: dict) -> dict:
    """A part's ``set`` table ``old`` with ``new`` over it: a key ``new`` gives in another unit
    (``fork.spring.rate_lb_per_in`` over the file's ``rate_N_per_mm``) replaces the old one's."""
    from mtbmj.config import ALTERNATIVES

    def canonical(key):
        return ALTERNATIVES.get(key, (key,))[0]

    given = {canonical(k) for k in new}
    return {**{k: v for k, v in old.items() if canonical(k) not in given}, **new}


def _in_units(section: str, name: str) -> list[str]:
    """The keys of ``section`` that are ``name`` with a unit (``spring_rate``: ``spring_rate_N_per_mm``,
    ``spring_rate_lb_per_in``) or, for a unit alone (``kg``), in that unit."""
    from mtbmj.config import UNITS

    keys = sorted(k for k in KNOWN.get(section) or () if k != "set")
    with_unit = [k for k in keys if k.startswith(f"{name}_") and k[len(name):] in UNITS]
    return with_unit or ([k for k in keys if k.endswith(f"_{name}")] if f"_{name}" in UNITS else [])


def mapping(overrides) -> None:
    """Refuse ``overrides`` from Python that are not a mapping (a str, a list of "key=value"), in one line."""
    limits.require_mapping(overrides, "'rider.mass_kg': 78")


def overridden(table: dict, overrides) -> dict:
    """``table`` with ``overrides`` applied: ``"section.key": value`` for a bike key (``rider.mass_kg``),
    ``"fork.set": {KEY: value}`` / ``"shock.set": {KEY: value}`` for keys of the fork's and the
    shock's configurations (merged into the file's). Unknown keys are refused by ``load``. ``table``
    itself is left as it was (its nested tables too)."""
    mapping(overrides)
    out = copy.deepcopy(table)
    for key, value in gated(dict(overrides or {})).items():
        if key in ("fork.set", "shock.set"):
            if not isinstance(value, dict):
                raise ConfigError(f"{key}: overrides must be a table of configuration keys")
            section = out.setdefault(key.split(".")[0], {})
            if not isinstance(section, dict):
                raise ConfigError(f"{key.split('.')[0]}: must be a table")
            section["set"] = over_set(section.get("set", {}), value)
            continue
        section, dot, name = str(key).partition(".")
        if not dot or not name:
            raise ConfigError(f"--set {key}: a bike key is SECTION.KEY (e.g. rider.mass_kg; known sections: "
                              f"{', '.join(k for k, v in KNOWN.items() if v)})")
        if section not in KNOWN or not KNOWN[section]:
            raise ConfigError(f"--set {key}: unknown section {section!r} (known: "
                              f"{', '.join(k for k, v in KNOWN.items() if v)})" + configuration_option(key))
        if name not in KNOWN[section] or name == "set":
            meant = _in_units(section, name)  # shock.spring_rate or rider.kg: the keys with the unit
            if meant:
                raise ConfigError(f"--set {key}: unknown key; the unit is part of the key's name: "
                                  f"{' or '.join(f'{section}.{k}' for k in meant)}")
            raise ConfigError(f"--set {key}: unknown key (known in [{section}]: "
                              f"{', '.join(sorted(k for k in KNOWN[section] if k != 'set'))})"
                              + (f"; a key of the {section}'s own configuration goes with --{section}-set, e.g. "
                                 f"--{section}-set {part_key(key)}=VALUE" if part_key(key) else ""))
        if section == "bike" and name in _chart.SETS and isinstance(out.get("geometry"), dict):
            raise ConfigError(f"--set {key}: this bike's frame is given by its geometry chart; set the chart's keys "
                              f"(geometry.{'head_angle_deg' if name == 'head_angle_deg' else 'wheelbase_mm'}, ...)")
        if section == "geometry" and not isinstance(out.get("geometry"), dict):  # a bike given by its axles
            if name not in _chart.FORK:
                raise ConfigError(f"--set {key}: this bike's frame is given by its axles (bike.front_axle_mm, "
                                  f"bike.rear_axle_mm, bike.head_angle_deg), not a geometry chart; set those")
            out.setdefault("fork", {}).setdefault("set", {}).update(_chart.fork_keys({name: value}))
            continue
        out.setdefault(section, {})[name] = value
        if (section == "geometry" and name in _chart.FRAME
                and not any(str(k).partition(".")[2] in _chart.CHECK for k in overrides)):
            # the chart's reach and stack checked the chart as published: a changed frame drops them
            out["geometry"] = {k: v for k, v in out["geometry"].items() if k not in _chart.CHECK}
        if section == "geometry" and name in _chart.FORK:  # a chart's fork key sets the fork's, as in a file
            out.setdefault("fork", {}).setdefault("set", {}).update(_chart.fork_keys({name: value}))
        if section == "geometry" and name in _chart.SEAT and isinstance(out.get("rider"), dict):
            out["rider"] = {k: v for k, v in out["rider"].items() if k != "seated_com_mm"}  # the saddle places it
        if (section, name) == ("rider", "seated_com_mm") and isinstance(out.get("geometry"), dict):
            out["geometry"] = {k: v for k, v in out["geometry"].items() if k not in _chart.SEAT}
        if section == "shock" and name in _shock.KEYS:  # a shock's key as sold sets its [shock.set] now
            sh = out["shock"]
            sh["set"] = _shock.schema_keys({name: value}, sh.get("set", {}), sh.get("spring"))
    return out


__all__ = ["KNOWN", "SENSOR_KEYS", "bike_key", "gated", "merge", "overridden", "part_key", "preset_names", "read_leverage_csv", "read_table"]

"""A grid (or list) of bike variants over one terrain, one row each (``mtbmj sweep BIKE --roll TERRAIN
--speed V --vary KEY=LO:HI:N``).

A variant changes bike keys (``rider.mass_kg``) and the fork's or the shock's configuration keys,
named ``fork:KEY`` and ``shock:KEY`` (``fork:fork.spring.air_pressure_psi``), as ``mtbmj bike``'s
``--set``, ``--fork-set`` and ``--shock-set`` do. Each runs as ``run_bike`` does, one after another
in this process (a bike run is tens of milliseconds of stepping per simulated second); a variant
that is refused or diverges is recorded with its reason, a crash with its kind and time. The table
holds the inputs, what riders read (travel peaks and bottom-outs at both ends, the rider's RMS and
the tyre-load variation over the feature, the crash) and the status.

Given an output folder, each variant's row is journaled as it finishes (``OUT/journal/``, the drop
sweeps' ``mtbmj.sweep.runner.Journal``), keyed by a digest of everything that makes it (the bike
file's table, terrain, speed, duration, the common overrides, the variant, and the content of every
file these name: the bike file and its bases, a leverage CSV, the fork's and shock's configuration
files, a terrain CSV; :func:`journal_recipe`); ``resume`` takes the
rows the journal holds and runs the rest, so a run killed at any point and resumed writes the table
an uninterrupted run writes, byte for byte.
"""
from __future__ import annotations

import json
from pathlib import Path

from mtbmj.errors import ConfigError, MtbmjError

# (column, label): what the figure draws
OUTPUTS = (
    ("max_front_travel_mm", "front travel peak [mm]"),
    ("max_rear_travel_mm", "rear wheel travel peak [mm]"),
    ("bottom_outs_count", "bottom-outs (bumper, either end)"),
    ("rider_rms_m_per_s2", "rider RMS over the feature [m/s²]"),
    ("front_load_variation", "front tyre-load variation"),
    ("crashes_count", "crashes"),
)


def overrides_of(variant: dict, base: dict | None = None) -> dict:
    """A variant's keys as ``run_bike`` overrides, on top of ``base``."""
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in (base or {}).items()}
    for key, value in variant.items():
        for prefix, section in (("fork:", "fork.set"), ("shock:", "shock.set")):
            if key.startswith(prefix):
                out.setdefault(section, {})[key[len(prefix):]] = value
                break
        else:
            out[key] = value
    return out


def _row(variant: dict, result) -> dict:
    s = result.summary
    f = s["feature"]
    bumps = sum(s[end]["bumper"]["count"] for end in ("front", "rear"))
    crash = s.get("crash")
    return {**variant, "status": "ok", "reason": "", "max_front_travel_mm": s["max_front_travel_mm"],
            "max_rear_travel_mm": s["max_rear_travel_mm"], "bottom_outs_count": bumps,
            "rider_rms_m_per_s2": f["rider_acceleration_rms_m_per_s2"],
            "front_load_variation": f["tire_load_variation"]["front"],
            "rear_load_variation": f["tire_load_variation"]["rear"],
            "crashes_count": int(crash is not None), "crash": crash["line"] if crash else ""}


def _native(value):
    """JSON for numpy scalars (a row is journaled and read back as the same Python values)."""
    import numpy as np

    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.bool_):
        return bool(value)
    raise TypeError(f"not JSON: {type(value).__name__}")


def variant_id(recipe: dict, variant: dict) -> str:
    import hashlib

    text = json.dumps({**recipe, "variant": variant}, sort_keys=True, default=_native)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def journal_recipe(bike: str, scenario: str, speed: float, duration: float | None = None,
                   base: dict | None = None) -> dict:
    """What every variant of a sweep is made of, the part of its journal key (:func:`variant_id`) the
    variants share: the bike file's table with its ``base`` chain merged in (``read_table``), the
    terrain, speed, duration and common overrides, and the content (SHA-256) of every file these
    name (``mtbmj.sweep.variants.files_digest``): the bike file and its bases, a leverage CSV, the
    fork's and the shock's configuration files with their bases, a terrain CSV. A file edited
    between two ``--resume`` runs gives its variants new keys, so they are computed again."""
    from mtbmj.bike.spec import read_table
    from mtbmj.sweep.variants import files_digest

    table = read_table(str(bike))[0]
    base = base or {}
    return {"bike": table, "scenario": scenario, "speed": speed, "duration": duration, "base": base,
            "files": files_digest([str(bike), table, scenario, base])}


def check(bike: str, scenario: str, variants: list[dict], base: dict | None = None) -> None:
    """Before any variant runs, what every variant shares, refused in one line naming its cause: the
    terrain (built as each run builds it), the bike with the common overrides (its fork's and shock's
    configurations read), the first variant's keys placed on it (a key the bike does not have, a frame
    key of a bike given by its chart), and each varied key a number where this bike holds it. A value a
    single variant cannot take (a negative mass) is that variant's failure, recorded with its reason."""
    from mtbmj.bike import spec as spec_mod
    from mtbmj.bike.run import setups
    from mtbmj.rolling import terrain

    terrain.make(scenario)
    fork, shock = setups(spec_mod.load(str(bike), base))
    table = spec_mod.read_table(str(bike))[0]
    from mtbmj.bike.bikefile import part_key

    for key in variants[0]:  # a part's key varied as a bike key: the bike file's refusal pointed at --fork-set
        meant = None if key.startswith(("fork:", "shock:")) else part_key(key)
        if meant is not None:
            raise ConfigError(f"--vary {key}: a key of the {key.partition('.')[0]}'s configuration is varied as "
                              f"{key.partition('.')[0]}:{meant} (--vary {key.partition('.')[0]}:{meant}=LO:HI:N)")
    spec_mod.overridden(table, overrides_of(variants[0], base))  # where its keys go
    table = spec_mod.overridden(table, base)
    for key in variants[0]:
        if key.startswith(("fork:", "shock:")):
            end, _, name = key.partition(":")
            held = (fork if end == "fork" else shock).config.values.get(name)
        else:
            section, _, name = key.partition(".")
            part = table.get(section)
            held = part.get(name) if isinstance(part, dict) else None
        if held is not None and (isinstance(held, bool) or not isinstance(held, (int, float))):
            raise ConfigError(f"--vary {key}: not a number on this bike (it is {held!r}); a sweep varies a number")


def run(bike: str, scenario: str, speed: float, variants: list[dict], duration: float | None = None,
        base: dict | None = None, progress=None, out_dir=None, resume: bool = False):
    """The sweep's table (a ``pandas.DataFrame``, one row per variant, in order); with ``out_dir``
    journaled there as it goes, and with ``resume`` the journal's rows reused (see the module doc)."""
    import warnings

    import pandas as pd

    from mtbmj.bike.run import run_bike
    from mtbmj.sweep.runner import Journal
    from mtbmj.sweep.variants import journal_records

    if not variants:
        raise ConfigError("sweep: no variants")
    for key in variants[0]:
        if not (key.startswith(("fork:", "shock:")) or "." in key):
            raise ConfigError(f"--vary {key}: a bike sweep varies a bike key (rider.mass_kg) or fork:KEY / shock:KEY")
    check(bike, scenario, variants, base)
    journal = Journal(Path(out_dir)) if out_dir is not None else None
    known = {} if journal is None else journal_records(Path(out_dir), journal, resume)
    recipe = journal_recipe(bike, scenario, speed, duration, base)
    rows = []
    for i, variant in enumerate(variants):
        vid = variant_id(recipe, variant)
        if vid in known and isinstance(known[vid].get("row"), dict):
            rows.append(known[vid]["row"])
            if progress is not None:
                progress((i + 1) / len(variants))
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # a variant's plausibility notes are in no table cell
                result = run_bike(bike, scenario, speed, duration, overrides=overrides_of(variant, base))
            rows.append(_row(variant, result))
        except MtbmjError as exc:
            if i == 0 and isinstance(exc, ConfigError) and "unknown" in str(exc):
                raise  # a key no variant can have: refused before the rest run
            rows.append({**variant, "status": "failed", "reason": str(exc)})
        rows[-1] = json.loads(json.dumps(rows[-1], default=_native))  # the values a resumed run reads back
        if journal is not None:
            journal.append([{"id": vid, "row": rows[-1]}])
        if progress is not None:
            progress((i + 1) / len(variants))
    return pd.DataFrame(rows)


def write(table, out_dir, bike: str, scenario: str, speed: float, keys: list[str]) -> list[Path]:
    """sweep.csv, sweep.json (what ran) and, over one or two keys, sweep.png; written whole."""
    from mtbmj import output
    from mtbmj.readout import quicklook
    from mtbmj.sweep.figure import sweep_figure

    files = {"sweep.csv": table.to_csv(index=False).encode(),
             "sweep.json": output.json_bytes({"bike": bike, "scenario": scenario, "speed_m_per_s": speed,
                                              "keys": keys, "variants": int(len(table)),
                                              "failed": int((table["status"] != "ok").sum()),
                                              "rows": json.loads(table.to_json(orient="records"))})}
    fig = sweep_figure(table, keys, f"sweep of bike {bike} over {scenario} at {speed:g} m/s", OUTPUTS)
    if fig is not None:
        files["sweep.png"] = quicklook.png(fig)
    return output.write_atomically(out_dir, files, keep=("journal",))

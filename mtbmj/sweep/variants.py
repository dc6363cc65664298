"""Sweep plans: the ranges and samples of ``--vary``, CSV variants, variant ids, the job a runner
gets, and the summary flattened into table columns."""
from __future__ import annotations

import csv
import hashlib
import itertools
import json
import math
import re
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from mtbmj.config import SCHEMA, Config, check_value
from mtbmj.readout.endtravel import TABLE_COLUMNS as END_OF_TRAVEL_COLUMNS
from mtbmj.errors import ConfigError, MtbmjError
from mtbmj import limits
from mtbmj.textfile import read_text

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SIGNALS = ("sled", "fork", "tire")
EVENTS = ("peak1", "topping", "peak2", "valley1", "peak3")
NUMERIC_KINDS = ("pos", "nonneg", "real")
SAMPLING_METHODS = ("lhs", "sobol")
BACKENDS = ("local", "dask")
RUNNERS = ("batch", "single")
TABLE = "sweep.parquet"
TABLE_CSV = "sweep.csv"
TRACES = "traces.h5"
MANIFEST = "sweep.json"
JOURNAL = "journal"
TIMINGS = "timings.csv"  # wall time per variant, kept out of the table so equal sweeps give equal tables
MAX_VARIANTS = 1_000_000

# The summary flattened into table columns, in this order (see ``flatten_summary``).
OUTPUT_COLUMNS = (
    [f"{s}_{e}_{q}" for s in SIGNALS for e in EVENTS for q in ("mm", "s")]
    + ["lift_off_s", "landing_s", "lifts_off", "fork_tops_out"]
    + [f"rest_{s}_mm" for s in SIGNALS]
    + ["rest_motion_mm", "at_rest", "max_fork_mm"] + list(END_OF_TRAVEL_COLUMNS)  # mtbmj.readout.endtravel, one definition
    + ["max_tire_mm",
       "impact_speed_m_per_s", "energy_input_J", "energy_mechanical_end_J", "energy_dissipated_J"]
)
STATUS_COLUMNS = ["status", "reason"]


# --------------------------------------------------------------------------------------------
# Variant generation


@dataclass(frozen=True)
class Range:
    """One ``--vary`` range: ``n`` values from ``lo`` to ``hi`` (``n`` is None for sampling)."""

    key: str
    lo: float
    hi: float
    n: int | None = None

    def values(self) -> list[float]:
        return [float(v) for v in np.linspace(self.lo, self.hi, self.n or 2)]


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def journal_records(out: Path, journal, resume: bool) -> dict[str, dict]:
    """The journal's records a sweep into ``out`` reuses (``journal``: the folder's
    ``mtbmj.sweep.runner.Journal``): with ``resume``, all; without it a journal there is refused,
    guarding its runs, in words that say whether the sweep was finished (its table written: it said
    "pass --resume to continue it" of a sweep with nothing to continue) or interrupted."""
    known = journal.records()
    if known and not resume:
        if (out / TABLE).is_file() or (out / TABLE_CSV).is_file():
            raise MtbmjError(f"{out}: holds a finished sweep ({len(known)} variants); pass --resume to reuse its runs "
                             f"(the variants it lacks are computed), or choose another --out")
        raise MtbmjError(f"{out}: holds the journal of an interrupted sweep ({len(known)} variants); pass --resume "
                         f"to continue it, or choose another --out")
    return known


def numeric_key(key: str, flag: str = "--vary") -> str:
    """``key`` if it names a numeric configuration key, else a ``ConfigError`` naming it."""
    if key not in SCHEMA:
        try:
            check_value(key, 0.0)  # the schema's own message: unit hints and "did you mean"
        except ConfigError as exc:
            raise ConfigError(f"{flag}: {exc}") from None
    if SCHEMA[key] not in NUMERIC_KINDS:
        twin = next((k for k in SCHEMA if k.startswith(f"{key}_") and SCHEMA[k] in NUMERIC_KINDS), None)  # preload_N
        raise ConfigError(f"{flag}: {key} is not a number that can be varied (it is {SCHEMA[key]!r})"
                          + (f"; did you mean {twin}?" if twin else ""))
    return key


def parse_vary(text: str, count: bool | None = None, check_key: bool = True) -> Range:
    """Parse ``key=lo:hi:n`` (a grid) or ``key=lo:hi`` (a sampling range).

    ``count`` True requires ``n``, False forbids it, None accepts both; ``check_key`` False leaves
    the key to its reader (a bike sweep's keys are the bike's, ``mtbmj.sweep.bike``)."""
    if not isinstance(text, str):  # None met "'NoneType' object has no attribute 'partition'"
        raise ConfigError(f"--vary: must be a str key=lo:hi:n (a grid) or key=lo:hi, e.g. "
                          f"'sled.drop_height_mm=100:600:6', got {text!r}")
    key, eq, span = (part.strip() for part in text.partition("="))
    parts = [p.strip() for p in span.split(":")]
    endless = [p for p in parts[:2] if p.lower().lstrip("+-") in ("nan", "inf", "infinity")]
    if eq and key and len(parts) in (2, 3) and endless:  # the form right, an end no number: said so
        raise ConfigError(f"--vary {text}: lo and hi must be finite numbers, got {endless[0]!r}")
    if not eq or not key or len(parts) not in (2, 3) or not all(re.fullmatch(_NUMBER, p) for p in parts[:2]):
        raise ConfigError(f"--vary {text}: expected key=lo:hi:n (a grid) or key=lo:hi (with --samples)")
    key = numeric_key(key) if check_key else key
    lo, hi = float(parts[0]), float(parts[1])
    if not lo < hi:
        raise ConfigError(f"--vary {text}: lo must be below hi, got {lo:g} >= {hi:g}")
    n = None
    if len(parts) == 3:
        if not re.fullmatch(r"[-+]?\d+", parts[2]):
            raise ConfigError(f"--vary {text}: n must be a whole number, got {parts[2]!r}")
        n = int(parts[2])
        if n < 1:
            raise ConfigError(f"--vary {text}: n must be at least 1, got {n}")
        if n == 1:  # linspace(lo, hi, 1) is lo alone: the range typed would be dropped without a word
            part, _, name = key.rpartition(":")  # a bike sweep's fork:KEY / shock:KEY go with --fork-set / --shock-set
            option = f"--{part}-set {name}" if part in ("fork", "shock") else f"--set {key}"
            raise ConfigError(f"--vary {text}: a grid of 1 value runs lo ({lo:g}) alone, not the range to "
                              f"{hi:g}; give n of 2 or more, or the one value with {option}={lo:g}")
    if count is True and n is None:
        raise ConfigError(f"--vary {text}: a grid needs a count, key=lo:hi:n (or give --samples N)")
    if count is False and n is not None:
        raise ConfigError(f"--vary {text}: a sampled range (sensitivity, sweep --samples) takes no count; give "
                          f"the range only, key=lo:hi")
    # an end far outside what any bike has (metres typed into a mm key): one warning, the sweep runs
    from mtbmj.config import plausibility, warn

    doubts = [m for m in dict.fromkeys((plausibility(key, lo), plausibility(key, hi))) if m]
    if doubts:
        warn([f"--vary {text}: {doubts[0]}"], stacklevel=3)
    return Range(key, lo, hi, n)


def variant_list(variants) -> list:
    """``variants`` from Python as a list of mappings, or ``ConfigError``: one mapping (not in a list) or a str
    met "'str' object has no attribute 'items'"."""
    from collections.abc import Iterable, Mapping

    example = "[{'sled.drop_height_mm': 300}, {'sled.drop_height_mm': 400}]"
    if isinstance(variants, (str, bytes, Mapping)) or not isinstance(variants, Iterable):
        one = " (one variant: put it in a list)" if isinstance(variants, Mapping) else ""
        raise ConfigError(f"variants: must be a list of mappings of key to value, e.g. {example}, got "
                          f"{limits.described(variants)}{one}")
    variants = list(variants)
    if not variants:
        raise ConfigError("sweep: no variants")
    for i, v in enumerate(variants):
        if not isinstance(v, Mapping):
            raise ConfigError(f"variants[{i}]: must be a mapping of key to value, e.g. {{'sled.drop_height_mm': 300}}, "
                              f"got {limits.described(v)}")
    return variants


def _unique_keys(ranges: Sequence[Range]) -> None:
    """Refuse a key given twice; ``ranges`` from Python that are not each a ``Range`` (a str typed as on the command
    line met "'str' object has no attribute 'key'") are named so."""
    if isinstance(ranges, str) or any(not isinstance(r, Range) for r in ranges):
        raise ConfigError(f"ranges: must be a list of Range (parse_vary('sled.drop_height_mm=100:600:6') makes one), "
                          f"got {ranges!r}")
    seen = set()
    for r in ranges:
        if r.key in seen:
            raise ConfigError(f"--vary: {r.key} is given twice")
        seen.add(r.key)


def grid(ranges: Sequence[Range]) -> list[dict[str, float]]:
    """The full factorial of the ranges' values, the first range slowest."""
    if not ranges:
        raise ConfigError("--vary: no ranges given")
    _unique_keys(ranges)
    count = math.prod(r.n or 2 for r in ranges)  # counted before any value is made (n = 1e11 is refused, not allocated)
    if count > MAX_VARIANTS:
        raise ConfigError(f"--vary: the grid has {count:.3g} variants, more than the {MAX_VARIANTS} a sweep may plan")
    keys = [r.key for r in ranges]
    return [dict(zip(keys, combo)) for combo in itertools.product(*(r.values() for r in ranges))]


def latin_hypercube(rng: np.random.Generator, n: int, d: int) -> np.ndarray:
    """``n`` points of a randomised Latin hypercube in [0, 1)^d: the points of
    ``scipy.stats.qmc.LatinHypercube(d, rng=rng).random(n)`` (default scrambling, no
    optimisation), drawn the same way from the same generator (a test holds them equal).

    Written out because importing ``scipy.stats`` costs 0.4 s, a third of a whole 200-variant
    fast-engine sweep command; Sobol sequences still come from scipy."""
    own = np.random.Generator(type(rng.bit_generator)(rng.bit_generator.seed_seq.spawn(1)[0]))
    jitter = own.uniform(size=(n, d))
    strata = np.tile(np.arange(1, n + 1), (d, 1))
    for row in strata:
        own.shuffle(row)
    return (strata.T - jitter) / n


def sample(ranges: Sequence[Range], n: int, method: str = "lhs", seed: int = 0) -> list[dict[str, float]]:
    """``n`` points in the box of the ranges: Latin hypercube or scrambled Sobol, seeded."""
    if not ranges:
        raise ConfigError("--samples: needs at least one --vary key=lo:hi range")
    _unique_keys(ranges)
    n = limits.whole("--samples", n, 1, none_ok=False)
    seed = limits.whole("--seed", seed, 0, none_ok=False)  # "a" met numpy's SeedSequence, -1 "expected non-negative"
    if n > MAX_VARIANTS:
        raise ConfigError(f"--samples: {n} is more than the {MAX_VARIANTS} variants a sweep may plan")
    if method not in SAMPLING_METHODS:
        raise ConfigError(f"--method: {method!r} is not one of {', '.join(SAMPLING_METHODS)}")
    rng = np.random.default_rng(seed)
    d = len(ranges)
    if method == "lhs":
        unit = latin_hypercube(rng, n, d)
    else:
        from scipy.stats import qmc

        with warnings.catch_warnings():  # Sobol's "n should be a power of 2" balance note
            warnings.simplefilter("ignore")
            unit = qmc.Sobol(d, rng=rng).random(n)
    lower, upper = np.array([r.lo for r in ranges], dtype=float), np.array([r.hi for r in ranges], dtype=float)
    points = unit * (upper - lower) + lower  # as qmc.scale
    return [{r.key: float(v) for r, v in zip(ranges, row)} for row in points]


def _cell(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):
        return text


def from_csv(path: str | Path) -> list[dict[str, Any]]:
    """Explicit variants: a CSV whose header names configuration keys, one variant per row.
    Values are read like ``--set`` values; an empty cell keeps the base value; ``#`` lines are
    comments."""
    path = Path(path)
    text = read_text(path, ConfigError, f"--from-csv {path}", "not a text file", "table")
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ConfigError(f"--from-csv {path}: no header line")
    try:
        dialect = csv.Sniffer().sniff(lines[0], delimiters=",;\t")
    except csv.Error:
        dialect = csv.excel
    rows = list(csv.reader(lines, dialect))
    header = [h.strip() for h in rows[0]]
    for name in header:
        if not name:
            raise ConfigError(f"--from-csv {path}: empty column name in the header")
        if name not in SCHEMA:
            try:
                check_value(name, 0.0)
            except ConfigError as exc:
                raise ConfigError(f"--from-csv {path}: column {exc}") from None
    if len(set(header)) != len(header):
        twice = next(name for name in header if header.count(name) > 1)
        raise ConfigError(f"--from-csv {path}: the column {twice} is named twice")
    if len(rows) - 1 > MAX_VARIANTS:
        raise ConfigError(f"--from-csv {path}: {len(rows) - 1} rows, more than the {MAX_VARIANTS} variants a sweep may plan")
    variants = []
    for number, row in enumerate(rows[1:], 2):
        if len(row) != len(header):
            raise ConfigError(f"--from-csv {path}: row {number} has {len(row)} cells, the header {len(header)}")
        variant = {k: _cell(v.strip()) for k, v in zip(header, row) if v.strip()}
        for key, value in variant.items():
            problem = type_problem(key, value)
            if problem:
                raise ConfigError(f"--from-csv {path}: row {number}, column {key}: {problem}")
        variants.append(variant)
    if not variants:
        raise ConfigError(f"--from-csv {path}: no variants (only a header)")
    return variants


def type_problem(key: str, value: Any) -> str | None:
    """Why ``value`` cannot be in the column ``key`` of a sweep table (None when it can): the
    kind of value a key takes (a number, a word, true/false, a list of numbers) fixes the
    column's type before any variant runs. A value of the right kind but out of range (a
    negative mass) is not refused here: that variant fails and is journaled with its reason."""
    kind = SCHEMA.get(key)
    if kind is None:
        return None  # an unknown key fails when its variant runs, with the schema's message
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind in NUMERIC_KINDS:
        return None if is_number else f"{value!r} is not a number"
    if kind == "bool":
        return None if isinstance(value, bool) else f"{value!r} is not true or false"
    if kind == "list":
        ok = isinstance(value, (list, tuple)) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        return None if ok else f"{value!r} is not a list of numbers"
    return None if isinstance(value, str) else f"{value!r} is not a word"


def check_types(variants: Sequence[Mapping[str, Any]]) -> None:
    """Refuse, before any work, a variant whose value does not fit its column (see
    :func:`type_problem`)."""
    for index, overrides in enumerate(variants):
        for key, value in overrides.items():
            problem = type_problem(key, value)
            if problem:
                raise ConfigError(f"variant {index}: {key}: {problem}")


# --------------------------------------------------------------------------------------------
# Variants, ids, jobs


def canonical_value(key: str, value: Any) -> Any:
    """``value`` as a variant id and the manifest hold it: checked and converted as the schema says,
    or its repr when invalid."""
    try:
        value = check_value(key, value)
    except ConfigError:
        return repr(value)  # invalid: it fails when run, its id only has to be stable
    return list(value) if isinstance(value, tuple) else value


def variant_id(config: Config, overrides: Mapping[str, Any], engine: str = "mujoco",
               duration: float | None = None, digest: str | None = None) -> str:
    """Stable id of a variant: hash of the base configuration's digest, the run settings and the
    canonical overrides (16 hex digits). ``digest``: ``config.digest()`` when the caller has it
    already (a plan's many variants of one configuration)."""
    payload = {"config": config.digest() if digest is None else digest, "engine": engine, "duration": duration,
               "overrides": {k: canonical_value(k, overrides[k]) for k in sorted(overrides)}}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


def named_files(values: Any) -> list[Path]:
    """The regular files a string anywhere in ``values`` (nested dicts, lists and tuples) names, as
    their resolved paths, sorted, each once; a TOML configuration's ``base`` chain with it (read by
    :func:`mtbmj.config.read_chain`). A string naming no file (a preset, a terrain spec, a word) is
    no file; a FIFO or device is none either (the run refuses it, the key does not wait on it)."""
    from mtbmj.config import read_chain

    found: dict[Path, None] = {}

    def add(path: Path) -> None:
        try:
            if not path.is_file():
                return
            real = path.resolve()
        except (OSError, ValueError, RuntimeError):  # a NUL byte, a name too long, a link loop
            return
        if real in found:
            return
        found[real] = None
        if real.suffix.lower() == ".toml":  # a configuration (fork.config, shock.config): its bases too
            try:
                chain = read_chain(str(real))
            except (MtbmjError, OSError, ValueError, RecursionError):
                return  # the run refuses it with its own line; the key holds the file itself
            for _, location, _ in chain:
                if isinstance(location, Path):
                    add(location)

    def walk(value: Any) -> None:
        if isinstance(value, str):
            if value and len(value) < 4096:
                add(Path(value))
        elif isinstance(value, Mapping):
            for item in value.values():
                walk(item)
        elif isinstance(value, (list, tuple)):
            for item in value:
                walk(item)

    walk(values)
    return sorted(found)


def files_digest(values: Any) -> dict[str, str]:
    """``{path: SHA-256 of its bytes}`` of every file :func:`named_files` finds in ``values``: what a
    journal key holds so that a variant is computed again when a file it reads was edited (a bike
    sweep's terrain CSV, leverage CSV, fork or shock configuration), however its name stayed."""
    from mtbmj.textfile import read_bytes

    return {str(path): hashlib.sha256(read_bytes(path, ConfigError, str(path), "record")).hexdigest()
            for path in named_files(values)}


@dataclass(frozen=True)
class Variant:
    index: int
    id: str
    overrides: dict


@dataclass
class BatchJob:
    """What a runner gets: the base configuration, the run settings and a batch of variants.
    ``drop`` is the per-variant run (``mtbmj.drop.run.run_drop`` or a drop-in replacement)."""

    config: Config
    engine: str
    duration: float | None
    variants: list[Variant]
    traces: bool = False
    drop: Callable | None = None
    threads: int = 1  # rollout threads per process (the batched runner, ``mtbmj.sweep.batch``)


def _json_value(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, (np.floating,)):
        return _json_value(float(value))
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def flatten_summary(summary: Mapping) -> dict[str, Any]:
    """A drop summary as flat table columns: ``fork_peak1_mm``/``fork_peak1_s`` per signal and
    event, ``lift_off_s``, ``rest_fork_mm``, ``energy_dissipated_J``, ...; keys this function does
    not know are kept (nested ones joined with ``_``, lists as JSON text)."""
    flat: dict[str, Any] = {}
    for key, value in summary.items():
        if key == "events":
            for sig, events in value.items():
                for ev, point in events.items():
                    flat[f"{sig}_{ev}_mm"] = None if point is None else point["value_mm"]
                    flat[f"{sig}_{ev}_s"] = None if point is None else point["time_s"]
        elif key == "rest_mm":
            for sig, v in value.items():
                flat[f"rest_{sig}_mm"] = v
        elif isinstance(value, dict):
            for k, v in value.items():
                flat[f"{key}_{k}"] = json.dumps(v) if isinstance(v, (list, dict)) else v
        elif isinstance(value, (list, tuple)):
            flat[key] = json.dumps(list(value))
        else:
            flat[key] = value
    return {k: _json_value(v) for k, v in flat.items()}



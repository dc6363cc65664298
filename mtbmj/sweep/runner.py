"""Sweeps: many variants of one configuration, run batched over processes (or a Dask cluster),
journaled so that nothing is lost, assembled into one table.

Variants are override sets on a base configuration:

- grids: ``--vary key=lo:hi:n`` (several keys: the full factorial, the first key slowest);
- samples: ``--samples N --method lhs|sobol`` over ``--vary key=lo:hi`` ranges (scipy.stats.qmc,
  seeded, so the same command gives the same variants);
- explicit: ``--from-csv FILE`` (one variant per row, columns = configuration keys, empty cells
  keep the base value).

Each variant has an id, the SHA-256 of the base configuration's digest, the engine, the duration
and its canonical overrides: the same variant of the same sweep always has the same id.

**Nothing lost.** Variants run in batches; every finished batch is committed to
``OUT/journal/`` as one JSON part file (and, with traces, one ``.npz`` beside it, written first),
each written to a temporary name, fsynced and renamed into place, so a part is there whole or
not at all. ``--resume`` reads the journal and computes only the variants it lacks; the final
table is assembled from the journal (one row per variant, in plan order) and written
atomically. A variant that fails (bad parameters, a run that diverges) is journaled with its
reason and the sweep goes on.

**Runners.** The work of one batch is ``runner(job: BatchJob) -> list[record]``. For the MuJoCo
engine the default is ``"batch"``, :func:`mtbmj.sweep.batch.run_batch_rollout` (the batch's variants
stepped together through ``mujoco.rollout`` on the compiled force laws); ``"single"``,
:func:`run_batch`, calls ``job.drop`` (``mtbmj.drop.run.run_drop``) per variant (the default for the
ODE engine or with a custom ``drop``). Either gives the same records; the runner does not touch
the journal, the table or the backends.
"""
from __future__ import annotations

import io
import json
import math
import os
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from mtbmj.config import SCHEMA, Config, warn
from mtbmj.errors import ConfigError, MtbmjError

from mtbmj import limits, output
from mtbmj.sweep.variants import (BACKENDS, BatchJob, JOURNAL, MANIFEST, NUMERIC_KINDS, OUTPUT_COLUMNS, RUNNERS, Range, SIGNALS, STATUS_COLUMNS, TABLE, TABLE_CSV, TIMINGS, TRACES, Variant, canonical_value, variant_list, check_types, flatten_summary, from_csv, grid, journal_records, parse_vary, sample, variant_id)
from mtbmj.sweep.single import run_batch, run_variant


# --------------------------------------------------------------------------------------------
# Journal


def _commit(path: Path, write: Callable[[Any], None]) -> None:
    """Write a file durably and atomically: temporary name, fsync, rename, fsync the directory."""
    tmp = path.parent / f".{path.name}.{uuid.uuid4().hex[:12]}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask decides the mode
    try:
        with os.fdopen(fd, "wb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    output.fsync_dir(path.parent)


class Journal:
    """``OUT/journal/part-*.json``: one committed batch each; ``part-*.npz`` holds its traces
    (committed before the JSON that names it, so a JSON part is the commit of both)."""

    def __init__(self, out_dir: Path):
        self.dir = Path(out_dir) / JOURNAL

    def parts(self) -> list[Path]:
        return sorted(self.dir.glob("part-*.json")) if self.dir.is_dir() else []

    def records(self) -> dict[str, dict]:
        """id -> record (the last committed one; with traces preferred to without)."""
        found: dict[str, dict] = {}
        for part in self.parts():
            try:
                data = json.loads(part.read_text())
                records = data["records"]
            except (OSError, ValueError, KeyError, TypeError):
                continue  # unreadable: its variants are computed again
            for rec in records:
                if not isinstance(rec, dict) or "id" not in rec:
                    continue
                rec["_part"] = part
                old = found.get(rec["id"])
                if old is None or rec.get("has_traces") or not old.get("has_traces"):
                    found[rec["id"]] = rec
        return found

    def append(self, records: list[dict]) -> None:
        self.dir.mkdir(parents=True, exist_ok=True)
        stem = f"part-{time.strftime('%Y%m%dT%H%M%S')}-{uuid.uuid4().hex[:12]}"
        with_traces = [r for r in records if r.get("traces") is not None]
        if with_traces:
            arrays = {}
            for r in with_traces:
                for name, values in r["traces"].items():
                    arrays[f"{r['id']}/{name}"] = values
            _commit(self.dir / f"{stem}.npz", lambda h: np.savez_compressed(h, **arrays))
        rows = []
        for r in records:
            row = {k: v for k, v in r.items() if k != "traces"}
            row["has_traces"] = r.get("traces") is not None
            rows.append(row)
        payload = json.dumps({"records": rows, "traces": f"{stem}.npz" if with_traces else None}).encode()
        _commit(self.dir / f"{stem}.json", lambda h: h.write(payload))

    def traces(self, record: dict) -> dict[str, np.ndarray] | None:
        if not record.get("has_traces"):
            return None
        npz = record["_part"].with_suffix(".npz")
        with np.load(npz) as data:
            prefix = f"{record['id']}/"
            return {k[len(prefix):]: data[k] for k in data.files if k.startswith(prefix)}


# --------------------------------------------------------------------------------------------
# Progress


class SweepProgress:
    """Progress on stderr: a bar with rate and ETA redrawn in place on a terminal, otherwise one
    line every ``interval`` seconds."""

    def __init__(self, total: int, already: int = 0, label: str = "sweep", stream=None,
                 interval: float = 10.0, enabled: bool = True):
        self.total, self.already, self.label = total, already, label
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = enabled
        self.interval = interval
        self.done = 0
        self.failed = 0
        self.start = time.perf_counter()
        self.last_line = self.start

    def text(self) -> str:
        elapsed = time.perf_counter() - self.start
        todo = self.total - self.already
        rate = self.done / elapsed if elapsed > 0 and self.done else 0.0
        eta = (todo - self.done) / rate if rate else float("nan")
        count = f"{self.already + self.done}/{self.total}"
        failed = f", {self.failed} failed" if self.failed else ""
        eta_text = _duration(eta) if math.isfinite(eta) else "?"
        return f"{count} variants{failed}, {rate:.1f}/s, elapsed {_duration(elapsed)}, ETA {eta_text}"

    def update(self, done: int, failed: int = 0) -> None:
        self.done += done
        self.failed += failed
        if not self.enabled:
            return
        if self.tty:
            fraction = (self.already + self.done) / max(self.total, 1)
            bar = "#" * int(fraction * 30)
            print(f"\r{self.label} [{bar:<30}] {fraction * 100:5.1f}% {self.text()}   ", end="",
                  file=self.stream, flush=True)
        elif time.perf_counter() - self.last_line >= self.interval and self.already + self.done < self.total:
            self.last_line = time.perf_counter()
            print(f"{self.label}: {self.text()}", file=self.stream, flush=True)

    def finish(self) -> None:
        if self.enabled:
            if not self.done:
                print(("\r" if self.tty else "") + f"{self.label}: all {self.total} variants from the journal",
                      file=self.stream, flush=True)
                return
            print(("\r" if self.tty else "") + f"{self.label}: {self.text()}" + (" " * 10 if self.tty else ""),
                  file=self.stream, flush=True)

    def abandon(self) -> None:
        if self.enabled and self.tty:
            print("\r" + " " * 100 + "\r", end="", file=self.stream, flush=True)


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


# --------------------------------------------------------------------------------------------
# Backends


def _batches(variants: list[Variant], size: int) -> list[list[Variant]]:
    return [variants[i:i + size] for i in range(0, len(variants), size)]


def _even_batches(variants: list[Variant], workers: int) -> list[list[Variant]]:
    """The default split: batches of up to 16 variants, about eight per worker, their number a
    multiple of ``workers`` and their sizes within one of each other, so every worker gets about
    as many variants (200 variants on 2 workers: 18 batches of 11-12, 100 each; cut into batches
    of 12 they were 17, one worker's 108 variants setting the sweep's end)."""
    n = len(variants)
    if n == 0:
        return []
    size = max(1, min(16, n // (workers * 8)))
    count = -(-n // size)
    count = min(n, -(-count // workers) * workers)
    base, extra = divmod(n, count)
    out, at = [], 0
    for k in range(count):
        step = base + (1 if k < extra else 0)
        out.append(variants[at:at + step])
        at += step
    return out


def _warm(engine: str) -> None:
    """A worker's first task from :func:`start_pool`: load the compiled code its batches run."""
    from mtbmj.controllers import native

    try:
        native.expect_many()
        if engine == "fast":
            from mtbmj.drop import engine_fast

            engine_fast.kernel()
    except Exception:  # noqa: BLE001 - only a head start: the batches themselves report any failure
        pass


def start_pool(workers: int | None = None, engine: str = "mujoco"):
    """A local worker pool for ``run_sweep(pool=...)``, its processes started now and loading
    the engine's compiled code (numba's cache, about 0.3 s each) while the caller goes on
    preparing the variants (the command line: ``scipy.stats`` for the samples, 0.4 s). The caller
    owns it: ``shutdown`` it when done."""
    from mtbmj.workers import process_pool

    count = workers or (os.cpu_count() or 1)
    pool = process_pool(count)
    for _ in range(count):
        pool.submit(_warm, engine)
    return pool


def _prefetch_table_libraries():
    """Import pandas and pyarrow (0.3 s) in a thread while the workers compute, when this
    process would otherwise only wait for them; joined before the table is made."""
    import threading

    def load():
        try:
            import pandas  # noqa: F401
            import pyarrow.parquet  # noqa: F401
        except Exception:  # noqa: BLE001 - the table's own import reports it
            pass

    thread = threading.Thread(target=load, name="mtbmj-sweep-prefetch", daemon=True)
    thread.start()
    return thread


def _run_local(jobs: list[BatchJob], runner, workers: int, on_done, pool=None) -> list[str]:
    from concurrent.futures import as_completed

    from mtbmj.workers import process_pool

    problems = []
    owned = pool is None
    if owned:
        pool = process_pool(min(workers, len(jobs)))
    try:
        futures = {pool.submit(runner, job): job for job in jobs}
        for future in as_completed(futures):
            try:
                records = future.result()
            except Exception as exc:  # a worker died (killed, out of memory): not journaled
                problems.append(f"{type(exc).__name__}: {exc}")
                continue
            on_done(records)
    except BaseException:
        if owned:
            pool.terminate()
        raise
    if owned:
        pool.shutdown(wait=True)
    return problems


def _client(scheduler):
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover
        raise MtbmjError("--backend dask needs dask distributed: pip install 'dask[distributed]'") from None
    if scheduler is None:
        raise MtbmjError("--backend dask needs --scheduler ADDRESS (e.g. tcp://10.0.0.5:8786)")
    if not isinstance(scheduler, str):
        return scheduler, False  # a Client given from Python
    try:
        return Client(scheduler, timeout="20s"), True
    except (OSError, TimeoutError, ValueError) as exc:
        raise MtbmjError(f"--scheduler {scheduler}: cannot connect ({exc})") from None


def _run_dask(jobs: list[BatchJob], runner, scheduler, on_done) -> list[str]:
    from distributed import as_completed

    client, own = _client(scheduler)
    problems = []
    futures = []
    try:
        futures = [client.submit(runner, job, pure=False) for job in jobs]
        for future in as_completed(futures):
            try:
                records = future.result()
            except Exception as exc:  # a lost worker (KilledWorker): not journaled
                problems.append(f"{type(exc).__name__}: {exc}")
                continue
            on_done(records)
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        if own:
            client.close()
    return problems


# --------------------------------------------------------------------------------------------
# The sweep


@dataclass
class SweepResult:
    table: Any  # pandas.DataFrame: one row per variant, in plan order
    files: list[Path]
    total: int
    computed: int  # variants computed by this call
    reused: int  # variants taken from the journal
    failed: int
    wall_time_s: float
    out_dir: Path
    problems: list[str] = field(default_factory=list)

    def line(self) -> str:
        failed = f", {self.failed} failed: {self.first_failure()}" if self.failed else ""
        return (f"{self.total} variants ({self.computed} computed, {self.reused} from the journal{failed}) in "
                f"{self.wall_time_s:.1f} s{self.envelope()}; wrote {', '.join(p.name for p in self.files)} to "
                f"{self.out_dir}")

    def first_failure(self) -> str:
        """"the first, variant 4: <its reason>" (the table's ``reason`` column holds every one)."""
        if "status" not in self.table or "reason" not in self.table:
            return "see the table's reason column"
        rows = self.table[self.table["status"] != "ok"]
        if not len(rows):
            return "see the table's reason column"
        row = rows.iloc[0]
        return f"the first, variant {row.get('variant', rows.index[0])}: {row['reason']}"

    def envelope(self) -> str:
        """"; 12 variants bottomed out on the bumper (deepest 121.1 mm), 3 hit the hard stop ..."
        (``mtbmj.readout.endtravel``), or "" when none did."""
        from mtbmj.readout.endtravel import ELEMENTS, WHAT

        parts = []
        for key in ELEMENTS:
            column = f"{key}_count"
            if column not in self.table:
                continue
            counts = self.table[column].fillna(0)
            hit = int((counts > 0).sum())
            if hit:
                deepest = float(self.table[f"{key}_deepest_mm"].max())
                parts.append(f"{hit} {'variant' if hit == 1 else 'variants'} {WHAT[key]} (deepest {deepest:.1f} mm)")
        return "".join(f"; {p}" for p in parts)


def plan(config: Config, overrides_list: Iterable[Mapping[str, Any]], engine: str = "mujoco",
         duration: float | None = None) -> list[Variant]:
    digest = config.digest()  # once for the plan, not once per variant
    return [Variant(i, variant_id(config, ov, engine, duration, digest), dict(ov)) for i, ov in enumerate(overrides_list)]


def run_sweep(config: Config | str, variants: Sequence[Mapping[str, Any]], out_dir: str | Path, *,
              engine: str = "mujoco", duration: float | None = None, base_overrides: Mapping | None = None,
              workers: int | None = None, batch_size: int | None = None, backend: str = "local",
              scheduler=None, traces: bool = False, csv: bool = False, resume: bool = False,
              progress: bool | SweepProgress = False, runner: Callable[[BatchJob], list[dict]] | str | None = None,
              drop: Callable | None = None, manifest_extra: Mapping | None = None, threads: int = 1,
              extra_files: Callable[[Any], Mapping[str, bytes]] | None = None, pool=None) -> SweepResult:
    """Run ``variants`` (override sets) of ``config`` and write ``OUT/sweep.parquet`` (and
    ``sweep.csv``, ``traces.h5`` on request, ``sweep.json`` always).

    ``runner(job)`` computes one batch: ``"batch"`` (:func:`mtbmj.sweep.batch.run_batch_rollout`, the
    default for engine "mujoco" without a custom ``drop``), ``"single"`` (:func:`run_batch`, which
    calls ``drop`` - ``mtbmj.drop.run.run_drop`` - per variant) or a picklable top-level function.
    ``threads``: rollout threads per worker process for the batched runner. With
    ``resume`` the journal in ``out_dir`` is reused and only missing variants run.
    ``extra_files(table)`` adds files (name -> bytes) to the folder, written with the table.
    ``pool`` (:func:`start_pool`, local backend) runs the batches in workers started earlier.

    Before any work: every variant's values are checked to fit their columns, the base run's
    length against the memory available, and ``out_dir`` must be writable and not in use by
    another mtbmj run (``mtbmj.output.claim``, a lock on ``OUT/.lock``). The finished folder (journal, table, manifest,
    timings, traces) replaces the old one in one step (:mod:`mtbmj.output`)."""
    from mtbmj.drop.chain import resolve
    from mtbmj.drop.run import ENGINES

    started = time.perf_counter()
    if engine not in ENGINES:
        raise ConfigError(f"engine: {engine!r} is not one of {', '.join(ENGINES)}")
    if backend not in BACKENDS:
        raise ConfigError(f"--backend: {backend!r} is not one of {', '.join(BACKENDS)}")
    limits.check_duration("duration", duration)
    workers = limits.whole("--workers", workers, 1)
    batch_size = limits.whole("--batch-size", batch_size, 1)
    threads = limits.whole("threads", threads, 1, none_ok=False)
    traces, csv, resume = (limits.switch(label, given) for label, given in
                           (("traces", traces), ("csv", csv), ("resume", resume)))
    variants = variant_list(variants)
    from mtbmj.extras import require

    # before any work: the table needs pandas and pyarrow, the traces h5py
    require("sweep", "mtbmj sweep", ["pandas", "pyarrow"] + (["h5py"] if traces else []))
    if backend == "dask":
        require("dask", "--backend dask")
    if runner is None:
        runner = "batch" if engine in ("mujoco", "fast") and drop is None else "single"
    if isinstance(runner, str):
        if runner not in RUNNERS:
            raise ConfigError(f"--runner: {runner!r} is not one of {', '.join(RUNNERS)}")
        if runner == "batch" and engine not in ("mujoco", "fast"):  # said, not refused: it runs, one by one
            warn([f"--runner batch: the {engine} engine has no batched runner, so each variant runs alone (as "
                  f"--runner single); --engine mujoco or fast steps the variants together"])
        if runner == "batch" and engine == "fast":
            from mtbmj.sweep.fast import run_batch_fast as runner
        elif runner == "batch":
            from mtbmj.sweep.batch import run_batch_rollout as runner
        else:
            runner = run_batch
    check_types(variants)
    cfg = resolve(config, base_overrides)
    if cfg.get("solver.timestep_s") is not None or duration is not None:  # the base run's length, before any work
        from mtbmj.compose import setup as compose_setup
        from mtbmj.limits import check_run

        base_setup = compose_setup(cfg)
        check_run(base_setup.duration if duration is None else duration, base_setup.timestep, base_setup.sample_rate,
                  "solver.duration_s" if duration is None else "duration")  # the length given, by its name
    out = Path(out_dir)
    planned = plan(cfg, variants, engine, duration)
    with output.claim(out, "sweep", folders=(JOURNAL,)):
        journal = Journal(out)
        known = journal_records(out, journal, resume)
        return _sweep(planned, cfg, out, journal, known, started, engine=engine, duration=duration,
                      base_overrides=base_overrides, workers=workers, batch_size=batch_size, backend=backend,
                      scheduler=scheduler, traces=traces, csv=csv, progress=progress, runner=runner,
                      drop=drop, manifest_extra=manifest_extra, threads=threads, extra_files=extra_files,
                      pool=pool)


def _sweep(planned, cfg, out, journal, known, started, *, engine, duration, base_overrides, workers, batch_size,
           backend, scheduler, traces, csv, progress, runner, drop, manifest_extra, threads,
           extra_files, pool=None) -> SweepResult:
    def complete(rec):
        return rec is not None and (rec.get("has_traces") or not traces or rec.get("status") != "ok")

    todo, seen = [], set()
    for v in planned:
        if not complete(known.get(v.id)) and v.id not in seen:
            todo.append(v)
            seen.add(v.id)
    unique = len({v.id for v in planned})
    reused = unique - len(todo)
    workers = workers or (os.cpu_count() or 1)
    batches = _even_batches(todo, workers) if batch_size is None else _batches(todo, batch_size)
    jobs = [BatchJob(cfg, engine, duration, batch, traces, drop, threads) for batch in batches]

    bar = progress if isinstance(progress, SweepProgress) else SweepProgress(unique, reused, enabled=bool(progress))
    bar.total, bar.already = unique, reused
    counts = {"computed": 0}

    def on_done(records):
        try:
            journal.append(records)
        except OSError as exc:
            raise MtbmjError(f"{journal.dir}: cannot write the journal ({exc.strerror or exc})") from None
        counts["computed"] += len(records)
        bar.update(len(records), sum(r["status"] != "ok" for r in records))

    problems: list[str] = []
    tables = _prefetch_table_libraries() if jobs else None
    try:
        if jobs:
            if backend == "local":
                problems = _run_local(jobs, runner, workers, on_done, pool)
            else:
                problems = _run_dask(jobs, runner, scheduler, on_done)
    except BaseException:
        bar.abandon()
        raise
    bar.finish()
    if problems:
        missing = len(todo) - counts["computed"]
        raise MtbmjError(f"{missing} variants were not computed ({problems[0]}); the others are journaled "
                         f"in {journal.dir}: run again with --resume")

    if tables is not None:
        tables.join()
    records = journal.records()
    table = assemble(planned, records)
    files = {TABLE: parquet_bytes(table), TIMINGS: timings_csv(planned, records)}
    if csv:
        files[TABLE_CSV] = table.map(output.spreadsheet_text).to_csv(index=False).encode()
    manifest = {
        "config": cfg.name, "config_sha256": cfg.digest(), "config_sources": list(cfg.sources),
        "base_overrides": {k: canonical_value(k, v) for k, v in (base_overrides or {}).items()},
        "engine": engine, "duration_s": duration, "variants": len(planned),
        "failed": int((table["status"] != "ok").sum()), "backend": backend,
        "versions": _versions(), **(manifest_extra or {}),
    }
    files[MANIFEST] = (json.dumps(manifest, indent=2, default=_json_default) + "\n").encode()
    if extra_files is not None:
        files.update(extra_files(table))
    with output.staged_folder(out, keep=(JOURNAL,)) as stage:
        if traces:
            write_traces(stage / TRACES, planned, records, journal, cfg, engine)
        for name, content in files.items():
            output.write_file(stage / name, content)
    written = ([out / TRACES] if traces else []) + [out / name for name in files]
    return SweepResult(table=table, files=written, total=len(planned), computed=counts["computed"],
                       reused=reused, failed=manifest["failed"], wall_time_s=time.perf_counter() - started,
                       out_dir=out, problems=problems)


def timings_csv(planned: Sequence[Variant], records: Mapping[str, dict]) -> bytes:
    """``variant,variant_id,wall_time_s``: how long each variant took (empty: unknown)."""
    lines = ["variant,variant_id,wall_time_s"]
    for v in planned:
        wall = records[v.id].get("wall_time_s")
        lines.append(f"{v.index},{v.id},{'' if wall is None else repr(float(wall))}")
    return ("\n".join(lines) + "\n").encode()


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, (set, tuple)):
        return list(value)
    return str(value)


def _versions() -> dict:
    from mtbmj.result import versions

    return versions()


def assemble(planned: Sequence[Variant], records: Mapping[str, dict]):
    """The table: one row per planned variant (inputs, outputs, status), in plan order.

    Every column has one type whatever the values: an input column the type of its key (a
    number: float, NaN where the base value is kept; a word or a list: text, a list as JSON), an
    output column float when its values are numbers, else text; so the table always writes.
    Timings are not in the table (see :func:`timings_csv`): equal sweeps give equal tables."""
    import pandas as pd

    inputs = list(dict.fromkeys(k for v in planned for k in v.overrides))
    extras = list(dict.fromkeys(k for r in records.values() for k in r.get("outputs", {}) if k not in OUTPUT_COLUMNS))
    outputs = OUTPUT_COLUMNS + extras
    rows = []
    for v in planned:
        rec = records[v.id]
        row = {"variant": v.index, "variant_id": v.id}
        row.update({k: v.overrides.get(k) for k in inputs})
        got = rec.get("outputs") or {}
        row.update({k: got.get(k) for k in outputs})
        row.update(status=str(rec["status"]), reason=str(rec.get("reason", "") or ""))
        rows.append(row)
    table = pd.DataFrame(rows, columns=["variant", "variant_id"] + inputs + outputs + STATUS_COLUMNS)
    for column in inputs:
        kind = SCHEMA.get(column)
        numeric = kind in NUMERIC_KINDS
        table[column] = _typed(table[column], numeric=numeric, boolean=kind == "bool")
    for column in outputs:  # flags stay booleans (missing where a variant failed)
        table[column] = _typed(table[column], boolean=True)
    return table


def _present(x) -> bool:
    return x is not None and not (isinstance(x, float) and math.isnan(x))


def _typed(series, numeric: bool | None = None, boolean: bool = False):
    """``series`` as one type: float (numbers, NaN for gaps), nullable boolean, or text (None for
    gaps). ``numeric`` None: float when every value present is a number."""
    import pandas as pd

    values = [x for x in series if _present(x)]
    is_num = [isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_)) for x in values]
    if numeric is None:
        numeric = all(is_num)
    if numeric and all(is_num):
        return pd.to_numeric(series, errors="coerce").astype(float)
    if boolean and all(isinstance(x, (bool, np.bool_)) for x in values):
        return series.astype("boolean")
    def text(x):
        if not _present(x):
            return None
        if isinstance(x, str):
            return x
        if isinstance(x, (list, tuple)):
            return json.dumps([float(v) if isinstance(v, (int, float)) else str(v) for v in x])
        return json.dumps(x, default=str)
    return series.map(text).astype(object)


def parquet_bytes(table) -> bytes:
    import pyarrow as pa
    import pyarrow.parquet as pq

    buffer = io.BytesIO()
    pq.write_table(pa.Table.from_pandas(table, preserve_index=False), buffer, compression="zstd")
    return buffer.getvalue()


def write_traces(path: Path, planned: Sequence[Variant], records: Mapping[str, dict], journal: Journal,
                 config: Config, engine: str) -> Path:
    """Traces as HDF5: ``sled_mm``, ``fork_mm``, ``tire_mm`` as [variant, time] (chunked, gzip),
    ``time_s`` as [time] (or [variant, time] when the grids differ), ``variant_id`` as [variant];
    a failed variant's row is NaN. Written to a temporary file and renamed into place."""
    import h5py

    cache: dict[str, dict | None] = {}
    lengths, grids = [], []
    for v in planned:
        tr = cache.setdefault(v.id, journal.traces(records[v.id]))
        if tr is not None:
            lengths.append(len(tr["time_s"]))
            grids.append(tr["time_s"])
    length = max(lengths, default=0)
    common = all(len(g) == len(grids[0]) and np.array_equal(g, grids[0]) for g in grids) if grids else True
    n = len(planned)
    chunk_rows = max(1, min(n, max(1, (1 << 20) // max(8 * length, 1))))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f".{path.name}.{uuid.uuid4().hex[:12]}.tmp"  # h5py creates it, mode per the umask
    try:
        with h5py.File(tmp, "w") as h5:
            h5.attrs.update({"config": config.name, "config_sha256": config.digest(), "engine": engine,
                             "conventions": "sled zero at tire touch, fork zero at unloaded full extension, "
                                            "tire = sled - fork, compression positive; 1 kHz logged signals",
                             "failed_rows": "NaN"})
            h5.create_dataset("variant_id", data=np.array([v.id for v in planned], dtype="S16"))
            h5.create_dataset("variant", data=np.array([v.index for v in planned], dtype=np.int64))
            kw = dict(shape=(n, length), dtype="f8", chunks=(chunk_rows, max(length, 1)) if length else None,
                      compression="gzip" if length else None, compression_opts=4 if length else None,
                      shuffle=bool(length), fillvalue=np.nan)
            names = [f"{s}_mm" for s in SIGNALS]
            sets = {name: h5.create_dataset(name, **kw) for name in names}
            if common:
                h5.create_dataset("time_s", data=grids[0] if grids else np.zeros(0))
            else:
                sets["time_s"] = h5.create_dataset("time_s", **kw)
            for i, v in enumerate(planned):
                tr = cache[v.id]
                if tr is None:
                    continue
                for name, ds in sets.items():
                    ds[i, : len(tr[name])] = tr[name]
            for name in names:
                sets[name].attrs["unit"] = "mm"
        with open(tmp, "rb+") as handle:
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_table(out_dir: str | Path):
    """The sweep table of ``out_dir`` as a ``pandas.DataFrame``."""
    import pandas as pd

    return pd.read_parquet(Path(out_dir) / TABLE)


__all__ = ["Range", "Variant", "BatchJob", "SweepResult", "SweepProgress", "Journal", "parse_vary", "grid",
           "sample", "from_csv", "variant_id", "plan", "run_sweep", "run_batch", "run_variant",
           "flatten_summary", "assemble", "read_table", "OUTPUT_COLUMNS"]

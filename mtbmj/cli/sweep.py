"""``mtbmj sweep``: many variants of a configuration (grids, samples, a CSV) into one table, and
the options it shares with ``mtbmj sensitivity``."""
from __future__ import annotations

from pathlib import Path

from mtbmj.cli.common import ENGINE_HELP, ENGINE_NAMES, add_out, overrides
from mtbmj.errors import ConfigError


def positive(flag: str, value, minimum: int = 1):
    """``flag``'s whole number at least ``minimum`` (the numeric gate, ``limits.ARGUMENTS``, lets a
    sample count of 0 through)."""
    if value is not None and value < minimum:
        raise ConfigError(f"{flag}: must be at least {minimum}, got {value}")


def variants_from_args(args) -> tuple[list[dict], dict]:
    """The override sets a ``sweep`` command asks for, and a description for the manifest."""
    from mtbmj import sweep

    given = [bool(args.vary), args.from_csv is not None]
    if args.from_csv is not None and (args.vary or args.samples is not None):
        raise ConfigError("--from-csv: give either --from-csv or --vary (and --samples), not both")
    if not any(given):
        raise ConfigError("sweep: give --vary key=lo:hi:n, --samples N with --vary key=lo:hi, or --from-csv FILE")
    if args.from_csv is not None:
        return sweep.from_csv(args.from_csv), {"kind": "csv", "file": str(args.from_csv)}
    if args.samples is not None:
        positive("--samples", args.samples)
        ranges = [sweep.parse_vary(v, count=False) for v in args.vary]
        method = args.method or "lhs"
        return (sweep.sample(ranges, args.samples, method, args.seed),
                {"kind": method, "samples": args.samples, "seed": args.seed,
                 "ranges": [[r.key, r.lo, r.hi] for r in ranges]})
    if args.method is not None and args.method != "lhs":
        raise ConfigError("--method: only with --samples N")
    ranges = [sweep.parse_vary(v, count=True) for v in args.vary]
    return sweep.grid(ranges), {"kind": "grid", "ranges": [[r.key, r.lo, r.hi, r.n] for r in ranges]}


def check_shared_options(args) -> None:
    if args.backend == "dask" and not args.scheduler:
        raise ConfigError("--backend dask needs --scheduler ADDRESS (e.g. tcp://10.0.0.5:8786)")
    if args.scheduler and args.backend != "dask":
        raise ConfigError("--scheduler: only with --backend dask")


def _bike_sweep(args) -> int:
    from mtbmj.sweep import bike as bike_sweep
    from mtbmj.cli.bike import bike_overrides
    from mtbmj.cli.common import Progress

    if args.roll is None or args.speed is None:
        raise ConfigError(f"sweep {args.config}: a bike sweep needs --roll TERRAIN and --speed V")
    if args.from_csv is not None or args.samples is not None:
        raise ConfigError("sweep: a bike sweep takes a grid (--vary KEY=LO:HI:N)")
    from mtbmj import sweep

    if not args.vary:
        raise ConfigError("sweep: give --vary KEY=LO:HI:N (a bike key, or fork:KEY / shock:KEY)")
    variants = sweep.grid([sweep.parse_vary(v, count=True, check_key=False) for v in args.vary])
    base = bike_overrides(args)
    from mtbmj import output

    with output.claim(args.out, "sweep", folders=("journal",)):  # the journal is mtbmj's from the start
        table = Progress(f"sweep bike {args.config} ({len(variants)} variants)", not args.quiet).around(
            lambda progress: bike_sweep.run(args.config, args.roll, args.speed, variants, args.duration, base,
                                            progress, out_dir=args.out, resume=args.resume))
        keys = list(variants[0])
        written = bike_sweep.write(table, args.out, args.config, args.roll, args.speed, keys)
    ok = table[table["status"] == "ok"]
    crashes = int(ok["crashes_count"].sum()) if len(ok) else 0
    print(f"sweep bike {args.config} over {args.roll} at {args.speed:g} m/s: {len(ok)} of {len(table)} variants ran"
          f"{f', {crashes} crashed' if crashes else ''}; front travel peak {ok['max_front_travel_mm'].min():.1f}-"
          f"{ok['max_front_travel_mm'].max():.1f} mm; wrote {len(written)} files to {args.out}"
          if len(ok) else f"sweep bike {args.config}: every variant failed (the first: {table['reason'].iloc[0]}; see sweep.csv); wrote {len(written)} "
                          f"files to {args.out}")
    return 0 if len(ok) else 1  # every variant failed: nothing to read


def cmd_sweep(args) -> int:
    from mtbmj.sweep.runner import SweepProgress, run_sweep, start_pool
    from mtbmj.cli.presets import is_bike

    if is_bike(args.config):
        return _bike_sweep(args)
    from mtbmj.cli.common import given_options

    given = given_options(args, roll=None, speed=None, fork_set=None, shock_set=None)
    if given:
        raise ConfigError(f"{given}: only for a bike sweep (CONFIG a bike preset or bike file)")
    check_shared_options(args)
    # the workers start now and load the compiled engine while the variants are drawn
    pool = start_pool(args.workers, args.engine) if args.backend == "local" else None
    try:
        variants, how = variants_from_args(args)
        bar = SweepProgress(len(variants), enabled=not args.quiet)
        result = run_sweep(args.config, variants, args.out, engine=args.engine, duration=args.duration,
                           base_overrides=overrides(args.set), workers=args.workers, batch_size=args.batch_size,
                           backend=args.backend, scheduler=args.scheduler, traces=args.traces, csv=args.csv,
                           resume=args.resume, progress=bar, manifest_extra={"variants_from": how},
                           runner=args.runner, threads=args.threads, pool=pool,
                           extra_files=None if args.no_figure else _figure_files(args.config, variants))
    except BaseException as exc:
        if pool is not None:
            pool.terminate()
        if isinstance(exc, KeyboardInterrupt):
            raise KeyboardInterrupt(f"finished variants are journaled in {args.out / 'journal'}: continue with the "
                                    f"same command and --resume") from None
        raise
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)
    print(f"sweep {args.config}: {result.line()}")
    return 1 if result.total and result.failed == result.total else 0  # every variant failed: nothing to read


def add_shared_options(p) -> None:
    p.add_argument("config", help="preset name (S1..S14, reference) or a TOML file")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a key of the base configuration (repeatable)")
    p.add_argument("--duration", type=float, help="simulated time in s (default: solver.duration_s)")
    p.add_argument("--engine", choices=ENGINE_NAMES, default="mujoco", help=ENGINE_HELP)
    p.add_argument("--workers", type=int, help="processes on the local backend (default: one per core)")
    p.add_argument("--backend", choices=("local", "dask"), default="local",
                   help="local processes, or a Dask distributed cluster (with --scheduler)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--resume", action="store_true", help="continue an interrupted run in --out: compute only missing variants")
    p.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")


def _figure_files(config: str, variants):
    """``extra_files`` for run_sweep: ``sweep.png`` for a sweep over one or two keys."""
    keys = list(dict.fromkeys(k for v in variants for k in v))

    def files(table) -> dict:
        from mtbmj.readout.quicklook import png
        from mtbmj.sweep.figure import sweep_figure

        fig = sweep_figure(table, keys, f"sweep of {config} over {' and '.join(keys)}")
        return {} if fig is None else {"sweep.png": png(fig)}

    return files


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep", help="run many variants of a configuration: grids, LHS/Sobol samples or a CSV; one table",
        description="Run variants of CONFIG batched over processes (or a Dask cluster) and write one table "
                    "(sweep.parquet; sweep.csv with --csv) of every variant's inputs and summary outputs, and "
                    "with --traces the sled/fork/tire histories in traces.h5. Finished variants are journaled: an "
                    "interrupted sweep continues with --resume; a failing variant is recorded with its reason.")
    add_shared_options(p)
    p.add_argument("--vary", action="append", metavar="KEY=LO:HI[:N]",
                   help="a grid of N values (repeatable: full factorial), or with --samples a range")
    p.add_argument("--samples", type=int, metavar="N", help="N sampled variants in the --vary ranges")
    p.add_argument("--method", choices=("lhs", "sobol"), help="sampling: Latin hypercube (default) or Sobol")
    p.add_argument("--from-csv", type=Path, metavar="FILE", help="explicit variants: columns = configuration keys")
    add_out(p, "out/sweep")
    p.add_argument("--traces", action="store_true", help="also write the histories to traces.h5")
    p.add_argument("--csv", action="store_true", help="also write the table as sweep.csv")
    p.add_argument("--no-figure", action="store_true",
                   help="do not draw sweep.png (drawn for a sweep over one or two keys: lines or heat maps)")
    p.add_argument("--batch-size", type=int, help="variants per journaled batch (default: automatic, <= 16)")
    p.add_argument("--runner", choices=("batch", "single"),
                   help="batch: variants stepped together in mujoco.rollout on the compiled laws (default for "
                        "--engine mujoco); single: one run_drop per variant")
    p.add_argument("--threads", type=int, default=1, help="rollout threads per process with --runner batch (default 1)")
    p.add_argument("--roll", metavar="TERRAIN", help="a bike sweep (CONFIG a bike preset or file): the terrain")
    p.add_argument("--speed", type=float, help="a bike sweep: the speed in m/s")
    p.add_argument("--fork-set", action="append", metavar="KEY=VALUE", dest="fork_set",
                   help="a bike sweep: a key of the fork's configuration for every variant (repeatable)")
    p.add_argument("--shock-set", action="append", metavar="KEY=VALUE", dest="shock_set",
                   help="a bike sweep: a key of the shock's configuration for every variant (repeatable)")
    p.set_defaults(func=cmd_sweep)

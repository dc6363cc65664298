"""``mtbmj sensitivity``: Sobol or Morris indices of drop outputs (SALib), run through the sweep."""
from __future__ import annotations


from mtbmj.cli.common import add_out, overrides
from mtbmj.cli.sweep import add_shared_options, check_shared_options
from mtbmj.errors import ConfigError


def cmd_sensitivity(args) -> int:
    from mtbmj import sweep
    from mtbmj.sweep.sensitivity import run_sensitivity

    check_shared_options(args)
    if not args.vary:
        raise ConfigError("sensitivity: give at least one --vary key=lo:hi")
    ranges = [sweep.parse_vary(v, count=False) for v in args.vary]
    outputs = args.output.split(",")
    bar = sweep.SweepProgress(0, enabled=not args.quiet, label="sensitivity")
    try:
        result = run_sensitivity(args.config, ranges, outputs, args.out, method=args.method, n=args.samples,
                                 seed=args.seed, levels=args.levels, engine=args.engine, duration=args.duration,
                                 base_overrides=overrides(args.set), workers=args.workers, backend=args.backend,
                                 scheduler=args.scheduler, resume=args.resume, progress=bar)
    except KeyboardInterrupt:
        raise KeyboardInterrupt(f"finished runs are journaled in {args.out / 'journal'}: continue with the same "
                                f"command and --resume") from None
    print(f"sensitivity {args.config}: {result.line()}; wrote {len(result.files)} files to {args.out}")
    return 0


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "sensitivity", help="Sobol or Morris sensitivity indices of drop outputs (SALib), with CIs and a plot",
        description="Sample the --vary ranges (Saltelli for Sobol, trajectories for Morris), run the samples "
                    "through the sweep, and write sensitivity.json, sensitivity.csv and sensitivity.png "
                    "(indices with 95 % confidence intervals) next to the sweep table.")
    add_shared_options(p)
    p.add_argument("--vary", action="append", metavar="KEY=LO:HI", help="a parameter range (repeatable)")
    p.add_argument("--output", default="fork_peak1_mm",
                   help="comma-separated sweep outputs, e.g. fork_peak1_mm,tire_peak1_mm (default fork_peak1_mm)")
    p.add_argument("--method", choices=("sobol", "morris"), default="sobol")
    p.add_argument("--samples", type=int, default=64,
                   help="base samples N: N(D+2) runs for Sobol, N(D+1) trajectories' runs for Morris (default 64)")
    p.add_argument("--levels", type=int, default=4, help="Morris grid levels (default 4)")
    add_out(p, "out/sensitivity")
    p.set_defaults(func=cmd_sensitivity)

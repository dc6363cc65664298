"""``mtbmj drop``, ``mtbmj study`` and ``mtbmj crosscheck``: one configuration on one engine, the
S1-S14 study on both engines, and the engines against each other."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from mtbmj.cli.common import ENGINE_HELP, ENGINE_NAMES, Progress, add_run_options, overrides


def cmd_drop(args) -> int:
    from mtbmj.drop.run import run_drop

    result = Progress(f"{args.config} on {args.engine}", not args.quiet).around(
        lambda progress: run_drop(args.config, args.engine, overrides(args.set), args.duration, progress))
    written = result.write(args.out)
    s = result.summary
    lift = f"{s['lift_off_s']:.3f} s" if s["lift_off_s"] is not None else "never"
    print(f"{result.name} ({args.engine}): fork peak {s['max_fork_mm']:.1f} mm "
          f"({s['travel_used_percent']:.0f} % of travel), tire peak {s['max_tire_mm']:.1f} mm, lift-off {lift}, "
          f"{'at rest' if s['at_rest'] else 'still moving'} at the end; wrote {len(written)} files to {args.out}")
    return 0


def cmd_study(args) -> int:
    from mtbmj.drop.study import run_study, write_study

    start = time.perf_counter()
    log = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    presets = args.presets.split(",") if args.presets else None
    results, checks = run_study(presets, overrides(args.set), args.duration, args.workers, log)
    written = write_study(args.out, results, checks)
    worst = max(checks, key=lambda c: c.worst[1])
    print(f"study: {len(checks)} configurations x 2 engines in {time.perf_counter() - start:.1f} s; "
          f"largest MuJoCo-ODE difference {worst.worst[1]:.4f} mm ({worst.name}, {worst.worst[0]}); "
          f"wrote {len(written)} files to {args.out}")
    return 0


def cmd_crosscheck(args) -> int:
    from mtbmj.validation import crosscheck

    check = crosscheck(args.config, args.tolerance_mm, overrides(args.set), args.duration)
    print(check.line())
    return 0 if check.passed else 1


def add_parser(sub) -> None:
    p = sub.add_parser("drop", help="run one configuration on one engine")
    p.add_argument("config", help="preset name (S1..S14, reference) or a TOML file")
    p.add_argument("--engine", choices=ENGINE_NAMES, default="mujoco", help=ENGINE_HELP)
    p.add_argument("--out", type=Path, default=Path("out/drop"), help="output directory (default out/drop)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_run_options(p)
    p.set_defaults(func=cmd_drop)

    p = sub.add_parser("study", help="run S1-S14 on both engines, write figures and the difference table")
    p.add_argument("--out", type=Path, default=Path("out/study"), help="output directory (default out/study)")
    p.add_argument("--presets", help="comma-separated subset, e.g. S1,S12")
    p.add_argument("--workers", type=int, help="processes (default: one per core)")
    p.add_argument("--quiet", action="store_true")
    add_run_options(p)
    p.set_defaults(func=cmd_study)

    p = sub.add_parser("crosscheck", help="run both engines; exit 1 when they differ by more than the tolerance")
    p.add_argument("config")
    p.add_argument("--tolerance-mm", type=float, default=0.1, help="largest allowed difference in mm (default 0.1)")
    add_run_options(p)
    p.set_defaults(func=cmd_crosscheck)

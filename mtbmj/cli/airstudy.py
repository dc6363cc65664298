"""``mtbmj air-study``: the air fork's drop with 0-3 volume spacers, two air pressures and two tire
pressures on both engines, the spring curves (paper Fig. 3 style) and a table."""
from __future__ import annotations

import sys
import time

from mtbmj.cli.common import add_out, add_run_options, overrides


def cmd_air_study(args) -> int:
    from mtbmj.drop.air_study import run_air_study, study_rows, write_air_study

    start = time.perf_counter()
    log = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    base, results, checks = run_air_study(args.config, overrides(args.set), args.duration, args.workers, log)
    written = write_air_study(args.out, base, results, checks)
    rows = study_rows(results, checks)
    for row in rows:
        print(f"{row['variant']:>14}: sag {_mm(row['static_sag_mm'], 5)}, fork peak {_mm(row['fork_peak1_mm'], 5)}, "
              f"tire peak {_mm(row['tire_peak1_mm'], 4)}, MuJoCo-ODE {row['max_mujoco_ode_diff_mm']:.4f} mm")
    if any(row["static_sag_mm"] is None for row in rows):
        print("note: sag '-': the spring does not carry the sled's weight anywhere in its travel (the fork would rest "
              "on its bumper)")
    if any(row["fork_peak1_mm"] is None or row["tire_peak1_mm"] is None for row in rows):
        print("note: peak '-': the run ends before Peak 1 (a longer --duration gives it)")
    print(f"air study of {base.name}: {len(checks)} variants x 2 engines in {time.perf_counter() - start:.1f} s; "
          f"wrote {len(written)} files to {args.out}")
    return 0


def _mm(value, width: int) -> str:
    return f"{'-':>{width}}" + "   " if value is None else f"{value:{width}.1f} mm"


def add_parser(sub) -> None:
    p = sub.add_parser("air-study", help="air fork study: spacers, air and tire pressures on both engines, spring curves")
    p.add_argument("config", nargs="?", default="air120", help="an air configuration (default air120)")
    add_out(p, "out/air-study")
    p.add_argument("--workers", type=int, help="processes (default: one per core)")
    p.add_argument("--quiet", action="store_true")
    add_run_options(p)
    p.set_defaults(func=cmd_air_study)

"""``mtbmj drop``, ``mtbmj study`` and ``mtbmj crosscheck``: one configuration on one engine, the
S1-S14 study on both engines, and the engines against each other."""
from __future__ import annotations

import sys
import time

from mtbmj.cli.common import (ENGINE_HELP, ENGINE_NAMES, Progress, add_out, add_run_options, given_options, options_verb,
                              overrides)


def cmd_drop(args) -> int:
    from mtbmj.drop.run import run_drop

    result = Progress(f"{args.config} on {args.engine}", not args.quiet).around(
        lambda progress: run_drop(args.config, args.engine, overrides(args.set), args.duration, progress))
    written = result.write(args.out, figure=not args.no_figure)
    print(f"{result.headline()}; wrote {len(written)} files to {args.out}")
    return 0


def cmd_study(args) -> int:
    from mtbmj.drop.study import run_study, write_study
    from mtbmj.runpath.crosscheck import number

    start = time.perf_counter()
    log = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    presets = None if args.presets is None else [n.strip() for n in args.presets.split(",") if n.strip()]
    if presets == []:  # an empty --presets is a mistake, not the whole study
        from mtbmj.errors import MtbmjError

        raise MtbmjError("--presets: no preset named (e.g. --presets S1,S12; leave it out for S1-S14)")
    if presets is not None:  # validate's --presets, a range too (S1..S7,S12): "S1..S3" was an unknown preset here
        from mtbmj.cli.validate import parse_presets

        presets = parse_presets(args.presets)
    engines = _engines(args.engines)
    results, checks = run_study(presets, overrides(args.set), args.duration, args.workers, log, engines)
    written = write_study(args.out, results, checks)
    largest = []
    for engine in engines:
        mine = [c for c in checks if c.engine == engine]
        if mine:
            worst = max(mine, key=lambda c: c.worst.max_abs)
            largest.append(f"largest {engine}-ODE difference {number(worst.worst.max_abs)} mm ({worst.case}, "
                           f"{worst.worst.name})")
    from mtbmj.readout.endtravel import line

    envelope = [f"{name} ({engine}) {line(r.summary)[2:]}" for name, per in results.items()
                for engine, r in per.items() if line(r.summary)]
    print(f"study: {len(results)} configurations x {len(engines)} engines in {time.perf_counter() - start:.1f} s; "
          f"{'; '.join(largest) or 'no reference run, no differences'}{''.join(f'; {e}' for e in envelope)}; "
          f"wrote {len(written)} files to {args.out}")
    return 0


def _engines(text: str) -> list[str]:
    from mtbmj.errors import MtbmjError

    engines = [e.strip().lower() for e in text.split(",") if e.strip()]  # MuJoCo,ODE as --engine takes them
    for e in engines:
        if e not in ENGINE_NAMES:
            raise MtbmjError(f"--engines: {e!r} is not one of {', '.join(ENGINE_NAMES)}")
    if not engines:
        raise MtbmjError("--engines: no engine named")
    return engines


def _refuse_bike_options(args) -> None:
    """A drop or rolling cross-check given an option only the bike's has: refused in one line."""
    from mtbmj.errors import MtbmjError

    given = given_options(args, pedal=None, power=None, seated=False, rider="passive")
    if given:
        raise MtbmjError(options_verb(given, "applies", "apply") + " to a bike cross-check (--bike)")


def cmd_crosscheck(args) -> int:
    if args.bike:
        return _crosscheck_bike(args)
    if args.roll is not None:
        return _crosscheck_roll(args)
    from mtbmj.errors import MtbmjError
    from mtbmj.validation import crosscheck_all

    given = given_options(args, speed=None, drive=None, head_angle=None)
    if given:
        raise MtbmjError(options_verb(given, "applies", "apply") + " to a rolling cross-check (--roll SCENARIO)")
    _refuse_bike_options(args)

    engines = [e for e in _engines(args.engines) if e != "ode"]
    if not engines:  # it was made mujoco's cross-check silently
        raise MtbmjError("--engines: ode is the reference every engine is checked against, not an engine to check; "
                         "name mujoco or fast (or both)")
    checks = crosscheck_all(args.config, engines, args.tolerance_mm, overrides(args.set), args.duration)
    for check in checks:
        print(check.line())
    return 0 if all(c.passed for c in checks) else 1


def _crosscheck_roll(args) -> int:
    """``crosscheck CONFIG --roll SCENARIO --speed V``: one line, exit 1 when not within the tolerances."""
    from mtbmj.errors import MtbmjError
    from mtbmj.rolling.reference import crosscheck

    if args.speed is None:
        raise MtbmjError("--roll: give the speed with --speed M_PER_S")
    _refuse_bike_options(args)
    given = given_options(args, engines="mujoco", tolerance_mm=0.1)
    if given:
        raise MtbmjError(options_verb(given, "applies", "apply") + " to a drop cross-check; a rolling one "
                         "compares MuJoCo with the rolling reference at 0.02 mm and 1 %")
    check = crosscheck(args.roll, args.speed, args.config, args.head_angle, args.duration, overrides(args.set),
                       args.drive or "rider")
    print(check.line())
    return 0 if check.passed else 1


def _crosscheck_bike(args) -> int:
    """``crosscheck BIKE --bike --roll SCENARIO --speed V``: the bike on MuJoCo against its own ODE
    reference; one line, exit 1 when not within 0.1 mm of travel at both ends and 1 % of the
    tire-load peaks and series."""
    from mtbmj.errors import MtbmjError
    from mtbmj.bike.crosscheck import crosscheck

    if args.roll is None or (args.speed is None and args.pedal is None):
        raise MtbmjError("--bike: give the terrain with --roll SCENARIO and the speed with --speed M_PER_S (or --pedal "
                         "RPM)")
    given = given_options(args, engines="mujoco", tolerance_mm=0.1, head_angle=None)
    if given:
        raise MtbmjError(options_verb(given, "does", "do") + " not apply to a bike cross-check (the "
                         "bike's description sets its geometry and laws)")
    from mtbmj.cli.common import parse_assignment

    bike_set = dict(parse_assignment(text) for text in args.set or ())  # bike keys (mtbmj bike --set)
    if args.drive not in (None, "rider", "coast"):
        raise MtbmjError(f"--drive: a bike is driven by its rider or coasts, not {args.drive}")
    from mtbmj.cli.bike import pedal_option

    args.drive = args.drive or "rider"
    pedal = pedal_option(args)
    check = crosscheck(args.config, args.roll, args.speed, args.duration, args.drive, pedal=pedal,
                       seated=args.seated, overrides=bike_set or None, rider=args.rider)
    print(check.line())
    return 0 if check.passed else 1


def add_parser(sub) -> None:
    p = sub.add_parser("drop", help="run one configuration on one engine")
    p.add_argument("config", help="preset name (S1..S14, reference) or a TOML file")
    p.add_argument("--engine", choices=ENGINE_NAMES, default="mujoco", help=ENGINE_HELP)
    add_out(p, "out/drop")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--no-figure", action="store_true", help="do not draw quicklook.png (saves about 0.3 s)")
    add_run_options(p)
    p.set_defaults(func=cmd_drop)

    p = sub.add_parser("study", help="run S1-S14 on the engines (MuJoCo and the ODE reference by default), write "
                                     "figures and the difference table")
    add_out(p, "out/study")
    p.add_argument("--presets", help="comma-separated subset, e.g. S1,S12 or S1..S7,S12")
    p.add_argument("--workers", type=int, help="processes (default: one per core)")
    p.add_argument("--engines", default="mujoco,ode",
                   help="comma-separated engines to run (default mujoco,ode; e.g. mujoco,ode,fast): each is "
                        "compared with ode when ode is among them")
    p.add_argument("--quiet", action="store_true")
    add_run_options(p)
    p.set_defaults(func=cmd_study)

    p = sub.add_parser("crosscheck", help="run an engine (or several) and the ODE reference; exit 1 when they "
                                          "differ by more than the tolerance")
    p.add_argument("config")
    p.add_argument("--tolerance-mm", type=float, default=0.1, help="largest allowed difference in mm (default 0.1)")
    p.add_argument("--engines", default="mujoco",
                   help="comma-separated engines to compare with the ODE reference (default mujoco; e.g. mujoco,fast)")
    p.add_argument("--roll", metavar="SCENARIO",
                   help="cross-check a rolling run instead (mtbmj roll SCENARIO) against the rolling ODE reference: "
                        "fork within 0.02 mm, axle force peaks within 1 %% (body, axle and tire reported); needs "
                        "--speed")
    p.add_argument("--speed", type=float, help="--roll: speed in m/s")
    p.add_argument("--head-angle", type=float, help="--roll: head angle in degrees (default as mtbmj roll)")
    p.add_argument("--drive", choices=("rider", "servo", "coast"), help="--roll: the drive (default rider)")
    p.add_argument("--bike", action="store_true",
                   help="CONFIG names a bike (mtbmj bike's presets or a bike TOML): its run over --roll SCENARIO at "
                        "--speed against the bike's own ODE reference, travel at both ends within 0.1 mm and each "
                        "tire's load within 1 %% of the reference's peak, at its peak and at every sample; --set "
                        "SECTION.KEY=VALUE then changes a key of the bike file")
    from mtbmj.cli.bike import add_pedal

    add_pedal(p)
    p.add_argument("--seated", action="store_true", help="--bike: the rider seated, held rigid on the frame")
    p.add_argument("--rider", choices=("passive", "active"), default="passive",
                   help="--bike: the rigid rider (passive, default) or the articulated one on both sides (active: "
                        "the reference with the rider's segments, pins and the same controller's torques; standing, "
                        "not pedalling)")
    add_run_options(p)
    p.set_defaults(func=cmd_crosscheck)

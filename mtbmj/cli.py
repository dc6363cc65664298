"""The ``mtbmj`` command: drop, study, crosscheck, presets. Headless; bad input gets one line on
stderr and exit status 2; results are written atomically."""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from . import __version__
from .config import parse_assignment, preset_names
from .errors import MtbmjError

EXIT_BAD_INPUT = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, not usage + message
        raise MtbmjError(message)


class Progress:
    """A progress bar on stderr, redrawn in place, on a terminal only: when stderr is a file or a
    pipe it stays free for the one-line error report."""

    def __init__(self, label: str, enabled: bool = True):
        self.label = label
        self.tty = sys.stderr.isatty()
        self.enabled = enabled and self.tty
        self.start = time.perf_counter()

    def __call__(self, fraction: float) -> None:
        if not self.enabled:
            return
        bar = "#" * int(fraction * 30)
        print(f"\r{self.label} [{bar:<30}] {fraction * 100:5.1f}%", end="", file=sys.stderr, flush=True)

    def done(self) -> None:
        if self.enabled:
            print(f"\r{self.label}: done in {time.perf_counter() - self.start:.2f} s" + " " * 30, file=sys.stderr)

    def abandon(self) -> None:
        """Clear the bar so an error report starts on a clean line."""
        if self.enabled:
            print("\r" + " " * 80 + "\r", end="", file=sys.stderr, flush=True)

    def around(self, work):
        """``work(progress)`` with the bar shown, finished, or cleared if it fails."""
        try:
            result = work(self)
        except BaseException:
            self.abandon()
            raise
        self.done()
        return result


def _overrides(pairs) -> dict:
    return dict(parse_assignment(p) for p in pairs or [])


def cmd_drop(args) -> int:
    from .drop import run_drop

    result = Progress(f"{args.config} on {args.engine}", not args.quiet).around(
        lambda progress: run_drop(args.config, args.engine, _overrides(args.set), args.duration, progress))
    written = result.write(args.out)
    s = result.summary
    lift = f"{s['lift_off_s']:.3f} s" if s["lift_off_s"] is not None else "never"
    print(f"{result.name} ({args.engine}): fork peak {s['max_fork_mm']:.1f} mm "
          f"({s['travel_used_percent']:.0f} % of travel), tire peak {s['max_tire_mm']:.1f} mm, lift-off {lift}, "
          f"{'at rest' if s['at_rest'] else 'still moving'} at the end; wrote {len(written)} files to {args.out}")
    return 0


def cmd_study(args) -> int:
    from .study import run_study, write_study

    start = time.perf_counter()
    log = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    presets = args.presets.split(",") if args.presets else None
    results, checks = run_study(presets, _overrides(args.set), args.duration, args.workers, log)
    written = write_study(args.out, results, checks)
    worst = max(checks, key=lambda c: c.worst[1])
    print(f"study: {len(checks)} configurations x 2 engines in {time.perf_counter() - start:.1f} s; "
          f"largest MuJoCo-ODE difference {worst.worst[1]:.4f} mm ({worst.name}, {worst.worst[0]}); "
          f"wrote {len(written)} files to {args.out}")
    return 0


def cmd_crosscheck(args) -> int:
    from mtbmj.validation import crosscheck

    check = crosscheck(args.config, args.tolerance_mm, _overrides(args.set), args.duration)
    print(check.line())
    return 0 if check.passed else 1


def cmd_fit(args) -> int:
    from .identify.run import identify

    bounds = {}
    for text in args.bound or []:
        key, _, span = text.partition("=")
        lo, _, hi = span.partition(":")
        try:
            bounds[key.strip()] = (float(lo), float(hi))
        except ValueError:
            raise MtbmjError(f"--bound {text}: expected key=low:high with numbers") from None
    free = [k.strip() for k in (args.free or "").split(",") if k.strip()]
    ident = identify(args.kind, args.data, model=args.model, friction=args.friction, mass_kg=args.mass_kg,
                     config=args.config, free=free, bounds=bounds or None, engine=args.engine,
                     starts=args.starts)
    written = ident.write(args.out)
    for name in ident.chosen:
        print(ident.results[name].line())
    for note in ident.notes:
        print(f"note: {note}")
    print(f"wrote {', '.join(p.name for p in written)} to {args.out}; run it with: mtbmj drop {args.out / 'fit.toml'}")
    return 0


def cmd_presets(args) -> int:
    from .config import load

    for name in preset_names():
        print(f"{name:10s} {load(name).get('description', '')}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="mtbmj", description="Mountain-bike fork + tire drop-sled study on MuJoCo with an ODE reference.")
    parser.add_argument("--version", action="version", version=f"mtbmj {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def common(p):
        p.add_argument("--set", action="append", metavar="KEY=VALUE",
                       help="override a configuration key, e.g. fork.spring.preload_N=300 (repeatable)")
        p.add_argument("--duration", type=float, help="simulated time in s (default: solver.duration_s)")

    p = sub.add_parser("drop", help="run one configuration on one engine")
    p.add_argument("config", help="preset name (S1..S14, reference) or a TOML file")
    p.add_argument("--engine", choices=("mujoco", "ode"), default="mujoco")
    p.add_argument("--out", type=Path, default=Path("out/drop"), help="output directory (default out/drop)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    common(p)
    p.set_defaults(func=cmd_drop)

    p = sub.add_parser("study", help="run S1-S14 on both engines, write figures and the difference table")
    p.add_argument("--out", type=Path, default=Path("out/study"), help="output directory (default out/study)")
    p.add_argument("--presets", help="comma-separated subset, e.g. S1,S12")
    p.add_argument("--workers", type=int, help="processes (default: one per core)")
    p.add_argument("--quiet", action="store_true")
    common(p)
    p.set_defaults(func=cmd_study)

    p = sub.add_parser("crosscheck", help="run both engines; exit 1 when they differ by more than the tolerance")
    p.add_argument("config")
    p.add_argument("--tolerance-mm", type=float, default=0.1, help="largest allowed difference in mm (default 0.1)")
    common(p)
    p.set_defaults(func=cmd_crosscheck)

    p = sub.add_parser("fit", help="identify parameters from bench data or a drop record; writes fit.toml")
    p.add_argument("kind", choices=("spring", "damper", "tire", "drop"))
    p.add_argument("data", nargs="+", help="record file(s): CSV with units in the column names, or .mat")
    p.add_argument("--model", default="auto", help="spring/damper model to write (default: best by BIC)")
    p.add_argument("--friction", default="auto", help="damper friction model to write (default: best by BIC)")
    p.add_argument("--mass-kg", type=float, help="tire: the mass dropped on the tire")
    p.add_argument("--config", default="S12", help="drop: the configuration whose free parameters are fitted")
    p.add_argument("--free", help="drop: comma-separated configuration keys to fit")
    p.add_argument("--bound", action="append", metavar="KEY=LOW:HIGH", help="drop: bounds of a free key (repeatable)")
    p.add_argument("--engine", choices=("mujoco", "ode"), default="mujoco", help="drop: engine to fit with")
    p.add_argument("--starts", type=int, default=1, metavar="N",
                   help="drop: fit from N start points (the start values and N-1 Latin hypercube points "
                        "within the bounds); the best fit wins (default 1)")
    p.add_argument("--out", type=Path, default=Path("out/fit"), help="output directory (default out/fit)")
    p.set_defaults(func=cmd_fit)

    from mtbmj.validation import cli_validate

    from . import cli_render, cli_roll, cli_sweep, cli_telemetry

    cli_validate.add_parser(sub)
    cli_sweep.add_parser(sub)
    cli_roll.add_parser(sub)
    cli_telemetry.add_parser(sub)
    cli_render.add_parser(sub)

    p = sub.add_parser("presets", help="list the bundled presets")
    p.set_defaults(func=cmd_presets)
    return parser


def main(argv=None) -> int:
    return run(build_parser(), argv)


def run(parser: argparse.ArgumentParser, argv=None) -> int:
    """Parse and run a command: bad input is one line on stderr and exit status 2."""
    try:
        args = parser.parse_args(argv)
        if getattr(args, "duration", None) is not None and not args.duration > 0:
            raise MtbmjError(f"--duration: must be positive, got {args.duration}")
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            return args.func(args)
    except MtbmjError as exc:
        print(f"mtbmj: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeWarning as exc:
        print(f"mtbmj: error: run diverged ({exc})", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("mtbmj: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""``mtbmj fit spring|damper|tire|drop``: parameters from bench data or a drop record, written as a
configuration that ``mtbmj drop`` runs as is."""
from __future__ import annotations

import sys

from pathlib import Path

from mtbmj.cli.common import ENGINE_HELP, ENGINE_NAMES, add_out, intermixed, overrides  # noqa: F401
from mtbmj.errors import MtbmjError


MAX_STARTS = 1000  # start points of a drop fit (each is a whole least-squares fit)
EXIT_MODEL_CHECK = 3  # the fit ran, but its model does not explain the record (docs/identification.md)


def cmd_fit(args) -> int:
    from mtbmj.identify.run import identify

    bounds = {}
    for text in args.bound or []:
        key, _, span = text.partition("=")
        lo, _, hi = span.partition(":")
        try:
            bounds[key.strip()] = (float(lo), float(hi))
        except ValueError:
            raise MtbmjError(f"--bound {text}: expected key=low:high with numbers") from None
    if not 1 <= args.starts <= MAX_STARTS:
        raise MtbmjError(f"--starts: must be in 1..{MAX_STARTS}, got {args.starts}")
    free = [k.strip() for k in (args.free or "").split(",") if k.strip()]
    clicks = _clicks(args.clicks) if args.clicks else None
    data = list(args.data)
    if data == ["example"] and not Path("example").exists():
        from mtbmj.identify.examples import example_paths

        data = example_paths(args.kind)
    if args.set and args.kind != "drop":
        raise MtbmjError(f"--set: applies to fit drop (the configuration it runs on), not fit {args.kind}")
    ident = identify(args.kind, data, model=args.model, friction=args.friction, mass_kg=args.mass_kg,
                     config=args.config, free=free, bounds=bounds or None, engine=args.engine,
                     starts=args.starts, touch_s=args.touch_s, clicks=clicks, overrides=overrides(args.set))
    written = ident.write(args.out)
    for name in ident.chosen:
        print(ident.results[name].line())
    for check in ident.model_checks:
        print(check["line"])
    for warning in ident.warnings:
        print(f"warning: {warning}")
    for note in ident.notes:
        print(f"note: {note}")
    print(f"wrote {', '.join(p.name for p in written)} to {args.out}; run it with: mtbmj drop {args.out / 'fit.toml'}")
    if not ident.model_check_passed:
        print(f"mtbmj: the model does not explain the record (exit status {EXIT_MODEL_CHECK}); fit.toml says so in "
              f"its header", file=sys.stderr)
        return EXIT_MODEL_CHECK
    return 0


def _clicks(given: list[str]) -> list:
    """``--clicks 0,6,12`` (one position per file, both adjusters) or one ``--clicks`` per file
    naming its adjusters, e.g. ``--clicks lsc=4,hsc=2,lsr=6,hsr=3``."""
    if not any("=" in g for g in given):  # positions only: --clicks 0,6,12 (or one --clicks per file)
        joined = ",".join(given)
        try:
            return [float(c) for c in joined.split(",")]
        except ValueError:
            raise MtbmjError(f"--clicks {joined}: expected comma-separated numbers of clicks") from None
    settings = []
    for text in given:
        label = {}
        for item in text.split(","):
            name, eq, value = item.partition("=")
            try:
                label[name.strip().lower()] = float(value)
            except ValueError:
                raise MtbmjError(f"--clicks {text}: expected adjuster=clicks pairs, e.g. lsc=4,hsc=2,lsr=6,hsr=3") \
                    from None
            if not eq:
                raise MtbmjError(f"--clicks {text}: expected adjuster=clicks pairs, e.g. lsc=4,hsc=2,lsr=6,hsr=3")
        settings.append(label)
    return settings


def add_parser(sub) -> None:
    p = sub.add_parser("fit", help="identify parameters from bench data or a drop record; writes fit.toml",
                       description="Identify parameters and write fit.toml, fit.json and fit.png. Each value comes "
                                   "with its 95 % interval. Drop, spring and tire fits check their model: when the residual "
                                   "is more than 3 x the record's noise floor (+ 0.1 mm for a drop), it says so and "
                                   "exits with status 3.")
    p.add_argument("kind", choices=("spring", "damper", "tire", "drop"))
    p.add_argument("data", nargs="+", help="record file(s): CSV with units in the column names, or .mat; "
                                           "'example' for the shipped synthetic example of the kind")
    p.add_argument("--model", default="auto", help="spring/damper model to write (default: best by BIC)")
    p.add_argument("--friction", default="auto", help="damper friction model to write (default: best by BIC)")
    p.add_argument("--mass-kg", type=float, help="tire: the mass dropped on the tire")
    p.add_argument("--config", default="S12", help="drop: the configuration whose free parameters are fitted")
    p.add_argument("--free", help="drop: comma-separated configuration keys to fit (default: "
                                  "tire.impact_rate_N_per_mm,fork.spring.preload_N)")
    p.add_argument("--touch-s", type=float, metavar="SECONDS",
                   help="drop: time zero (tire touch) on the record's clock; default: found from the record")
    p.add_argument("--bound", action="append", metavar="KEY=LOW:HIGH",
                   help="drop: bounds of a free key (repeatable); default start / 4 to 4 x start (start -/+ 4 |start| "
                        "for a signed key). A value that ends within 1 %% of a bound is reported, with no interval")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="drop: set a key of the configuration the fit runs on, e.g. sled.drop_height_mm=150 (repeatable)")
    p.add_argument("--engine", choices=ENGINE_NAMES, default="mujoco", help=f"drop: engine to fit with: {ENGINE_HELP}")
    p.add_argument("--starts", type=int, default=1, metavar="N",
                   help="drop: fit from N start points (the start values and N-1 Latin hypercube points "
                        "within the bounds); the best fit wins (default 1)")
    p.add_argument("--clicks", action="append", metavar="CLICKS",
                   help="damper: the adjuster positions of the dyno files, in clicks from closed; writes a clicks "
                        "damper. Either one position per file for both adjusters (--clicks 0,6,12) or one "
                        "--clicks per file naming its adjusters: lsc, hsc, lsr, hsr (low/high-speed compression "
                        "and rebound) or c, r (one adjuster per stroke), e.g. --clicks lsc=4,hsc=2,r=6")
    add_out(p, "out/fit")
    p.set_defaults(func=cmd_fit)
    intermixed(p)

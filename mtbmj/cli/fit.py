"""``mtbmj fit spring|damper|tire|drop``: parameters from bench data or a drop record, written as a
configuration that ``mtbmj drop`` runs as is."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mtbmj.cli.common import ENGINE_HELP, ENGINE_NAMES, Progress, add_out, intermixed, overrides  # noqa: F401
from mtbmj.errors import MtbmjError


MAX_STARTS = 1000  # start points of a drop fit (each is a whole least-squares fit)
EXIT_MODEL_CHECK = 3  # the fit ran, but its model does not explain the record (docs/identification.md)


def _applies(args) -> None:
    """An option of another kind of fit (``fit spring --bound ...``) is refused in one line naming
    it, not ignored: the user would read a result the option did not shape."""
    for flags, keywords, _, helps in OPTIONS:
        dest = flags[0].lstrip("-").replace("-", "_")
        value = getattr(args, dest, None)
        if args.kind in helps or value is None or value == keywords.get("default"):
            continue
        if args.kind == "spring" and dest == "config":
            continue
        kinds = " and ".join(f"fit {k}" for k in helps)
        what = ("the configuration the fit runs on" if dest == "set" else "")
        raise MtbmjError(f"{flags[0]}: applies to {kinds}{f' ({what})' if what else ''}, not fit {args.kind}")


def cmd_fit(args) -> int:
    from mtbmj.identify.run import identify

    _applies(args)

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
    if args.free is not None and not free:  # `--free ""` or `--free ,`: a list left empty by mistake
        raise MtbmjError(f"--free {args.free!r}: names no key; give comma-separated configuration keys, "
                         "or leave --free out for the default ones")
    clicks = _clicks(args.clicks) if args.clicks else None
    data = list(args.data)
    if any(not name.strip() for name in data):  # '' is no file (read as the current folder: "is a directory" was the line)
        raise MtbmjError(f"fit {args.kind}: an empty name among the records; give each record's file")
    if len(data) > 1 and "example" in data and not Path("example").exists():  # "example: no such file" was the line
        raise MtbmjError(f"fit {args.kind} {' '.join(data)}: 'example' is the shipped record alone; give it once, "
                         f"or your records without it")
    if data == ["example"] and not Path("example").exists():
        from mtbmj.identify.examples import example_paths

        data = example_paths(args.kind)
    def fit(progress=None):
        return identify(args.kind, data, model=args.model, friction=args.friction, mass_kg=args.mass_kg,
                        config=args.config, free=free, bounds=bounds or None, engine=args.engine,
                        starts=args.starts, touch_s=args.touch_s, clicks=clicks, overrides=overrides(args.set),
                        progress=progress)

    # a damper fit's laws, one by one (a bar on a terminal only; a record of samples takes a while)
    ident = Progress(f"fit {args.kind}").around(fit) if args.kind == "damper" and not clicks else fit()
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


KINDS = ("spring", "damper", "tire", "drop")

# What each kind fits and from what (``mtbmj fit KIND --help``).
KIND_DESCRIPTIONS = {
    "spring": "Fit the fork spring to one bench stroke record (displacement_mm, force_N; time_s optional): the "
              "linear, compression_rebound, bilinear and progressive laws, top_out and preload when the stroke "
              "reaches full extension, and the air spring with an air configuration (--config air120). The law "
              "with the lowest BIC is written unless --model names one. The model is checked against the force's "
              "own noise floor: more than 3 x it, the fit says so and exits with status 3.",
    "damper": "Fit the fork damper and friction to one dyno record (velocity_mm_per_s, force_N), or to one file "
              "per adjuster position with --clicks (a clicks damper). The hydraulic law (linear, bilinear, "
              "digressive, table) and the friction law with the lowest BIC are written unless --model and "
              "--friction name them; the fit says when the friction cannot be told from the hydraulic law. The "
              "model is checked against the force's scatter at repeated test speeds (with --clicks, each file's): "
              "more than 3 x it, the fit says so and exits with status 3.",
    "tire": "Fit the tire to one drop record of the wheel on its tire (time_s, deflection_mm) and, optionally, a "
            "static ramp (deflection_mm, force_N): impact and contact rates and damping, and the static rate "
            "from the ramp. Each part is checked against the record's own noise (exit status 3 when it fails).",
    "drop": "Fit free keys of a configuration (--config, default S12) to one sled drop record (time_s, sled_mm, "
            "fork_mm) by running the engine: each value with its 95 % interval and its bounds. The fit is "
            "checked against the record's noise floor + 0.1 mm: beyond it, it says so and exits with status 3.",
}


def _choices(kind: str, what: str) -> str:
    """The model names the fit of ``kind`` accepts (read when help is printed, from the fit code)."""
    if kind == "spring":
        from mtbmj.identify.spring import MODELS

        return ", ".join(MODELS + ("air",))  # (air: fitted with an air configuration's geometry)
    from mtbmj.identify import damper

    return ", ".join(damper.HYDRAULIC if what == "model" else damper.FRICTION)


# Every option of ``mtbmj fit``: (flags, argparse keywords, help for the whole command, {kind: help
# for that kind}; a callable help is given the kind). The command's parser takes them all (so
# ``mtbmj fit KIND DATA...`` parses as it always has); ``fit KIND --help`` shows the kind's own.
OPTIONS = (
    # a model's name in any case (LuGre, Linear), as --engine's and --rider's choices are read
    (("--model",), dict(default="auto", type=str.lower), "spring/damper model to write (default: best by BIC)",
     {"spring": lambda k: f"spring law to write: {_choices(k, 'model')} (air with an air --config; default: "
                          "the lowest BIC)",
      "damper": lambda k: f"hydraulic law to write: {_choices(k, 'model')} (default: the lowest BIC); with "
                          "--clicks, the law each dyno file is read through: table (default) or digressive"}),
    (("--friction",), dict(default="auto", type=str.lower), "damper friction model to write (default: best by BIC)",
     {"damper": lambda k: f"friction law to write: {_choices(k, 'friction')} (default: the lowest BIC)"}),
    (("--mass-kg",), dict(type=float), "tire: the mass dropped on the tire",
     {"tire": "the mass dropped on the tire (kg)"}),
    (("--config",), dict(default="S12"), "drop: the configuration whose free parameters are fitted",
     {"spring": "a configuration whose air spring geometry (piston, chamber, spacers) the air model is fitted "
                "with; an air configuration (e.g. air120) adds the air model (default S12: coil only)",
      "drop": "the configuration (preset or TOML file) the fit runs and whose free keys it fits (default S12)"}),
    (("--free",), {}, "drop: comma-separated configuration keys to fit (default: "
                      "tire.impact_rate_N_per_mm,fork.spring.preload_N)",
     {"drop": "comma-separated configuration keys to fit (default: tire.impact_rate_N_per_mm,fork.spring.preload_N)"}),
    (("--touch-s",), dict(type=float, metavar="SECONDS"),
     "drop: time zero (tire touch) on the record's clock; default: found from the record",
     {"drop": "time zero (tire touch) on the record's clock; default: found from the record"}),
    (("--bound",), dict(action="append", metavar="KEY=LOW:HIGH"),
     "drop: bounds of a free key (repeatable); default start / 4 to 4 x start (start -/+ 4 |start| for a signed "
     "key). A value that ends within 1 %% of a bound is reported, with no interval",
     {"drop": "bounds of a free key (repeatable); default start / 4 to 4 x start (start -/+ 4 |start| for a signed "
              "key). A value that ends within 1 %% of a bound is reported, with no interval"}),
    (("--set",), dict(action="append", metavar="KEY=VALUE"),
     "drop: set a key of the configuration the fit runs on, e.g. sled.drop_height_mm=150 (repeatable)",
     {"drop": "set a key of the configuration the fit runs on, e.g. sled.drop_height_mm=150 (repeatable)"}),
    (("--engine",), dict(choices=ENGINE_NAMES, default="mujoco"), f"drop: engine to fit with: {ENGINE_HELP}",
     {"drop": f"engine to fit with: {ENGINE_HELP}"}),
    (("--starts",), dict(type=int, default=1, metavar="N"),
     "drop: fit from N start points (the start values and N-1 Latin hypercube points within the bounds); the best "
     "fit wins (default 1)",
     {"drop": "fit from N start points (the start values and N-1 Latin hypercube points within the bounds); the "
              "best fit wins (default 1)"}),
    (("--clicks",), dict(action="append", metavar="CLICKS"),
     "damper: the adjuster positions of the dyno files, in clicks from closed; writes a clicks damper. Either one "
     "position per file for both adjusters (--clicks 0,6,12) or one --clicks per file naming its adjusters: lsc, "
     "hsc, lsr, hsr (low/high-speed compression and rebound) or c, r (one adjuster per stroke), e.g. --clicks "
     "lsc=4,hsc=2,r=6",
     {"damper": "the adjuster positions of the dyno files, in clicks from closed; writes a clicks damper. Either "
                "one position per file for both adjusters (--clicks 0,6,12) or one --clicks per file naming its "
                "adjusters: lsc, hsc, lsr, hsr (low/high-speed compression and rebound) or c, r (one adjuster per "
                "stroke), e.g. --clicks lsc=4,hsc=2,r=6"}),
)
DATA_HELP = {
    "spring": "the stroke record: CSV with units in the column names, or .mat; 'example' for the shipped one",
    "damper": "the dyno record (several with --clicks, one per position): CSV with units in the column names, or "
              ".mat; 'example' for the shipped one",
    "tire": "the tire drop record and, optionally, a static ramp: CSV with units in the column names, or .mat; "
            "'example' for the shipped ones",
    "drop": "the sled drop record: CSV with units in the column names, or .mat; 'example' for the shipped one",
}


def kind_parser(kind: str):
    """The parser whose help ``mtbmj fit KIND --help`` prints: the options that apply to ``kind``
    (only for help: ``mtbmj fit`` parses with the command's own parser)."""
    from mtbmj.cli.common import Parser

    p = Parser(prog=f"mtbmj fit {kind}", description=KIND_DESCRIPTIONS[kind] + " Writes fit.toml (a "
               "configuration mtbmj drop runs as is), fit.json and fit.png.")
    p.add_argument("data", nargs="+", help=DATA_HELP[kind])
    for flags, keywords, _, helps in OPTIONS:
        if kind in helps:
            text = helps[kind]
            p.add_argument(*flags, **keywords, help=text(kind) if callable(text) else text)
    add_out(p, "out/fit")
    return p


class _KindHelp(argparse.Action):
    """``-h/--help``: the help of the kind the command line names (``mtbmj fit damper --help``),
    else the whole command's."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        kind = _kind_named(parser, getattr(parser, "fit_arguments", ()))
        (kind_parser(kind) if kind else parser).print_help()
        parser.exit()


def _kind_named(parser, arguments) -> str | None:
    """The first positional argument of ``arguments`` (the kind) when it is one of KINDS: option
    values are skipped (``--config drop`` names no kind), ``--`` ends the options."""
    options = parser._option_string_actions
    longs = [o for o in options if o.startswith("--")]
    words = list(arguments)
    i = 0
    while i < len(words):
        word = words[i]
        if word == "--":
            rest = words[i + 1:]
            return rest[0] if rest and rest[0] in KINDS else None
        if word.startswith("-") and len(word) > 1:
            name = word.split("=", 1)[0]
            matches = [name] if name in options else [o for o in longs if o.startswith(name)]
            action = options[matches[0]] if len(matches) == 1 else None
            if action is not None and "=" not in word and action.nargs != 0:
                i += 1  # its value
            i += 1
            continue
        return word if word in KINDS else None
    return None


def _remember_arguments(parser) -> None:
    """Keep the command line ``parser`` is given, for ``_KindHelp`` to find the kind in."""
    parse = parser.parse_known_args
    busy = []

    def parse_known_args(args=None, namespace=None):
        if not busy:
            parser.fit_arguments = list(sys.argv[1:] if args is None else args)
        busy.append(True)
        try:
            return parse(args, namespace)
        finally:
            busy.pop()

    parser.parse_known_args = parse_known_args


def add_parser(sub) -> None:
    p = sub.add_parser("fit", help="identify parameters from bench data or a drop record; writes fit.toml",
                       add_help=False,
                       description="Identify parameters and write fit.toml, fit.json and fit.png. Each value comes "
                                   "with its 95 % interval. Every fit checks its model where the record tells its own "
                                   "noise: when the residual is more than 3 x the record's noise floor (+ 0.1 mm for a "
                                   "drop), it says so and exits with status 3.",
                       epilog="mtbmj fit KIND --help shows the options of one kind (spring, damper, tire, drop).")
    p.add_argument("-h", "--help", action=_KindHelp, help="show this help message (with a KIND: that kind's) and exit")
    p.add_argument("kind", choices=KINDS)
    p.add_argument("data", nargs="+", help="record file(s): CSV with units in the column names, or .mat; "
                                           "'example' for the shipped synthetic example of the kind")
    for flags, keywords, text, _ in OPTIONS:
        p.add_argument(*flags, **keywords, help=text)
    add_out(p, "out/fit")
    p.set_defaults(func=cmd_fit)
    intermixed(p)
    _remember_arguments(p)
    from mtbmj.cli.bounce import add_bounce_parser

    add_bounce_parser(p)  # mtbmj fit bounce: a rider's own seat slams (mtbmj.identify.bounce)

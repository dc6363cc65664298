"""What every command shares: the parser that reports bad input in one line, the progress bar,
``--set`` overrides, and ``run`` (parse, run, map errors to exit statuses)."""
from __future__ import annotations

import argparse
import io
import logging
import os
import re
import sys
import time
import tomllib
import warnings
from pathlib import Path

from mtbmj.config import ConfigError, ConfigWarning
from mtbmj.errors import MtbmjError, RunError, check_interrupt, interrupt_handling, interrupted
from mtbmj.limits import argument, command_line
from mtbmj.textfile import parses_as_number

EXIT_BAD_INPUT = 2
# The drop engines (``mtbmj.drop.run.ENGINES``), named here so the parser needs no engine imported.
ENGINE_NAMES = ("mujoco", "ode", "fast")
ENGINE_HELP = "mujoco (default), ode (the scipy reference) or fast (the same ODE natively on the compiled laws)"


class Parser(argparse.ArgumentParser):
    """The parser of every command: bad input is one line (``error``), and every numeric argument
    passes the one numeric-input gate: an argument added with ``type=float`` or ``type=int`` is
    parsed by :func:`numeric` (its range from ``mtbmj.limits.ARGUMENTS``), so a command cannot
    take a number that is NaN, infinite, a huge integer or outside what the model allows."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # a value that starts like a negative number (``-40,20``, ``-1e3``) is a value for the option
        # before it, not an unknown option: its own check then names what is wrong with it (argparse
        # takes only ``-40`` and ``-0.5`` so, and says "expected one argument" for the rest, ``-inf`` among them)
        self._negative_number_matcher = re.compile(r"^-(\.?\d|(inf|infinity|nan)$)", re.IGNORECASE)

    def error(self, message):  # one line, not usage + message
        raise MtbmjError(message)

    def parse_known_args(self, args=None, namespace=None):
        given = sys.argv[1:] if args is None else list(args)
        _one_comma_list(getattr(self, "_comma_lists", ()), given)
        _one_side(self._actions, given)
        namespace, extras = super().parse_known_args(args, namespace)
        # ``--speed 20 km/h``: argparse's "unrecognized arguments: km/h", or the unit read as the positional after it
        # ("W: cannot read"), where the cause is the unit (not in an intermixed parse's first pass, whose extras are
        # its positionals: checked on its final parse, ``intermixed``)
        if not getattr(self, "_intermixing", False):
            _unit_apart(self._actions, given, extras)
        return namespace, extras

    def add_argument(self, *args, **kwargs):
        if "," in str(kwargs.get("metavar", "")):  # a comma list (``--clicks K1,K2,...``): typed with spaces, said so
            self._comma_lists = (*getattr(self, "_comma_lists", ()), *(a for a in args if a.startswith("--")))
        if kwargs.get("type") in (float, int):
            option = next((a for a in args if a.startswith("--")), args[0] if args else "")
            kwargs["type"] = numeric(option, integer=kwargs["type"] is int)
        if kwargs.get("type") is Path:  # '' is no file: Path("") is the current folder ("given twice (as .)")
            kwargs["type"] = _a_path
        if "type" not in kwargs and kwargs.get("action") in (None, "store", "append", "extend") and \
                _dest(args, kwargs) in INPUT_NAMES:  # a preset's name or a file's path, kept a str
            kwargs["type"] = home
        choices = kwargs.get("choices")
        if choices and "type" not in kwargs and all(isinstance(c, str) and c == c.lower() for c in choices):
            kwargs["type"] = _in_any_case(choices)  # --engine MuJoCo, --rider Active: as presets are named
        return super().add_argument(*args, **kwargs)


# The arguments typed as str that name an input file (or a preset, a terrain, 'example'), by their dest in every
# command: a leading ~ in them is the home folder, as in the arguments typed as Path and in --out
INPUT_NAMES = frozenset({"config", "configs", "bike", "scenario", "speed_profile", "ride", "records", "data", "source",
                         "show", "roll", "try_file", "speed_csv"})


def home(text: str) -> str:
    """``text`` with a leading ``~`` (``~/x``, ``~user/x``) made the home folder, as the shell makes it where it
    sees one (it does not after ``=``, ``--ride=~/x.SST``, nor in quotes): the one place every path a user gives
    (an input or ``--out``) is so read."""
    return os.path.expanduser(text) if text.startswith("~") else text


def _dest(args, kwargs) -> str:
    if "dest" in kwargs:
        return kwargs["dest"]
    long = next((a for a in args if a.startswith("--")), None)
    return (long[2:] if long else args[0] if args else "").replace("-", "_")


def _a_path(text: str) -> Path:
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: an empty name; give a file or a folder")
    return Path(home(text))


def _unit_apart(actions, args, extras) -> None:
    """Refuse a unit typed apart after a numeric option's value (``--speed 20 km/h``, ``--load-kg=180 lb``),
    naming the number to give (``limits.unit_apart``): where argparse found an argument it did not expect (the
    unit, or the positional the unit displaced), or took the unit as a positional (``bob --power 250 W REC``:
    the record "W"; ``roll --duration 0.2 s``: the scenario "s"). A unit's word taken as a positional is the
    positional where it is one: a file so named (``validate example --duration 0.5 s`` with a configuration
    ``s``) or one of its choices (no preset, terrain or choice is named as a unit)."""
    from mtbmj.limits import unit_apart

    if not extras and not any(not a.option_strings for a in actions):
        return  # nothing left over and no positional to take a unit
    numeric_options = {o: a.type.option for a in actions if hasattr(a.type, "option") for o in a.option_strings}
    every = [o for a in actions for o in a.option_strings if o.startswith("--")]
    full = {}  # a prefix typed: the option it stands for, named in the refusal
    for typed in {str(a).partition("=")[0] for a in args if str(a).startswith("--")} - set(every):
        whole = [o for o in every if o.startswith(typed)]  # argparse takes a long option's unique prefix (``--pow``)
        if len(whole) == 1 and whole[0] in numeric_options:
            numeric_options[typed], full[typed] = numeric_options[whole[0]], whole[0]
    choices = {str(c) for a in actions if not a.option_strings and a.choices for c in a.choices}
    said = [str(a) for a in args]
    for i, word in enumerate(said[1:], 1):
        option, eq, value = said[i - 1].partition("=")
        if not eq and i >= 2 and said[i - 2] in numeric_options:  # ``--speed 20 km/h``: the value the word before
            option, value = said[i - 2], said[i - 1]
        elif not (eq and option in numeric_options):  # ``--speed=20 km/h``
            continue
        if word not in extras and (word in choices or os.path.exists(home(word))):
            continue  # read as the positional it names
        note = unit_apart(numeric_options[option], value, word)
        if note:
            error = MtbmjError(f"argument {full.get(option, option)}: '{value} {word}' is a number and its unit{note}")
            error.alone = True  # no note of the number's range beside it: the number was read without its unit
            raise error


def _in_any_case(choices):
    """A choice typed in another case taken as the choice; anything else left for argparse to refuse
    naming the choices."""
    def choice(text: str) -> str:
        return text.lower() if text.lower() in choices else text

    return choice


def _one_comma_list(options, args) -> None:
    """Refuse a comma-list option whose numbers were typed apart (``--clicks 0 8``, ``--clicks 0, 8``):
    argparse would take the first and say "unrecognized arguments: 8" or read 8 as a file; the line
    names the way out."""
    def number(token: str) -> bool:  # a number, or numbers with commas (``0,``, ``0,8``)
        parts = [part for part in token.split(",") if part]
        return not token.startswith("--") and bool(parts) and all(parses_as_number(part) for part in parts)

    for i, token in enumerate(args):
        option, eq, first = str(token).partition("=")
        if option not in options:
            continue
        values = [first] if eq else []
        for later in args[i + 1:]:
            if not number(str(later)):
                break
            values.append(str(later))
        if len(values) > 1 and all(number(v) for v in values):
            listed = ",".join(v.strip(",") for v in values if v.strip(","))
            raise MtbmjError(f"{option} takes one comma list without spaces: {option} {listed} (not "
                             f"{option} {' '.join(values)})")


def _one_side(actions, args) -> None:
    """Refuse a switch given both ways (``--calibrate --no-calibrate``): argparse lets the last one win,
    silently; the line names both."""
    said = [str(a) for a in args]
    said = said[:said.index("--")] if "--" in said else said  # past "--" every word is a positional
    options = [o for action in actions for o in action.option_strings]

    def whole(word: str) -> str:  # an option as argparse reads it: its unique abbreviation taken whole
        word = word.split("=", 1)[0]
        if word in options:
            return word
        matches = [o for o in options if o.startswith(word)]
        return matches[0] if len(matches) == 1 else word

    said = [whole(w) for w in said if w.startswith("--")]
    for action in actions:
        if isinstance(action, argparse.BooleanOptionalAction):
            ways = [o for o in dict.fromkeys(said) if o in action.option_strings]  # in the order typed
            if len({o.startswith("--no-") for o in ways}) == 2:
                raise MtbmjError(f"{ways[0]} and {ways[1]} given both: one would silently win over the other; give one")


def intermixed(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Let a sub-command's options and positional arguments come in any order
    (``validate my.csv --presets S12 mine.toml``): its parse goes through argparse's
    ``parse_known_intermixed_args``, which itself calls ``parse_known_args`` twice."""
    plain = parser.parse_known_args

    def parse_known_args(args=None, namespace=None):
        if getattr(parser, "_intermixing", False):  # one of its two passes: the plain parse, no unit check in it
            return plain(args, namespace)
        parser._intermixing = True  # its two passes leave positionals over on the first
        try:
            namespace, extras = parser.parse_known_intermixed_args(args, namespace)
        finally:
            parser._intermixing = False
        # a unit typed apart named, left over at the end or read as a positional, as in the other commands
        _unit_apart(parser._actions, sys.argv[1:] if args is None else list(args), extras)
        return namespace, extras

    parser.parse_known_args = parse_known_args
    return parser


class Progress:
    """A progress bar on stderr, redrawn in place, on a terminal only: when stderr is a file or a
    pipe it stays free for the one-line error report."""

    def __init__(self, label: str, enabled: bool = True):
        self.label = label
        self.tty = sys.stderr.isatty()
        self.enabled = enabled and self.tty
        self.start = time.perf_counter()

    def __call__(self, fraction: float, note: str = "") -> None:
        """Redraw the bar at ``fraction`` (0-1), ``note`` after it ("run 3/12")."""
        if not self.enabled:
            return
        bar = "#" * int(fraction * 30)
        print(f"\r{self.label} [{bar:<30}] {fraction * 100:5.1f}%{' ' + note if note else ''}", end="",
              file=sys.stderr, flush=True)

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


def numeric(option: str, integer: bool = False):
    """The argparse type of the numeric argument ``option`` (``"--speed"``): the one gate every
    command's numbers pass (``mtbmj.limits.argument`` and its table ``ARGUMENTS``): a value that is
    not a number, not finite, a huge integer or outside what the model allows is refused in one
    line naming the option; one outside the plausible range is warned about. An option the table
    lacks (``integer``: a whole number) is held to a finite number within ``limits.MAX_MAGNITUDE``."""
    def parse(text: str):
        try:
            return argument(option, text, integer)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = "number"
    parse.option = option  # the option whose number it reads (``_unit_apart``)
    return parse


def parse_assignment(text: str, option: str = "--set") -> tuple[str, object]:
    """Parse a ``--set key=value`` override (``option``: the option it came with, as its refusal
    names it); the value is read as TOML (numbers, lists) or, failing that, as a bare word."""
    if "=" not in text:
        raise ConfigError(f"{option} {text}: expected key=value")
    key, raw = (part.strip() for part in text.split("=", 1))
    if not key:
        raise ConfigError(f"{option} {text}: no key before '='; expected key=value")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    except RecursionError:
        raise ConfigError(f"{option} {key}: value nested too deeply") from None
    return key, value


class Typed(dict):
    """Overrides a person typed (``--set``, ``--fork-set``, ``--shock-set``): ``mtbmj.compose`` refuses,
    in one line, a key of these that the part's model does not read (it would change nothing). Keys a
    program sets (a sweep's grid, a fit's trial) are not held to it."""

    typed = True


def overrides(pairs) -> dict:
    return Typed(parse_assignment(p) for p in pairs or [])


def add_run_options(p) -> None:
    """``--set KEY=VALUE`` (repeatable) and ``--duration`` for a command that runs a configuration."""
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a configuration key, e.g. fork.spring.preload_N=300 (repeatable)")
    p.add_argument("--duration", type=numeric("--duration"), help="simulated time in s (default: solver.duration_s)")


class _Stderr(logging.Handler):
    """Log records as lines on whatever ``sys.stderr`` is when they come (not the stream of the
    moment the handler was made)."""

    def emit(self, record):
        print(self.format(record), file=sys.stderr, flush=True)


def show_compile_notices() -> None:
    """Print the compiled laws' "compiling ..." notice (a cold first run) on stderr."""
    log = logging.getLogger("mtbmj.compile")
    if not log.handlers:
        handler = _Stderr()
        handler.setFormatter(logging.Formatter("mtbmj: %(message)s"))
        log.addHandler(handler)
        log.setLevel(logging.INFO)
        log.propagate = False


def _note(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings that reach the command line (a FallbackWarning: the run goes on along a slower
    path) as one line on stderr, without the source location; none once Ctrl-C came (an interrupt
    inside a C extension's import comes up as that import's failure, which a library may turn into a
    warning: matplotlib's "Unable to import Axes3D" beside "mtbmj: interrupted", 1 of 25 slow trials)."""
    if interrupted():
        return
    print(f"mtbmj: note: {message}", file=sys.stderr)


class _ConfigWarnings:
    """The configuration's plausibility warnings (``mtbmj.config.ConfigWarning``) of one command,
    each kept once: printed as ``mtbmj: warning:`` lines when the command has answered. A refused
    command's report stays the one line naming the cause; the warnings about a key that line names
    are added to it (a travel of 0.12 mm refused for its top-out spring: metres were meant), and a
    run that diverged names them all (an implausible value is the likeliest cause)."""

    def __init__(self):
        self.lines: list[str] = []

    def showwarning(self, message, category, filename, lineno, file=None, line=None) -> None:
        if issubclass(category, ConfigWarning):
            if str(message) not in self.lines:
                self.lines.append(str(message))
        else:
            _note(message, category, filename, lineno, file, line)

    def print(self) -> None:
        for text in self.lines:
            print(f"mtbmj: warning: {_one_line(text)}", file=sys.stderr)

    def suffix(self, message: str | None = None) -> str:
        """The warnings to add to a refusal: those whose key ``message`` names, or all."""
        named = [w for w in self.lines if message is None or w.split(" = ", 1)[0] in message]
        return f" (note: {'; '.join(named)})" if named else ""


def add_out(p, default: str, what: str = "output directory") -> None:
    """``--out DIR`` for a command that writes a folder: the command line claims the folder
    before the work starts (``mtbmj.output.claim``: it must be empty or mtbmj's, hold none of
    the command's inputs, and no other mtbmj run may be writing to it)."""
    p.add_argument("--out", type=out_path, default=Path(default), help=f"{what} (default {default})")
    p.set_defaults(out_folder=True)


def write_and_say(result, out) -> int:
    """Write ``result`` (a result object with ``write(out)`` and ``line()``) to ``out`` and print its
    line with what was written: what every command that writes one result ends with; exit status 0."""
    written = result.write(out)
    print(f"{result.line()}; wrote {len(written)} files to {out}")
    return 0


def out_path(text: str) -> Path:
    """An ``--out`` name: refused when it holds a line break or another control character,
    which would break every line that names it; a leading ``~`` is the home folder."""
    if not text or any(ord(ch) < 32 or ord(ch) == 127 or ch in LINE_BREAKS for ch in text):
        shown = text.encode("unicode_escape").decode("ascii")
        raise argparse.ArgumentTypeError(f"{shown!r}: an output name must be non-empty and hold no line break or "
                                         f"control character")
    # ``--out=~/runs`` (bash expands no ~ after "=") or a quoted '~/runs': the home folder meant, as the shell
    # would have read it, not a folder named "~" in the current one
    return Path(home(text))


def command_name(args) -> str:
    """``drop``, ``fit spring``: the command as the user typed it, for the output folder's record."""
    words = [getattr(args, "command", None) or "mtbmj"]
    if isinstance(getattr(args, "kind", None), str):
        words.append(args.kind)
    return " ".join(words)


def input_files(args) -> list[Path]:
    """The existing files and folders a command was given (its positional arguments and options,
    a telemetry comparison's run folders among them), which ``--out`` must not hold."""
    found = []
    for name, value in vars(args).items():
        if name == "out" or callable(value):
            continue
        for item in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(item, (str, Path)) and str(item):
                try:
                    if Path(item).exists():
                        found.append(Path(item))
                except (OSError, ValueError):
                    continue
    return found


def _run_claimed(args) -> int:
    if not getattr(args, "out_folder", False):
        return args.func(args)
    from mtbmj import output

    with output.claim(args.out, command_name(args), inputs=input_files(args)):
        return args.func(args)


def run(parser: argparse.ArgumentParser, argv=None) -> int:
    """Parse and run a command: bad input is one line on stderr and exit status 2; Ctrl-C, at
    any moment, the one line ``mtbmj: interrupted`` and exit status 130."""
    from mtbmj.controllers import native

    native.one_shot()  # a command loads the compiled laws when its work repays it, never in the background
    show_compile_notices()
    try:
        with interrupt_handling():
            status = _run_parsed(parser, argv)
            check_interrupt()  # an interrupt swallowed where Python could not raise it
            return status
    except KeyboardInterrupt as exc:  # (also one landing while the handling itself is set up or undone)
        detail = f"; {exc.args[0]}" if exc.args and isinstance(exc.args[0], str) else ""
        _report_line(f"mtbmj: interrupted{detail}")
        return 130
    except BaseException:
        if interrupted():  # what an interrupt became on its way up (a C extension's failed import)
            _report_line("mtbmj: interrupted")
            return 130
        raise


def _report_line(line: str) -> None:
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def _run_parsed(parser: argparse.ArgumentParser, argv=None) -> int:
    config_warnings = _ConfigWarnings()
    try:
        with warnings.catch_warnings(), command_line():  # a number refused deep in a run names the option typed
            # numpy's RuntimeWarnings (overflow, invalid value) are errors only where a run steps
            # (``mtbmj.errors.diverging``, around every rig's stepping); elsewhere (a fit, a reader,
            # a library that meets such a value and handles it) they are not the user's concern
            warnings.simplefilter("ignore", RuntimeWarning)
            warnings.simplefilter("always", ConfigWarning)  # each kept once by config_warnings
            warnings.showwarning = config_warnings.showwarning  # restored with the filters when the command ends
            args = parser.parse_args(argv)  # the numeric arguments' plausibility warnings come from here
            status = _run_claimed(args)
        config_warnings.print()
        return status
    except RunError as exc:
        _report(f"{exc}{config_warnings.suffix()}")
        return EXIT_BAD_INPUT
    except MtbmjError as exc:
        _report(f"{exc}{'' if getattr(exc, 'alone', False) else config_warnings.suffix(str(exc))}")
        return EXIT_BAD_INPUT
    except (RuntimeWarning, FloatingPointError) as exc:  # a numerical failure no guard named (none is known)
        _report(f"numerical failure ({exc}){config_warnings.suffix()}")
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # the reader went away (``mtbmj presets | head -1``): stop quietly
        _silence_stdout()
        return EXIT_BROKEN_PIPE
    except RecursionError:
        print("mtbmj: error: input nested too deeply", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # the machine refused (disk full, read-only, permissions): one line too
        where = f"{exc.filename}: " if exc.filename else ""
        _report(f"{where}{exc.strerror or exc}")
        return EXIT_BAD_INPUT


# every character ``str.splitlines`` breaks a line at
LINE_BREAKS = frozenset("\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029")


def _report(message: str) -> None:
    """The one line on stderr: a line break in the message (from a file name or a value the
    user gave) is shown escaped, so the report stays one line. An error that an interrupt caused
    (a worker's pool broken by it, a call it cut short) is reported as the interrupt."""
    check_interrupt()
    print(f"mtbmj: error: {_one_line(message)}", file=sys.stderr)


def _one_line(message: str) -> str:
    return "".join(ch.encode("unicode_escape").decode("ascii") if ch in LINE_BREAKS else ch for ch in message)


EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, what a shell reports for a command whose reader quit


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        pass


def comma_words(text: str) -> list[str]:
    """The words of a comma list a user typed (``--lock Rear,pitch,``, ``--stance standing, seated``): stripped, in
    lower case, an empty one (a comma too many) left out, as ``--presets S1,,S2`` is read."""
    return [word.strip().lower() for word in text.split(",") if word.strip()]


def given_options(args, **defaults) -> str:
    """The options of ``defaults`` (attribute: its default) the command line set, as the user typed them
    ("--engines and --tolerance-mm"): a refusal names those only."""
    names = [f"--{k.replace('_', '-')}" for k, default in defaults.items() if _set(getattr(args, k, default), default)]
    return ", ".join(names[:-1]) + (" and " if len(names) > 1 else "") + names[-1] if names else ""


def options_verb(given: str, one: str, many: str) -> str:
    """``given`` (:func:`given_options`) with its verb agreeing: "--power: applies", "--pedal and --power: apply"."""
    return f"{given}: {one if ' and ' not in given else many}"


def _set(value, default) -> bool:
    """An option's value differs from its default (an appending option's empty list is not set)."""
    return value != default and not (isinstance(value, (list, tuple)) and not value)

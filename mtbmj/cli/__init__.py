"""The ``mtbmj`` command line: one module per command, the shared parts in ``common``. Headless;
bad input gets one line on stderr and exit status 2; results are written atomically."""
from __future__ import annotations

import sys

from mtbmj._package import __version__
from mtbmj.cli.common import EXIT_BAD_INPUT, Parser, run  # noqa: F401  (the exit status, for callers)

COMMANDS = ("drop", "airstudy", "sag", "curve", "compare", "fit", "synth", "validate", "sweep", "sensitivity", "roll", "telemetry", "render", "presets")


def build_parser() -> Parser:
    """The whole command line; each command module adds its sub-command(s) with ``add_parser``."""
    import importlib

    parser = Parser(prog="mtbmj", description="Mountain-bike fork + tire drop-sled study on MuJoCo with an ODE reference.")
    parser.add_argument("--version", action="version", version=f"mtbmj {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for name in COMMANDS:
        importlib.import_module(f"mtbmj.cli.{name}").add_parser(sub)
    return parser


def main(argv=None) -> int:
    return run(build_parser(), argv)


if __name__ == "__main__":
    sys.exit(main())

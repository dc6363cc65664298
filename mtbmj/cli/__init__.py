"""The ``mtbmj`` command line: one module per command, the shared parts in ``common``. Headless;
bad input gets one line on stderr and exit status 2; results are written atomically."""
from __future__ import annotations

import sys

from mtbmj._package import __version__

# Nothing heavy at import: ``python -m mtbmj.cli`` and the ``mtbmj`` script import this package
# before their entry (``_entry``) installs its Ctrl-C handler, so the shared parts load after it.

COMMANDS = ("drop", "airstudy", "sag", "curve", "compare", "fit", "synth", "validate", "sweep", "sensitivity", "roll", "bike", "telemetry", "render", "presets", "linkage", "reconstruct", "advise", "bob")


def build_parser():
    """The whole command line (a ``common.Parser``); each command module adds its sub-command(s)
    with ``add_parser``."""
    import importlib

    from mtbmj.cli.common import Parser

    parser = Parser(prog="mtbmj", description="Mountain-bike fork + tire drop-sled study on MuJoCo with an ODE reference.")
    parser.add_argument("--version", action="version", version=f"mtbmj {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for name in COMMANDS:
        importlib.import_module(f"mtbmj.cli.{name}").add_parser(sub)
    return parser


def main(argv=None) -> int:
    from mtbmj.cli.common import run

    return run(build_parser(), argv)


def __getattr__(name):  # the shared names callers read from here: EXIT_BAD_INPUT, Parser, run
    if name in ("EXIT_BAD_INPUT", "Parser", "run"):
        from mtbmj.cli import common

        return getattr(common, name)
    raise AttributeError(f"module 'mtbmj.cli' has no attribute {name!r}")


if __name__ == "__main__":
    sys.exit(main())

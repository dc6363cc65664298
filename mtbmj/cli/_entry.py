"""The ``mtbmj`` executable: Ctrl-C from the first instant is one line and exit status 130.

The command line's own handling (``mtbmj.errors.interrupt_handling``) covers the command; before
it, while Python imports the command line, Ctrl-C would print a traceback, and after it, while the
interpreter shuts down, end the process without a word. This entry point, used by the console script and by
``python -m mtbmj.cli`` only (never by ``import mtbmj`` or ``import mtbmj.cli``), covers those
moments (all but the first few tens of milliseconds, while ``mtbmj.cli`` itself is imported): nothing has been
written then, so it exits at once.
"""
from __future__ import annotations

import os
import signal
import sys


def _interrupted_outside_a_command(signum, frame) -> None:
    try:
        os.write(2, b"mtbmj: interrupted\n")
    finally:
        os._exit(130)


def main() -> int:  # never returns: exits with the command's status
    signal.signal(signal.SIGINT, _interrupted_outside_a_command)
    # the executable's own process: linear algebra on one thread, before numpy loads its BLAS (importing
    # mtbmj.workers loads neither numpy nor scipy); a user's own setting of the variables is kept
    from mtbmj.workers import one_blas_thread

    one_blas_thread()
    from mtbmj.cli import main as cli_main

    status = cli_main()
    # The command is done and has shut its pools down: leave without the interpreter's teardown,
    # during which Python restores the default SIGINT handler and a late Ctrl-C would end the
    # process silently (killed by the signal, no line).
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            if stream is sys.stdout:
                status = status or 141  # the reader went away before the last line (as a broken pipe)
    os._exit(status)

"""The command line's help imports no engine: ``mtbmj --help`` (and a command's own) builds every
parser, and the parsers read constants of the law modules (the drive's limits, the terrain names),
which import no MuJoCo (``mtbmj.controllers`` imports its callback on first use)."""
from __future__ import annotations

import subprocess
import sys

import pytest

CODE = """
import contextlib, io, sys
sys.argv = ["mtbmj", *sys.argv[1:]]
from mtbmj.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main()
    except SystemExit:
        pass
print(sorted(m for m in ("mujoco", "numba", "scipy", "matplotlib") if m in sys.modules))
"""


@pytest.mark.parametrize("argv", [["--help"], ["roll", "--help"], ["bike", "--help"], ["drop", "--help"]])
def test_help_imports_no_engine(argv):
    out = subprocess.run([sys.executable, "-c", CODE, *argv], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", (argv, out.stdout)


def test_the_lazy_names_still_import():
    from mtbmj.controllers import ForkCallback, installed
    from mtbmj.controllers.callback import ForkCallback as direct, installed as direct_installed

    assert ForkCallback is direct and installed is direct_installed
    import mtbmj.controllers as controllers

    with pytest.raises(AttributeError, match="nope"):
        controllers.nope  # noqa: B018

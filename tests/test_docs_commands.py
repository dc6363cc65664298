"""Every command the README and the docs pages show is one the command line takes: each `mtbmj`
line of a fenced shell block parses with the installed parser (its options and choices exist, its
values have their types), and each `python -c` snippet compiles. Running them all would take
minutes (a study, a 10 000-variant sweep); the pages whose commands are run as written are tested
on their own (docs/figures.md in tests/test_curve.py, docs/configuration.md in
tests/test_config_reference.py, the dm_control example of docs/rolling.md in tests/test_rl.py)."""
from __future__ import annotations

from pathlib import Path

import pytest

from mtbmj.cli import build_parser

from helpers import PAGES, shell_commands


CASES = [(page, line, argv) for page in PAGES for line, argv in shell_commands(page)]


def test_the_pages_show_commands():
    mtbmj_commands = [c for c in CASES if c[2][0] == "mtbmj"]
    assert len(mtbmj_commands) >= 60
    assert {p.name for p, _, _ in mtbmj_commands} >= {"README.md", "usage.md", "fitting.md", "sweeps.md"}


@pytest.mark.parametrize("page, line, argv", [c for c in CASES if c[2][0] == "mtbmj"],
                         ids=lambda v: v.name if isinstance(v, Path) else str(v) if isinstance(v, int) else None)
def test_every_mtbmj_command_shown_parses(page, line, argv, capsys):
    parser = build_parser()
    if argv[1:] and argv[-1] in ("--help", "-h"):
        with pytest.raises(SystemExit) as done:
            parser.parse_args(argv[1:])
        assert done.value.code == 0
        return
    from mtbmj.errors import MtbmjError

    try:
        args = parser.parse_args(argv[1:])
    except (SystemExit, MtbmjError) as exc:  # pragma: no cover - the message says which
        pytest.fail(f"{page.name}:{line}: {' '.join(argv)} does not parse ({exc}): {capsys.readouterr().err}")
    assert hasattr(args, "func"), f"{page.name}:{line}: {' '.join(argv)} names no command"


@pytest.mark.parametrize("page, line, argv", [c for c in CASES if c[2][:2] in (["python", "-c"], ["python3", "-c"])],
                         ids=lambda v: v.name if isinstance(v, Path) else str(v) if isinstance(v, int) else None)
def test_every_python_snippet_shown_compiles(page, line, argv):
    compile(argv[2], f"{page.name}:{line}", "exec")


def test_the_scan_and_the_parser_catch_a_wrong_command(tmp_path):
    """The check can fail: a page with a misspelled option and a continued line is read as the
    shell would, and the misspelled option does not parse."""
    page = tmp_path / "page.md"
    page.write_text("```bash\nmtbmj drop S12 \\\n  --enigne fast --out x   # a typo\nmtbmj presets | head -1\n```\n")
    assert shell_commands(page) == [(2, ["mtbmj", "drop", "S12", "--enigne", "fast", "--out", "x"]),
                                    (4, ["mtbmj", "presets"]), (4, ["head", "-1"])]
    from mtbmj.errors import MtbmjError

    with pytest.raises((SystemExit, MtbmjError)):
        build_parser().parse_args(["drop", "S12", "--enigne", "fast", "--out", "x"])

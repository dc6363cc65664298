"""``mtbmj fit KIND --help`` prints the options of that kind (issue 23), wherever the kind and the
help option stand on the command line; ``mtbmj fit --help`` keeps the whole command's; and the
command lines a fit is run with parse exactly as they did (every option still taken by every
kind: the per-kind parsers only print help)."""
import subprocess
import sys

import pytest

from mtbmj.cli import build_parser, main
from mtbmj.cli.fit import KINDS, kind_parser

OWN = {
    "spring": {"--model", "--config"},
    "damper": {"--model", "--friction", "--clicks"},
    "tire": {"--mass-kg"},
    "drop": {"--config", "--free", "--bound", "--set", "--engine", "--starts", "--touch-s"},
}
ALL = set().union(*OWN.values())


def _help(capsys, argv) -> str:
    capsys.readouterr()
    with pytest.raises(SystemExit) as done:
        main(argv)
    assert done.value.code == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_prints_its_own_options(capsys, kind):
    text = _help(capsys, ["fit", kind, "--help"])
    assert text.startswith(f"usage: mtbmj fit {kind} ")
    assert "  -h, --help" in text
    for option in OWN[kind] | {"--out"}:
        assert f"  {option}" in text, option
    for option in ALL - OWN[kind]:
        assert f"  {option}" not in text and f"[{option}" not in text, option
    assert "%%" not in text and "%(" not in text
    assert "fit.toml" in text


def test_the_model_names_are_the_fits_own(capsys):
    from mtbmj.identify import damper, spring

    text = " ".join(_help(capsys, ["fit", "spring", "--help"]).split())
    for name in spring.MODELS:
        assert name in text
    text = " ".join(_help(capsys, ["fit", "damper", "--help"]).split())
    for name in damper.HYDRAULIC + damper.FRICTION:
        assert name in text


@pytest.mark.parametrize("argv, kind", [
    (["fit", "damper", "dyno.csv", "--help"], "damper"),
    (["fit", "-h", "tire"], "tire"),
    (["fit", "--config", "drop", "spring", "--help"], "spring"),  # an option's value is no kind
    (["fit", "--config=air120", "spring", "-h"], "spring"),
    (["fit", "--conf", "damper", "drop", "--help"], "drop"),  # an abbreviated option takes its value too
    (["fit", "--engine", "ode", "--starts", "3", "drop", "--help"], "drop"),
    (["fit", "--help"], None),
    (["fit", "nonsense", "--help"], None),
])
def test_the_kind_is_found_wherever_it_stands(capsys, argv, kind):
    text = _help(capsys, argv)
    if kind is None:
        assert text.startswith("usage: mtbmj fit [-h]")
        for option in ALL:
            assert f"  {option}" in text  # the whole command's options
        assert "mtbmj fit KIND --help" in text
    else:
        assert text.startswith(f"usage: mtbmj fit {kind} ")


@pytest.mark.parametrize("argv, expected", [
    (["fit", "damper", "a.csv", "b.csv", "--clicks", "0,6", "--model", "digressive"],
     {"kind": "damper", "data": ["a.csv", "b.csv"], "clicks": ["0,6"], "model": "digressive", "friction": "auto"}),
    (["fit", "--starts", "4", "drop", "rec.csv", "--free", "tire.impact_rate_N_per_mm", "--bound",
      "tire.impact_rate_N_per_mm=10:400", "--set", "sled.drop_height_mm=150", "--engine", "fast"],
     {"kind": "drop", "data": ["rec.csv"], "starts": 4, "free": "tire.impact_rate_N_per_mm",
      "bound": ["tire.impact_rate_N_per_mm=10:400"], "set": ["sled.drop_height_mm=150"], "engine": "fast",
      "config": "S12", "touch_s": None}),
    (["fit", "tire", "drop.csv", "--mass-kg", "2.5", "ramp.csv"],
     {"kind": "tire", "data": ["drop.csv", "ramp.csv"], "mass_kg": 2.5}),
    (["fit", "spring", "example", "--config", "air120"], {"kind": "spring", "data": ["example"], "config": "air120",
                                                          "model": "auto", "starts": 1, "clicks": None}),
    (["fit", "damper", "x.csv", "--starts", "2", "--mass-kg", "3"],  # taken (and left unused) as before
     {"kind": "damper", "starts": 2, "mass_kg": 3.0}),
])
def test_command_lines_parse_as_before(argv, expected):
    args = build_parser().parse_args(argv)
    for key, value in expected.items():
        assert getattr(args, key) == value, key
    assert args.func.__name__ == "cmd_fit"


def test_kind_parsers_print_help_only():
    for kind in KINDS:
        text = kind_parser(kind).format_help()
        assert "%%" not in text and "%(" not in text


def test_the_installed_command_prints_the_kinds_help():
    done = subprocess.run([sys.executable, "-m", "mtbmj.cli", "fit", "damper", "--help"], capture_output=True,
                          text=True, check=False, timeout=120)
    assert done.returncode == 0 and done.stderr == ""
    assert done.stdout.startswith("usage: mtbmj fit damper") and "--clicks" in done.stdout
    assert "--starts" not in done.stdout

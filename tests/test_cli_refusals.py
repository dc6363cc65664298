"""Refusals the red team's round 4 found missing (issue 37 item 4)."""
import pytest

from mtbmj import cli


@pytest.mark.parametrize("value", ["-1", "0", "nan", "inf", "-inf"])
def test_crosscheck_tolerance_must_be_positive(value, capsys):
    """``crosscheck S1 --tolerance-mm -1`` ran and reported that the engines exceed a negative
    tolerance; now one line, exit 2, before any run."""
    assert cli.main(["crosscheck", "S1", f"--tolerance-mm={value}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--tolerance-mm" in err and "Traceback" not in err

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


@pytest.mark.parametrize("engines", ["ode", "ode,ode"])
def test_crosscheck_of_the_reference_alone_is_refused(engines, capsys):
    """``crosscheck S1 --engines ode`` ran MuJoCo's cross-check instead, silently (the reference is what
    every engine is checked against): one line naming the option, exit 2, before any run."""
    assert cli.main(["crosscheck", "S1", "--engines", engines]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--engines: ode is the reference" in err and "Traceback" not in err


@pytest.mark.parametrize("argv", [
    ["roll", "washboard:length_m=1e9", "--speed", "4"],
    ["bike", "trail", "washboard:length_m=1e9", "--speed", "4"],
    ["roll", "flat:length_m=5000", "--speed", "4"],
    ["bike", "trail", "iso8608:sample_mm=0.001", "--speed", "4"],
    ["roll", "rock:at_m=1e12", "--speed", "4"],
])
def test_huge_terrains_are_refused_before_anything_is_allocated(argv, capsys, tmp_path, monkeypatch):
    """``roll`` or ``bike`` over ``washboard:length_m=1e9`` tried to allocate 1.46 TiB (a MemoryError
    traceback); a terrain's size is checked before its profile is made (issue 37 item 3)."""
    import tracemalloc

    monkeypatch.chdir(tmp_path)
    tracemalloc.start()
    try:
        assert cli.main(argv) == 2
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "terrain" in err and "Traceback" not in err
    assert peak < 200e6  # nothing of the profile's size was made
    assert list(tmp_path.iterdir()) == []

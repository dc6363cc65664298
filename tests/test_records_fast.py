"""The CSV reader parses a record's numbers at once with numpy and falls back to its line-by-line
reader for anything numpy refuses. Checked here against a reader written in this file (Python's
``csv`` and ``float``, one line at a time): every record reads to bitwise the same values, and
every record it refuses gets the same one-line message, naming the same line."""
import csv
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtbmj.measured import records
from mtbmj.measured.records import RecordError, read_csv
from mtbmj.measured.records import _convert as convert

FAST = {"read": 0, "refused": 0}  # how often the fuzz below took numpy's path, and how often not


def spy(lines, delimiter, width):
    table = FAST_READER(lines, delimiter, width)
    FAST["read" if table is not None else "refused"] += 1
    return table


FAST_READER = records._numbers


def reference(path):
    """What a record holds, line by line: (names, rows) or the error text for the line at fault."""
    lines = [(n, line) for n, line in enumerate(path.read_text().splitlines(), 1)
             if line.strip() and not line.strip().startswith("#")]
    header = lines[0][1]
    delimiter = max((",", ";", "\t"), key=header.count)
    names = [c.strip() for c in next(csv.reader([header], delimiter=delimiter))]
    rows = []
    for n, line in lines[1:]:
        cells = [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]
        if len(cells) != len(names):
            return f"{path}: line {n}: {len(cells)} cells for {len(names)} columns"
        try:
            row = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not _parses(c))
            return f"{path}: line {n}: {bad!r} is not a number"
        if not all(math.isfinite(v) for v in row):
            return f"{path}: line {n}: NaN or infinite value"
        rows.append(row)
    if not rows:
        return f"{path}: header but no data rows"
    return names, np.array(rows)


def _parses(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def same_reading(path):
    expected = reference(path)
    if isinstance(expected, str):
        with pytest.raises(RecordError) as caught:
            read_csv(path)
        assert str(caught.value) == expected
        return False
    got = read_csv(path)
    want = convert(str(path), expected[0], expected[1], [])
    assert list(got.columns) == list(want.columns)
    for name in want.columns:
        a, b = got.columns[name], want.columns[name]
        assert a.shape == b.shape and a.tobytes() == b.tobytes(), name  # bitwise, sign of zero included
    return True


CELLS = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.floats(-1e3, 1e3).map(lambda x: f"{x:.17g}"),
    st.integers(-10**20, 10**20).map(str),
    st.sampled_from(["0", "-0", "+1", ".5", "5.", "1e-3", "1E+3", " 2.5 ", "\t7", "1_000", '"3"', "0x10", "",
                     "nan", "inf", "-Infinity", "1e400", "abc", "1 2", "1,5", "١٢", "1.0d3", "  "]),
)


@settings(max_examples=300, deadline=None)
@given(delimiter=st.sampled_from([",", ";", "\t"]), width=st.integers(1, 4),
       rows=st.lists(st.lists(CELLS, min_size=1, max_size=5), min_size=0, max_size=6),
       clean=st.booleans(), crlf=st.booleans())
def test_fast_reader_reads_as_the_line_by_line_reader(tmp_path_factory, delimiter, width, rows, clean, crlf):
    names = ["time_s", "displacement_mm", "force_N", "velocity_mm_per_s"][:width]
    if clean:  # mostly records a user has: plain numbers, the right width
        rows = [[c if _parses(c) and math.isfinite(float(c)) else "1" for c in (row * width)[:width]] for row in rows]
    text = "# a comment\n" + delimiter.join(names) + "\n" + "\n".join(delimiter.join(r) for r in rows) + "\n"
    path = tmp_path_factory.mktemp("csv") / "record.csv"
    path.write_bytes(text.replace("\n", "\r\n").encode() if crlf else text.encode())
    records._numbers = spy
    try:
        same_reading(path)
    finally:
        records._numbers = FAST_READER


def test_the_fuzz_took_both_paths():
    """The fuzz above read records on numpy's path and refused others to the line-by-line one."""
    assert FAST["read"] >= 30 and FAST["refused"] >= 30, FAST


def test_a_long_dyno_record_reads_bitwise_as_line_by_line(tmp_path):
    """29 000 lines of a synthetic dyno record (as ``mtbmj synth damper`` writes them), with blank
    and comment lines in between, and the same record with one line spoiled near its end."""
    from mtbmj.cli import main

    path = tmp_path / "dyno.csv"
    assert main(["synth", "damper", "S12", "--seed", "4", "--out", str(path)]) == 0
    lines = path.read_text().splitlines()
    lines[500:500] = ["", "# a note in the middle", "   "]
    path.write_text("\n".join(lines) + "\n")
    assert records._numbers([(1, "1,2"), (2, "3,4")], ",", 2).tolist() == [[1.0, 2.0], [3.0, 4.0]]
    assert same_reading(path)
    for spoil in ("1.0,2.0", "1.0,x,3,4", "1,2,3,nan"):
        spoiled = tmp_path / "spoiled.csv"
        spoiled.write_text("\n".join(lines[:-3] + [spoil] + lines[-2:]) + "\n")
        assert not same_reading(spoiled)


def test_a_warning_from_numpys_reader_leaves_the_record_to_the_line_by_line_reader(tmp_path, monkeypatch):
    """The fast path turns warnings into errors to catch numpy's empty-input warning; a warning of
    another kind (a deprecation in some numpy) must not escape as an exception: the line-by-line
    reader reads the record, to the same values."""
    path = tmp_path / "record.csv"
    path.write_text("time_s,force_N\n0.0,1.5\n0.001,-2.25\n")
    expected = read_csv(path)
    loadtxt = np.loadtxt

    def warning_loadtxt(*args, **kwargs):
        import warnings
        warnings.warn("some future numpy deprecates an argument", DeprecationWarning)
        return loadtxt(*args, **kwargs)

    monkeypatch.setattr(records.np, "loadtxt", warning_loadtxt)
    got = read_csv(path)
    assert list(got.columns) == list(expected.columns) == ["time", "force"]
    for name in expected.columns:
        assert np.array_equal(got.columns[name], expected.columns[name])

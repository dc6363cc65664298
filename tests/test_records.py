"""Reading bench and drop records: units in column names, comments, delimiters, .mat, bad input."""
import numpy as np
import pytest
from scipy.io import savemat

from mtbmj.measured.records import RecordError, read_record, split_unit, write_csv_text


def test_units_are_parsed_from_column_names():
    assert split_unit("displacement_mm") == ("displacement", "mm")
    assert split_unit("velocity_mm_per_s") == ("velocity", "mm_per_s")
    assert split_unit("force_N") == ("force", "N")
    assert split_unit("time_s") == ("time", "s")
    assert split_unit("force") is None


@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_csv_with_comments_and_any_delimiter_is_read_in_si(tmp_path, delimiter):
    path = tmp_path / "spring.csv"
    path.write_text(f"# synthetic dyno record\n# rate 10 N/mm\n"
                    f"time_s{delimiter}displacement_mm{delimiter}force_N\n"
                    f"0{delimiter}0{delimiter}0\n\n0.1{delimiter}10{delimiter}100.5\n# a note\n0.2{delimiter}20{delimiter}201\n")
    r = read_record(path).require("displacement", "force", min_points=3)
    assert np.allclose(r["displacement"], [0.0, 0.01, 0.02])  # mm -> m
    assert np.allclose(r["force"], [0.0, 100.5, 201.0])
    assert r.synthetic and r.units["displacement"] == "mm" and len(r) == 3


def test_mat_export_reads_like_the_csv(tmp_path):
    x = np.linspace(0, 100, 50)
    savemat(tmp_path / "r.mat", {"displacement_mm": x, "force_N": 10 * x, "description": "synthetic test"})
    (tmp_path / "r.csv").write_text(write_csv_text({"displacement_mm": x, "force_N": 10 * x}, ["synthetic test"]))
    a, b = read_record(tmp_path / "r.mat"), read_record(tmp_path / "r.csv")
    for q in ("displacement", "force"):
        assert np.allclose(a[q], b[q])
    assert a.synthetic and b.synthetic


@pytest.mark.parametrize("text, needle", [
    ("displacement,force_N\n1,2\n", "'displacement' has no unit"),
    ("displacement_mm,force_N\n1,abc\n", "line 2: 'abc' is not a number"),
    ("displacement_mm,force_N\n1,2,3\n", "line 2: 3 cells for 2 columns"),
    ("displacement_mm,force_N\n1,nan\n", "line 2: NaN"),
    ("# only a comment\n", "no header row"),
    ("displacement_mm,force_N\n", "no data rows"),
    ("displacement_mm,displacement_m\n1,2\n", "displacement appears twice"),
    # a unit mtbmj does not read was said to be no unit at all
    ("displacement_in,force_lbf\n1,2\n", "column 'displacement_in': unit 'in' is not one mtbmj reads"),
])
def test_bad_csv_names_file_line_or_column(tmp_path, text, needle):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(RecordError) as exc:
        read_record(path)
    assert needle in str(exc.value) and str(path) in str(exc.value)
    assert "\n" not in str(exc.value)


def test_required_columns_point_count_and_time_order(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time_s,force_N\n0,1\n0.1,2\n0.1,3\n0.3,4\n")
    r = read_record(path)
    with pytest.raises(RecordError, match="missing column displacement_<unit>"):
        r.require("displacement", "force", min_points=2)
    with pytest.raises(RecordError, match="too few points"):
        r.require("force", min_points=10)
    with pytest.raises(RecordError, match="time is not increasing at row 3"):
        r.require("force", min_points=2)


def test_missing_binary_and_not_mat_files(tmp_path):
    with pytest.raises(RecordError, match="no such file"):
        read_record(tmp_path / "none.csv")
    (tmp_path / "bin.csv").write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(RecordError, match="not a text file"):
        read_record(tmp_path / "bin.csv")
    (tmp_path / "x.mat").write_text("hello")
    with pytest.raises(RecordError, match="not a readable MATLAB"):
        read_record(tmp_path / "x.mat")


def test_a_byte_order_mark_is_not_part_of_the_record(tmp_path):
    """Excel's "CSV UTF-8" starts the file with a byte-order mark: it stuck to the first line, so a
    comment line read as the header ("line 3: 3 cells for 6 columns") and a header's first name as an
    unknown column."""
    text = "# synthetic dyno record\ntime_s;displacement_mm;force_N\r\n0;0;0\r\n0.1;10;100.5\r\n0.2;20;201\r\n"
    (tmp_path / "plain.csv").write_text(text)
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + text.encode())
    (tmp_path / "bom_header.csv").write_bytes(b"\xef\xbb\xbf" + text.split("\n", 1)[1].encode())
    plain = read_record(tmp_path / "plain.csv")
    for name in ("bom.csv", "bom_header.csv"):
        r = read_record(tmp_path / name).require("displacement", "force", min_points=3)
        assert list(r.columns) == ["time", "displacement", "force"]
        assert np.allclose(r["force"], [0.0, 100.5, 201.0]) and np.array_equal(r["force"], plain["force"])
    assert read_record(tmp_path / "bom.csv").synthetic


def test_units_in_another_case_read_as_the_known_units(tmp_path):
    """A spreadsheet's capitalised header (Displacement_MM, Force_n, Time_MS) was refused as "has no
    unit in its name": each unit is read as the one of UNITS spelled so in lower case (none two differ
    only in case), converted to SI as written in its own case."""
    assert split_unit("Displacement_MM") == ("displacement", "mm")
    assert split_unit("force_n") == ("force", "N") and split_unit("Force_KN") == ("force", "kN")
    assert split_unit("Velocity_MM_PER_S") == ("velocity", "mm_per_s") and split_unit("displacement_in") is None
    (tmp_path / "r.csv").write_text("Time_MS,Displacement_MM,Force_KN\n0,10,1.5\n100,20,2.5\n")
    r = read_record(tmp_path / "r.csv")
    assert np.allclose(r["time"], [0.0, 0.1]) and np.allclose(r["displacement"], [0.01, 0.02])
    assert np.allclose(r["force"], [1500.0, 2500.0])

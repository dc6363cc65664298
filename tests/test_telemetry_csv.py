"""A ride as a CSV of travel (issue 41 item 1): the headline's numbers are the series' own (sines
written here, their maximum and mean known), the rear from the shock's stroke through the recorded
bike's leverage curve (integrated here), and bad files refused in one line naming the line."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.cli import main

RATE = 500.0


def _csv(path, columns: dict, rate=RATE, seconds=40.0, comment=True):
    t = np.arange(int(seconds * rate)) / rate
    data = {"time_s": t, **{k: f(t) for k, f in columns.items()}}
    lines = (["# exported by a logger"] if comment else []) + [",".join(data)]
    lines += [",".join(f"{data[k][i]:.6f}" for k in data) for i in range(t.size)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_travel_csv_gives_the_headline_of_its_own_series(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    _csv(tmp_path / "ride.csv", {"fork_mm": lambda t: 50.0 + 40.0 * np.sin(2 * np.pi * 1.3 * t),
                                 "rear_mm": lambda t: 60.0 + 30.0 * np.sin(2 * np.pi * 1.1 * t)})
    assert main(["telemetry", "ride.csv", "--out", "tel"]) == 0
    out = capsys.readouterr().out
    assert "ride.csv: 40.0 s at 500 Hz" in out
    assert "fork max 50 % (90.0 of 180 mm), 0 bottom-outs, dynamic sag 28 %" in out  # 90 of 180; mean 50 of 180


def test_the_shock_column_goes_through_the_bikes_leverage_curve(tmp_path, monkeypatch, capsys):
    from mtbmj.bike import spec

    monkeypatch.chdir(tmp_path)
    _csv(tmp_path / "ride.csv", {"shock_mm": lambda t: 20.0 + 15.0 * np.sin(2 * np.pi * 1.1 * t)})
    assert main(["telemetry", "ride.csv", "--bike", "trail", "--out", "tel"]) == 0
    out = capsys.readouterr().out
    lev = spec.load("trail").leverage
    # the wheel travel at 35 mm of stroke: integrate dw = LR(w) ds here, on a fine grid
    def wheel(stroke, ds=1e-3):
        w, s = 0.0, 0.0
        while s < stroke - 1e-12:
            w += lev.ratio_at((w + 0.5 * lev.ratio_at(w * 1e-3) * ds) * 1e-3) * ds  # midpoint rule
            s += ds
        return w

    w, full = wheel(35.0), wheel(spec.load("trail").shock_stroke * 1e3)  # full: the shock's whole stroke
    assert f"rear max {100 * w / full:.0f} % ({w:.1f} of {full:.0f} mm)" in out


@pytest.mark.parametrize("text,said", [
    ("time_s,fork_mm\n0,1\n0.002,x\n", "line 3: fork_mm is not a number: 'x'"),
    ("time_s,fork\n0,1\n", "line 1: unknown column 'fork'"),
    ("time_s,fork_mm\n0,1\n0.002,2\n0.004,3\n0.010,4\n", "line 5: time_s steps 0.006 s"),
    ("time_s,fork_mm\n0,1\n0.002\n", "line 3: 1 values for 2 columns"),
    ("time_s\n0\n1\n", "needs time_s and one or more"),
    ("time_s,fork_mm\n0,nan\n", "line 2: fork_mm is not finite"),
])
def test_a_bad_csv_is_one_line_naming_the_line(tmp_path, monkeypatch, capsys, text, said):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ride.csv").write_text(text)
    assert main(["telemetry", "ride.csv", "--out", "tel"]) == 2
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "tel").exists()


def _exported(path, separator=",", newline="\n", bom=False, names=("time_s", "fork_mm"), closed=False):
    """The same 40 s ride (fork 50 +- 40 mm at 1.3 Hz, 500 Hz) as a spreadsheet or logger exports it:
    its separator, line ends, a UTF-8 byte-order mark, the names' case, a separator closing each row."""
    t = np.arange(int(40.0 * RATE)) / RATE
    fork = 50.0 + 40.0 * np.sin(2 * np.pi * 1.3 * t)
    end = separator if closed else ""
    lines = [separator.join(names) + end] + [f"{a:.6f}{separator}{b:.6f}{end}" for a, b in zip(t, fork)]
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + newline.join(lines + [""]).encode())
    return path


@pytest.mark.parametrize("export", [
    {"bom": True},                                    # Excel's "CSV UTF-8": refused as column '\ufefftime_s'
    {"separator": ";"}, {"separator": "\t"},          # a spreadsheet in a comma-decimal locale, a tab export:
    {"separator": ";", "newline": "\r\n", "bom": True},  # refused as one unknown column 'time_s;fork_mm'
    {"names": ("Time_s", "Fork_MM")},                 # the names in another case: refused as unknown
    {"closed": True},                                 # a separator closing every row: refused as column ''
])
def test_a_travel_csv_as_spreadsheets_export_it_reads_as_the_plain_one(tmp_path, monkeypatch, capsys, export):
    monkeypatch.chdir(tmp_path)
    _exported(tmp_path / "ride.csv")
    assert main(["telemetry", "ride.csv", "--out", "plain"]) == 0
    plain = capsys.readouterr().out
    assert "fork max 50 % (90.0 of 180 mm), 0 bottom-outs, dynamic sag 28 %" in plain  # 90 of 180; mean 50
    _exported(tmp_path / "exported.csv", **export)
    assert main(["telemetry", "exported.csv", "--out", "exported"]) == 0
    assert capsys.readouterr().out.replace("exported", "ride") == plain.replace("plain", "ride")


def test_a_decimal_comma_is_refused_saying_so(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ride.csv").write_text("time_s;fork_mm\n0,000;50,5\n0,002;51,0\n")
    assert main(["telemetry", "ride.csv", "--out", "tel"]) == 2
    err = capsys.readouterr().err
    assert "line 2: time_s is not a number: '0,000' (a decimal comma? write the point: 0.000)" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "tel").exists()


def test_a_shock_and_a_rear_column_that_disagree_are_said(tmp_path, monkeypatch, capsys):
    """Both shock_mm and rear_mm given: each end is read from its own column, so one warning line says
    where they disagree through the bike's leverage curve (a logger's rear at a constant 2.6 ratio on
    the trail bike, whose curve is its own); the same ride with rear_mm made from shock_mm through that
    curve (integrated here, not by the reader) is read without it."""
    from mtbmj.bike import spec

    monkeypatch.chdir(tmp_path)
    lev = spec.load("trail").leverage
    grid = np.linspace(0.0, 160.0, 4001)  # wheel mm; the stroke along it, ds = dw / LR(w), integrated here
    ratio = np.array([lev.ratio_at(w * 1e-3) for w in grid])
    stroke_at = np.concatenate(([0.0], np.cumsum(np.diff(grid) / (0.5 * (ratio[1:] + ratio[:-1])))))

    def shock(t):
        return 20.0 + 15.0 * np.sin(2 * np.pi * 1.1 * t)

    _csv(tmp_path / "apart.csv", {"shock_mm": shock, "rear_mm": lambda t: 2.6 * shock(t)})
    assert main(["telemetry", "apart.csv", "--bike", "trail", "--out", "a"]) == 0
    err = capsys.readouterr().err
    assert "apart.csv: shock_mm and rear_mm disagree through the leverage curve they are read with" in err, err
    _csv(tmp_path / "one.csv", {"shock_mm": shock, "rear_mm": lambda t: np.interp(shock(t), stroke_at, grid)})
    assert main(["telemetry", "one.csv", "--bike", "trail", "--out", "b"]) == 0
    assert "disagree" not in capsys.readouterr().err

"""``--lift-rear`` takes the rear tyre off: no rear tyre, no rear rim strike (issue 39 item 6: it
reported rear rim strikes of 5.7e9-2.8e12 N, the probe's depth of a rim that has no tyre)."""
import json

import numpy as np

from mtbmj.cli import main


def test_a_lifted_rear_reports_no_rear_tyre_contact(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["bike", "sst", "drop:height_mm=300,at_m=0.4", "--speed", "4", "--lock", "pitch", "--lift-rear",
                 "--out", "run", "--quiet", "--no-figure"]) == 0
    s = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert s["rim_strikes"]["rear"] == 0 and s["rear"]["rim_strikes"]["count"] == 0
    assert s["tire_load"]["rear"]["max_N"] == 0.0
    rows = np.genfromtxt(tmp_path / "run" / "timeseries.csv", delimiter=",", names=True, skip_header=2)
    assert np.all(rows["rear_tire_mm"] == -10.0) and np.all(rows["rear_tire_N"] == 0.0)
    assert s["rim_strikes"]["front"] >= 1  # the front wheel alone took the 300 mm ledge onto its rim

"""The bike's sag (issue 40: no sag for the bike; 182 psi for 28 % was found by looping runs):
`mtbmj sag BIKE --bike --front-sag-percent F --rear-sag-percent R` solves the fork's and the
shock's springs together and writes a bike file that `mtbmj bike` runs at that sag."""
from __future__ import annotations

import math
import tomllib

import mtbmj
from mtbmj.cli import main

G = 9.81


def test_the_written_bike_sags_as_asked_and_its_fork_carries_the_front_load(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["sag", "trail", "--bike", "--front-sag-percent", "20", "--rear-sag-percent", "30",
                 "--set", "rider.mass_kg=78", "--out", "set"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and "run it with: mtbmj bike set/trail_sag.toml" in out
    written = tomllib.loads((tmp_path / "set" / "trail_sag.toml").read_text())
    assert written["base"] == "trail" and written["rider"]["mass_kg"] == 78
    k = written["fork"]["set"]["fork.spring.progressive_rate_N_per_mm"]
    r = mtbmj.run_bike(str(tmp_path / "set" / "trail_sag.toml"), "flat", speed_m_per_s=4.0, duration=0.05)
    s = r.summary
    assert r.headline().startswith("bike trail_sag ")  # named after the bike it set, not "bike"
    assert abs(s["static_front_travel_mm"] / 130.0 - 0.20) < 2e-4
    assert abs(s["static_rear_travel_mm"] / 120.0 - 0.30) < 2e-4
    # the fork's spring at that sag (the trail preset's law: preload 100 N + k x + c x^3, c = 1e-4 N/mm^3)
    # carries the front tyre's load less the fork lower and front wheel, along the steering axis
    x = s["static_front_travel_mm"]
    spring = 100.0 + k * x + 1e-4 * x ** 3
    head = math.radians(s["geometry"]["at_sag"]["head_angle_deg"])
    axial = (s["static_front_load_N"] - (1.1 + 2.1) * G) * math.sin(head)
    assert abs(spring - axial) < 0.01 * axial


def test_impossible_sags_and_mixed_options_are_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["sag", "trail", "--bike", "--front-sag-percent", "20", "--out", "a"]) == 2
    assert main(["sag", "trail", "--bike", "--front-sag-percent", "20", "--rear-sag-percent", "30",
                 "--sag-percent", "20", "--out", "b"]) == 2
    assert main(["sag", "trail", "--bike", "--front-sag-percent", "0.01", "--rear-sag-percent", "30",
                 "--out", "c"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []

"""A shock's adjusters in clicks (issue 40 item 4, the click maps): a bike's [shock.set] takes the
fork's clicks damper in shock units, its setting changes with --shock-set, and the rear rebounds
faster as the rebound adjuster opens."""
from __future__ import annotations

import numpy as np
import pytest

SHOCK = """base = "trail"
[shock.set]
"fork.damper.model" = "clicks"
"fork.damper.velocity_mm_per_s" = [-1000.0, -300.0, -100.0, 0.0, 100.0, 300.0, 1000.0]
"fork.damper.rebound_clicks_measured" = [0, 10, 20]
"fork.damper.rebound_force_N" = [[-3000.0, -1200.0, -500.0], [-2000.0, -800.0, -330.0], [-1200.0, -480.0, -200.0]]
"fork.damper.compression_clicks_measured" = [0, 10, 20]
"fork.damper.compression_force_N" = [[250.0, 700.0, 2000.0], [200.0, 560.0, 1600.0], [150.0, 420.0, 1200.0]]
"fork.damper.rebound_clicks" = 10
"fork.damper.compression_clicks" = 10
"""


def test_the_shock_s_clicks_set_its_damper_and_its_rebound(tmp_path):
    from mtbmj.bike import run, spec

    path = tmp_path / "bike.toml"
    path.write_text(SHOCK)
    laws = {}
    for clicks in (0, 5, 10, 20):
        s = spec.load(str(path), {"shock.set": {"fork.damper.rebound_clicks": clicks}})
        laws[clicks] = run.setups(s)[1].fork.damper
    # at a measured position the table's own row; between two, linear in clicks (written out here)
    assert laws[10].force(-0.3) == pytest.approx(-800.0)
    assert laws[5].force(-0.3) == pytest.approx(-1000.0)  # halfway between -1200 (0) and -800 (10)
    assert laws[20].force(0.3) == pytest.approx(560.0)  # compression stays at its 10 clicks
    speeds = {}
    for clicks in (0, 20):
        r = run.run_bike(str(path), "drop:height_mm=300,at_m=0.4", 5.0,
                         overrides={"shock.set": {"fork.damper.rebound_clicks": clicks}})
        w, t = r.raw["rear_travel_mm"], r.raw["time_s"]
        speeds[clicks] = float(np.min(np.gradient(w, t)))  # the fastest rebound, mm/s
    assert speeds[20] < 1.3 * speeds[0] < 0.0  # open (20 clicks) rebounds at least 30 % faster than closed

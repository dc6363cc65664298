"""Random plausible forks (mtbmj.drop.envelope, a seed of this file's own): both engines agree,
the end stops hold, the default step is chosen, never refused."""
import numpy as np
import pytest

import mtbmj
from mtbmj import compose
from mtbmj.drop.envelope import draws
from mtbmj.drop.run import run_drop

SEED = 20261123
N = 12
DURATION_S = 0.8
STOP_COMPLIANCE_MM = 2.0


def _table():
    return list(mtbmj.load_config("reference").require("fork.damper.force_N"))


CASES = draws(N, SEED, _table())


@pytest.mark.parametrize("preset,overrides", CASES, ids=[f"{p}-{i}" for i, (p, _) in enumerate(CASES)])
def test_random_fork_engines_agree_and_stops_hold(preset, overrides):
    cfg = mtbmj.load_config(preset, overrides)
    setup = compose.setup(cfg)  # never refused at default settings: the rule picks the step
    assert setup.timestep > 0
    m = run_drop(cfg, "mujoco", duration=DURATION_S)
    o = run_drop(cfg, "ode", duration=DURATION_S)
    worst = max(d["max_abs_mm"] for d in m.difference(o).values())
    assert worst <= 0.1, (preset, overrides, m.difference(o))
    travel = cfg.require("fork.travel_mm")
    deepest = cfg.require("tire.max_deflection_mm")
    for r in (m, o):
        assert np.max(r.raw["fork_mm"]) <= travel + STOP_COMPLIANCE_MM
        assert np.min(r.raw["fork_mm"]) >= -cfg.get("fork.stops.extension_mm", 5.0) - STOP_COMPLIANCE_MM
        assert np.max(r.raw["tire_mm"]) <= deepest + STOP_COMPLIANCE_MM
        report = r.summary["bottoms_out"]
        assert (report["count"] > 0) == bool(np.max(r.raw["fork_mm"]) >= travel)


def test_envelope_reaches_the_stops():
    """The envelope is not all gentle: some draws bottom out or strike the rim (else the stop
    checks above would check nothing)."""
    hits = 0
    for preset, overrides in CASES[:6]:
        r = run_drop(mtbmj.load_config(preset, overrides), "mujoco", duration=0.4)
        hits += r.summary["bottoms_out"]["count"] + r.summary["rim_strikes"]["count"]
    assert hits > 0

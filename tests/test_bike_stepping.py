"""The bike's step rule (``mtbmj.bike.stepping``): the coarse step where no stop or rim is near, the
fine step where one is, and which stretches get which.

* The shock stroke the rule watches, from the swingarm angle (in numpy: ``Leverage.strokes``),
  equals the stroke of the exact geometry (``PlanarBike.wheel_travel`` and the curve's own
  ``stroke``, point by point).
* The first and last samples within reach of a stop, on signals written here.
* A friction state that stiffens with the stroke speed (LuGre) makes the coarse step itself fine.
* The adaptive run (0.5 ms, fine near the stops) over a ledge drop that takes the fork into its
  bumper equals a run at the fine step throughout, sampled on the same grid."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mtbmj.bike import run as bike_run
from mtbmj.bike import spec as spec_mod
from mtbmj.bike import stepping as stepping_mod
from mtbmj.bike.reference import PlanarBike


def _plan(bike="sst"):
    spec = spec_mod.load(bike)
    fork, shock = bike_run.setups(spec)
    return spec, fork, shock, stepping_mod.stepping(spec, fork, shock)


def test_the_sst_bike_steps_at_half_a_millisecond_and_finer_near_its_stops():
    spec, fork, shock, plan = _plan()
    assert plan.coarse == pytest.approx(5e-4)
    assert plan.substeps > 1 and plan.fine * plan.substeps == pytest.approx(plan.coarse)
    assert "stops" in plan.fine_why  # the stops set the fine step (whether it is fine enough: the last test)
    assert plan.fork_zone == pytest.approx((-fork.fork.spring.extension, fork.fork.spring.bumper_start))


def test_the_stroke_it_watches_is_the_geometry_s():
    spec, _, _, plan = _plan()
    planar = PlanarBike(spec, 0.85, 0.45, 9.81)  # the rider's springs play no part in the wheel's path
    phi = np.linspace(-0.15, 0.45, 301)
    want = np.array([spec.leverage.stroke(planar.wheel_travel(a)[0]) for a in phi])
    assert np.max(np.abs(plan.stroke(phi) - want)) < 1e-15  # m


def _within_reach(plan, fork_travel, phi, deflections):
    """The bike's refinement's span over rows made here: states (time, fork, swingarm angle),
    sensors (the two tires' deflections)."""
    states = np.column_stack([np.zeros_like(fork_travel), fork_travel, phi])
    return plan.refinement(1, 2, [0, 1]).span(states, np.column_stack(deflections))


def test_within_reach_finds_the_first_and_last_samples_near_a_stop():
    _, fork, _, plan = _plan()
    bumper = fork.fork.spring.bumper_start
    n = 200
    x = np.full(n, 0.04)
    x[100:120] = np.linspace(0.04, bumper + 0.002, 20)  # into the bumper and back out
    x[120:140] = np.linspace(bumper + 0.002, 0.04, 20)
    phi = np.zeros(n)
    clear = [np.full(n, 0.01), np.full(n, 0.01)]
    step = np.max(np.abs(np.diff(x)))
    reach = stepping_mod.FORK_MARGIN_M + 2.0 * step
    near = np.flatnonzero(x >= bumper - reach)
    assert _within_reach(plan, x, phi, clear) == (near[0], near[-1])
    assert _within_reach(plan, np.full(n, 0.04), phi, clear) is None
    rim = list(clear)
    rim[1] = np.linspace(0.01, plan.rim_deflections[1] - 0.5e-3, n)  # the rear tire pressed towards its rim
    reach = stepping_mod.FORK_MARGIN_M + 2.0 * np.max(np.diff(rim[1]))
    near = np.flatnonzero(rim[1] >= plan.rim_deflections[1] - reach)
    assert _within_reach(plan, np.full(n, 0.04), phi, rim) == (near[0], n - 1)


def test_a_lugre_friction_state_makes_the_coarse_step_fine():
    base = spec_mod.load("sst")
    lugre = {"fork.friction.model": "lugre", "fork.friction.coulomb_N": 20.0, "fork.friction.breakaway_N": 30.0}
    bike = dataclasses.replace(base, fork_overrides={**base.fork_overrides, **lugre})
    fork, shock = bike_run.setups(bike)
    plan = stepping_mod.stepping(bike, fork, shock)
    assert plan.coarse < 1e-4 and "LuGre" in plan.coarse_why


def test_the_adaptive_run_equals_the_fine_step_throughout(monkeypatch):
    scenario, speed, duration = "drop:at_m=0.4", 4.0, 0.5
    adaptive = bike_run.run_bike("sst", scenario, speed, duration)
    assert 0.0 < adaptive.info["refined_fraction"] < 0.5  # the fork into its bumper: some of it fine
    assert adaptive.summary["front"]["bumper"]["count"] >= 1
    fine = adaptive.info["fine_timestep_s"]
    monkeypatch.setattr(stepping_mod, "COARSE_STEP_S", fine)  # one step everywhere: the fine one
    uniform = bike_run.run_bike("sst", scenario, speed, duration)
    assert uniform.info["timestep_s"] == pytest.approx(fine)
    every = int(round(adaptive.info["timestep_s"] / fine))
    for column in ("front_travel_mm", "rear_travel_mm", "stroke_mm"):
        a = adaptive.raw[column]
        b = uniform.raw[column][::every][:a.size]  # the same instants
        assert np.max(np.abs(a - b)) < 0.05, column  # mm: RK4 at 0.5 ms away from the stops


def test_the_leverage_curve_in_numpy_is_its_lookup():
    for name in ("sst", "trail"):
        lev = spec_mod.load(name).leverage
        w = np.concatenate([np.linspace(-0.03, lev.full_travel + 0.03, 2001), lev.table[0]])
        want = np.array([lev.stroke(x) for x in w])
        assert np.max(np.abs(lev.strokes(w) - want)) < 1e-15  # m: the same pieces, round-off apart
        # the ratio over an array: the lookup's own arithmetic, to the bit, the ends held
        assert np.array_equal(lev.ratios(w), [lev.ratio_at(x) for x in w])
        assert lev.ratios(-0.03) == lev.table[1][0] and lev.ratios(lev.full_travel + 0.03) == lev.table[1][-1]

"""The step rule (``mtbmj.runpath.steprule``) against physics written here, and the one rule for a
fork law whichever rig runs it.

* A linear spring and tire on the wheel's mass: the chosen step is on the ladder, gives at least
  ``STEPS_PER_PERIOD`` steps per period 2 pi sqrt(m / k), and the next step up the ladder would not.
* Near the stops and the rim the fine step resolves the hard stop's linear rate where the run
  cannot reach it, and its tangent rate 2 mm deep (with the rim's) where it can; the zones the drop
  refines in are the bumper's start, the top stop and the rim, as configured.
* The rolling front end steps at the drop's fine step; the bike's fork meets the drop's limits for
  the same law and masses, refines in the same stop zone, and at the bike's output rate takes the
  drop's step.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import mtbmj
from mtbmj import compose
from mtbmj.bike import run as bike_run
from mtbmj.bike import spec as spec_mod
from mtbmj.bike import stepping as bike_stepping
from mtbmj.drop.envelope import draws
from mtbmj.rolling import frontend
from mtbmj.runpath import steprule

LADDER = steprule.STEP_LADDER


def period(mass_kg: float, rate_N_per_m: float) -> float:
    """The undamped period (s) of a mass on a spring."""
    return 2.0 * math.pi * math.sqrt(mass_kg / rate_N_per_m)


def tangent_rate(force, x: float, h: float = 1e-7) -> float:
    """dF/dx (N/m) of ``force(x)`` at ``x``, by central differences."""
    return (force(x + h) - force(x - h)) / (2.0 * h)


@pytest.mark.parametrize("integrator, tire_N_per_mm", [("rk4", 450.0), ("implicitfast", 450.0), ("euler", 85.1)])
def test_a_linear_spring_and_tire_get_their_steps_per_period(integrator, tire_N_per_mm):
    # S1: a linear spring (16.47 N/mm) without top-out, the impact tire; the wheel rides between them
    s = compose.setup(mtbmj.load_config("S1", {"solver.integrator": integrator,
                                               "tire.impact_rate_N_per_mm": tire_N_per_mm}))
    assert "steps per period" in steprule.timestep_limit(s)[1]  # the period, not the logger, sets it
    k = (16.47 + tire_N_per_mm) * 1e3
    t = period(2.3, k)
    need = steprule.STEPS_PER_PERIOD[integrator]
    assert s.timestep in LADDER
    assert t / s.timestep >= need
    up = [h for h in LADDER if h > s.timestep]
    assert up and t / min(up) < need  # the largest ladder step that keeps them


def test_a_stop_out_of_reach_is_resolved_at_its_linear_rate():
    s = compose.setup(mtbmj.load_config("S1"))  # 95 mm: the bumper, never the compression stop
    reach = steprule.reachable(s)
    assert reach["bumper"] and not reach["compression_stop"] and not reach["rim"]
    k = 20000e3 + 85.1e3  # the hard stop's linear rate and the tire's (reference.toml)
    assert s.substeps > 1
    assert period(2.3, k) / s.fine_timestep >= steprule.STOP_STEPS_PER_PERIOD["rk4"]
    assert s.fine_timestep in LADDER
    # where the drop refines: the bumper's start, the top stop, the rim (from the configuration)
    compress, extend, rim = steprule.refine_zones(s)[:3]
    assert (compress, extend, rim) == pytest.approx(((120.0 - 8.0) * 1e-3, -5e-3, 48.7e-3), abs=1e-15)


@pytest.mark.parametrize("integrator", ["rk4", "euler"])
def test_a_reachable_stop_and_rim_are_resolved_at_their_tangent_rate(integrator):
    s = compose.setup(mtbmj.load_config("S1", {"sled.drop_height_mm": 800.0, "solver.integrator": integrator}))
    reach = steprule.reachable(s)
    assert reach["compression_stop"] and reach["rim"]
    spring, rim = s.fork.spring, s.tire.rim
    depth = 2e-3  # the deepest a hard landing goes
    k_stop = tangent_rate(lambda x: spring.stop_forces(x, 0.0)[1], spring.travel + depth)
    k_rim = tangent_rate(lambda d: rim.force(d, 0.0), rim.max_deflection + depth)
    assert k_stop > 30.0 * spring.stop_rate  # stiffened: p (1 + (p / p0)^2)'s slope, 34 times
    k = k_stop + k_rim + s.tire.impact.rate  # engaged together, the worst case
    need = steprule.HARD_STOP_STEPS_PER_PERIOD[integrator]
    assert period(s.wheel_mass, k) / s.fine_timestep >= need * (1.0 - 1e-9)
    assert period(s.wheel_mass, k) / s.timestep < need  # the coarse step alone would not do
    assert s.fine_timestep * s.substeps == pytest.approx(s.timestep, rel=1e-12)


def test_every_chosen_step_is_on_the_ladder_and_within_the_limits():
    for name, overrides in [(p, {}) for p in mtbmj.preset_names()] + draws(12, 3):
        s = compose.setup(mtbmj.load_config(name, overrides))
        limits = steprule.limits(s)
        assert s.timestep in LADDER, name
        assert s.timestep <= limits.coarse[0] and s.fine_timestep <= limits.fine[0] * (1.0 + 1e-12), name
        assert 1 <= s.contact_substeps <= s.substeps, name
        assert s.timestep / s.contact_substeps <= limits.contact[0] * (1.0 + 1e-12), name


def test_whole_fractions_and_even_cuts():
    for interval, limit in [(5e-4, 2.2e-5), (5e-4, 5e-4), (5e-4, 1.0), (1e-3, 3e-4), (1 / 300, 1e-3)]:
        k = steprule.cuts_within(interval, limit)
        h = steprule.fraction_within(interval, limit)
        assert h == interval / k and h <= limit * (1.0 + 1e-12)
        assert k == 1 or interval / (k - 1) > limit  # the fewest cuts


@pytest.mark.parametrize("preset", ["S1", "S12"])
def test_the_front_end_steps_coarse_and_at_the_drop_s_fine_step_near_a_stop(preset):
    """The front end's coarse step is the rolling rigs' 0.5 ms (within the limits away from the
    stops: 0.74 ms for S12's friction state, the 1 kHz logger for S1) and its fine step the drop's."""
    drop = compose.setup(mtbmj.load_config(preset))
    p = frontend.prepare("flat", 5.0, config=preset, callback="python")
    assert p.setup.timestep == 5e-4
    assert p.front.model.opt.timestep == 5e-4
    assert steprule.limits(drop).away_from_stops[0] >= 5e-4
    assert p.setup.substeps == 5 and p.setup.fine_timestep == pytest.approx(drop.fine_timestep, rel=1e-12)


def test_reach_span_finds_the_first_run_of_rows_within_reach():
    """Written out by hand: a stop at 10 (values within 1 of it, plus twice the step into or out of a
    row) and a band from 0 to 1."""
    x = np.array([0.0, 2.0, 4.0, 6.0, 6.5, 7.0, 7.0, 7.0, 5.0, 5.0, 5.0, 5.0])
    # the larger step into or out of each row: 2 2 2 2 .5 .5 0 2 2 0 0 0
    # a stop at 10, margin 1: row 3 (6 >= 10 - 1 - 4) alone; rows 4-6 fall short; 7-8 a second run
    assert steprule.reach_span([(x, (-np.inf, 10.0), 1.0)]) == (3, 3)
    # a stop at 7.5, no margin: rows 2 (4 >= 7.5 - 4) to 5 (7 >= 7.5 - 1); row 6 (7 < 7.5) ends it
    assert steprule.reach_span([(x, (-np.inf, 7.5), 0.0)]) == (2, 5)
    assert steprule.reach_span([(x, (-np.inf, 100.0), 1.0)]) is None
    # a band from -1 to 1: row 0 inside, rows 1-2 within their reach of it (2 <= 1 + 4, 4 <= 1 + 4)
    assert steprule.reach_span([(x, (-1.0, 1.0), 0.0, "inside")]) == (0, 2)
    # a band at 4.9-5.1: row 1 (2 >= 4.9 - 4) to row 3 (6 <= 5.1 + 4); row 4 (6.5 > 5.1 + 1) ends it
    assert steprule.reach_span([(x, (4.9, 5.1), 0.0, "inside")]) == (1, 3)
    # two signals: the earlier run wins
    assert steprule.reach_span([(x, (4.9, 5.1), 0.0, "inside"), (x, (-1.0, 1.0), 0.0, "inside")]) == (0, 3)


def test_the_bike_s_fork_meets_the_drop_s_rule():
    """The bike's fork law on the drop sled with the bike's fork masses (unsprung mass as the wheel,
    half the sprung mass as the body) and the bike's output rate: the same limits, the same stop
    zone, the same coarse step; the fine step within the drop's."""
    spec = spec_mod.load("sst")
    fork, shock = bike_run.setups(spec)
    plan = bike_stepping.stepping(spec, fork, shock)
    unsprung = spec.fork_lower_mass + spec.front_wheel_mass
    sprung = spec.total_mass - unsprung - spec.rear_wheel_mass - spec.swingarm_mass
    wheel, body = min(unsprung, spec.rear_wheel_mass), sprung / 2.0
    rate = 1.0 / bike_stepping.COARSE_STEP_S
    drop = compose.setup(fork.config.with_overrides({
        "sled.wheel_mass_kg": wheel, "sled.body_mass_kg": body,
        "solver.sample_rate_Hz": rate, "solver.antialias_Hz": rate / 4.0}))
    on_bike = steprule.limits(dataclasses.replace(fork, wheel_mass=wheel, body_mass=body))
    on_sled = steprule.limits(dataclasses.replace(drop, sample_rate=fork.sample_rate))
    assert on_sled == on_bike
    assert plan.fork_zone == (steprule.refine_zones(drop)[1], steprule.refine_zones(drop)[0])
    assert plan.coarse == drop.timestep == bike_stepping.COARSE_STEP_S
    assert plan.fine <= on_sled.fine[0] * (1.0 + 1e-12)  # the shock's stops may set a finer one


def test_a_bumper_that_does_not_push_is_refined_from_its_start_on_every_rig():
    spec = spec_mod.load("sst")
    quiet = dataclasses.replace(spec, fork_overrides={**spec.fork_overrides, "fork.stops.bumper_force_N": 0.0})
    fork, shock = bike_run.setups(quiet)
    plan = bike_stepping.stepping(quiet, fork, shock)
    compress, extend = steprule.refine_zones(fork)[:2]
    assert plan.fork_zone == (extend, compress) == (-fork.fork.spring.extension, fork.fork.spring.bumper_start)


def test_the_rule_lives_in_one_module():
    for name in ("choose_timestep", "timestep_limit", "fine_limit", "away_from_stops_limit", "STEP_LADDER",
                 "STEPS_PER_PERIOD", "refine_zones", "at_fine_step", "reachable", "stiffest_rates"):
        assert not hasattr(compose, name), name
    assert not hasattr(bike_stepping, "_ladder_step") and not hasattr(bike_stepping, "_zone")
    assert np.all(np.diff(LADDER) < 0)

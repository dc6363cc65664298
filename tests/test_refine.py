"""The drop engine steps coarsely over the working stroke and finely only where a stop, the rim or
a steep velocity band may act (steprule.fine_limit, stepping.stop_index): refined runs equal
runs at the fine step throughout, the scan never lets a step into a stop unrefined, and the ODE
reference resolves a fork resting on its stop at any tolerance."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import mtbmj
from mtbmj import compose
from mtbmj.drop import stepping
from mtbmj.drop.envelope import draws
from mtbmj.drop.run import run_drop
from mtbmj.runpath import steprule


def test_coarse_step_and_substeps_follow_the_rule():
    for preset in ("S1", "S4", "S9", "S12"):
        s = compose.setup(mtbmj.load_config(preset))
        assert s.timestep <= steprule.timestep_limit(s)[0]
        assert s.fine_timestep <= steprule.fine_limit(s)[0]
        assert s.substeps == round(s.timestep / s.fine_timestep) >= 1


@pytest.mark.parametrize("preset,overrides", [
    ("S1", {"sled.drop_height_mm": 300.0, "sled.body_mass_kg": 110.0}),  # bottoms out hard
    ("S4", {"sled.drop_height_mm": 250.0, "tire.impact_rate_N_per_mm": 45.0}),  # rim strikes, direction band
])
def test_refined_run_equals_a_run_at_the_fine_step(preset, overrides):
    """Refinement changes where the step is fine, not the answer: within 0.02 mm of the same
    fork stepped at the fine step everywhere, and it did refine (the stops acted)."""
    coarse = run_drop(preset, overrides=overrides, duration=0.6)
    info = coarse.trace.info
    assert info["substeps"] > 1 and info["steps_refined"] > 0
    assert coarse.summary["hard_stop"]["count"] + coarse.summary["rim_strikes"]["count"] > 0
    fine = run_drop(preset, overrides={**overrides, "solver.timestep_s": info["timestep_s"] / info["substeps"]},
                    duration=0.6)
    assert fine.trace.info["substeps"] == 1
    k = info["substeps"]
    for name in ("sled_mm", "fork_mm", "tire_mm"):
        assert np.max(np.abs(coarse.raw[name] - fine.raw[name][::k])) <= 0.02, name
    ode = run_drop(preset, engine="ode", overrides=overrides, duration=0.6)
    assert max(d["max_abs_mm"] for d in coarse.difference(ode).values()) <= 0.1  # the envelope's bound


ZONES = (0.112, -0.005, 0.0487, 0.0, math.inf)  # bumper start, extension stop, rim, no velocity band or speed
COLUMNS = (0, 1, 2, 3)  # sled, fork, sled velocity, fork velocity


@settings(max_examples=200, deadline=None, derandomize=True, database=None)
@given(x0=st.floats(0.0, 0.11), x1=st.floats(0.0, 0.13), v=st.floats(-3.0, 3.0), tire=st.floats(0.0, 0.06))
def test_scan_flags_every_step_that_reaches_a_zone(x0, x1, v, tire):
    """Any step with an end inside a zone (a stop, the rim, the tire at the ground) is flagged; a
    step far from every zone is not."""
    h = 5e-4
    previous = np.array([x0 + 0.01, x0, v, v])
    state = np.array([x1 + tire, x1, v, v])
    k = stepping.stop_index(previous, state[None, :], COLUMNS, ZONES, h)
    inside = max(x0, x1) >= ZONES[0] or tire >= ZONES[2] or tire == 0.0
    if inside:
        assert k == 0
    margin = h * 2 * abs(v) + stepping.STOP_MARGIN_M
    if max(x0, x1) + margin < ZONES[0] and max(0.01, tire) + margin < ZONES[2] and min(0.01, tire) - margin > 0.0:
        assert k is None


def test_scan_flags_the_velocity_band_and_a_reversal():
    zones = (math.inf, -math.inf, math.inf, 0.06, math.inf)
    rows = np.zeros((4, 4))
    rows[:, 0] = 0.01  # the tire well into contact
    rows[:, 3] = [0.5, 0.45, -0.3, -0.5]  # crosses zero between rows 1 and 2
    assert stepping.stop_index(rows[0], rows[1:], COLUMNS, zones, 1e-4) == 1
    rows[:, 3] = [0.5, 0.45, 0.4, 0.35]
    assert stepping.stop_index(rows[0], rows[1:], COLUMNS, zones, 1e-4) is None


def test_ode_resolves_a_fork_resting_on_its_stop_at_any_tolerance():
    """A heavy rider (103 kg) on a soft fork rests on the compression stop, where the stop's
    force crosses zero back and forth: the reference gives the same run at rtol 1e-8 and 1e-10,
    and MuJoCo agrees with it (this random fork was 0.9 mm off when the stop's kink was located)."""
    table = list(mtbmj.load_config("reference").require("fork.damper.force_N"))
    preset, overrides = draws(7, 7, table)[6]
    loose = run_drop(preset, engine="ode", overrides=overrides, duration=0.8)
    tight = run_drop(preset, engine="ode", overrides={**overrides, "solver.ode_rtol": 1e-10}, duration=0.8)
    # on and off the stop again and again (the reported engagements merge dips under 0.5 mm: count
    # the raw crossings of full travel here)
    from mtbmj.readout.endtravel import episodes

    travel_mm = loose.config["fork.travel_mm"]
    assert len(episodes(loose.raw["fork_mm"], travel_mm, release=0.0)) >= 5
    assert loose.summary["hard_stop"]["count"] >= 1
    assert max(d["max_abs_mm"] for d in loose.difference(tight).values()) <= 0.01
    mj = run_drop(preset, overrides=overrides, duration=0.8)
    assert max(d["max_abs_mm"] for d in mj.difference(tight).values()) <= 0.1


@pytest.mark.parametrize("dt", [1e-3, 5e-4, 1e-4, 2e-5])
def test_logger_filter_is_the_analog_butterworth_at_any_step(dt):
    """A ramp through the logger's filter lags by the analog 4th-order Butterworth's DC group
    delay, sum over its poles of -1/p = 2.6131 / (2 pi f_c), whatever the engine step; and the
    filter passes a constant unchanged."""
    from scipy import signal

    from mtbmj.drop import measure

    cutoff = 400.0
    sos, zi = measure.antialias_filter(cutoff, dt)
    t = np.arange(0.0, 0.05, dt)
    out, _ = signal.sosfilt(sos, t, zi=zi * 0.0)
    poles = signal.butter(4, 2.0 * math.pi * cutoff, analog=True, output="zpk")[1]
    delay = float(np.sum(-1.0 / poles).real)
    assert delay == pytest.approx(2.6131 / (2.0 * math.pi * cutoff), rel=1e-4)
    late = t > 0.02  # transients gone
    assert np.max(np.abs(out[late] - (t[late] - delay))) < 1e-9
    level, _ = signal.sosfilt(sos, np.full(50, 3.0), zi=zi * 3.0)
    assert np.allclose(level, 3.0, atol=1e-12)


def test_logged_record_does_not_depend_on_the_engine_step():
    """S1 logged from a 1 ms and from a 0.05 ms engine trace: the same record, but for what
    joining the 1 ms samples by straight lines misses of the path, h^2 |a| / 8 (a from the fine
    trace), plus the engines' own 0.005 mm."""
    coarse = run_drop("S1", duration=0.6)
    fine = run_drop("S1", overrides={"solver.timestep_s": 5e-5}, duration=0.6)
    h = coarse.trace.info["timestep_s"]
    assert h == 1e-3
    for name, velocity in (("sled_mm", "sled_velocity"), ("fork_mm", "fork_velocity"), ("tire_mm", None)):
        if velocity is None:
            v = fine.trace.sled_velocity - fine.trace.fork_velocity
        else:
            v = getattr(fine.trace, velocity)
        a_max = np.max(np.abs(np.diff(v))) / fine.trace.info["timestep_s"]
        bound = h * h * a_max / 8.0 * 1e3 + 0.005
        assert np.max(np.abs(coarse.signals[name] - fine.signals[name])) <= bound, name


@settings(max_examples=40, deadline=None, derandomize=True, database=None)
@given(rate=st.integers(150, 2500))
def test_the_chosen_step_logs_at_the_rate_asked_for(rate):
    """Any logger rate: the chosen step goes a whole number of times into its sample interval
    (the record is the step grid decimated), within the step rule's limit."""
    s = compose.setup(mtbmj.load_config("S12", {"solver.sample_rate_Hz": float(rate),
                                                 "solver.antialias_Hz": 0.4 * rate}))
    ratio = 1.0 / (rate * s.timestep)
    assert abs(ratio - round(ratio)) <= 1e-6 * ratio and round(ratio) >= 1
    assert s.timestep <= steprule.timestep_limit(s)[0]


def test_an_odd_logger_rate_is_logged_at_that_rate_and_a_step_that_does_not_divide_is_refused():
    run = run_drop("S1", overrides={"solver.sample_rate_Hz": 300.0, "solver.antialias_Hz": 100.0}, duration=0.2)
    assert np.allclose(np.diff(run.signals["time_s"]), 1.0 / 300.0, rtol=1e-9)
    with pytest.raises(mtbmj.ConfigError, match="solver.timestep_s: 0.0003 s does not go a whole number"):
        compose.setup(mtbmj.load_config("S1", {"solver.timestep_s": 3e-4}))


def test_the_tire_switch_lands_within_a_fine_step_of_the_reference():
    """A random S12 fork (envelope seed 1, draw 4) whose tire law switches mid-way through a 1 ms
    step: the engine finds it at the fine step and finishes that step under the new law, so the
    switch time and the run agree with the reference (switched at the coarse step's end, 1 ms
    late, it was 0.74 mm off)."""
    table = list(mtbmj.load_config("reference").require("fork.damper.force_N"))
    preset, overrides = draws(5, 1, table)[4]
    assert preset == "S12"
    mj = run_drop(preset, overrides=overrides, duration=0.5)
    ode = run_drop(preset, engine="ode", overrides=overrides, duration=0.5)
    first = lambda r: r.raw["time_s"][np.argmax(r.trace.tire_phase == 1)]
    assert abs(first(mj) - first(ode)) <= mj.trace.info["timestep_s"]
    assert max(d["max_abs_mm"] for d in mj.difference(ode).values()) <= 0.1


def test_the_energy_bound_never_misses_a_stop_the_run_reaches():
    """steprule.reachable is an upper bound: on random forks, a run that reaches the bumper, the
    compression stop or the rim was told it could; the paper's S12 drop cannot bottom, and a
    110 kg rider dropped 300 mm on S1 can."""
    assert not steprule.reachable(compose.setup(mtbmj.load_config("S12")))["compression_stop"]
    assert steprule.reachable(compose.setup(mtbmj.load_config(
        "S1", {"sled.drop_height_mm": 300.0, "sled.body_mass_kg": 110.0})))["compression_stop"]
    table = list(mtbmj.load_config("reference").require("fork.damper.force_N"))
    reached = 0
    for preset, overrides in draws(10, 5, table):
        cfg = mtbmj.load_config(preset, overrides)
        setup = compose.setup(cfg)
        bound = steprule.reachable(setup)
        run = run_drop(cfg, duration=0.4)
        if run.raw["fork_mm"].max() >= setup.fork.spring.bumper_start * 1e3:
            assert bound["bumper"], (preset, overrides)
            reached += 1
        if run.summary["hard_stop"]["count"]:
            assert bound["compression_stop"], (preset, overrides)
        if run.summary["rim_strikes"]["count"]:
            assert bound["rim"], (preset, overrides)
            reached += 1
    assert reached > 0  # the draws do reach some of them


def _plan(preset="S4"):
    setup = compose.setup(mtbmj.load_config(preset))
    assert setup.substeps > setup.contact_substeps > 1  # S4 can reach its stops: the two levels differ
    return setup, stepping.Stepping(setup, COLUMNS)


def _rows(x, deflection, v):
    rows = np.zeros((len(x), 4))
    rows[:, 1], rows[:, 0], rows[:, 3], rows[:, 2] = x, np.asarray(x) + deflection, v, v
    return rows


def test_touchdown_far_from_the_stops_is_refined_at_the_contact_level():
    """The tire reaching the ground mid-stroke: cut there, and stepped at the other zones' level,
    not at the stops' (a hundred fine steps per millisecond on S4)."""
    setup, plan = _plan()
    rows = _rows(np.full(6, 0.03), np.array([-0.004, -0.003, -0.002, -0.001, 0.0005, 0.002]), 0.0)
    rows[:, 2] = 1.0  # the sled (and wheel) coming down at 1 m/s
    keep, switch, _ = plan.keep(rows[0], rows[1:])
    assert plan.fine and not switch and keep < 5
    assert plan.substeps == plan.contact_level == setup.contact_substeps


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(x0=st.floats(0.0, 0.08), speed=st.floats(0.5, 4.0))
def test_a_stop_coming_within_reach_at_the_contact_level_cuts_and_goes_on_at_the_stops_level(x0, speed):
    """Stepping finely at the contact level, the fork compresses towards its bumper: the chunk is
    kept only up to the last step clear of it, and stepping goes on at the stops' level."""
    setup, plan = _plan()
    plan.fine, plan.substeps = True, plan.contact_level
    h = setup.timestep
    x = x0 + speed * h * np.arange(12)
    rows = _rows(x, 0.01, speed)  # tire well in contact, clear of the rim
    fine = np.repeat(rows[1:], plan.substeps, axis=0)
    keep, switch, _ = plan.keep(rows[0], rows[1:], fine)
    bumper, extension = steprule.refine_zones(setup)[:2]
    margin = 2 * h * speed + stepping.STOP_MARGIN_M  # what one coarse step can cover, and the margin
    reaches = np.flatnonzero((x[1:] + margin > bumper) | (x[:-1] - margin < extension))
    if reaches.size and not switch:
        assert keep == reaches[0] and plan.fine and plan.substeps == plan.stop_level
    elif not switch:
        assert keep == 11 and plan.substeps == plan.contact_level

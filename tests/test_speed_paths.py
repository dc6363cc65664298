"""The fast paths give the reference paths' numbers: forces after a run (compiled and vectorised
against the per-sample Python laws), and the streamed CSV against the one built in memory."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj import compose, config
from mtbmj.drop import measure
from mtbmj.trace import RawTrace


def _python_forces(setup, trace):
    fork_law, tire_law = setup.fork, setup.tire
    x, v, z = trace.fork, trace.fork_velocity, trace.friction_state
    d, dv, ph = trace.tire, trace.tire_velocity, trace.tire_phase
    fork = np.array([fork_law.force(x[i], v[i], z[i]) for i in range(x.size)])
    tire = np.array([tire_law.force(d[i], dv[i], ph[i]) for i in range(d.size)])
    return fork, tire


def _random_trace(rng, n=4000):
    """States a drop visits and beyond: extension past top-out, compression past travel, both
    stroke directions through the damper table's breakpoints, tire in the air and deflected."""
    x = rng.uniform(-0.03, 0.15, n)
    s = x + rng.uniform(-0.02, 0.06, n)
    v = rng.normal(0.0, 1.0, n) * rng.choice([1e-3, 0.05, 1.0], n)
    sv = v + rng.normal(0.0, 1.0, n)
    z = rng.uniform(-1e-4, 1e-4, n)
    return RawTrace("test", np.arange(n) * 1e-4, s, x, sv, v, z, rng.integers(0, 2, n).astype(np.int8))


@pytest.mark.parametrize("name", config.preset_names())
def test_forces_match_python_laws_bit_for_bit(name):
    cfg = config.load(name)
    rng = np.random.default_rng(sum(name.encode()))
    if cfg.get("fork.friction.model", "none") == "none":  # a friction law the presets leave out
        cfg = cfg.with_overrides({"fork.friction.model": "stribeck", "fork.friction.coulomb_N": 20.0,
                                  "fork.friction.breakaway_N": 35.0, "fork.friction.viscous_N_s_per_m": 10.0,
                                  "fork.friction.stribeck_velocity_mm_per_s": 30.0})
    setup = compose.setup(cfg)
    trace = _random_trace(rng)
    fork, tire = measure.forces(setup, trace)
    want_fork, want_tire = _python_forces(setup, trace)
    assert np.array_equal(fork, want_fork)
    assert np.array_equal(tire, want_tire)


def test_streamed_csv_is_the_table_written_at_once(tmp_path):
    """Chunked CSV (several chunks, a last short one) equals np.savetxt of the whole table."""
    import io

    from mtbmj import output

    rng = np.random.default_rng(7)
    columns = {"time_s": np.arange(1001) * 1e-4, "a": rng.normal(size=1001) * 1e3, "b": rng.uniform(-1, 1, 1001)}
    buffer = io.StringIO()
    buffer.write("# one\n# two\ntime_s,a,b\n")
    np.savetxt(buffer, np.column_stack(list(columns.values())), delimiter=",", fmt="%.9g")
    chunks = list(output.csv_chunks(columns, "one\ntwo", rows=300))
    assert len(chunks) == 1 + 4
    assert b"".join(chunks) == buffer.getvalue().encode()
    written = output.write_atomically(tmp_path, {"t.csv": output.csv_chunks(columns, "one\ntwo", rows=300)})
    assert written[0].read_bytes() == buffer.getvalue().encode()


def test_filter_in_chunks_equals_one_pass():
    """The anti-alias filter run chunk by chunk (state carried) gives the one-pass numbers, and
    those are scipy's: the modal filter against ``sosfilt`` of the same analog filter discretised
    by ``cont2discrete`` ("foh"), and its numpy fallback against its compiled kernel."""
    from scipy import signal

    setup = compose.setup(config.load("S12"))
    rng = np.random.default_rng(11)
    n = 3 * measure.FILTER_CHUNK + 17
    raw = {"time_s": np.arange(n) * 1e-4, "x": np.cumsum(rng.normal(size=n))}
    got = measure.logged(setup, raw)
    coefficients = measure.logger_filter(setup.antialias, 1e-4)
    one_pass = measure._filter_modal(coefficients, raw["x"][None, :], raw["x"][0] * coefficients[4][None, :])[0]
    assert np.array_equal(got["x"], one_pass[::10])
    sos, zi = measure.antialias_filter(setup.antialias, 1e-4)
    want, _ = signal.sosfilt(sos, raw["x"], zi=zi * raw["x"][0])
    assert np.max(np.abs(one_pass - want)) <= 1e-11 * np.max(np.abs(want))
    from mtbmj.controllers import compiled

    short = raw["x"][None, :3000]
    fast = measure._filter_modal(coefficients, short, short[:, :1] * coefficients[4][None, :])
    original = compiled.modal_filter
    compiled.modal_filter = lambda *args: False  # the numpy recursion, as without numba
    try:
        slow = measure._filter_modal(coefficients, short, short[:, :1] * coefficients[4][None, :])
    finally:
        compiled.modal_filter = original
    assert np.allclose(fast, slow, rtol=0, atol=1e-12 * np.max(np.abs(short)))


@pytest.mark.parametrize("cutoff,dt", [(400.0, 1e-3), (400.0, 1e-4), (400.0, 2e-5), (100.0, 5e-4), (450.0, 1e-3)])
def test_logger_filter_is_the_foh_butterworth(cutoff, dt):
    """The modal form against scipy's design (butter, cont2discrete "foh", sosfilt) on a random
    walk, at the logger's cutoff and other cutoffs and steps; and it passes a constant unchanged."""
    from scipy import signal

    rng = np.random.default_rng(int(cutoff + 1 / dt))
    u = np.cumsum(rng.normal(size=(2, 4000)), axis=1) + 50.0
    sos, zi = measure.antialias_filter(cutoff, dt)
    want = np.array([signal.sosfilt(sos, x, zi=zi * x[0])[0] for x in u])
    c = measure.logger_filter(cutoff, dt)
    got = measure._filter_modal(c, u, u[:, :1] * c[4][None, :])
    assert np.max(np.abs(got - want)) <= 1e-9 * np.max(np.abs(want))
    level = measure._filter_modal(c, np.full((1, 50), 3.0), 3.0 * c[4][None, :].copy())
    assert np.allclose(level, 3.0, rtol=1e-12)

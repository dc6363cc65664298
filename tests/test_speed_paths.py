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
    """The anti-alias filter run chunk by chunk (state carried) gives the one-pass numbers."""
    from scipy import signal

    setup = compose.setup(config.load("S12"))
    rng = np.random.default_rng(11)
    n = 3 * measure.FILTER_CHUNK + 17
    raw = {"time_s": np.arange(n) * 1e-4, "x": np.cumsum(rng.normal(size=n))}
    got = measure.logged(setup, raw)
    sos, zi = measure.antialias_filter(setup.antialias, 1e-4)
    want, _ = signal.sosfilt(sos, raw["x"], zi=zi * raw["x"][0])
    assert np.array_equal(got["x"], want[::10])
    assert np.array_equal(got["time_s"], raw["time_s"][::10])

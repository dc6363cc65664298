"""Engine traces seen through the sled's instruments.

Conventions (paper, "Test Setup"): sled zero when the tread just touches the ground, fork zero at
unloaded full extension, tire = sled - fork, compression positive, all in mm. The logger samples
at 1 kHz behind a 400 Hz anti-aliasing filter; here the analog 4th-order Butterworth low-pass
(the usual anti-aliasing response) acts on the engine-rate trace, joined by straight lines between
steps, before decimation (:func:`antialias_filter`): what the logger records does not depend on
the engine's step.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from mtbmj.compose import Setup
from mtbmj.controllers import native
from mtbmj.controllers.stops import contact_force
from mtbmj.trace import RawTrace

COLUMNS = (
    "time_s", "sled_mm", "fork_mm", "tire_mm",
    "sled_velocity_mm_per_s", "fork_velocity_mm_per_s", "tire_velocity_mm_per_s",
    "fork_force_N", "tire_force_N",
)


def tire_forces(tire_law, deflection, rate, phase) -> np.ndarray:
    """``TireLaw.force(d, dd/dt, phase)`` along a trace, vectorised (the same arithmetic)."""
    out = np.zeros(deflection.shape)
    touching = deflection > 0.0
    for p in np.unique(phase):
        law = tire_law.values(int(p))
        force = law.rate * deflection
        force += law.damping * rate
        np.maximum(0.0, force, out=force)
        np.copyto(out, force, where=touching & (phase == p))
    rim = tire_law.rim
    if rim is not None:  # Rim.force: past the maximum deflection, pushing only
        at = deflection - rim.max_deflection >= 0.0
        p = deflection[at] - rim.max_deflection
        # through the one stop/rim formula, sample by sample (math.tanh: numpy's may differ in the
        # last bit; rim strikes are few samples)
        force = np.fromiter((contact_force(rim.rate, rim.damping, pi, vi) for pi, vi in zip(p, rate[at])), float, p.size)
        out[at] += np.maximum(0.0, force)
    return out


def forces(setup: Setup, trace: RawTrace, tire=None, tire_velocity=None) -> tuple[np.ndarray, np.ndarray]:
    """Fork force (N, pushing apart) and tire force (N, pushing up) along a trace, from the laws:
    the fork through the compiled kernel when it can run (the Python law otherwise), the tire
    vectorised. Both give the Python laws' numbers bit for bit. ``tire`` and ``tire_velocity``
    (m, m/s), when given, save recomputing them from the trace."""
    x, v, z = trace.fork, trace.fork_velocity, trace.friction_state
    fork = None
    if native.worth(x.size):  # numba already loaded, or a trace long enough to repay loading it
        from mtbmj.controllers import compiled

        fork = compiled.fork_forces_along(setup.fork, x, v, z)
    if fork is None:
        law = setup.fork
        fork = np.fromiter((law.force(x[i], v[i], z[i]) for i in range(x.size)), float, x.size)
    tire = trace.tire if tire is None else tire
    tire_velocity = trace.tire_velocity if tire_velocity is None else tire_velocity
    return fork, tire_forces(setup.tire, tire, tire_velocity, trace.tire_phase)


def engine_signals(setup: Setup, trace: RawTrace) -> dict[str, np.ndarray]:
    """The raw trace in the output columns and units, at the engine rate (scaled in place where
    it can: a long run holds no more engine-rate arrays than it returns)."""
    tire, tire_velocity = trace.tire, trace.tire_velocity
    fork_force, tire_force = forces(setup, trace, tire, tire_velocity)
    tire *= 1e3
    tire_velocity *= 1e3
    return {
        "time_s": trace.time,
        "sled_mm": trace.sled * 1e3,
        "fork_mm": trace.fork * 1e3,
        "tire_mm": tire,
        "sled_velocity_mm_per_s": trace.sled_velocity * 1e3,
        "fork_velocity_mm_per_s": trace.fork_velocity * 1e3,
        "tire_velocity_mm_per_s": tire_velocity,
        "fork_force_N": fork_force,
        "tire_force_N": tire_force,
    }


@lru_cache(maxsize=32)
def antialias_filter(cutoff_Hz: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(sos, zi) of the logger's analog anti-aliasing filter (4th-order Butterworth, ``cutoff_Hz``)
    for samples ``dt`` apart: the analog filter discretised with a first-order hold, i.e. its exact
    response to the samples joined by straight lines (``scipy.signal.cont2discrete``, "foh").
    The bilinear transform (``butter(..., fs=)``) warps the response near the cutoff by an amount
    that depends on ``dt``: on S1's sled it moved the logged record by 0.22 mm between steps of
    0.5 ms and 0.01 ms; this filter, by 0.0005 mm. ``zi`` is the steady state for a unit input.
    Cached (scipy's ``sosfilt`` needs writable arrays, so they are not locked). For callers that
    filter with scipy (the synthetic records); the drop filters with ``logger_filter``, the same
    filter in modal form."""
    from scipy import signal  # ~0.7 s to import: deferred to the first run

    zeros, poles, gain = signal.butter(4, 2.0 * np.pi * cutoff_Hz, analog=True, output="zpk")
    discrete = signal.cont2discrete(signal.zpk2ss(zeros, poles, gain), dt, method="foh")[:4]
    sos = signal.zpk2sos(*signal.ss2zpk(*discrete))
    return sos, signal.sosfilt_zi(sos)  # shared between calls: callers must not write to them


BUTTERWORTH_ORDER = 4


def _hold_integrals(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For x = p dt: (x e^x - e^x + 1, e^x - 1 - x), the integrals of one mode over a step
    against the hold's two ramps, times p x; by their series where |x| is small (no cancellation)."""
    near, far = np.abs(x) < 0.5, np.abs(x) >= 0.5
    old = np.empty_like(x)
    new = np.empty_like(x)
    e = np.expm1(x[far])
    old[far], new[far] = x[far] * (1.0 + e) - e, e - x[far]
    xs = x[near]
    term = xs * xs / 2.0  # x^n / n!, from n = 2
    o, n = term.copy(), term.copy()
    for k in range(3, 30):
        term = term * xs / k
        o += (k - 1) * term
        n += term
    old[near], new[near] = o, n
    return old, new


@lru_cache(maxsize=32)
def logger_filter(cutoff_Hz: float, dt: float) -> tuple[np.ndarray, ...]:
    """The logger's anti-aliasing filter (a 4th-order analog Butterworth at ``cutoff_Hz``) for
    samples ``dt`` apart, in modal form: its response to the samples joined by straight lines (a
    first-order hold), exact. H(s) = sum r_i / (s - p_i) over the Butterworth poles p_i; each mode
    over a step: z' = phi z + g_old u_k + g_new u_(k+1), with phi = e^(p dt) and the hold's
    integrals in closed form. Kept as w = z - g_new u, so that
    y_k = 2 Re sum r (w + g_new u_k) and w <- phi w + (phi g_new + g_old) u_k over the modes in the
    upper half-plane (their conjugates give the conjugate terms). Returns (phi, g_in, g_new, r,
    w_unit), w_unit being the state at rest under a unit input. The same filter as
    ``antialias_filter``'s (``scipy.signal.cont2discrete``, "foh"), without importing
    ``scipy.signal`` (about half a second of every command's start)."""
    n = BUTTERWORTH_ORDER
    k = np.arange(1, n + 1)
    poles = 2.0 * np.pi * cutoff_Hz * np.exp(1j * np.pi * (2 * k + n - 1) / (2 * n))
    gain = np.prod(-poles)  # unit gain at rest
    residues = np.array([gain / np.prod(p - np.delete(poles, i)) for i, p in enumerate(poles)])
    upper = poles.imag > 0
    p, r = poles[upper], residues[upper]
    x = p * dt
    phi = np.exp(x)
    old, new = _hold_integrals(x)
    g_old, g_new = old / (p * x), new / (p * x)
    g_in = phi * g_new + g_old
    w_unit = g_in / (1.0 - phi)
    arrays = (phi, g_in, g_new, r, w_unit)
    for a in arrays:
        a.flags.writeable = False
    return arrays


def _filter_modal(coefficients, u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """y of ``logger_filter`` along ``u`` (signals x samples), ``w`` (signals x modes) updated in
    place: the compiled kernel, or the same recursion in numpy (vectorised over the signals)."""
    phi, g_in, g_new, r, _ = coefficients
    out = np.empty(u.shape)
    if native.worth(u.shape[1]):  # numba already loaded, or enough samples to repay loading it
        from mtbmj.controllers import compiled

        if compiled.modal_filter(phi, g_in, g_new, r, w, u, out):
            return out
    for k in range(u.shape[1]):
        x = u[:, k, None]
        out[:, k] = 2.0 * np.sum((r * (w + g_new * x)).real, axis=1)
        w *= phi
        w += g_in * x
    return out


FILTER_CHUNK = 1 << 16  # samples filtered at a time (the filter state carries over: same numbers)


def logged(setup: Setup, raw: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Anti-alias filter (``logger_filter``) and resample the engine-rate signals to the
    logger's rate."""
    t = raw["time_s"]
    dt = t[1] - t[0]
    ratio = int(round(1.0 / (setup.sample_rate * dt)))
    coefficients = logger_filter(setup.antialias, dt)
    out = {"time_s": t[::ratio].copy()}
    chunk = FILTER_CHUNK - FILTER_CHUNK % ratio  # a multiple of the ratio: every chunk starts on a sample kept
    names = [name for name in raw if name != "time_s"]
    # Start the filter at rest on the first values, as a logger running before t = 0; all
    # signals at once, the state carried from chunk to chunk.
    state = np.array([raw[name][0] for name in names])[:, None] * coefficients[4][None, :]
    kept = []
    for start in range(0, t.size, chunk):
        block = np.array([raw[name][start: start + chunk] for name in names], dtype=float)
        kept.append(_filter_modal(coefficients, block, state)[:, ::ratio])
    joined = np.concatenate(kept, axis=1)
    for k, name in enumerate(names):
        out[name] = joined[k]
    return out

"""``stepping.stop_index`` compiled (numba): the first row of a chunk of recorded states that
comes within reach of a stop, the rim, the tire's touchdown or lift-off, the band around rest or
the friction state's speed limit. The same comparisons on the same doubles as the numpy
definition in ``stepping``, one row at a time, stopping at the first row found.

The MuJoCo engines ask this of every chunk they step, about 50 chunks per S12 drop, most of them
ten rows long: numpy's calls cost 1.4 ms of a sweep variant's 50 ms more than this does
(interleaved rounds of 48 variants), which answers in about 1.5 µs. Imported only where numba is already loaded
(``stepping._compiled``); ``tests/test_stepping_compiled.py`` checks it against the numpy one.
"""
from __future__ import annotations

import math

from mtbmj.controllers import jit


@jit.kernel(inline=True)
def _minimum(a, b):
    """np.minimum of two doubles (NaN if either is)."""
    if a != a or b != b:
        return a + b
    return a if a <= b else b


@jit.kernel(inline=True)
def _maximum(a, b):
    """np.maximum of two doubles (NaN if either is)."""
    if a != a or b != b:
        return a + b
    return a if a >= b else b


@jit.kernel
def first_near(previous, states, sled, fork, sled_v, fork_v, compress, extend, rim, band, fast, step, margin,
               stops_only):
    """``stepping.stop_index`` for ``previous`` (a state row) and ``states`` (rows): the index
    of the first step near a zone, or -1."""
    px, pv = previous[fork], previous[fork_v]
    pd, pw = previous[sled] - px, previous[sled_v] - pv
    for i in range(states.shape[0]):
        x, v = states[i, fork], states[i, fork_v]
        d, w = states[i, sled] - x, states[i, sled_v] - v
        reach = step * (abs(pv) + abs(v) + abs(v - pv)) + margin
        x_low, x_high = _minimum(px, x) - reach, _maximum(px, x) + reach
        reach = step * (abs(pw) + abs(w) + abs(w - pw)) + margin
        d_low, d_high = _minimum(pd, d) - reach, _maximum(pd, d) + reach
        near = x_high > compress or x_low < extend or d_high > rim
        if not stops_only:
            near = near or (d_low < 0.0 and d_high > 0.0)
            if band > 0.0:
                slowest = 0.0 if pv * v <= 0.0 else _minimum(abs(pv), abs(v)) - abs(v - pv)
                near = near or slowest < band
            if fast < math.inf:
                near = near or _maximum(abs(pv), abs(v)) + abs(v - pv) > fast
        if near:
            return i
        px, pv, pd, pw = x, v, d, w
    return -1

"""How a MuJoCo drop follows the step rule (``mtbmj.runpath.steprule``): where a run may take the
coarse step and where it steps finely, and how long each ``mujoco.rollout`` chunk is. ``Stepping``
holds one run's decisions; the single-run engine (``engine_mujoco.run``) and the batched engine
(``engine_batch``) both follow it, so a batched variant is stepped exactly as a single run.

The coarse step is ``Setup.timestep`` (``steprule.timestep_limit`` over the working stroke); finer
steps per output step only where ``stop_index`` finds an end stop, the rim, the tire at the
ground, the steep band around rest or a stroke faster than the friction state allows within
reach (``steprule.refine_zones``): ``Setup.substeps`` (the limits of ``steprule.fine_limit``) near
a stop or the rim, ``Setup.contact_substeps`` in the other zones. Chunks are cut before such a
step, where a stop comes within reach of a stretch at the second level, and at the tire-law switch
(``switch_index``, the rule of ``controllers.tire.SWITCH_RULE``).
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.compose import Setup
from mtbmj.runpath import steprule

SWITCH_CHUNK_S = 0.1  # simulated time per rollout while a tire-law switch is pending (the most recomputed)
CHUNK_S = 2.0  # simulated time per rollout otherwise (each call costs setup time; progress per chunk)


def switch_index(previous, states, columns) -> int | None:
    """The tire-law switch (``controllers.tire.SWITCH_RULE``) in a chunk of recorded states: the
    index of the first state at which the tire has left the ground (deflection <= 0 after > 0) or
    the fork has turned from extension back into compression (velocity >= 0 after < 0), or None.
    ``previous`` is the state before the chunk; ``columns`` are the sled and fork position and the
    fork velocity columns of a state row."""
    sled, fork, fork_velocity = columns
    deflection = np.concatenate(([previous[sled] - previous[fork]], states[:, sled] - states[:, fork]))
    v = np.concatenate(([previous[fork_velocity]], states[:, fork_velocity]))
    found = np.flatnonzero(((deflection[:-1] > 0.0) & (deflection[1:] <= 0.0)) | ((v[:-1] < 0.0) & (v[1:] >= 0.0)))
    return int(found[0]) if found.size else None


STOP_MARGIN_M = steprule.STOP_MARGIN_M  # see stop_index
REFINED_CHUNK_S = 0.01  # simulated time per rollout at the fine step
AFTER_REFINED_CHUNK_S = 0.01  # the first coarse rollout after one: doubled while none is cut


def stop_index(previous, states, columns, zones, step: float, stops_only: bool = False) -> int | None:
    """The index of the first step of a chunk of recorded states that a stop or the rim may have
    acted in, or in which the tire may have touched down or lifted off (see ``STOP_MARGIN_M``),
    or None; with ``stops_only``, of a stop or the rim only. ``columns`` are the sled and fork
    position and velocity columns of a state row; ``zones`` as ``steprule.refine_zones``."""
    compiled = _compiled()
    if (compiled is not None and previous.dtype == np.float64 and states.dtype == np.float64 and states.ndim == 2
            and previous.flags.c_contiguous and states.flags.c_contiguous):
        k = compiled(previous, states, *columns, *zones, step, STOP_MARGIN_M, stops_only)
        return None if k < 0 else int(k)
    return stop_index_numpy(previous, states, columns, zones, step, stops_only)


def stop_index_numpy(previous, states, columns, zones, step: float, stops_only: bool = False) -> int | None:
    """``stop_index``'s definition in numpy (what runs where numba is not loaded)."""
    sled, fork, sled_v, fork_v = columns
    compress, extend, rim, band, fast = zones
    rows = np.concatenate((previous[None, :], states))
    x, v = rows[:, fork], rows[:, fork_v]
    d, w = rows[:, sled] - x, rows[:, sled_v] - v

    def reach(value, rate):
        a, b = value[:-1], value[1:]
        ra, rb = np.abs(rate[:-1]), np.abs(rate[1:])
        margin = step * (ra + rb + np.abs(rate[1:] - rate[:-1])) + STOP_MARGIN_M
        return np.minimum(a, b) - margin, np.maximum(a, b) + margin

    x_low, x_high = reach(x, v)
    d_low, d_high = reach(d, w)
    near = (x_high > compress) | (x_low < extend) | (d_high > rim)  # a stop or the rim
    if stops_only:
        found = np.flatnonzero(near)
        return int(found[0]) if found.size else None
    near |= (d_low < 0.0) & (d_high > 0.0)  # the tire touching down or lifting off (its damping force jumps)
    if band > 0.0:  # the stroke velocity comes within the band of zero (or crosses it)
        a, b = v[:-1], v[1:]
        slowest = np.where(a * b <= 0.0, 0.0, np.minimum(np.abs(a), np.abs(b)) - np.abs(b - a))
        near |= slowest < band
    if fast < math.inf:  # the stroke speed may pass the friction state's limit within the step
        a, b = np.abs(v[:-1]), np.abs(v[1:])
        near |= np.maximum(a, b) + np.abs(v[1:] - v[:-1]) > fast
    found = np.flatnonzero(near)
    return int(found[0]) if found.size else None


_COMPILED: list = []  # the compiled stop_index, once numba is in the process


def _compiled():
    """``stepping_compiled.first_near`` where numba is already loaded (``controllers.native``),
    else None: ``stop_index_numpy`` answers, with the same numbers (a short drop that never
    loads numba does not load it for this)."""
    if _COMPILED:
        return _COMPILED[0]
    from mtbmj.controllers import native

    if not native.loaded():
        return None
    from mtbmj.controllers import jit
    from mtbmj.drop import stepping_compiled

    with jit.compiling("the step rule", stepping_compiled.first_near):
        stepping_compiled.first_near(np.zeros(4), np.zeros((1, 4)), 0, 1, 2, 3, 1.0, -1.0, 1.0, 0.0, math.inf,
                                     1e-3, STOP_MARGIN_M, False)
    _COMPILED.append(stepping_compiled.first_near)
    return _COMPILED[0]


class Stepping:
    """The stepping decisions of one drop run, shared by ``engine_mujoco.run`` and the batched
    engine (``engine_batch``):
    how many output steps the next rollout makes and at which step (:meth:`size`, ``fine``),
    and, from what it returned, how many to keep and what comes next (:meth:`keep`).

    ``columns`` are the sled and fork position and velocity columns of a recorded state row.
    Chunks are sized in simulated time; at the coarse step they start short after a refined
    stretch (a cut discards the rest of a chunk) and double while none is cut. ``computed`` and
    ``refined`` count the MuJoCo steps and the refined output steps of the rollouts handed to
    :meth:`keep` (a caller adds the fine steps that finish a switch's output step).
    """

    def __init__(self, setup: Setup, columns):
        h = setup.timestep
        self.setup = setup
        # fine steps per output step: near a stop or the rim, and in the other zones
        self.stop_level = setup.substeps
        self.contact_level = min(setup.contact_substeps or setup.substeps, setup.substeps)
        self.substeps = self.stop_level  # the level of the next fine rollout
        self.stop_columns = tuple(columns)
        sled, fork, _, fork_v = self.stop_columns
        self.switch_columns = (sled, fork, fork_v)
        self.zones = steprule.refine_zones(setup)
        self.chunk = max(1, int(round(CHUNK_S / h)))
        self.switch_chunk = max(1, int(round(SWITCH_CHUNK_S / h)))
        self.refined_chunk = max(1, int(round(REFINED_CHUNK_S / h)))
        self.after_refined = min(self.chunk, max(1, int(round(AFTER_REFINED_CHUNK_S / h))))
        self.coarse_chunk = self.after_refined if self.stop_level > 1 else self.chunk
        self.fine = False
        self.phase = 0
        self.computed = 0  # MuJoCo steps made (fine ones each counted), discarded ones included
        self.refined = 0  # output steps made at a fine step

    @property
    def pending(self) -> bool:
        """The tire-law switch is still to come."""
        return self.setup.tire.switches and self.phase == 0

    def size(self, remaining: int) -> int:
        """Output steps for the next rollout (at ``setup.timestep / substeps`` if ``fine``)."""
        if self.fine:
            return min(self.refined_chunk, remaining)
        return min(min(self.switch_chunk, self.coarse_chunk) if self.pending else self.coarse_chunk, remaining)

    def _level(self, before, step) -> int:
        """The fine level for output step ``step`` (a one-row array) from state ``before``: the
        stops' where a stop or the rim may act in it, else the other zones'."""
        near = stop_index(before, step, self.stop_columns, self.zones, self.setup.timestep, stops_only=True)
        return self.stop_level if near is not None else self.contact_level

    def keep(self, previous, states, fine_states=None) -> tuple[int, bool, tuple | None]:
        """(how many of ``states``, recorded from ``previous``, to keep; whether the tire law
        switches after them; ``None``, or (i, m) when it switches inside the next output step:
        after fine state ``fine_states[i]``, with ``m`` fine steps left to finish that output
        step under the new law), and the mode of the next rollout.

        At the fine step ``fine_states`` are all the states the output ``states`` were taken
        from (at ``substeps`` per output step, the level this rollout was made at), and the
        switch is made at the fine step it falls in. At a coarse step that may hold the switch,
        the chunk is cut before that step and stepped finely: the switch lands within a fine
        step, as the reference's event does (1 ms late, it moved a random S12 fork 0.7 mm).
        Stepped finely at the other zones' level, a chunk is cut where a stop or the rim comes
        within reach, and goes on at the stops' level."""
        n = len(states)
        level = self.substeps
        self.computed += n if fine_states is None else len(fine_states)
        self.refined += 0 if fine_states is None else n
        keep, switch, partial = n, False, None
        if self.stop_level > 1 and not self.fine:
            k = stop_index(previous, states, self.stop_columns, self.zones, self.setup.timestep)
            if k is not None:
                keep = k
        elif self.fine and level < self.stop_level:
            k = stop_index(previous, states, self.stop_columns, self.zones, self.setup.timestep, stops_only=True)
            if k is not None:
                keep = k
        if self.pending and keep:
            if fine_states is not None:
                k = switch_index(previous, fine_states[: keep * level], self.switch_columns)
                if k is not None:
                    whole, part = divmod(k + 1, level)
                    keep, switch = whole, True
                    if part:
                        partial = (k, level - part)
            else:
                k = switch_index(previous, states[:keep], self.switch_columns)
                if k is not None and self.stop_level > 1:
                    keep = k  # refine the step that holds it
                elif k is not None:
                    keep, switch = k + 1, True
        if switch and self.fine:
            pass  # stays fine for one more chunk: the exit is judged on whole output steps
        elif self.fine and keep < n:  # a stop came within reach: on at the stops' level
            self.substeps = self.stop_level
        elif self.fine:  # back to the coarse step once the last step is clear of every zone
            before = previous if keep == 1 else states[keep - 2]
            self.fine = stop_index(before, states[keep - 1: keep], self.stop_columns, self.zones,
                                   self.setup.timestep) is not None
            if self.fine:
                self.substeps = self._level(before, states[keep - 1: keep])
            self.coarse_chunk = self.after_refined
        elif keep < n and not switch:
            self.fine = True
            self.substeps = self._level(previous if keep == 0 else states[keep - 1], states[keep: keep + 1])
        elif keep == n:
            self.coarse_chunk = min(self.chunk, 2 * self.coarse_chunk)
        if switch:
            self.phase = 1
        return keep, switch, partial

"""The chunked rollout every rig steps MuJoCo with.

:func:`chunked` steps a model from its current state in chunks through ``mujoco.rollout`` (the loop
and the recording stay in C++; the rig's control callback supplies its forces), reads MuJoCo's
warnings and checks the states after every chunk (``mtbmj.runpath.guard``), and reports progress.
It returns the states, one row more than steps (row 0 the start), and the sensors, one row per
step: **row i of the sensors describes row i of the states**, the state at the start of step i
(MuJoCo evaluates the sensors in the forward pass of a step, before it integrates; with RK4 the
intermediate stages skip the sensors).

A rig that needs a finer step where an end stop or a rim may act gives a :class:`Refinement`: after
each chunk stepped at the coarse step it names the first and the last row within reach of a stop;
the coarse rows before the row ahead of the first are kept, the stretch from there to one row
past the last (at least ``min_steps`` rows) is stepped again ``substeps`` times finer, and of those
fine steps every ``substeps``-th state is kept with the sensors of the fine step that starts at the
same instant (the state of the coarse grid's own time stamp), so the output stays on the coarse
grid. After a fine stretch chunks start at ``min_steps`` and double while no stop is within reach.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import mujoco
import numpy as np
from mujoco import rollout

from mtbmj.runpath import guard

CHUNK = 10000  # steps per chunk where no refinement is planned


class Refinement(Protocol):
    substeps: int  # fine steps per coarse step where a stop may act (1: never)
    min_steps: int  # a fine stretch covers at least this many coarse steps
    max_chunk: int  # coarse steps per chunk

    def span(self, states: np.ndarray, sensors: np.ndarray) -> tuple[int, int] | None:
        """The first and the last row of a coarse chunk within reach of a stop, or None."""

    def before_fine(self) -> None:
        """Called before a fine stretch (e.g. the callback's contact search made afresh)."""


@dataclass
class Counts:
    """What a run stepped: coarse output steps made, of which ``refined`` at the fine step."""

    stepped: int = 0
    refined: int = 0


def chunked(model, data, steps: int, timestep: float, rig: str, refine: Refinement | None = None,
            progress: Callable[[float], None] | None = None, counts: Counts | None = None,
            chunk: int = CHUNK, report_every: int = CHUNK):
    """(states (steps + 1, nstate), sensors (steps, nsensordata)) of ``steps`` steps of ``timestep``
    from ``data``'s current state (see the module doc). Ends the run with one ``RunError`` line
    (``rig`` named) on a MuJoCo warning, a non-finite state or a state MuJoCo reset; MuJoCo's warning
    text never reaches the terminal or MUJOCO_LOG.TXT."""
    counts = Counts() if counts is None else counts
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    states = np.empty((steps + 1, state.size))
    sensors = np.empty((steps, model.nsensordata))
    states[0] = state
    k = 1 if refine is None else refine.substeps
    size = chunk if k == 1 else refine.max_chunk
    done = 0
    last_report = 0
    messages: list[str] = []
    with guard.collected_warnings(messages):
        while done < steps:
            n = min(size, steps - done)
            start = states[done]
            st, se = rollout.rollout(model, data, start[None, :], nstep=n)
            st, se = st[0], se[0]
            if k > 1:
                clean = guard.steps_clean(start, st)
                span = refine.span(st, se) if clean else (0, n - 1)  # diverged coarse: the whole chunk fine
                if span is not None:
                    keep = max(span[0] - 1, 0)  # coarse rows kept: those before the row ahead of the first
                    if guard.first_warning(data) is not None or messages:
                        # a warning of the coarse pass: which step raised it is not known, so no coarse
                        # row is kept and the whole stretch is stepped again fine (a warning there ends the run)
                        guard.clear_warnings(data, messages)
                        keep = 0
                    n = min(n, max(span[1] + 2, keep + refine.min_steps))  # fine to one past the last; the rest anew
                    origin = start if keep == 0 else st[keep - 1]
                    refine.before_fine()
                    model.opt.timestep = timestep / k
                    try:
                        fs, fe = rollout.rollout(model, data, origin[None, :], nstep=(n - keep) * k)
                    finally:
                        model.opt.timestep = timestep
                    st, se = st[:n], se[:n]
                    fine_ok = guard.steps_clean(origin, fs[0])
                    st[keep:] = fs[0, k - 1::k]  # the state at the end of each coarse step ...
                    se[keep:] = fe[0, ::k]  # ... and the sensors of the state at its start (row i with state i)
                    if fine_ok:
                        st[:, 0] = start[0] + timestep * np.arange(1, n + 1)  # the coarse grid's times
                        data.time = st[-1, 0]
                    counts.refined += n - keep
                    size = refine.min_steps  # near a stop: short coarse chunks, doubling while clear
                else:
                    size = min(2 * size, refine.max_chunk)
            guard.check(rig, data, messages, start, st, start[0] + n * timestep, model=model)
            counts.stepped += n
            states[done + 1: done + 1 + n] = st
            sensors[done: done + n] = se
            done += n
            if progress is not None and (done - last_report >= report_every or done == steps):
                last_report = done
                progress(done / steps)
    return states, sensors

"""The chunked rollout every rig steps MuJoCo with.

:func:`stepped` steps a model from its current state in chunks through ``mujoco.rollout`` (the
loop and the recording stay in C++; the rig's control callback supplies its forces), reads
MuJoCo's warnings and checks the states after every chunk (``mtbmj.runpath.guard``), reports
progress and hands each stretch of output rows to the rig's ``sink``. **Row i of the sensors
describes row i of the states**, the state at the start of output step i (MuJoCo evaluates the
sensors in the forward pass of a step, before it integrates; with RK4 the intermediate stages
skip the sensors); state row i + 1 is the state at the end of that step.

Where a rig needs a finer step (an end stop, a rim, a tire-law switch) a :class:`Plan` decides,
chunk by chunk, how many output steps the next rollout makes and at how many substeps each
(``size``, ``fine``, ``substeps``), and from what it returned how many rows to keep (``keep``):
the rest is stepped again from the last row kept. Two plans ride on this one interface:

- **cut before a stop** (the drop, ``mtbmj.drop.stepping.Stepping``): a coarse chunk is cut
  before the first step that may reach a stop, and stepping goes on finely until clear; a
  tire-law switch is made between two fine steps (``Plan.switched``), and an output step the
  switch fell inside is finished under the new law (``keep``'s third value);
- **redo after the fact** (the rolling front end and the bike; :class:`AfterTheFact` over a :class:`Refinement`): a chunk
  stepped coarse is looked at after the fact, its rows before the one ahead of the first row
  within reach of a stop are kept, and the stretch from there to one row past the last (at least
  ``min_steps`` rows) is stepped again ``substeps`` times finer; after a fine stretch chunks start
  at ``min_steps`` and double while no stop is within reach.

Of a fine rollout every ``substeps``-th state is kept with the sensors of the fine step that starts
at the same instant, so the output stays on the coarse grid; a :class:`Refinement` with
``fine_rows`` (the rolling front end) keeps every fine state instead, so a fine stretch's output
is at the fine step (a square edge's force rise is seen step by step, not in one coarse row):
the rows' times are then not evenly spaced, and :func:`chunked` says which rows lie on the
coarse grid (its ``grid`` mask), the rows every coarse-grid consumer (the logger) reads.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable, Protocol

import mujoco
import numpy as np
from mujoco import rollout

from mtbmj import errors
from mtbmj.runpath import guard, steprule

CHUNK = 10000  # steps per chunk where no refinement is planned
REFINE_CHUNK = 1024  # coarse steps per chunk an after-the-fact plan looks at
FINE_MIN_STEPS = 32  # a stretch stepped fine covers at least this many coarse steps


def skip_collision(model) -> None:
    """Skip MuJoCo's collision pass in ``model`` when none of its geoms can collide (every
    ``contype`` and ``conaffinity`` 0: the rolling rigs, whose tires push through their callbacks).
    No contact could be found, so the steps are the same; the pass is a fifth of a front-end step."""
    if not np.any(model.geom_contype | model.geom_conaffinity):
        model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT


# Passive forces a model may have, each an array of its (or a count): all zero, MuJoCo's passive stage
# computes nothing but zeros and may be skipped (``passive_skipped``)
PASSIVE = ("jnt_stiffness", "jnt_stiffnesspoly", "dof_damping", "dof_dampingpoly", "tendon_stiffness",
           "tendon_stiffnesspoly", "tendon_damping", "tendon_dampingpoly", "actuator_damping", "actuator_dampingpoly",
           "body_gravcomp", "ngravcomp", "nflex")


def has_passive(model) -> bool:
    """Whether MuJoCo's passive stage has anything to compute in ``model`` now: an array of ``PASSIVE``
    not all zero, a fluid (``opt.density``, ``opt.viscosity``) or an ``mjcb_passive`` installed."""
    return (any(np.any(getattr(model, name, 0)) for name in PASSIVE) or bool(model.opt.density)
            or bool(model.opt.viscosity) or mujoco.get_mjcb_passive() is not None)


@contextmanager
def passive_skipped(model):
    """MuJoCo's passive stage skipped (``mjDSBL_SPRING | mjDSBL_DAMPER``) for the block where ``model``
    has nothing for it (:func:`has_passive`, judged when the block starts: a spring given to the model
    after it was built, as the seated replay gives the saddle, pushes); the flags put back after. The
    stage would write only zeros, so the steps are the same to the bit (``tests/test_runpath_levers.py``);
    it was ~2 % of a bike step."""
    if has_passive(model):
        yield
        return
    saved = model.opt.disableflags
    model.opt.disableflags = saved | int(mujoco.mjtDisableBit.mjDSBL_SPRING) | int(mujoco.mjtDisableBit.mjDSBL_DAMPER)
    try:
        yield
    finally:
        model.opt.disableflags = saved


@lru_cache(maxsize=1)
def _time_hook():
    """The ctypes cell of MuJoCo's global ``mjcb_time`` in the library the ``mujoco`` package loaded
    (None where it is not found: then nothing is changed)."""
    import ctypes
    import glob
    import os

    here = os.path.dirname(mujoco.__file__)
    for pattern in ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll"):
        for path in sorted(glob.glob(os.path.join(here, pattern))):
            try:
                return ctypes.c_void_p.in_dll(ctypes.CDLL(path), "mjcb_time")
            except (OSError, ValueError):
                continue
    return None


@contextmanager
def untimed():
    """MuJoCo's timers off for the block: the ``mujoco`` package installs a clock as ``mjcb_time``
    (``set_mjcb_time(None)`` does not remove it), and MuJoCo then reads the clock twice around each
    of its stages, every evaluation, to fill ``mjData.timer``, which nothing here reads: 15 % of a
    bike step (``benchmarks/bike_step_levers.py``). The clock is put back after the block; the
    physics does not read it (the states are the same to the bit, ``tests/test_runpath_levers.py``)."""
    hook = _time_hook()
    if hook is None:
        yield
        return
    saved = hook.value
    hook.value = None
    try:
        yield
    finally:
        hook.value = saved


class Plan(Protocol):
    fine: bool  # the next rollout is made at ``substeps`` fine steps per output step
    substeps: int  # fine steps per output step of the next fine rollout

    def size(self, remaining: int) -> int:
        """Output steps of the next rollout (at most ``remaining``)."""

    def keep(self, previous, states, fine_states=None, sensors=None, warned: bool = False
             ) -> tuple[int, bool, tuple[int, int] | None]:
        """(rows of ``states`` (stepped from ``previous``) to keep; whether to call ``switched``
        after them; None, or (i, m): finish the next output step with ``m`` fine steps from
        ``fine_states[i]``). ``warned``: MuJoCo warned during the rollout."""

    def switched(self) -> None:
        """Re-parameterise the model between two steps (the drop's tire law)."""


@dataclass(frozen=True)
class Watch:
    """One signal a :class:`Refinement` watches, one value per coarse row: column ``column`` of the
    states (``source`` "state": time, qpos, qvel, ...) or of the sensors ("sensor"), mapped by ``of``
    where the signal is not the column itself (the bike's shock stroke from its swingarm angle);
    ``zone`` (low, high) with stops at or below ``low`` and at or above ``high``, or with ``inside``
    a band from ``low`` to ``high`` (a tire's fast-changing force); ``margin`` the reach added
    (``steprule.reach_span``)."""

    source: str
    column: int
    zone: tuple[float, float]
    margin: float
    inside: bool = False
    of: Callable | None = None

    def signal(self, states: np.ndarray, sensors: np.ndarray):
        x = (states if self.source == "state" else sensors)[:, self.column]
        x = x if self.of is None else self.of(x)
        return (x, self.zone, self.margin, "inside") if self.inside else (x, self.zone, self.margin)


@dataclass
class Refinement:
    """A rig's refinement for the "redo after the fact" plan, the one object the rolling front end
    and the bike both hand :func:`chunked`: the signals it watches (:class:`Watch`), the fine steps
    per coarse step where one is within reach (``substeps``; 1: never), what to do before a fine
    stretch (``before``: the callbacks' contact search made afresh), a fine stretch's minimum
    length and the coarse chunk looked at (``min_steps``, ``max_chunk``), and whether every fine
    state of a fine stretch is an output row (``fine_rows``: the front end's square-edge rise seen
    step by step)."""

    substeps: int
    watches: tuple[Watch, ...]
    before: Callable[[], None] = lambda: None
    min_steps: int = FINE_MIN_STEPS
    max_chunk: int = REFINE_CHUNK
    fine_rows: bool = False

    def span(self, states: np.ndarray, sensors: np.ndarray) -> tuple[int, int] | None:
        """The first and the last row of a coarse chunk within reach of a watched stop or band
        (``steprule.reach_span``), or None."""
        return steprule.reach_span([w.signal(states, sensors) for w in self.watches])

    def before_fine(self) -> None:
        self.before()


@dataclass
class Counts:
    """What a run stepped: coarse output steps made, of which ``refined`` at the fine step."""

    stepped: int = 0
    refined: int = 0


class Coarse:
    """The plan of a rig that steps at one step throughout: chunks of ``chunk`` steps, all kept."""

    fine = False
    substeps = 1

    def __init__(self, chunk: int = CHUNK):
        self.chunk = chunk

    def size(self, remaining: int) -> int:
        return min(self.chunk, remaining)

    def keep(self, previous, states, fine_states=None, sensors=None, warned=False):
        return len(states), False, None

    def switched(self) -> None:
        pass


class AfterTheFact:
    """The "redo after the fact" plan over a rig's :class:`Refinement` (see the module doc): a
    coarse chunk is looked at after it is stepped; a fine stretch's states carry the coarse grid's
    time stamps (``timestep`` apart from the stretch's origin)."""

    def __init__(self, refine: Refinement, timestep: float, data, counts: Counts):
        self.refine, self.timestep, self.data, self.counts = refine, timestep, data, counts
        self.substeps = refine.substeps
        self.fine = False
        self.next = refine.max_chunk
        self.stretch = 0
        self.fine_rows = refine.fine_rows

    def size(self, remaining: int) -> int:
        if self.fine:
            self.refine.before_fine()
            return min(self.stretch, remaining)
        return min(self.next, remaining)

    def keep(self, previous, states, fine_states=None, sensors=None, warned=False):
        n = len(states)
        r = self.refine
        if self.fine:
            self.fine = False
            self.next = r.min_steps  # near a stop: short coarse chunks, doubling while clear
            self.counts.refined += n
            if guard.steps_clean(previous, fine_states):
                states[:, 0] = previous[0] + self.timestep * np.arange(1, n + 1)  # the coarse grid's times
                if self.fine_rows:  # the same times where a fine row is on the coarse grid
                    fine_states[:, 0] = previous[0] + self.timestep * (np.arange(1, len(fine_states) + 1) / self.substeps)
                self.data.time = states[-1, 0]
            return n, False, None
        clean = guard.steps_clean(previous, states)
        span = r.span(states, sensors) if clean else (0, n - 1)  # diverged coarse: the whole chunk fine
        if span is None:
            self.next = min(2 * self.next, r.max_chunk)
            return n, False, None
        # coarse rows kept: those before the row ahead of the first; after a warning of the coarse
        # pass (which step raised it is not known) none, and the whole stretch is stepped again fine
        keep = 0 if warned else max(span[0] - 1, 0)
        end = min(n, max(span[1] + 2, keep + r.min_steps))  # fine to one past the last; the rest anew
        self.fine, self.stretch = True, end - keep
        return keep, False, None

    def switched(self) -> None:
        pass


def roll(model, data, start, n: int, level: int, nstep: int | None = None, fine: bool = True,
         all_sensors: bool = False):
    """(every ``level``-th state, the sensors of the fine steps starting on the output grid, all
    the states, or None where not ``fine``) of ``n`` output steps (or ``nstep`` fine steps) from
    ``start`` (one state) at ``level`` fine steps each (the model's step is restored after); with
    ``all_sensors`` a fourth item, the sensors of every fine step."""
    if not fine:
        st, se = rollout.rollout(model, data, start[None, :], nstep=n)
        return (st[0], se[0], None, None) if all_sensors else (st[0], se[0], None)
    step = model.opt.timestep
    model.opt.timestep = step / level
    try:
        fs, fe = rollout.rollout(model, data, start[None, :], nstep=n * level if nstep is None else nstep)
    finally:
        model.opt.timestep = step
    if all_sensors:
        return fs[0, level - 1::level], fe[0, ::level], fs[0], fe[0]
    return fs[0, level - 1::level], fe[0, ::level], fs[0]


class Stopped(Exception):
    """Raised inside :func:`stepped` when the rig's ``stop`` ended the run early."""


def stepped(model, data, steps: int, timestep: float, rig: str, plan: Plan,
            sink: Callable[..., None],
            progress: Callable[[float], None] | None = None, report_every: int = 0,
            limit: tuple[slice, float, str] | None = None,
            stop: Callable[[int, np.ndarray, np.ndarray], int | None] | None = None) -> int:
    """Step ``steps`` output steps of ``timestep`` from ``data``'s current state under ``plan``,
    handing each stretch of kept rows to ``sink(first_step, states, sensors)`` (states row j: the
    state at the end of output step first_step + j; sensors row j: at its start). Ends the run with
    one ``RunError`` line (``rig`` named) on a MuJoCo warning, a non-finite state, a state MuJoCo
    reset, a numpy overflow or invalid value while stepping (``mtbmj.errors.diverging``: the only
    place a MuJoCo rig's run turns such a value into an error), or a state whose ``limit`` columns
    (columns, bound, what) pass the bound; MuJoCo's
    warning text never reaches the terminal or MUJOCO_LOG.TXT. ``progress(fraction)`` is called
    when ``report_every`` more steps are done (0: after every chunk) and at the end.

    ``stop(first_step, states, sensors)`` (the rig's end of the run, e.g. the bike's crash) sees each
    stretch's finite rows before they are checked; where it names a row j, the rows up to j are
    kept and the run ends there: what MuJoCo did after that row (a warning, a divergence) is past
    the end and not judged. Returns the output steps made.

    Under a plan with ``fine_rows``, a fine stretch hands every fine row to
    ``sink(first_step, states, sensors, fine=True)`` (``first_step`` still counts output steps)."""
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    t0 = state[0]
    done = last_report = 0
    messages: list[str] = []

    def accept(start, rows, sensor_rows, fine=False):
        at = t0 + (done + len(rows)) * timestep if not fine else rows[-1, 0]
        if stop is not None:
            if fine:
                raise ValueError("a plan with fine_rows cannot be stopped by a rig's stop")
            bad = np.flatnonzero(~np.all(np.isfinite(rows), axis=1))
            end = stop(done, rows[:int(bad[0]) if bad.size else len(rows)],
                       sensor_rows[:int(bad[0]) if bad.size else len(rows)])
            if end is not None:
                rows, sensor_rows = rows[:end + 1], sensor_rows[:end + 1]
                guard.clear_warnings(data, messages)  # what MuJoCo met after the end is not judged
                if not guard.steps_clean(start, rows):
                    raise guard.diverged(rig, at, "MuJoCo reset the state after an instability")
                sink(done, rows, sensor_rows)
                raise Stopped(done + len(rows))
        guard.check(rig, data, messages, start, rows, at, model=model)
        if limit is not None and np.max(np.abs(rows[:, limit[0]])) > limit[1]:
            raise guard.diverged(rig, at, limit[2])
        if fine:
            sink(done, rows, sensor_rows, fine=True)
        else:
            sink(done, rows, sensor_rows)

    n = 0
    # numpy's overflow, division by zero and invalid value are divergence while the run steps (a
    # callback's force law, a plan's look at the states): one line naming the rig and the stretch
    with guard.collected_warnings(messages), errors.diverging(rig, lambda: t0 + (done + max(n, 1)) * timestep), \
            untimed(), passive_skipped(model):
        try:
            while done < steps:
                n = plan.size(steps - done)
                level = plan.substeps if plan.fine else 1
                every_row = plan.fine and getattr(plan, "fine_rows", False)
                states, sensors, fine_states, *fine_sensors = roll(model, data, state, n, level, fine=plan.fine,
                                                                   all_sensors=every_row)
                warned = bool(messages) or guard.first_warning(data) is not None
                keep, switch, partial = plan.keep(state, states, fine_states, sensors, warned)
                if keep < n and warned and guard.steps_clean(state, states[:keep]):
                    guard.clear_warnings(data, messages)  # the warning came from steps past the cut, thrown away
                if keep and every_row and keep == n and partial is None:
                    accept(state, fine_states, fine_sensors[0], fine=True)
                    state = states[keep - 1].copy()
                    done += keep
                elif keep:
                    accept(state, states[:keep], sensors[:keep])
                    state = states[keep - 1].copy()
                    done += keep
                if switch:
                    plan.switched()
                if partial is not None:  # the switch fell inside an output step: finish it under the new law
                    at, left = partial
                    _, _, rest = roll(model, data, fine_states[at], 0, level, nstep=left)
                    accept(fine_states[at], rest[-1:], sensors[keep: keep + 1])
                    state = rest[-1].copy()
                    done += 1
                if progress is not None and (done - last_report >= report_every or done == steps):
                    last_report = done
                    progress(done / steps)
        except Stopped as end:
            return end.args[0]
    return done


def chunked(model, data, steps: int, timestep: float, rig: str, refine: Refinement | None = None,
            progress: Callable[[float], None] | None = None, counts: Counts | None = None,
            chunk: int = CHUNK, report_every: int = CHUNK, stop=None, grid: list | None = None):
    """(states (steps + 1, nstate), sensors (steps, nsensordata)) of ``steps`` steps of ``timestep``
    from ``data``'s current state, row 0 of the states the start (see the module doc), on
    :func:`stepped` with the :class:`Coarse` plan, or :class:`AfterTheFact` over ``refine``; where
    ``stop`` (see :func:`stepped`) ended the run early, the rows up to its end.

    Where ``refine`` has ``fine_rows``, a fine stretch's every fine step is a row (more rows than
    ``steps``); ``grid`` (a list) then receives the boolean mask of the sensor rows that lie on the
    coarse grid (``steps`` of them: the rows the run would have without ``fine_rows``)."""
    counts = Counts() if counts is None else counts
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    plan = Coarse(chunk) if refine is None or refine.substeps == 1 else AfterTheFact(refine, timestep, data, counts)
    if getattr(plan, "fine_rows", False):
        return _chunked_rows(model, data, steps, timestep, rig, plan, progress, counts, report_every, stop, grid)
    states = np.empty((steps + 1, mujoco.mj_stateSize(model, kind)))
    mujoco.mj_getState(model, data, states[0], kind)
    sensors = np.empty((steps, model.nsensordata))

    def sink(first, rows, sensor_rows):
        states[first + 1: first + 1 + len(rows)] = rows
        sensors[first: first + len(rows)] = sensor_rows
        counts.stepped += len(rows)

    made = stepped(model, data, steps, timestep, rig, plan, sink, progress, report_every, stop=stop)
    if grid is not None:
        grid.append(np.ones(made, dtype=bool))
    return states[:made + 1], sensors[:made]


def _chunked_rows(model, data, steps, timestep, rig, plan, progress, counts, report_every, stop, grid):
    """:func:`chunked` where a fine stretch keeps its every fine row: the stretches gathered as they
    come (their number is not known ahead), with each sensor row's place on the coarse grid."""
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    start = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, start, kind)
    state_blocks, sensor_blocks, on_grid = [start[None, :]], [], []

    def sink(first, rows, sensor_rows, fine=False):
        state_blocks.append(rows.copy())
        sensor_blocks.append(sensor_rows.copy())
        mask = np.ones(len(rows), dtype=bool)
        if fine:  # sensor row k starts fine step k: on the coarse grid every substeps-th from the first
            mask[:] = False
            mask[::plan.substeps] = True
        on_grid.append(mask)
        counts.stepped += int(mask.sum())

    stepped(model, data, steps, timestep, rig, plan, sink, progress, report_every, stop=stop)
    sensors = np.concatenate(sensor_blocks) if sensor_blocks else np.empty((0, model.nsensordata))
    mask = np.concatenate(on_grid) if on_grid else np.empty(0, dtype=bool)
    if grid is not None:
        grid.append(mask)
    return np.concatenate(state_blocks), sensors

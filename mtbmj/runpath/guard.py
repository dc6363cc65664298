"""MuJoCo's warnings and the divergence checks of every rig's run.

By default MuJoCo prints each warning to the terminal and appends it to ``MUJOCO_LOG.TXT`` in the
working directory; during a run :func:`collected_warnings` routes the text into a list instead,
and :func:`check` turns the first warning, a non-finite state, a state MuJoCo reset after an
instability or a runaway displacement into one ``RunError`` line naming the rig, the time and the
likely cause.
"""
from __future__ import annotations

from contextlib import contextmanager

import mujoco
import numpy as np

from mtbmj.errors import RunError

# What each MuJoCo warning most likely means in these models (the force laws are the only source
# of control values; the contacts and laws the only stiff elements).
_CAUSES = {
    # a stock fork too: ``mtbmj roll step_up:height_mm=300 --speed 15`` drives it through its hard stop in a step
    "BADCTRL": "a force law gave a non-finite or huge force (an impact through the end stops harder than the step "
               "resolves, a feature that tall at that speed? or a rate, damping or preload far beyond any bike's?)",
    "BADQACC": "the accelerations blew up (a stiffness or damping too large for the step, or a value far beyond "
               "any bike's?)",
    "BADQVEL": "the velocities blew up (a stiffness or damping too large for the step?)",
    "BADQPOS": "the positions blew up (a stiffness or damping too large for the step?)",
    "CONTACTFULL": "more contacts than MuJoCo's buffer holds",
    "CNSTRFULL": "more constraints than MuJoCo's buffer holds",
}


def first_warning(data) -> str | None:
    """The name of the first MuJoCo warning raised on ``data`` (``"BADQACC"``, ...) or None."""
    raised = np.flatnonzero(data.warning.number)  # one array read (iterating the structs costs 0.1 ms)
    return mujoco.mjtWarning(int(raised[0])).name.removeprefix("mjWARN_") if raised.size else None


def clear_warnings(data, messages: list) -> None:
    data.warning.number[:] = 0
    messages.clear()


def steps_clean(start, states) -> bool:
    """True if no step of ``states`` (recorded from ``start``) was reset by MuJoCo after an
    instability: their times (the first column) rise steadily from the start's."""
    times = np.concatenate(([start[0]], states[:, 0]))
    return bool(np.all(np.isfinite(states)) and np.all(np.diff(times) > 0.0))


@contextmanager
def collected_warnings(messages: list):
    """Route MuJoCo's warning text into ``messages`` for the run (by default MuJoCo prints it
    and appends it to MUJOCO_LOG.TXT in the working directory); restore the handler after."""
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


def likely_cause(warning: str | None, text: str | None = None, model=None) -> str:
    """A short phrase for MuJoCo warning ``warning``; its text, where given, names the element
    (by its name in ``model`` where one is given)."""
    import re

    cause = _CAUSES.get(warning or "", "MuJoCo found the simulation unstable")
    tag = f"MuJoCo {warning}" if warning else "MuJoCo"
    found = re.search(r"in (\w+) at (ACTUATOR|DOF) (\d+)", text or "")
    if found is None:
        return f"{cause} [{tag}]"
    value, kind, index = found.group(1), found.group(2), int(found.group(3))
    name = None
    if model is not None:
        try:
            if kind == "ACTUATOR" and index < model.nu:
                name = model.actuator(index).name
            elif kind == "DOF" and index < model.nv:
                name = model.joint(int(model.dof_jntid[index])).name
        except (IndexError, KeyError):
            name = None
    element = f"{kind.lower()} {name!r}" if name else f"{kind.lower()} {index}"
    return f"{cause} [{tag}: non-finite or huge {value} at {element}]"


def warned_cause(data, messages: list, model=None) -> str | None:
    """``likely_cause`` of the first MuJoCo warning raised on ``data`` or collected in ``messages``
    (``collected_warnings``), or None where MuJoCo raised none: a state it reset stays finite, so
    this, not the values, says a run blew up."""
    warning = first_warning(data)
    if warning is None and not messages:
        return None
    return likely_cause(warning, messages[0] if messages else None, model)


def diverged(rig: str, t: float, cause: str) -> RunError:
    """The one-line error for a run of ``rig`` that left the model's envelope before ``t`` s."""
    return RunError(f"{rig} run diverged before t = {t:.4f} s: {cause}")


def check(rig: str, data, messages: list, start, states, t: float, model=None) -> None:
    """Raise one ``RunError`` line if the chunk ``states`` stepped from ``start`` (ending at ``t`` s)
    raised a MuJoCo warning, holds a non-finite value, or was reset by MuJoCo."""
    cause = warned_cause(data, messages, model)
    if cause is not None:
        raise diverged(rig, t, cause)
    if not np.all(np.isfinite(states)):
        raise diverged(rig, t, "the state is not finite")
    if not steps_clean(start, states):
        raise diverged(rig, t, "MuJoCo reset the state after an instability")


def prepared(rig: str, make, data_of=lambda p: p.data, model_of=None):
    """``make()`` (a rig's preparation: its scene built, its start state settled) with MuJoCo's
    warnings collected; a warning there ends the run in one line naming the rig, at t = 0."""
    messages: list[str] = []
    with collected_warnings(messages):
        p = make()
    cause = warned_cause(data_of(p), messages, model_of(p) if model_of is not None else None)
    if cause is not None:
        raise diverged(rig, 0.0, "at the start: " + cause)
    return p

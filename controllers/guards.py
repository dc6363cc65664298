"""The guard protocol shared by the force laws.

A piecewise law exposes ``n_guards`` smooth functions ``guards(x, v)`` whose signs select its
branch, and accepts ``sides`` (one boolean per guard, True for guard >= 0) to freeze the branch:
the ODE reference integrates with every branch frozen and stops at each guard's root, so no step
crosses a kink or a jump. With ``sides=None`` the branch follows the state (the MuJoCo callback).
"""
from __future__ import annotations


def on_positive_side(value: float, sides, index: int) -> bool:
    """True when guard ``index`` is on its non-negative side: frozen if ``sides`` is given (an
    entry None is live: a guard the reference has released, see ``mtbmj.drop.engine_ode``), else live."""
    if sides is None or sides[index] is None:
        return value >= 0.0
    return sides[index]


LIVE = -1  # a guard flag: the branch follows the state


def flag(sides, index: int) -> int:
    """Guard ``index``'s frozen side as the law functions take it: 1 (non-negative side), 0
    (negative side) or ``LIVE`` (-1: decided by the guard's value)."""
    if sides is None:
        return LIVE
    s = sides[index]
    return LIVE if s is None else (1 if s else 0)


def side(value: float, frozen: int) -> bool:
    """``on_positive_side`` for the plain law functions (which numba compiles too): the guard's
    own sign when ``frozen`` is ``LIVE``, else the frozen side."""
    if frozen < 0:
        return value >= 0.0
    return frozen == 1


class SmoothLaw:
    """A law with a single smooth branch: no guards."""

    n_guards = 0
    has_state = False

    def guards(self, x, v):
        return ()

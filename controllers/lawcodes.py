"""The compiled laws' registration: each law class's code, and a ``ForkLaw`` flattened into the
integer and float rows the kernels (``controllers.kernels``) read.

Plain Python, no numba. A law's numbers go into the float row in its layout's order
(``controllers.layout``, derived from the dataclass), and the kernels read them back by name; the
integer row says which law sits where: the spring tree (Linear, Bilinear, Progressive, Air,
Directional, TopOut, EndStops, nested at will) as a short postfix program of (code, offset) pairs,
the damper (Linear, Bilinear, Digressive, Orifice, Table) and the friction law (NoFriction, Coulomb,
CoulombViscous, Stiction, Stribeck, LuGre, and Sticking around a static law) one code each.
Registering a law: a code below, its class in the matching table, a branch in the kernel.
"""
from __future__ import annotations

import numpy as np

from mtbmj.controllers import damper as _damper
from mtbmj.controllers import friction as _friction
from mtbmj.controllers import spring as _spring
from mtbmj.controllers import stops as _stops
from mtbmj.controllers.fork import ForkLaw
from mtbmj.controllers.layout import values

SP_LINEAR, SP_BILINEAR, SP_PROGRESSIVE, SP_DIRECTIONAL, SP_TOPOUT, SP_STOPS, SP_AIR = 1, 2, 3, 4, 5, 6, 7
DA_LINEAR, DA_BILINEAR, DA_TABLE, DA_DIGRESSIVE, DA_ORIFICE = 1, 2, 3, 4, 5
FR_NONE, FR_COULOMB, FR_COULOMB_VISCOUS, FR_STICTION, FR_STRIBECK, FR_LUGRE = 0, 1, 2, 3, 4, 5
FR_STICKING = 6  # Sticking around one of the static laws: I_FRICTION_INNER holds that law's code

# the law classes by code; a spring that wraps another (Directional, TopOut, EndStops) says how below
SPRINGS = {_spring.LinearSpring: SP_LINEAR, _spring.BilinearSpring: SP_BILINEAR,
           _spring.ProgressiveSpring: SP_PROGRESSIVE, _spring.AirSpring: SP_AIR,
           _spring.DirectionalSpring: SP_DIRECTIONAL, _spring.TopOutSpring: SP_TOPOUT, _stops.EndStops: SP_STOPS}
WRAPPED = {_spring.DirectionalSpring: ("compression", "rebound"), _spring.TopOutSpring: ("main",),
           _stops.EndStops: ("main",)}  # the springs each one combines, evaluated first, in this order
DAMPERS = {_damper.LinearDamper: DA_LINEAR, _damper.BilinearDamper: DA_BILINEAR,
           _damper.DigressiveDamper: DA_DIGRESSIVE, _damper.OrificeDamper: DA_ORIFICE}
# (TableDamper: a row of its own length, flattened below)
FRICTIONS = {_friction.NoFriction: FR_NONE, _friction.Coulomb: FR_COULOMB,
             _friction.CoulombViscous: FR_COULOMB_VISCOUS, _friction.Stiction: FR_STICTION,
             _friction.Stribeck: FR_STRIBECK, _friction.LuGre: FR_LUGRE}
STICKING_INNER = (_friction.Coulomb, _friction.CoulombViscous, _friction.Stiction, _friction.Stribeck)

# the integer row of a slot
I_MODEL, I_QPOS, I_DOF, I_STATE, I_ACT, I_CTRL, I_COUNT, I_CALLS = 0, 1, 2, 3, 4, 5, 6, 7
I_DAMPER, I_DAMPER_AT, I_DAMPER_N, I_FRICTION, I_FRICTION_AT, I_NSPRING = 8, 9, 10, 11, 12, 13
I_SPRING = 14  # then (opcode, parameter offset) pairs
MAX_SPRING_OPS = 24
I_FRICTION_INNER = I_SPRING + 2 * MAX_SPRING_OPS  # 62
I_RIM, I_RIM_AT, I_SLED_QPOS, I_SLED_DOF = 63, 64, 65, 66  # the rim strike (drop scene only)
I_FLOOR, I_FLOOR_AT = 67, 68  # the soft contact's correction (drop scene only; controllers.tire.ContactFloor)
I_FRICTION_INNER_AT = 69  # where a Sticking law's inner law starts
INT_WIDTH = 70
FLOAT_WIDTH = 1024
STACK_DEPTH = 16


class UnsupportedLaw(TypeError):
    """A law this module cannot compile (the Python path still runs it)."""


def flatten(law: ForkLaw) -> tuple[list[int], list[float]]:
    """(integer row, float row) of ``law``, without the slot header (model, indices, counters)."""
    ints = [0] * INT_WIDTH
    floats: list[float] = []

    def put(part) -> int:
        at = len(floats)
        floats.extend(values(part))
        return at

    program: list[tuple[int, int]] = []
    depth = [0, 0]  # current, maximum

    def spring(s):
        # Exact types only: a subclass may override force() and must run on the Python path.
        kind = type(s)
        if kind not in SPRINGS:
            raise UnsupportedLaw(f"spring law {kind.__name__} has no compiled form")
        wrapped = WRAPPED.get(kind, ())
        for name in wrapped:
            spring(getattr(s, name))
        program.append((SPRINGS[kind], put(s)))
        depth[0] += 1 - len(wrapped)  # a wrapper pops what it combines and pushes its result
        depth[1] = max(depth[1], depth[0])

    if type(law) is not ForkLaw:
        raise UnsupportedLaw(f"{type(law).__name__} is not a ForkLaw")
    spring(law.spring)
    if len(program) > MAX_SPRING_OPS or depth[1] > STACK_DEPTH:
        raise UnsupportedLaw("spring law too deeply composed to compile")
    ints[I_NSPRING] = len(program)
    for k, (op, at) in enumerate(program):
        ints[I_SPRING + 2 * k] = op
        ints[I_SPRING + 2 * k + 1] = at

    d = law.damper
    kind = type(d)
    if kind in DAMPERS:
        ints[I_DAMPER], ints[I_DAMPER_AT] = DAMPERS[kind], put(d)
    elif kind is _damper.TableDamper:  # velocity[n], force[n], slopes[n - 1]
        n = len(d.velocity)
        ints[I_DAMPER], ints[I_DAMPER_N] = DA_TABLE, n
        ints[I_DAMPER_AT] = len(floats)
        floats.extend(float(a) for a in (*d.velocity, *d.force_table, *d.slopes))
    else:
        raise UnsupportedLaw(f"damper law {kind.__name__} has no compiled form")

    f = law.friction
    kind = type(f)
    if kind is _friction.Sticking:
        inner = type(f.inner)
        if inner not in STICKING_INNER:
            raise UnsupportedLaw(f"friction law Sticking({inner.__name__}) has no compiled form")
        ints[I_FRICTION], ints[I_FRICTION_INNER] = FR_STICKING, FRICTIONS[inner]
        ints[I_FRICTION_AT] = put(f)
        ints[I_FRICTION_INNER_AT] = put(f.inner)
    elif kind in FRICTIONS:
        ints[I_FRICTION] = FRICTIONS[kind]
        ints[I_FRICTION_AT] = put(f)
    else:
        raise UnsupportedLaw(f"friction law {kind.__name__} has no compiled form")
    if len(floats) > FLOAT_WIDTH:
        raise UnsupportedLaw(f"law needs {len(floats)} parameters, more than {FLOAT_WIDTH}")
    ints[I_STATE] = int(bool(law.has_state))
    return ints, floats


def law_arrays(law: ForkLaw) -> tuple[np.ndarray, np.ndarray]:
    """``flatten(law)`` as the (int64, float64) arrays the kernels take (``fork_force(I, P, ...)``)."""
    ints, floats = flatten(law)
    P = np.zeros(FLOAT_WIDTH)
    P[: len(floats)] = floats
    return np.asarray(ints, dtype=np.int64), P


__all__ = ["flatten", "law_arrays", "UnsupportedLaw", "INT_WIDTH", "FLOAT_WIDTH", "STACK_DEPTH"]

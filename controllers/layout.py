"""Parameter layouts: where each of a law's numbers sits in the float row the compiled kernels read.

A law is a frozen dataclass; its layout is derived from it, never kept by hand: the dataclass's
number fields in the order they are declared (fields holding another law are skipped: the kernels
read those laws from rows of their own), then the names in the class's ``derived`` tuple (values
the formula needs that the law computes from its fields once, e.g. an air spring's absolute
pressure). ``offsets(cls)`` gives a named tuple of offsets, so a kernel reads a parameter by name,
``P[o + BILINEAR.knee]``; ``values(law)`` gives the numbers in the same order for the row. A field
added to a law moves the offsets of the fields after it in both places at once.

Plain Python, no numba: the row is built on the Python side (``controllers.lawcodes.flatten``).
"""
from __future__ import annotations

import collections
import dataclasses
import functools
import numbers
import typing


@functools.lru_cache(maxsize=None)
def params(cls) -> tuple[str, ...]:
    """The names of ``cls``'s parameters in row order: its number fields, then ``cls.derived``."""
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"{cls.__name__} is not a dataclass: it has no derived layout")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls) if hints.get(f.name) in (float, int)]
    names += list(getattr(cls, "derived", ()))
    if len(set(names)) != len(names):
        raise TypeError(f"{cls.__name__}'s layout names a parameter twice: {names}")
    return tuple(names)


@functools.lru_cache(maxsize=None)
def offsets(cls):
    """A named tuple of the offsets of ``cls``'s parameters within its part of the row."""
    names = params(cls)
    return collections.namedtuple(f"{cls.__name__}Layout", names)(*range(len(names)))


def width(cls) -> int:
    """How many floats ``cls`` takes in the row."""
    return len(params(cls))


def values(law) -> list[float]:
    """``law``'s parameters in its layout's order, as floats."""
    out = []
    for name in params(type(law)):
        value = getattr(law, name)
        if not isinstance(value, numbers.Real):
            raise TypeError(f"{type(law).__name__}.{name} is not a number: {value!r}")
        out.append(float(value))
    return out


__all__ = ["params", "offsets", "width", "values"]

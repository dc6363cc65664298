"""The one face every rig shows the rest of the package, and the registry that lists the rigs.

A rig (the drop, the rolling front end, the whole bike) is a :class:`Rig`: the word its refusals
name it by, the command that runs it, the callback kinds it takes, its presets, and three callables
with one signature for every rig: ``prepare(preset, **case)`` (what a run steps from: the drop's
configuration and setup; the front end's and the bike's scene, callback and initial state),
``run(preset, **case)`` (a ``mtbmj.result.RunOutput``: its columns, summary, files, figure,
``to_csv``, ``difference``) and ``crosscheck(preset, **case)`` (a
:class:`mtbmj.runpath.crosscheck.CrosscheckResult` against the rig's ODE reference). How each steps
near a stop is the run path's (``mtbmj.runpath.loop``: the drop's "cut before a stop" plan, the
front end's and the bike's :class:`~mtbmj.runpath.loop.Refinement`). ``case`` is the
rig's own keywords (a terrain and a speed, a duration); ``example`` is a short case over a feature
that every rig's run and cross-check take as written, so code that walks the rigs (the every-rig
test, a benchmark) holds no branch per rig.

The registry (:class:`Registry`) is filled on the package's face (``mtbmj.rigs``), the one floor
that sees every rig; this module imports none.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterator, Mapping, Sequence


@dataclass(frozen=True)
class Rig:
    """One rig's face (see the module doc)."""

    name: str  # the word a refusal names the rig by ("drop", "rolling", "bike")
    command: str  # the command that runs it (``mtbmj drop``, ``mtbmj roll``, ``mtbmj bike``)
    presets: Callable[[], Sequence[str]]
    prepare: Callable[..., object]
    run: Callable[..., object]
    crosscheck: Callable[..., object]
    example: Mapping[str, object] = field(default_factory=dict)
    callbacks: tuple[str, ...] = ("auto", "compiled", "python")


class Registry:
    """The rigs by name, in the order registered."""

    def __init__(self) -> None:
        self._rigs: dict[str, Rig] = {}

    def register(self, rig: Rig) -> Rig:
        if rig.name in self._rigs:
            raise ValueError(f"a rig named {rig.name!r} is registered already")
        self._rigs[rig.name] = rig
        return rig

    def __getitem__(self, name: str) -> Rig:
        try:
            return self._rigs[name]
        except KeyError:
            raise KeyError(f"no rig named {name!r} (known: {', '.join(self._rigs)})") from None

    def __iter__(self) -> Iterator[Rig]:
        return iter(self._rigs.values())

    def __len__(self) -> int:
        return len(self._rigs)

    def names(self) -> list[str]:
        return list(self._rigs)


__all__ = ["Rig", "Registry"]

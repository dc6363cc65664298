"""The registry of the rigs (``mtbmj.runpath.rig``), on the package's face, the floor that sees
every rig: ``RIGS`` lists the drop, the rolling front end and the whole bike, in that order.

    >>> from mtbmj.rigs import RIGS
    >>> [rig.name for rig in RIGS]
    ['drop', 'rolling', 'bike']
    >>> RIGS["bike"].command
    'bike'
"""
from __future__ import annotations

from mtbmj.bike.rig import RIG as BIKE
from mtbmj.drop.rig import RIG as DROP
from mtbmj.rolling.rig import RIG as ROLLING
from mtbmj.runpath.rig import Registry

RIGS = Registry()
for _rig in (DROP, ROLLING, BIKE):
    RIGS.register(_rig)

__all__ = ["RIGS"]

"""Validation against sled records: a configuration's drop beside a record, the paper's Fig. 10 way
(installed as ``mtbmj.validation``). The engine against the ODE reference is the drop's own
(``mtbmj.drop.crosscheck``), still named here."""
from mtbmj.drop.crosscheck import DEFAULT_TOLERANCE_MM, crosscheck, crosscheck_all, from_results

__all__ = ["crosscheck", "crosscheck_all", "from_results", "DEFAULT_TOLERANCE_MM"]

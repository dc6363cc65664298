"""Validation: MuJoCo runs lined up against the ODE reference (installed as ``mtbmj.validation``)."""
from mtbmj.drop.crosscheck import DEFAULT_TOLERANCE_MM, crosscheck, crosscheck_all, from_results

__all__ = ["crosscheck", "crosscheck_all", "from_results", "DEFAULT_TOLERANCE_MM"]

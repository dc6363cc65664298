"""Validation: MuJoCo runs lined up against the ODE reference (installed as ``mtbmj.validation``)."""
from mtbmj.validation.compare import DEFAULT_TOLERANCE_MM, crosscheck, crosscheck_all, from_results

__all__ = ["crosscheck", "crosscheck_all", "from_results", "DEFAULT_TOLERANCE_MM"]

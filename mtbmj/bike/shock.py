"""A shock as riders buy it: a bike file's ``[shock]`` keys in the shock's own units, turned into the
keys of the shock's configuration (the fork schema read in shock coordinates, ``[shock.set]``).

A coil shock is sold by its spring's rate in lb/in and set by its preload collar; an air shock by its
air can's pressure, with volume spacers in its positive chamber. So ``[shock]`` takes:

* ``spring = "coil"`` with ``spring_rate_lb_per_in`` (or ``spring_rate_N_per_mm``) and
  ``preload_mm`` (the collar's turns of compression on the spring; 0 without): fork.spring.model
  "linear", its rate, and a preload of rate x preload_mm carried by the top-out spring;
* ``spring = "air"`` with ``pressure_psi``, ``piston_diameter_mm`` (the air can's bore),
  ``positive_volume_cm3`` (the positive chamber at full extension, no spacer),
  ``negative_volume_cm3`` (0: none), ``volume_spacers`` and ``spacer_volume_cm3``: fork.spring.model
  "air" and its keys (``controllers.spring.AirSpring``; polytropic index 1.3 unless
  ``[shock.set]`` gives one);
* ``compression_N_s_per_m`` and ``rebound_N_s_per_m``: a bilinear damper at the shaft.

1 lb/in = 0.175126835 N/mm (0.45359237 kg x 9.80665 m/s^2 per 25.4 mm). A key given here replaces the
same setting in that file's ``[shock.set]`` and its bases'; with ``spring`` given, the other kind's
spring keys are dropped there (a coil's rate means nothing to an air can). They are applied file by
file as the bases are merged (``mtbmj.bike.spec.read_table``), so a file built on this one, and a
``--shock-set`` (``mtbmj sag`` and ``advise`` write their changes so), change the setting again
through ``[shock.set]``; a ``--set shock.KEY=VALUE`` is applied as one more file. The resulting keys
go through the shock configuration's own checks.
"""
from __future__ import annotations

import contextlib
import math
import warnings

from mtbmj.config import N_PER_MM_PER_LB_PER_IN  # the units' one table
from mtbmj.errors import ConfigError, ConfigWarning

POLYTROPIC_INDEX = 1.3  # assumed, as the air fork preset: between isothermal (1.0) and adiabatic (1.4) for a 0.1-0.3 s stroke
COIL = ("spring_rate_lb_per_in", "spring_rate_N_per_mm", "preload_mm")
AIR = ("pressure_psi", "piston_diameter_mm", "positive_volume_cm3", "negative_volume_cm3", "volume_spacers",
       "spacer_volume_cm3")
DAMPER = ("compression_N_s_per_m", "rebound_N_s_per_m")
KEYS = ("spring",) + COIL + AIR + DAMPER
# the spring keys of each kind in the fork schema (dropped from [shock.set] when the other kind is chosen)
_COIL_SCHEMA = ("fork.spring.rate_N_per_mm", "fork.spring.rate_lb_per_in", "fork.spring.preload_N",
                "fork.spring.preload", "fork.spring.progressive_rate_N_per_mm", "fork.spring.progressive_cubic_N_per_mm3")
# an air can's keys it cannot do without, and the shock configuration's keys they set
_AIR_NEEDED = (("pressure_psi", "fork.spring.air_pressure_psi"), ("piston_diameter_mm", "fork.spring.piston_diameter_mm"),
               ("positive_volume_cm3", "fork.spring.air_volume_cm3"))
_AIR_SCHEMA = ("fork.spring.air_pressure_psi", "fork.spring.air_pressure_bar", "fork.spring.piston_diameter_mm",
               "fork.spring.air_volume_cm3", "fork.spring.tokens", "fork.spring.token_volume_cm3",
               "fork.spring.negative_volume_cm3", "fork.spring.transfer_port_mm", "fork.spring.polytropic_index")


def _value(part: dict, key: str, low: float = 0.0, strict: bool = True) -> float:
    v = part[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or \
            (v <= low if strict else v < low):
        raise ConfigError(f"shock.{key}: must be a number {'above' if strict else 'at least'} {low:g}, got {v!r}")
    return float(v)


def schema_keys(part: dict, given: dict, kind: str | None = None) -> dict:
    """The shock configuration's keys (``[shock.set]``) from the ``[shock]`` keys of one file (or one
    ``--set``) ``part`` over the ``[shock.set]`` ``given`` so far (its bases' and its own): ``given``
    with those keys applied (see the module doc). ``kind``: the spring its bases named, when
    ``part`` does not; else the kind is read from ``given``'s spring model."""
    mine = {k: part[k] for k in KEYS if k in part}
    if not mine:
        return dict(given)
    if not isinstance(given, dict):
        raise ConfigError("shock.set: must be a table of configuration keys")
    out = dict(given)
    kind = mine.get("spring", kind)
    if kind is None:
        kind = {"linear": "coil", "air": "air"}.get(given.get("fork.spring.model"))
    coil = [k for k in COIL if k in mine]
    air = [k for k in AIR if k in mine]
    if kind is None and (coil or air):
        raise ConfigError(f"shock.{(coil + air)[0]}: give the kind of spring with shock.spring = \"coil\" or \"air\"")
    if kind is not None and kind not in ("coil", "air"):
        raise ConfigError(f"shock.spring: must be \"coil\" or \"air\", got {kind!r}")
    if kind == "coil":
        if air:
            raise ConfigError(f"shock.{air[0]}: an air can's key, but the shock is a coil"
                              f"{'' if 'spring' in mine else ' (its base says so)'}: set shock.spring = \"air\"")
        rates = [k for k in ("spring_rate_lb_per_in", "spring_rate_N_per_mm") if k in mine]
        if len(rates) > 1:
            raise ConfigError("shock.spring_rate_N_per_mm: give the spring's rate once, in lb/in or in N/mm")
        if not rates and "fork.spring.rate_N_per_mm" not in given:
            raise ConfigError("shock.spring_rate_lb_per_in: a coil shock needs its spring's rate, in lb/in or as "
                              "shock.spring_rate_N_per_mm")
        for key in _AIR_SCHEMA + _COIL_SCHEMA:
            if key != "fork.spring.rate_N_per_mm" or rates:
                out.pop(key, None)
        out["fork.spring.model"] = "linear"
        if rates:
            out["fork.spring.rate_N_per_mm"] = _value(mine, rates[0]) * (
                N_PER_MM_PER_LB_PER_IN if rates[0].endswith("lb_per_in") else 1.0)
        preload = _value(mine, "preload_mm", strict=False) if "preload_mm" in mine else 0.0
        # the collar's preload, 0 without: never the preload of the configuration's base (a fork's)
        out["fork.spring.preload_N"] = float(out["fork.spring.rate_N_per_mm"]) * preload
        if preload > 0.0:
            out["fork.spring.top_out"] = True
    elif kind == "air":
        if coil:
            raise ConfigError(f"shock.{coil[0]}: a coil's key, but the shock is an air shock"
                              f"{'' if 'spring' in mine else ' (its base says so)'}: set shock.spring = \"coil\"")
        for key, schema in _AIR_NEEDED:
            if key not in mine and schema not in given:
                raise ConfigError(f"shock.{key}: an air shock needs it (with shock.pressure_psi, "
                                  f"shock.piston_diameter_mm and shock.positive_volume_cm3)")
        for key in _COIL_SCHEMA:
            out.pop(key, None)
        out["fork.spring.model"] = "air"
        out["fork.spring.preload"] = False  # the air's own pressure is its preload
        out.setdefault("fork.spring.polytropic_index", POLYTROPIC_INDEX)
        for key, schema in _AIR_NEEDED:
            if key in mine:
                out[schema] = _value(mine, key)
        if "negative_volume_cm3" in mine:
            out["fork.spring.negative_volume_cm3"] = _value(mine, "negative_volume_cm3", strict=False)
        if "volume_spacers" in mine:
            spacers = mine["volume_spacers"]
            if isinstance(spacers, bool) or not isinstance(spacers, int) or spacers < 0:
                raise ConfigError(f"shock.volume_spacers: must be a whole number of spacers (0 or more), got "
                                  f"{spacers!r}")
            out["fork.spring.tokens"] = spacers
        if "spacer_volume_cm3" in mine:
            out["fork.spring.token_volume_cm3"] = _value(mine, "spacer_volume_cm3")
        if out.get("fork.spring.tokens", 0) and "fork.spring.token_volume_cm3" not in out:
            raise ConfigError("shock.spacer_volume_cm3: the volume of one spacer is needed with shock.volume_spacers")
    damper = [k for k in DAMPER if k in mine]
    if damper:
        if out.get("fork.damper.model") != "bilinear":
            for key in [k for k in out if k.startswith("fork.damper.")]:
                out.pop(key)
        out["fork.damper.model"] = "bilinear"
        for key in damper:
            out[f"fork.damper.{key}"] = _value(mine, key, strict=False)
        missing = [k for k in DAMPER if f"fork.damper.{k}" not in out]
        if missing:
            raise ConfigError(f"shock.{missing[0]}: a bilinear damper at the shaft needs both "
                              f"shock.compression_N_s_per_m and shock.rebound_N_s_per_m")
    return out


__all__ = ["schema_keys", "KEYS", "N_PER_MM_PER_LB_PER_IN"]


def written(part: dict) -> frozenset:
    """The shock configuration's keys that the ``[shock]`` keys as sold in ``part`` set (each judged
    by its own key's plausible range, ``mtbmj.bike.keys``, in the shock's own terms)."""
    mine = {k for k in KEYS if k in part}
    out = set()
    if mine & set(COIL):
        out |= {"fork.spring.rate_N_per_mm", "fork.spring.preload_N"}
    out |= {schema for key, schema in _AIR_NEEDED if key in mine}
    out |= {schema for key, schema in (("negative_volume_cm3", "fork.spring.negative_volume_cm3"),
                                       ("volume_spacers", "fork.spring.tokens"),
                                       ("spacer_volume_cm3", "fork.spring.token_volume_cm3")) if key in mine}
    out |= {f"fork.damper.{k}" for k in DAMPER if k in mine}
    return frozenset(out)


@contextlib.contextmanager
def judged_as_sold(keys):
    """Within: the plausibility warnings (``ConfigWarning``) on the shock configuration's ``keys``
    (:func:`written`) are dropped, the others issued as they come. A shock's 5000 lb/in spring is
    warned of once, as ``shock.spring_rate_lb_per_in``, not again as the 875.6 N/mm its configuration
    holds, judged by a fork's range and given a wrong unit hint."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConfigWarning)
        yield
    for w in caught:
        text = str(w.message)
        if not (issubclass(w.category, ConfigWarning) and any(text.startswith(f"{k} ") for k in keys)):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)

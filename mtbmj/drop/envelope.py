"""Random plausible forks: override sets drawn from a stated envelope of real-world values, for
checks on cases no preset covers (tests, ``benchmarks/accuracy.py``).

The envelope (uniform draws): body 30-120 kg, wheel 1.5-4 kg, drop 20-300 mm, spring rates
5-40 N/mm (every rate key of the preset's spring model), preload 0-400 N, damping 50-800 N s/m (a
damper table is scaled to that mean slope), Coulomb friction 0-60 N, tire 40-150 N/mm and
0-300 N s/m (impact, in-contact and static values drawn together, in-contact <= impact).
"""
from __future__ import annotations

import numpy as np

PRESETS = ("S1", "S4", "S7", "S10", "S12", "S14")
RATE_KEYS = ("rate_N_per_mm", "compression_rate_N_per_mm", "rebound_rate_N_per_mm", "rate_below_knee_N_per_mm",
             "rate_above_knee_N_per_mm", "progressive_rate_N_per_mm")
REFERENCE_TABLE_SLOPE_N_S_PER_M = 201.3  # mean slope of the reference damper table (reference.toml)


def random_overrides(rng: np.random.Generator, base_table: list[float] | None = None) -> dict:
    """One draw from the envelope, as configuration overrides (``base_table``: the reference
    damper's ``force_N`` list, scaled to the drawn damping)."""
    u = rng.uniform
    damping = u(50.0, 800.0)
    tire = u(40.0, 150.0)
    over = {
        "sled.body_mass_kg": u(30.0, 120.0),
        "sled.wheel_mass_kg": u(1.5, 4.0),
        "sled.drop_height_mm": u(20.0, 300.0),
        "fork.spring.preload_N": u(0.0, 400.0),
        "fork.damper.coefficient_N_s_per_m": damping,
        "fork.damper.compression_N_s_per_m": damping * u(0.5, 1.0),
        "fork.damper.rebound_N_s_per_m": damping * u(1.0, 1.5),
        "fork.friction.coulomb_N": u(0.0, 60.0),
        "tire.impact_rate_N_per_mm": tire,
        "tire.contact_rate_N_per_mm": tire * u(0.8, 1.0),
        "tire.static_rate_N_per_mm": tire / u(1.16, 1.38),
        "tire.impact_damping_N_s_per_m": u(0.0, 300.0),
        "tire.contact_damping_N_s_per_m": u(0.0, 300.0),
    }
    for key in RATE_KEYS:
        over[f"fork.spring.{key}"] = u(5.0, 40.0)
    if base_table is not None:
        over["fork.damper.force_N"] = [f * damping / REFERENCE_TABLE_SLOPE_N_S_PER_M for f in base_table]
    return over


def draws(n: int, seed: int, base_table: list[float] | None = None) -> list[tuple[str, dict]]:
    """``n`` (preset, overrides) pairs, the presets taken in turn."""
    rng = np.random.default_rng(seed)
    return [(PRESETS[i % len(PRESETS)], random_overrides(rng, base_table)) for i in range(n)]


__all__ = ["PRESETS", "random_overrides", "draws"]

"""The raw trace an engine produces, on a uniform grid at the engine timestep (SI units)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

MAX_DISPLACEMENT_M = 10.0  # a sled or fork beyond this has run away: both engines stop there


@dataclass(frozen=True)
class RawTrace:
    """State history: sled descent s (m, zero at tire touch), fork compression x (m, zero at
    unloaded full extension), their velocities, the friction state z and the tire-law phase."""

    engine: str
    time: np.ndarray
    sled: np.ndarray
    fork: np.ndarray
    sled_velocity: np.ndarray
    fork_velocity: np.ndarray
    friction_state: np.ndarray
    tire_phase: np.ndarray
    info: dict = field(default_factory=dict)

    @property
    def tire(self) -> np.ndarray:
        """Tire deflection = sled - fork (m)."""
        return self.sled - self.fork

    @property
    def tire_velocity(self) -> np.ndarray:
        return self.sled_velocity - self.fork_velocity

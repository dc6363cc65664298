"""Skyhook control of a semi-active fork damper (Karnopp et al. 1974), for ``mtbmj.rolling.env``.

The ideal skyhook damper pushes the body with F_z = -c_sky v_body (a damper to the sky). The fork
pushes the body along its axis, so the wanted fork force (pushing apart positive) is
F = -c_sky v_body / sin(head angle). A semi-active damper can only give a force with the sign of
its compression velocity, between the softest and firmest scales: when F has that sign the
command is the scale F / D(v) (D the passive damper force), clipped to the limits; otherwise the
softest setting (the classic on/off skyhook is the clipped version at the limits).
"""
from __future__ import annotations

import numpy as np


class Skyhook:
    def __init__(self, c_sky_N_s_per_m: float = 2000.0, scale_min: float = 0.2, scale_max: float = 3.0):
        self.c_sky = float(c_sky_N_s_per_m)
        self.scale_min = float(scale_min)
        self.scale_max = float(scale_max)

    def scale(self, body_z_velocity: float, damper_force_per_scale: float, head_angle_sin: float = 1.0) -> float:
        wanted = -self.c_sky * body_z_velocity / max(head_angle_sin, 1e-6)
        passive = damper_force_per_scale
        if passive == 0.0 or wanted * passive <= 0.0:
            return self.scale_min
        return float(np.clip(wanted / passive, self.scale_min, self.scale_max))

    def command(self, observation) -> np.ndarray:
        """Action in [0, 1] from a ``mtbmj.rolling.env`` observation."""
        s = self.scale(float(observation["body_z_velocity"][0]), float(observation["damper_force_per_scale"][0]),
                       float(observation["head_angle_sin"][0]))
        return np.array([(s - self.scale_min) / (self.scale_max - self.scale_min)])


__all__ = ["Skyhook"]

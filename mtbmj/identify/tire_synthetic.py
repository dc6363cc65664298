"""Synthetic tire records from known parameters, for testing the tire fits.

``tire_drop_record`` drops a mass on a tire (a drop rig: the mass rides on the wheel, vertical
motion only) and records the deflection through impact, rebound, the following bounces and the
settling. The contact is the Kelvin-Voigt law of ``controllers.tire``: F = max(0, k d + b dd/dt)
while d > 0, else 0 -- it pushes but never pulls. The first contact uses the impact values; every
later contact (the bounces and the settled oscillation) the in-contact values, as the paper
describes for the coefficient-of-restitution method. The motion is integrated piecewise with
``scipy.integrate.solve_ivp`` and events at the force switching on and off, sampled at 20 kHz,
passed through a 4th-order Butterworth 400 Hz anti-aliasing low-pass, decimated to 1 kHz, then
given potentiometer noise and ADC quantisation.

``tire_ramp_record`` is a static force-deflection ramp with noise on both channels.

Deflection is positive into the ground; zero when the tread just touches. Each record's first
comment line says it is synthetic and gives the true values.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal
from scipy.integrate import solve_ivp

from mtbmj.measured.records import write_csv_text

G = 9.81


@dataclass(frozen=True)
class TireTruth:
    """True values of a synthetic tire (config units)."""

    impact_rate_N_per_mm: float = 85.1
    impact_damping_N_s_per_m: float = 150.0
    contact_rate_N_per_mm: float = 73.4
    contact_damping_N_s_per_m: float = 150.0
    static_rate_N_per_mm: float = 61.7

    def keys(self) -> dict[str, float]:
        return {f"tire.{k}": v for k, v in self.__dict__.items()}


def simulate_drop(truth: TireTruth, mass_kg: float, drop_height_mm: float, duration_s: float,
                  hold_s: float = 0.02, gravity: float = G, rate_Hz: float = 20000.0):
    """Exact-physics motion of the drop rig: (time, deflection m, velocity m/s, force N) at
    ``rate_Hz``; released from rest at ``hold_s``, ``drop_height_mm`` above touch."""
    m = mass_kg
    values = [(truth.impact_rate_N_per_mm * 1e3, truth.impact_damping_N_s_per_m),
              (truth.contact_rate_N_per_mm * 1e3, truth.contact_damping_N_s_per_m)]
    t_grid = np.arange(0.0, duration_s, 1.0 / rate_Hz)
    d_out = np.full(t_grid.size, -drop_height_mm * 1e-3)
    v_out = np.zeros(t_grid.size)
    f_out = np.zeros(t_grid.size)
    t0, y = hold_s, np.array([-drop_height_mm * 1e-3, 0.0])
    contacts, pushing = 0, False
    for _ in range(10000):
        if t0 >= duration_s:
            break
        k, b = values[min(contacts, 1)]  # the next (or current) contact's values

        if pushing:
            def rhs(t, s, k=k, b=b):
                return [s[1], gravity - max(0.0, k * s[0] + b * s[1]) / m]

            def event(t, s, k=k, b=b):  # force falls to zero: the tire lets go
                return k * s[0] + b * s[1]
            event.direction = -1
        else:
            def rhs(t, s):
                return [s[1], gravity]

            def event(t, s, k=k, b=b):  # the force comes back (touch, or catching up while d > 0)
                return min(s[0], k * s[0] + b * s[1])
            event.direction = 1
        event.terminal = True
        sol = solve_ivp(rhs, (t0, duration_s), y, method="DOP853", events=event, dense_output=True,
                        rtol=1e-10, atol=1e-12, max_step=2e-3)
        t_end = sol.t_events[0][0] if sol.t_events[0].size else duration_s
        sel = (t_grid >= t0) & (t_grid < t_end)
        if sel.any():
            states = sol.sol(t_grid[sel])
            d_out[sel], v_out[sel] = states
            if pushing:
                f_out[sel] = np.maximum(0.0, k * states[0] + b * states[1])
        y = sol.sol(t_end)
        if not sol.t_events[0].size:
            break
        if pushing:
            contacts += 1
        pushing = not pushing
        t0 = t_end
    return t_grid, d_out, v_out, f_out


def _log(values: np.ndarray, rate_Hz: float, sample_Hz: float, antialias_Hz: float) -> np.ndarray:
    sos = signal.butter(4, antialias_Hz, fs=rate_Hz, output="sos")
    filtered, _ = signal.sosfilt(sos, values, zi=signal.sosfilt_zi(sos) * values[0])
    return filtered[:: int(round(rate_Hz / sample_Hz))]


def tire_drop_record(truth: TireTruth | None = None, mass_kg: float = 25.0, drop_height_mm: float = 50.0,
                     duration_s: float = 3.0, noise_mm: float = 0.05, quantum_mm: float = 0.005,
                     force_noise_N: float = 2.0, force_quantum_N: float = 0.1, with_force: bool = True,
                     seed: int = 0, sample_Hz: float = 1000.0, antialias_Hz: float = 400.0,
                     gravity: float = G) -> str:
    """CSV text of a synthetic tire drop record: time_s, deflection_mm (, force_N)."""
    truth = truth or TireTruth()
    rate = 20000.0
    t, d, _, f = simulate_drop(truth, mass_kg, drop_height_mm, duration_s, gravity=gravity, rate_Hz=rate)
    rng = np.random.default_rng(seed)
    time = t[:: int(round(rate / sample_Hz))]
    d_mm = _log(d * 1e3, rate, sample_Hz, antialias_Hz)
    d_mm = np.round((d_mm + rng.normal(0.0, noise_mm, d_mm.size)) / quantum_mm) * quantum_mm
    columns = {"time_s": time, "deflection_mm": d_mm}
    if with_force:
        f_n = _log(f, rate, sample_Hz, antialias_Hz)
        columns["force_N"] = np.round((f_n + rng.normal(0.0, force_noise_N, f_n.size)) / force_quantum_N) * force_quantum_N
    true = ", ".join(f"{k} = {v:g}" for k, v in truth.keys().items() if "static" not in k)
    comments = [
        f"synthetic tire drop record (mtbmj.identify.tire_synthetic), true values: {true}",
        f"mass_kg = {mass_kg:g}",
        f"drop_height_mm = {drop_height_mm:g}; gravity_m_per_s2 = {gravity:g}",
        "first contact: impact values; later contacts: in-contact values; Kelvin-Voigt, pushes only",
        f"1 kHz after a 4th-order Butterworth {antialias_Hz:g} Hz low-pass; noise {noise_mm:g} mm rms, "
        f"quantum {quantum_mm:g} mm; seed {seed}",
    ]
    return write_csv_text(columns, comments)


def tire_ramp_record(truth: TireTruth | None = None, max_deflection_mm: float = 40.0, points: int = 200,
                     noise_mm: float = 0.02, force_noise_N: float = 3.0, force_quantum_N: float = 0.1,
                     seed: int = 0) -> str:
    """CSV text of a synthetic static ramp: deflection_mm, force_N (a slow press, loading)."""
    truth = truth or TireTruth()
    rng = np.random.default_rng(seed)
    d = np.linspace(0.5, max_deflection_mm, points)
    f = truth.static_rate_N_per_mm * d
    d_meas = d + rng.normal(0.0, noise_mm, d.size)
    f_meas = np.round((f + rng.normal(0.0, force_noise_N, d.size)) / force_quantum_N) * force_quantum_N
    comments = [
        f"synthetic static tire ramp (mtbmj.identify.tire_synthetic), true values: "
        f"tire.static_rate_N_per_mm = {truth.static_rate_N_per_mm:g}",
        f"noise {noise_mm:g} mm and {force_noise_N:g} N rms; force quantum {force_quantum_N:g} N; seed {seed}",
    ]
    return write_csv_text({"deflection_mm": np.round(d_meas, 4), "force_N": f_meas}, comments)


__all__ = ["TireTruth", "simulate_drop", "tire_drop_record", "tire_ramp_record"]

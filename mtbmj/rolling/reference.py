"""The rolling front end's ODE reference: the same model as ``mtbmj roll``, integrated by scipy
without MuJoCo, so every rolling run can be checked against an independent solver (``mtbmj
crosscheck CONFIG --roll SCENARIO --speed V``).

The planar front end has three degrees of freedom that matter: the chassis' horizontal and
vertical slides (qx, qz) and the fork's slide qf along the head tube (compression positive, the
unsprung mass moving by qf (-cos a, sin a)); the wheel's spin carries no force (the radial tire
has none along its tread) and is left out. With M the chassis' mass and m the unsprung mass
(lower legs and wheel), the kinetic energy is 1/2 M (qx'^2 + qz'^2) + 1/2 m ((qx' - c qf')^2 +
(qz' + s qf')^2), c = cos a, s = sin a, so the mass matrix is constant:

    [[M + m, 0, -m c], [0, M + m, m s], [-m c, m s, m]]

(``mass_matrix``; a test compares it with MuJoCo's own). The generalised forces are gravity
(-(M + m) g on qz, -m g s on qf), the fork law F (pushing apart: -F on qf), the tire's force (Fx,
Fz) at the axle (Fx on qx, Fz on qz, -c Fx + s Fz on qf) and the drive's force on qx (the ideal
servo kp (x0 + v t - qx) + kv (v - qx'), or ``controllers.drive``'s rider, or none). A fork law
with a friction state adds its state equation.

What it shares with the engine is the model, not its numerics: the same force-law objects
(``setup.fork``, the ``RadialTire`` law per patch with its rim, ``controllers.drive``), but the
terrain's contact patches are found afresh at every evaluation (the exact closest points, where the
engine refreshes them every millisecond), and the equations are integrated by
``scipy.integrate.solve_ivp`` (DOP853, tight tolerances, steps no longer than the engine's). A
drum rig (moving terrain) has no reference here.
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from mtbmj.errors import ConfigError
from mtbmj.runpath.crosscheck import CrosscheckResult, compare_series


def mass_matrix(body_mass: float, unsprung_mass: float, head_angle: float) -> np.ndarray:
    """The front end's mass matrix over (qx, qz, qf) (see the module doc)."""
    c, s = math.cos(head_angle), math.sin(head_angle)
    M, m = body_mass, unsprung_mass
    return np.array([[M + m, 0.0, -m * c], [0.0, M + m, m * s], [-m * c, m * s, m]])


class Reference:
    """The equations of motion of a prepared rolling run (``frontend.prepare``), from its state
    at t = 0."""

    def __init__(self, prepared):
        p = prepared
        if p.terrain.moving:
            raise ConfigError("crosscheck --roll: the drum rig moves its surface; the rolling reference covers fixed "
                              "terrain only")
        self.p = p
        setup, front, cb = p.setup, p.front, p.callback
        self.law = setup.fork
        self.tire = p.tire
        self.drive = cb.drive
        self.speed = cb.speed
        self.x_ref0 = cb.x_ref0
        model = front.model
        self.kp = float(model.actuator_gainprm[model.actuator("drive_position").id, 0])
        self.kv = float(model.actuator_gainprm[model.actuator("drive_velocity").id, 0])
        self.g = setup.gravity
        self.M, self.m = setup.body_mass, setup.wheel_mass
        self.c, self.s = front.axis
        self.inverse = np.linalg.inv(mass_matrix(self.M, self.m, front.head_angle))
        self.x0, self.z0, self.L = front.chassis_x0, front.chassis_z0, front.fork_length
        self.has_state = bool(self.law.has_state)
        q, v = p.data.qpos, p.data.qvel
        self.y0 = np.array([q[cb.xq], q[cb.zq], q[cb.fq], v[cb.xv], v[cb.zv], v[cb.fv]]
                           + ([float(p.data.act[cb.act_index])] if self.has_state else []))

    def axle(self, y):
        qx, qz, qf, vx, vz, vf = y[:6]
        c, s = self.c, self.s
        return (self.x0 + qx + (self.L - qf) * c, self.z0 + qz - (self.L - qf) * s, vx - vf * c, vz + vf * s)

    def forces(self, t, y):
        """(fork force N, tire Fx N, tire Fz N, deepest deflection m, drive force N, state rate)."""
        qx, qz, qf, vx, vz, vf = y[:6]
        z = y[6] if self.has_state else 0.0
        fork = self.law.force(qf, vf, z) if self.has_state else self.law.force(qf, vf)
        rate = self.law.state_rate(vf, z) if self.has_state else 0.0
        cx, cz, ax, az = self.axle(y)
        fx, fz, deepest, _, _ = self.tire.force(cx, cz, ax, az, self.tire.patches(cx, cz, t))
        if self.drive.mode == "servo":
            drive = self.kp * (self.x_ref0 + self.speed * t - qx) + self.kv * (self.speed - vx)
        else:
            drive = self.drive.force(self.speed, vx)
        return fork, fx, fz, deepest, drive, rate

    def rhs(self, t, y):
        fork, fx, fz, _, drive, rate = self.forces(t, y)
        g = np.array([fx + drive, fz - (self.M + self.m) * self.g,
                      -fork - self.c * fx + self.s * fz - self.m * self.g * self.s])
        acc = self.inverse @ g
        out = [y[3], y[4], y[5], acc[0], acc[1], acc[2]]
        if self.has_state:
            out.append(rate)
        return out

    def run(self, times: np.ndarray, max_step: float, rtol: float = 1e-10, atol: float = 1e-12) -> dict:
        """The reference's signals at ``times`` (s), in the engine's columns and units."""
        start = time.perf_counter()
        sol = solve_ivp(self.rhs, (0.0, float(times[-1])), self.y0, method="DOP853", t_eval=times, rtol=rtol,
                        atol=atol, max_step=max_step)
        if not sol.success:
            raise RuntimeError(f"rolling reference: {sol.message}")
        y = sol.y
        n = times.size
        fork_force, fx, fz, deflection, drive = (np.empty(n) for _ in range(5))
        for i in range(n):
            fork_force[i], fx[i], fz[i], deflection[i], drive[i], _ = self.forces(times[i], y[:, i])
        cx, cz, _, _ = self.axle(y)
        return {"time_s": times, "x_m": cx, "fork_mm": y[2] * 1e3, "body_z_mm": (y[1] - self.y0[1]) * 1e3,
                "axle_z_mm": (cz - self.axle(self.y0)[1]) * 1e3, "tire_mm": deflection * 1e3,
                "fork_force_N": fork_force, "axle_force_x_N": fx, "axle_force_z_N": fz, "drive_force_N": drive,
                "wall_time_s": time.perf_counter() - start, "nfev": int(sol.nfev)}


DISPLACEMENTS = {"fork_mm": "fork", "body_z_mm": "body_height", "axle_z_mm": "axle_height"}  # column -> signal
TOLERANCE_MM = 0.02  # fork travel: the rolling cross-check's tolerance
FORCE_TOLERANCE = 0.01  # the axle force peaks (up and back), relative
MAX_STEP_S = 1e-3  # the reference's longest step (it converges to 2.5e-6 mm at 2 ms on the root)


def crosscheck(scenario, speed_m_per_s: float, config="S12", head_angle_deg: float | None = None,
               duration: float | None = None, overrides=None, drive: str = "rider") -> CrosscheckResult:
    """``mtbmj roll``'s run of ``scenario`` at ``speed_m_per_s`` against this reference from the
    same initial state, sample by sample: fork travel (judged, ``TOLERANCE_MM``), body and axle
    height and the tire's deflection in contact (mm, reported), and the axle force up and back
    (N; their peaks judged relative to the reference's, ``FORCE_TOLERANCE``; the series reported)."""
    from mtbmj.rolling.frontend import DEFAULT_HEAD_ANGLE_DEG, prepare, run_roll

    head = DEFAULT_HEAD_ANGLE_DEG if head_angle_deg is None else head_angle_deg
    engine = run_roll(scenario, speed_m_per_s, config, head, duration, overrides, drive=drive)
    reference = Reference(prepare(scenario, speed_m_per_s, config, head, overrides, callback="python", drive=drive))
    raw = engine.raw
    times = raw["time_s"]
    ref = reference.run(times, max_step=MAX_STEP_S)
    signals = [compare_series(name, "mm", times, raw[column], ref[column],
                              TOLERANCE_MM if column == "fork_mm" else None)
               for column, name in DISPLACEMENTS.items()]
    signals.append(compare_series("tire", "mm", times, np.maximum(raw["tire_mm"], 0.0),
                                  np.maximum(ref["tire_mm"], 0.0)))  # the deflection in contact
    for name, column, sign in (("axle_force_up", "axle_force_z_N", 1.0), ("axle_force_back", "axle_force_x_N", -1.0)):
        signals.append(compare_series(name, "N", times, sign * raw[column], sign * ref[column], FORCE_TOLERANCE,
                                      relative=True, judged=("peak",)))
    return CrosscheckResult("roll", f"{scenario} at {float(speed_m_per_s):g} m/s ({engine.name}, drive {drive})",
                            "mujoco", "rolling ODE reference", signals, engine.wall_time_s, ref["wall_time_s"],
                            {"scenario": str(scenario), "speed_m_per_s": float(speed_m_per_s), "config": engine.name,
                             "drive": drive, "head_angle_deg": float(head)})


__all__ = ["Reference", "mass_matrix", "crosscheck", "TOLERANCE_MM", "FORCE_TOLERANCE"]

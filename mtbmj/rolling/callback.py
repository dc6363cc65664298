"""The rolling front end's control callback in Python: the specification of its compiled twin
(``mtbmj.rolling.callback_compiled``, beside it) and the fallback when numba is missing.

Each step it writes into ``ctrl``: the fork law's force (and its friction state's rate), the radial
tire's force on the axle from the terrain's contact patches (``mtbmj.rolling.tire``), the tire's
deflection (a probe actuator, for the record) and the drive (``controllers.drive``).
"""
from __future__ import annotations

import math

from mtbmj.controllers.drive import Drive
from mtbmj.rolling.tire import REFRESH_DISTANCE_M, REFRESH_S, PatchSearch, RadialTire


def find_indices(cb, front, fork_law) -> None:
    """Set on the callback ``cb`` (this module's or its compiled twin) what it reads of the front
    end's model: the chassis' and fork's qpos and qvel indices (``xq``/``xv``, ``zq``/``zv``,
    ``fq``/``fv``), its actuators' ids (the probes: deflection and touch) and the friction state's activation index, whether the law
    has that state, and the steering axis' cosine and sine."""
    m = front.model
    j = lambda name: (int(m.joint(name).qposadr[0]), int(m.joint(name).dofadr[0]))  # noqa: E731
    cb.xq, cb.xv = j("chassis_x")
    cb.zq, cb.zv = j("chassis_z")
    cb.fq, cb.fv = j("fork")
    a = lambda name: int(m.actuator(name).id)  # noqa: E731
    cb.a_state, cb.a_fork = a("friction_state"), a("fork_force")
    cb.a_dp, cb.a_dv, cb.a_tx, cb.a_tz = a("drive_position"), a("drive_velocity"), a("tire_x"), a("tire_z")
    cb.a_probe = a("tire_deflection_probe")
    cb.a_touch = a("tire_touch_probe")
    cb.act_index = int(m.actuator_actadr[cb.a_state])
    cb.has_state = fork_law.has_state
    cb.cos, cb.sin = front.axis


class RollCallback:
    """Fork law + radial tire + speed servo reference, written into ``ctrl`` each step.

    Acts only on its own model; assigns, never accumulates. The terrain geometry (contact
    patches) is refreshed every ``refresh`` seconds of simulated time or 0.25 mm of axle travel, by
    the patch search the bike's wheels use too (``mtbmj.rolling.tire.PatchSearch``: kept while the
    axle stays over the straight stretch its one patch lies on); ``refreshes`` counts the searches.
    ``damper_scale`` (None = passive) multiplies the fork's hydraulic damper force: the
    semi-active command of ``mtbmj.rolling.env``."""

    def __init__(self, front, fork_law, tire: RadialTire, speed: float, x_ref0: float,
                 refresh: float = REFRESH_S, drive: Drive | None = None):
        m = front.model
        self.drive = drive if drive is not None else Drive("servo")
        self._model = m
        self._address = m._address
        self.front = front
        self.law = fork_law
        self.tire = tire
        self.speed = float(speed)
        self.x_ref0 = float(x_ref0)
        self.refresh = float(refresh)
        find_indices(self, front, fork_law)
        self.search = PatchSearch(tire)
        self.patch_time = 0.0
        self.next_refresh = -math.inf
        self.last_x = math.inf
        self.refreshes = 0
        self.calls = 0
        self.damper_scale = None
        self._data = None
        self._arrays = None

    def bind(self, data) -> None:
        self._data = data
        self._arrays = (data.qpos, data.qvel, data.act, data.ctrl)

    @property
    def patches(self) -> list:
        """The contact patches of the last refresh: (qx, qz, nx, nz, surface vx, surface vz, share,
        prominence): ``RadialTire.patches``."""
        return self.search.patches

    def reset(self) -> None:
        self.search.reset()
        self.next_refresh, self.last_x = -math.inf, math.inf

    def axle_state(self, qpos, qvel):
        return self.front.axle_state(qpos, qvel, (self.xq, self.zq, self.fq, self.xv, self.zv, self.fv))

    def __call__(self, m, d):
        if m is not self._model and m._address != self._address:
            return
        self.calls += 1
        if d is self._data:
            qpos, qvel, act, ctrl = self._arrays
        else:
            qpos, qvel, act, ctrl = d.qpos, d.qvel, d.act, d.ctrl
        t = d.time
        x = qpos[self.fq]
        v = qvel[self.fv]
        law = self.law
        z = act[self.act_index] if self.has_state else 0.0
        if self.damper_scale is None:
            force = law.force(x, v, z) if self.has_state else law.force(x, v)
        else:
            force = law.spring.force(x, v) + self.damper_scale * law.damper.force(v) + law.friction.force(v, z)
        if self.has_state:
            ctrl[self.a_state] = law.state_rate(v, z)
        ctrl[self.a_fork] = -force
        cx, cz, vx, vz = self.axle_state(qpos, qvel)
        if t >= self.next_refresh or abs(cx - self.last_x) > REFRESH_DISTANCE_M:
            if self.search.refresh(cx, cz, t):
                self.refreshes += 1
            self.patch_time = t
            self.next_refresh = t + self.refresh - 1e-12
            self.last_x = cx
        patches = self.search.patches
        if patches and self.tire.terrain.moving:
            dt = t - self.patch_time
            patches = [(p[0] + p[4] * dt, p[1] + p[5] * dt, *p[2:]) for p in patches]  # qx + sx dt, qz + sz dt
        fx, fz, deflection, _, _ = self.tire.force(cx, cz, vx, vz, patches)
        ctrl[self.a_probe] = deflection
        ctrl[self.a_touch] = self.tire.shallowest(cx, cz, patches, deflection)
        ctrl[self.a_tx] = fx
        ctrl[self.a_tz] = fz
        if self.drive.mode == "servo":  # the ideal PD servo on x0 + v t (its actuators' own forces)
            ctrl[self.a_dp] = self.x_ref0 + self.speed * t
            ctrl[self.a_dv] = self.speed
        else:  # the rider's (or no) force, through the same actuators: position term 0, velocity term F
            x, vx = qpos[self.xq], qvel[self.xv]
            ctrl[self.a_dp] = x
            ctrl[self.a_dv] = vx + self.drive.force(self.speed, vx) / self.drive.kv


__all__ = ["RollCallback", "find_indices"]

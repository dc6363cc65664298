"""The rolling front end at a 90 degree head angle on the washboard, against a model written here
(issue 25): the classic quarter car does not apply (a round tire does not follow the profile's
points: its envelope rides over the crests and can sit on two of them), so the model here rolls
the same round tire over the same sampled profile, like with like. Written from the equations,
without the package's integrator, tire, geometry or fork law: S1's linear spring and damper
(k x + c v) written out, the tire's radial law per contact patch (k d + c tanh(3 d / 3 mm) dd/dt,
pushing only) with its contacts found here as the local minima of the distance along the runs of
profile segments within reach of the axle, each bearing its share of the overlap (``contacts``),
the ideal servo on x0 + v t, and scipy's LSODA."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mtbmj
from mtbmj import compose
from mtbmj.rolling.frontend import prepare, run_roll, tire_values
from mtbmj.rolling.terrain import make

SPEED = 3.0
DURATION = 0.8
MARGIN = 0.010  # a run: the segments within radius + 10 mm of the axle


class Washboard90:
    """The front end with a vertical fork: chassis x and z, the fork's compression qf (the
    unsprung mass moves up by qf), M chassis, m unsprung."""

    def __init__(self):
        cfg = mtbmj.load_config("S1")
        setup = compose.setup(cfg)
        self.k_fork = cfg["fork.spring.rate_N_per_mm"] * 1e3
        self.c_fork = cfg["fork.damper.coefficient_N_s_per_m"]
        self.k_tire, self.c_tire = tire_values(setup)
        self.M, self.m, self.g = setup.body_mass, setup.wheel_mass, setup.gravity
        self.r, self.L = setup.tire_radius, setup.fork_length
        terrain = make("washboard")
        self.px, self.pz = np.asarray(terrain.x, float), np.asarray(terrain.z, float)
        p = prepare("washboard", SPEED, "S1", 90.0, drive="servo", callback="python")  # only its numbers
        model, cb = p.front.model, p.callback
        self.kp = float(model.actuator_gainprm[model.actuator("drive_position").id, 0])
        self.kv = float(model.actuator_gainprm[model.actuator("drive_velocity").id, 0])
        self.x0, self.z0, self.xref0 = p.front.chassis_x0, p.front.chassis_z0, cb.x_ref0
        q = p.data.qpos
        self.y0 = [q[cb.xq], q[cb.zq], q[cb.fq], SPEED, 0.0, 0.0]

    def axle(self, qx, qz, qf):
        return self.x0 + qx, self.z0 + qz - (self.L - qf)  # straight below the crown

    def tire(self, ax, az, vx, vz):
        """Force (Fx, Fz) on the axle and the deepest deflection, from the contacts here: along each
        run of segments within reach the local minima of the distance (contacts), each bearing its
        share of the overlap's depth (``shares``), its force that fraction of the law at its depth."""
        reach = self.r + MARGIN
        i0 = max(int(np.searchsorted(self.px, ax - reach)) - 1, 0)
        i1 = min(int(np.searchsorted(self.px, ax + reach)) + 1, self.px.size - 1)
        x0, z0 = self.px[i0:i1], self.pz[i0:i1]
        ex, ez = self.px[i0 + 1:i1 + 1] - x0, self.pz[i0 + 1:i1 + 1] - z0
        u = np.clip(((ax - x0) * ex + (az - z0) * ez) / (ex * ex + ez * ez), 0.0, 1.0)
        qx, qz = x0 + u * ex, z0 + u * ez
        dist = np.hypot(ax - qx, az - qz)
        corner = np.hypot(ax - self.px[i0 + 1:i1 + 1], az - self.pz[i0 + 1:i1 + 1])  # each segment's end
        near = dist < reach
        fx = fz = 0.0
        deepest = -math.inf
        start = None
        for j in range(near.size + 1):  # runs of segments in reach
            inside = j < near.size and near[j]
            if inside and start is None:
                start = j
            if not inside and start is not None:
                for k, w in contacts(dist[start:j], corner[start:j - 1], self.r):
                    k += start
                    nx, nz = (ax - qx[k]) / dist[k], (az - qz[k]) / dist[k]
                    d = self.r - dist[k]
                    deepest = max(deepest, d)
                    if d > 0.0:
                        rate = -(vx * nx + vz * nz)
                        f = w * max(0.0, self.k_tire * d + self.c_tire * math.tanh(3.0 * d / 3e-3) * rate)
                        fx, fz = fx + f * nx, fz + f * nz
                start = None
        return fx, fz, deepest

    def rhs(self, t, y):
        qx, qz, qf, vx, vz, vf = y
        ax, az = self.axle(qx, qz, qf)
        fx, fz, _ = self.tire(ax, az, vx, vz + vf)
        fork = self.k_fork * qf + self.c_fork * vf
        drive = self.kp * (self.xref0 + SPEED * t - qx) + self.kv * (SPEED - vx)
        # (M + m) x'' = Fx + drive;  M z'' + m (z'' + qf'') = Fz - (M + m) g;  m (z'' + qf'') = Fz - m g - fork
        ax_ = (fx + drive) / (self.M + self.m)
        az_ = (fork - self.M * self.g) / self.M  # the chassis: the fork pushes it up, gravity down
        af = (fz - self.m * self.g - fork) / self.m - az_
        return [vx, vz, vf, ax_, az_, af]


def contacts(dist, corner, radius):
    """The contacts of a run of segments (``dist`` each one's closest distance, ``corner`` the
    distance of the corner between segment k and k + 1) and the share of its depth each one bears:
    [(segment, share)]. The contacts are the local minima of the distance along the run (a corner
    shared by two segments one minimum), each standing out by more than round-off; between two
    neighbours the barrier is the highest distance between them. As depths (radius - distance), the
    run's overlap above a level h falls apart at the shallowest barrier above h into two overlaps;
    each contact bears its depth down to that barrier in its own overlap, and the overlap below it
    down to h is shared in proportion to those (a lone contact bears its whole depth)."""
    seq = []  # the distance's critical values along the run: (value, segment or None)
    for k, d in enumerate(dist):
        if k:
            seq.append((max(corner[k - 1], d, dist[k - 1]), None))
        seq.append((d, k))
    minima, barriers, last = [], [], None
    for n, (v, k) in enumerate(seq):
        if k is None or (n and seq[n - 1][0] <= v) or (n + 1 < len(seq) and seq[n + 1][0] < v):
            continue
        lows = [m for m in range(n) if seq[m][0] <= v]
        cols = [max(w for w, _ in seq[lows[-1] + 1:n])] if lows else []
        highs = [m for m in range(n + 1, len(seq)) if seq[m][0] < v]
        cols += [max(w for w, _ in seq[n + 1:highs[0]])] if highs else []
        if cols and min(cols) - v <= 1e-12:
            continue
        if last is not None:
            barriers.append(radius - max(w for w, _ in seq[last + 1:n]))
        minima.append((k, radius - v))
        last = n

    def borne(a, b, h):  # {contact: depth borne below its overlap's top, down to level h}, contacts a..b
        if a == b:
            return {a: minima[a][1] - h}
        t = min(range(a, b), key=lambda m: barriers[m])
        if barriers[t] <= h:
            return {**borne(a, t, h), **borne(t + 1, b, h)}
        above = {**borne(a, t, barriers[t]), **borne(t + 1, b, barriers[t])}
        total = sum(above.values())
        return {m: e * (total + barriers[t] - h) / total for m, e in above.items()}

    shares = borne(0, len(minima) - 1, 0.0)
    return [(k, 1.0 if depth <= 0.0 else min(1.0, max(0.0, shares[m] / depth))) for m, (k, depth) in enumerate(minima)]


def test_the_front_end_on_the_washboard_at_90_degrees_is_the_model_written_here():
    model = Washboard90()
    engine = run_roll("washboard", SPEED, "S1", 90.0, DURATION, drive="servo")
    t = engine.raw["time_s"]
    sol = solve_ivp(model.rhs, (0.0, t[-1]), model.y0, method="LSODA", t_eval=t, rtol=1e-10, atol=1e-12,
                    max_step=2e-4)
    assert sol.success
    fork = sol.y[2] * 1e3
    # the written model holds where the engine goes: the fork between its top-out and its bumper
    assert engine.raw["fork_mm"].min() > 0.0 and engine.raw["fork_mm"].max() < 112.0
    assert np.ptp(engine.raw["fork_mm"]) > 5.0  # and the washboard works it
    assert np.max(np.abs(engine.raw["fork_mm"] - fork)) < 0.02
    body = (sol.y[1] - sol.y[1][0]) * 1e3
    assert np.max(np.abs(engine.raw["body_z_mm"] - body)) < 0.02

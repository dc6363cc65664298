"""Seat slams at several rebound clicks replayed through the bike together (``fit bounce --replay``).

A rebound adjuster changes the damper only: the spring and the shock's dry friction are the same
shock's at every click. So the records of one bike at several clicks are fitted jointly: one
spring-rate scale and one Coulomb friction shared by all of them, a linear damper and a slam
amplitude per record (each record's replay as ``mtbmj.identify.bounce_replay``: its own start, its
own push). Fitted alternately (``bounce_replay.ROUNDS`` times): each record's push on the record up
to its peak, the shock held (``bounce_replay.fit_push``); then the shared spring and friction with
every record's damper and slam amplitude on all the replays at once (``scipy.optimize.least_squares``;
a record's damper and slam touch only its own residual, so the Jacobian's finite differences perturb
them together). 95 % intervals: the joint stage's Jacobian with the pooled residual's variance,
inflated for the records' mean lag-1 autocorrelation, Student's t (conditional on the push's timing).

Why pooled: fitted alone, a record's damper and friction trade against each other (their correlation
-0.94 on the shared 8-click slam, -0.90 on the 0-click one: the ring-down's loss is split between them
differently in each record), so the damper read per record need not rise with the clicks. With the
friction one value, each record's loss beyond it is its damper's. Measured on the shared slams it
does not make the damper rise (docs/identification.md: 2069, 1602, 2497 N s/m at 0, 8, 17 clicks), so
``fit bounce --replay`` still replays each record alone.

A record the joint replay cannot follow (RMS above ``MAX_RELATIVE_RMS`` of its slam's rise) or whose
values end at a bound is refused with the reason, and the others are fitted again without it.
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.identify.bounce import lag1
from mtbmj.identify.bounce_ends import correlations, covariance
from mtbmj.identify.bounce_replay import LOWER, MAX_RELATIVE_RMS, NAMES, ROUNDS, UPPER, Slam, at_bound, finish, fit_push

SHARED = ("spring_scale", "friction_N")  # the same shock's at every rebound click
PER_RECORD = ("slam_N", "damper_N_s_per_m")
# optional: "compression_N_s_per_m" shared (the damper's per record is then its rebound), "settle_N" per
# record (the rider's weight moved onto the saddle after the slam, ``bounce_replay.push``)
EXTRA = {"compression_N_s_per_m": (2000.0, 50.0, 30000.0), "settle_N": (0.0, -1500.0, 1500.0)}  # start, bounds


def replay_pooled(slams: list[Slam], max_nfev: int = 40, max_relative_rms: float = MAX_RELATIVE_RMS,
                  shared=SHARED, per_record=PER_RECORD):
    """The records' slams (``bounce_replay.prepare_slam``, each on its own ``SeatedReplay``) fitted
    jointly. Returns (replays, refused, pooled): the Replay per record followed (its shared values and
    their intervals the joint fit's), {name: reason} for the records refused, and the pooled values."""
    slams = list(slams)
    refused: dict = {}
    while slams:
        replays, bad, pooled = _fit(slams, max_nfev, max_relative_rms, tuple(shared), tuple(per_record))
        if not bad:
            return replays, refused, pooled
        refused.update(bad)
        slams = [s for s in slams if s.name not in bad]
    return [], refused, None


class _Vars:
    """The joint unknowns: each record's ``per_record`` values and the ``shared`` ones, scaled."""

    def __init__(self, slams, shared, per_record):
        self.slams, self.shared, self.per = slams, shared, per_record
        self.x = [sl.x0.copy() for sl in slams]  # NAMES' values per record
        self.e = [{k: EXTRA[k][0] for k in EXTRA if k in shared + per_record} for _ in slams]
        specs = []  # (record or None, name)
        for name in per_record:
            specs += [(k, name) for k in range(len(slams))]
        specs += [(None, name) for name in shared]
        self.specs = specs
        ref = slams[0]
        for name in shared:  # every record from the first record's start
            for k in range(len(slams)):
                self.put(k, name, self.get(0, name))
        self.start = np.array([self.get(0 if k is None else k, n) for k, n in specs])
        self.scale = np.array([EXTRA[n][0] if n in EXTRA and EXTRA[n][0] else
                               (1000.0 if n in EXTRA else ref.base[NAMES.index(n)]) for _, n in specs])
        self.lower = np.array([EXTRA[n][1] if n in EXTRA else LOWER[NAMES.index(n)] for _, n in specs])
        self.upper = np.array([EXTRA[n][2] if n in EXTRA else UPPER[NAMES.index(n)] for _, n in specs])

    def get(self, k, name):
        return self.e[k][name] if name in EXTRA else float(self.x[k][NAMES.index(name)])

    def put(self, k, name, v):
        if name in EXTRA:
            self.e[k][name] = float(v)
        else:
            self.x[k][NAMES.index(name)] = v

    def theta(self):
        return (np.array([self.get(0 if k is None else k, n) for k, n in self.specs]) - self.start) / self.scale

    def set(self, th):
        for (k, n), v in zip(self.specs, self.start + th * self.scale):
            for j in (range(len(self.slams)) if k is None else (k,)):
                self.put(j, n, v)


def _fit(slams, max_nfev, max_relative_rms, shared, per_record):
    from scipy.optimize import least_squares
    from scipy.sparse import lil_matrix

    n = len(slams)
    v = _Vars(slams, shared, per_record)
    rows = np.cumsum([0] + [sl.grid.size for sl in slams])

    def residual(th):
        v.set(th)
        return np.concatenate([sl.residual(v.x[k], None, v.e[k]) for k, sl in enumerate(slams)])

    sparsity = lil_matrix((rows[-1], len(v.specs)), dtype=int)
    for j, (k, _) in enumerate(v.specs):
        if k is None:
            sparsity[:, j] = 1
        else:
            sparsity[rows[k]:rows[k + 1], j] = 1
    lo, hi = (v.lower - v.start) / v.scale, (v.upper - v.start) / v.scale
    nfev = 0
    sol = None
    for _ in range(ROUNDS):
        for k, sl in enumerate(slams):  # each record's push on the record up to its peak, the shock held
            u = (v.x[k] - sl.x0) / sl.base
            nfev += fit_push(sl, u, max_nfev, v.e[k])
            v.x[k] = sl.x0 + u * sl.base
        th0 = np.clip(v.theta(), lo + 1e-12, hi - 1e-12)
        sol = least_squares(residual, th0, bounds=(lo, hi), diff_step=1e-3, max_nfev=max_nfev,
                            jac_sparsity=sparsity)
        v.set(sol.x)
        nfev += sol.nfev * n
    r = sol.fun
    J = np.asarray(sol.jac.todense() if hasattr(sol.jac, "todense") else sol.jac) / v.scale
    rho = float(np.mean([lag1(r[rows[k]:rows[k + 1]]) for k in range(n)]))
    cov, tq = covariance(r, J, rho)
    labels = [n_ if k is None else f"{n_}[{k}]" for k, n_ in v.specs]
    sd_all = dict(zip(labels, np.sqrt(np.maximum(np.diag(cov), 0.0)) * tq))
    corr_all = correlations(cov, labels)
    replays, bad = [], {}
    for k, sl in enumerate(slams):
        rk = r[rows[k]:rows[k + 1]]
        rms = float(np.sqrt(np.mean(rk * rk)))
        x = v.x[k]
        if rms > max_relative_rms * sl.rise:
            bad[sl.name] = (f"{sl.name}: the replay through the bike, with the spring and friction shared with the "
                            f"other records, cannot follow the record: RMS {rms:.1f} mm of a {sl.rise:.1f} mm slam "
                            f"(more than {100 * max_relative_rms:.0f} %)")
            continue
        bound = at_bound(x)
        if bound:
            bad[sl.name] = (f"{sl.name}: the replay's {bound[0]} ends at its bound ({x[NAMES.index(bound[0])]:.4g}): "
                            f"the bike cannot describe the record within it")
            continue
        sd = {nm: math.nan for nm in NAMES}
        for name in per_record:
            sd[name] = float(sd_all[f"{name}[{k}]"])
        for name in shared:
            sd[name] = float(sd_all[name])
        own = {key.replace(f"[{k}]", ""): val for key, val in corr_all.items()
               if all(("[" not in part) or part.endswith(f"[{k}]") for part in key.split("|"))}
        replays.append(finish(sl, x, sd, rms, nfev, own, v.e[k]))
    if bad:
        return replays, bad, None
    pooled = {"records": [sl.name for sl in slams], "rms_mm": float(np.sqrt(np.mean(r * r))), "runs": int(nfev),
              **{name: v.get(0, name) for name in shared}, **{name + "_sd": float(sd_all[name]) for name in shared},
              "damper_correlations": {f"{slams[a].name}|{slams[b].name}":
                                      corr_all[f"damper_N_s_per_m[{a}]|damper_N_s_per_m[{b}]"]
                                      for a in range(n) for b in range(a + 1, n)}}
    return replays, bad, pooled


__all__ = ["PER_RECORD", "SHARED", "replay_pooled"]

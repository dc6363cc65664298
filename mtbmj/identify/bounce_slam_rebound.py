"""Seat slams at several rebound clicks fitted together on the slam and its first rebound (``fit bounce
--replay``'s ``"slam_rebound"``): one spring and one compression coefficient shared, a push and a rebound
coefficient per record, each with a 95 % interval.

Why. The whole-trace replay (``mtbmj.identify.bounce_replay``) has one linear damper both ways. Its
slam is arrested by that damper and the spring, so the push that makes the record's compression speed
overshoots the record's peak (0 clicks: 51.6 mm above rest against 44.0) or, at a weaker push, comes
late (8 clicks: 25 ms late, 47.3 against 45.0 mm), and the damper is spent on both and on the level
after the slam. Measured one factor at a time at that replay's values (docs/identification.md): the
friction (0-150 N) moves the peak by 0.3 mm (0 clicks) and 2.9 mm (8), the rider's resonance (4-8 Hz)
by 0.8 and 4.3 mm, the compression coefficient alone (4000 and 8000 N s/m for 1794 and 1450) by 6-25
mm. With a compression coefficient of its own, fitted with the push, the replay meets the peak within
about 1 mm and 10-25 ms. A rebound adjuster changes the rebound coefficient only, so the spring and
the compression coefficient are shared by the records.

Method. Per record, the replay's stroke less the record's on ``bounce_replay``'s grid from
``BEFORE_S`` before the peak to where the record's first rebound crosses the rest level before the
slam (``window_end``: before the top-out the 0- and 8-click rebounds reach, and before the level after
the slam moves). The values: the shared spring scale and compression coefficient, and per record the
push's six (``bounce_replay.PUSH_NAMES``) and its rebound coefficient; the friction is given (the
best-determined whole-trace replay's), not fitted. Fitted by
``scipy.optimize.least_squares`` on all records' residuals together, the Jacobian by forward
differences record by record (a record's residual depends on the shared values and its own). 95 %
intervals from that Jacobian with the residual's variance, inflated for its lag-1 autocorrelation
(each record's effective samples n (1 - rho) / (1 + rho) summed; ``bounce_ends.covariance``),
Student's t; shared values ``held`` are given, not fitted, and the others' intervals are then
conditional on them. The window does not identify the spring: on the shared slams the cost is flat
from 0.45 to 0.73 x (113.6, 114.9, 115.6), the spring trading with the rebound coefficients
(correlation 0.90-0.99), so every interval is wide. A record whose window the replay
cannot follow (RMS over ``MAX_RELATIVE_RMS`` of its rise) or a value at its bound is said in the
line and the entry (``"refused"``), not hidden.

The spring from the ring-down's period (``spring_from_periods``, ``read_records``' ``"ring_spring"``).
The spring's information is in the free oscillation after the first rebound, outside the window. Each
record's free half periods (``bounce_decay.extrema``, vertex times) are set against the same half cycles
(those starting at the same turning point after the slam, ``Extrema.first_turn``) of its whole-trace
replay's run at each of ``RING_SCALES`` (its push, damper and friction; ``RING_AFTER_S`` past the peak);
over the halves two neighbouring scales both simulate (a record's half the simulation lacks is left out
and said), the mean log ratio is interpolated to 0 in log scale, its 95 % interval the ratios' scatter
(Student's t) through the slope. The run borrows the whole-trace replay's friction and one damper: on the
test file's generator those are off (64 and 0 N for 30) and read its spring 15 % low (0.52 x with its
friction given; docs/identification.md).
``read_records`` holds that spring in :func:`fit` and carries its interval into the others'
(``held_ci95``: linearised, added in quadrature); ``"spring_from"`` says which. Then the spring is read
again on the free ring-downs with a friction of its own and a scale on this fit's dampers
(``bounce_ring.from_slam_rebound``, ``"ring_fit"``): the spring, friction and compression the rebound
dampers take (``bounce_rebound``); this fit is not refitted at it. On the shared slams:
0.46 x [0.33, 0.64] from 6 of 7 halves, and the rebound coefficients 1794 [0, 4938], 4418 [953, 7883],
6754 [4051, 9456] N s/m at 0, 8, 17 clicks (the 0-click interval still reaches 0); on the test file's
generator 0.47 x [0.36, 0.60] for 0.55 x (docs/identification.md).
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.identify.bounce import BounceError, first_rebound, interval95, lag1, record_name
from mtbmj.identify.bounce_ends import correlations, covariance
from mtbmj.identify.bounce_replay import BOUNDS, MAX_RELATIVE_RMS, NAMES, PUSH_NAMES, Slam

SHARED = ("spring_scale", "compression_N_s_per_m")
OWN = PUSH_NAMES + ("rebound_N_s_per_m",)
LIMITS = {**BOUNDS, "compression_N_s_per_m": BOUNDS["damper_N_s_per_m"],
          "rebound_N_s_per_m": BOUNDS["damper_N_s_per_m"]}
CYCLE = False  # the window runs one whole cycle, to the record's second peak (False: to the first rest crossing)
Z95 = 1.959963984540054
STEP = 1e-3  # the forward difference's step, in each value's scale
MAX_NFEV = 30
RING_SCALES = (0.25, 0.35, 0.45, 0.55, 0.65, 0.75, 0.9)  # the spring scales the ring-down is simulated at
RING_AFTER_S = 2.5  # ... for this long after the slam's peak (the records' free halves end within ~1.5 s)
RING_METHOD = ("each record's free half periods after the slam (bounce_decay.extrema, vertex times) against the same "
               "half cycles (those starting at the same turning point after the slam) of its whole-trace replay's run "
               "(its push, damper and friction) at each spring scale tried; the mean log ratio over the halves "
               "simulated at two neighbouring scales interpolated to 0 in log scale; 95 % from the ratios' scatter "
               "at that scale (Student's t, n - 1) through the slope")
START = {"spring_scale": 0.5, "compression_N_s_per_m": 4000.0, "rebound_N_s_per_m": 2000.0}
METHOD = ("the slam and its first rebound (to the record's rest level) of every record replayed on the seated "
          "MuJoCo bike together: one spring scale and one compression coefficient shared, a push (lift and slam "
          "lobes) and a rebound coefficient per record, the friction given; least squares, 95 % intervals from "
          "the Jacobian inflated for the residual's lag-1 autocorrelation")


def window_end(sl: Slam, cycle: bool = CYCLE) -> float:
    """The time (s from the peak) where the record's first rebound first reaches its rest before the slam
    (``cycle``: the record's next peak after that, one whole cycle)."""
    g, x = sl.grid, sl.rec_g
    after = np.nonzero((g > 0.0) & (x <= 0.0))[0]
    if after.size == 0:
        raise BounceError(f"{sl.name}: the first rebound never reaches the rest before the slam within the record")
    i = int(after[0])
    if not cycle:
        return float(g[i])
    step = float(g[1] - g[0])
    trough = i + int(np.argmin(x[i:i + int(round(0.3 / step))]))  # the first trough within 0.3 s
    return float(g[trough + int(np.argmax(x[trough:trough + int(round(0.5 / step))]))])  # the next peak


class _Pool:
    """The values of all records in one vector: SHARED first, then each record's OWN."""

    def __init__(self, slams, friction_N: float, starts: list[dict]):
        self.slams, self.friction = slams, float(friction_N)
        self.ends = [window_end(sl) for sl in slams]
        self.masks = [sl.grid <= e for sl, e in zip(slams, self.ends)]
        names = list(SHARED) + [f"{i}:{k}" for i in range(len(slams)) for k in OWN]
        self.names = names
        x0 = [starts[0].get(k, START[k]) for k in SHARED]
        for sl, st in zip(slams, starts):
            x0 += [st.get(k, sl.x0[NAMES.index(k)]) if k in NAMES else st.get(k, START[k]) for k in OWN]
        self.lower = np.array([LIMITS[n.split(":")[-1]][0] for n in names])
        self.upper = np.array([LIMITS[n.split(":")[-1]][1] for n in names])
        self.x0 = np.clip(np.array(x0, float), self.lower + 1e-9, self.upper - 1e-9)
        self.base = np.array([0.1 if n.endswith(("start_s", "end_s")) else max(abs(v), 0.05)
                              for n, v in zip(names, self.x0)])

    def index(self, i: int) -> np.ndarray:
        """Record ``i``'s columns: the shared ones and its own."""
        own = len(SHARED) + i * len(OWN) + np.arange(len(OWN))
        return np.concatenate((np.arange(len(SHARED)), own))

    def values(self, x, i: int) -> dict:
        own = dict(zip(OWN, x[self.index(i)[len(SHARED):]]))
        return {**{k: own[k] for k in PUSH_NAMES}, "spring_scale": x[0], "compression_N_s_per_m": x[1],
                "damper_N_s_per_m": own["rebound_N_s_per_m"], "friction_N": self.friction}

    def run(self, x, i: int):
        """Record ``i``'s replay at ``x``: its stroke less its start on the grid (None: diverged)."""
        sl = self.slams[i]
        sl.sr.set_rest(sl.rest, None)
        try:
            out = sl.sr.run(self.values(x, i))
        except BounceError:
            return None
        return np.interp(sl.grid, out["time_s"], out["stroke_mm"] - out["stroke_mm"][0])

    def part(self, x, i: int) -> np.ndarray:
        sl, m = self.slams[i], self.masks[i]
        s = self.run(x, i)
        return np.full(int(m.sum()), 10.0 * sl.rise) if s is None else (s - sl.rec_g)[m]

    def residual(self, x) -> np.ndarray:
        return np.concatenate([self.part(x, i) for i in range(len(self.slams))])

    def jacobian(self, x, r=None, cols=None) -> np.ndarray:
        """d residual / d x[cols] (all by default), record by record (each record's rows depend on its
        columns only)."""
        cols = np.arange(x.size) if cols is None else np.asarray(cols)
        sizes = [int(m.sum()) for m in self.masks]
        J = np.zeros((sum(sizes), x.size))
        row = 0
        for i, n in enumerate(sizes):
            r0 = self.part(x, i) if r is None else r[row:row + n]
            for j in np.intersect1d(self.index(i), cols):
                h = STEP * self.base[j] * (-1.0 if x[j] + STEP * self.base[j] > self.upper[j] else 1.0)
                xj = x.copy()
                xj[j] += h
                J[row:row + n, j] = (self.part(xj, i) - r0) / h
            row += n
        return J[:, cols]


def fit(slams, clicks, friction_N: float, starts: list[dict] | None = None, max_nfev: int = MAX_NFEV,
        held: dict | None = None, held_ci95: list | None = None) -> dict:
    """The slams' (``bounce_replay.prepare_slam``; one ``SeatedReplay`` each is safest) shared spring and
    compression and each one's rebound coefficient (module docstring): {"spring_scale", ...,
    "records": [per record], "rises", "line"}. ``held``: shared values given instead of fitted (their
    interval then 0 wide: the others' are conditional on them); ``held_ci95``: the held spring's 95 %
    interval, carried into the others' (linearised) and reported as the spring's."""
    from scipy.optimize import least_squares

    held = held or {}
    starts = [{**st, **held} for st in (starts or [{} for _ in slams])]
    pool = _Pool(slams, friction_N, starts)
    base, x0 = pool.base, pool.x0
    free = np.array([j for j, n in enumerate(pool.names) if n not in held])
    lo, hi = (pool.lower - x0) / base, (pool.upper - x0) / base

    def full(v):
        u = np.zeros(x0.size)
        u[free] = v
        return x0 + u * base

    sol = least_squares(lambda v: pool.residual(full(v)), np.zeros(free.size), bounds=(lo[free], hi[free]),
                        jac=lambda v: pool.jacobian(full(v), cols=free) * base[free], max_nfev=max_nfev)
    x = full(sol.x)
    r = pool.residual(x)
    J = np.zeros((r.size, x.size))
    J[:, free] = pool.jacobian(x, r, cols=free)
    sizes = [int(m.sum()) for m in pool.masks]
    parts = np.split(r, np.cumsum(sizes)[:-1])
    # the effective samples summed over the records (each its own lag-1), as one equivalent rho
    n_eff = sum(p.size * (1 - lag1(p)) / (1 + lag1(p)) for p in parts)
    rho = (r.size - n_eff) / (r.size + n_eff)
    cov_free, tq = covariance(r, J[:, free], rho)
    cov = np.zeros((x.size, x.size))
    cov[np.ix_(free, free)] = cov_free
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0)) * tq
    out_held = {}
    if held_ci95 and "spring_scale" in held:
        # the spring's interval carried into the others': each value's derivative on the spring at the
        # solution, dx/ds = -(J^T J)^-1 J^T J_s (J_s one more Jacobian column), times the spring's 95 %
        # half-width (the wider side), added in quadrature to the conditional 95 % half-width
        js = pool.jacobian(x, r, cols=[0])[:, 0]
        g = -np.linalg.lstsq(J[:, free], js, rcond=None)[0]
        half = max(held["spring_scale"] - held_ci95[0], held_ci95[1] - held["spring_scale"])
        sd[free] = np.hypot(sd[free], g * half / Z95)  # sd here is a 95 % half-width over Z95
        sd[0] = half / Z95
        out_held = {"d_value_d_spring": {pool.names[j]: float(v) for j, v in zip(free, g)
                                         if pool.names[j].split(":")[-1] in SHARED + ("rebound_N_s_per_m",)}}
    out = _summary(pool, x, sd, parts, clicks, cov, sol)
    if out_held:
        out["spring_scale_ci95"] = [float(held_ci95[0]), float(held_ci95[1])]
        out.update(out_held)
        out["line"] = line(out)
    return out


def _ci(v, s, floor=None):
    lo, hi = interval95(v, s)
    return [lo if floor is None else max(lo, floor), hi]


def _summary(pool, x, sd, parts, clicks, cov, sol) -> dict:
    at_bound = [n for n, v, lo, hi in zip(pool.names, x, pool.lower, pool.upper)  # the shock's values only
                if (hi - v < 1e-3 * (hi - lo) or v - lo < 1e-3 * (hi - lo))
                and n.split(":")[-1] in SHARED + ("rebound_N_s_per_m",)]
    out = {"method": METHOD, "friction_N": pool.friction, "runs": int(sol.nfev), "cost": float(sol.cost)}
    for j, k in enumerate(SHARED):
        out[k] = float(x[j])
        out[k + "_ci95"] = _ci(x[j], sd[j], 0.0)
    out["correlation"] = {k: v for k, v in correlations(cov, pool.names).items()
                          if not any(p.split(":")[-1] in PUSH_NAMES for p in k.split("|"))}
    recs = []
    for i, (sl, k, res) in enumerate(zip(pool.slams, clicks, parts)):
        idx = pool.index(i)[len(SHARED):]
        own = dict(zip(OWN, x[idx]))
        e = {"file": sl.name, "clicks": k, "window_end_s": pool.ends[i],
             "rms_mm": float(math.sqrt(float(np.mean(res ** 2)))), "slam_rise_mm": sl.rise}
        j = idx[OWN.index("rebound_N_s_per_m")]
        e["rebound_N_s_per_m"] = float(x[j])
        e["rebound_N_s_per_m_ci95"] = _ci(x[j], sd[j], 0.0)
        e["push"] = {kk: float(own[kk]) for kk in PUSH_NAMES}
        s = pool.run(x, i)
        g = sl.grid
        e["replay_peak"] = _peak(g, s)
        e["record_peak"] = _peak(g, sl.rec_g)
        rb = first_rebound(g, s, int(np.argmax(np.where(np.abs(g) < 0.1, s, -np.inf))), 0.0)
        e["replay_mid_rebound_speed_mm_per_s"] = rb["mid_rebound_speed_mm_per_s"]
        e["trace"] = {"time_s": g, "record_mm": sl.rec_g, "replay_mm": s}
        if e["rms_mm"] > MAX_RELATIVE_RMS * sl.rise:
            e["refused"] = (f"{sl.name}: the replay cannot follow the slam and its first rebound: RMS {e['rms_mm']:.1f} "
                            f"mm of a {sl.rise:.1f} mm slam")
        recs.append(e)
    for n in at_bound:
        out.setdefault("at_bound", []).append(n)
    out["records"] = sorted(recs, key=lambda e: e["clicks"])
    out["rises"] = rises(out["records"]) if not at_bound else None
    out["line"] = line(out)
    return out


def _peak(g, s) -> dict:
    p = int(np.argmax(np.where(np.abs(g) < 0.15, s, -np.inf)))
    return {"time_s": float(g[p]), "above_rest_mm": float(s[p])}


def rises(records) -> bool | None:
    """Whether the rebound coefficients rise with the clicks, each interval above the one before's value
    and clear of 0 (None with fewer than two read records)."""
    read = [e for e in records if "refused" not in e]
    if len(read) < 2:
        return None
    ok = all(e["rebound_N_s_per_m_ci95"][0] > 0.0 for e in read)
    return ok and all(b["rebound_N_s_per_m"] > a["rebound_N_s_per_m"] for a, b in zip(read, read[1:]))


def line(out: dict) -> str:
    def said(e):
        if "refused" in e:
            return f"refused at {e['clicks']:g} clicks ({e['refused']})"
        lo, hi = e["rebound_N_s_per_m_ci95"]
        return f"{e['rebound_N_s_per_m']:.0f} [{lo:.0f}, {hi:.0f}] at {e['clicks']:g} clicks (RMS {e['rms_mm']:.2f} mm)"

    (slo, shi), (clo, chi) = out["spring_scale_ci95"], out["compression_N_s_per_m_ci95"]
    verdict = {True: "they rise with the clicks, every interval clear of 0",
               None: "not read" + (f" ({', '.join(out['at_bound'])} at a bound)" if out.get("at_bound") else ""),
               False: "they do not rise with the clicks (or an interval reaches 0)"}[out["rises"]]
    return (f"slam and first rebound fitted together (spring {out['spring_scale']:.2f} x [{slo:.2f}, {shi:.2f}], "
            f"compression {out['compression_N_s_per_m']:.0f} N s/m [{clo:.0f}, {chi:.0f}] shared, friction "
            f"{out['friction_N']:.0f} N given): rebound {'; '.join(said(e) for e in out['records'])} N s/m: {verdict}")


def _halves(t, x, peak: int) -> list:
    """The free half periods after the slam at ``peak`` (``bounce_decay.extrema``, vertex times:
    ``bounce_predict.timed_halves``), as the ring-down readings take them, each led by its place: the
    turning point it starts from, counted from the slam's peak (1: the first after it)."""
    from mtbmj.identify import bounce_decay as bd
    from mtbmj.identify import bounce_predict as bp

    t, x = np.asarray(t, float), np.asarray(x, float)
    seq = bd.extrema(t, x, "shock", peak)
    return [(seq.first_turn + j, *h) for j, h in enumerate(bp.timed_halves(seq, t, x))]


def _matched(rec: list, sim: list) -> list:
    """log(simulated / recorded) of the same half cycles: the one starting at the same turning point after
    the slam in both (a first trough at the top-out is left out of one trace and not the other, so the
    k-th free half of a direction need not be the same half cycle); None where the simulation has none."""
    by_turn = {q[0]: q for q in sim}
    out = []
    for q in rec:
        s = by_turn.get(q[0])
        out.append(math.log(s[4] / q[4]) if s is not None and s[1] == q[1] else None)
    return out


def spring_from_periods(rings, scales=RING_SCALES) -> dict:
    """The spring scale whose simulated ring-down has the records' free half periods (module docstring,
    "The spring from the ring-down's period"). ``rings``: per record (name, time_s, shock_mm, slam, values),
    ``slam`` a ``prepare_slam`` result and ``values`` its replay's (``NAMES``; the spring is replaced).
    {"spring_scale", "spring_scale_ci95", "halves", "mean_log_ratio" per scale, "line"} or {"refused"}."""
    from mtbmj.identify.bounce import find_slam

    rows = {}  # scale -> every record's matched log ratios (None: the simulated ring-down has too few halves)
    n_rec = 0
    for name, t, x, sl, v in rings:
        rec = _halves(t, x, find_slam(np.asarray(t, float), np.asarray(x, float), name))
        n_rec += len(rec)
        for sc in scales:
            sl.sr.set_rest(sl.rest, None)
            try:
                out = sl.sr.run({**v, "spring_scale": sc}, after_s=RING_AFTER_S)
                sim = _halves(out["time_s"], out["stroke_mm"], int(np.argmin(np.abs(out["time_s"]))))
            except BounceError:
                sim = []
            rows.setdefault(sc, []).extend(_matched(rec, sim))
    scales = sorted(rows)
    matched = {sc: {i for i, q in enumerate(rows[sc]) if q is not None} for sc in scales}
    means = {sc: float(np.mean([rows[sc][i] for i in matched[sc]])) if matched[sc] else None for sc in scales}
    base = {"halves": n_rec, "mean_log_ratio": {f"{sc:g}": means[sc] for sc in scales}, "method": RING_METHOD}
    pair, keep = None, []
    for a, b in zip(scales, scales[1:]):  # the halves both scales simulate, the same on either side of the root
        keep = sorted(matched[a] & matched[b])
        if len(keep) >= 2 and np.mean([rows[a][i] for i in keep]) >= 0.0 >= np.mean([rows[b][i] for i in keep]):
            pair = (a, b)
            break
    if pair is None:
        why = (f"{n_rec} free half period(s) in the records" if n_rec < 2 else
               "no two spring scales tried bracket the records' half periods (two halves or more simulated at both)")
        return {**base, "refused": f"the spring from the ring-down's period not read: {why}",
                "line": f"spring from the ring-down's period not read: {why}"}
    a, b = pair
    ra, rb = np.array([rows[a][i] for i in keep]), np.array([rows[b][i] for i in keep])
    la, lb = math.log(a), math.log(b)
    slope = (rb.mean() - ra.mean()) / (lb - la)  # d mean log ratio / d log scale (about -1/2)
    u = -ra.mean() / (rb.mean() - ra.mean())
    ls = la + u * (lb - la)
    d = (1 - u) * ra + u * rb  # each half's misfit at the root
    from scipy.stats import t as student

    half = float(student.ppf(0.975, d.size - 1)) * float(np.std(d, ddof=1)) / math.sqrt(d.size)
    lo, hi = sorted((math.exp(ls - half / slope), math.exp(ls + half / slope)))
    spring = math.exp(ls)
    left = n_rec - len(keep)
    return {**base, "spring_scale": spring, "spring_scale_ci95": [lo, hi], "halves_matched": len(keep),
            "line": (f"spring from the ring-down's period: {spring:.2f} x [{lo:.2f}, {hi:.2f}] ({len(keep)} free half "
                     f"periods of {len(rings)} records matched on the MuJoCo bike between {a:g} and {b:g} x"
                     + (f"; {left} of the records' halves not simulated there, left out" if left else "") + ")")}


def read_records(records, clicks, replayed: list, bike="sst", rider_hz: float | None = None,
                 ring_fit: bool = True) -> dict | None:
    """``fit bounce --replay``'s ``"slam_rebound"``: the records' slams (each on a seated bike of its own)
    fitted together, the friction and the starting spring from the best-determined whole-trace replay
    (``replayed``: ``bounce_replay.replay_records``' summary; the narrowest spring interval), each
    record's push started from its own replay (or the best one's). ``ring_fit``: then the spring,
    friction and a scale on these dampers read from the free ring-downs (``bounce_ring.from_slam_rebound``,
    ``"ring_fit"``: the spring the rebound dampers take). None when no record was replayed."""
    from mtbmj.identify.bounce_replay import RIDER_HZ, SeatedReplay, prepare_slam

    done = [e for e in replayed if "refused" not in e]
    if not done:
        return None
    best = min(done, key=lambda e: e["spring_scale_ci95"][1] - e["spring_scale_ci95"][0])
    by_file = {e["file"]: e for e in done}
    slams, ks, starts, refused, rings = [], [], [], [], []
    for rec, k in zip(records, clicks):
        name = record_name(rec)
        sr = SeatedReplay(bike, RIDER_HZ if rider_hz is None else rider_hz)
        own = by_file.get(name, best)
        try:
            slams.append(prepare_slam(rec.time_s, rec.shock_mm, rec.fork_mm, name, sr,
                                      getattr(rec, "shock_max_mm", None),
                                      start={kk: own[kk] for kk in NAMES}))
        except BounceError as e:
            refused.append({"file": name, "clicks": k, "refused": str(e)})
            continue
        ks.append(k)
        starts.append({**{kk: own[kk] for kk in PUSH_NAMES}, "spring_scale": best["spring_scale"]})
        rings.append((name, rec.time_s, rec.shock_mm, slams[-1], {kk: own[kk] for kk in NAMES}))
    if len(slams) < 1:
        return None
    ring = spring_from_periods(rings)
    if "refused" in ring:
        out = fit(slams, ks, best["friction_N"], starts)
        out["spring_from"] = "fitted on the window (" + ring["refused"] + ")"
    else:
        out = fit(slams, ks, best["friction_N"], starts, held={"spring_scale": ring["spring_scale"]},
                  held_ci95=ring["spring_scale_ci95"])
        out["spring_from"] = "the ring-down's period"
    out["ring_spring"] = ring
    out["line"] = ring["line"] + "; " + out["line"]
    if ring_fit:  # the spring read again on the ring-down with its own friction and these dampers (bounce_ring)
        from mtbmj.identify.bounce_ring import from_slam_rebound

        out["ring_fit"] = from_slam_rebound(rings, out)
        out["line"] += "; " + out["ring_fit"]["line"]
    out["from"] = best["file"]
    out["records"] = sorted(out["records"] + refused, key=lambda e: e["clicks"])
    return out


def public(out: dict | None) -> dict | None:
    """fit.json's ``"slam_rebound"``: ``out`` without the traces (they are in slam_rebound.png)."""
    if out is None:
        return None
    return {**out, "records": [{k: v for k, v in e.items() if k != "trace"} for e in out["records"]]}


def figure_png(out: dict) -> bytes:
    """slam_rebound.png: per record, the record's slam and first rebound beside the replay fitted on it."""
    from matplotlib.figure import Figure

    from mtbmj.readout.quicklook import png

    shown = [e for e in out["records"] if "trace" in e]
    fig = Figure(figsize=(9.5, 2.6 * max(len(shown), 1)))
    axes = fig.subplots(max(len(shown), 1), 1, squeeze=False)
    for ax, e in zip(axes[:, 0], shown):
        tr = e["trace"]
        ax.plot(tr["time_s"], tr["record_mm"], "k", lw=1.6, label="record: shock")
        ax.plot(tr["time_s"], tr["replay_mm"], "C3", lw=1.2, label="replay (fitted up to the window's end)")
        ax.axvline(e["window_end_s"], color="0.5", ls="--", lw=0.8)
        lo, hi = e["rebound_N_s_per_m_ci95"]
        ax.set_title(f"{e['file']} at {e['clicks']:g} clicks: rebound {e['rebound_N_s_per_m']:.0f} N s/m "
                     f"[{lo:.0f}, {hi:.0f}]; peak {e['replay_peak']['above_rest_mm']:.1f} mm at "
                     f"{1e3 * e['replay_peak']['time_s']:.0f} ms (record {e['record_peak']['above_rest_mm']:.1f} "
                     f"at {1e3 * e['record_peak']['time_s']:.0f}); RMS {e['rms_mm']:.2f} mm"
                     + (" REFUSED" if "refused" in e else ""), fontsize=8)
        ax.set_xlim(-0.35, e["window_end_s"] + 0.25)
        ax.set_ylabel("travel above rest (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time from the slam's peak (s); dashed: the fitted window's end")
    fig.suptitle(f"shared: spring {out['spring_scale']:.2f} x ({out.get('spring_from', 'fitted')}), compression {out['compression_N_s_per_m']:.0f} N s/m, "
                 f"friction {out['friction_N']:.0f} N (given)", fontsize=9)
    fig.tight_layout()
    return png(fig, dpi=80)


__all__ = ["METHOD", "figure_png", "fit", "public", "read_records", "rises", "spring_from_periods", "window_end"]

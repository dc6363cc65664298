"""The spring read from the seat slams' free ring-downs through the bike with a friction and dampers of its
own (``fit bounce --replay``'s ``"ring_fit"``): the spring scale, the Coulomb friction and a scale on the
dampers given fitted together on the free half cycles' durations and swing ratios.

Why. ``bounce_slam_rebound.spring_from_periods`` reads the spring from the free half periods alone, on
a ring-down simulated with the whole-trace replay's friction and one damper both ways. Those are off
(on the tests' generator 64 and 0.25 N for its 30, 1888 and 3742 N s/m both ways for 2500 in compression
and 2500 / 5000 in rebound), and since a 2-3 half ring-down's halves move only about 0.3 x the log
spring, the 5 % they shift the periods is a 15 % spring. Friction and viscous damping leave different
signatures in the amplitudes (Feeny and Liang, J. Sound Vib. 195(1), 1996; Den Hartog 1931): with dry
friction F alone the swing loses a constant amount each half cycle, with viscous damping alone it keeps
a constant share. So the swings read the friction and the damping, and the periods then the spring.

Method. Per record, a push and the dampers given (``fit``'s ``rings``; ``from_slam_rebound``: the
slam-and-first-rebound fit's push, compression and rebound coefficients), the MuJoCo bike run
``RING_AFTER_S`` past the slam's peak. Its turning points (``bounce_decay.extrema``, vertex times as
``bounce_predict.vertex_time``; the slam's peak is turning point 0) set against the record's
(``residuals``): per half cycle of the record (the slam's peak to the first turning point left out),
the log ratio of the same half cycle's duration (by its turning point after the slam,
``Extrema.first_turn``) over ``PERIOD_SD``; per two successive half cycles of the record, its swing
ratio (the second swing over the first) less the simulation's at the same first swing and direction
(``swing_ratio_at``: a friction ratio depends on the swing, so the two are compared at the same swing;
no rest level needed, which the shared records' rider moves after the slam) over ``RATIO_SD``. A half
or pair the simulation lacks (it stuck sooner) keeps its place, and the residual moves smoothly where a
value tried sticks the simulation a half cycle sooner or later: a missing half against the simulation's
nearest half cycle, a missing pair's ratio from the simulation's own swing decrement law s2 = alpha s1 -
beta (``swing_ratio_at``; a linear oscillator with Coulomb friction keeps it, Den Hartog), down to 0 where
it leaves no swing; 0 only where the simulation has no pair at all. (Before, a missing half read 0 and a
missing pair the last pair's ratio: a jump of hundreds in the sum of squares where the simulation stuck a
half sooner, and the least squares stayed in a local minimum on a dry ring-down.) The values
(``fitted``: log spring scale, friction, log dampers' scale; any ``held``) by
``scipy.optimize.least_squares`` (forward differences), started from the best point of the grid
``SPRING_STARTS`` by ``FRICTION_STARTS`` by ``DAMPER_STARTS`` (of those fitted). 95 % intervals from the
Jacobian with the residual's variance (Student's t at n - p). With the friction and the dampers' scale
both fitted, three models (``MODELS``) are fitted, each from its own grid: viscous only (friction held
0), friction only (the dampers' scale held 0) and both (started also from the other two's answers with
the value each held at its ``START``, the lowest sum of squares kept), and one chosen by the
small-sample Akaike criterion (``aicc``, the residual's variance unknown: its sd scales are not known
well enough for a chi-square); ``"model"`` says which, and
the line says it with each model's AICc and, where it is not both, the chosen model's values. The values
and intervals given (and taken by ``from_slam_rebound``) stay both's: a model with the dampers at 0 would
give the rebound fits no compression. Refused, with its reason and the values it stopped at, with n <= p
residuals, or where the bike does not follow the records (RMS over ``MAX_RMS_SD`` sd, or more than
``MAX_MISSING`` of the halves and pairs missing).

Measured (docs/identification.md): the tests' generator at 0.55 x read 0.54 x [0.52, 0.57] and 0.59 x
[0.52, 0.67] on two pairs of slams before the model choice (the periods alone 0.47 and 0.53 x); its
friction-only slam (80 N) chosen friction only, 85 N [73, 96], its viscous-only one viscous only; the
closed form's dry ring-down (150 N) read at 150 N [147, 153]; the shared slams refused (6.0 sd, every
model: their ring-downs start after the top-out, which the bike pushed so does not follow).
"""
from __future__ import annotations

import itertools
import math

import numpy as np

from mtbmj.identify.bounce import BounceError, find_slam

RING_AFTER_S = 2.5
PERIOD_SD = 0.01  # a half period's relative scatter about its model (the records' 1.2-2.1 %, docs/identification.md)
RATIO_SD = 0.03  # a swing ratio's scatter (the swing's vertex levels, a few tenths of a mm of 10-40 mm)
FITTED = ("spring_scale", "friction_N")
LIMITS = {"spring_scale": (0.2, 3.0), "friction_N": (0.0, 400.0), "damper_scale": (0.05, 20.0),
          "compression_scale": (0.05, 20.0), "rebound_scale": (0.05, 20.0)}
START = {"spring_scale": 0.5, "friction_N": 30.0, "damper_scale": 1.0, "compression_scale": 1.0, "rebound_scale": 1.0}
LOG = ("spring_scale", "damper_scale", "compression_scale", "rebound_scale")  # fitted in log
STEP = 0.01  # forward-difference step in the scaled value
MAX_NFEV = 40
SPRING_STARTS = (0.3, 0.4, 0.5, 0.6, 0.75, 0.9)
FRICTION_STARTS = (1.0, 15.0, 30.0, 60.0, 120.0, 240.0)  # N: the fit starts from the best of these and
DAMPER_STARTS = (0.25, 0.5, 1.0, 2.0)  # the dampers' scales (where fitted; the others at START): a friction
# that sticks the simulation sooner than the record leaves its halves missing, where the residual is flat
# or jumps, and a fit started there stays
MAX_RMS_SD = 3.0  # the fit's residuals' RMS (in their sd) over this: the bike does not follow the ring-downs, refused
MAX_MISSING = 1 / 3  # ... or more than this share of the records' halves and pairs has none in the simulation
PEAK_WINDOW_S = 0.1
METHOD = ("the records' free half cycles after the slam against the MuJoCo bike's run with each record's push and the "
          "dampers given: each half's log duration ratio against the same half cycle (by turning point after the "
          "slam's peak; sd 1 %) and each two successive halves' swing ratio against the bike's at the same swing "
          "(sd 0.03), a half or pair the simulation lacks against its nearest half and its swing decrement law; the "
          "spring scale, Coulomb friction and a scale on the dampers fitted by least squares from the best point of "
          "a grid, 95 % from the Jacobian (Student's t, n - p); viscous only, friction only and both fitted apart "
          "and one chosen by AICc")


def turning_points(t, x, peak: int) -> list:
    """The slam's peak and the free turning points after it: [(turn, level_mm, time_s)], turn 0 the peak,
    then ``Extrema.first_turn`` onwards (a stuck level's time nan), times the vertex times
    (``bounce_predict.vertex_time``)."""
    from mtbmj.identify import bounce_decay as bd
    from mtbmj.identify import bounce_predict as bp

    t, x = np.asarray(t, float), np.asarray(x, float)
    dt = float(t[1] - t[0])
    w = max(int(round(PEAK_WINDOW_S / dt)), 1)
    lo = max(peak - w, 0)
    p = lo + int(np.argmax(x[lo:peak + w + 1]))
    out = [(0, float(x[p]), float(t[p]))]
    seq = bd.extrema(t, x, "shock", peak)
    times = seq.times_s
    fin = times[np.isfinite(times)]
    half0 = float(np.median(np.diff(fin))) if fin.size >= 2 else 0.3
    for j, (lv, ti) in enumerate(zip(seq.levels_mm, times)):
        tv = bp.vertex_time(t, x, ti, half0)[0] if np.isfinite(ti) else float("nan")
        out.append((seq.first_turn + j, float(lv), float(tv)))
    return out


def _pairs(tp: list) -> list:
    """Two successive half cycles of turning points ``tp``: (first swing, second over first, the second's
    direction: +1 compression, -1 rebound), where the three turning points are consecutive."""
    by = {q[0]: q for q in tp}
    out = []
    for a in sorted(by):
        if a + 1 in by and a + 2 in by:
            s1 = abs(by[a + 1][1] - by[a][1])
            s2 = abs(by[a + 2][1] - by[a + 1][1])
            if s1 > 0.0:
                out.append((s1, s2 / s1, 1 if by[a + 2][1] > by[a + 1][1] else -1, a))
    return out


def _decrement_law(pairs: list) -> tuple[float, float] | None:
    """The swing decrement law s2 = alpha s1 - beta least squares through the pairs (first swing, ratio):
    viscous damping gives alpha (beta 0), Coulomb friction beta (alpha 1), both together both (a linear
    oscillator's swings: s2 = r s1 - 2 (1 + r) F / k, Den Hartog); None from fewer than two distinct swings."""
    s1 = np.array([q[0] for q in pairs], float)
    if s1.size < 2 or np.ptp(s1) <= 1e-9 * max(float(np.max(s1)), 1.0):
        return None
    s2 = s1 * np.array([q[1] for q in pairs], float)
    alpha, c = np.polyfit(s1, s2, 1)
    return float(alpha), float(-c)


def swing_ratio_at(sim_pairs: list, swing: float, direction: int) -> float:
    """The simulation's swing ratio (second over first) at a first swing of ``swing`` mm into a half of
    ``direction``: interpolated in its own pairs of that direction by their first swing (a viscous ratio
    does not depend on the swing, a friction one does, so the record and the simulation are compared at
    the same swing, not at the same turning point); beyond them, the simulation's own swing decrement
    law (``_decrement_law`` on that direction's pairs, or on both directions' where one has fewer than
    two; a single pair's ratio held), down to 0 where that law leaves no swing (it sticks there); 0
    where the simulation has no pair at all (it stuck sooner: no swing). So the ratio moves smoothly
    where a value tried sticks the simulation a half cycle sooner or later, not by the jump from the
    last pair's ratio to nothing."""
    own = sorted((s1, r) for s1, r, d, _ in sim_pairs if d == direction)
    every = sorted((s1, r) for s1, r, d, _ in sim_pairs)
    if not every:
        return 0.0
    if own and own[0][0] <= swing <= own[-1][0]:
        return float(np.interp(swing, [q[0] for q in own], [q[1] for q in own]))
    law = _decrement_law(own) or _decrement_law(every)
    if law is None:
        return float((own or every)[0][1])
    alpha, beta = law
    return float(max(alpha - beta / max(swing, 1e-9), 0.0))


def residuals(rec: list, sim: list) -> tuple[np.ndarray, dict]:
    """The scaled residuals of the record's turning points ``rec`` against the simulation's ``sim`` (each
    ``turning_points``), one per half cycle and per two successive halves of the record, so their number
    is the record's whatever the simulation does: a half's log duration ratio, the same half cycle (by
    turning point) in both (the slam's peak to the first turn left out: the push ends there), 0 where
    the simulation lacks it (it stuck sooner, or topped out where the record did not); two successive
    halves' swing ratio (the second swing over the first) less the simulation's at the same first swing
    and direction (``swing_ratio_at``), over RATIO_SD. ({"periods", "ratios", "missing"} counts)."""
    by = {q[0]: q for q in sim}
    have = {q[0]: q for q in rec}
    per, missing = [], 0
    halves = {a: by[a + 1][2] - by[a][2] for a in by if a > 0 and a + 1 in by
              and np.isfinite(by[a][2]) and np.isfinite(by[a + 1][2]) and by[a + 1][2] > by[a][2]}
    for a in sorted(have):
        b = a + 1
        if b not in have:
            continue
        ra, rb = have[a], have[b]
        if a > 0 and np.isfinite(ra[2]) and np.isfinite(rb[2]) and rb[2] > ra[2]:
            dur = halves.get(a)
            if dur is None and halves:  # the simulation's nearest half cycle (the later one on a tie)
                dur = halves[min(halves, key=lambda j: (abs(j - a), -j))]
            per.append(math.log(dur / (rb[2] - ra[2])) / PERIOD_SD if dur is not None else 0.0)
            missing += 0 if a in halves else 1
    sp = _pairs(sim)
    rat = []
    for s1, r, d, _ in _pairs(rec):
        if not any(q[2] == d for q in sp):
            missing += 1
        rat.append((swing_ratio_at(sp, s1, d) - r) / RATIO_SD)
    return np.array(per + rat, float), {"periods": len(per), "ratios": len(rat), "missing": missing}


def _values(x, names, held):
    v = dict(held)
    for k, u in zip(names, x):
        v[k] = math.exp(u) if k in LOG else u
    return v


def _record_points(ring) -> list:
    """The record's turning points (``turning_points`` from its slam's peak)."""
    name, t, x = ring[:3]
    t, x = np.asarray(t, float), np.asarray(x, float)
    return turning_points(t, x, find_slam(t, x, name))


def _run(ring, v) -> list:
    """The simulation's turning points at values ``v`` (the MuJoCo bike pushed as given, ``RING_AFTER_S``
    past the peak; none when it leaves its envelope)."""
    name, t, xr, sl, push, damp = ring
    sc = v.get("damper_scale", 1.0)
    p = {**push, "spring_scale": v["spring_scale"], "friction_N": v["friction_N"],
         "damper_N_s_per_m": sc * v.get("rebound_scale", 1.0) * damp["rebound_N_s_per_m"],
         "compression_N_s_per_m": sc * v.get("compression_scale", 1.0) * damp["compression_N_s_per_m"]}
    sl.sr.set_rest(sl.rest, None)
    try:
        out = sl.sr.run(p, after_s=RING_AFTER_S)
    except BounceError:
        return []
    return turning_points(out["time_s"], out["stroke_mm"], int(np.argmin(np.abs(out["time_s"]))))


MODELS = {"viscous": {"friction_N": 0.0}, "friction": {"damper_scale": 0.0}, "both": {}}
MODEL_WORDS = {"viscous": "viscous damping only", "friction": "Coulomb friction only",
               "both": "viscous damping and Coulomb friction"}
CRITERION = ("AICc: n ln(RSS / n) + 2 k + 2 k (k + 1) / (n - k - 1), n the residuals, RSS their sum of squares in "
             "their sd, k the values fitted and the residual's variance; the lowest chosen")


def aicc(rss: float, n: int, p: int) -> float:
    """The small-sample Akaike criterion of a least-squares fit of ``p`` values on ``n`` residuals whose
    sum of squares is ``rss`` (the variance fitted too: k = p + 1); inf where n - k - 1 <= 0."""
    k = p + 1
    if n - k - 1 <= 0:
        return math.inf
    return n * math.log(max(rss / n, 1e-12)) + 2 * k + 2 * k * (k + 1) / (n - k - 1)


def _fit_one(rings, recs, names, held, st, max_nfev, extra=()) -> dict:
    """One model's least squares (``fit``): ``names`` fitted, ``held`` given; started from the best point
    of the start grid of those fitted, and from each of ``extra`` (value dicts: the restricted models'
    answers), the lowest sum of squares kept."""
    from scipy.optimize import least_squares
    from scipy.stats import t as student

    def to_x(v):
        return np.array([math.log(max(v[k], LIMITS[k][0])) if k in LOG else v[k] for k in names])

    lo, hi = to_x({k: LIMITS[k][0] for k in names}), to_x({k: LIMITS[k][1] for k in names})
    scale = np.array([1.0 if k in LOG else 30.0 for k in names])
    counts = {}

    def res_x(x):
        v = _values(x, names, held)
        parts, n = [], {"periods": 0, "ratios": 0, "missing": 0}
        for ring, rec in zip(rings, recs):
            r, c = residuals(rec, _run(ring, v))
            parts.append(r)
            n = {k: n[k] + c[k] for k in n}
        counts.update(n)
        return np.concatenate(parts) if parts else np.zeros(0)

    starts = {"spring_scale": SPRING_STARTS, "friction_N": FRICTION_STARTS, "damper_scale": DAMPER_STARTS}
    base_v = {k: st[k] for k in names}
    grid = [(k, starts[k]) for k in names if k in starts]
    best = (math.inf, base_v, 0)  # (sum of squares, values, residuals) of the best grid point
    for point in (itertools.product(*(g for _, g in grid)) if grid else [()]):
        v = {**base_v, **dict(zip((k for k, _ in grid), point))}
        r = res_x(to_x(v))
        best = min(best, (float(r @ r), v, r.size), key=lambda q: q[0])
    n_res = best[2]
    out = {"halves_in_records": sum(max(len(q) - 2, 0) for q in recs)}
    if n_res <= len(names):
        why = f"{n_res} residual(s) from the records' free half cycles for {len(names)} value(s)"
        return {**out, "refused": f"the ring-down fit not read: {why}", "line": f"ring-down fit not read: {why}"}
    sol = None
    for v in [best[1]] + [{k: e.get(k, best[1][k]) for k in names} for e in extra]:
        x0 = np.clip(to_x(v), lo, hi)
        s = least_squares(lambda u: res_x(x0 + u * scale), np.zeros(len(names)),
                          bounds=((lo - x0) / scale, (hi - x0) / scale), diff_step=STEP, max_nfev=max_nfev,
                          x_scale=1.0)
        if sol is None or s.cost < sol[0].cost:
            sol = (s, x0)
    sol, x0 = sol
    r = res_x(x0 + sol.x * scale)
    J = sol.jac / scale[None, :]
    dof = r.size - len(names)
    rss = float(r @ r)
    try:
        cov = np.linalg.inv(J.T @ J) * rss / dof
    except np.linalg.LinAlgError:
        cov = np.linalg.pinv(J.T @ J) * rss / dof
    tq = float(student.ppf(0.975, dof))
    u = x0 + sol.x * scale
    out.update({"residual_counts": dict(counts), "rms_scaled": float(math.sqrt(rss / r.size)), "dof": dof,
                "runs": int(sol.nfev), "rss": rss, "n_residuals": int(r.size)})
    for j, k in enumerate(names):
        half = tq * math.sqrt(max(cov[j, j], 0.0))
        if not np.any(J[:, j]):  # the residual did not move with it: its interval is its whole range, not 0 wide
            out.setdefault("undetermined", []).append(k)
            out[k], out[k + "_ci95"] = (math.exp(u[j]) if k in LOG else float(u[j])), list(LIMITS[k])
            continue
        if k in LOG:
            out[k], out[k + "_ci95"] = math.exp(u[j]), [math.exp(u[j] - half), math.exp(u[j] + half)]
        else:
            out[k], out[k + "_ci95"] = float(u[j]), [max(float(u[j] - half), 0.0), float(u[j] + half)]
        span = LIMITS[k]
        if min(abs(out[k] - span[0]), abs(span[1] - out[k])) < 1e-3 * (span[1] - span[0]):
            out.setdefault("at_bound", []).append(k)
    for k, v in held.items():
        out.setdefault(k, v)
    miss = counts["missing"] / max(r.size, 1)
    if out["rms_scaled"] > MAX_RMS_SD or miss > MAX_MISSING:
        why = (f"the bike does not follow the records' free ring-downs: residual RMS {out['rms_scaled']:.1f} sd "
               f"(at most {MAX_RMS_SD:g}), {counts['missing']} of {r.size} halves and pairs missing in the simulation "
               f"(at most {MAX_MISSING:.0%}); at spring {out['spring_scale']:.2f} x")
        out["refused"] = f"the ring-down fit refused: {why}"
    return out


def fit(rings, fitted=FITTED, held: dict | None = None, start: dict | None = None, max_nfev: int = MAX_NFEV) -> dict:
    """The spring scale and friction (``fitted``) read from the free ring-downs (module docstring).
    ``rings``: per record (name, time_s, shock_mm, slam, push, dampers): ``slam`` a
    ``bounce_replay.prepare_slam`` result, ``push`` its replay's push (``PUSH_NAMES``), ``dampers``
    {"compression_N_s_per_m", "rebound_N_s_per_m"}. ``held``: values given (default the dampers'
    scale 1). With the friction and the dampers' scale both fitted, the three models (``MODELS``:
    viscous only, friction only, both) are each fitted, both started also from the other two's answers
    (the value each holds at its start value), and one chosen by ``aicc``: ``"model"``, ``"models"``
    (each one's values, intervals, RMS and criterion), ``"criterion"``; the values and intervals given
    are both's. {"spring_scale",
    "spring_scale_ci95", "friction_N", ..., "line"} or {"refused", "line"}."""
    held = {**({} if "damper_scale" in fitted else {"damper_scale": 1.0}), **(held or {})}
    names = [k for k in fitted if k not in held]
    st = {**START, **(start or {})}
    recs = [_record_points(ring) for ring in rings]
    base = {"method": METHOD, "held": held, "records": len(rings)}
    if not ("friction_N" in names and "damper_scale" in names):
        out = {**base, **_fit_one(rings, recs, names, held, st, max_nfev)}
        out["line"] = line(out)
        return out
    sub = {m: _fit_one(rings, recs, [k for k in names if k not in MODELS[m]], {**held, **MODELS[m]}, st, max_nfev)
           for m in ("viscous", "friction")}
    # both also from each restricted model's answer, the value it held at its start value (START: 30 N, 1 x)
    extra = [{**s, **{k: st[k] for k in MODELS[m]}} for m, s in sub.items() if "rss" in s]
    both = _fit_one(rings, recs, names, held, st, max_nfev, extra=extra)
    out = {**base, **both}
    models = {}
    for m, s in (*sub.items(), ("both", both)):
        p = len(names) - len(MODELS[m])
        e = {"fitted": [k for k in names if k not in MODELS[m]], "held": dict(MODELS[m])}
        if "rss" in s:
            a = aicc(s["rss"], s["n_residuals"], p)  # null where too few residuals (fit.json has no inf)
            e.update({k: s[k] for k in names}, rms_scaled=s["rms_scaled"], rss=s["rss"],
                     aicc=a if math.isfinite(a) else None)
            e.update({k + "_ci95": s[k + "_ci95"] for k in names if k + "_ci95" in s})
            if s.get("undetermined"):
                e["undetermined"] = s["undetermined"]
        if "refused" in s:
            e["refused"] = s["refused"]
        models[m] = e
    scored = {m: e["aicc"] for m, e in models.items() if e.get("aicc") is not None}
    if scored:
        out["model"] = min(scored, key=scored.get)
    out.update(models=models, criterion=CRITERION)
    out["line"] = line(out)
    return out


def line(out: dict) -> str:
    if "refused" in out:
        return out.get("line") or out["refused"]
    said = []
    for k, unit in (("spring_scale", "x"), ("friction_N", "N"), ("damper_scale", "x the dampers given"),
                    ("compression_scale", "x the compression given"), ("rebound_scale", "x the rebound given")):
        if k + "_ci95" in out:
            lo, hi = out[k + "_ci95"]
            f = ".2f" if k != "friction_N" else ".0f"
            said.append(f"{k.split('_')[0]} {out[k]:{f}} {unit} [{lo:{f}}, {hi:{f}}]")
        elif k in out and k in ("spring_scale", "friction_N", "damper_scale"):
            said.append(f"{k.split('_')[0]} {out[k]:.4g} given")
    c = out["residual_counts"]
    visc = "friction_N_ci95" in out and out["friction_N_ci95"][0] <= 0.0
    return (f"ring-down fit (free half periods and swing ratios, {c['periods']} and {c['ratios']}, of "
            f"{out['records']} records): " + ", ".join(said)
            + ("; the friction's interval holds 0 (viscous only within the uncertainty)" if visc else "")
            + (f"; at a bound: {', '.join(out['at_bound'])}" if out.get("at_bound") else "")
            + (f"; not determined (the residual does not move with it): {', '.join(out['undetermined'])}"
               if out.get("undetermined") else "") + _model_words(out))


def _model_words(out: dict) -> str:
    """The model the criterion chose with each model's AICc (``fit``) and, where it is not both, its own
    values and intervals; nothing without a choice."""
    if "model" not in out:
        return ""
    m = out["model"]
    said = ", ".join(f"{k} {e['aicc']:.1f}" if e.get("aicc") is not None else f"{k} none (too few residuals)"
                     for k, e in out["models"].items() if "aicc" in e)
    own = ""
    if m != "both":
        e = out["models"][m]
        vals = []
        for k, unit, f in (("spring_scale", "x", ".2f"), ("friction_N", "N", ".0f"), ("damper_scale", "x", ".2f")):
            if k + "_ci95" in e:
                lo, hi = e[k + "_ci95"]
                vals.append(f"{k.split('_')[0]} {e[k]:{f}} {unit} [{lo:{f}}, {hi:{f}}]")
            elif k in e["held"]:
                vals.append(f"{k.split('_')[0]} {e[k]:g} held")
        own = ": " + ", ".join(vals) + ("" if "refused" not in e else " (the bike does not follow it: "
                                        f"RMS {e['rms_scaled']:.1f} sd)")
    return f"; model by AICc: {MODEL_WORDS[m]}{own} (AICc {said}; the values before are both's)" if m != "both" \
        else f"; model by AICc: {MODEL_WORDS[m]} (AICc {said})"


__all__ = ["CRITERION", "METHOD", "MODELS", "aicc", "fit", "line", "residuals", "swing_ratio_at", "turning_points"]


DEFAULT_FITTED = ("spring_scale", "friction_N", "damper_scale")
SPRING_FROM = ("the ring-down fit (the free half periods and swing ratios, with its own friction and the "
               "slam-and-first-rebound fit's dampers scaled)")


def from_slam_rebound(rings, pooled: dict) -> dict:
    """``fit bounce --replay``'s ``"ring_fit"``: the spring scale, friction and one scale on the dampers of
    the slam-and-first-rebound fit (``pooled``: ``bounce_slam_rebound.fit``'s result: its shared
    compression, each record's rebound) read from the free ring-downs, each record pushed as that fit
    pushed it (its push was fitted with those dampers; the whole-trace replay's, ``rings``' values,
    where it has none; ``rings``: per record (name, time_s, shock_mm, slam, replay values), as
    ``spring_from_periods`` takes them). Adds ``compression_N_s_per_m`` and per record
    ``rebound_N_s_per_m`` (the given ones times the scale fitted) and their sources."""
    from mtbmj.identify.bounce_replay import PUSH_NAMES

    by = {e["file"]: e for e in pooled["records"] if "rebound_N_s_per_m" in e and "refused" not in e}
    comp = float(pooled["compression_N_s_per_m"])
    use = [(name, t, x, sl, {k: float(by[name].get("push", v)[k]) for k in PUSH_NAMES},
            {"compression_N_s_per_m": comp, "rebound_N_s_per_m": float(by[name]["rebound_N_s_per_m"])})
           for name, t, x, sl, v in rings if name in by]
    if not use:
        why = "no record read by the slam-and-first-rebound fit"
        return {"refused": f"the ring-down fit not read: {why}", "line": f"ring-down fit not read: {why}"}
    out = fit(use, fitted=DEFAULT_FITTED)
    out["dampers_given"] = {"compression_N_s_per_m": comp,
                            "rebound_N_s_per_m": {n: d["rebound_N_s_per_m"] for n, *_, d in use},
                            "from": "the slam-and-first-rebound fit"}
    if "refused" not in out:
        sc = out["damper_scale"]
        out["compression_N_s_per_m"] = sc * comp
        out["rebound_N_s_per_m"] = {n: sc * d["rebound_N_s_per_m"] for n, *_, d in use}
    return out


__all__ += ["DEFAULT_FITTED", "SPRING_FROM", "from_slam_rebound"]

"""A seat slam's rebound damper read from its first rebound through the bike (``fit bounce --replay``'s
``"rebound_dampers"``).

Why. The whole-trace replay (``mtbmj.identify.bounce_replay``) fits one linear damper to the slam, the
ring-down and the level after it together. On the shared slams its damper does not rise with the
rebound clicks (2012 and 1364 N s/m at 0 and 8), while the records' own first rebounds slow with
them (``bounce.first_rebound``: from one 44-45 mm peak, 352, 291 and 227 mm/s through the rebound's
middle at 0, 8 and 17 clicks). The replay's slam peaks 20-30 ms late and 2-8 mm high (a smooth push
through the compliant rider does not make the record's compression), and the rest after the slam
moves 6-8 mm (the rider settling); the whole-trace fit spends the damper on both. What a rebound
adjuster changes is the first rebound's speed from the peak, which needs neither.

Method. Per record, on the seated MuJoCo bike of the replay (its start, its rest): the spring scale,
the friction and the compression coefficient given (shared by the records: a rebound adjuster
changes none of them; ``read_records`` takes the spring, friction and compression of the ring-down fit
(``bounce_ring.from_slam_rebound``: the free half periods and swing ratios with a friction and dampers of
its own) where it is given (``ring=``, as ``fit bounce --replay`` gives it) and read, the spring alone from
the ring-down's period reading (``bounce_slam_rebound.spring_from_periods``) where that is given, else all
three from the best whole-trace replay, ``spring_given``, and says which in ``"spring_from"``), the push fitted on the record up to its peak (``bounce_replay.fit_push``),
then the rebound coefficient solved (``brentq``) so that the replay's first rebound, read as the
record's (``bounce.first_rebound``), has the record's middle speed per millimetre of the peak's
height above rest (1/s: for a linear end independent of how high the slam went, so the replay's
peak need not match the record's). Its 95 % interval (``combine``): the record's own noise (``rate_spread``:
the record less its 10 ms moving average resampled in blocks onto the average, the rate read again;
its 95 % ends solved through on the same replay, ``rebound_noise_ci95``) and the spring's interval
(the same solve with the spring at the ends of the interval given, ``spring_ci95``, which is what
moves it most: 0.49 x gives 208, 2591, 5368 N s/m on the shared slams, 0.6 x 961, 3956, 7065), their
half-widths added in quadrature on each side, and with them the friction's and the compression's
intervals (``at_nuisance_ends``: every record read again at each end of the two axes of the best
whole-trace replay's joint 95 % interval of its friction and its damper, their correlation from its
Jacobian, ``bounce_ends.joint_ends``; each alone, the other held, where its summary has no correlation;
per axis the larger move on each side, ``at_nuisance_ci95``; the whole-trace replay barely determines them, [0, 874] N and
[0, 6773] N s/m on the shared slams, and they move the coefficients as much as the spring does) and
the nuisance fit's reproducibility (``reproducibility``: Z95 x the standard deviation of the
coefficient over the reading and its ``RESTARTS`` restarts: ``restarted`` fits the best whole-trace
replay again from starts moved by its own finite-difference step, and every record is read again at
each landing; none by default, since the intervals carried hold the landings' scatter many times
over; where the spring, friction and compression come from the ring-down fit, neither). The readings
run on a seated bike whose rest is solved to ``READ_REST_TOL_MM`` (1e-7 mm, no path noise: the same
values read the same coefficient whatever ran before). A side whose end has no coefficient is open (None),
said in ``interval_open`` (on the shared slams the 0- and 8-click intervals are open below: at the
friction's and compression's together axis' upper end, and at the spring's lower end, where the bike
rebounds slower than the record even undamped; the 17-click one closes below at 1778 N s/m, its
reading at the spring's lower end). Refused for the record (a reason, no
value) when no coefficient within ``BOUNDS`` gives the record's speed: the bike with the spring given
rebounds slower than the record even undamped, or faster even at the largest coefficient (a replay's first
rebound with no middle there, turning before 25 % of the slam's height, is slower than any: ``solve_on``
reads the coefficient below it, and refuses only where the rebound is still faster than the record where it
stops having a middle). The law in
clicks, each record held out and the answer in clicks, its range carrying the friction's, compression's
and spring's ends: ``law_in_clicks`` (``bounce_rebound_clicks``).
"""
from __future__ import annotations

import numpy as np

from mtbmj.identify.bounce import BounceError, first_rebound, record_name
from mtbmj.identify.bounce_decay import moving_average
from mtbmj.identify.bounce_ends import CORRELATION, joint_ends
from mtbmj.identify.bounce_replay import NAMES, Slam, fit_push

BOUNDS = (50.0, 30000.0)  # N s/m: the rebound coefficient sought within these (bounce_replay's damper bounds)
XTOL = 1.0  # N s/m
STALL_BISECTIONS = 14  # solve_on: the upper end bisected (in log) at most this often below a stalled rebound
NOISE_S = 0.010  # the record's noise: what is left after a moving average over this (first_rebound's smoothing)
DRAWS = 200  # the record's noise resampled this many times (rate_spread)
Z95 = 1.959963984540054
DAMPER = NAMES.index("damper_N_s_per_m")
RESTARTS = 0  # the nuisance fit (the best whole-trace replay) fitted again this many times (``restarted``):
# none by default since its friction's and compression's intervals are carried (``at_nuisance_ends``)
READ_REST_TOL_MM = 1e-7  # the readings' seated rest solved to this (``SeatedReplay(rest_tol_mm=)``): no path noise
RESTART_STEP = 1e-3  # ... each from a start moved by a normal draw of this times each value's scale: the fit's
# own finite-difference step (``bounce_replay``'s diff_step), starts the fit cannot tell apart


def replay_rebound(sl: Slam, x: np.ndarray, extra: dict) -> dict:
    """The replay's first rebound (``bounce.first_rebound``) at values ``x`` (NAMES) and ``extra``."""
    sl.sr.set_rest(sl.rest, None)
    out = sl.sr.run({**dict(zip(NAMES, x)), **extra})
    t, xs = out["time_s"], out["stroke_mm"] - out["stroke_mm"][0]
    top = int(np.argmax(np.where(np.abs(t) < 0.1, xs, -np.inf)))
    return first_rebound(t, xs, top, 0.0)


def _per_mm(rb: dict) -> float:
    v = rb["mid_rebound_speed_mm_per_s"]
    return float("nan") if v is None else float(v / rb["peak_above_rest_mm"])


class _Curve:
    """The replay's first-rebound rate per mm of height (1/s) against the rebound coefficient for one
    slam, the spring, friction, compression and push held: every run kept, so solves for several
    targets share them (a run is about 0.1 s; the push's fit, 25-30 s, is done once)."""

    def __init__(self, sl: Slam, x: np.ndarray, extra: dict):
        self.sl, self.x, self.extra, self.seen = sl, x, extra, {}

    def __call__(self, c: float) -> float:
        c = float(c)
        if c not in self.seen:
            xx = self.x.copy()
            xx[DAMPER] = c
            self.seen[c] = _per_mm(replay_rebound(self.sl, xx, self.extra))
        return self.seen[c]

    def points(self) -> list:
        """[(coefficient, rate)] seen, by coefficient, the finite ones."""
        return [(c, v) for c, v in sorted(self.seen.items()) if np.isfinite(v)]


def curve(sl: Slam, spring_scale: float, friction_N: float, compression: float) -> _Curve:
    """The slam's rate-against-coefficient curve at the spring, friction and compression given, the
    push fitted on the record up to its peak (``bounce_replay.fit_push``)."""
    x = sl.x0.copy()
    x[NAMES.index("spring_scale")], x[NAMES.index("friction_N")] = spring_scale, friction_N
    extra = {"compression_N_s_per_m": float(compression)}
    u = (x - sl.x0) / sl.base
    fit_push(sl, u, extra=extra)  # the push on the compression, the shock held
    return _Curve(sl, sl.x0 + u * sl.base, extra)


def solve_on(cv: _Curve, target: float, spring_scale: float) -> float:
    """The coefficient whose replay's rate is ``target`` (1/s) on the curve ``cv``; BounceError when none
    within BOUNDS gives it. A first rebound with no middle at the largest coefficient (NaN: it turns before
    25 % of the slam's height) is slower than the record, not faster: the bracket's upper end is bisected
    down (in log, ``STALL_BISECTIONS`` times) to a coefficient whose rebound has a middle and is slower
    than the record, and the root read below it."""
    from scipy.optimize import brentq

    a, b = BOUNDS
    lo, hi = cv(a) - target, cv(b) - target
    where = (f"{cv.sl.name}: no rebound coefficient within {a:g}-{b:g} N s/m gives the record's first rebound "
             f"({target:.2f} /s): with the spring at {spring_scale:.2f} x the bike")
    if not np.isfinite(lo):
        raise BounceError(f"{where}'s first rebound has no middle even undamped (it turns before 25 % of the "
                          f"slam's height)")
    if lo < 0.0:
        raise BounceError(f"{where} rebounds slower than the record even undamped")
    if np.isfinite(hi) and hi > 0.0:
        raise BounceError(f"{where} rebounds faster than the record at the largest coefficient")
    top = b
    if not np.isfinite(hi):  # stalled at the largest coefficient: find a coefficient with a middle below it
        top = None
        for _ in range(STALL_BISECTIONS):
            m = float(np.sqrt(a * b))
            v = cv(m) - target
            if not np.isfinite(v):
                b = m
            elif v > 0.0:
                a = m
            else:
                top = m
                break
        if top is None:
            raise BounceError(f"{where}'s first rebound is still faster than the record ({cv(a):.2f} /s) at "
                              f"{a:.0f} N s/m and has no middle from {b:.0f} N s/m up (it turns before 25 % of "
                              f"the slam's height)")
    return float(brentq(lambda c: cv(c) - target, BOUNDS[0], top, xtol=XTOL))


def solve(sl: Slam, record: dict, spring_scale: float, friction_N: float, compression: float) -> float:
    """The rebound coefficient (N s/m) whose replay has the record's first rebound (``record``:
    ``first_rebound`` of the record) per mm of height; BounceError when none within BOUNDS does."""
    target = _per_mm(record)
    if not np.isfinite(target):
        raise BounceError(f"{sl.name}: the record's first rebound has no middle (it does not pass from 75 % to "
                          f"25 % of the slam's height): no rebound damper is read from it")
    return solve_on(curve(sl, spring_scale, friction_N, compression), target, spring_scale)


def rate_spread(time_s, x_mm, peak: int, rest_mm: float = 0.0, draws: int = DRAWS, seed: int = 0) -> dict:
    """The record's own noise carried into its first-rebound rate (1/s per mm of height, ``first_rebound``):
    the record split into its ``NOISE_S`` moving average and what is left (its noise: sensor counts,
    the frame's buzz), the left-over resampled in blocks of ``NOISE_S`` (its correlation kept) onto the
    average ``draws`` times (seeded), the rate read again each time. {"rate_per_s", "sd_per_s",
    "noise_mm" (the left-over's RMS), "draws" (how many read)}; sd None when fewer than half read."""
    t = np.asarray(time_s, float)
    x = np.asarray(x_mm, float)
    dt = float(t[1] - t[0])
    n = max(int(round(NOISE_S / dt)), 1)
    smooth = moving_average(x, n)
    left = x - smooth
    rng = np.random.default_rng(seed)
    starts = np.arange(0, max(left.size - n, 1))
    rates = []
    for _ in range(draws):
        idx = np.concatenate([s + np.arange(n) for s in rng.choice(starts, size=left.size // n + 1)])[:left.size]
        try:
            r = _per_mm(first_rebound(t, smooth + left[np.minimum(idx, left.size - 1)], peak, rest_mm))
        except BounceError:
            continue
        if np.isfinite(r):
            rates.append(r)
    own = _per_mm(first_rebound(t, x, peak, rest_mm))
    sd = float(np.std(rates, ddof=1)) if len(rates) >= max(draws // 2, 2) else None
    return {"rate_per_s": own, "sd_per_s": sd, "noise_mm": float(np.sqrt(np.mean(left * left))), "draws": len(rates)}


def _ends(cv: _Curve, target: float, sd, spring_scale: float) -> list:
    """The coefficients at the rate's own 95 % ends (target -/+ Z95 sd; a faster rebound needs less
    damping, so the slower end gives the larger coefficient), None where none within BOUNDS does."""
    if sd is None:
        return [None, None]
    out = []
    for rate in (target + Z95 * sd, target - Z95 * sd):
        try:
            out.append(solve_on(cv, rate, spring_scale))
        except BounceError:
            out.append(None)
    return out


def combine(c: float, noise, spring, restarts_half: float | None = None, nuisance=None) -> tuple[list, list]:
    """The damper's 95 % interval: the half-widths from the record's noise, from the spring's interval,
    from the nuisance fit's restarts (``restarts_half``: Z95 x their sd, ``reproducibility``) and from
    the friction's and compression's intervals (``nuisance``: {name: [coefficient at its lower end, at
    its upper end]}, ``at_nuisance_ends``; either end may move the coefficient either way, so each side
    takes the larger move of the ends on its side) added in quadrature on each side; a side whose end is
    missing (None: no coefficient within BOUNDS gives it; a nuisance end read none: both sides) is
    open, with why. Returns ([low or None, high or None], [reasons for open sides])."""
    ends, why = [], []
    moves = [[max([0.0] + [abs(c - v) for v in pair if v is not None and (v < c if k == 0 else v > c)]) for k in (0, 1)]
             for pair in (nuisance or {}).values()]
    unread = [name for name, pair in (nuisance or {}).items() if None in pair]
    for side, k in (("low", 0), ("high", 1)):
        if unread:
            ends.append(None)
            why.append(f"open {'below' if k == 0 else 'above'}: no coefficient within {BOUNDS[0]:g}-{BOUNDS[1]:g} "
                       f"N s/m at an end of the {', '.join(unread)} interval")
            continue
        n = None if noise is None else noise[k]
        sp = None if spring is None else spring[k]
        if n is None or (spring is not None and sp is None):
            ends.append(None)
            which = "the spring interval's " + ("lower" if k == 0 else "upper") + " end" if n is not None else \
                "the record's rate at its " + ("fast" if k == 0 else "slow") + " 95 % end"
            why.append(f"open {'below' if k == 0 else 'above'}: no coefficient within {BOUNDS[0]:g}-{BOUNDS[1]:g} "
                       f"N s/m at {which}")
            continue
        half = float(np.sqrt((c - n) ** 2 + (0.0 if sp is None else c - sp) ** 2 + (restarts_half or 0.0) ** 2
                             + sum(m[k] ** 2 for m in moves)))
        ends.append(max(c - half, 0.0) if k == 0 else c + half)
    return ends, why


def rebound_dampers(slams, clicks, spring_scale: float, friction_N: float, compression: float,
                    spring_ci95=None, draws: int = DRAWS) -> list[dict]:
    """Per slam (``bounce_replay.prepare_slam``; each record's ``first_rebound`` read from its own
    window) its rebound coefficient with its 95 % interval, or ``"refused"`` with the reason. The
    interval: the record's noise (``rate_spread``) solved through at the spring given, and with
    ``spring_ci95`` the coefficients at the spring's interval ends (``at_spring_ci95``, either None
    where refused), combined by ``combine`` (an open side said in ``"interval_open"``). ``rate_curve``:
    the replay's rate against the coefficient at the spring given (``rate_curve_at_spring_ci95`` at
    its ends), for the law in clicks (``bounce_rebound_clicks``)."""
    out = []
    for sl, k in zip(slams, clicks):
        peak = int(np.argmin(np.abs(sl.tt)))
        record = first_rebound(sl.tt, sl.rec, peak, 0.0)
        per_mm = _per_mm(record)
        spread = rate_spread(sl.tt, sl.rec, peak, 0.0, draws) if np.isfinite(per_mm) else None
        sd = None if spread is None else spread["sd_per_s"]
        entry = {"file": sl.name, "clicks": k, "record_mid_rebound_per_s": per_mm if np.isfinite(per_mm) else None,
                 "record_rate_sd_per_s": sd, "record_noise_mm": None if spread is None else spread["noise_mm"],
                 "spring_scale": float(spring_scale), "friction_N": float(friction_N),
                 "compression_N_s_per_m": float(compression)}
        if not np.isfinite(per_mm):
            entry["refused"] = (f"{sl.name}: the record's first rebound has no middle (it does not pass from 75 % to "
                                f"25 % of the slam's height): no rebound damper is read from it")
            out.append(entry)
            continue
        try:
            cv = curve(sl, spring_scale, friction_N, compression)
            c = solve_on(cv, per_mm, spring_scale)
        except BounceError as e:
            entry["refused"] = str(e)
            out.append(entry)
            continue
        entry["rebound_N_s_per_m"] = c
        noise = _ends(cv, per_mm, sd, spring_scale)
        entry["rebound_noise_ci95"] = noise
        entry["rate_curve"] = [list(p) for p in cv.points()]
        spring = None
        if spring_ci95 is not None:
            spring, curves = [], []
            for s in spring_ci95:
                s = max(float(s), 0.2)
                try:
                    cs = curve(sl, s, friction_N, compression)
                    spring.append(solve_on(cs, per_mm, s))
                    curves.append([list(p) for p in cs.points()])
                except BounceError:
                    spring.append(None)
                    curves.append(None)
            entry["at_spring_ci95"] = spring
            entry["rate_curve_at_spring_ci95"] = curves
        entry["rebound_N_s_per_m_ci95"], entry["interval_open"] = combine(c, noise, spring)
        out.append(entry)
    return out


def rises(entries) -> bool | None:
    """Do the read coefficients rise strictly with the clicks? None with fewer than two read."""
    done = sorted((e for e in entries if "rebound_N_s_per_m" in e), key=lambda e: e["clicks"])
    if len({e["clicks"] for e in done}) < 2:
        return None
    return all(b["rebound_N_s_per_m"] > a["rebound_N_s_per_m"] for a, b in zip(done, done[1:])
               if b["clicks"] > a["clicks"])


def read_records(records, clicks, replayed: list, bike="sst", rider_hz: float | None = None,
                 target_per_s: float | None = None, ring: dict | None = None, restarts: int = RESTARTS) -> dict | None:
    """``fit bounce --replay``'s ``"rebound_dampers"``: every record's rebound coefficient, the friction
    and compression given by the best-determined whole-trace replay (``replayed``:
    ``bounce_replay.replay_records``' summary; the one whose spring interval is the narrowest; its one
    damper taken as the compression), the spring (with its interval) by the ring-down's period
    (``ring``: ``bounce_slam_rebound.spring_from_periods``' result) where it was read, else by that
    replay (``"spring_from"`` says which, and why not the period), each coefficient with its interval;
    the law in clicks, each record held out and the answer for ``target_per_s``
    (``bounce_rebound_clicks``; "lines" printed). None when no record was replayed."""
    from mtbmj.identify.bounce_replay import RIDER_HZ, SeatedReplay, prepare_slam

    done = [e for e in replayed if "refused" not in e]
    if not done:
        return None
    best = min(done, key=lambda e: e["spring_scale_ci95"][1] - e["spring_scale_ci95"][0])
    sr = SeatedReplay(bike, RIDER_HZ if rider_hz is None else rider_hz, rest_tol_mm=READ_REST_TOL_MM)
    slams, ks, entries = [], [], []
    for rec, k in zip(records, clicks):
        name = record_name(rec)
        try:
            slams.append(prepare_slam(rec.time_s, rec.shock_mm, rec.fork_mm, name, sr,
                                      getattr(rec, "shock_max_mm", None)))
            ks.append(k)
        except BounceError as e:
            entries.append({"file": name, "clicks": k, "refused": str(e)})
    spring, spring_from = spring_given(ring, best)
    own = _is_fit(ring)  # the ring-down fit's friction and compression with its spring, else the replay's
    friction = float(ring["friction_N"]) if own else float(best["friction_N"])
    compression = float(ring["compression_N_s_per_m"]) if own else float(best["damper_N_s_per_m"])
    entries = rebound_dampers(slams, ks, spring[0], friction, compression, spring[1]) + entries
    entries.sort(key=lambda e: e["clicks"])
    nuisance = {} if own else at_nuisance_ends(slams, ks, spring[0], best, entries)
    nuisance["spring_scale"] = at_spring_ends(entries)  # already read: the held-out residual's moves there too
    again = []
    if not own and restarts:  # the replay's values: its fit again from starts it cannot tell apart
        rec = next(r for r in records if record_name(r) == best["file"])
        for v in restarted(rec, sr, restarts):
            if "refused" not in v:
                s_k = spring[0] if spring_from == RING_FROM else v["spring_scale"]
                v["entries"] = rebound_dampers(slams, ks, s_k, v["friction_N"], v["compression_N_s_per_m"], None)
            again.append(v)
    landed = [v["entries"] for v in again if "entries" in v]  # the records read at each restart that landed
    reproducibility(entries, landed)
    up = rises(entries)
    read = [e for e in entries if "rebound_N_s_per_m" in e]

    def said(e):
        lo, hi = e.get("rebound_N_s_per_m_ci95", [None, None])
        return (f"{e['rebound_N_s_per_m']:.0f} [{'open' if lo is None else format(lo, '.0f')}, "
                f"{'open' if hi is None else format(hi, '.0f')}]")

    at = ", ".join(format(e["clicks"], "g") for e in read)
    said_spring = ("the ring-down fit" if own else "the ring-down's period" if spring_from == RING_FROM
                   else f"{best['file']}'s replay")
    said_from = "the ring-down fit" if own else f"{best['file']}'s replay"
    said_again = (f", the replay's reproducibility over {len(landed)} restart(s)" if landed else "")
    rho = None if own else best.get(CORRELATION)
    said_again += ("" if own else ", the friction's and compression's intervals" if rho is None else
                   f", the friction's and compression's joint interval (correlated {rho:+.2f})")
    line = (f"rebound dampers from the first rebounds (spring {spring[0]:.2f} x from {said_spring}, friction "
            f"{friction:.0f} N, compression {compression:.0f} N s/m from {said_from}): {', '.join(said(e) for e in read) or 'none'} N s/m (95 %: the record's noise and the spring's "
            f"interval{said_again}) at {at or 'no'} clicks"
            + ("" if up is None else ": they rise with the clicks" if up else ": they do not rise with the clicks"))
    out = {"from": best["file"], "spring_scale": spring[0], "spring_scale_ci95": list(spring[1]),
           "spring_from": spring_from, "friction_N": friction, "compression_N_s_per_m": compression,
           "restarts": [{k: v for k, v in r.items() if k != "entries"} | ({"rebound_N_s_per_m": [
               e.get("rebound_N_s_per_m") for e in sorted(r["entries"], key=lambda e: e["clicks"])]}
               if "entries" in r else {}) for r in again],
           "records": entries, "rises": up, "line": line}
    out["nuisance_ends"] = None if own else {k: [list(p) for p in v] for k, v in nuisance_ends(best).items()}
    out["friction_compression_correlation"] = rho
    out.update(law_in_clicks(entries, target_per_s, landed, nuisance))
    return out


def at_spring_ends(entries, partial: bool = False) -> list:
    """The records as read at each end of the spring's interval (``at_spring_ci95`` with its
    ``rate_curve_at_spring_ci95``; the noise interval moved with the coefficient), for the held-out sd
    beside the friction's and compression's: [at the lower end, at the upper end], None where a read
    record has no coefficient there (``partial``: the records that have one, for the answer's range)."""
    read = [e for e in entries if "rebound_N_s_per_m" in e]
    out = []
    for i in (0, 1):
        got = []
        for e in read:
            c = (e.get("at_spring_ci95") or [None, None])[i]
            cv = (e.get("rate_curve_at_spring_ci95") or [None, None])[i]
            if c is None or not cv:
                if partial:
                    continue
                got = None
                break
            move = c - e["rebound_N_s_per_m"]
            got.append({**e, "rebound_N_s_per_m": c, "rate_curve": cv,
                        "rebound_noise_ci95": [None if v is None else v + move for v in e["rebound_noise_ci95"]]})
        out.append(got if read else None)
    return out


def nuisance_ends(best: dict) -> dict:
    """{name: [(friction, compression) at the lower end, at the upper end]} for the friction and the
    compression of the whole-trace replay ``best`` (its summary: its friction and its one damper with
    their intervals): their joint interval's two axes (``bounce_ends.joint_ends``) where the summary
    carries their correlation, else each value's own ends, the other held."""
    joint = joint_ends(best)
    if joint is not None:
        return joint
    f, c = float(best["friction_N"]), float(best["damper_N_s_per_m"])
    flo, fhi = best["friction_N_ci95"]
    clo, chi = best["damper_N_s_per_m_ci95"]
    return {"friction_N": [(float(flo), c), (float(fhi), c)],
            "compression_N_s_per_m": [(f, float(clo)), (f, float(chi))]}


def at_nuisance_ends(slams, ks, spring_scale: float, best: dict, entries) -> dict:
    """Every record read again (``rebound_dampers``, the spring given, no spring ends) at each end of the
    friction's and the compression's 95 % intervals (``nuisance_ends``): {name: [entries at the lower
    end, at the upper end]}, for the held-out sd (``bounce_rebound_clicks.held_out``). Each read entry of
    ``entries`` gets ``at_nuisance_ci95`` ({name: [coefficient at the lower end, at the upper end]},
    None where none is read), carried into its interval by ``reproducibility`` (``combine``)."""
    out = {name: [rebound_dampers(slams, ks, spring_scale, f, c, None) for f, c in ends]
           for name, ends in nuisance_ends(best).items()}
    for e in entries:
        if "rebound_N_s_per_m" in e:
            e["at_nuisance_ci95"] = {name: [next((a.get("rebound_N_s_per_m") for a in got if a["file"] == e["file"]),
                                                 None) for got in pair] for name, pair in out.items()}
    return out


def restarted(record, sr, n: int = RESTARTS, seed: int = 0) -> list[dict]:
    """The whole-trace replay of ``record`` (``bounce_replay.replay``: the best-determined one, whose
    spring, friction and damper the rebound dampers are given) fitted again ``n`` times, each from the
    start it had moved by a normal draw of ``RESTART_STEP`` times each value's scale (seeded): what the
    fit lands on from starts it cannot tell apart, as it lands differently from machine to machine (it
    stops where the noise of its rest's solve, ``bounce_replay.REST_TOL_MM``, hides its slope). Per restart
    {"spring_scale", "friction_N", "compression_N_s_per_m" (the replay's one damper)} or {"refused"}."""
    from mtbmj.identify.bounce_replay import prepare_slam, replay

    name = record_name(record)
    top = getattr(record, "shock_max_mm", None)
    sl = prepare_slam(record.time_s, record.shock_mm, record.fork_mm, name, sr, top)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        x = sl.x0 + RESTART_STEP * sl.base * rng.standard_normal(sl.x0.size)
        try:
            rp = replay(record.time_s, record.shock_mm, record.fork_mm, name=name, seated=sr, shock_max_mm=top,
                        start=dict(zip(NAMES, (float(v) for v in x))))
        except BounceError as e:
            out.append({"refused": str(e)})
            continue
        out.append({"spring_scale": float(rp.values["spring_scale"]), "friction_N": float(rp.values["friction_N"]),
                    "compression_N_s_per_m": float(rp.values["damper_N_s_per_m"])})
    return out


def reproducibility(entries, again) -> None:
    """Each read record's coefficient at every restart's nuisance values (``again``: ``rebound_dampers``'
    entries per restart) in ``rebound_restarts_N_s_per_m`` (None where that restart read none), their
    standard deviation with the reading's own (``rebound_reproducibility_sd_N_s_per_m``, None with no
    restart read), carried into its 95 % interval (``combine``: Z95 x that sd in quadrature)."""
    for e in entries:
        if "rebound_N_s_per_m" not in e:
            continue
        got = [next((a.get("rebound_N_s_per_m") for a in entries_k if a["file"] == e["file"]), None)
               for entries_k in again]
        e["rebound_restarts_N_s_per_m"] = got
        read = [v for v in got if v is not None]
        sd = float(np.std([e["rebound_N_s_per_m"]] + read, ddof=1)) if read else None
        e["rebound_reproducibility_sd_N_s_per_m"] = sd
        e["rebound_N_s_per_m_ci95"], e["interval_open"] = combine(
            e["rebound_N_s_per_m"], e["rebound_noise_ci95"], e.get("at_spring_ci95"), None if sd is None else Z95 * sd,
            e.get("at_nuisance_ci95"))


RING_FROM = "the ring-down's period"


def spring_given(ring: dict | None, best: dict) -> tuple[tuple[float, list], str]:
    """((spring scale, its 95 % interval), where it came from): the ring-down fit's
    (``bounce_ring.from_slam_rebound``: it has a friction of its own) or the ring-down's period reading
    (``ring``) where it was read, else the best-determined whole-trace replay's (``best``), saying why."""
    from mtbmj.identify.bounce_ring import SPRING_FROM

    if ring is not None and "refused" not in ring:
        return ((float(ring["spring_scale"]), list(ring["spring_scale_ci95"])),
                SPRING_FROM if _is_fit(ring) else RING_FROM)
    why = ("not given" if ring is None else ring["refused"])
    return ((float(best["spring_scale"]), list(best["spring_scale_ci95"])),
            f"the whole-trace replay of {best['file']} (the ring-down: {why})")


def _is_fit(ring: dict | None) -> bool:
    """Whether ``ring`` is the ring-down fit (its own friction and compression) and read."""
    return ring is not None and "refused" not in ring and "compression_N_s_per_m" in ring


def law_in_clicks(entries, target_per_s: float | None = None, again=(), nuisance=None) -> dict:
    """The law in clicks, each record held out (``again``: the records read at each restart's nuisance
    values, ``nuisance``: at the ends of the friction's and compression's intervals, ``at_nuisance_ends``,
    and of the spring's, ``at_spring_ends``; both carried into the held-out sd) and the answer
    (``bounce_rebound_clicks``; with ``nuisance`` its range carries the friction's and compression's ends
    and the spring's, the records read at each), with the lines they print ("lines")."""
    from mtbmj.identify import bounce_rebound_clicks as rc

    lines = []
    try:
        law = rc.fit_law(entries)
        lines.append(f"rebound law: {law['c0_N_s_per_m']:.0f} + {law['slope_N_s_per_m_per_click']:.1f} x clicks N s/m "
                     f"(slope 95 % [{law['slope_ci95'][0]:.1f}, {law['slope_ci95'][1]:.1f}])"
                     + ("" if law["records_rates_fall"] else "; flagged: the records' own first rebounds do not slow "
                        "with the clicks"))
    except BounceError as e:
        law = {"refused": str(e)}
        lines.append(f"rebound law refused: {e}")
    rows = rc.held_out(entries, again, nuisance) if "refused" not in law else []
    if rc.held_out_line(rows):
        lines.append(rc.held_out_line(rows))
    # the answer's range: the friction's and compression's ends and the spring's (the records read there)
    carried = None if nuisance is None else {**{k: v for k, v in nuisance.items() if k != "spring_scale"},
                                             "spring_scale": at_spring_ends(entries, partial=True)}
    ans = rc.answer(entries, target_per_s, carried) if "refused" not in law else {
        "target_per_s": target_per_s, "set_clicks": None, "note": law["refused"]}
    lines.append(rc.answer_line(ans))
    return {"law": law, "held_out": rows, "answer": ans, "lines": lines}


__all__ = ["BOUNDS", "READ_REST_TOL_MM", "RESTARTS", "at_nuisance_ends", "at_spring_ends", "combine", "curve", "law_in_clicks",
           "nuisance_ends", "rate_spread", "read_records", "rebound_dampers", "replay_rebound", "reproducibility", "restarted", "rises", "solve", "solve_on"]

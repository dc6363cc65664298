"""An answer in clicks from the rebound dampers read off the slams' first rebounds (``fit bounce
--replay``'s ``"rebound_dampers"``: ``"law"``, ``"held_out"``, ``"answer"``).

**The law.** The rebound coefficients per record (``bounce_rebound.rebound_dampers``, each with its
interval from the record's noise) as a straight line in clicks, c = c0 + slope x clicks, by weighted
least squares with each record's standard deviation (the half-width of its noise interval / 1.96);
with more records than two the covariance is widened by chi^2 / dof when that exceeds 1 (the records
scatter more than their noise says). The spring's interval moves every record's coefficient the same
way, so it is carried as a second answer at each of its ends rather than into the law (into the
held-out check it is carried, below). Refused (a
reason, no law) with fewer than two distinct clicks read, when a record's noise was not read, or when
the coefficients do not rise with the clicks (a rebound adjuster adds damping one way: clicks
mislabelled or a record that is not a clean slam); flagged when the records' own rates do not fall
with the clicks.

**Held out.** Each record in turn: the law fitted on the others, its coefficient predicted at the
record's clicks with the law's interval, carried to the record's first-rebound rate (1/s per mm of
height) through that record's own rate-against-coefficient curve (the replay at the spring given),
and compared with the record's rate: it holds when the two lie within 2 combined standard deviations.
The combined sd has four parts in quadrature: the prediction's (the law's), the record's noise, the
values given (the friction's and the compression's joint 95 % interval, along its two axes, and the
spring's: the held-out residual again with every record read at each end, ``bounce_rebound.at_nuisance_ends``
and ``at_spring_ends``; per value the mean move over the ends read / Z95, the values in quadrature:
``nuisance_sd_per_s``; on the shared slams the records' bend off the line changes sign between the
ends of the compression's interval and between the spring's and its upper end, so the check cannot
tell the law's bend from theirs, and says so by its sd), and the nuisance fit's reproducibility
(none by default). The last: the spring, friction and compression the replays are
given come out of a whole-trace fit whose values are barely determined (their 95 % intervals span
0-900 N and 0-6600 N s/m on the shared slams) and which stops where the noise of its rest's solve
(``bounce_replay.REST_TOL_MM``) hides its slope, so it lands differently from machine to machine,
and the coefficients' bend in clicks follows where it lands
(on the shared slams the 0/8/17-click records held out at +-0.4 sd at one landing, +-4 at another
22 N and 250 N s/m away, the records' noise being 0.13 % of the rate). ``bounce_rebound.restarted``
fits it again from starts moved by its own finite-difference step, the records are read again at
each landing, and the held-out residual's standard deviation over the reading and its restarts is
that part (``reproducibility_sd_per_s``, from ``restart_residuals_per_s``). Without restarts it is
None and said so.

**The target** (``RULE``, ``SOURCE``): a first-rebound rate, the mean speed from 75 % to 25 % of the
slam's height per mm of that height (1/s) that the rider aims for. The rebound matched to the spring
as the makers' charts do keeps the rate of extension about the same for every spring (a stiffer spring
needs more rebound damping to rebound as fast: Vorsprung Suspension, "Mountain bike suspension 101:
understanding rebound damping"), so the target is a rate, not a coefficient: the coefficient it needs
follows the spring. Its value is the rider's (``--rebound-target-per-s``); none is assumed.

**The answer.** The first click (searched in ``STEP``) where the law's coefficient, carried through the
curves of the two records that bracket the click (their rates weighted linearly in clicks; at a
record, its own curve), gives the target; "set N clicks" is the nearest whole click. Its range: the
2.5 and 97.5 percentiles over ``DRAWS // 4`` draws of the law's two values (seeded), widened to hold
the answers from the lower and from the upper bracketing record's curve alone (a replayed slam's rate
at one coefficient is not the same for every slam: on the shared slams at 7 /s the 0- and 8-click
slams' curves alone give 8.0 and 4.9 clicks), then to whole clicks. Only the clicks between the
records' are searched (the line is not extrapolated): a target past them is refused with its side.
Repeated with the dampers and curves at the spring interval's ends (``at_spring_ci95``), each end's
answer or why there is none. With the values given read at their ends (``carry``: the friction's and
compression's joint ends and the spring's, the records read at each), the range carries them: the answer
again at every end, per value the larger move on each side added in quadrature to the law's own
half-widths, then to whole clicks; an end whose answer lies past the records read there opens that side
(to the records' end), one with no law opens both (``"range_open"``); the law's alone is kept
(``"clicks_range95_law"``). Beside it, model-free, the clicks where the records' own rates joined by straight lines
in clicks reach the target (``records_clicks``).
"""
from __future__ import annotations

import math

import numpy as np

from mtbmj.identify.bounce import BounceError

Z95 = 1.959963984540054
HOLD_SIGMAS = 2.0
DRAWS = 2000
RULE = ("the first rebound's mean speed from 75 % to 25 % of the slam's height per mm of that height (1/s) at the "
        "target; the answer: the whole click nearest where the rebound-coefficient law meets the coefficient the "
        "records' replays need for it")
SOURCE = ("Vorsprung Suspension, 'Mountain bike suspension 101: understanding rebound damping' (stiffer springs need "
          "more rebound damping so the rate of extension stays about the same): the rebound matched to the spring as "
          "the makers' charts do is a rate, its value the rider's")


def _sd(e: dict) -> float | None:
    """A record's coefficient's standard deviation from its noise interval (the mean half-width / Z95)."""
    c, n = e["rebound_N_s_per_m"], e.get("rebound_noise_ci95") or [None, None]
    halves = [abs(c - v) for v in n if v is not None]
    return None if not halves else max(float(np.mean(halves)) / Z95, 1e-6 * max(c, 1.0))


def fit_law(entries, key: str = "rebound_N_s_per_m") -> dict:
    """The line c = c0 + slope x clicks through the read records (``entries``: ``rebound_dampers``'
    entries; ``key`` the coefficient's, e.g. a spring end's). BounceError when it cannot be fitted."""
    rows = sorted((e for e in entries if e.get(key) is not None), key=lambda e: e["clicks"])
    ks = np.array([e["clicks"] for e in rows], float)
    if np.unique(ks).size < 2:
        raise BounceError(f"no law in clicks: {len(rows)} record(s) read at {np.unique(ks).size} distinct click "
                          f"setting(s); it needs two")
    c = np.array([e[key] for e in rows], float)
    bad = [(a, b) for a, b in zip(rows, rows[1:]) if b["clicks"] > a["clicks"] and b[key] <= a[key]]
    if bad:
        a, b = bad[0]
        raise BounceError(f"no law in clicks: the rebound coefficient falls from {a[key]:.0f} N s/m at {a['clicks']:g} "
                          f"clicks to {b[key]:.0f} at {b['clicks']:g} (more rebound clicks, more damping): the clicks "
                          f"may be mislabelled or a record is not a clean slam")
    sds = [_sd(e) for e in rows]
    if None in sds:
        none = [e["file"] for e, v in zip(rows, sds) if v is None]
        raise BounceError(f"no law in clicks: the noise of {', '.join(none)} was not read (its first rebound read in "
                          f"fewer than half the resampled records), so the law's weights and interval are not known")
    sd = np.array(sds)
    X = np.column_stack((np.ones_like(ks), ks))
    W = 1.0 / sd ** 2
    cov = np.linalg.inv(X.T @ (X * W[:, None]))
    theta = cov @ (X.T @ (W * c))
    r = (c - X @ theta) / sd
    dof = c.size - 2
    chi2 = float(r @ r)
    widen = max(chi2 / dof, 1.0) if dof > 0 else 1.0
    cov = cov * widen
    rates = [e.get("record_mid_rebound_per_s") for e in rows]
    slows = all(b is not None and a is not None and b < a for a, b, ea, eb in zip(rates, rates[1:], rows, rows[1:])
                if eb["clicks"] > ea["clicks"])
    return {"c0_N_s_per_m": float(theta[0]), "slope_N_s_per_m_per_click": float(theta[1]),
            "c0_ci95": [float(theta[0] - Z95 * math.sqrt(cov[0, 0])), float(theta[0] + Z95 * math.sqrt(cov[0, 0]))],
            "slope_ci95": [float(theta[1] - Z95 * math.sqrt(cov[1, 1])), float(theta[1] + Z95 * math.sqrt(cov[1, 1]))],
            "cov": cov.tolist(), "chi2": chi2, "dof": dof, "widened_by": widen,
            "clicks": ks.tolist(), "records": [e["file"] for e in rows], "records_rates_fall": bool(slows)}


def _rate_at(points, c: float) -> float:
    """The rate (1/s) at coefficient ``c`` on a record's curve ([(coefficient, rate)], by coefficient)."""
    p = np.asarray(points, float)
    return float(np.interp(c, p[:, 0], p[:, 1]))


def _coefficient_for(points, rate: float) -> float | None:
    """The coefficient giving ``rate`` on a curve (the rate falls with the coefficient); None outside it."""
    p = np.asarray(points, float)
    c, v = p[:, 0], p[:, 1]
    if not (v.min() <= rate <= v.max()):
        return None
    order = np.argsort(v)
    return float(np.interp(rate, v[order], c[order]))


def _held_one(e: dict, rest: list) -> dict:
    """Record ``e`` predicted by the law fitted on ``rest`` (BounceError when it cannot be fitted): the
    predicted coefficient and rate with their sd (the law's, carried through ``e``'s own curve), the
    record's rate with its noise sd and the residual (predicted less the record's rate, 1/s)."""
    law = fit_law(rest)
    cov = np.asarray(law["cov"])
    x = np.array([1.0, e["clicks"]])
    c = law["c0_N_s_per_m"] + law["slope_N_s_per_m_per_click"] * e["clicks"]
    c_sd = float(math.sqrt(x @ cov @ x))
    pts = e["rate_curve"]
    rate = _rate_at(pts, c)
    h = max(c_sd, 10.0)
    slope = (_rate_at(pts, c + h) - _rate_at(pts, c - h)) / (2 * h)
    rec, rec_sd = e["record_mid_rebound_per_s"], e.get("record_rate_sd_per_s") or 0.0
    return {"predicted_N_s_per_m": c, "predicted_sd_N_s_per_m": c_sd, "read_N_s_per_m": e["rebound_N_s_per_m"],
            "predicted_rate_per_s": rate, "predicted_rate_sd_per_s": abs(slope) * c_sd, "record_rate_per_s": rec,
            "record_rate_sd_per_s": rec_sd, "residual_per_s": rate - rec}


def _readable(entries) -> list:
    return [e for e in entries if e.get("rebound_N_s_per_m") is not None and e.get("rate_curve")]


def held_out(entries, restarts=(), nuisance=None) -> list[dict]:
    """Each read record predicted from a law fitted on the others (module docstring); [] with fewer than
    three read. Per record: predicted coefficient and rate with their sd, the record's, the residual,
    z, holds. ``restarts``: the same records read again at each restart's nuisance values
    (``bounce_rebound.rebound_dampers``' entries, one list per restart): the held-out residual's
    standard deviation over the reading and its restarts (``reproducibility_sd_per_s``, with
    ``restart_residuals_per_s``) is added to the combined sd; without restarts it is None and the sd
    is the prediction's and the record's noise alone. ``nuisance``: {name: [entries at its interval's
    lower end, at its upper end]} (``bounce_rebound.at_nuisance_ends``; an end None where not read):
    the held-out residual again at each end, per name the mean shift from the reading's over the ends
    read / Z95 (the ends are 95 % ends), the names in quadrature (``nuisance_sd_per_s``, with
    ``nuisance_residuals_per_s``) added to the combined sd; without it None and said so."""
    read = _readable(entries)
    out = []
    if len(read) < 3:
        return out
    again = []
    for entries_k in restarts:
        by_file = {e["file"]: e for e in _readable(entries_k)}
        again.append([by_file.get(e["file"]) for e in read])
    for j, e in enumerate(read):
        rest = read[:j] + read[j + 1:]
        row = {"file": e["file"], "clicks": e["clicks"], "from": [r["file"] for r in rest]}
        try:
            row.update(_held_one(e, rest))
        except BounceError as err:
            row["refused"] = str(err)
            out.append(row)
            continue
        residuals = []
        for got in again:  # a restart whose record, or either of the others, was not read: left out
            if None in got:
                continue
            try:
                residuals.append(_held_one(got[j], got[:j] + got[j + 1:])["residual_per_s"])
            except BounceError:
                continue
        rep = float(np.std([row["residual_per_s"]] + residuals, ddof=1)) if residuals else None
        at_ends, nui = _nuisance_residuals(e["file"], nuisance or {}), None
        shifts = [[abs(v - row["residual_per_s"]) for v in ends if v is not None] for ends in at_ends.values()]
        if any(shifts):
            nui = float(math.sqrt(sum((np.mean(s) / Z95) ** 2 for s in shifts if s)))
        both = math.sqrt(row["predicted_rate_sd_per_s"] ** 2 + row["record_rate_sd_per_s"] ** 2 + (rep or 0.0) ** 2
                         + (nui or 0.0) ** 2)
        z = row["residual_per_s"] / both if both > 0 else math.inf
        row.update({"restart_residuals_per_s": residuals, "reproducibility_sd_per_s": rep,
                    "nuisance_residuals_per_s": at_ends, "nuisance_sd_per_s": nui, "sd_per_s": both,
                    "z": float(z), "holds": bool(abs(z) <= HOLD_SIGMAS)})
        out.append(row)
    return out


def _nuisance_residuals(name: str, nuisance: dict) -> dict:
    """Record ``name``'s held-out residual (1/s) with the records read at each end of each nuisance
    value's interval ({name: [entries or None, entries or None]}): {value: [at lower, at upper]}, None
    where that end, the record or either of the others was not read or no law was fitted."""
    out = {}
    for key, ends in nuisance.items():
        got = []
        for ents in ends:
            read = _readable(ents or [])
            j = next((i for i, e in enumerate(read) if e["file"] == name), None)
            if ents is None or j is None or len(read) < 3:
                got.append(None)
                continue
            try:
                got.append(_held_one(read[j], read[:j] + read[j + 1:])["residual_per_s"])
            except BounceError:
                got.append(None)
        out[key] = got
    return out


SAID = {"friction_N": "friction", "compression_N_s_per_m": "compression", "spring_scale": "spring",
        "friction_compression_together": "friction and compression (jointly)",
        "friction_compression_traded": "friction and compression (jointly)"}
STEP = 0.05  # clicks searched in this step
SHORT = {"friction_compression_together": "friction & compression jointly",
         "friction_compression_traded": "friction & compression jointly"}  # rebound.png's title


def _rates(law_ab, ks, rows, curve_of, only: int | None = None) -> np.ndarray:
    """The predicted first-rebound rate at clicks ``ks`` for law values ``law_ab`` (c0, slope): the law's
    coefficient carried through the curves of the two records that bracket each click, weighted
    linearly in clicks (at a record, its own curve); ``only``: 0 or 1, the lower or upper record's
    curve alone."""
    a, b = law_ab
    kr = np.array([e["clicks"] for e in rows], float)
    c = a + b * ks
    j = np.clip(np.searchsorted(kr, ks, side="right") - 1, 0, kr.size - 2)
    out = np.empty(ks.size)
    for i in range(kr.size - 1):
        m = j == i
        if not m.any():
            continue
        lo, hi = (np.asarray(curve_of(rows[i]), float), np.asarray(curve_of(rows[i + 1]), float))
        r_lo, r_hi = np.interp(c[m], lo[:, 0], lo[:, 1]), np.interp(c[m], hi[:, 0], hi[:, 1])
        w = np.clip((ks[m] - kr[i]) / (kr[i + 1] - kr[i]), 0.0, 1.0)
        out[m] = r_lo if only == 0 else r_hi if only == 1 else (1 - w) * r_lo + w * r_hi
    return out


def _crossing(ks, rates, target) -> float | None:
    """The first click where ``rates`` (falling with the clicks) reach ``target``; None when they do not."""
    below = np.flatnonzero(rates <= target)
    if not below.size or below[0] == 0:
        return None
    i = int(below[0])
    return float(ks[i - 1] + (rates[i - 1] - target) / (rates[i - 1] - rates[i]) * (ks[i] - ks[i - 1]))


def _one_answer(entries, target: float, key: str, curve_of, seed: int = 0) -> dict:
    """The answer at one spring (``key``: the coefficients', ``curve_of(e)``: each record's curve): the
    clicks where the law's coefficient, carried through the bracketing records' curves (``_rates``),
    gives the target rate; its range from ``DRAWS`` draws of the law, widened to hold the answers from
    the lower and the upper record's curve alone (the slams' curves differ: a replayed slam's rate per
    mm is not the same at one coefficient for every slam)."""
    law = fit_law(entries, key)
    rows = sorted((e for e in entries if e.get(key) is not None and curve_of(e)), key=lambda e: e["clicks"])
    arrays = {id(e): np.asarray(curve_of(e), float) for e in rows}  # each curve read into an array once, not at

    def curve(e):  # every draw's every bracket (a curve of thousands of points: 93 % of the answer's time)
        return arrays[id(e)]
    lo, hi = min(law["clicks"]), max(law["clicks"])
    ks = np.arange(lo, hi + 0.5 * STEP, STEP)
    ab = (law["c0_N_s_per_m"], law["slope_N_s_per_m_per_click"])
    rates = _rates(ab, ks, rows, curve)
    row = {"law": law, "searched_clicks": [lo, hi], "rate_at_searched_ends_per_s": [float(rates[0]), float(rates[-1])]}
    k = _crossing(ks, rates, target)
    if k is None:
        above = target < rates[-1]
        row["set_clicks"], row["past"] = None, "above" if above else "below"
        row["note"] = (f"no answer within the records: the law's rebound at {hi if above else lo:g} clicks is "
                       f"{rates[-1] if above else rates[0]:.2f} /s, still {'faster' if above else 'slower'} than the "
                       f"target: {'more' if above else 'fewer'} than {hi if above else lo:g} clicks (the law is not "
                       f"extrapolated): record a slam there")
        return row
    row["clicks_exact"] = k
    row["needed_N_s_per_m"] = float(ab[0] + ab[1] * k)
    rng = np.random.default_rng(seed)
    got, outside = [], 0
    for th in rng.multivariate_normal(ab, np.asarray(law["cov"]), size=DRAWS // 4):
        r = _rates(th, ks, rows, curve)
        kk = _crossing(ks, r, target)
        if kk is None:
            outside += 1
            kk = hi + 1.0 if target < r[-1] else lo - 1.0
        got.append(kk)
    alone = [_crossing(ks, _rates(ab, ks, rows, curve, only), target) for only in (0, 1)]
    row["clicks_by_curve"] = {"lower_record": alone[0], "upper_record": alone[1]}
    p_lo, p_hi = np.percentile(got, [2.5, 97.5])
    span = [p_lo, p_hi] + [a for a in alone if a is not None]
    row["set_clicks"] = int(round(k))
    row["clicks_range95"] = [int(math.floor(max(min(span), lo))), int(math.ceil(min(max(span), hi)))]
    row["law_half_clicks"] = [max(k - min(span), 0.0), max(max(span) - k, 0.0)]  # before whole clicks
    share = outside / (DRAWS // 4)
    row["draws_outside_searched"] = share
    if share > 0.025 or None in alone:
        row["note"] = "the range reaches past the records' clicks: it is wider than shown"
    return row


def records_clicks(entries, target: float) -> float | None:
    """The model-free cross-check: the clicks where the records' own first-rebound rates, joined by
    straight lines in clicks, reach ``target``; None when they do not fall with the clicks or the
    target lies outside them."""
    rows = sorted((e for e in entries if e.get("record_mid_rebound_per_s") is not None), key=lambda e: e["clicks"])
    ks = np.array([e["clicks"] for e in rows], float)
    rs = np.array([e["record_mid_rebound_per_s"] for e in rows], float)
    if ks.size < 2 or np.unique(ks).size < ks.size or not np.all(np.diff(rs) < 0) or not rs[-1] <= target <= rs[0]:
        return None
    return float(np.interp(target, rs[::-1], ks[::-1]))


def _end_clicks(ents, target: float):
    """The answer's clicks (exact) with the records read at one end of a value given (``ents``), "below"
    or "above" where it lies past the records read there, None where no law is read there."""
    read = _readable(ents or [])
    if len({e["clicks"] for e in read}) < 2:
        return None
    try:
        r = _one_answer(read, target, "rebound_N_s_per_m", lambda e: e.get("rate_curve"))
    except BounceError:
        return None
    return r.get("past") if r["set_clicks"] is None else r["clicks_exact"]


def carry(row: dict, target: float, nuisance: dict) -> dict:
    """The answer's range carrying the values given (``nuisance``: {name: [entries at the lower end of
    its 95 % interval, at the upper end]}, the records read there): the answer again at each end
    (``_end_clicks``), per value the larger move on each side, added in quadrature to the law's own
    half-widths (its draws and either curve alone), then to whole clicks within the records'. An end
    whose answer lies past the records read there opens that side (to the records' end); one where no
    law is read opens both. Sets "clicks_range95" (the law's alone kept as "clicks_range95_law"),
    "clicks_at_ends" and "range_open"."""
    k = row["clicks_exact"]
    lo, hi = row["searched_clicks"]
    moves, opened, at = [[], []], set(), {}
    for name, ends in nuisance.items():
        got = [_end_clicks(ents, target) for ents in (ends or [None, None])]
        at[name] = got
        for v in got:
            if v is None:
                opened |= {f"below: no law read at an end of the {SAID.get(name, name)} given",
                           f"above: no law read at an end of the {SAID.get(name, name)} given"}
            elif isinstance(v, str):
                opened.add(f"{v}: at an end of the {SAID.get(name, name)} given the answer lies {v} the records")
        moves[0].append(max([0.0] + [k - v for v in got if isinstance(v, float) and v < k]))
        moves[1].append(max([0.0] + [v - k for v in got if isinstance(v, float) and v > k]))
    half = [math.sqrt(row["law_half_clicks"][i] ** 2 + sum(m * m for m in moves[i])) for i in (0, 1)]
    low = lo if any(w.startswith("below") for w in opened) else int(math.floor(max(k - half[0], lo)))
    high = hi if any(w.startswith("above") for w in opened) else int(math.ceil(min(k + half[1], hi)))
    return {"clicks_range95_law": row["clicks_range95"], "clicks_range95": [int(low), int(high)],
            "clicks_at_ends": at, "range_open": sorted(opened), "range_carries": sorted(nuisance)}


def answer(entries, target_per_s: float | None, nuisance: dict | None = None) -> dict:
    """The setting for the target rate (module docstring), at the spring given and at its interval's ends.
    {"target_per_s", "rule", "source", "set_clicks", ...}; with no target, why there is no answer. With
    ``nuisance`` ({name: [entries at its lower end, at its upper end]}) the range carries them (``carry``)."""
    base = {"target_per_s": target_per_s, "rule": RULE, "source": SOURCE}
    if target_per_s is None:
        return {**base, "set_clicks": None,
                "note": "no target given (--rebound-target-per-s: the first rebound's rate to aim for, 1/s per mm of "
                        "height): no answer in clicks"}
    try:
        row = _one_answer(entries, target_per_s, "rebound_N_s_per_m", lambda e: e.get("rate_curve"))
    except BounceError as e:
        return {**base, "set_clicks": None, "note": str(e)}
    ends = []
    for i, which in ((0, "lower"), (1, "upper")):
        read = [e for e in entries if e.get("rebound_N_s_per_m") is not None]
        at = [{**e, "end_c": (e.get("at_spring_ci95") or [None, None])[i]} for e in read]
        if not any("at_spring_ci95" in e for e in read):
            ends.append(None)
            continue
        if any(e["end_c"] is None for e in at):
            none = [e["file"] for e in at if e["end_c"] is None]
            ends.append({"set_clicks": None, "note": f"none at the spring interval's {which} end ({', '.join(none)} "
                                                     f"read no coefficient there)"})
            continue
        try:
            r = _one_answer(at, target_per_s, "end_c", lambda e, i=i: (e.get("rate_curve_at_spring_ci95")
                                                                       or [None, None])[i])
            ends.append({k: r[k] for k in ("set_clicks", "clicks_exact", "note") if k in r})
        except BounceError as err:
            ends.append({"set_clicks": None, "note": f"none at the spring interval's {which} end: {err}"})
    if nuisance:
        row.update(carry(row, target_per_s, nuisance))
    return {**base, **row, "at_spring_ci95": ends, "records_clicks": records_clicks(entries, target_per_s)}


def held_out_line(rows) -> str | None:
    done = [r for r in rows if "holds" in r]
    if not done:
        return None
    parts = [f"{r['clicks']:g} clicks {r['predicted_rate_per_s']:.2f} /s against {r['record_rate_per_s']:.2f} "
             f"({r['z']:+.1f} sd, {'holds' if r['holds'] else 'MISSES'})" for r in done]
    n = sum(r["holds"] for r in done)
    k = max(len(r.get("restart_residuals_per_s") or []) for r in done)
    names = sorted({m for r in done if r.get("nuisance_sd_per_s") is not None
                    for m, v in (r.get("nuisance_residuals_per_s") or {}).items() if any(x is not None for x in v)})
    said = ["the law's", "the record's noise"] + ([f"the replay's reproducibility over {k} restart(s)"] if k else [])
    named = list(dict.fromkeys(SAID.get(m, m) for m in names))
    said += [f"the {' and '.join([', '.join(named[:-1])] + named[-1:] if len(named) > 1 else named)} given at "
             f"their 95 % ends"] if names else []
    sd = ("sd: " + ", ".join(said[:-1]) + " and " + said[-1] if len(said) > 2 else
          "sd: the law's and the record's noise; the replay's reproducibility not measured")
    return (f"rebound law held out (each record from the others; {sd}): {'; '.join(parts)}: {n} of {len(done)} "
            f"within 2 sd")


def answer_line(ans: dict) -> str:
    head = "rebound answer"
    if ans["target_per_s"] is not None:
        head += f" (first rebound at {ans['target_per_s']:.2f} /s per mm of height)"
    if ans.get("set_clicks") is None:
        return f"{head}: {ans.get('note', 'none')}"
    carried = [SAID.get(m, m) for m in ans.get("range_carries") or []]
    said_range = ("95 % of the law's draws and either bracketing slam's curve alone" + (
        f", with the {', '.join(dict.fromkeys(carried))} given at their 95 % ends" if carried else "") + (
        f"; open {' and '.join(sorted({w.split(':')[0] for w in ans['range_open']}))}" if ans.get("range_open") else ""))
    text = (f"{head}: set {ans['set_clicks']} clicks ({ans['clicks_exact']:.1f} on the law, "
            f"{ans['needed_N_s_per_m']:.0f} N s/m); within the uncertainty {ans['clicks_range95'][0]}-{ans['clicks_range95'][1]} clicks ("
            f"{said_range})")
    ends = ans.get("at_spring_ci95") or []
    said = []
    for which, e in zip(("lower", "upper"), ends):
        if e is None:
            continue
        said.append(f"at the spring's {which} end {e['set_clicks']} clicks" if e.get("set_clicks") is not None
                    else e.get("note", f"none at the spring's {which} end"))
    if said:
        text += "; " + "; ".join(said)
    if ans.get("note"):
        text += f"; {ans['note']}"
    if ans.get("records_clicks") is not None:
        text += f"; model-free, the records' own rates joined in clicks reach it at {ans['records_clicks']:.1f} clicks"
    return text


def figure_png(got: dict) -> bytes:
    """rebound.png (``figure``) as PNG bytes."""
    from mtbmj.readout.quicklook import png

    return png(figure(got), dpi=80)


def figure(got: dict):
    """rebound.png's figure: (left) each record's rebound coefficient against its clicks with its 95 % interval
    (an open side drawn to the axis' edge, dashed), the law with its 95 % band and the answer's clicks
    and coefficient; (right) the records' first-rebound rates with their 95 % noise, the held-out
    predictions with theirs, and the target."""
    from matplotlib.figure import Figure

    recs = [e for e in got["records"] if e.get("rebound_N_s_per_m") is not None]
    fig = Figure(figsize=(10.0, 4.0))
    ax, bx = fig.subplots(1, 2)
    top = max([e["rebound_N_s_per_m_ci95"][1] or e["rebound_N_s_per_m"] for e in recs] + [1.0]) * 1.1
    for e in recs:
        k, c = e["clicks"], e["rebound_N_s_per_m"]
        lo, hi = e["rebound_N_s_per_m_ci95"]
        ax.plot([k, k], [c, hi if hi is not None else top], color="k", lw=1.2, ls="-" if hi is not None else "--")
        ax.plot([k, k], [lo if lo is not None else 0.0, c], color="k", lw=1.2, ls="-" if lo is not None else "--")
        n = e.get("rebound_noise_ci95") or [None, None]
        if None not in n:
            ax.plot([k, k], n, "C3-", lw=4, alpha=0.6)
        ax.plot(k, c, "ko")
    law = got.get("law") or {}
    if "c0_N_s_per_m" in law:
        ks = np.linspace(min(law["clicks"]), max(law["clicks"]), 100)
        cov = np.asarray(law["cov"])
        X = np.column_stack((np.ones_like(ks), ks))
        mid = law["c0_N_s_per_m"] + law["slope_N_s_per_m_per_click"] * ks
        band = Z95 * np.sqrt(np.einsum("ij,jk,ik->i", X, cov, X))
        ax.plot(ks, mid, "C0", label=f"law {law['c0_N_s_per_m']:.0f} + {law['slope_N_s_per_m_per_click']:.1f} x clicks")
        ax.fill_between(ks, mid - band, mid + band, color="C0", alpha=0.3)
    ans = got.get("answer") or {}
    if ans.get("set_clicks") is not None:
        ax.axvspan(*ans["clicks_range95"], color="C2", alpha=0.15, label="answer's range (95 %)")
        ax.plot(ans["clicks_exact"], ans["needed_N_s_per_m"], "C2*", ms=12,
                label=f"set {ans['set_clicks']} clicks for {ans['target_per_s']:.2f} /s")
    ax.plot([], [], "k--", label="open side (an end given reads none)")
    ax.plot([], [], "C3-", lw=4, alpha=0.6, label="record's noise alone")
    ax.set_ylim(0.0, top)
    ax.set_xlabel("rebound clicks")
    ax.set_ylabel("rebound coefficient at the shock (N s/m)")
    refused = ", ".join(format(e["clicks"], "g") for e in got["records"] if "refused" in e)
    said = [f"spring {got['spring_scale']:.2f} x from {got['spring_from'].split(' (')[0]}"] if "spring_from" in got else []
    said += [f"refused at {refused} clicks"] if refused else []
    again = any(e.get("rebound_reproducibility_sd_N_s_per_m") is not None for e in got["records"])
    given = sorted({k for e in got["records"] for k in (e.get("at_nuisance_ci95") or {})})
    parts = list(dict.fromkeys(["noise", "spring"] + [SHORT.get(k, k.split("_")[0]) for k in given]
                               + (["restarts"] if again else [])))
    ax.set_title(f"rebound dampers from the first rebounds (95 %: {', '.join(parts)})"
                 + ("\n" + "; ".join(said) if said else ""), fontsize=8)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(alpha=0.3)
    for e in got["records"]:
        r, sd = e.get("record_mid_rebound_per_s"), e.get("record_rate_sd_per_s") or 0.0
        if r is not None:
            bx.errorbar(e["clicks"], r, yerr=Z95 * sd, fmt="ko", capsize=3)
    bx.plot([], [], "ko", label="record (95 % noise)")
    for row in got.get("held_out") or []:
        if "holds" in row:
            err = Z95 * math.hypot(row["predicted_rate_sd_per_s"], row.get("reproducibility_sd_per_s") or 0.0,
                                   row.get("nuisance_sd_per_s") or 0.0)
            bx.errorbar(row["clicks"] + 0.3, row["predicted_rate_per_s"], yerr=err,
                        fmt="s", color="C1" if row["holds"] else "C3", capsize=3)
    held = [r for r in got.get("held_out") or [] if "holds" in r]
    shares = ["law"] + (["values given"] if any(r.get("nuisance_sd_per_s") for r in held) else []) \
        + (["restarts"] if any(r.get("reproducibility_sd_per_s") for r in held) else [])
    bx.plot([], [], "s", color="C1", label=f"held out: predicted from the others (95 %: {', '.join(shares)})")
    if ans.get("target_per_s") is not None:
        bx.axhline(ans["target_per_s"], color="C2", ls=":", label=f"target {ans['target_per_s']:.2f} /s")
    bx.set_xlabel("rebound clicks")
    bx.set_ylabel("first rebound: mid speed per mm of height (1/s)")
    bx.set_title("the records' first rebounds and each held out", fontsize=9)
    bx.legend(fontsize=7)
    bx.grid(alpha=0.3)
    fig.tight_layout()
    return fig


__all__ = ["HOLD_SIGMAS", "RULE", "SOURCE", "answer", "answer_line", "figure", "figure_png", "fit_law", "held_out",
           "held_out_line", "records_clicks"]

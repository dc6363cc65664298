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
changes none of them), the push fitted on the record up to its peak (``bounce_replay.fit_push``),
then the rebound coefficient solved (``brentq``) so that the replay's first rebound, read as the
record's (``bounce.first_rebound``), has the record's middle speed per millimetre of the peak's
height above rest (1/s: for a linear end independent of how high the slam went, so the replay's
peak need not match the record's). Its spread: the same solve with the spring at the ends of the
interval given (``spring_ci95``), which is what moves it most (0.49 x gives 208, 2591, 5368 N s/m
on the shared slams, 0.6 x 961, 3956, 7065). Refused for the record (a reason, no value) when no
coefficient within ``BOUNDS`` gives the record's speed: the bike with the spring given rebounds
slower than the record even undamped, or faster even at the largest coefficient.
"""
from __future__ import annotations

import numpy as np

from mtbmj.identify.bounce import BounceError, first_rebound
from mtbmj.identify.bounce_replay import NAMES, Slam, fit_push

BOUNDS = (50.0, 30000.0)  # N s/m: the rebound coefficient sought within these (bounce_replay's damper bounds)
XTOL = 1.0  # N s/m
DAMPER = NAMES.index("damper_N_s_per_m")


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


def solve(sl: Slam, record: dict, spring_scale: float, friction_N: float, compression: float) -> float:
    """The rebound coefficient (N s/m) whose replay has the record's first rebound (``record``:
    ``first_rebound`` of the record) per mm of height; BounceError when none within BOUNDS does."""
    from scipy.optimize import brentq

    target = _per_mm(record)
    if not np.isfinite(target):
        raise BounceError(f"{sl.name}: the record's first rebound has no middle (it does not pass from 75 % to "
                          f"25 % of the slam's height): no rebound damper is read from it")
    x = sl.x0.copy()
    x[NAMES.index("spring_scale")], x[NAMES.index("friction_N")] = spring_scale, friction_N
    extra = {"compression_N_s_per_m": float(compression)}
    u = (x - sl.x0) / sl.base
    fit_push(sl, u, extra=extra)  # the push on the compression, the shock held
    x = sl.x0 + u * sl.base

    def gap(c):
        xx = x.copy()
        xx[DAMPER] = c
        return _per_mm(replay_rebound(sl, xx, extra)) - target

    lo, hi = gap(BOUNDS[0]), gap(BOUNDS[1])
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0.0 or hi > 0.0:
        side = "slower than the record even undamped" if lo < 0.0 else "faster than the record at the largest"
        raise BounceError(f"{sl.name}: no rebound coefficient within {BOUNDS[0]:g}-{BOUNDS[1]:g} N s/m gives the "
                          f"record's first rebound ({target:.2f} /s): with the spring at {spring_scale:.2f} x the bike "
                          f"rebounds {side} coefficient")
    return float(brentq(gap, *BOUNDS, xtol=XTOL))


def rebound_dampers(slams, clicks, spring_scale: float, friction_N: float, compression: float,
                    spring_ci95=None) -> list[dict]:
    """Per slam (``bounce_replay.prepare_slam``; each record's ``first_rebound`` read from its own
    window) its rebound coefficient, or ``"refused"`` with the reason; with ``spring_ci95`` also the
    coefficients at the spring's interval ends (``at_spring_ci95``, either None where refused)."""
    out = []
    for sl, k in zip(slams, clicks):
        peak = int(np.argmin(np.abs(sl.tt)))
        record = first_rebound(sl.tt, sl.rec, peak, 0.0)
        per_mm = _per_mm(record)
        entry = {"file": sl.name, "clicks": k, "record_mid_rebound_per_s": per_mm if np.isfinite(per_mm) else None,
                 "spring_scale": float(spring_scale), "friction_N": float(friction_N),
                 "compression_N_s_per_m": float(compression)}
        try:
            entry["rebound_N_s_per_m"] = solve(sl, record, spring_scale, friction_N, compression)
        except BounceError as e:
            entry["refused"] = str(e)
            out.append(entry)
            continue
        if spring_ci95 is not None:
            ends = []
            for s in spring_ci95:
                try:
                    ends.append(solve(sl, record, max(float(s), 0.2), friction_N, compression))
                except BounceError:
                    ends.append(None)
            entry["at_spring_ci95"] = ends
        out.append(entry)
    return out


def rises(entries) -> bool | None:
    """Do the read coefficients rise strictly with the clicks? None with fewer than two read."""
    done = sorted((e for e in entries if "rebound_N_s_per_m" in e), key=lambda e: e["clicks"])
    if len({e["clicks"] for e in done}) < 2:
        return None
    return all(b["rebound_N_s_per_m"] > a["rebound_N_s_per_m"] for a, b in zip(done, done[1:])
               if b["clicks"] > a["clicks"])


def read_records(records, clicks, replayed: list, bike="sst", rider_hz: float | None = None) -> dict | None:
    """``fit bounce --replay``'s ``"rebound_dampers"``: every record's rebound coefficient, the spring
    (with its interval), friction and compression given by the best-determined whole-trace replay
    (``replayed``: ``bounce_replay.replay_records``' summary; the one whose spring interval is the
    narrowest; its one damper taken as the compression). None when no record was replayed."""
    from mtbmj.identify.bounce_replay import RIDER_HZ, SeatedReplay, prepare_slam

    done = [e for e in replayed if "refused" not in e]
    if not done:
        return None
    best = min(done, key=lambda e: e["spring_scale_ci95"][1] - e["spring_scale_ci95"][0])
    sr = SeatedReplay(bike, RIDER_HZ if rider_hz is None else rider_hz)
    slams, ks, entries = [], [], []
    for rec, k in zip(records, clicks):
        name = getattr(rec, "name", None) or str(getattr(rec, "path", "record"))
        try:
            slams.append(prepare_slam(rec.time_s, rec.shock_mm, rec.fork_mm, name, sr,
                                      getattr(rec, "shock_max_mm", None)))
            ks.append(k)
        except BounceError as e:
            entries.append({"file": name, "clicks": k, "refused": str(e)})
    entries = rebound_dampers(slams, ks, best["spring_scale"], best["friction_N"], best["damper_N_s_per_m"],
                              best["spring_scale_ci95"]) + entries
    entries.sort(key=lambda e: e["clicks"])
    up = rises(entries)
    read = [e for e in entries if "rebound_N_s_per_m" in e]
    said = ", ".join(f"{e['rebound_N_s_per_m']:.0f}" for e in read)
    at = ", ".join(format(e["clicks"], "g") for e in read)
    line = (f"rebound dampers from the first rebounds (spring {best['spring_scale']:.2f} x, friction "
            f"{best['friction_N']:.0f} N, compression {best['damper_N_s_per_m']:.0f} N s/m from {best['file']}'s "
            f"replay): {said or 'none'} N s/m at {at or 'no'} clicks"
            + ("" if up is None else ": they rise with the clicks" if up else ": they do not rise with the clicks"))
    return {"from": best["file"], "records": entries, "rises": up, "line": line}


__all__ = ["BOUNDS", "read_records", "rebound_dampers", "replay_rebound", "rises", "solve"]

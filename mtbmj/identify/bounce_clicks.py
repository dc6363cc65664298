"""An answer in clicks: the rebound setting a stated target asks for, from the decay law with friction.

**The target** ("one overshoot"): after a hit, "the shock compresses, rebounds further than it
started, and returns to its original position" (whafi.com, "Testing and adjusting rebound damping
for the best setting": too fast when it springs back and kicks, too slow when it wallows). In the law
(:mod:`mtbmj.identify.bounce_decay`; amplitudes from the static position x_eq, a_{n+1} = r a_n -
(1 + r) d, at rest once an extremum lies within the friction band d) a hit that compresses the end
``hit_mm`` above x_eq (a_0) meets it when the first rebound passes the rest band (a_1 > d: it
rebounds further than it started) and the next extremum lies within it (a_2 <= d: it returns and
stays). More damping than that leaves no overshoot (a_1 <= d: it wallows); less gives a second one
(a_2 > d: pogo). The clicks that meet it form a window between those two limits (the overshoots
never increase with the damping); the answer is the whole number of clicks nearest the window's
middle, between pogo and packing as ShockWiz ("Goldilocks Rebound") puts it, "often 2 or 3 clicks of
rebound between the two phenomena".

**The uncertainty**: the window's middle over 400 draws of (zeta0, slope, d) from the law's
covariance (seeded); its 2.5 and 97.5 percentiles, widened to whole clicks, are the range of clicks
within the uncertainty. Only clicks between the records' are searched (a law linear in clicks is not
extrapolated); a window that reaches past them on one side is said to (its middle is then the
middle of the part within them), one that reaches past both tells no setting, and an answer that
lies past them is refused with the side it lies on ("more than 17 clicks: record a slam there").
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtbmj.identify import bounce_decay as bd

TARGET = "one overshoot"
RULE = ("from a hit hit_mm above the static position, the first rebound passes the friction band (a_1 > d: it "
        "rebounds further than it started) and the next extremum lies within it (a_2 <= d: it returns to its "
        "position and stays); a_{n+1} = r a_n - (1 + r) d; the answer: the whole click nearest the middle of the "
        "window of clicks that meet it")
SOURCE = ("whafi.com, 'Testing and adjusting rebound damping for the best setting' (after a small drop-off 'the shock "
          "compresses, rebounds further than it started, and returns to its original position'); ShockWiz, "
          "'Goldilocks Rebound' (between pogo and packing, 'often 2 or 3 clicks of rebound')")
STEP = 0.05  # clicks searched in this step
DRAWS = 400


def overshoots(zeta: float, d: float, hit_mm: float) -> int:
    """How many times the law's motion passes the rest band after a hit ``hit_mm`` above x_eq."""
    r = bd.ratio(zeta)
    a, n = hit_mm, 0
    while n < 100:
        a = r * a - (1.0 + r) * d
        if a <= d:
            return n
        n += 1
    return n


def window(zeta_of, d: float, hit_mm: float, lo: float, hi: float) -> tuple[float | None, float | None, str]:
    """(first click with one overshoot, last click with one, where the window lies) over lo..hi
    (``zeta_of(k)``); "inside", "above" (pogo at hi: it needs more clicks), "below" (no overshoot at lo),
    or "spans" when the window reaches past both ends."""
    ks = np.arange(lo, hi + 0.5 * STEP, STEP)
    n = np.array([overshoots(zeta_of(k), d, hit_mm) for k in ks])
    one = np.flatnonzero(n == 1)
    if one.size == 0:
        return None, None, "above" if n[-1] >= 2 else "below"
    a, b = float(ks[one[0]]), float(ks[one[-1]])
    if one[0] == 0 and one[-1] == ks.size - 1:
        return a, b, "spans"
    return a, b, "inside"


@dataclass
class ClickAnswer:
    """The rebound setting for the target on one end: ``clicks`` (None when the law cannot answer,
    with ``note`` saying why), the window of clicks that meet it, and the range within the uncertainty."""

    end: str
    hit_mm: float
    searched: tuple
    clicks: int | None
    window: tuple | None  # (first, last) click meeting the target, within the searched clicks
    window_open: tuple  # (window reaches below the searched clicks, above them)
    range95: tuple | None  # whole clicks holding 95 % of the draws' middles
    draws_outside: float  # share of the draws whose window lies outside the searched clicks
    note: str = ""

    def summary(self) -> dict:
        return {"target": TARGET, "rule": RULE, "source": SOURCE, "hit_mm": self.hit_mm,
                "searched_clicks": list(self.searched), "set_clicks": self.clicks,
                "window_clicks": None if self.window is None else list(self.window),
                "window_reaches_past": {"below": self.window_open[0], "above": self.window_open[1]},
                "clicks_range95": None if self.range95 is None else list(self.range95),
                "draws_outside_searched": self.draws_outside, **({"note": self.note} if self.note else {})}

    def line(self) -> str:
        head = f"{self.end} answer ({TARGET} after a {self.hit_mm:.1f} mm hit): "
        if self.clicks is None:
            return head + self.note
        lo, hi = self.window
        text = (f"set {self.clicks} clicks (meets it from {lo:.1f} to {hi:.1f} clicks"
                + (", and past the records below" if self.window_open[0] else "")
                + (", and past the records above" if self.window_open[1] else "") + ")")
        if self.range95 is not None:
            text += f"; within the uncertainty {self.range95[0]}-{self.range95[1]} clicks (95 %)"
        if self.note:
            text += f"; {self.note}"
        return head + text


def answer(law, hit_mm: float) -> ClickAnswer:
    """The setting for the one-overshoot target from ``law`` (a :class:`mtbmj.identify.bounce_predict.DecayLaw`)
    after a hit ``hit_mm`` above the static position."""
    lo, hi = float(min(law.clicks)), float(max(law.clicks))
    searched = (lo, hi)
    z0d = law.zeta_d

    def zeta_at(k, th=None):
        return z0d(k)[0] if th is None else th[0] + th[1] * k

    names = law.fit.names
    if "zeta0" not in names:
        return ClickAnswer(law.end, hit_mm, searched, None, None, (False, False), None, 1.0,
                           "no answer: the chosen law has no damping that changes with the clicks (friction only)")
    d = z0d(lo)[1]
    if zeta_at(hi) < zeta_at(lo):  # the window's "more clicks" / "fewer clicks" read clicks as adding damping
        return ClickAnswer(law.end, hit_mm, searched, None, None, (False, False), None, 1.0,
                           f"no answer: the law's damping falls as the clicks rise (zeta {zeta_at(lo):.3f} at {lo:g} "
                           f"clicks, {zeta_at(hi):.3f} at {hi:g}) where rebound clicks add damping: --clicks not in "
                           f"the records' order, or counted from closed?")
    a, b, where = window(zeta_at, d, hit_mm, lo, hi)
    if where == "above":
        return ClickAnswer(law.end, hit_mm, searched, None, None, (False, True), None, 1.0,
                           f"no answer within the records: at {hi:g} clicks the law still overshoots twice or more; "
                           f"more than {hi:g} clicks (the law is not extrapolated): record a slam at more clicks")
    if where == "below":
        return ClickAnswer(law.end, hit_mm, searched, None, None, (True, False), None, 1.0,
                           f"no answer within the records: at {lo:g} clicks the law already does not overshoot; fewer "
                           f"than {lo:g} clicks (the law is not extrapolated): record a slam at fewer clicks")
    open_lo, open_hi = a <= lo + 1e-9, b >= hi - 1e-9
    if open_lo and open_hi:
        return ClickAnswer(law.end, hit_mm, searched, None, (a, b), (True, True), None, 1.0,
                           f"no single setting told: every setting from {lo:g} to {hi:g} clicks meets it (the window's "
                           f"limits lie past the records' clicks); a larger hit, or slams at more and fewer clicks, "
                           f"would place them")
    mid = 0.5 * (a + b)
    # the draws: zeta0, slope and d from the law's covariance
    iz, js, jd = names.index("zeta0"), names.index("slope_per_click"), (
        names.index("friction_band_mm") if "friction_band_mm" in names else None)
    idx = [iz, js] + ([jd] if jd is not None else [])
    mean = law.fit.theta[idx]
    cov = law.fit.cov[np.ix_(idx, idx)]
    rng = np.random.default_rng(0)
    mids = []
    outside = 0
    for th in rng.multivariate_normal(mean, cov, size=DRAWS):
        dd = max(float(th[2]), 0.0) if jd is not None else 0.0
        x, y, w = window(lambda k, th=th: zeta_at(k, th), dd, hit_mm, lo, hi)
        if w in ("above", "below"):
            outside += 1
            mids.append(hi + 1.0 if w == "above" else lo - 1.0)
        else:
            mids.append(0.5 * (x + y))
    share = outside / DRAWS
    p_lo, p_hi = np.percentile(mids, [2.5, 97.5])
    rng95 = (int(math.floor(max(p_lo, lo))), int(math.ceil(min(p_hi, hi))))
    note = ""
    if open_lo or open_hi:
        note = ("the window reaches past the records' clicks, so its middle (and the answer) is only as far as "
                "they go")
    if share > 0.025:
        note = (note + "; " if note else "") + (f"{100 * share:.0f} % of the draws put the window outside the "
                                                f"records' clicks: the range is wider than shown")
    return ClickAnswer(law.end, hit_mm, searched, int(round(mid)), (a, b), (open_lo, open_hi), rng95, share, note)


def default_hit(law) -> float:
    """The records' own hit: the median over the records of their first free extremum's distance
    from x_eq (mm)."""
    hits = [abs(float(s.levels_mm[0]) - law.x_eq_of(s, k)) for s, k in zip(law.seqs, law.clicks) if s.levels_mm.size]
    return float(np.median(hits))


__all__ = ["ClickAnswer", "RULE", "SOURCE", "TARGET", "answer", "default_hit", "overshoots", "window"]

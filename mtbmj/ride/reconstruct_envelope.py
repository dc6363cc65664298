"""What a trail can be: the ground a reconstruction found checked against what the ridden bike could
climb (issue 51; ``reconstruct.reconstruct`` uses it).

**The bound.** A bike that rolls from a low point of the ground to a higher one within
``RISE_WINDOW_S`` climbs on its kinetic energy and what its rider adds by pedalling: a rise of Δh
over the T seconds between them needs

    g Δh <= v^2 / 2 + P T / m

(energy per kg: the bike arrives with nothing left, no rolling or air drag), with v the highest
speed of the ride's speed profile over the stretch, P = ``PEDAL_POWER_W`` (a strong rider's 5 s
sprint, 13 W/kg at 75 kg: generous, nobody sprints up a kicker's face) and m the bike with its
rider. A ground found that rises more than that is not a trail the bike rode: it is the
reconstruction's (00100.SST at 7.5 m/s, while the whole bike took the hard stop's impulse its quarter
car found after a long fall: 4.3 m up in 1.0 s, 15.8-16.8 s, where 3.8 m is the most;
``reconstruct_flight.stop_kicks`` since).
Falls are not bounded (a drop is a trail's). The rise is looked for on the ground read every
``STEP_S``.

**Where.** Each stretch exceeded runs from its low point to its high point and on until the ground
falls back below the highest it could have reached from the low point (at most ``RISE_WINDOW_S``
past the high point): the hump's back is the reconstruction's too. Its samples are not checked
(``reconstruct`` leaves them out), ``reconstruction.json`` lists it (``beyond_trail``) and one
``ConfigWarning`` names it (:func:`warn`); ``reconstruction.png`` shades it, hatched, in each panel
(:func:`shade`).
"""
from __future__ import annotations

import numpy as np

RISE_WINDOW_S = 2.0  # a rise is looked for within this long before each sample (15 m at 7.5 m/s)
PEDAL_POWER_W = 1000.0  # the most a rider adds by pedalling over a few seconds
STEP_S = 0.01  # the ground read every this for the bound (a rise the bound sees takes tenths of a second)


def beyond(t, distance, ground, speed, mass: float, gravity: float = 9.81) -> list:
    """The stretches where ``ground`` (m on ``t``) rises more than the bike of ``mass`` (kg, with its
    rider) at ``speed`` (m/s on ``t``) could climb (module doc): [{"start_s", "end_s", "start_m",
    "end_m" (along ``distance``), "rise_m", "allowed_m" (the most the bound allows for that rise),
    "speed_m_per_s"}], by time."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    t, x = np.asarray(t, float), np.asarray(distance, float)
    z, v = np.asarray(ground, float), np.asarray(speed, float)
    dt = float(t[1] - t[0])
    k = max(int(round(STEP_S / dt)), 1)
    zs, vs = z[::k], v[::k]
    w = max(int(round(RISE_WINDOW_S / (k * dt))), 1)
    # g dh <= v^2/2 + P T/m between a low point i and a later j: (z_j - c t_j) - (z_i - c t_i) <= v^2/2g with c
    # the climb rate pedalling gives, P/(m g); over trailing windows (the sample and the w before it) the
    # lowest of z - c t and the highest speed
    ts = t[::k]
    c = PEDAL_POWER_W / (mass * gravity)
    y = zs - c * ts
    low = minimum_filter1d(y, w + 1, origin=w // 2, mode="nearest")
    fast = maximum_filter1d(vs, w + 1, origin=w // 2, mode="nearest")
    energy = fast ** 2 / (2.0 * gravity)
    spans = []
    for j in np.flatnonzero(y - low > energy):
        part = y[max(j - w, 0):j + 1]
        i = max(j - w, 0) + part.size - 1 - int(np.argmin(part[::-1]))  # the latest lowest: the rise's foot
        rise, allowed = zs[j] - zs[i], energy[j] + c * (ts[j] - ts[i])
        back = j + 1
        while back < min(j + w, zs.size - 1) and zs[back] > zs[i] + allowed:
            back += 1
        if spans and i <= spans[-1][1]:
            a, b, r, al, s = spans[-1]
            spans[-1] = (a, max(b, back), max(r, rise), al if r >= rise else allowed, max(s, fast[j]))
        else:
            spans.append((i, back, rise, allowed, fast[j]))
    n = t.size - 1
    return [{"start_s": float(t[min(a * k, n)]), "end_s": float(t[min(b * k, n)]),
             "start_m": round(float(x[min(a * k, n)]), 2), "end_m": round(float(x[min(b * k, n)]), 2),
             "rise_m": round(float(r), 3), "allowed_m": round(float(al), 3), "speed_m_per_s": round(float(s), 2)}
            for a, b, r, al, s in spans]


def mask(t, stretches) -> np.ndarray:
    """The samples of ``t`` within the ``stretches`` (``beyond``'s)."""
    t = np.asarray(t, float)
    out = np.zeros(t.size, bool)
    for s in stretches or []:
        out |= (t >= s["start_s"]) & (t <= s["end_s"])
    return out


LABEL = "beyond what the bike could climb (not checked)"  # the figure's legend for the stretches


def shade(ax, stretches, along: str = "s") -> list:
    """Each of ``stretches`` (``beyond``'s) shaded on ``ax`` over its times (``along`` "s") or its
    places ("m"), hatched, labelled ``LABEL`` once for the legend: the artists drawn."""
    return [ax.axvspan(s[f"start_{along}"], s[f"end_{along}"], facecolor="C4", alpha=0.25, hatch="//",
                       label=LABEL if i == 0 else "_nolegend_") for i, s in enumerate(stretches or [])]


def warn(ride: str, stretches) -> None:
    """One ``ConfigWarning`` naming where the ground found leaves what the bike could climb."""
    import warnings

    from mtbmj.errors import ConfigWarning

    def apart(rise, allowed):  # as few decimals as show the rise above what is allowed (0.62 for 0.58, not 0.6 for 0.6)
        digits = next((d for d in (1, 2) if round(rise, d) > round(allowed, d)), 3)
        return f"{rise:.{digits}f} m up, at most {allowed:.{digits}f}"

    if stretches:
        where = ", ".join(f"{s['start_m']:.0f}-{s['end_m']:.0f} m ({s['start_s']:.1f}-{s['end_s']:.1f} s: "
                          f"{apart(s['rise_m'], s['allowed_m'])})" for s in stretches)
        warnings.warn(f"{ride}: the terrain found rises more than the bike at its speed could climb at {where} "
                      f"(v^2/2g and {PEDAL_POWER_W:g} W of pedalling): no trail is so, the reconstruction's "
                      f"own; not checked there", ConfigWarning, stacklevel=2)


__all__ = ["RISE_WINDOW_S", "PEDAL_POWER_W", "STEP_S", "LABEL", "beyond", "mask", "shade", "warn"]

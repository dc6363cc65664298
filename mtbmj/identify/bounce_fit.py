"""The bounce fit (``mtbmj fit bounce``): each record's seat slam read as a ring-down
(``mtbmj.identify.bounce``) and as a decay with friction (``mtbmj.identify.bounce_decay``), the
damping per rebound click as a law, the ring-down it predicts at other clicks, and optionally
each ring-down through a bike's seated model (``mtbmj.identify.bounce_bike``): one
:class:`BounceFit` that the command and the Python API read alike (its summary, files and lines)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mtbmj.errors import MtbmjError


@dataclass
class BounceFit:
    """What a bounce fit found: ``summary`` (fit.json's content), the ``records`` read, each
    record's ring-down ``fits`` by end, the click ``laws`` by end, the records' ``clicks`` and the
    predicted ring-downs' ``csv`` columns by file name."""

    summary: dict
    records: list
    fits: list
    laws: dict
    clicks: list
    csv: dict

    def files(self) -> dict[str, bytes]:
        """fit.json, fit.png and ringdown_<K>_clicks.csv per predicted click, as bytes."""
        from mtbmj import output

        files = {"fit.json": json_bytes(self.summary), "fit.png": figure_png(self)}
        for name, cols in self.csv.items():
            files[name] = output.csv_bytes(cols)
        return files

    def write(self, out_dir) -> list[Path]:
        """The files written atomically to ``out_dir`` (``mtbmj.output.write_atomically``)."""
        from mtbmj import output

        return output.write_atomically(out_dir, self.files())

    def lines(self) -> list[str]:
        """What the command prints: each record's fits, decays, the laws, the predictions, the notes."""
        out = []
        for rec in self.summary["records"]:
            parts = []
            for end in ("shock", "fork"):
                e = rec.get(end)
                if e is None:
                    continue
                if e["damping_ratio"] is None:
                    parts.append(f"{end}: {e.get('note', 'no fit')}")
                else:
                    lo, hi = e["damping_ratio_ci95"]
                    flo, fhi = e["frequency_hz_ci95"]
                    parts.append(f"{end} zeta {e['damping_ratio']:.3f} [{lo:.3f}, {hi:.3f}], "
                                 f"{e['frequency_hz']:.2f} Hz [{flo:.2f}, {fhi:.2f}]" + _bike_text(e.get("bike")))
            out.append(f"{rec['file']} at {rec['clicks']:g} clicks: {'; '.join(parts)}")
        for rec in self.summary["records"]:
            for end in ("shock", "fork"):
                dec = rec.get(end, {}).get("decay")
                if dec is None:
                    continue
                if dec["model"] is None:
                    out.append(f"{rec['file']} {end} decay: {dec['note']}")
                    continue
                zl, zh = dec["damping_ratio_ci95"]
                dl, dh = dec["friction_band_mm_ci95"]
                out.append(f"{rec['file']} {end} decay ({dec['model']}, BIC): zeta {dec['damping_ratio']:.3f} [{zl:.3f}, {zh:.3f}], "
                           f"friction band {dec['friction_band_mm']:.2f} mm [{dl:.2f}, {dh:.2f}], first half cycle's decay "
                           f"{dec['measured_first_half_cycle_decay']:.2f} (law {dec['law_first_half_cycle_decay']:.2f})")
        for end, dl in self.summary.get("decay_law", {}).items():
            per = ", ".join(f"{p['clicks']:g}: {p['damping_ratio']:.3f} [{p['damping_ratio_ci95'][0]:.3f}, "
                            f"{p['damping_ratio_ci95'][1]:.3f}]" for p in dl["per_click"])
            lo, hi = dl["friction_band_mm_ci95"]
            out.append(f"{end} decay law ({dl['model']}, BIC; friction common to the clicks): friction band "
                       f"{dl['friction_band_mm']:.2f} mm [{lo:.2f}, {hi:.2f}]; zeta per click {per}")
        for end, law in self.summary["law"].items():
            out.append(f"{end} law: zeta = {law['zeta0']:.3f} + {law['slope_per_click']:.4f} x clicks "
                       f"(slope 95 % [{law['slope_per_click_ci95'][0]:.4f}, {law['slope_per_click_ci95'][1]:.4f}]), "
                       f"undamped {law['undamped_frequency_hz']:.2f} Hz")
            if "bike" in law:
                b = law["bike"]
                out.append(f"{end} damper law: {b['damper0_N_s_per_m']:.0f} + {b['slope_N_s_per_m_per_click']:.1f} x clicks N s/m "
                           f"(slope 95 % [{b['slope_N_s_per_m_per_click_ci95'][0]:.1f}, "
                           f"{b['slope_N_s_per_m_per_click_ci95'][1]:.1f}])")
        for p in self.summary["predicted"]:
            for end in ("shock", "fork"):
                if end in p:
                    e = p[end]
                    freq = (f"{e['frequency_hz']:.2f} Hz" if e["frequency_hz"] is not None else
                            e.get("note", "no oscillation"))
                    out.append(f"predicted at {p['clicks']:g} clicks: {end} zeta {e['damping_ratio']:.3f} "
                               f"[{e['damping_ratio_ci95'][0]:.3f}, {e['damping_ratio_ci95'][1]:.3f}], {freq}"
                               + _bike_text(e.get("bike")))
        for note in self.summary["notes"]:
            out.append(f"note: {note}")
        return out


def _records(paths, clicks):
    from mtbmj.measured.telemetry import read_sst

    return [read_sst(p) for p in paths]


RATE_AGREES = 1.25  # a ring-down's spring rate within this factor of the bike file's says nothing


def _through_bike(seated, end: str, zeta: float, zeta_sd: float, fd: float, fd_sd: float) -> dict:
    try:
        return seated.identify(end, zeta, zeta_sd, fd, fd_sd)
    except MtbmjError as e:
        return {"note": str(e)}


def _damper_law(points) -> dict | None:
    """damper = c0 + slope x clicks by weighted least squares over the records' (clicks, c, sd)."""
    pts = [(k, c, sd) for k, c, sd in points if math.isfinite(sd) and sd > 0]
    if len({k for k, _, _ in pts}) < 2:
        return None
    from mtbmj.identify.bounce import interval95, weighted_line

    beta, cov, _ = weighted_line([p[0] for p in pts], [p[1] for p in pts], [p[2] for p in pts])
    return {"form": "damper_N_s_per_m = damper0 + slope_per_click * clicks (weighted least squares on the records' "
                    "coefficients)", "damper0_N_s_per_m": float(beta[0]),
            "damper0_N_s_per_m_ci95": interval95(float(beta[0]), math.sqrt(cov[0, 0])),
            "slope_N_s_per_m_per_click": float(beta[1]),
            "slope_N_s_per_m_per_click_ci95": interval95(float(beta[1]), math.sqrt(cov[1, 1]))}


def fit_bounce(paths, clicks, predict=(), bike=None) -> BounceFit:
    """The seat slams in the SST records ``paths`` (one number of rebound ``clicks`` each) fitted:
    everything ``mtbmj fit bounce`` writes and prints, as a :class:`BounceFit`; ``predict``: clicks to
    predict the ring-down at. ``bike`` (a preset, a file or a ``BikeSpec``): each ring-down also read
    through that bike's seated model (``mtbmj.identify.bounce_bike``)."""
    from mtbmj.identify import bounce

    paths = [Path(p) for p in paths]
    if len(clicks) != len(paths):
        raise MtbmjError(f"--clicks: {len(clicks)} value(s) for {len(paths)} record(s); give one number of clicks "
                         f"per record, in their order")
    seated = None
    if bike is not None:
        from mtbmj.identify.bounce_bike import SeatedBike

        seated = SeatedBike(bike)
    records = _records(paths, clicks)
    fits = [bounce.fit_record(r) for r in records]
    for r, f in zip(records, fits):
        if "shock" not in f and "fork" not in f:
            raise MtbmjError(f"{r.path}: no sensor present")
    notes = sorted({n for r in records for n in r.notes})
    laws = {}
    for end in bounce.ENDS:
        usable = [(k, f[end]) for k, f in zip(clicks, fits) if end in f and f[end].fitted]
        if len({k for k, _ in usable}) >= 2:
            laws[end] = bounce.click_law(end, [k for k, _ in usable], [rd for _, rd in usable])
        elif any(end in f for f in fits) and len(paths) > 1:
            notes.append(f"{end}: no law in clicks (fitted ring-downs at {len({k for k, _ in usable})} distinct "
                         f"click setting(s); two are needed)")
    if predict and not laws:
        raise MtbmjError("--predict-clicks: no law in clicks to predict from (it needs fitted ring-downs at two or "
                         "more different --clicks)")
    for k in predict:  # a law linear in clicks is read between its records, never extrapolated beyond them
        for end, law in laws.items():
            lo, hi = min(law.clicks), max(law.clicks)
            if not lo <= k <= hi:
                raise MtbmjError(f"--predict-clicks {k:g}: outside the clicks the {end} law was fitted on ({lo:g} to "
                                 f"{hi:g}); a law linear in clicks is not extrapolated beyond its records: record a "
                                 f"slam at {k:g} clicks instead")
    out = {"method": bounce.METHOD, "units": {"time": "s", "travel": "mm", "frequency": "Hz"},
           "intervals": "95 %", "notes": notes, "records": [], "law": {}, "predicted": []}
    for r, k, f in zip(records, clicks, fits):
        out["records"].append({"file": r.name, "path": r.path, "sst_version": r.version,
                               "sample_rate_Hz": r.sample_rate_Hz, "clicks": k,
                               **{end: rd.summary() for end, rd in f.items()}})
        if seated is not None:
            for end, rd in f.items():
                if rd.fitted:
                    b = _through_bike(seated, end, rd.zeta, rd.zeta_sd, rd.fd_Hz, rd.fd_sd)
                    out["records"][-1][end]["bike"] = b
                    scale = b.get("spring_rate_over_bike_file")
                    if scale is not None and not 1 / RATE_AGREES <= scale <= RATE_AGREES:
                        notes.append(f"{r.name}: the {end}'s ring-down implies {scale:.2f} x the spring rate of "
                                     f"{seated.spec.name} ({b['spring_rate_N_per_mm']:.1f} of "
                                     f"{b['bike_file_spring_rate_N_per_mm']:.1f} N/mm): the bike file's spring, or its "
                                     f"seated masses (rider.seated_com_mm, rider.mass_kg), is not this bike's")
    for end, law in laws.items():
        out["law"][end] = law.summary()
        if seated is not None:
            pts = []
            for rec in out["records"]:
                e = rec.get(end, {}).get("bike", {})
                if "damper_N_s_per_m" in e:
                    lo, hi = e["damper_N_s_per_m_ci95"]
                    pts.append((rec["clicks"], e["damper_N_s_per_m"], (hi - lo) / (2 * bounce.Z95)))
            dl = _damper_law(pts)
            if dl is not None:
                out["law"][end]["bike"] = dl
    if seated is not None:
        from mtbmj.identify.bounce_bike import METHOD as BIKE_METHOD

        out["bike"] = {"name": seated.spec.name, "method": BIKE_METHOD,
                       "seated_com_mm": [v * 1e3 for v in seated.spec.rider.seated_com]}
    decay_fits, decay_laws = _decay(records, clicks, out, notes)
    csvs = {}
    base_i = int(np.argmin(clicks))
    base_rec, base_fit = records[base_i], fits[base_i]
    for k in predict:
        entry = {"clicks": k}
        columns = {}
        for end, law in laws.items():
            z, zsd = law.zeta(k)
            fd, fsd = law.frequency(k)
            entry[end] = {"damping_ratio": z, "damping_ratio_ci95": bounce.interval95(z, zsd),
                          "frequency_hz": fd if math.isfinite(fd) else None,
                          "frequency_hz_ci95": bounce.interval95(fd, fsd) if math.isfinite(fd) else None,
                          "undamped_frequency_hz": law.fn_Hz,
                          "undamped_frequency_hz_ci95": bounce.interval95(law.fn_Hz, law.fn_sd)}
            if end in decay_laws:
                entry[end]["decay"] = _decay_prediction(decay_laws[end], decay_fits, clicks, end, k)
            if not 0.0 <= z < 1.0:
                entry[end]["note"] = "the law gives no oscillation here (damping ratio outside 0 to 1); no ring-down"
                continue
            if seated is not None:
                entry[end]["bike"] = _through_bike(seated, end, z, zsd, fd, fsd)
            src = base_fit.get(end)
            if src is None or not src.fitted:
                entry[end]["note"] = f"no ring-down: the {clicks[base_i]:g}-click record has no fitted {end} start"
                continue
            t, x = bounce.predicted_ring_down(src, base_rec.time_s, z, fd)
            columns[end] = (t, x)
        if columns:
            name = f"ringdown_{k:g}_clicks.csv"
            t0 = max(t[0] for t, _ in columns.values())
            t1 = min(t[-1] for t, _ in columns.values())
            grid = base_rec.time_s[(base_rec.time_s >= t0 - 1e-12) & (base_rec.time_s <= t1 + 1e-12)]
            cols = {"time_s": grid}
            for end in ("shock", "fork"):
                if end in columns:
                    t, x = columns[end]
                    cols[f"{end}_mm"] = np.interp(grid, t, x)
            csvs[name] = cols
            entry["ringdown_csv"] = name
            entry["ringdown_from"] = (f"{base_rec.name} ({clicks[base_i]:g} clicks): its rest level and free start "
                                      f"(displacement and velocity) at t0, with the predicted parameters; "
                                      f"{', '.join(c for c in cols if c != 'time_s')}; compression positive")
            missing = [e for e in ("shock", "fork") if e not in columns]
            if missing:
                entry["ringdown_note"] = f"{', '.join(missing)}: no predicted ring-down (no law or no fitted start)"
        out["predicted"].append(entry)
    return BounceFit(out, records, fits, laws, list(clicks), csvs)


def _decay(records, clicks, out, notes):
    """Each record's ends read as a decay law with friction (``mtbmj.identify.bounce_decay``): under
    the end's ``"decay"`` in each record, and, with two or more click settings, ``decay_law`` with the
    friction band common to the records."""
    from mtbmj.identify import bounce_decay as bd

    fits = [bd.fit_record(r) for r in records]
    for rec, f in zip(out["records"], fits):
        for end, ed in f.items():
            if end in rec:
                rec[end]["decay"] = ed.summary()
    out["decay_law"] = {}
    laws = {}
    for end in ("shock", "fork"):
        pts = [(k, f[end].seq) for k, f in zip(clicks, fits) if end in f and f[end].seq.levels_mm.size >= 2
               and not f[end].refusal.startswith("no decay law: the first")]
        if len({k for k, _ in pts}) < 2:
            continue
        ks, seqs = [k for k, _ in pts], [s for _, s in pts]
        per = {m: bd.fit_common(seqs, ks, m, law=False) for m in bd.MODELS}
        law = {m: bd.fit_common(seqs, ks, m, law=True) for m in bd.MODELS}
        chosen = bd.choose(per)
        if chosen is None:
            notes.append(f"{end}: no decay law across clicks (the records' free half cycles leave no degree of "
                         f"freedom)")
            continue
        f = per[chosen]
        entry = {"assumption": bd.COMMON_FRICTION, "law": bd.LAW_FORM, "information_criterion": bd.IC,
                 "model": chosen, "bic": {m: (None if v is None else v.bic) for m, v in per.items()},
                 "fitted_on_clicks": ks, "dof": f.dof, "residual_scale_mm": f.scale_mm,
                 "friction_band_mm": f.value("friction_band_mm")[0] if "friction_band_mm" in f.names else 0.0,
                 "friction_band_mm_ci95": (f.interval("friction_band_mm") if "friction_band_mm" in f.names
                                           else [0.0, 0.0]), "per_click": []}
        for i, k in enumerate(ks):
            z = f.value(f"zeta[{i}]")[0] if f"zeta[{i}]" in f.names else 0.0
            ci = f.interval(f"zeta[{i}]") if f"zeta[{i}]" in f.names else [0.0, 0.0]
            entry["per_click"].append({"clicks": k, "damping_ratio": z, "damping_ratio_ci95": ci})
        lf = law.get(chosen)
        if lf is not None and "zeta0" in lf.names:
            entry.update({"zeta0": lf.value("zeta0")[0], "zeta0_ci95": lf.interval("zeta0"),
                          "slope_per_click": lf.value("slope_per_click")[0],
                          "slope_per_click_ci95": lf.interval("slope_per_click")})
        if lf is not None:
            laws[end] = lf
        out["decay_law"][end] = entry
    return fits, laws


def _decay_prediction(fit, fits, clicks, end, k) -> dict:
    """zeta, the friction band and the first free half cycle's decay at ``k`` clicks (at the
    lowest-click record's own first free swing)."""
    from mtbmj.identify import bounce_decay as bd

    order = sorted(range(len(clicks)), key=lambda i: clicks[i])
    src = next((i for i in order if end in fits[i] and fits[i][end].seq.swings.size >= 1), None)
    if src is None:
        return {"note": "no record with a free swing to start from"}
    s0 = float(fits[src][end].seq.swings[0])
    p = bd.law_prediction(fit, k, s0)
    return {"damping_ratio": p["zeta"], "damping_ratio_ci95": interval(p["zeta"], p["zeta_sd"]),
            "friction_band_mm": p["friction_band_mm"],
            "first_half_cycle_decay": p["decay"], "first_half_cycle_decay_ci95": interval(p["decay"], p["decay_sd_total"]),
            "first_swing_mm": s0, "first_swing_from_clicks": clicks[src]}


def interval(v, sd):
    from mtbmj.identify.bounce import interval95

    return interval95(v, sd)


def figure_png(result: BounceFit) -> bytes:
    """fit.png: each record's ends with their fits, and the damping ratio against clicks."""
    from matplotlib.figure import Figure

    from mtbmj.readout.quicklook import png

    records, fits, laws, clicks = result.records, result.fits, result.laws, result.clicks
    n = len(records)
    fig = Figure(figsize=(11, 2.6 * (n + 1)))
    axes = fig.subplots(n + 1, 2, squeeze=False)
    for i, (r, f, k) in enumerate(zip(records, fits, clicks)):
        for j, end in enumerate(("shock", "fork")):
            ax = axes[i, j]
            rd = f.get(end)
            if rd is None:
                ax.set_axis_off()
                continue
            x = r.shock_mm if end == "shock" else r.fork_mm
            lo, hi = rd.slam_s - 0.5, max(rd.t_end_s, rd.t0_s + 1.0) + 0.5
            m = (r.time_s >= lo) & (r.time_s <= hi)
            ax.plot(r.time_s[m], x[m], color="0.55", lw=0.8, label="record")
            ax.axvline(rd.t0_s, color="0.3", ls=":", lw=0.8)
            if rd.fitted:
                mm = (r.time_s >= rd.t0_s) & (r.time_s <= rd.t_end_s)
                ci = rd.summary()["damping_ratio_ci95"]
                ax.plot(r.time_s[mm], rd.curve(r.time_s[mm]), color="C3", lw=1.4,
                        label=f"fit: zeta {rd.zeta:.3f} [{ci[0]:.3f}, {ci[1]:.3f}], {rd.fd_Hz:.2f} Hz")
            else:
                ax.text(0.02, 0.04, "no fit: too few cycles" if "too few" in rd.note else "no fit",
                        transform=ax.transAxes, ha="left", va="bottom", fontsize=8)
            ax.set_title(f"{r.name}, {k:g} clicks: {end}", fontsize=9)
            ax.set_ylabel("travel (mm, approx.)" if r.version == 2 else "travel (mm)")
            ax.legend(fontsize=7, loc="upper right")
            ax.set_xlabel("time (s)")
    ax = axes[n, 0]
    for end, color in (("shock", "C0"), ("fork", "C1")):
        pts = [(k, f[end]) for k, f in zip(clicks, fits) if end in f and f[end].fitted]
        if pts:
            ax.errorbar([k for k, _ in pts], [rd.zeta for _, rd in pts],
                        yerr=[1.959963984540054 * rd.zeta_sd for _, rd in pts], fmt="o", color=color,
                        capsize=3, label=f"{end}: measured (95 %)")
        if end in laws:
            law = laws[end]
            kk = np.linspace(0, max(list(clicks) + [p["clicks"] for p in result.summary["predicted"]]), 100)
            zz = np.array([law.zeta(v) for v in kk])
            ax.plot(kk, zz[:, 0], color=color, lw=1, label=f"{end} law: {law.zeta0:.3f} + {law.slope:.4f} k")
            ax.fill_between(kk, zz[:, 0] - 1.96 * zz[:, 1], zz[:, 0] + 1.96 * zz[:, 1], color=color, alpha=0.15)
            pk = [p["clicks"] for p in result.summary["predicted"] if end in p]
            if pk:
                ax.plot(pk, [law.zeta(v)[0] for v in pk], "x", color=color, ms=8, label=f"{end}: predicted")
    ax.set_xlabel("rebound clicks")
    ax.set_ylabel("damping ratio")
    ax.set_title("damping ratio against clicks", fontsize=9)
    ax.legend(fontsize=7)
    axes[n, 1].set_axis_off()
    axes[n, 1].text(0, 0.5, "fit window: from the dotted line (free start)\nmethod: damped sinusoid, least squares\n"
                    "version-2 records: amplitudes approximate", fontsize=8, va="center")
    fig.tight_layout()
    return png(fig, dpi=80)


def _bike_text(b: dict | None) -> str:
    if not b:
        return ""
    if "note" in b:
        return f"; through the bike: {b['note']}"
    lo, hi = b["damper_N_s_per_m_ci95"]
    klo, khi = b["spring_rate_N_per_mm_ci95"]
    return (f"; through the bike: spring {b['spring_rate_N_per_mm']:.1f} N/mm [{klo:.1f}, {khi:.1f}] "
            f"({b['spring_rate_over_bike_file']:.2f} x the bike file's), wheel rate {b['wheel_rate_N_per_mm']:.2f} N/mm, "
            f"damper {b['damper_N_s_per_m']:.0f} N s/m [{lo:.0f}, {hi:.0f}]")


def _not_finite(value, where: str = "") -> str | None:
    """The key path of the first value in ``value`` (dicts, lists, numbers) that is not a finite number."""
    if isinstance(value, dict):
        for k, v in value.items():
            found = _not_finite(v, f"{where}.{k}" if where else str(k))
            if found is not None:
                return found
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            found = _not_finite(v, f"{where}[{i}]")
            if found is not None:
                return found
    elif isinstance(value, float) and not math.isfinite(value):
        return f"{where} = {value}"
    return None


def json_bytes(data) -> bytes:
    """fit.json's bytes: strict JSON. A value that is not a finite number is refused in one line naming
    its key (``json.dumps(allow_nan=False)`` writes no NaN or Infinity, which JSON does not have)."""
    import json

    bad = _not_finite(data)
    if bad is not None:
        raise MtbmjError(f"fit.json: {bad} is not a number; nothing written")
    return (json.dumps(data, indent=2, allow_nan=False) + "\n").encode()


__all__ = ["BounceFit", "RATE_AGREES", "figure_png", "fit_bounce", "interval", "json_bytes"]

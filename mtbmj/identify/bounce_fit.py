"""The bounce fit (``mtbmj fit bounce``): each record's seat slam read as a ring-down
(``mtbmj.identify.bounce``) and as a decay with friction (``mtbmj.identify.bounce_decay``), the
damping per rebound click as a law, the ring-down it predicts at other clicks, and optionally
each ring-down through a bike's seated model (``mtbmj.identify.bounce_bike``): one
:class:`BounceFit` that the command and the Python API read alike (its summary, files and lines)."""
from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mtbmj import limits
from mtbmj.errors import MtbmjError


@dataclass
class BounceFit:
    """What a bounce fit found: ``summary`` (fit.json's content), the ``records`` read, each
    record's ring-down ``fits`` by end, the click ``laws`` by end, the records' ``clicks`` and the
    predicted ring-downs' ``csv`` columns by file name; ``predictions`` (each end's ring-down at each
    predicted click from the decay law, :class:`mtbmj.identify.bounce_predict.Prediction`) and
    ``answers`` (the clicks to set per end, :class:`mtbmj.identify.bounce_clicks.ClickAnswer`)."""

    summary: dict
    records: list
    fits: list
    laws: dict
    clicks: list
    csv: dict
    predictions: list = field(default_factory=list)  # bounce_predict.Prediction per predicted click and end
    answers: dict = field(default_factory=dict)  # end -> bounce_clicks.ClickAnswer
    extra: dict = field(default_factory=dict)  # further files by name (replay.png), as bytes
    replay_lines: list = field(default_factory=list)  # what --replay prints

    def files(self) -> dict[str, bytes]:
        """fit.json, fit.png and ringdown_<K>_clicks.csv per predicted click, as bytes."""
        from mtbmj import output

        files = {"fit.json": json_bytes(self.summary), "fit.png": figure_png(self)}
        for name, cols in self.csv.items():
            files[name] = output.csv_bytes(cols)
        files.update(self.extra)
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
        for p in self.predictions:
            out.append(f"predicted at {p.clicks:g} clicks from {p.source} (decay law): {p.end} first half cycle's decay "
                       f"{_est(p.first_half_cycle_decay, 2)}, {_est(p.frequency_hz, 2)} Hz, rebound speed "
                       f"{_est(p.rebound_speed_mm_per_s, 0)} mm/s, inside the stroke: {'yes' if p.inside_stroke() else 'NO'}"
                       + (f" (reaches the stroke's end at {p.stop_reached_s():.3f} s: outside the law's envelope from "
                          f"there{'; held there by the seated body' if p.body else ''})" if p.stop_reached_s() is not None
                          else ""))
        for end, ans in self.answers.items():
            out.append(ans.line())
        out.extend(self.replay_lines)
        for note in self.summary["notes"]:
            out.append(f"note: {note}")
        return out


def _est(e, digits: int) -> str:
    return f"{e.value:.{digits}f} [{e.low:.{digits}f}, {e.high:.{digits}f}]"


def _records(paths, clicks):
    """The records read, one slam each: the same samples twice (a file given twice, or copied) would be
    one ring-down read at two clicks, a damper the clicks do not change; refused naming both."""
    from mtbmj.errors import MtbmjError
    from mtbmj.measured.telemetry import read_sst, repeated_samples

    records = [read_sst(p) for p in paths]
    twice = repeated_samples(records)
    if twice is not None:
        first, k = twice
        raise MtbmjError(f"{records[k].name}: the same record as {records[first].name} (the same samples), given at "
                         f"{clicks[first]:g} and {clicks[k]:g} clicks: one slam read twice would say the clicks do "
                         f"not change the damping; give each slam once")
    return records


RATE_AGREES = 1.25  # a ring-down's spring rate within this factor of the bike file's says nothing


def _check_rider_hz(hz) -> None:
    """A resonance (Hz) that is a positive number; outside a seated body's 4-6 Hz one warning line."""
    import warnings

    from mtbmj.errors import ConfigWarning
    from mtbmj.identify.bounce_bike import RIDER_HZ

    if not (isinstance(hz, (int, float)) and math.isfinite(hz) and hz > 0):
        raise MtbmjError(f"--rider-hz {hz}: the seated rider's resonance must be a positive number of Hz")
    if not RIDER_HZ[0] <= hz <= RIDER_HZ[1]:
        warnings.warn(f"--rider-hz {hz:g}: a seated body's vertical resonance lies at {RIDER_HZ[0]:g}-{RIDER_HZ[1]:g} Hz "
                      f"(Griffin; ISO 2631-1); read as given", ConfigWarning, stacklevel=3)


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


def fit_bounce(paths, clicks, predict=(), bike=None, hit_mm=None, rider_hz=None, replay=False,
               rebound_target_per_s=None) -> BounceFit:
    """The seat slams in the SST records ``paths`` (one number of rebound ``clicks`` each) fitted:
    everything ``mtbmj fit bounce`` writes and prints, as a :class:`BounceFit`; ``predict``: clicks to
    predict the ring-down at. ``bike`` (a preset, a file or a ``BikeSpec``): each ring-down also read
    through that bike's seated model (``mtbmj.identify.bounce_bike``). ``hit_mm``: the hit the answer in
    clicks is for (mm above the static position; default the records' own, ``bounce_clicks.default_hit``).
    ``rider_hz``: with ``bike``, the seated rider compliant on the saddle at that resonance (Hz) instead
    of rigid (``bounce_bike.SeatedBike``), and each reading gives the rider's share of the mode.
    ``replay``: with ``bike``, each slam also replayed through the MuJoCo bike with the compliant seated
    rider (at ``rider_hz``, default 5 Hz) and its shock's spring, damper and friction fitted
    (``mtbmj.identify.bounce_replay``): fit.json's "replay", replay_<file>.csv and replay.png; with it
    "rebound_dampers" (``bounce_rebound``: each record's rebound coefficient with its interval, the law
    in clicks, each record held out, and the answer for ``rebound_target_per_s``, 1/s per mm of height)
    and "slam_rebound" (``bounce_slam_rebound``: the slams and first rebounds fitted together, a rebound
    coefficient per record with its interval)."""
    from mtbmj.identify import bounce

    if isinstance(hit_mm, (int, float)) and hit_mm > 0:  # the command line's warning, said to a caller from Python too
        limits.plausible("--hit-mm", float(hit_mm))
    paths = [Path(p) for p in paths]
    if len(clicks) != len(paths):
        raise MtbmjError(f"--clicks: {len(clicks)} value(s) for {len(paths)} record(s); give one number of clicks "
                         f"per record, in their order")
    seated = None
    if replay and bike is None:
        raise MtbmjError("--replay: the slam is replayed through a bike; give --bike too")
    if rebound_target_per_s is not None and not replay:
        raise MtbmjError("--rebound-target-per-s: the answer from the rebound dampers needs --replay (and --bike)")
    if rider_hz is not None and bike is None:
        raise MtbmjError("--rider-hz: the rider's resonance is read through a bike; give --bike too")
    if bike is not None:
        from mtbmj.identify.bounce_bike import SeatedBike

        if rider_hz is not None:
            _check_rider_hz(rider_hz)
        seated = SeatedBike(bike, rider_hz=rider_hz)
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
                        rider = ("the rider rigid" if seated.saddle is None else
                                 f"the rider compliant at {seated.rider_hz:g} Hz")
                        notes.append(f"{r.name}: the {end}'s ring-down implies {scale:.2f} x the spring rate of "
                                     f"{seated.spec.name} ({b['spring_rate_N_per_mm']:.1f} of "
                                     f"{b['bike_file_spring_rate_N_per_mm']:.1f} N/mm, {rider}): the bike file's "
                                     f"spring, or its seated masses (rider.seated_com_mm, rider.mass_kg), is not this "
                                     f"bike's")
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
                       "seated_com_mm": [v * 1e3 for v in seated.spec.rider.seated_com],
                       "rider": "rigid on the frame" if seated.saddle is None else
                       f"compliant on the saddle at {seated.rider_hz:g} Hz (damping ratio {seated.saddle['damping_ratio']:g})"}
    decay_fits, _ = _decay(records, clicks, out, notes)
    plaws = _prediction_laws(records, clicks, decay_fits, out, seated.spec if seated is not None else None)
    csvs, predictions = {}, []
    for k in predict:
        entry = {"clicks": k}
        for end, law in laws.items():
            z, zsd = law.zeta(k)
            fd, fsd = law.frequency(k)
            entry[end] = {"damping_ratio": z, "damping_ratio_ci95": bounce.interval95(z, zsd),
                          "frequency_hz": fd if math.isfinite(fd) else None,
                          "frequency_hz_ci95": bounce.interval95(fd, fsd) if math.isfinite(fd) else None,
                          "undamped_frequency_hz": law.fn_Hz,
                          "undamped_frequency_hz_ci95": bounce.interval95(law.fn_Hz, law.fn_sd)}
            if not 0.0 <= z < 1.0:
                entry[end]["note"] = "the law gives no oscillation here (damping ratio outside 0 to 1); no ring-down"
            elif seated is not None:
                entry[end]["bike"] = _through_bike(seated, end, z, zsd, fd, fsd)
        columns, source = {}, None
        for end, (plaw, rows) in plaws.items():
            p = _predict_end(plaw, rows, records, clicks, k)
            if isinstance(p, str):
                entry.setdefault(end, {})["decay"] = {"note": p}
                continue
            entry.setdefault(end, {})["decay"] = p.summary()
            predictions.append(p)
            if source is None or p.source == source:
                source = p.source
                columns[end] = p
        if columns:
            name = f"ringdown_{k:g}_clicks.csv"
            first = next(iter(columns.values()))
            n = min(p.time_s.size for p in columns.values())  # each end's trace on the record's own time grid from
            cols = {"time_s": first.time_s[:n]}  # 0, as long as its slam's peak plus the law's span: the shortest
            for end in ("shock", "fork"):
                if end in columns:
                    cols[f"{end}_mm"] = columns[end].travel_mm[:n]
            csvs[name] = cols
            entry["ringdown_csv"] = name
            entry["ringdown_from"] = (f"{first.source} ({first.source_clicks:g} clicks, the record nearest in clicks): "
                                      f"its own travel up to its slam's peak, then the decay law's motion at {k:g} "
                                      f"clicks from rest there; {', '.join(c for c in cols if c != 'time_s')}; "
                                      f"compression positive, inside the stroke")
        missing = [e for e in ("shock", "fork") if any(e in f for f in fits) and e not in columns]
        if missing:
            entry["ringdown_note"] = (f"{', '.join(missing)}: no predicted ring-down (no decay law across clicks, or "
                                      f"its source is another record)")
        out["predicted"].append(entry)
    answers = {}
    if plaws:
        from mtbmj.identify import bounce_clicks as bc

        out["answer"] = {}
        for end, (plaw, _) in plaws.items():
            hit = float(hit_mm) if hit_mm is not None else bc.default_hit(plaw)
            stroke = max(r.shock_max_mm if end == "shock" else r.fork_max_mm for r in records)
            if hit_mm is not None and hit >= stroke:  # a hit past the whole stroke: no law has an answer for it
                raise MtbmjError(f"--hit-mm {hit:g}: not less than the {end}'s whole {'stroke' if end == 'shock' else 'travel'} "
                                 f"as the records are read ({stroke:g} mm); the hit is the {end}'s own compression "
                                 f"above its static position" + (", in shock mm (not the rear wheel's travel)"
                                                                 if end == "shock" else ""))
            answers[end] = bc.answer(plaw, hit)
            out["answer"][end] = answers[end].summary()
    extra, replay_lines = {}, []
    if replay:
        from mtbmj.identify import bounce_replay

        done = bounce_replay.replay_records(records, clicks, bike, rider_hz)
        out["replay"] = done["summary"]
        out["replay_check"] = done["check"]
        from mtbmj.identify import bounce_rebound
        from mtbmj.identify import bounce_slam_rebound as bsr

        # the slams and first rebounds first, then the spring, friction and dampers' scale read on the free
        # ring-downs (``"ring_fit"``, bounce_ring), which the rebound dampers take (the whole-trace replay's where
        # it is not read; docs/identification.md)
        pooled = bsr.read_records(records, clicks, done["summary"], bike, rider_hz)
        out["rebound_dampers"] = bounce_rebound.read_records(records, clicks, done["summary"], bike, rider_hz,
                                                             rebound_target_per_s,
                                                             ring=None if pooled is None else pooled.get("ring_fit"))
        if out["rebound_dampers"] is not None:
            done["lines"].append(out["rebound_dampers"]["line"])
            done["lines"] += out["rebound_dampers"]["lines"]
        out["slam_rebound"] = bsr.public(pooled)
        if pooled is not None:
            done["lines"].append(pooled["line"])
            extra["slam_rebound.png"] = bsr.figure_png(pooled)
        out["replay_fork"] = fork_refusals(records, out["records"])
        done["lines"] += [f"fork not replayed: {e['refused']}" for e in out["replay_fork"]]
        csvs.update(done["csv"])
        if done["replays"]:
            extra["replay.png"] = bounce_replay.figure_png(done["replays"])
        read = out["rebound_dampers"]["records"] if out["rebound_dampers"] is not None else []
        if any("rebound_N_s_per_m" in e for e in read):
            from mtbmj.identify.bounce_rebound_clicks import figure_png

            extra["rebound.png"] = figure_png(out["rebound_dampers"])
        replay_lines = done["lines"]
    return BounceFit(out, records, fits, laws, list(clicks), csvs, predictions, answers, extra, replay_lines)


SHIFT_MM = 2.0  # a level after the slam this far from the one before is a moved rest (the records': 7-13 mm)


def fork_refusals(records, summaries) -> list:
    """``--replay``'s word on the fork (its spring, damper and friction are not replayed): per record with
    a fork, the decay reading's note (``bounce_decay``: how many free half cycles it has) and how far its
    level after the slam lies from its level before (``bounce.rest_shift``), beside the shock's."""
    from mtbmj.identify import bounce

    out = []
    for rec, summ in zip(records, summaries):
        if rec.fork_mm is None or rec.shock_mm is None:
            continue
        peak = bounce.find_slam(rec.time_s, rec.shock_mm, rec.name)
        fork = bounce.rest_shift(rec.time_s, rec.fork_mm, peak)
        shock = bounce.rest_shift(rec.time_s, rec.shock_mm, peak)
        note = (summ.get("fork", {}).get("decay") or {}).get("note") or "its decay was read"
        why = f"{rec.name}: {note}"
        if fork is not None and shock is not None:
            df, ds = fork[1] - fork[0], shock[1] - shock[0]
            why += (f"; after the slam it rests {df:+.1f} mm from its level before ({fork[0]:.1f} to "
                    f"{fork[1]:.1f} mm), the shock {ds:+.1f} mm ({shock[0]:.1f} to {shock[1]:.1f})")
            if df * ds < 0 and min(abs(df), abs(ds)) > SHIFT_MM:
                why += (": opposite ways, the rider's weight moved between the bars and the saddle, which the "
                        "replay's vertical push on the rider does not make")
        why += "; the fork's spring, damper and friction are not replayed"
        out.append({"file": rec.name, "refused": why, "rest_before_mm": None if fork is None else fork[0],
                    "rest_after_mm": None if fork is None else fork[1]})
    return out


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


def _prediction_laws(records, clicks, decay_fits, out, spec=None) -> dict:
    """end -> (DecayLaw, record indices) for each end whose decay law across clicks was fitted, with the
    records' placements in the stroke under ``decay_law[end]["placements"]`` and their held-out checks
    under ``decay_law[end]["held_out"]`` (three or more click settings; the shock's with the bike's own
    stiffening at each held-out centre beside, given a bike ``spec``)."""
    from mtbmj.identify import bounce_predict as bp
    from mtbmj.identify import bounce_stroke as bs

    plaws = {}
    for end, entry in out.get("decay_law", {}).items():
        rows = [i for i, f in enumerate(decay_fits) if end in f and f[end].seq.levels_mm.size >= 2
                and not f[end].refusal.startswith("no decay law: the first")]
        seqs = [decay_fits[i][end].seq for i in rows]
        ks = [clicks[i] for i in rows]
        series = [getattr(records[i], f"{end}_mm") for i in rows]
        law = bp.decay_law(end, seqs, ks, [records[i] for i in rows], series, entry["model"])
        if law is None:
            continue
        plaws[end] = (law, rows)
        entry["undamped_frequency_hz"] = law.fn_hz
        entry["undamped_frequency_hz_ci95"] = interval(law.fn_hz, law.fn_sd)
        recs = [records[i] for i in rows]
        entry["placements"] = [_finite_or_none(p.summary()) for p in bs.placements(seqs, ks, recs, series,
                                                                                    entry["model"])]
        if len(set(ks)) >= 3:
            spring = bs.BikeSpring.of_bike(spec) if spec is not None and end == "shock" else None
            entry["held_out"] = [_finite_or_none(bs.held_out(seqs, ks, recs, series, j, spring, entry["model"])
                                                 if spring is not None else
                                                 bp.held_out(seqs, ks, recs, series, j, entry["model"]))
                                 for j in range(len(rows))]
    return plaws


def _finite_or_none(d: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


def _predict_end(law, rows, records, clicks, k):
    """The end's Prediction at ``k`` clicks from the record nearest in clicks (the lower on a tie), or
    the reason there is none."""
    i = min(rows, key=lambda j: (abs(clicks[j] - k), clicks[j]))
    seq = law.seqs[rows.index(i)]
    rec = records[i]
    x = getattr(rec, f"{law.end}_mm")
    stroke = getattr(rec, f"{law.end}_max_mm")
    try:
        return law.predict(k, rec, seq, law.x_eq_of(seq, clicks[i]), clicks[i], x, stroke)
    except MtbmjError as e:
        return str(e)


def interval(v, sd):
    from mtbmj.identify.bounce import interval95

    return interval95(v, sd)


def figure_png(result: BounceFit) -> bytes:
    """fit.png (:func:`figure`)."""
    from mtbmj.readout.quicklook import png

    return png(figure(result), dpi=80)


def figure(result: BounceFit):
    """fit.png's figure: each record's ends with their fits, the damping ratio against clicks, and,
    with a decay law across clicks, the predicted ring-downs and the answer in clicks."""
    from matplotlib.figure import Figure

    records, fits, laws, clicks = result.records, result.fits, result.laws, result.clicks
    n = len(records)
    extra = 1 if (result.predictions or result.answers) else 0
    fig = Figure(figsize=(11, 2.6 * (n + 1 + extra)))
    axes = fig.subplots(n + 1 + extra, 2, squeeze=False)
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
    if extra:
        _prediction_panel(axes[n + 1, 0], result)
        _answer_panel(axes[n + 1, 1], result)
    fig.tight_layout()
    return fig


def _prediction_panel(ax, result: BounceFit) -> None:
    """Each predicted ring-down (decay law) beside the record it starts from, in time from that
    record's slam peak, with the stroke's ends."""
    shown = set()
    for j, p in enumerate(result.predictions):
        m = (p.time_s >= p.slam_s - 0.5) & (p.time_s <= p.slam_s + 3.0)
        if p.source not in shown:
            rec = next(r for r in result.records if r.name == p.source)
            x = getattr(rec, f"{p.end}_mm")
            mr = (rec.time_s >= p.slam_s - 0.5) & (rec.time_s <= p.slam_s + 3.0)
            ax.plot(rec.time_s[mr] - p.slam_s, x[mr], color="0.6", lw=0.8, ls=":" if shown else "-",
                    label=f"record {p.source} ({p.source_clicks:g} clicks)")
            shown.add(p.source)
        ax.plot(p.time_s[m] - p.slam_s, p.travel_mm[m], color=f"C{j % 10}", lw=1.2,
                label=f"{p.end} at {p.clicks:g} clicks from {p.source}: first decay "
                      f"{p.first_half_cycle_decay.value:.2f}, {p.frequency_hz.value:.2f} Hz")
        ax.axhline(p.stroke_mm, color="0.3", lw=0.6, ls="--")
    ax.axhline(0.0, color="0.3", lw=0.6, ls="--")
    ax.set_title("predicted ring-downs (decay law, from the record's own state; stroke's ends dashed)", fontsize=9)
    ax.set_xlabel("time from the record's slam peak (s)")
    ax.set_ylabel("travel (mm)")
    if result.predictions:
        ax.legend(fontsize=6, loc="upper right")
    else:
        ax.text(0.5, 0.5, "no --predict-clicks", transform=ax.transAxes, ha="center", fontsize=8)


def _answer_panel(ax, result: BounceFit) -> None:
    """The decay law's zeta against clicks, the window of clicks meeting the target shaded, the answer
    marked, the title saying it."""
    from mtbmj.identify import bounce_clicks as bc

    titles = []
    for c, (end, ans) in enumerate(result.answers.items()):
        lo, hi = ans.searched
        kk = np.linspace(lo, hi, 60)
        fit = result.summary["decay_law"][end]
        if "zeta0" in fit:
            zz = fit["zeta0"] + fit["slope_per_click"] * kk
            ax.plot(kk, zz, color=f"C{c}", lw=1.2, label=f"{end}: decay law's zeta (friction common)")
            pc = fit["per_click"]
            ax.errorbar([q["clicks"] for q in pc], [q["damping_ratio"] for q in pc],
                        yerr=np.array([[q["damping_ratio"] - q["damping_ratio_ci95"][0],
                                        q["damping_ratio_ci95"][1] - q["damping_ratio"]] for q in pc]).T,
                        fmt="o", color=f"C{c}", capsize=3, label=f"{end}: zeta per record (95 %)")
        if ans.window is not None:
            ax.axvspan(ans.window[0], ans.window[1], color="C2", alpha=0.2, label=f"{end}: {bc.TARGET}")
        if ans.range95 is not None:
            ax.axvspan(ans.range95[0], ans.range95[1], facecolor="none", hatch="//", edgecolor="C2", lw=0.5,
                       label=f"{end}: clicks within the uncertainty (95 %)")
        if ans.clicks is not None:
            ax.axvline(ans.clicks, color="k", lw=1.2)
            titles.append(f"{end}: set {ans.clicks} clicks")
        else:
            titles.append(f"{end}: no answer within {lo:g}-{hi:g} clicks")
            ax.text(0.02, 0.04 + 0.2 * c, "\n".join(textwrap.wrap(ans.note, 60)), transform=ax.transAxes,
                    fontsize=7, va="bottom")
    hits = ", ".join(f"{a.hit_mm:.1f} mm" for a in result.answers.values())
    ax.set_title("; ".join(titles) + f" ({bc.TARGET} after a {hits} hit)" if titles else "answer in clicks",
                 fontsize=9)
    ax.set_xlabel("rebound clicks")
    ax.set_ylabel("damping ratio (decay law)")
    if titles:
        ax.legend(fontsize=7, loc="upper left")


def _bike_text(b: dict | None) -> str:
    if not b:
        return ""
    if "note" in b:
        return f"; through the bike: {b['note']}"
    lo, hi = b["damper_N_s_per_m_ci95"]
    klo, khi = b["spring_rate_N_per_mm_ci95"]
    rider = ""
    if "rider" in b:
        sh = b["rider"]["mode_strain_energy_share"]
        rider = (f"; the mode's strain energy {100 * sh['spring']:.0f} % in the spring, {100 * sh['rider']:.0f} % in the "
                 f"rider's body (on the saddle at {b['rider']['resonance_hz']:g} Hz)")
    return (f"; through the bike: spring {b['spring_rate_N_per_mm']:.1f} N/mm [{klo:.1f}, {khi:.1f}] "
            f"({b['spring_rate_over_bike_file']:.2f} x the bike file's), wheel rate {b['wheel_rate_N_per_mm']:.2f} N/mm, "
            f"damper {b['damper_N_s_per_m']:.0f} N s/m [{lo:.0f}, {hi:.0f}]" + rider)


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


__all__ = ["BounceFit", "RATE_AGREES", "figure", "figure_png", "fit_bounce", "fork_refusals", "interval", "json_bytes"]

"""The advice's HTML report (``advice.html``): the one recommended change first, the calibration and
how well the model matched the ride, then every table with its units (``mtbmj.ride.advise``'s
``Advice.html`` writes it)."""
from __future__ import annotations

from mtbmj.ride.advice_rules import RULES, SHARES, flat_metrics


def metric_unit(metric: str) -> str:
    """The unit of a metric (``flat_metrics`` name), as the report's tables show it."""
    leaf = metric.rpartition(".")[2]
    if leaf in SHARES:
        return "% of time"
    for end, unit in (("_percent", "% of travel"), ("_per_minute", "per minute"), ("_mm_per_s", "mm/s"),
                      ("_m_per_s2", "m/s2"), ("_mm", "mm"), ("_s", "s")):
        if leaf.endswith(end):
            return unit
    return {"bottom_outs": "count", "rebound_over_compression": "ratio", "tyre_load_variation": "std/mean",
            "balance_points": "points of travel %"}.get(leaf, "")


LEGEND_ROOM = 1.45  # the histograms' height over their tallest bar: the legend sits above the bars


def figure(advice):
    """Each end's travel histogram: the record, the recorded setting and the recommended (or best) one simulated."""
    import numpy as np
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.8), layout="constrained")
    axes = fig.subplots(1, 2)
    best = advice.recommendation
    shown = best if best is not None else (advice.verdict or {}).get("best_candidate")
    run = None
    if shown is not None:
        run = next((r for a, d, v, r in ([advice.searched] if advice.searched else []) + list(advice.judged)
                    + list(advice.candidates)
                    if a.name == shown["key"] and d == shown["direction"] and v == shown["to"]), None)
    for ax, end, rec, top in ((axes[0], "front", advice.record_front, advice.base.metrics["front"]["travel_mm"]),
                              (axes[1], "rear", advice.record_rear, advice.base.metrics["rear"]["travel_mm"])):
        edges = np.linspace(0, 100, 21)
        series = [("recorded ride", 100 * np.asarray(rec) / top, "0.5"),
                  ("simulated, recorded setting", 100 * advice.base.front_mm / top if end == "front"
                   else 100 * advice.base.rear_mm / top, "C0")]
        if run is not None:
            st = shown.get("setting", {"from": shown["from"], "to": shown["to"], "unit": ""})
            series.append((f"simulated, {shown['label']} {st['from']:g} -> {st['to']:g}"
                           f"{' ' + st['unit'] if st['unit'] else ''}{'' if best is not None else ' (not advised)'}",
                           100 * (run.front_mm if end == "front" else run.rear_mm) / top, "C3"))
        tallest = 0.0
        for label, x, color in series:
            h, _ = np.histogram(np.clip(x, 0, 100), bins=edges)
            share = 100 * h / max(h.sum(), 1)
            tallest = max(tallest, float(share.max()))
            ax.stairs(share, edges, label=label, color=color, linewidth=1.6)
        # room above the tallest bar for the legend, so no bar is hidden behind it
        ax.set_ylim(0.0, LEGEND_ROOM * max(tallest, 1.0))
        ax.set(xlim=(0, 100), xlabel=f"{'fork' if end == 'front' else 'rear wheel'} travel (% of {top:.0f} mm)",
               ylabel="time (%)", title=f"{end}: travel histogram")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    if best is None:
        title = (advice.verdict or {}).get("answer", "inconclusive") + ": no change advised"
    else:
        st = best.get("setting", {"from": best["from"], "to": best["to"], "unit": ""})
        title = f"recommended: {best['label']} {st['from']:g} -> {st['to']:g}{' ' + st['unit'] if st['unit'] else ''}"
    fig.suptitle(f"{advice.ride} on {advice.bike}: " + title)
    return fig


def matched(advice) -> str:
    """How well the model matched the ride, in words: the reconstruction's rear against its naive
    baselines (a pooled advice: the worst ride's numbers), and the recorded setting simulated beside
    the ride recorded (dynamic sag, maximum travel, bottom-outs per end)."""
    c = advice.reconstruction.get("checks", {})
    out = []
    if "baseline_delayed_fork_rms_mm" in c:
        rms, fork, mean = c["rear_predicted_rms_mm"], c["baseline_delayed_fork_rms_mm"], c["baseline_rear_mean_rms_mm"]
        better = min(fork, mean)
        out.append(f"The reconstruction predicted the rear wheel's travel within {rms:.1f} mm RMS, against "
                   f"{fork:.1f} mm for a delayed copy of the fork and {mean:.1f} mm for the rear's mean travel: "
                   f"{100.0 * (1.0 - rms / better):.0f} % below the better of the two (the check asks "
                   f"{c.get('beat_margin_percent', 40.0):g} %)")
        bound = c.get("bound_fork_filter_rms_mm")
        if bound is not None:  # None: too few samples checked for it
            out.append(f"a linear filter from the fork's record fitted on the rear's itself (what the fork's record "
                       f"holds about the rear, not judged by) reached {bound:.1f} mm where it was not fitted, against "
                       f"the check's mark of {c['pass_mark_rms_mm']:.1f} mm")
    sim, rode = advice.base.metrics, advice.measured
    for end, part in (("front", "fork"), ("rear", "rear wheel")):
        s, r = sim[end], rode[end]
        out.append(f"at the recorded setting the model's {part} sat at {s['dynamic_sag_percent']:.0f} % of its travel "
                   f"on average where the ride's sat at {r['dynamic_sag_percent']:.0f} %, reached "
                   f"{s['max_travel_percent']:.0f} % (the ride {r['max_travel_percent']:.0f} %) and bottomed out "
                   f"{s['bottom_outs']} times (the ride {r['bottom_outs']})")
    return "; ".join(out) + "."


def num(x, spec: str = ".3g") -> str:
    return "" if x is None else format(x, spec)


def html(advice, png: bytes) -> str:
    """The self-contained report of ``advice`` (an ``Advice``) with its figure ``png`` inlined."""
    import base64
    import html as esc

    d = advice.to_dict()
    rec = d["recommendation"]
    v = d["verdict"] or {}
    shown = rec if rec is not None else v.get("best_candidate")

    def metric_rows(changes, skip_still=True):
        out = []
        for k, c in sorted(changes.items()):
            if skip_still and c["change"] == 0:
                continue
            out.append(f"<tr><td>{esc.escape(k)}</td><td>{esc.escape(metric_unit(k))}</td><td>{num(c['recorded'])}"
                       f"</td><td>{c['from']:.3g}</td><td>{c['to']:.3g}</td><td>{c['change']:+.3g}</td>"
                       f"<td>{num(c['uncertainty'])}</td><td>{c['expected']:.3g}</td></tr>")
        return out

    head = ("<tr><th>metric</th><th>unit</th><th>recorded</th><th>simulated now</th><th>simulated {}</th>"
            "<th>change</th><th>uncertainty (same unit)</th><th>expected on your ride</th></tr>")
    blank = "<td></td>" * 7
    if shown is not None:
        rows = metric_rows(shown["changes"])
        caption = ("the recommended change" if rec is not None else
                   "the best candidate, not advised: what it improves moves less than its uncertainty")
        rows = rows or [f"<tr><td>no metric moves at {esc.escape(shown['label'])} {shown['to']:g}</td>{blank}</tr>"]
    else:
        caption = "no change: " + v.get("answer", "")
        rows = [f"<tr><td>no candidate to show: {esc.escape(v.get('why', 'no candidate'))}</td>{blank}</tr>"]

    def cand_row(c):
        st = c["setting"]
        return (f"<tr><td>{esc.escape(c['label'])} ({esc.escape(st['key'])})</td><td>{esc.escape(st['unit'])}</td>"
                f"<td>{st['from']:g}</td><td>{st['to']:g}</td><td>{c['penalty_change']:+.2f}</td>"
                f"<td>{esc.escape(c['crash'] or '')}</td></tr>")

    cand = "".join(cand_row(c) for c in d["candidates"])
    skip = "".join(f"<li>{esc.escape(c['label'])} {c['setting']['from']:g} -&gt; {c['setting']['to']:g} "
                   f"{esc.escape(c['setting']['unit'])}: {esc.escape(c['why'])}</li>" for c in d["skipped"])
    if skip:
        skip = f'<h2>Skipped: not allowed by the part</h2><ul id="skipped">{skip}</ul>'
    tried = ""
    for tr in d["tried"]:
        crash = f" ({esc.escape(tr['crash'])})" if tr["crash"] else ""
        tried += (f"<h2>Tried: {esc.escape(tr['label'])}</h2><p>rule penalty (no unit) "
                  f"{d['recorded_setting']['penalty']:.2f} -&gt; {tr['penalty']:.2f}{crash}</p><table class=\"tried\">"
                  f"{head.format('tried')}{''.join(metric_rows(tr['changes'], False))}</table>")
    sim, meas, u = flat_metrics(advice.base.metrics), flat_metrics(advice.measured), d["uncertainty"]
    match = "".join(f"<tr><td>{esc.escape(k)}</td><td>{esc.escape(metric_unit(k))}</td><td>{meas[k]:.3g}</td>"
                    f"<td>{sim[k]:.3g}</td><td>{sim[k] - meas[k]:+.3g}</td><td>{num(u.get(k))}</td></tr>"
                    for k in sorted(meas) if k in sim and k not in ("duration_s",) and not k.endswith("travel_mm"))
    rc = d["reconstruction"]["checks"]
    cal = d.get("calibration")
    if cal:
        rows_c = "".join(f"<tr><td>{esc.escape(e)}: {esc.escape(c['key'])}</td><td>{esc.escape(c['unit'])}</td>"
                         f"<td>{c['file']:g}</td><td>{c['calibrated']:g}</td><td>{c['calibrated_low']:g}-"
                         f"{c['calibrated_high']:g}</td><td>{c['scale']:.3f}</td></tr>" for e, c in cal["springs"].items())
        calibration = (f"<h2>Calibrated on the ride</h2><p>{esc.escape(cal['method'])}; not identified: "
                       f"{esc.escape(cal['not_identified'])}. Every run below rides the calibrated bike; a change is "
                       f"read in the bike file's units, relative to it.</p><table id=\"calibration\"><tr><th>spring "
                       f"(key)</th><th>unit</th><th>bike file</th><th>calibrated</th><th>95 % interval</th>"
                       f"<th>scale (no unit)</th></tr>{rows_c}</table>")
        from mtbmj.ride.calibrate import carried_words

        other = cal.get("or")
        if other:
            sags = ", ".join(f"{e} {v['springs_apart']:.1f} % calibrated, {v['springs_together']:.1f} % the other way"
                             for e, v in other["static_sag_percent"].items())
            calibration += (f"<p id=\"other-reading\">The same ride read the other way: both springs "
                            f"x{other['common_scale']:.3f} of the file's with "
                            f"{carried_words(other['load_forward_N'], other['rider_place_forward_mm'], other['descent_deg'])}. "
                            f"The travel cannot tell the two apart; static sag (closed-form statics): {esc.escape(sags)}. "
                            f"A change that rests on static sag is advised only where it holds on both.</p>")
        carried = cal.get("carried") or {}
        if "load_forward_N" in carried:
            calibration += (f"<p id=\"carried\">The springs from the static sag measured; on the ride "
                            f"{carried_words(carried['load_forward_N'], carried['rider_place_forward_mm'], carried['descent_deg'])} "
                            f"and {carried['weight_beyond_file_kg']:+.1f} kg of weight beyond the file's rider.</p>")
    else:
        calibration = "<p>Not calibrated: the bike file's springs as they are (advise without --no-calibrate reads them from the ride).</p>"
    then = advice.then()
    then = f'<p id="then">{esc.escape(then)}</p>' if then else ""
    pooled = ""
    if "rides" in d:  # several rides pooled (mtbmj.ride.advice_pool): each one's own verdict, the rides left out
        def own(e):
            st = (e["change"] or {}).get("setting")
            return "" if st is None else f"{st['part']} {st['adjuster']} {st['from']:g} -&gt; {st['to']:g} {esc.escape(st['unit'])}".rstrip()
        rows_r = "".join(f"<tr><td>{esc.escape(e['ride'])}</td><td>{e['seconds']:.1f}</td><td>{esc.escape(e['answer'])}"
                         f"</td><td>{own(e)}</td></tr>" for e in d["rides"])
        pooled = (f'<h2>The rides pooled</h2><table id="rides"><tr><th>ride</th><th>length (s)</th><th>its own '
                  f'answer (one step, no unit)</th><th>its own change (in the part\'s unit)</th></tr>{rows_r}</table>')
        if d["refused"]:
            pooled += ('<h2>Left out of the pool</h2><ul id="refused">'
                       + "".join(f"<li>{esc.escape(r['why'] if r['why'].startswith(r['ride']) else r['ride'] + ': ' + r['why'])}"
                                 f"</li>" for r in d["refused"])
                       + "</ul>")
    img = base64.b64encode(png).decode()
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>mtbmj advice: {esc.escape(advice.ride)}</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}table{{border-collapse:collapse}}
td,th{{border:1px solid #bbb;padding:2px 6px;text-align:right}}td:first-child{{text-align:left}}</style></head>
<body><h1>Setup advice: {esc.escape(advice.ride)} on {esc.escape(advice.bike)}</h1>
<p id="recommended"><b>{esc.escape(advice.headline())}</b></p>
{then}<p id="line">{esc.escape(advice.line())}</p>
<p>Reconstruction check: front reproduced within {rc['front_reproduced_rms_mm']:.2f} mm RMS, rear predicted
{rc['rear_predicted_rms_mm']:.1f} mm RMS ({rc['rear_predicted_rms_percent_of_used']:.0f} % of the travel used),
{rc['samples_checked_percent']:.0f} % of the ride checked; speed {d['reconstruction']['speed_m_per_s']:.2f} m/s.</p>
{calibration}
<img id="histograms" src="data:image/png;base64,{img}" alt="travel histograms before and after">
<h2>Predicted change of every metric: {esc.escape(caption)}</h2>
<table id="changes">{head.format('after')}
{''.join(rows)}</table>
<h2>How well the model matched the ride (recorded setting)</h2>
<p id="matched">{esc.escape(matched(advice))}</p>
<p>Uncertainty: {esc.escape(d['uncertainty_method'])}.</p>
<table id="match"><tr><th>metric</th><th>unit</th><th>recorded</th><th>simulated</th><th>simulated - recorded</th>
<th>model's error (same unit)</th></tr>{match}</table>
<h2>Every candidate</h2>
<table id="candidates"><tr><th>setting (key)</th><th>unit</th><th>from</th><th>to</th><th>rule penalty change (no unit)</th>
<th>crash</th></tr>{cand}</table>
{skip}
{pooled}
{tried}
<h2>Rules</h2><ul>{''.join(f'<li>{esc.escape(k)}: {esc.escape(v)}</li>' for k, v in RULES.items())}</ul>
</body></html>
"""

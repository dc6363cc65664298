"""``mtbmj advise`` on recorded rides: each ride's calibrated springs with their intervals, whether the
rides' intervals agree, and the advice's answer or its refusal (issue 52).

    python benchmarks/advise_rides.py [--rides PATH|FOLDER] ... [--bike sst] [--workers 2] [--out PATH]

Each ride (an SST recording; a folder: its *.SST, sorted; default: the shared version-3 rides of
the SST bike, ``data/sst`` of the folder 'shared' beside the repository) is read through ``--bike``
as ``mtbmj advise`` reads it. Per ride: its length, the calibration of ``mtbmj.ride.calibrate``
(each end's spring scale and its 95 % interval, the file's value and the calibrated one in the
bike file's units; or the calibration's own refusal), then ``mtbmj.ride.advise.advise`` as the
command runs it (calibrated, every candidate searched): its verdict and recommendation, or its
one-line refusal (the reconstruction's check, the recorded setting crashing). Then, per end, whether
the rides' intervals agree: the range every interval holds (the largest low to the smallest high;
none where that is empty) and each pair's overlap. Where two rides or more are advised, the pooled
advice (``mtbmj.ride.advice_pool.pooled``) too; where two or more are calibrated, their pooled calibration
(``mtbmj.ride.calibrate.calibrate_pooled``, the one bike ``advise RIDE RIDE ...`` reports). Nothing here sets a verdict to pass: what is
recorded is what the command answers. Writes its results where ``--out`` says (default
``<tempdir>/mtbmj-benchmarks/advise_rides.json``, outside the repository). Not a test: nothing is
asserted.
"""
from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, write_json  # noqa: E402

SHARED_V3 = ("00642.SST", "00643.SST", "00649.SST")  # the shared version-3 rides of the SST bike


def agreement(cals: dict) -> dict:
    """Per end: the rides' scales and intervals, the range all of them hold (``common``: [low, high],
    or None where no value is in every interval) and each pair's overlap (True where the two share a
    value)."""
    out = {}
    ends = sorted({e for c in cals.values() for e in c["springs"]})
    for end in ends:
        have = {ride: c["springs"][end] for ride, c in cals.items() if end in c["springs"]}
        if len(have) < 2:
            continue
        lo, hi = max(s["low"] for s in have.values()), min(s["high"] for s in have.values())
        out[end] = {"rides": sorted(have), "common": [lo, hi] if lo <= hi else None,
                    "pairs": {f"{a} {b}": have[a]["low"] <= have[b]["high"] and have[b]["low"] <= have[a]["high"]
                              for a, b in itertools.combinations(sorted(have), 2)}}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rides", action="append",
                    help="an SST recording or a folder (its *.SST, sorted); repeat for more; default: the shared "
                         "version-3 rides 00642, 00643 and 00649 (data/sst of the folder 'shared' next to the clone)")
    ap.add_argument("--bike", default="sst", help="the recorded bike (preset or file)")
    ap.add_argument("--workers", type=int, default=2, help="processes for the advice's runs")
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.errors import MtbmjError
    from mtbmj.measured import telemetry
    from mtbmj.ride import advice_pool, advise, calibrate

    named = list(args.rides or [])  # as given (the command recorded names no machine's path by default)
    if not args.rides:
        data = Path(__file__).resolve().parents[2] / "shared" / "data" / "sst"
        args.rides = [str(data / name) for name in SHARED_V3]
    rides = []
    for ride in args.rides:
        rides += sorted(str(p) for p in Path(ride).glob("*.SST")) if Path(ride).is_dir() else [ride]
    rows, cals, advised, calibrated = [], {}, [], []
    for ride in rides:
        path = Path(ride)
        row = {"ride": path.name, "folder": path.parent.name}
        t0 = time.perf_counter()
        try:
            record = telemetry.read_ride(path, **decoding(SimpleNamespace(bike=args.bike, fork_max_mm=None,
                                                                          shock_max_mm=None)))
        except MtbmjError as exc:
            row.update(unread=str(exc))
            rows.append(row)
            print(f"{path.name}: not read: {exc}", flush=True)
            continue
        row["version"], row["seconds"] = record.version, float(record.time_s[-1] - record.time_s[0])
        try:
            cal = calibrate.calibrate(record, args.bike)
            row["calibration"] = cal.to_dict()
            cals[path.name] = row["calibration"]
            calibrated.append(record)
            print(f"{path.name}: {cal.line()}", flush=True)
        except MtbmjError as exc:
            row["calibration_refused"] = str(exc)
            print(f"{path.name}: calibration refused: {exc}", flush=True)
        try:
            a = advise.advise(record, args.bike, workers=args.workers)
            rec = a.recommendation
            row["advice"] = {"answer": a.verdict.get("answer"), "why": a.verdict.get("why"),
                             "recommendation": None if rec is None else
                             {"key": rec["key"], "direction": rec["direction"], "setting": rec["setting"]},
                             "candidates": len(a.candidates)}
            advised.append(record)
            print(f"{path.name}: {a.verdict.get('answer')}: {a.verdict.get('why')}", flush=True)
        except MtbmjError as exc:
            row["advice_refused"] = str(exc)
            print(f"{path.name}: advice refused: {exc}", flush=True)
        row["wall_s"] = time.perf_counter() - t0
        rows.append(row)
    pooled_cal = None
    if len(calibrated) >= 2:  # the rides' one bike: every calibrated ride's balances together (advise RIDE RIDE's)
        try:
            pc = calibrate.calibrate_pooled(calibrated, args.bike)
            pooled_cal = {**pc.to_dict(), "ride_names": [r.name for r in calibrated]}
            print(f"pooled: {pc.line()}", flush=True)
        except MtbmjError as exc:
            pooled_cal = {"refused": str(exc)}
    pooled = None
    if len(advised) >= 2:
        try:
            p = advice_pool.pooled(advised, args.bike, workers=args.workers)
            pooled = {"answer": p.verdict.get("answer"), "why": p.verdict.get("why"), "rides": p.each()}
        except MtbmjError as exc:
            pooled = {"refused": str(exc)}
    agree = agreement(cals)
    for end, a in agree.items():
        common = "none" if a["common"] is None else f"x{a['common'][0]:.3f}-x{a['common'][1]:.3f}"
        print(f"{end}: the intervals all hold {common}; pairs overlapping: "
              + ", ".join(f"{k} {'yes' if v else 'no'}" for k, v in a["pairs"].items()))
    out = {"command": "python benchmarks/advise_rides.py" + "".join(f" --rides {r}" for r in named)
                      + (f" --bike {args.bike}" if args.bike != "sst" else "")
                      + (f" --workers {args.workers}" if args.workers != 2 else "")
                      + " --out benchmarks/results/advise_rides.json",
           "bike": args.bike, "rides": rows, "agreement": agree, "pooled": pooled,
           "pooled_calibration": pooled_cal,
           "verdict_set_to_pass": False}
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""``mtbmj reconstruct`` on recorded rides: the speed profile, the rear's check beside its two naive
baselines and the verdict, per ride (issue 51).

    python benchmarks/reconstruct_rides.py [--rides PATH|FOLDER] ... [--shared] [--bike sst] [--out PATH]

Each ride (an SST recording or a travel CSV; 'example' for the shipped 00649.SST) is read through
``--bike`` as ``mtbmj reconstruct`` reads it and reconstructed once in this process; a ride the
command refuses is kept with its one-line reason. Per ride: its length, the windows' speeds (median,
range, accepted and rejected windows, the median of the accepted windows' standard errors), the rear
predicted's RMS error, the two baselines' (the fork's record delayed by wheelbase / speed(t) with a
least-squares scale and offset; the rear's mean), the rear predicted's correlation with the record, the
fork's record at the same moment with its own scale and offset (reported, not judged by), the rear
with the share of its ground met at the front's moment fitted on its record (``at_once_fit``:
``reconstruct(..., at_once=True)``, reported, not judged; the wall time includes it), what the fork's
record holds about the rear (``checks.bound_fork_filter_rms_mm``: a linear filter from the fork's
record fitted on the rear's itself, cross-validated; reported, not judged) beside the pass mark,
the whole bike's passes and where it diverged (if it did), the share of the ride checked, the verdict,
the flights bridged and each drop's edge flight's level change read, kept or left (``drop_levels``,
``mtbmj/ride/reconstruct_flight.py``), the stretches whose ground found rises more than the bike could
climb (``beyond_trail``, ``mtbmj/ride/reconstruct_envelope.py``) and the wall time. Writes its results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/
reconstruct_rides.json``, outside the repository). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, write_json  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rides", action="append",
                    help="an SST recording or travel CSV, a folder (its *.SST, sorted), or 'example' (00649.SST); "
                         "repeat for more; default: example")
    ap.add_argument("--shared", action="store_true",
                    help="every ride of the shared telemetry beside the repository (data/sst and data/sst_v2 of "
                         "the folder 'shared' next to the clone)")
    ap.add_argument("--bike", default="sst", help="the recorded bike (preset or file)")
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.errors import MtbmjError
    from mtbmj.measured import telemetry
    from mtbmj.ride import reconstruct

    named = list(args.rides or [])  # as given (the command recorded names no machine's path for --shared)
    if args.shared:
        data = Path(__file__).resolve().parents[2] / "shared" / "data"
        args.rides = (args.rides or []) + [str(data / "sst"), str(data / "sst_v2")]
    args.rides = args.rides or ["example"]
    rides = []
    for ride in args.rides:
        rides += sorted(str(p) for p in Path(ride).glob("*.SST")) if Path(ride).is_dir() else [ride]
    rows = []
    for ride in rides:
        path = telemetry.ride_path(ride)
        row = {"ride": path.name, "folder": path.parent.name}
        t0 = time.perf_counter()
        try:
            record = telemetry.read_ride(path, **decoding(SimpleNamespace(bike=args.bike, fork_max_mm=None,
                                                                          shock_max_mm=None)))
            row["version"], row["seconds"] = record.version, float(record.time_s[-1] - record.time_s[0])
            rec = reconstruct.reconstruct(record, args.bike, at_once=True)
        except MtbmjError as exc:
            row.update(refused=str(exc), wall_s=time.perf_counter() - t0)
            rows.append(row)
            print(f"{path.name}: refused: {exc}", flush=True)
            continue
        s = rec.summary()
        sds = [w["speed_sd_m_per_s"] for w in s["windows"] if w["speed_sd_m_per_s"] is not None]
        import numpy as np

        v = rec.valid & np.isfinite(rec.rear_predicted)
        corr = float(np.corrcoef(rec.rear_predicted[v], rec.rear[v])[0, 1]) if v.sum() > 2 else None
        row.update(wall_s=time.perf_counter() - t0, speed_profile=s["speed_profile"], whole_bike=s["whole_bike"],
                   rear_correlation=corr,
                   speed_sd_median_m_per_s=statistics.median(sds) if sds else None,
                   rejected=sorted({w["rejected"].split(" (")[0].split(":")[0] for w in s["windows"] if w["rejected"]}),
                   checks=s["checks"], wheelbase_at_sag_m=s["wheelbase_at_sag_m"], at_once_fit=s.get("at_once_fit"),
                   flights=len(s["flights"]), drop_levels=s["drop_levels"], beyond_trail=s["beyond_trail"],
                   wall_s_includes="the at-once fit (two or three more runs of the whole bike than the command's)")
        rows.append(row)
        b = s['checks']['bound_fork_filter_rms_mm']
        print(f"{path.name}: {s['checks']['verdict']} (the fork's filter " + ("none" if b is None else f"{b:.1f} mm") + ", "
              f"the mark {s['checks']['pass_mark_rms_mm']:.1f}; {row['wall_s']:.1f} s)", flush=True)
    out = {"command": "python benchmarks/reconstruct_rides.py" + "".join(f" --rides {r}" for r in named)
                      + (" --shared" if args.shared else "")
                      + (f" --bike {args.bike}" if args.bike != "sst" else "")
                      + " --out benchmarks/results/reconstruct_rides.json",
           "bike": args.bike, "beat_margin_percent": 100.0 * reconstruct.BEAT_MARGIN, "rides": rows}
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Does the whole bike ride its own reconstruction? Per shared ride, as a user would run it and as
``mtbmj advise`` does (issue 51, item 4).

    python benchmarks/ride_own.py [--rides PATH|FOLDER] ... [--shared] [--bike sst] [--no-advise] [--out PATH]

Each ride (an SST recording; 'example' for the shipped 00649.SST) is first reconstructed with the
command, ``mtbmj reconstruct RIDE --bike BIKE --out DIR``, and its terrain ridden with the command,
``mtbmj bike BIKE DIR/terrain.csv --speed-profile DIR/speed.csv --out DIR2`` (the recorded setting:
the bike file as it is, the rider's drive holding the speed found). A ride ``mtbmj reconstruct``
refuses (no speed) is kept with its one-line reason. Then, unless ``--no-advise``, as ``mtbmj advise``
rides it: ``mtbmj.ride.advise.prepare`` (the springs calibrated on the ride, and not) and the recorded
setting's run as ``advise.simulate`` makes it (its ``run_bike`` call, whose positions place a crash); where ``prepare`` refuses the ride (its reconstruction fails
its own check) the same steps are taken without the check (``ridden_anyway``), the refusal kept.

Per run: crashed or not, and where (the front axle's place on the ride and the ride's time there;
a run that trails the ride's speed gets there later than the ride did); what the terrain found looks like there (height, the steepest slope and the largest step
within 2 m before the crash, over 0.2 m; the ``beyond_trail`` stretches, flights and drop levels of
``reconstruction.json`` within 3 s); the speed there and whether a window gave it (or it is held or
interpolated over a stretch without one, ``left_out``); and the ride's own record there (both ends'
travel within 1 s: the rider came home through it, the record running on past it). Writes its
results where ``--out`` says (default ``<tempdir>/mtbmj-benchmarks/ride_own.json``, outside the
repository). Not a test: nothing is asserted.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, write_json  # noqa: E402

NEAR_S = 3.0  # a reconstruction's stretch (beyond trail, flight, drop) this close to the crash is "there"
LOOK_BACK_M = 2.0  # the terrain read over this far before the front axle's place at the crash
STEP_OVER_M = 0.2  # a "step": the largest height change over this distance there
RECORD_S = 1.0  # the ride's own record read this far either side of the crash


def _csv(path: Path) -> np.ndarray:
    """A run folder's CSV table by column name (its leading '#' lines skipped)."""
    with open(path) as f:
        skip = next(i for i, line in enumerate(f) if not line.startswith("#"))
    return np.genfromtxt(path, delimiter=",", names=True, skip_header=skip)


def terrain_there(x: np.ndarray, z: np.ndarray, at_m: float) -> dict:
    """The terrain (x m, z m) over ``LOOK_BACK_M`` before ``at_m`` and 0.5 m after: the height at
    ``at_m``, the steepest slope (deg, either sign; from the profile's own points) and the largest
    rise or fall over ``STEP_OVER_M`` (m)."""
    keep = (x >= at_m - LOOK_BACK_M) & (x <= at_m + 0.5)
    xs, zs = x[keep], z[keep]
    if xs.size < 3:
        return {"height_m": float(np.interp(at_m, x, z)), "slope_max_deg": None, "step_m": None}
    slope = np.degrees(np.arctan(np.diff(zs) / np.maximum(np.diff(xs), 1e-9)))
    later = np.interp(xs + STEP_OVER_M, x, z) - zs
    return {"height_m": float(np.interp(at_m, x, z)), "height_range_m": float(zs.max() - zs.min()),
            "slope_max_deg": float(slope[np.argmax(np.abs(slope))]),
            "step_m": float(later[np.argmax(np.abs(later))])}


def record_there(t: np.ndarray, fork: np.ndarray, rear: np.ndarray, at_s: float) -> dict:
    """The ride's own record within ``RECORD_S`` of ``at_s``: both ends' largest travel (mm) and how
    long the record runs on past it."""
    keep = np.abs(t - at_s) <= RECORD_S
    return {"fork_max_mm": float(fork[keep].max()) if keep.any() else None,
            "rear_max_mm": float(rear[keep].max()) if keep.any() else None,
            "record_runs_on_s": float(t[-1] - at_s)}


def near(stretches, at_s: float) -> list:
    return [s for s in stretches or [] if s["start_s"] - NEAR_S <= at_s <= s["end_s"] + NEAR_S]


def speed_kind(rec: dict, at_s: float) -> str:
    """'window' where a window gave the speed at ``at_s``, else 'held or interpolated' (a stretch
    without a speed, ``left_out``)."""
    for s in rec.get("left_out") or []:
        if s["start_s"] <= at_s <= s["end_s"]:
            return "held or interpolated (no window here)"
    return "a window's"


def where(crash_t_ride: float, front_m_ride: float | None, rec_json: dict, series, terrain) -> dict:
    """What there is at the crash: ``crash_t_ride`` (ride time, s), ``front_m_ride`` (the front axle's
    ride distance, m, or None to read it from the time)."""
    t, v = series["time_s"], series["speed_m_per_s"]
    dist = np.concatenate(([0.0], np.cumsum(np.diff(t) * v[:-1])))
    lead = float(rec_json.get("terrain_csv_lead_in_m", 0.0))
    if front_m_ride is None:
        front_m_ride = float(np.interp(crash_t_ride, t, dist))
    return {"ride_s": crash_t_ride, "ride_m": front_m_ride,
            "speed_m_per_s": float(np.interp(crash_t_ride, t, v)), "speed_from": speed_kind(rec_json, crash_t_ride),
            "terrain": terrain_there(terrain["distance_m"], terrain["height_mm"] / 1000.0, front_m_ride + lead),
            "beyond_trail": near(rec_json.get("beyond_trail"), crash_t_ride),
            "flights": near(rec_json.get("flights"), crash_t_ride),
            "drop_levels": near(rec_json.get("drop_levels"), crash_t_ride),
            "record": record_there(t, series["fork_mm"], series["rear_mm"], crash_t_ride)}


def run_cli(args: list, env: dict) -> tuple[int, str]:
    exe = shutil.which("mtbmj") or "mtbmj"
    done = subprocess.run([exe, *args], capture_output=True, text=True, env=env)
    return done.returncode, (done.stdout + done.stderr).strip().splitlines()[-1] if (done.stdout + done.stderr).strip() else ""


def by_command(path: Path, bike: str, work: Path) -> dict:
    """The ride reconstructed and ridden by the two commands (module doc)."""
    out: dict = {}
    rdir, bdir = work / f"r_{path.stem}", work / f"b_{path.stem}"
    t0 = time.perf_counter()
    code, line = run_cli(["reconstruct", str(path), "--bike", bike, "--out", str(rdir)], dict(os.environ))
    out["reconstruct_exit"], out["reconstruct_wall_s"] = code, time.perf_counter() - t0
    if not (rdir / "terrain.csv").is_file():
        out["refused"] = line
        return out
    rec_json = json.loads((rdir / "reconstruction.json").read_text())
    out["reconstruction"] = {"verdict": rec_json["checks"].get("verdict"), "passes": rec_json["checks"].get("passes"),
                             "speed_median_m_per_s": rec_json["speed_profile"]["median_m_per_s"],
                             "beyond_trail": rec_json.get("beyond_trail"), "terrain_m": rec_json.get("terrain_length_m"),
                             "whole_bike_diverged_s": (rec_json.get("whole_bike") or {}).get("diverged_s")}
    t0 = time.perf_counter()
    code, line = run_cli(["bike", bike, str(rdir / "terrain.csv"), "--speed-profile", str(rdir / "speed.csv"),
                          "--out", str(bdir)], dict(os.environ))
    out["bike_exit"], out["bike_wall_s"], out["bike_line"] = code, time.perf_counter() - t0, line[:300]
    if not (bdir / "summary.json").is_file():
        out["bike_refused"] = line
        return out
    s = json.loads((bdir / "summary.json").read_text())
    series, terrain = _csv(rdir / "series.csv"), _csv(rdir / "terrain.csv")
    ride_s = float(series["time_s"][-1])
    out["crash"] = s.get("crash")
    if s.get("crash"):
        ts = _csv(bdir / "timeseries.csv")
        tc = float(s["crash"]["time_s"])
        x_front = ts["x_m"] - ts["x_m"][0] + float(s["start_m"])  # the front axle starts at start_m
        front_m = float(np.interp(tc, ts["time_s"], x_front)) - float(rec_json.get("terrain_csv_lead_in_m", 0.0))
        t, v = series["time_s"], series["speed_m_per_s"]
        dist = np.concatenate(([0.0], np.cumsum(np.diff(t) * v[:-1])))
        tride = float(np.interp(front_m, dist, t))
        out["at"] = where(tride, front_m, rec_json, series, terrain)
        out["ridden_percent"] = 100.0 * tride / ride_s
    else:
        out["ridden_percent"] = 100.0
    return out


def as_advise(record, bike: str, calibrated: bool) -> dict:
    """The recorded setting ridden as ``mtbmj advise`` rides it (module doc)."""
    from mtbmj.errors import MtbmjError
    from mtbmj.ride import advise, reconstruct as rc
    from mtbmj.ride.advice_rules import RideNotDescribed

    out: dict = {"calibrated": calibrated}
    t0 = time.perf_counter()
    try:
        ride = advise.prepare(record, bike, calibrated=calibrated, candidates=False)
    except RideNotDescribed as exc:
        out["prepare_refused"] = str(exc)[:300]
        ride = None
    except MtbmjError as exc:
        out["refused"] = str(exc)[:300]
        return out
    if ride is None:  # the same steps as prepare's without its check (advise.prepare)
        ridden = rc.ridden_part(record)[0]
        over = None
        if calibrated:
            from mtbmj.ride import calibrate as cal_mod

            try:
                cal = cal_mod.calibrate(ridden, bike, None, None, None, "rider")
            except MtbmjError as exc:  # the calibration's own refusal: advise rides nothing
                out["refused"] = str(exc)[:300]
                return out
            over, statics = cal.apply(bike, None), cal.apply(bike, None, statics=True)
        else:
            cal, statics = None, None
        rec = rc.reconstruct(record, bike, statics, spectral=False)
        profile = rec.speed_along()
        speed = float(profile[1][0])
        terrain = advise.terrain_of(rec, 0.0 if cal is None else cal.descent_deg)
        lead_s = (rec.distance[0] - terrain.start_x) / speed
        ride_s = float(ridden.time_s[-1] - ridden.time_s[0])
        job = ("sst" if bike == "sst" else bike, dict(over or {}), terrain, speed, ride_s + lead_s, "recorded setting",
               lead_s, profile)
        out["ridden_anyway"] = True
    else:
        rec, job, ride_s = ride.rec, ride.jobs()[0], ride.ride_s
    # advise.simulate's own call (its Run keeps no position): the crash placed by where the bike is, not
    # by the ride's clock (a run that trails the ride's speed is short of where the ride was at that time)
    from mtbmj.bike import run as bike_run

    bk, over, terrain, speed, duration, _, lead_s, profile = job
    r = bike_run.run_bike(bk, terrain, speed, duration=duration, drive="rider", overrides=over or None,
                          speed_profile=profile)
    out["wall_s"] = time.perf_counter() - t0
    crash = r.summary.get("crash")
    out["crash"] = crash["line"] if crash else None
    if crash:
        raw = r.raw
        x_front = raw["x_m"] - raw["x_m"][0] + float(terrain.start_x)  # the front axle starts at the start
        at_m = float(np.interp(crash["time_s"], raw["time_s"], x_front))
        tr = float(np.interp(at_m, rec.distance, rec.t))  # the ride's time where the ride was there
        out["ride_s"], out["ride_m"] = tr, at_m - float(rec.distance[0])
        out["run_s"] = float(crash["time_s"]) - lead_s  # the run's own time from the ride's first metre
        out["ridden_percent"] = 100.0 * (tr - float(rec.t[0])) / ride_s
        out["terrain"] = terrain_there(np.asarray(terrain.x), np.asarray(terrain.z), at_m)
        out["record"] = record_there(np.asarray(rec.t), np.asarray(rec.front), np.asarray(rec.rear), tr)
    else:
        out["ridden_percent"] = 100.0
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rides", action="append",
                    help="an SST recording, a folder (its *.SST, sorted), or 'example' (00649.SST); repeat for more")
    ap.add_argument("--shared", action="store_true",
                    help="the shared rides that give a speed (benchmarks/results/reconstruct_rides.json): data/sst and "
                         "data/sst_v2 of the folder 'shared' next to the clone")
    ap.add_argument("--bike", default="sst", help="the recorded bike (preset or file)")
    ap.add_argument("--no-advise", action="store_true", help="the two commands only")
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)

    from types import SimpleNamespace

    from mtbmj.cli.telemetry import decoding
    from mtbmj.measured import telemetry

    named = list(args.rides or [])
    rides = []
    if args.shared:
        data = Path(__file__).resolve().parents[2] / "shared" / "data"
        known = json.loads((Path(__file__).resolve().parent / "results" / "reconstruct_rides.json").read_text())
        rides += [str(data / r["folder"] / r["ride"]) for r in known["rides"] if "refused" not in r]
    for ride in args.rides or ([] if args.shared else ["example"]):
        rides += sorted(str(p) for p in Path(ride).glob("*.SST")) if Path(ride).is_dir() else [ride]
    rows = []
    with tempfile.TemporaryDirectory(prefix="mtbmj-ride-own-") as tmp:
        for ride in rides:
            path = telemetry.ride_path(ride)
            row = {"ride": path.name, "folder": path.parent.name, **by_command(path, args.bike, Path(tmp))}
            if "refused" not in row and not args.no_advise:
                record = telemetry.read_ride(path, **decoding(SimpleNamespace(bike=args.bike, fork_max_mm=None,
                                                                              shock_max_mm=None)))
                row["seconds"] = float(record.time_s[-1] - record.time_s[0])
                row["advise"] = [as_advise(record, args.bike, c) for c in (False, True)]
            rows.append(row)
            said = row.get("refused") or (row["crash"]["line"] if row.get("crash") else "rode it all")
            adv = "; ".join(f"advise {'calibrated' if a['calibrated'] else 'file'}: "
                            + (a.get("refused") or a["crash"] or "rode it all") for a in row.get("advise", []))
            print(f"{path.name}: {said}" + (f" (ride {row['at']['ride_s']:.1f} s, {row['at']['ride_m']:.0f} m)"
                                            if row.get("at") else "") + (f"; {adv}" if adv else ""), flush=True)
    out = {"command": "python benchmarks/ride_own.py" + "".join(f" --rides {r}" for r in named)
                      + (" --shared" if args.shared else "") + (f" --bike {args.bike}" if args.bike != "sst" else "")
                      + (" --no-advise" if args.no_advise else "") + " --out benchmarks/results/ride_own.json",
           "bike": args.bike, "near_s": NEAR_S, "look_back_m": LOOK_BACK_M, "step_over_m": STEP_OVER_M,
           "record_s": RECORD_S, "rides": rows}
    print(f"wrote {write_json(__file__, out, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

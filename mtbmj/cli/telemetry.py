"""``mtbmj telemetry FILE.SST [--compare RUN_DIR ...] [--out DIR]``: the rider's metrics of a real
ride, and the same metrics of simulated runs on the same axes.

A compared run is a drop or rolling run (its fork) or a bike run (``mtbmj bike --out``: its fork
and its rear wheel, beside the ride's fork and rear wheel). Writes ``telemetry.json`` (metrics of
the fork and rear of the ride and of the fork of every compared run, and the rear of a bike run) and ``telemetry.png`` (travel histogram in % of travel and velocity histogram with
the high/low-speed split, both in % of time), atomically. The comparison is
``mtbmj.ride.comparison``'s; this module parses, decodes the ride, calls it and prints.
"""
from __future__ import annotations

from pathlib import Path

from mtbmj.cli.common import add_out
from mtbmj.measured import telemetry


def add_parser(subparsers):
    """Add the ``telemetry`` sub-command to an argparse sub-parser collection."""
    p = subparsers.add_parser(
        "telemetry", help="metrics of a real ride (SST file), optionally against simulated runs",
        description="Read a Sufni Suspension Telemetry (SST v3) file, compute the travel histogram (% of travel), "
                    "the velocity histogram (compression positive) with the high/low-speed split, bottom-outs and "
                    "airtime for the fork and the rear wheel, and plot simulated runs' fork (and a bike run's rear "
                    "wheel) on the same axes.")
    p.add_argument("sst", type=Path, metavar="FILE.SST",
                   help="SST v3 or v2 recording, a travel CSV (time_s with fork_mm, shock_mm and/or rear_mm; "
                        "docs/rolling.md), or 'example' for the shipped 00649.SST")
    p.add_argument("--compare", type=Path, nargs="+", action="extend", metavar="RUN_DIR",
                   help="run directories (mtbmj drop/roll --out: the fork; mtbmj bike --out: the fork and the rear wheel) "
                        "compared with the ride")
    add_out(p, "out/telemetry")
    p.add_argument("--threshold-mm-per-s", type=float, default=100.0,
                   help="high/low-speed split of the velocity histogram (default 100)")
    p.add_argument("--bin-percent", type=float, default=5.0, help="travel histogram bin width in %% of travel (default 5)")
    p.add_argument("--bike", metavar="BIKE",
                   help="the recorded bike (a bike preset or file): its fork travel, shock stroke and leverage curve "
                        "decode the ride (default: the SST example's bike, the Commencal Clash 2022)")
    p.add_argument("--fork-max-mm", type=float,
                   help=f"fork travel of the recorded bike (default the --bike's, else {telemetry.FORK_TRAVEL_MAX_MM:g})")
    p.add_argument("--shock-max-mm", type=float,
                   help=f"rear shock stroke of the recorded bike (default the --bike's, else "
                        f"{telemetry.SHOCK_STROKE_MAX_MM:g})")
    p.set_defaults(func=cmd_telemetry)
    return p


def add_ride(p, bike_help: str, many: bool = False) -> None:
    """The recorded ride (a positional RIDE; ``many``: one or more, a list) and its --bike, as
    :func:`ride_record` reads them."""
    p.add_argument("ride", type=Path, metavar="RIDE", nargs="+" if many else None,
                   help="SST v3 or v2 recording or a travel CSV with both ends, or 'example' (the shipped 00649.SST; in any case)"
                        + ("; several rides of one bike at one setting are pooled into one advice" if many else ""))
    p.add_argument("--bike", required=True, metavar="BIKE", help=bike_help)


def add_sensor_spans(p) -> None:
    """--fork-max-mm and --shock-max-mm, the travels the recorder's sensors span (:func:`decoding`)."""
    p.add_argument("--fork-max-mm", type=float, help="fork travel the recording's sensor spans (default: the bike's)")
    p.add_argument("--shock-max-mm", type=float, help="shock stroke the sensor spans (default: the bike's)")


def decoding(args, bike=None, overrides=None) -> dict:
    """read_sst's fork_max_mm, shock_max_mm and leverage: the --bike's (``bike``: that file
    resolved already, ``mtbmj.bike.spec.resolve``; ``overrides``: the command's --set, --fork-set and
    --shock-set over it, as its runs take them), with --fork-max-mm and --shock-max-mm over them; the
    SST example's bike without --bike."""
    out = {"fork_max_mm": telemetry.FORK_TRAVEL_MAX_MM, "shock_max_mm": telemetry.SHOCK_STROKE_MAX_MM,
           "leverage": telemetry.LeverageCurve()}
    if args.bike is not None:
        from mtbmj.bike import spec

        out = spec.ride_decoding(spec.load(args.bike if bike is None else bike, overrides or None))
    for key in ("fork_max_mm", "shock_max_mm"):
        if getattr(args, key) is not None:
            out[key] = getattr(args, key)
    return out


def travel_keys(args, named: str) -> tuple[str, str]:
    """What the fork travel and the shock stroke a ride is read with were set by (``decoding``), as
    a refusal names them: --fork-max-mm, the bike's key (``named``: how the command names its bike,
    ``ride_record``'s), or the default (the SST example's bike)."""
    keys = []
    for option, attr, bike_key, default in (
            ("--fork-max-mm", "fork_max_mm", "geometry.fork_travel_mm", telemetry.FORK_TRAVEL_MAX_MM),
            ("--shock-max-mm", "shock_max_mm", "shock.stroke_mm", telemetry.SHOCK_STROKE_MAX_MM)):
        if getattr(args, attr, None) is not None:
            keys.append(option)
        elif getattr(args, "bike", None) is not None:
            keys.append(f"{bike_key} of {named}")
        else:
            keys.append(f"{option} default {default:g}, the SST example's bike; give --bike")
    return keys[0], keys[1]


def ride_record(ride, args, bike=None, overrides=None, named: str | None = None):
    """The ride a command names (a recording or travel CSV, or "example": the shipped SST ride)
    decoded through ``decoding(args, bike, overrides)``; refused when it travels past the travel it is
    read with (``telemetry.beyond_travel``), else its quality warnings issued. ``named``: how the
    command names its bike in those lines (default "--bike BIKE"; ``mtbmj bike``'s is positional)."""
    from mtbmj.config import warn

    read = decoding(args, bike, overrides)
    record = telemetry.read_ride(telemetry.ride_path(ride), **read)
    named = named or f"--bike {getattr(args, 'bike', None)}"
    beyond = telemetry.beyond_travel(record, *travel_keys(args, named))
    unset = [end for end in ("front", "rear") if end not in read] if getattr(args, "bike", None) is not None else []
    if unset and record.version == 3:  # the recorder's arms not given: the example's taken, said
        beyond.append(f"{record.name}: {named} gives no [sensors] for its {' and '.join(unset)} sensor: "
                      f"decoded with the SST example's recorder's arms (mtbmj/bike/presets/sst.toml [sensors]); "
                      f"another recorder's travel is wrong by as much as its arms differ")
    given = [end for end in ("front", "rear") if end in read] if getattr(args, "bike", None) is not None else []
    from mtbmj.bike.spec import preset_names

    preset = str(getattr(args, "bike", "")).lower() in {n.lower() for n in preset_names()}
    if given and record.version == 2 and not preset:  # a file's arms are a version-3 recorder's: set aside, said
        beyond.append(f"{record.name}: {named}'s [sensors] ({' and '.join(given)}) are a version-3 "
                      f"recorder's arms: not used for this version-2 record, read with the calibration of its time")
    warn(telemetry.quality(record) + beyond)
    return record


def cmd_telemetry(args) -> int:
    from mtbmj.readout.compare import refuse_repeated
    from mtbmj.ride import comparison

    refuse_repeated(args.compare or [], "--compare ")  # drawn and counted twice: refused, as mtbmj compare does
    record = ride_record(args.sst, args)
    runs = [comparison.load_run(d) for d in args.compare or []]
    result = comparison.compare(record, runs, args.threshold_mm_per_s, args.bin_percent)
    written = result.write(args.out)
    print(f"{result.line()}; wrote {', '.join(p.name for p in written)} to {args.out}")
    return 0

"""``mtbmj reconstruct``: a ride through a bike's laws: its speed from the lag between the two ends,
the terrain under the front wheel, and the rear predicted from it beside the measured rear (the
check printed with every reconstruction) (``mtbmj.ride.reconstruct``)."""
from __future__ import annotations

from mtbmj.cli.common import add_out, write_and_say


def cmd_reconstruct(args) -> int:
    from mtbmj.bike import spec
    from mtbmj.cli.telemetry import ride_record
    from mtbmj.ride import reconstruct

    bike = spec.resolve(args.bike)  # read once: the decoding and the reconstruction take it
    record = ride_record(args.ride, args, bike)
    (given,) = given_speeds(args, [record])  # a bad --speed-csv: one line before any work
    result = reconstruct.reconstruct(record, bike, at_once=args.at_once, speed=given)
    return write_and_say(result, args.out)


def given_speeds(args, records) -> list:
    """The speed given per ride (``--speed`` or ``--speed-csv``: :mod:`mtbmj.ride.reconstruct_given`), None
    where none was given; each CSV read and checked against its ride's clock before any work. Given once,
    ``--speed`` holds for every ride; otherwise each option once per ride, in the rides' order."""
    from mtbmj.errors import ConfigError
    from mtbmj.ride import reconstruct_given as given_mod

    speeds, files = ([] if x is None else list(x) if isinstance(x, list) else [x]
                     for x in (getattr(args, "speed", None), getattr(args, "speed_csv", None)))
    if speeds and files:
        raise ConfigError("--speed and --speed-csv: the ride's speed given twice; give one")
    if not speeds and not files:
        return [None] * len(records)
    if len(speeds) == 1:
        speeds = speeds * len(records)
    many = len(speeds or files)
    if many != len(records):
        raise ConfigError(f"{'--speed' if speeds else '--speed-csv'} given {many} times for {len(records)} rides: give "
                          f"one per ride, in the rides' order" + (" (or --speed once for all)" if speeds else ""))
    out = [given_mod.constant(v) for v in speeds] or [given_mod.read_csv(f) for f in files]
    cut = getattr(args, "duration", None)  # advise's: it limits the runs, the reconstruction is of the whole ride
    short = "" if cut is None else (f" (--duration {cut:g} s limits the runs over the ride; the ride is "
                                    f"reconstructed whole, at the speed given)")
    for g, record in zip(out, records):
        g.check_covers(float(record.time_s[0]), float(record.time_s[-1]), record.name, short)
    return out


def add_given_speed(p, many: bool = False) -> None:
    """``--speed M_PER_S`` and ``--speed-csv FILE``: the ride's speed given (``many``: one per ride, repeatable)."""
    each = " (repeatable: once for every ride, or once per ride in the rides' order)" if many else ""
    csv_each = " (repeatable: once per ride, in the rides' order)" if many else ""
    p.add_argument("--speed", type=float, action="append" if many else None, metavar="M_PER_S",
                   help="the ride's speed, one for the whole ride (a known steady speed), used in place of the lag "
                        "between the ends; the lag's speed is reported beside it" + each)
    p.add_argument("--speed-csv", action="append" if many else None, dest="speed_csv", metavar="FILE",
                   help="the ride's speed over time from a CSV of the columns time_s (the ride's clock) and "
                        "speed_m_per_s (a GPS track, a bike computer), interpolated onto the ride and used in place "
                        "of the lag between the ends; the lag's speed is reported beside it" + csv_each)


def add_parser(sub) -> None:
    from mtbmj.cli.telemetry import add_ride, add_sensor_spans

    p = sub.add_parser("reconstruct", help="a ride through a bike's laws: speed from the lag between the ends, the "
                                           "terrain under the front wheel, the rear predicted and checked")
    add_ride(p, "the recorded bike (preset or bike file): its fork and shock laws, leverage curve, masses and "
                "wheelbase")
    p.add_argument("--at-once", action="store_true", dest="at_once",
                   help="also the rear with a share of its ground met at the front's moment, the share fitted on the "
                        "rear's record (reported beside the check as at_once_fit, never judged)")
    add_given_speed(p)
    add_sensor_spans(p)
    add_out(p, "out/reconstruct")
    p.set_defaults(func=cmd_reconstruct)

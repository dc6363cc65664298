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
    result = reconstruct.reconstruct(ride_record(args.ride, args, bike), bike, at_once=args.at_once)
    return write_and_say(result, args.out)


def add_parser(sub) -> None:
    from mtbmj.cli.telemetry import add_ride, add_sensor_spans

    p = sub.add_parser("reconstruct", help="a ride through a bike's laws: speed from the lag between the ends, the "
                                           "terrain under the front wheel, the rear predicted and checked")
    add_ride(p, "the recorded bike (preset or bike file): its fork and shock laws, leverage curve, masses and "
                "wheelbase")
    p.add_argument("--at-once", action="store_true", dest="at_once",
                   help="also the rear with a share of its ground met at the front's moment, the share fitted on the "
                        "rear's record (reported beside the check as at_once_fit, never judged)")
    add_sensor_spans(p)
    add_out(p, "out/reconstruct")
    p.set_defaults(func=cmd_reconstruct)

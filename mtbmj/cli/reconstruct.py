"""``mtbmj reconstruct``: a ride through a bike's laws: its speed from the lag between the two ends,
the terrain under the front wheel, and the rear predicted from it beside the measured rear (the
check printed with every reconstruction) (``mtbmj.ride.reconstruct``)."""
from __future__ import annotations

from pathlib import Path

from mtbmj.cli.common import add_out


def cmd_reconstruct(args) -> int:
    from mtbmj.bike import spec
    from mtbmj.cli.telemetry import ride_record
    from mtbmj.ride import reconstruct

    bike = spec.resolve(args.bike)  # read once for the decoding (the reconstruction reads its source)
    result = reconstruct.reconstruct(ride_record(args.ride, args, bike), bike.source)
    written = result.write(args.out)
    print(f"{result.line()}; wrote {len(written)} files to {args.out}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("reconstruct", help="a ride through a bike's laws: speed from the lag between the ends, the "
                                           "terrain under the front wheel, the rear predicted and checked")
    p.add_argument("ride", type=Path, metavar="RIDE",
                   help="SST v3 or v2 recording or a travel CSV with both ends, or 'example' (the shipped 00649.SST)")
    p.add_argument("--bike", required=True, metavar="BIKE",
                   help="the recorded bike (preset or bike file): its fork and shock laws, leverage curve, masses "
                        "and wheelbase")
    p.add_argument("--fork-max-mm", type=float, help="fork travel the recording's sensor spans (default: the bike's)")
    p.add_argument("--shock-max-mm", type=float, help="shock stroke the sensor spans (default: the bike's)")
    add_out(p, "out/reconstruct")
    p.set_defaults(func=cmd_reconstruct)

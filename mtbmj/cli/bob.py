"""``mtbmj bob RECORD... --bike BIKE --out DIR``: recorded pedalling rides (Sufni SST files) and the
bike pedalled as each was, their pedal bob side by side (``mtbmj.ride.pedalling.against``): bob.json and
bob.png, one line per record."""
from __future__ import annotations

from mtbmj.cli.common import add_out, comma_words


def cmd_bob(args) -> int:
    from mtbmj.cli.bike import bike_overrides
    from mtbmj.errors import ConfigError
    from mtbmj.ride import pedalling
    from mtbmj.measured.telemetry import example_path, read_sst, repeated_samples, ride_path

    shipped = next((r for r in args.records if ride_path(r) == example_path()), None)
    if shipped is not None:  # the other ride commands' 'example': a trail ride, no pedal bob to read (00649 descends)
        raise ConfigError(f"{shipped}: the shipped example (00649.SST) is a trail ride, no pedalling; bob reads "
                          f"Sufni SST recordings of pedalling (docs/bike.md: 00088-00091)")
    twice = repeated_samples([read_sst(path) for path in args.records])  # a bad record: one line before any work
    if twice is not None:  # one ride twice (the file twice, or a copy) is two runs of one record
        first, k = twice
        raise ConfigError(f"{args.records[k]}: the same record as {args.records[first]} (the same samples); give each "
                          f"record once")
    stances = None if args.stance is None else comma_words(args.stance)  # Standing = standing; 'standing,' one
    if stances == []:  # `--stance ""`: a list left empty by mistake
        raise ConfigError(f"--stance {args.stance!r}: names no stance; give standing or seated, one per record, "
                          f"or leave --stance out for all standing")
    if args.duration is not None:  # before any run, named as typed (against's own check names duration_s)
        pedalling.check_run_s(args.duration, "--duration")
    result = pedalling.against(args.records, args.bike, stances, args.power or 250.0, bike_overrides(args) or None,
                         args.duration or pedalling.RUN_S, args.rider)
    result.write(args.out)
    for line in result.lines():
        print(line)
    print(f"wrote bob.json and bob.png to {args.out}")
    return 0


def add_parser(sub) -> None:
    from mtbmj.cli.bike import add_bike_sets

    p = sub.add_parser("bob", help="pedal bob of recorded pedalling rides beside the bike pedalled as each was")
    p.add_argument("records", nargs="+", metavar="RECORD", help="Sufni SST recordings of pedalling (not 'example', the shipped "
                                                                "trail ride)")
    p.add_argument("--bike", default="sst", help="bike preset or bike TOML file (default sst)")
    p.add_argument("--stance", help="standing or seated, one per record, comma-separated (default all standing)")
    p.add_argument("--power", type=float, help="the rider's power in W (default 250)")
    p.add_argument("--duration", type=float, help="simulated seconds per record (default 14; the bob is read over "
                                                  "the second half)")
    p.add_argument("--rider", choices=("passive", "active"), default="passive",
                   help="the rigid rider on spring-damper legs (default) or the articulated one, whose legs carry the "
                        "pedal stroke's reaction")
    add_bike_sets(p)
    add_out(p, "out/bob")
    p.set_defaults(func=cmd_bob)


__all__ = ["add_parser", "cmd_bob"]

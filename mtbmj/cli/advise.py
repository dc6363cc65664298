"""``mtbmj advise RIDE [RIDE ...] --bike BIKE``: candidate settings simulated over the ride's reconstructed
terrain, scored on what riders read, and the change recommended (``mtbmj.ride.advise``); several rides
of one setting pooled into one advice (``mtbmj.ride.advice_pool``)."""
from __future__ import annotations

import argparse

from mtbmj.cli.common import add_out


def cmd_advise(args) -> int:
    from mtbmj.bike import spec
    from mtbmj.cli.bike import bike_overrides
    from mtbmj.cli.common import Progress
    from mtbmj.cli.telemetry import ride_record
    from mtbmj.cli.common import parse_assignment
    from mtbmj.ride import advice_report, advise

    over = bike_overrides(args)
    sag = static_sag(args.static_sag_mm, args.calibrate)
    if args.carried_as is not None and sag is None:
        from mtbmj.errors import ConfigError

        raise ConfigError("--carried-as says how the runs carry the load a measured static sag leaves: it needs "
                          "--static-sag-mm FORK,SHOCK")
    carried = args.carried_as or "rider"
    if args.rider_kg is not None:
        if "rider.mass_kg" in over and over["rider.mass_kg"] != args.rider_kg:  # one would silently win
            from mtbmj.errors import ConfigError

            raise ConfigError(f"--rider-kg {args.rider_kg:g} and --set rider.mass_kg={over['rider.mass_kg']}: the rider's "
                              f"mass given twice; give one")
        over["rider.mass_kg"] = args.rider_kg
    sets = [parse_assignment(text, "--try-set") for text in args.try_set or ()]
    bike = spec.resolve(args.bike)  # the bike file read once: the decoding, the tries and the advice take it
    tries = []  # checked before any work: a bad file, key or value is one line and nothing written
    if args.try_file or sets:
        tries = [advise.trial(bike, over or None, other, sets) for other in (args.try_file or [None])]
    # every ride read (and a bad file refused in one line) before anything is simulated
    # each ride decoded through the bike as ridden: its --set sensors, leverage and travels too
    records = [ride_record(path, args, bike, over or None) for path in args.ride]
    from mtbmj.cli.reconstruct import given_speeds

    speeds = given_speeds(args, records)  # one per ride (--speed once: every ride's); a bad CSV: one line, no work
    if len(records) == 1:
        result = Progress("advise").around(
            lambda progress: advise.advise(records[0], bike, over or None, args.duration, progress, args.workers,
                                           tries=tries, calibrated=args.calibrate, static_sag_mm=sag,
                                           carried_as=carried, speed=speeds[0]))
    else:
        from mtbmj.ride import advice_pool

        result = Progress("advise").around(
            lambda progress: advice_pool.pooled(records, bike, over or None, args.duration, progress, args.workers,
                                                tries=tries, calibrated=args.calibrate, static_sag_mm=sag,
                                                carried_as=carried, speeds=speeds))
    written = result.write(args.out)
    for rec in records:  # a --duration past a ride's end is its whole ride: said, not silent
        length = float(rec.time_s[-1] - rec.time_s[0])
        if args.duration is not None and args.duration > length:
            print(f"--duration {args.duration:g} s is longer than {rec.name} ({length:.1f} s): the whole ride was "
                  f"advised on")
    for r in getattr(result, "refused", ()):
        print(f"left out of the pool: {r['why']}")
    for r in getattr(result, "rides", ()):
        print(f"{r.ride} alone: {r.headline()}")
    if result.calibration is not None:
        print(result.calibration.line())
    checks = result.reconstruction["checks"]
    given = result.reconstruction.get("speed_given")
    print(f"reconstruction: speed {result.reconstruction['speed_m_per_s']:.2f} m/s"
          f"{' given (' + given['given'] + ')' if given else ''}; check: front reproduced within "
          f"{checks['front_reproduced_rms_mm']:.2f} mm RMS, rear predicted within "
          f"{checks['rear_predicted_rms_percent_of_used']:.0f} % of the travel used")
    for tr in result.tried():
        print(f"tried {tr['label']}: " + "; ".join(f"{k} {c['from']:.3g} -> {c['to']:.3g} {advise.metric_unit(k)} "
                                                     f"(expected on the ride {c['expected']:.3g} +- "
                                                     f"{c['uncertainty'] or 0:.2g})"
                                                     for k, c in tr["changes"].items() if k in advise.HEADLINE)
              + (f"; {tr['crash']}" if tr["crash"] else ""))
    print(advice_report.matched(result))
    print(result.headline())
    if result.then():
        print(result.then())
    print(f"{result.line()}; {len(result.candidates)} candidates simulated in {result.wall_s:.0f} s; "
          f"wrote {', '.join(p.name for p in written)} to {args.out}")
    return 0


def static_sag(text, calibrate: bool):
    """``--static-sag-mm FORK,SHOCK`` read: (fork mm, shock mm), or None where not given; a bad value or
    the option beside ``--no-calibrate`` is a ``ConfigError`` naming it."""
    import math

    from mtbmj.errors import ConfigError

    if text is None:
        return None
    if not calibrate:
        raise ConfigError("--static-sag-mm calibrates the springs on the sag measured: it cannot go with --no-calibrate")
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) and v > 0.0 for v in values):
        raise ConfigError(f"--static-sag-mm: {text!r} is not two sags in mm, the fork's stroke and the shock's, "
                          f"both > 0 (e.g. --static-sag-mm 40,15)")
    return values


def add_parser(sub) -> None:
    from mtbmj.cli.bike import add_bike_sets
    from mtbmj.cli.reconstruct import add_given_speed
    from mtbmj.cli.telemetry import add_ride, add_sensor_spans

    p = sub.add_parser("advise", help="setup advice: candidate settings simulated over the ride's reconstructed "
                                      "terrain, and the change recommended (several rides of one setting: pooled)",
                       description="Setup advice from a ride: candidate settings simulated over its reconstructed "
                                   "terrain, the one change recommended first (the balance of the ends before the "
                                   "rest), in clicks, lb/in and psi as the part is set. Several RIDEs of one bike at "
                                   "one setting are pooled into one advice (each ride's own answer beside it; a ride "
                                   "refused is left out and named; that the rides share the setting is your word: it "
                                   "cannot be told from the files). A progress counter shows on a terminal only.")
    add_ride(p, "the recorded bike with the settings it was ridden with (preset or bike file)", many=True)
    p.add_argument("--rider-kg", type=float, metavar="KG", help="the whole rider's mass (rider.mass_kg)")
    add_bike_sets(p)  # the settings as ridden, where they differ from the bike file
    p.add_argument("--duration", type=float, metavar="S",
                   help="advise on the ride's first S seconds only (a ride shorter than S: the whole ride, said in a line)")
    p.add_argument("--try", action="append", dest="try_file", metavar="BIKE_FILE",
                   help="predict the ride's metrics at this bike file's settings beside the recorded ones (repeatable)")
    p.add_argument("--try-set", action="append", dest="try_set", metavar="KEY=VALUE",
                   help="a setting to try (repeatable, all in one try): fork:KEY or shock:KEY of the part's "
                        "configuration (e.g. fork:fork.spring.rate_N_per_mm=7, shock:fork.damper.rebound_clicks=8) "
                        "or a bike key (shock.spring_rate_lb_per_in=500, rider.mass_kg=80); over --try's file")
    p.add_argument("--calibrate", action=argparse.BooleanOptionalAction, default=True,
                   help="calibrate each end's spring on the ride first (its mean force the end's static load) and "
                        "advise relative to that bike (the default); --no-calibrate: the bike file's springs as "
                        "they are")
    p.add_argument("--static-sag-mm", metavar="FORK,SHOCK",
                   help="the static sag measured standing on level ground in the riding position, mm: the fork's "
                        "stroke and the shock's (the O-rings); the springs are calibrated on it, and the ride then "
                        "says what load it carried fore-aft (the travel alone cannot tell a soft fork from a "
                        "descent)")
    p.add_argument("--carried-as", choices=("rider", "descent"), default=None,
                   help="with --static-sag-mm: how every run carries the load the ride carried fore-aft: rider (the "
                        "rider moved to where it was carried, the default) or descent (the reconstructed terrain laid "
                        "on the mean descent that carries it, the rider in place)")
    p.add_argument("--workers", type=int, default=2, metavar="N",
                   help="processes the candidate runs spread over (default 2)")
    add_given_speed(p, many=True)  # the reconstruction's speed given, per ride
    add_sensor_spans(p)
    add_out(p, "out/advise")
    p.set_defaults(func=cmd_advise)

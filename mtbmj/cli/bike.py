"""``mtbmj bike PRESET TERRAIN --speed V --out DIR``: a whole bike (fork, shock through its
leverage curve, a rider, two tires) rolled over a terrain of ``mtbmj roll``'s library, written
atomically. Bad bike descriptions (a leverage table that is not positive or not increasing, a pivot
inside a wheel, a shock stroke shorter than the curve needs, negative masses, a head angle outside
45-90 degrees) raise ConfigError: one line naming the key, exit status 2, nothing written. A run
that ends in a crash (a part other than a tyre on the ground, or the pitch past what a rider
recovers from) is written up to the crash, its headline starting "crashed: ...", exit status 3."""
from __future__ import annotations

from mtbmj.cli.common import Progress, Typed, add_out

# A run that ended in a crash (``mtbmj.bike.crash``): its folder is written, up to the crash
EXIT_CRASHED = 3


def cmd_bike(args) -> int:
    from mtbmj.bike.run import run_bike

    lock = lock_option(args.lock)
    overrides = bike_overrides(args)
    if args.ride is not None:  # a bad ride file, or another bike's ride: one line before any work
        ride_checked(args, overrides)
    if args.video:
        from mtbmj.rolling.render import gl_backend

        gl_backend()  # no headless OpenGL: one line before any work
    profile = None
    if args.speed_profile is not None:  # a bad file: one line before any work
        from mtbmj.bike.schedule import read_csv

        from mtbmj.rolling import terrain as terrain_mod

        ter = terrain_mod.make(args.scenario)  # the profile along it: a bad scenario is said here as after
        profile = read_csv(args.speed_profile).along(ter.start_x, ter.start_x + ter.length,
                                                     f"--speed-profile: {args.speed_profile}")
        if args.speed is None:  # the start's: the profile's first
            args.speed = float(profile.v[0])
    if args.rider == "active" and (args.lock or args.lift_rear):  # the options set, not run_bike's lock=/rear_tire=
        from mtbmj.errors import ConfigError

        raise ConfigError(f"{'--lock' if args.lock else '--lift-rear'}: the active rider rides the whole bike (no "
                          f"--lock, no --lift-rear; --rider passive holds parts)")
    why = ("--pedal: a pedalling rider's speed is its own" if args.pedal is not None
           else "--drive coast: a coasting bike has no drive to hold it" if args.drive == "coast" else None)
    if args.speed_profile is not None and why is not None:  # the options set, not run_bike's speed_profile=
        from mtbmj.errors import ConfigError

        raise ConfigError(f"--speed-profile with {why} (the rider's drive, passive or active, holds the profile)")
    pedal = pedal_option(args)
    if args.legs_swing and (pedal is None or args.rider != "active"):
        from mtbmj.errors import ConfigError

        raise ConfigError("--legs-swing: the legs swing only for a pedalling active rider (--pedal RPM --rider active)")
    result = Progress(f"bike {args.bike} over {args.scenario}", not args.quiet).around(
        lambda progress: run_bike(args.bike, args.scenario, args.speed, args.duration, args.drive, args.start_m,
                                  progress, lock=lock,
                                  rear_tire=not args.lift_rear, overrides=overrides, seated=args.seated, rider=args.rider,
                                  pedal=pedal, legs_swing=args.legs_swing,
                                  speed_profile=None if profile is None else (profile.x, profile.v)))
    extra = None
    if args.ride is not None:  # beside a real ride
        from mtbmj.ride import beside

        extra = beside.files(result, args.ride)
    written = result.write(args.out, figure=not args.no_figure, video=args.video, extra=extra)
    print(f"{result.headline()}; {result.info['real_time_factor']:.2f}x real time; wrote {len(written)} files to "
          f"{args.out}")
    return EXIT_CRASHED if result.summary.get("crash") else 0


def lock_option(text) -> tuple[str, ...]:
    """The parts ``--lock`` names (``Rear,pitch,``: rear and pitch), or one line naming ``--lock``: a list left empty
    (``--lock ''`` ran with nothing locked), a part that is none of ``LOCKS`` (the line said "lock: ...")."""
    from mtbmj.bike.model import LOCKS
    from mtbmj.cli.common import comma_words
    from mtbmj.errors import ConfigError

    if text is None:
        return ()
    parts = comma_words(text)
    if not parts:
        raise ConfigError(f"--lock {text!r}: names no part; give {', '.join(LOCKS)}, comma-separated, or leave "
                          f"--lock out to lock none")
    bad = [part for part in parts if part not in LOCKS]
    if bad:
        raise ConfigError(f"--lock: {bad[0]!r} is not one of {', '.join(LOCKS)}")
    return tuple(parts)


def ride_checked(args, overrides) -> None:
    """``--ride`` read as ``telemetry``, ``advise`` and ``bob`` read it, through the bike that runs (its
    overrides too): the same warnings (a version-2 record's approximate amplitudes, its travel past the
    bike's within that uncertainty, a short ride), and the same refusal of a ride that travels past the
    bike's travel. Refused, not warned: the ride's histogram is drawn in % of this bike's travel, which
    it passes, so the comparison would be false; another bike's ride is compared by reading it as its
    own (``mtbmj telemetry RIDE --bike RECORDED --compare RUN_DIR``)."""
    import argparse

    from mtbmj.cli.telemetry import ride_record
    from mtbmj.measured.telemetry import TelemetryError, read_sst, ride_path

    if str(args.ride).lower().endswith(".csv"):  # telemetry reads a travel CSV; the comparison beside a run does not
        raise TelemetryError(f"--ride {args.ride}: a travel CSV; --ride reads an SST recording. Compare a CSV ride "
                             f"with a run's folder: mtbmj telemetry {args.ride} --bike BIKE --compare RUN_DIR")
    read_sst(ride_path(args.ride))  # an SST recording (beside.files reads one): else one line, no run
    as_read = argparse.Namespace(bike=args.bike, fork_max_mm=None, shock_max_mm=None)
    try:
        ride_record(args.ride, as_read, None, overrides or None, named=f"bike {args.bike}")
    except TelemetryError as error:
        if "a ride of another bike" not in str(error):
            raise
        raise TelemetryError(f"--ride {args.ride}: {error}; or run this bike without --ride and compare its "
                             f"folder with the ride read as its own: mtbmj telemetry {args.ride} --bike RECORDED "
                             f"--compare RUN_DIR") from None


def pedal_option(args):
    """(cadence_rpm, power_W) from ``--pedal`` and ``--power``, or None; ``--speed`` is needed
    without ``--pedal`` (with it, it is the start speed, by default the gear's at the cadence)."""
    from mtbmj.errors import ConfigError

    if args.pedal is None:
        if args.power is not None:
            raise ConfigError("--power: is the pedalling rider's power; give the cadence with --pedal RPM")
        if args.speed is None:
            raise ConfigError("--speed: give the speed in m/s (or --pedal RPM: the rider pedals, at the gear's speed)")
        return None
    if args.drive != "rider":
        raise ConfigError(f"--pedal: the pedalling rider is the drive; --drive {args.drive} cannot go with it")
    if getattr(args, "ride", None) is not None and args.duration is not None and args.duration < 8.0:
        raise ConfigError(f"--duration: {args.duration:g} s is too short to read the pedal bob beside --ride (8 s at "
                          f"least: the bob is read over the run's second half)")
    # the cadence and the power were held to the model's range by the numeric gate (mtbmj.limits.ARGUMENTS)
    return (args.pedal, PEDAL_POWER_DEFAULT_W if args.power is None else args.power)


# a trail rider's steady climbing power (assumed: a round value for a fit amateur over minutes)
PEDAL_POWER_DEFAULT_W = 250.0


def add_pedal(p) -> None:
    p.add_argument("--pedal", type=float, metavar="RPM",
                   help="the rider pedals at this cadence instead of holding a speed: the crank's torque (each leg "
                        "on its downstroke) pulls the chain (needs drive.chainring_teeth and drive.cog_teeth) and "
                        "the feet push the pedals; the start speed is the gear's at RPM unless --speed gives it")
    p.add_argument("--power", type=float, metavar="W",
                   help=f"--pedal: the rider's power in W (default {PEDAL_POWER_DEFAULT_W:g}), held as the crank "
                        f"speeds up or slows")


def bike_overrides(args) -> dict:
    """The bike's overrides from ``--set`` (bike keys), ``--fork-set`` and ``--shock-set`` (keys of
    the fork's and the shock's configurations)."""
    from mtbmj.cli.common import parse_assignment

    out: dict = {}
    for text in args.set or ():
        key, value = parse_assignment(text)
        out[key] = value
    for option, section in (("fork_set", "fork.set"), ("shock_set", "shock.set")):
        for text in getattr(args, option) or ():
            key, value = parse_assignment(text, f"--{option.replace('_', '-')}")
            out.setdefault(section, Typed())[key] = value  # a person's keys: each must be read (compose)
    return out


def add_bike_sets(p) -> None:
    p.add_argument("--set", action="append", metavar="SECTION.KEY=VALUE",
                   help="change a key of the bike file (repeatable), e.g. rider.mass_kg=78 (docs/configuration.md, "
                        "'Bike files')")
    p.add_argument("--fork-set", action="append", metavar="KEY=VALUE", dest="fork_set",
                   help="change a key of the fork's configuration (repeatable), e.g. fork.spring.air_pressure_psi=60")
    p.add_argument("--shock-set", action="append", metavar="KEY=VALUE", dest="shock_set",
                   help="change a key of the shock's configuration (repeatable), e.g. fork.spring.rate_N_per_mm=90")


def add_parser(subparsers) -> None:
    from mtbmj.rolling.terrain import names

    p = subparsers.add_parser("bike", help="roll a whole bike (fork, shock, rider, two tires) over terrain")
    p.add_argument("bike", help="bike preset (sst, trail) or a bike TOML file (see docs/bike.md)")
    p.add_argument("scenario", help=f"terrain: {', '.join(n for n in names() if n != 'drum')} (optionally "
                                    "name:key=value,...) or a CSV profile (distance_m, height_mm)")
    p.add_argument("--speed", type=float, help="speed in m/s (> 0); with --pedal or --speed-profile the start speed")
    p.add_argument("--speed-profile", metavar="CSV", dest="speed_profile",
                   help="the speed held along the terrain: a CSV of distance_m (the terrain's x) and speed_m_per_s "
                        "(mtbmj reconstruct writes speed.csv beside terrain.csv)")
    p.add_argument("--drive", choices=("rider", "coast"), default="rider",
                   help="rider (default): a speed controller at the rear wheel within a rider's push, power and "
                        "braking and the rear tire's traction; coast: no drive")
    p.add_argument("--duration", type=float, help="simulated time in s (default: both wheels across the terrain and 0.5 s to settle)")
    p.add_argument("--start-m", type=float, dest="start_m",
                   help="where the front axle starts along the terrain, m (default the terrain's start)")
    p.add_argument("--lock", metavar="PARTS",
                   help="hold degrees of freedom at their static values, comma-separated: rear (the shock locked "
                        "out at its sag), pitch (the frame level at its static pitch), rider (the rider rigid on "
                        "the frame)")
    p.add_argument("--lift-rear", action="store_true", dest="lift_rear",
                   help="take the rear tire off: the bike on its front wheel alone (needs --lock pitch; with "
                        "--lock rear,pitch,rider it is the rolling front end's rig)")
    p.add_argument("--rider", choices=("passive", "active"), default="passive",
                   help="passive (default): the rider a rigid body on spring-damper legs and arms; active: an "
                        "articulated rider (de Leva's segments, hip, knee, ankle, shoulder and elbow torques within "
                        "human strength) that rides: attack position, hips back ahead of a drop, legs and arms "
                        "taking the landing (docs/bike.md)")
    p.add_argument("--seated", action="store_true",
                   help="the rider seated on the saddle, held rigid on the frame (rider.seated_com_mm)")
    add_pedal(p)
    p.add_argument("--legs-swing", action="store_true", dest="legs_swing",
                   help="--pedal --rider active: the two legs' thighs and shanks swing on their own pedals about the "
                        "lumped leg, their inertia and weight on the trunk at the hips (off by default: on, the bob "
                        "no longer matches the shared pedalling records; docs/bike.md)")
    add_bike_sets(p)
    add_out(p, "out/bike")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--no-figure", action="store_true", help="do not draw quicklook.png")
    p.add_argument("--ride", metavar="SST",
                   help="also write ride_comparison.png/.json: both ends' travel histograms beside a real Sufni SST "
                        "ride (a .SST file, or 'example' for the shipped ride of the SST bike); with --pedal also "
                        "bob.png/.json: both ends' pedal bob (frequency, peak to peak) beside the ride's")
    p.add_argument("--video", action="store_true",
                   help="also write bike.gif: the run side on at 30 frames/s (headless EGL or OSMesa)")
    p.set_defaults(func=cmd_bike)


__all__ = ["add_parser", "add_pedal", "cmd_bike", "pedal_option", "ride_checked"]

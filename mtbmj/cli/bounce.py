"""``mtbmj fit bounce REC... --clicks 0,8,17 [--predict-clicks 4,12] --out DIR``: damping ratio and
natural frequency of each end from a rider's own seat slams (SST recordings), the damping per
rebound click as a law, and the ring-down it predicts at other clicks (``mtbmj.identify.bounce_fit``:
this module parses, calls it and prints what it found).

Writes fit.json, fit.png and, per predicted click, ringdown_<K>_clicks.csv (with --replay also
replay_<file>.csv per record, replay.png, slam_rebound.png and rebound.png), atomically. The ``fit``
command's parser takes it with ``add_bounce_parser(p)`` (``p``: the ``fit`` parser): the kind
``bounce`` is then parsed by this module's own parser.
"""
from __future__ import annotations

import math
from pathlib import Path


from mtbmj.cli.common import add_out
from mtbmj.errors import MtbmjError

DESCRIPTION = ("Fit each end's ring-down after a seat slam in SST recordings (v2 or v3): the damping ratio and the "
               "damped natural frequency with 95 % intervals, from a damped sinusoid fitted about the rest level "
               "(independent of the amplitude calibration). With records at two or more rebound clicks, the damping "
               "ratio as a law linear in clicks, and with --predict-clicks the damping ratio, frequency and ring-down "
               "it predicts at other clicks. With a decay law across clicks (friction common), each predicted click's ring-down from "
               "the nearest record's own state, with its first half cycle's decay, frequency and rebound speed, and an "
               "answer in clicks: the setting for one overshoot after a hit (--hit-mm). Writes fit.json, fit.png and "
               "ringdown_<K>_clicks.csv per predicted click.")


def _numbers(text: str, option: str) -> list[float]:
    items = [s.strip() for s in str(text).split(",")]
    try:
        values = [float(s) for s in items]
    except ValueError:
        raise MtbmjError(f"{option} {text}: expected comma-separated numbers of clicks") from None
    if not values or not all(math.isfinite(v) and v >= 0 for v in values):
        raise MtbmjError(f"{option} {text}: clicks must be finite and not negative")
    part = next((v for v in values if v != round(v)), None)
    if part is not None:  # a damper is set at its detents: a slam was ridden at one, an answer is one
        raise MtbmjError(f"{option} {text}: {part:g} is not a whole click (a damper is set at its detents, whole clicks)")
    return values


def bounce_parser(prog: str = "mtbmj fit bounce"):
    from mtbmj.cli.common import Parser

    p = Parser(prog=prog, description=DESCRIPTION)
    p.add_argument("records", nargs="+", type=Path, metavar="REC", help="SST recordings, one seat slam each")
    p.add_argument("--clicks", required=True, metavar="K1,K2,...",
                   help="rebound clicks of each record, in the order of the records, e.g. 0,8,17")
    p.add_argument("--predict-clicks", metavar="K1,K2,...",
                   help="clicks to predict the damping ratio, frequency and ring-down at, from the law")
    p.add_argument("--bike", metavar="BIKE",
                   help="read each ring-down through this bike (a preset or a bike file with rider.seated_com_mm): "
                        "the spring rate and the damper's coefficient of the end that rang, at the end and at the wheel")
    p.add_argument("--hit-mm", type=float, metavar="MM",
                   help="the hit the answer in clicks is for: its compression above the static position (mm; "
                        "default: the records' own, the median of their first free excursions)")
    p.add_argument("--rider-hz", type=float, metavar="HZ",
                   help="with --bike: the seated rider compliant on the saddle, ringing at HZ with the frame held "
                        "(a seated body: 4-6 Hz; default: held rigid), and the rider's share of each mode stated")
    p.add_argument("--replay", action="store_true",
                   help="with --bike: replay each slam through the MuJoCo bike with the seated rider compliant "
                        "(--rider-hz, default 5 Hz), pushed as the slam pushed, and fit the shock's spring scale, "
                        "damper and friction to the record, and the slams with their first rebounds together for a "
                        "rebound coefficient per record (replay_<file>.csv, replay.png, slam_rebound.png; two to four "
                        "minutes per record)")
    p.add_argument("--rebound-target-per-s", type=float, metavar="RATE",
                   help="with --replay: the first rebound's rate to aim for (its mean speed from 75 %% to 25 %% of the "
                        "slam's height per mm of that height, 1/s): the answer in clicks from the rebound dampers")
    add_out(p, "out/fit")
    p.set_defaults(func=cmd_fit_bounce, command="fit", kind="bounce")
    return p


def add_bounce_parser(fit_parser) -> None:
    """Let the ``fit`` parser take ``fit bounce ...``: its kind choices gain ``bounce`` (for its help)
    and a command line whose first word is ``bounce`` is parsed by :func:`bounce_parser`."""
    for action in fit_parser._actions:
        if action.dest == "kind" and action.choices is not None and "bounce" not in action.choices:
            action.choices = tuple(action.choices) + ("bounce",)
    own = bounce_parser()
    parse = fit_parser.parse_known_args

    def parse_known_args(args=None, namespace=None):
        words = list(args or [])
        if words and words[0] == "bounce":
            return own.parse_known_args(words[1:], namespace)
        return parse(args, namespace)

    fit_parser.parse_known_args = parse_known_args


def cmd_fit_bounce(args) -> int:
    from mtbmj.identify.bounce_fit import fit_bounce
    from mtbmj.measured.telemetry import example_path, ride_path

    shipped = next((r for r in args.records if ride_path(r) == example_path()), None)
    if shipped is not None:  # fit's other kinds take 'example' (their shipped records); bounce has none
        raise MtbmjError(f"{shipped}: fit bounce has no shipped example (the shipped ride, 00649.SST, is a trail "
                         f"ride, no seat slam); give SST recordings of seat slams, one each")
    clicks = _numbers(args.clicks, "--clicks")
    predict = _numbers(args.predict_clicks, "--predict-clicks") if args.predict_clicks else []
    twice = sorted({k for k in predict if predict.count(k) > 1})
    if twice:  # one prediction twice: two entries in fit.json, one ringdown CSV written over the other
        raise MtbmjError(f"--predict-clicks {args.predict_clicks}: {twice[0]:g} clicks given twice; give each once")
    if args.hit_mm is not None and not (math.isfinite(args.hit_mm) and args.hit_mm > 0):
        raise MtbmjError(f"--hit-mm {args.hit_mm:g}: the hit must be a positive number of millimetres")
    target = args.rebound_target_per_s
    if target is not None and not (math.isfinite(target) and target > 0):
        raise MtbmjError(f"--rebound-target-per-s {target:g}: the target rate must be a positive number (1/s)")
    if target is not None and not args.replay:
        raise MtbmjError("--rebound-target-per-s: the answer from the rebound dampers needs --replay (and --bike)")
    result = fit_bounce(args.records, clicks, predict, bike=args.bike, hit_mm=args.hit_mm, rider_hz=args.rider_hz,
                        replay=args.replay, rebound_target_per_s=target)
    if args.hit_mm is not None and not result.answers:  # else it would change nothing, silently (a past-stroke hit too)
        raise MtbmjError(f"--hit-mm {args.hit_mm:g}: the hit of the answer in clicks, which needs a decay law across "
                         f"two or more different --clicks; these records give none (leave --hit-mm out)")
    written = result.write(args.out)
    for line in result.lines():
        print(line)
    print(f"wrote {', '.join(p.name for p in written)} to {args.out}")
    return 0


__all__ = ["add_bounce_parser", "bounce_parser", "cmd_fit_bounce"]

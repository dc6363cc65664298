"""``mtbmj compare RUN RUN... --out DIR``: result folders of ``mtbmj drop`` (or of ``mtbmj roll``, or of
``mtbmj bike``) overlaid on shared axes, and a table of their summaries' differences."""
from __future__ import annotations

from pathlib import Path

from mtbmj.cli.common import add_out, write_and_say


def cmd_compare(args) -> int:
    from mtbmj.readout.compare import compare_runs

    comparison = compare_runs(args.runs)
    return write_and_say(comparison, args.out)


def add_parser(sub) -> None:
    p = sub.add_parser("compare", help="overlay drop, roll or bike result folders and tabulate their differences",
                       description="Overlay two or more result folders of mtbmj drop, of mtbmj roll or of mtbmj bike "
                                   "(not a mix: a drop's time zero is the tire's touch, a roll's and a bike's the start "
                                   "over the terrain): fork travel, tire deflection, fork and tire force against time "
                                   "(a bike's: front and rear wheel travel, pitch and both tyre loads), one colour per "
                                   "run named by its folder (compare.png); differences.csv holds one row per summary "
                                   "figure, one column per run and one per run's difference from the first.")
    p.add_argument("runs", nargs="+", metavar="RUN", type=Path,
                   help="result folder written by mtbmj drop, mtbmj roll or mtbmj bike --out")
    add_out(p, "out/compare")
    p.set_defaults(func=cmd_compare)

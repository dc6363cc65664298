"""``mtbmj validate``: configurations against a sled record (or the ODE reference), the paper's
Fig. 10 and a self-contained HTML report.
"""
from __future__ import annotations

import re
import sys
import time
from pathlib import Path

from mtbmj.cli.common import ENGINE_HELP, ENGINE_NAMES, add_out, intermixed  # noqa: F401
from mtbmj.cli.common import parse_assignment
from mtbmj.config import study_presets
from mtbmj.errors import ConfigError

_RANGE = re.compile(r"^([A-Za-z_]*)(\d+)\.\.([A-Za-z_]*)(\d+)$")


def parse_presets(text: str) -> list[str]:
    """``S1,S2`` / ``S1..S14`` / ``S1..S7,S12`` -> preset names (unknown names fail when loaded)."""
    names: list[str] = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        match = _RANGE.match(part)
        if match:
            a, i, b, j = match.group(1), int(match.group(2)), match.group(3) or match.group(1), int(match.group(4))
            if a != b or j < i:
                raise ConfigError(f"--presets: {part!r} is not a range like S1..S14")
            if j - i >= 1000:
                raise ConfigError(f"--presets: {part!r} names {j - i + 1} presets; a range names at most 1000")
            names += [f"{a}{k}" for k in range(i, j + 1)]
        else:
            names.append(part)
    if not names:
        raise ConfigError(f"--presets: no preset names in {text!r}")
    return list(dict.fromkeys(names))


def add_parser(subparsers):
    """Add the ``validate`` sub-command to an argparse sub-parser collection."""
    p = subparsers.add_parser(
        "validate", help="compare configurations with a sled record (or the ODE reference): Fig. 10 and an HTML report",
        description="Run configurations and compare them with a drop-sled record (time_s, sled_mm, fork_mm, "
                    "or the three displacements): amplitude and timing errors at Peak 1, topping, Peak 2, "
                    "Valley 1, Peak 3 and rest, RMS errors; writes the paper's Fig. 10, overlays, a CSV, a JSON "
                    "summary and one self-contained HTML report. Default configurations: S1..S14.")
    p.add_argument("data", help="sled record: CSV (units in the column names) or .mat, or 'example' for the "
                                "shipped synthetic record; with --reference ode it only sets the default duration")
    p.add_argument("configs", nargs="*", metavar="CONFIG", help="preset names or TOML files")
    p.add_argument("--presets", help="presets, e.g. S1,S12 or S1..S14 (added to CONFIG)")
    p.add_argument("--reference", choices=("ode",),
                   help="use the ODE run of each configuration as the measurement (engine vs reference)")
    p.add_argument("--engine", choices=ENGINE_NAMES, default="mujoco", help="engine under test (default mujoco)")
    add_out(p, "out/validate")
    p.add_argument("--sled-offset-mm", type=float, default=0.0,
                   help="sled reading at tread touch, subtracted (default 0: already zeroed)")
    p.add_argument("--fork-offset-mm", type=float, default=0.0,
                   help="fork reading at unloaded full extension, subtracted (default 0)")
    p.add_argument("--touch-s", type=float, metavar="SECONDS",
                   help="time zero (tire touch) on the record's clock; default: found from the record "
                        "(free fall then impact, or a record that starts at impact)")
    p.add_argument("--workers", type=int, help="processes (default: one per core)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a key in every configuration")
    p.add_argument("--duration", type=float, help="simulated time after touch in s (default: the record's)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_validate)
    return intermixed(p)


def cmd_validate(args) -> int:
    from mtbmj.validation.report import run_validation
    from mtbmj.measured.sled import example_path

    start = time.perf_counter()
    presets = parse_presets(args.presets) if args.presets is not None else []  # "" is a list left empty
    configs = presets + list(args.configs or [])
    twice = next((c for i, c in enumerate(configs) if c in configs[:i]), None)
    if twice is not None:  # it ran twice (as S12 and S12-2), unsaid, as compare refuses a run given twice
        where = "in --presets and as CONFIG" if twice in presets else "as CONFIG"
        raise ConfigError(f"{twice}: given twice ({where}); give each configuration once")
    if not configs:
        configs = study_presets()
    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers: must be at least 1, got {args.workers}")
    overrides = dict(parse_assignment(a) for a in args.set or [])
    quiet = getattr(args, "quiet", False) or not sys.stderr.isatty()
    log = None if quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    data = args.data
    if data == "example" and not Path(data).exists():
        data = example_path()
    validation = run_validation(data, configs, reference_engine=args.reference, engine=args.engine,
                                duration=args.duration, overrides=overrides, workers=args.workers,
                                sled_offset_mm=args.sled_offset_mm, fork_offset_mm=args.fork_offset_mm,
                                touch_s=args.touch_s, progress=log)
    written = validation.write(args.out)
    worst = [(n, validation.metrics[n].worst_amplitude()) for n in validation.configs]
    worst = [(n, w) for n, w in worst if w is not None]
    detail = ""
    if worst:
        name, (signal, event, value) = max(worst, key=lambda p: abs(p[1][2]))
        detail = f"; largest amplitude error {value:+.2f} mm ({name}, {signal} {event})"
    count = len(validation.configs)
    if validation.record is not None and validation.record.touch is not None and not args.reference:
        print(f"{validation.record.name}: {validation.record.touch.describe()}")
    envelope = "".join(f"; {phrase}" for phrase in validation.envelope_lines())
    print(f"validate: {count} configuration{'s' if count != 1 else ''} on {args.engine} against "
          f"{validation.measurement} in {time.perf_counter() - start:.1f} s{detail}{envelope}; "
          f"wrote {len(written)} files to {args.out} (report: {args.out / 'validation_report.html'})")
    return 0

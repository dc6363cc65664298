"""``mtbmj synth spring|damper``: a synthetic shock-dyno record generated from a configuration's own
laws (marked synthetic in its first comment line), to try ``mtbmj fit`` on a known truth."""
from __future__ import annotations

import contextlib
import os
import secrets

from mtbmj.cli.common import out_path, overrides
from mtbmj.errors import MtbmjError
from mtbmj.output import check_file_target
from mtbmj.output.filesystem import missing_ancestors


def cmd_synth(args) -> int:
    from mtbmj.drop.chain import resolve
    from mtbmj.identify import dyno_synthetic as synth

    if args.out.suffix.lower() not in (".csv", ".mat"):
        raise MtbmjError(f"--out {args.out}: the record file must end in .csv or .mat")
    if args.seed < 0:
        raise MtbmjError(f"--seed: must be 0 or more, got {args.seed}")
    if args.out.exists():
        raise MtbmjError(f"--out {args.out}: file exists; not overwriting it")
    check_file_target(args.out)  # a folder in its place, a name too long, no permission: before the work
    config = resolve(args.config, overrides(args.set))
    truth = synth.config_truth(config, args.kind)
    if args.kind == "spring":
        record = synth.spring_record(truth, seed=args.seed)
    else:
        record = synth.damper_record(truth, seed=args.seed)
    made = missing_ancestors(args.out.parent)
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        # staged under a short name of its own beside it (the user's name plus a suffix could pass the file system's
        # limit that the name itself keeps), then renamed: the record appears whole or not at all
        staged = args.out.with_name(f".synth-{secrets.token_hex(4)}.partial{args.out.suffix}")
        try:
            synth.write_record(staged, record)
            os.replace(staged, args.out)
        finally:
            with contextlib.suppress(OSError):
                os.unlink(staged)
    except OSError as exc:
        for folder in made:  # nothing half-written: the folders made for it go (the deepest first), if empty
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise MtbmjError(f"--out {args.out}: cannot write the record ({exc.strerror})") from None
    print(f"wrote a synthetic {args.kind} dyno record of {config.name} to {args.out}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("synth", help="write a synthetic dyno record (spring stroke or damper test) of a configuration")
    p.add_argument("kind", choices=("spring", "damper"))
    p.add_argument("config", help="preset name (air120, S12, ...) or a TOML file: the true fork")
    p.add_argument("--out", type=out_path, required=True, help="record file to write (.csv or .mat)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a configuration key of the truth, e.g. fork.spring.air_pressure_psi=90 (repeatable)")
    p.set_defaults(func=cmd_synth)

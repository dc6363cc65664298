"""The test suite's wall time on this machine: the README's two test commands, the suite (``-m "not
slow"``) and the long physics checks (``-m slow``), each on two processes, one after the other.

    python benchmarks/suite_time.py [--out PATH]

Each command runs from the repository root in a fresh process; its wall time, exit status and the
pytest summary line are recorded, beside the machine's load average before and after. The suite's
target is at most 12 minutes on two processes (issue 50). Writes its results where ``--out`` says
(default ``<tempdir>/mtbmj-benchmarks/suite_time.json``, outside the repository). Not a test:
nothing is asserted.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench import add_out_option, load_average, write_json  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
COMMANDS = {"suite": ["-m", "not slow"], "slow": ["-m", "slow"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(COMMANDS), help="time one of the two commands only")
    add_out_option(ap, __file__)
    args = ap.parse_args(argv)
    runs = {}
    for name, marks in COMMANDS.items():
        if args.only and name != args.only:
            continue
        command = [sys.executable, "-m", "pytest", "-q", "-n", "2", "--dist", "loadfile", "--no-loadscope-reorder", *marks, "-p", "no:cacheprovider"]
        before = load_average()
        start = time.perf_counter()
        done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
        wall = time.perf_counter() - start
        lines = [ln for ln in done.stdout.splitlines() if ln.strip()]
        runs[name] = {"command": " ".join(["python", "-m", "pytest", "-q", "-n", "2", "--dist", "loadfile", "--no-loadscope-reorder",
                                           marks[0], repr(marks[1]) if " " in marks[1] else marks[1]]),
                      "wall_s": wall, "exit": done.returncode, "summary": lines[-1] if lines else "",
                      "load_before": before, "load_after": load_average()}
        print(f"{name}: {wall / 60:.1f} min, exit {done.returncode}: {runs[name]['summary']}", flush=True)
    path = write_json(__file__, {"runs": runs, "target_suite_minutes": 12.0,
                                 "command": "python benchmarks/suite_time.py" + (f" --only {args.only}" if args.only else "")},
                      args.out)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

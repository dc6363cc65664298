"""Generated input for ``mtbmj render`` (issue 37: the fuzz tests cover render): run folders that
are not what mtbmj wrote (missing, empty, broken or edited files, special files, huge numbers,
names with mathtext characters) and output targets a user already has (their file, a folder, a
link). The invariant: exit 0, or exit 2 with one line on stderr and no traceback; a file of the
user's at the target is never touched, and nothing is left beside it."""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mtbmj.cli import main

RUNS = 160
COUNT = {"cases": 0}

MANIFESTS = st.one_of(
    st.just(None),  # no manifest.json
    st.just("not json {"),
    st.just("[1, 2, 3]"),
    st.just(json.dumps({"name": "S12"})),  # no versions
    st.fixed_dictionaries({"versions": st.just({"mtbmj": "0"}), "scenario": st.sampled_from(["root", "x:y=1", "$\\frac{a$"]),
                           "name": st.sampled_from(["S12", "trail", "nope"])}).map(json.dumps),
    st.fixed_dictionaries({"versions": st.just({"mtbmj": "0"}), "bike_source": st.sampled_from(["trail", "sst", "gone.toml"]),
                           "scenario": st.just("root"), "bike_overrides": st.sampled_from([None, {"rider.mass_kg": 1e300}]),
                           "engine_info": st.just({})}).map(json.dumps),
)
SUMMARIES = st.one_of(st.just(None), st.just("{"), st.fixed_dictionaries({
    "duration_s": st.sampled_from([0.4, 60.0, 1e300, -1.0, float("nan")]),
    "speed_m_per_s": st.sampled_from([4.0, 0.0, -3.0, 1e9]),
    "drive": st.just({"mode": "rider"})}).map(lambda d: json.dumps(d, allow_nan=True)))
SERIES = st.one_of(st.just(None), st.just(""), st.just("time_s,front_travel_mm\n0,0\n0.0005,0.1\n"),
                   st.just("time_s,fork_mm\n0,nan\n"), st.just("x\n" + "1\n" * 50))
SPECIAL = st.sampled_from([None, "fifo_manifest", "fifo_summary", "zero_series", "folder_as_manifest"])
TARGETS = st.sampled_from(["new", "user_gif", "user_mp4", "folder", "link_to_user"])
NAMES = st.sampled_from(["run", "r$x$", "a$\\frac{b$", "ü run", "--dash"])


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@settings(max_examples=RUNS, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
@given(manifest=MANIFESTS, summary=SUMMARIES, series=SERIES, special=SPECIAL, target=TARGETS, name=NAMES)
def test_generated_render_inputs(tmp_path_factory, capfd, manifest, summary, series, special, target, name):
    COUNT["cases"] += 1
    case = tmp_path_factory.mktemp("render")
    run = case / name
    run.mkdir()
    for filename, text in (("manifest.json", manifest), ("summary.json", summary), ("timeseries.csv", series)):
        if text is not None:
            (run / filename).write_text(text)
    if special == "fifo_manifest":
        (run / "manifest.json").unlink(missing_ok=True)
        os.mkfifo(run / "manifest.json")
    elif special == "fifo_summary":
        (run / "summary.json").unlink(missing_ok=True)
        os.mkfifo(run / "summary.json")
    elif special == "zero_series":
        (run / "timeseries.csv").unlink(missing_ok=True)
        (run / "timeseries.csv").symlink_to("/dev/zero")
    elif special == "folder_as_manifest":
        (run / "manifest.json").unlink(missing_ok=True)
        (run / "manifest.json").mkdir()
    users = case / "holiday.gif"
    users.write_bytes(b"GIF89a the user's own holiday")
    before = _sha(users)
    out = {"new": case / "new.gif", "user_gif": users, "user_mp4": case / "holiday.mp4", "folder": case / "adir",
           "link_to_user": case / "link.gif"}[target]
    if target == "user_mp4":
        out.write_bytes(b"user's mp4")
    elif target == "folder":
        out.mkdir()
    elif target == "link_to_user":
        out.symlink_to(users)
    listing = sorted(p.name for p in case.iterdir())
    capfd.readouterr()
    status = main(["render", str(run), "--out", str(out), "--width", "64", "--height", "48"])
    err = capfd.readouterr().err
    assert "Traceback" not in err, err
    assert _sha(users) == before  # the user's file, whatever the target
    if target == "user_mp4":
        assert out.read_bytes() == b"user's mp4"
    if status != 0:
        assert status == 2 and err.count("\n") == 1, (status, err)
        assert sorted(p.name for p in case.iterdir()) == listing  # nothing left beside the target


def test_enough_render_cases():
    if COUNT["cases"] == 0:
        pytest.skip("the generated render test did not run in this session")
    assert COUNT["cases"] >= RUNS

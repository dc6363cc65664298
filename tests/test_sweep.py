"""Sweeps: variant generation, the table, the journal (kill -9 and --resume), failing variants,
the Dask backend against the local one, sensitivity indices and the command line's bad input."""
from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mtbmj
from mtbmj import cli
from mtbmj import sweep
from mtbmj.errors import RunError

DURATION = 0.2
RATE = "fork.spring.rate_N_per_mm"
TIRE = "tire.impact_rate_N_per_mm"
GRID = [f"{RATE}=14:18:3", f"{TIRE}=75:95:2"]  # 6 variants


def _grid():
    return sweep.grid([sweep.parse_vary(v) for v in GRID])


def _comparable(table: pd.DataFrame) -> pd.DataFrame:
    """In plan order (the wall times are not in the table: see timings.csv)."""
    return table.sort_values("variant").reset_index(drop=True)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The 6-variant S1 sweep run once, uninterrupted, on the local backend with traces."""
    out = tmp_path_factory.mktemp("reference")
    result = sweep.run_sweep("S1", _grid(), out, duration=DURATION, workers=2, traces=True, csv=True)
    return result, out


# --- variant generation ---------------------------------------------------------------------


def test_grid_is_full_factorial_first_key_slowest():
    variants = _grid()
    assert len(variants) == 6
    assert [v[RATE] for v in variants] == [14.0, 14.0, 16.0, 16.0, 18.0, 18.0]
    assert [v[TIRE] for v in variants] == [75.0, 95.0] * 3
    assert sweep.grid([sweep.parse_vary(f"{RATE}=14:18:2")]) == [{RATE: 14.0}, {RATE: 18.0}]


@pytest.mark.parametrize("method", ["lhs", "sobol"])
def test_samples_count_range_determinism(method):
    ranges = [sweep.parse_vary(f"{RATE}=14:18", count=False), sweep.parse_vary(f"{TIRE}=75:95", count=False)]
    a = sweep.sample(ranges, 16, method, seed=3)
    assert len(a) == 16 and len({tuple(v.values()) for v in a}) == 16
    for v in a:
        assert 14 <= v[RATE] <= 18 and 75 <= v[TIRE] <= 95
    assert a == sweep.sample(ranges, 16, method, seed=3)
    assert a != sweep.sample(ranges, 16, method, seed=4)
    if method == "lhs":  # one point in each of the 16 strata of every dimension
        strata = sorted(int((v[RATE] - 14) / 4 * 16) for v in a)
        assert strata == list(range(16))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**63), n=st.integers(1, 300), lows=st.lists(st.floats(-1e3, 1e3), min_size=1, max_size=6),
       width=st.floats(1e-3, 1e3))
def test_latin_hypercube_is_scipys(seed, n, lows, width):
    """Our Latin hypercube (numpy only: scipy.stats takes 0.4 s to import) gives scipy's points,
    bit for bit, for any seed, size and box: a sweep drawn before it is drawn again the same."""
    from scipy.stats import qmc

    ranges = [sweep.Range(f"k{i}", lo, lo + width) for i, lo in enumerate(lows)]
    ours = sweep.sample(ranges, n, "lhs", seed=seed)
    unit = qmc.LatinHypercube(len(ranges), rng=np.random.default_rng(seed)).random(n)
    theirs = qmc.scale(unit, [r.lo for r in ranges], [r.hi for r in ranges])
    assert [[v[r.key] for r in ranges] for v in ours] == theirs.tolist()


def test_variant_ids_are_stable_and_distinct():
    cfg = mtbmj.load_config("S1")
    a = sweep.variant_id(cfg, {RATE: 16, TIRE: 80.0}, "mujoco", 0.2)
    assert a == sweep.variant_id(cfg, {TIRE: 80, RATE: 16.0}, "mujoco", 0.2)  # order, int/float
    assert a != sweep.variant_id(cfg, {RATE: 16.5, TIRE: 80.0}, "mujoco", 0.2)
    assert a != sweep.variant_id(cfg, {RATE: 16, TIRE: 80.0}, "ode", 0.2)
    assert a != sweep.variant_id(cfg, {RATE: 16, TIRE: 80.0}, "mujoco", 0.3)
    assert a != sweep.variant_id(mtbmj.load_config("S2"), {RATE: 16, TIRE: 80.0}, "mujoco", 0.2)


def test_from_csv(tmp_path):
    path = tmp_path / "v.csv"
    path.write_text(f"# three variants\n{RATE};fork.spring.model;{TIRE}\n15;linear;80\n16;;\n17;progressive;90\n")
    variants = sweep.from_csv(path)
    assert variants == [{RATE: 15, "fork.spring.model": "linear", TIRE: 80},
                        {RATE: 16},
                        {RATE: 17, "fork.spring.model": "progressive", TIRE: 90}]


# --- a small sweep ------------------------------------------------------------------------------


def test_small_sweep_writes_table(reference):
    result, out = reference
    assert result.total == 6 and result.computed == 6 and result.failed == 0
    table = pd.read_parquet(out / "sweep.parquet")
    assert len(table) == 6 and table["variant_id"].is_unique
    assert list(table["variant"]) == list(range(6))
    assert (table["status"] == "ok").all()
    grid = _grid()
    assert table[RATE].tolist() == [v[RATE] for v in grid]
    assert table[TIRE].tolist() == [v[TIRE] for v in grid]
    for column in ("fork_peak1_mm", "sled_peak1_mm", "tire_peak1_mm", "lift_off_s", "rest_fork_mm",
                   "energy_dissipated_J", "status", "reason"):
        assert column in table.columns
    # a stiffer fork spring compresses less
    assert table.groupby(RATE)["fork_peak1_mm"].mean().is_monotonic_decreasing
    # the row of a variant is that variant's drop, made the way a sweep's worker makes it (with the
    # compiled laws and the compiled logger filter, which the workers load up front: the numpy
    # filter rounds the logged signals differently, by about 1e-14 mm)
    from mtbmj.controllers import native

    native.expect_many()
    direct = mtbmj.run_drop("S1", overrides=grid[3], duration=DURATION)
    row = table.iloc[3]
    assert row["fork_peak1_mm"] == direct.summary["events"]["fork"]["peak1"]["value_mm"]
    assert row["tire_peak1_mm"] == direct.summary["events"]["tire"]["peak1"]["value_mm"]
    assert row["energy_dissipated_J"] == direct.summary["energy"]["dissipated_J"]
    csv = pd.read_csv(out / "sweep.csv")
    assert np.allclose(csv["fork_peak1_mm"], table["fork_peak1_mm"])
    manifest = json.loads((out / "sweep.json").read_text())
    assert manifest["variants"] == 6 and manifest["config_sha256"] == mtbmj.load_config("S1").digest()
    # traces: [variant, time] per signal, equal to the drop's logged signals
    import h5py

    with h5py.File(out / "traces.h5") as h5:
        assert h5["fork_mm"].shape == (6, len(direct.time)) and h5["fork_mm"].compression == "gzip"
        assert np.array_equal(h5["time_s"][:], direct.time)
        for name in ("sled_mm", "fork_mm", "tire_mm"):
            assert np.array_equal(h5[name][3], direct.signals[name])
        assert [x.decode() for x in h5["variant_id"][:]] == table["variant_id"].tolist()


def test_journal_guards_against_reuse_and_resume_reuses(reference, tmp_path):
    import shutil

    out = tmp_path / "copy"
    shutil.copytree(reference[1], out)
    with pytest.raises(mtbmj.MtbmjError, match="--resume"):
        sweep.run_sweep("S1", _grid(), out, duration=DURATION, workers=2)
    again = sweep.run_sweep("S1", _grid()[:4], out, duration=DURATION, workers=2, resume=True)
    assert again.computed == 0 and again.reused == 4 and len(again.table) == 4


def _fails_on_soft_spring(config, engine="mujoco", overrides=None, duration=None):
    """A per-variant run that diverges for one variant (picklable: module level)."""
    if overrides.get(RATE) == 14.0:
        raise RunError("run diverged at t = 0.0123 s: state is not finite")
    return mtbmj.run_drop(config, engine, overrides, duration)


def test_failing_variants_are_recorded_and_the_sweep_goes_on(tmp_path):
    path = tmp_path / "v.csv"
    path.write_text(f"{RATE},sled.body_mass_kg,solver.timestep_s\n16,,\n16,-1,\n16,,0.01\n14,,\n")
    result = sweep.run_sweep("S1", sweep.from_csv(path), tmp_path / "out", duration=DURATION, workers=2,
                             drop=_fails_on_soft_spring)
    table = result.table
    assert list(table["status"]) == ["ok", "failed", "failed", "failed"] and result.failed == 3
    assert "sled.body_mass_kg: must be positive" in table["reason"][1]
    assert "solver.timestep_s" in table["reason"][2]
    assert "diverged" in table["reason"][3]
    assert np.isnan(table["fork_peak1_mm"][1]) and table["fork_peak1_mm"][0] > 0
    # failures are journaled too: a resume computes nothing
    again = sweep.run_sweep("S1", sweep.from_csv(path), tmp_path / "out", duration=DURATION, resume=True,
                            drop=_fails_on_soft_spring)
    assert again.computed == 0 and again.reused == 4


# --- nothing lost: kill -9 and --resume ------------------------------------------------------


def test_killed_sweep_resumes_with_only_the_missing_variants(tmp_path):
    vary = [f"{RATE}=14:18:8", f"{TIRE}=75:95:5"]  # 40 variants
    args = ["sweep", "S1", "--duration", str(DURATION), "--quiet"] + [a for v in vary for a in ("--vary", v)]
    out = tmp_path / "killed"
    code = "import sys; from mtbmj.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen([sys.executable, "-c", code, *args, "--out", str(out), "--workers", "1", "--batch-size", "1"],
                            start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    journal = out / "journal"
    deadline = time.monotonic() + 60
    try:
        while len(list(journal.glob("part-*.json"))) < 3:
            assert proc.poll() is None, proc.stderr.read().decode()
            assert time.monotonic() < deadline, "no variant journaled within 60 s"
            time.sleep(0.01)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its worker, mid-run
        proc.wait()
        proc.stderr.close()
    assert not (out / "sweep.parquet").exists()
    journaled = len(sweep.Journal(out).records())
    assert 3 <= journaled < 40
    (journal / ".part-stray.json.tmp").write_text('{"records": [')  # a half-written temporary file

    assert cli.main(args + ["--out", str(out), "--resume", "--workers", "2"]) == 0
    resumed = pd.read_parquet(out / "sweep.parquet")
    manifest = json.loads((out / "sweep.json").read_text())
    assert manifest["variants"] == 40
    assert len(resumed) == 40 and resumed["variant_id"].is_unique and list(resumed["variant"]) == list(range(40))
    ids = [rec["id"] for part in journal.glob("part-*.json") for rec in json.loads(part.read_text())["records"]]
    assert len(ids) == len(set(ids)) == 40  # each variant computed exactly once over both runs

    clean = tmp_path / "clean"
    assert cli.main(args + ["--out", str(clean), "--workers", "2"]) == 0
    pd.testing.assert_frame_equal(_comparable(resumed), _comparable(pd.read_parquet(clean / "sweep.parquet")))


# --- Dask ----------------------------------------------------------------------------------------


def test_dask_backend_gives_identical_results(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    local, out = reference
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        dask_out = tmp_path / "dask"
        result = sweep.run_sweep("S1", _grid(), dask_out, duration=DURATION, backend="dask",
                                 scheduler=cluster.scheduler_address, traces=True)
        assert result.computed == 6
    pd.testing.assert_frame_equal(_comparable(local.table), _comparable(result.table))
    pd.testing.assert_frame_equal(_comparable(pd.read_parquet(out / "sweep.parquet")),
                                  _comparable(pd.read_parquet(dask_out / "sweep.parquet")))
    import h5py

    with h5py.File(out / "traces.h5") as a, h5py.File(dask_out / "traces.h5") as b:
        assert np.array_equal(a["fork_mm"][:], b["fork_mm"][:])


# --- sensitivity ---------------------------------------------------------------------------------


@pytest.mark.parametrize("method,n,keys", [("sobol", 8, ("S1", "S1_conf", "ST", "ST_conf")),
                                           ("morris", 4, ("mu", "mu_star", "sigma", "mu_star_conf"))])
def test_sensitivity(tmp_path, method, n, keys):
    from mtbmj.sweep.sensitivity import run_sensitivity

    ranges = [sweep.parse_vary(f"{RATE}=14:18", count=False), sweep.parse_vary(f"{TIRE}=75:95", count=False)]
    result = run_sensitivity("S1", ranges, ["fork_peak1_mm", "tire_peak1_mm"], tmp_path, method=method, n=n,
                             duration=DURATION, workers=2)
    assert result.runs == (n * 4 if method == "sobol" else n * 3)
    for out in ("fork_peak1_mm", "tire_peak1_mm"):
        for p in (RATE, TIRE):
            values = result.indices[out][p]
            assert set(values) == set(keys) and all(v is not None and np.isfinite(v) for v in values.values())
    main = "ST" if method == "sobol" else "mu_star"
    # the fork spring rate drives the fork peak more than the tire rate does
    assert result.indices["fork_peak1_mm"][RATE][main] > result.indices["fork_peak1_mm"][TIRE][main]
    data = json.loads((tmp_path / "sensitivity.json").read_text())
    assert data["method"] == method and data["indices"]["fork_peak1_mm"][RATE][keys[-1]] >= 0
    assert (tmp_path / "sensitivity.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len((tmp_path / "sensitivity.csv").read_text().splitlines()) == 1 + 4
    assert len(pd.read_parquet(tmp_path / "sweep.parquet")) == result.runs


# --- command line --------------------------------------------------------------------------------


@pytest.mark.parametrize("argv,message", [
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm"], "expected key=lo:hi:n"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=a:b:3"], "expected key=lo:hi:n"),
    (["sweep", "S1", "--vary", "fork.spring.rat_N_per_mm=1:2:3"], "unknown key"),
    (["sweep", "S1", "--vary", "fork.spring.rate=1:2:3"], "without its unit"),
    (["sweep", "S1", "--vary", "fork.spring.model=1:2:3"], "not a number"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=18:14:3"], "lo must be below hi"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:14:3"], "lo must be below hi"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:0"], "at least 1"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:2.5"], "whole number"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18"], "needs a count"),
    (["sweep", "S1", "--samples", "4", "--vary", "fork.spring.rate_N_per_mm=14:18:3"], "range only"),
    (["sweep", "S1", "--samples", "0", "--vary", "fork.spring.rate_N_per_mm=14:18"], "at least 1"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:2", "--vary", "fork.spring.rate_N_per_mm=1:2:2"], "twice"),
    (["sweep", "S1"], "give --vary"),
    (["sweep", "S9999", "--vary", "fork.spring.rate_N_per_mm=14:18:2"], "unknown preset"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:2", "--backend", "dask"], "--scheduler"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:2", "--workers", "0"], "--workers"),
    (["sweep", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:2", "--duration", "-1"], "--duration"),
    (["sweep", "S1", "--from-csv", "CSV_UNKNOWN"], "column foo: unknown key"),
    (["sweep", "S1", "--from-csv", "CSV_MISSING"], "cannot read"),
    (["sensitivity", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18", "--output", "fork_peak_mm"], "not a numeric sweep output"),
    (["sensitivity", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18:3"], "range only"),
    (["sensitivity", "S1"], "at least one --vary"),
    (["sensitivity", "S1", "--vary", "fork.spring.rate_N_per_mm=14:18", "--samples", "1"], "at least 2"),
])
def test_cli_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, message):
    (tmp_path / "unknown.csv").write_text(f"{RATE},foo\n16,1\n")
    argv = [str(tmp_path / "unknown.csv") if a == "CSV_UNKNOWN" else str(tmp_path / "none.csv") if a == "CSV_MISSING"
            else a for a in argv]
    assert cli.main(argv + ["--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mtbmj: error: ") and err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "out" / "sweep.parquet").exists()


def test_cli_sweep_wired_into_mtbmj(tmp_path, capsys):
    from mtbmj import cli

    parser = cli.build_parser()
    choices = next(a for a in parser._actions if a.dest == "command").choices
    assert "sweep" in choices and "sensitivity" in choices
    assert cli.main(["sweep", "S1", "--vary", f"{RATE}=14:18:2", "--duration", "0.1", "--out", str(tmp_path), "--quiet"]) == 0
    assert "2 variants (2 computed" in capsys.readouterr().out  # (a grid of 1 value is refused: test_fuzz_careless31)


@pytest.mark.parametrize("grid, status, failed", [("-6:-2:2", 1, "2 failed"), ("-6:14:2", 0, "1 failed")])
def test_a_sweep_says_why_its_variants_failed_and_exits_1_when_all_did(tmp_path, capsys, grid, status, failed):
    """A sweep whose variants fail (a spring of -6 N/mm) said only "2 failed" and exited 0 though
    nothing ran: the line names the first failure's reason (the table holds each one), and a sweep
    whose every variant failed exits 1 (its table written); one that ran some exits 0."""
    from mtbmj import cli

    out = tmp_path / "sw"
    assert cli.main(["sweep", "S1", "--vary", f"{RATE}={grid}", "--duration", "0.1", "--out", str(out), "--quiet"]) \
        == status
    line = capsys.readouterr().out
    assert f"{failed}: the first, variant 0: {RATE}: must be positive, got -6" in line, line
    table = pd.read_parquet(out / "sweep.parquet")
    assert (table["status"] == "failed").sum() == int(failed.split()[0])


def test_the_progress_of_a_sweep_with_failed_variants_counts_them():
    """The progress line counts the failed variants (the closing line names the first's reason); a
    replace meant for the closing line once made it call a method it does not have."""
    from mtbmj.sweep.runner import SweepProgress

    bar = SweepProgress(4, stream=io.StringIO(), enabled=True)
    bar.update(2, failed=1)
    assert "2/4 variants, 1 failed," in bar.text()

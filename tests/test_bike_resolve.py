"""A bike file resolved once (``mtbmj.bike.spec.resolve``): read (bases, chart, shock as sold,
linkage, leverage CSV), derived and checked into one ``ResolvedBike`` (the resolved table, the
bike, its linkage and curves); the same file at other settings derived from it without reading it
again; ``mtbmj advise`` reads its bike file at most 3 times (issue 50 item 3).

The reads are counted where a bike file is opened (``mtbmj.config.read_chain``, the one reader of
base chains: a call naming the file), on bike files and rides written here."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj import config
from mtbmj.bike import spec as spec_mod
from mtbmj.cli import main

from helpers import HORST, MM, advise_ride, reconstruction_passing


@pytest.fixture
def reads(monkeypatch):
    """Names -> how often ``read_chain`` was asked for them (a file, and each of its bases)."""
    counts: dict[str, int] = {}
    real = config.read_chain

    def counting(ref, *args, **kwargs):
        counts[str(ref)] = counts.get(str(ref), 0) + 1
        return real(ref, *args, **kwargs)

    monkeypatch.setattr(config, "read_chain", counting)
    return counts


def horst_bike(tmp_path):
    points = "\n".join(f"{k}_mm = [{v[0] / MM:g}, {v[1] / MM:g}]" for k, v in HORST.items())
    path = tmp_path / "horst.toml"
    path.write_text('base = "trail"\n[linkage]\nkind = "horst_link"\n' + points + "\n")
    return path


def csv_bike(tmp_path):
    (tmp_path / "lr.csv").write_text("travel;ratio\n0;3.0\n80;2.6\n160;2.4\n")
    path = tmp_path / "csv.toml"
    path.write_text('base = "sst"\n[leverage]\ncsv = "lr.csv"\n[shock]\nstroke_mm = 61.0\n')
    return path


def test_the_resolved_bike_is_the_loaded_bike_and_other_settings_are_not_read_again(tmp_path, reads, monkeypatch):
    path = csv_bike(tmp_path)
    csv_reads = []
    real_csv = spec_mod.read_leverage_csv
    monkeypatch.setattr(spec_mod, "read_leverage_csv", lambda p: csv_reads.append(p) or real_csv(p))
    resolved = spec_mod.resolve(str(path))
    assert reads[str(path)] == 1 and len(csv_reads) == 1
    assert resolved.spec == spec_mod.load(str(path))  # the same bike as load gives (read again here: 2)
    over = {"rider.mass_kg": 95.0, "shock.set": {"fork.spring.rate_N_per_mm": 70.0}}
    other = resolved.with_overrides(over)
    assert reads[str(path)] == 2 and len(csv_reads) == 2  # the settings below read neither file again
    assert other.spec == spec_mod.load(str(path), over)
    assert reads[str(path)] == 3 and len(csv_reads) == 3
    assert spec_mod.load(resolved, over) == other.spec and spec_mod.load(resolved) is resolved.spec
    assert reads[str(path)] == 3 and len(csv_reads) == 3
    assert other.spec.rider.mass + other.spec.rider.on_bike_mass == pytest.approx(95.0)
    assert other.spec.shock_overrides["fork.spring.rate_N_per_mm"] == 70.0
    # the leverage curve is the CSV's: 3.0 at 0, 2.6 at 80 mm (typed here, not read back from the package)
    assert other.spec.leverage.ratio_at(0.0) == 3.0 and other.spec.leverage.ratio_at(0.080) == pytest.approx(2.6)
    # a bad override is refused as load refuses it, and the resolved bike is as it was
    with pytest.raises(spec_mod.ConfigError, match="rider.nope"):
        resolved.with_overrides({"rider.nope": 1.0})
    assert resolved.overrides == {} and "mass_kg" in resolved.read["rider"] and resolved.read["rider"]["mass_kg"] != 95.0


def test_a_linkage_is_solved_once_and_kept_with_its_curves(tmp_path, reads):
    from mtbmj.bike import linkage as lk

    path = horst_bike(tmp_path)
    resolved = spec_mod.resolve(str(path))
    assert resolved.linkage is not None and resolved.linkage.kind == "horst_link"
    c = resolved.curves
    # the curves cover the shock's stroke, and the bike's leverage table is theirs, millimetre by millimetre
    again = lk.curves(lk.from_table(resolved.read["linkage"]), resolved.spec.shock_stroke)
    assert np.array_equal(c.travel, again.travel) and np.array_equal(c.leverage_ratio, again.leverage_ratio)
    assert np.allclose(np.asarray(resolved.spec.leverage.travel), c.travel, atol=1e-12)
    assert resolved.table["bike"]["pivot_mm"] == [x / MM for x in resolved.spec.pivot]
    assert "linkage" not in resolved.table  # the resolved table holds what the bike was built from
    assert reads[str(path)] == 1
    assert spec_mod.resolve(resolved) is resolved


def test_a_run_takes_the_resolved_bike_as_it_takes_the_file(tmp_path, reads):
    from mtbmj.bike import run

    path = tmp_path / "bike.toml"
    path.write_text('base = "trail"\n[rider]\nmass_kg = 82.0\n')
    over = {"fork.set": {"fork.spring.progressive_rate_N_per_mm": 11.0}}  # (the fork is progressive)
    by_path = run.run_bike(str(path), "root:at_m=0.4", 5.0, duration=0.3, overrides=over)
    n = reads[str(path)]
    resolved = spec_mod.resolve(str(path))
    by_object = run.run_bike(resolved, "root:at_m=0.4", 5.0, duration=0.3, overrides=over)
    assert reads[str(path)] == n + 1  # the resolution read it; the run did not
    for key in ("time_s", "front_travel_mm", "rear_travel_mm", "pitch_deg"):
        if key in by_path.raw:
            assert np.array_equal(by_path.raw[key], by_object.raw[key]), key


@pytest.mark.slow
def test_advise_reads_its_bike_file_at_most_three_times(tmp_path, reads):
    bike, sst, *_ = advise_ride(tmp_path, fork_rate=5.0, seconds=16.0)  # the maker reads the bike file once, counted
    with reconstruction_passing():
        assert main(["advise", str(sst), "--bike", str(bike), "--workers", "1", "--try-set",
                     "fork:fork.spring.rate_N_per_mm=6", "--out", str(tmp_path / "out")]) == 0
    assert 1 <= reads[str(bike)] <= 3, reads
    assert (tmp_path / "out" / "advice.json").exists()

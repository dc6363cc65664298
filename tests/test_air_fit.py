"""``mtbmj fit spring`` on an air fork: a synthetic dyno record made by ``mtbmj synth`` from known
values; the air model is offered beside the coil ones, chosen by BIC, and recovers the pressure and
the volume."""
import warnings

import numpy as np
import pytest

import mtbmj
from mtbmj import cli
from mtbmj.config import load
from mtbmj.measured.records import read_record
from mtbmj.identify.run import identify


def test_air_fit_recovers_pressure_and_volume_from_a_synthetic_record(tmp_path, capsys):
    rng = np.random.default_rng(1616)
    for trial in range(2):
        psi, volume, tokens = float(rng.uniform(70, 110)), float(rng.uniform(140, 200)), int(rng.integers(0, 4))
        negative = float(rng.choice([0.0, 10.0]))
        record = tmp_path / f"air_{trial}.csv"
        truth = [f"fork.spring.air_pressure_psi={psi}", f"fork.spring.air_volume_cm3={volume}",
                 f"fork.spring.tokens={tokens}", f"fork.spring.negative_volume_cm3={negative}"]
        args = ["synth", "spring", "air120", "--out", str(record), "--seed", str(trial)]
        assert cli.main(args + [a for t in truth for a in ("--set", t)]) == 0
        assert read_record(record).synthetic
        geometry = tmp_path / f"geometry_{trial}.toml"  # the fork's known geometry, pressure and volume unknown
        geometry.write_text(f'base = "air120"\n[fork.spring]\ntokens = {tokens}.0\nnegative_volume_cm3 = {negative}\n')
        out = tmp_path / f"fit_{trial}"
        assert cli.main(["fit", "spring", str(record), "--config", str(geometry), "--out", str(out)]) == 0
        printed = capsys.readouterr().out
        assert "spring air:" in printed
        fitted = load(out / "fit.toml")
        assert fitted["fork.spring.model"] == "air"
        assert fitted["fork.spring.air_pressure_psi"] == pytest.approx(psi, rel=0.02)
        assert fitted["fork.spring.air_volume_cm3"] == pytest.approx(volume, rel=0.02)
        assert fitted["fork.spring.tokens"] == tokens
        with warnings.catch_warnings(record=True) as seen:  # fit.toml stands alone (its base a file): it carries
            warnings.simplefilter("always")  # the file's values, not the preset's keys its models do not read
            assert mtbmj.run_drop(fitted, duration=0.3).summary["max_fork_mm"] > 0
        assert not [str(w.message) for w in seen if "does not read it" in str(w.message)]
        assert "knee_mm" not in (out / "fit.toml").read_text() and "fork.spring.knee_mm" in load("air120").values


def test_air_model_is_offered_only_with_an_air_geometry(tmp_path):
    record = tmp_path / "coil.csv"
    assert cli.main(["synth", "spring", "S12", "--out", str(record)]) == 0
    coil = identify("spring", [record])
    assert "air" not in coil.results and coil.chosen[0] != "air"
    air = identify("spring", [record], config="air120")
    assert "air" in air.results
    assert air.chosen[0] != "air"  # a coil fork's stroke is not better described by an air spring
    assert air.results["air"].bic > air.results[air.chosen[0]].bic


@pytest.mark.parametrize("args,needle", [
    (["synth", "spring", "air120", "--out", "{dir}/rec.txt"], "--out"),
    (["synth", "spring", "air120", "--out", "{dir}/exists.csv"], "exists"),
    (["synth", "spring", "air120", "--out", "{dir}/r.csv", "--set", "fork.spring.tokens=40"], "fork.spring.tokens"),
])
def test_synth_bad_input_exits_2(tmp_path, capsys, args, needle):
    (tmp_path / "exists.csv").write_text("keep me\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    assert cli.main([a.format(dir=tmp_path) for a in args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert (tmp_path / "exists.csv").read_text() == "keep me\n"

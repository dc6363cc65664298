"""``mtbmj air-study``: every variant on both engines, the figures and the table."""
import csv

from mtbmj import cli
from mtbmj.config import load
from mtbmj.drop.air_study import static_sag_mm, variants


def test_variants_cover_spacers_pressures_and_tire_pressures():
    groups = {}
    for group, change in variants(load("air120")).values():
        groups.setdefault(group, []).append(change)
    assert [c["fork.spring.tokens"] for c in groups["spacers"]] == [0.0, 1.0, 2.0, 3.0]
    assert len([c for c in groups["pressure"] if c]) == 2 and len(groups["tire"]) == 2


def test_static_sag_falls_with_pressure_and_spacers():
    base = load("air120")
    sags = [static_sag_mm(base.with_overrides({"fork.spring.air_pressure_psi": p})) for p in (70.0, 85.0, 100.0)]
    assert sags[0] > sags[1] > sags[2]
    sags = [static_sag_mm(base.with_overrides({"fork.spring.tokens": float(t)})) for t in (0, 3)]
    assert sags[0] > sags[1]


def test_air_study_command_writes_figures_and_table(tmp_path, capsys):
    out = tmp_path / "study"
    assert cli.main(["air-study", "--duration", "0.3", "--workers", "2", "--quiet", "--out", str(out)]) == 0
    names = {p.name for p in out.iterdir()}
    assert {"air_spacers.png", "air_pressure.png", "air_tire.png", "air_spring_curves.png", "air_study.csv",
            "engine_vs_reference.md", "air_study_summary.json"} <= names
    rows = {r["variant"]: r for r in csv.DictReader((out / "air_study.csv").open())}
    peaks = [float(rows[n]["fork_peak1_mm"]) for n in ("0 spacers", "1 spacer", "2 spacers", "3 spacers")]
    assert peaks == sorted(peaks, reverse=True)
    assert float(rows["tire 18 psi"]["tire_peak1_mm"]) > float(rows["tire 24 psi"]["tire_peak1_mm"])
    assert all(float(r["max_mujoco_ode_diff_mm"]) < 0.1 for r in rows.values())


def test_air_study_refuses_a_coil_configuration(tmp_path, capsys):
    assert cli.main(["air-study", "S12", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fork.spring.model" in err[0]
    assert not (tmp_path / "x").exists()

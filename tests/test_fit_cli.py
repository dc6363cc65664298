"""`mtbmj fit` end to end: synthetic records in, a parameter set that `mtbmj drop` runs out; bad
input gets one line, exit status 2 and no half-written TOML."""
import json
import subprocess
import sys

import numpy as np
import pytest

import mtbmj
from mtbmj import cli, output
from mtbmj.identify import dyno_synthetic as dyno, tire_synthetic as tires


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "mtbmj.cli", *map(str, args)], capture_output=True, text=True, cwd=cwd)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    d = tmp_path_factory.mktemp("records")
    dyno.write_spring_record(d / "spring.csv")
    dyno.write_damper_record(d / "damper.csv", peaks=True)  # the reference table damper
    dyno.write_damper_record(d / "damper_bilinear.csv", truth=dyno.DAMPER_BILINEAR, peaks=True)
    (d / "tire_drop.csv").write_text(tires.tire_drop_record())
    (d / "tire_ramp.csv").write_text(tires.tire_ramp_record())
    return d


@pytest.mark.parametrize("kind, files, extra, expect", [
    ("spring", ["spring.csv"], [], {"fork.spring.model": "progressive", "fork.spring.progressive_rate_N_per_mm": 11.37,
                                    "fork.spring.preload_N": 211.1, "fork.spring.top_out_rate_N_per_mm": 35.3}),
    ("damper", ["damper_bilinear.csv"], [], {"fork.damper.model": "bilinear", "fork.friction.model": "coulomb",
                                             "fork.damper.compression_N_s_per_m": 133.2,
                                             "fork.damper.rebound_N_s_per_m": 269.4, "fork.friction.coulomb_N": 34.2}),
    ("damper", ["damper.csv"], [], {"fork.damper.model": "table", "fork.friction.coulomb_N": 34.2}),
    ("tire", ["tire_drop.csv", "tire_ramp.csv"], ["--mass-kg", "25"],
     {"tire.model": "switch", "tire.impact_rate_N_per_mm": 85.1, "tire.contact_rate_N_per_mm": 73.4,
      "tire.static_rate_N_per_mm": 61.7}),
])
def test_fit_writes_a_parameter_set_that_drop_runs(records, tmp_path, kind, files, extra, expect):
    out = tmp_path / "fit"
    done = run_cli("fit", kind, *[records / f for f in files], *extra, "--out", out)
    assert done.returncode == 0, done.stderr
    assert {p.name for p in out.iterdir()} - set(output.BOOKKEEPING) == {"fit.toml", "fit.json", "fit.png"}
    config = mtbmj.load_config(str(out / "fit.toml"))
    for key, value in expect.items():
        if isinstance(value, str):
            assert config[key] == value
        else:
            assert config[key] == pytest.approx(value, rel=0.05), key
    summary = json.loads((out / "fit.json").read_text())
    assert summary["synthetic_data"] is True and summary["chosen"]
    assert (out / "fit.png").read_bytes()[:4] == b"\x89PNG"
    drop = run_cli("drop", out / "fit.toml", "--duration", "0.2", "--out", tmp_path / "drop")
    assert drop.returncode == 0, drop.stderr


def test_damper_auto_choice_is_backed_by_the_residual(records, tmp_path):
    out = tmp_path / "fit"
    assert run_cli("fit", "damper", records / "damper.csv", "--out", out).returncode == 0
    summary = json.loads((out / "fit.json").read_text())
    models = summary["models"]
    hydraulic = summary["chosen"][0]
    assert models[hydraulic]["bic"] == min(models[m]["bic"] for m in ("linear", "bilinear", "table"))
    assert models["linear"]["rms"] > 2 * models[hydraulic]["rms"]  # the wrong model is clearly worse


def _write(path, text):
    path.write_text(text)
    return path


@pytest.mark.parametrize("name, text, args, needle", [
    ("unitless", "displacement,force_N\n1,2\n", [], "has no unit"),
    ("missing", "time_s,force_N\n" + "".join(f"{i},{i}\n" for i in range(50)), [], "missing column displacement"),
    ("nonnumeric", "displacement_mm,force_N\n1,2\n2,x\n", [], "'x' is not a number"),
    ("time_back", "time_s,displacement_mm,force_N\n" + "".join(f"{t},{t},{t}\n" for t in [0, 1, 2, 1.5, 3] * 10),
     [], "time is not increasing"),
    ("few", "displacement_mm,force_N\n1,2\n2,4\n", [], "too few points"),
])
def test_bad_spring_records(tmp_path, name, text, args, needle):
    path = _write(tmp_path / f"{name}.csv", text)
    out = tmp_path / "out"
    done = run_cli("fit", "spring", path, *args, "--out", out)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in done.stderr
    assert not out.exists()


def test_top_out_asked_on_a_stroke_without_extension(tmp_path, capsys):
    record = dyno.spring_record(extension_mm=5.0)  # the stroke stays in compression
    path = tmp_path / "no_extension.csv"
    dyno.write_csv(path, record)
    out = tmp_path / "out"
    assert cli.main(["fit", "spring", str(path), "--model", "top_out", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "never reaches extension" in err[0]
    assert not out.exists()


def test_tire_fit_needs_the_mass_and_an_impact(records, tmp_path, capsys):
    out = tmp_path / "out"
    # the mass comes from --mass-kg or from a "# mass_kg = ..." header line; here from neither
    text = "\n".join(line for line in (records / "tire_drop.csv").read_text().splitlines() if "mass_kg" not in line)
    no_mass = _write(tmp_path / "no_mass.csv", text + "\n")
    assert cli.main(["fit", "tire", str(no_mass), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "mass" in err[0]
    flat = _write(tmp_path / "flat.csv", "time_s,deflection_mm\n" + "".join(f"{i / 1000},{-5.0}\n" for i in range(500)))
    assert cli.main(["fit", "tire", str(flat), "--mass-kg", "25", "--out", str(out)]) == 2
    assert "impact" in capsys.readouterr().err
    assert not out.exists()


def test_drop_fit_bad_free_key_and_bounds(records, tmp_path, capsys):
    sled = tmp_path / "sled.csv"
    from mtbmj.identify import drop_synthetic

    drop_synthetic.make_drop_record("S12", {"fork.spring.preload_N": 230.0}, path=sled, duration=0.3)
    out = tmp_path / "out"
    assert cli.main(["fit", "drop", str(sled), "--free", "fork.spring.prelod_N", "--out", str(out)]) == 2
    assert "fork.spring.prelod_N" in capsys.readouterr().err
    # without --free the default pair is fitted, and the output says so
    assert cli.main(["fit", "drop", str(sled), "--out", str(tmp_path / "default")]) == 0
    assert "no --free given: fitting tire.impact_rate_N_per_mm, fork.spring.preload_N" in capsys.readouterr().out
    assert cli.main(["fit", "drop", str(sled), "--free", "fork.spring.preload_N", "--bound", "x", "--out", str(out)]) == 2
    assert "--bound" in capsys.readouterr().err
    for empty in ("", ",", " , "):  # a list left empty by mistake is refused, not read as "the default"
        assert cli.main(["fit", "drop", str(sled), "--free", empty, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--free" in err[0] and "names no key" in err[0]
    assert not out.exists()


def test_drop_fit_on_the_fast_engine_end_to_end(tmp_path, capsys):
    """`mtbmj fit drop --engine fast` on a record the ODE reference made (with a logger's free
    fall and clock offset): the two parameters come back within their intervals, and the
    parameter set it writes runs. It used to fail at the end, looking up the engine to measure
    its own error against."""
    import json

    from mtbmj.identify import drop_synthetic

    truth = {"fork.spring.preload_N": 240.0, "tire.impact_rate_N_per_mm": 84.0}
    sled = tmp_path / "sled.csv"
    drop_synthetic.make_drop_record("S12", truth, path=sled, duration=0.5, seed=11, fall_s=0.04, clock_offset_s=3.2)
    out = tmp_path / "fit"
    assert cli.main(["fit", "drop", str(sled), "--engine", "fast", "--free", ",".join(truth), "--out", str(out)]) == 0
    fit = json.loads((out / "fit.json").read_text())["models"]["drop"]
    assert fit["model"] == "S12 (fast)"
    for key, value in truth.items():
        low, high = fit["ci95"][key]
        assert low <= value <= high and high - low < 0.01 * value, (key, low, high)
    # the report says what measured the engine's own error
    said = capsys.readouterr().out + (out / "fit.json").read_text()
    assert "engine's own error (against the fast engine stepped twice as finely at the optimum, its difference doubled)" in said
    assert cli.main(["drop", str(out / "fit.toml"), "--quiet", "--out", str(tmp_path / "run")]) == 0


def test_a_fit_that_does_not_converge_is_reported(records, tmp_path, capsys):
    """A drop fit given one engine run cannot converge: one line, exit 2, nothing written."""
    sled = tmp_path / "sled.csv"
    from mtbmj.identify import drop_synthetic, dropfit

    drop_synthetic.make_drop_record("S12", {"fork.spring.preload_N": 260.0}, path=sled, duration=0.3)
    out = tmp_path / "out"
    original = dropfit.fit_drop

    def starved(*args, **kwargs):
        return original(*args, **{**kwargs, "max_nfev": 1})

    dropfit.fit_drop = starved
    try:
        code = cli.main(["fit", "drop", str(sled), "--free", "fork.spring.preload_N", "--out", str(out)])
    finally:
        dropfit.fit_drop = original
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "converge" in err[0]
    assert not out.exists()

"""Fork spring and damper identification on noisy synthetic shock-dyno records (issue 3).

The records are generated from known parameters (mtbmj.identify.dyno_synthetic) with 1 kHz
sampling, 0.05 mm / 5 N sensor noise and 16-bit quantisation; the fits must recover them: rates
within 2 %, damping within 5 %, friction within 10 %, the knee within 2 mm.
"""
import numpy as np
import pytest

import mtbmj
from mtbmj import compose
from mtbmj.errors import MtbmjError
from mtbmj.identify import damper as dfit
from mtbmj.identify import dyno_synthetic as syn
from mtbmj.identify import spring as sfit
from mtbmj.measured.records import Record, read_record

S, D, R = "fork.spring.", "fork.damper.", "fork.friction."


def rel(a, b):
    return abs(a - b) / abs(b)


@pytest.fixture(scope="module")
def progressive_record():
    return syn.spring_record(syn.SPRING_PROGRESSIVE, seed=1)


@pytest.fixture(scope="module")
def bilinear_record():
    return syn.spring_record(syn.SPRING_BILINEAR, seed=2)


@pytest.fixture(scope="module")
def bilinear_damper_record():
    return syn.damper_record(syn.DAMPER_BILINEAR, seed=3)


@pytest.fixture(scope="module")
def stribeck_damper_record():
    return syn.damper_record(syn.DAMPER_STRIBECK, low_speeds=True, seed=4)


def test_records_are_labelled_synthetic_with_their_truth(progressive_record, bilinear_damper_record):
    for rec in (progressive_record, bilinear_damper_record):
        assert rec.synthetic and "synthetic" in rec.comments[0]
        assert "true parameters" in rec.comments[1]
    x = progressive_record["displacement"] * 1e3
    assert x.min() < -9.0 and x.max() > 105.0  # into extension past the top-out spring, near full travel
    assert np.all(np.diff(progressive_record["time"]) > 0)


# --- spring ---------------------------------------------------------------------------------------

def test_progressive_top_out_preload_recovered(progressive_record):
    r = sfit.fit_spring(progressive_record, "progressive")
    t = syn.SPRING_PROGRESSIVE
    assert r.extra["model_keys"] == {S + "model": "progressive", S + "top_out": True, S + "preload": True}
    for key in ("progressive_rate_N_per_mm", "top_out_rate_N_per_mm", "preload_N"):
        assert rel(r.values[S + key], t[S + key]) < 0.02, key
    assert rel(r.values[S + "progressive_cubic_N_per_mm3"], t[S + "progressive_cubic_N_per_mm3"]) < 0.05
    assert rel(r.extra["friction_N"], t[R + "coulomb_N"]) < 0.10
    assert r.rms < 7.0  # about the 5 N sensor noise
    assert all(np.isfinite(r.stderr[k]) and r.stderr[k] > 0 for k in r.values)


def test_bilinear_knee_found_by_the_fit(bilinear_record):
    r = sfit.fit_spring(bilinear_record, "bilinear")
    t = syn.SPRING_BILINEAR
    for key in ("rate_below_knee_N_per_mm", "rate_above_knee_N_per_mm", "top_out_rate_N_per_mm", "preload_N"):
        assert rel(r.values[S + key], t[S + key]) < 0.02, key
    assert abs(r.values[S + "knee_mm"] - t[S + "knee_mm"]) < 2.0
    assert rel(r.extra["friction_N"], t[R + "coulomb_N"]) < 0.10
    x, f = r.extra["curve"]
    assert len(x) == len(f) and x.min() < 0


def test_wrong_spring_model_has_clearly_worse_residual(bilinear_record):
    fits = sfit.fit_spring_all(bilinear_record)
    assert fits["linear"].rms >= 2.0 * fits["bilinear"].rms
    assert fits["progressive"].rms >= 2.0 * fits["bilinear"].rms
    assert min(fits.values(), key=lambda r: r.bic).model == "bilinear"


def test_compression_rebound_rates_and_linear_rate():
    rec = syn.spring_record(syn.SPRING_COMPRESSION_REBOUND, extension_mm=5.0, seed=5)
    t = syn.SPRING_COMPRESSION_REBOUND
    r = sfit.fit_spring(rec, "compression_rebound")
    assert rel(r.values[S + "compression_rate_N_per_mm"], t[S + "compression_rate_N_per_mm"]) < 0.02
    assert rel(r.values[S + "rebound_rate_N_per_mm"], t[S + "rebound_rate_N_per_mm"]) < 0.02
    assert rel(r.extra["friction_N"], t[R + "coulomb_N"]) < 0.10
    lin_truth = {S + "model": "linear", S + "rate_N_per_mm": 16.0, S + "top_out": False, S + "preload": False,
                 R + "model": "coulomb", R + "coulomb_N": 34.2}
    lin = sfit.fit_spring(syn.spring_record(lin_truth, extension_mm=5.0, seed=6), "linear")
    assert rel(lin.values[S + "rate_N_per_mm"], 16.0) < 0.02
    assert lin.extra["model_keys"][S + "top_out"] is False


def test_mat_record_gives_the_same_fit_as_csv(tmp_path, bilinear_record):
    csv = syn.write_csv(tmp_path / "spring.csv", bilinear_record)
    mat = syn.write_mat(tmp_path / "spring.mat", bilinear_record)
    assert csv.read_text().splitlines()[0].startswith("# synthetic")
    a, b = read_record(csv), read_record(mat)
    assert a.synthetic and b.synthetic
    ra, rb = sfit.fit_spring(a, "bilinear"), sfit.fit_spring(b, "bilinear")
    for key, value in ra.values.items():
        assert rb.values[key] == pytest.approx(value, rel=1e-6), key


def test_spring_overrides_load_and_set_up(progressive_record, bilinear_record):
    for rec in (progressive_record, bilinear_record):
        for name, r in sfit.fit_spring_all(rec).items():
            config = mtbmj.load_config("reference", r.overrides())
            compose.setup(config)


def test_top_out_without_extension_is_one_clear_line():
    rec = syn.spring_record(syn.SPRING_PROGRESSIVE, extension_mm=10.0, cycles=1)
    with pytest.raises(MtbmjError) as err:
        sfit.fit_spring(rec, "top_out")
    message = str(err.value)
    assert "\n" not in message and "never reaches extension" in message
    with pytest.raises(MtbmjError, match="never reaches extension"):
        sfit.fit_spring(rec, "progressive", top_out=True)
    assert "top_out" not in sfit.fit_spring_all(rec)  # the rest still fit


def test_too_few_points_spring_and_damper():
    x = np.linspace(0, 0.05, 8)
    rec = Record("tiny.csv", {"displacement": x, "force": 16e3 * x}, {"displacement": "mm", "force": "N"})
    with pytest.raises(MtbmjError, match="too few points"):
        sfit.fit_spring(rec, "linear")
    peaks = Record("tiny.csv", {"velocity": np.array([-0.5, 0.5, 1.0]), "force": np.array([-150.0, 100.0, 170.0])},
                   {"velocity": "mm_per_s", "force": "N"})
    with pytest.raises(MtbmjError, match="too few points"):
        dfit.fit_damper(peaks, "bilinear")


def test_plot_spring_returns_a_figure(bilinear_record):
    fig = sfit.plot_spring(bilinear_record, sfit.fit_spring_all(bilinear_record))
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 4


# --- damper ---------------------------------------------------------------------------------------

def test_peak_points_one_per_half_cycle(bilinear_damper_record):
    peaks = syn.peak_points(bilinear_damper_record)
    v = peaks["velocity"] * 1e3
    assert np.sum(v > 0) >= 2 * len(syn.TEST_SPEEDS_MM_PER_S) and np.sum(v < 0) >= 2 * len(syn.TEST_SPEEDS_MM_PER_S)
    assert abs(v).max() == pytest.approx(1500.0, rel=0.03)


def test_bilinear_damper_and_coulomb_recovered(bilinear_damper_record):
    t = syn.DAMPER_BILINEAR
    fits = dfit.fit_damper_all(bilinear_damper_record)
    b = fits["bilinear"]
    assert rel(b.values[D + "compression_N_s_per_m"], t[D + "compression_N_s_per_m"]) < 0.05
    assert rel(b.values[D + "rebound_N_s_per_m"], t[D + "rebound_N_s_per_m"]) < 0.05
    assert rel(b.values[R + "coulomb_N"], t[R + "coulomb_N"]) < 0.10
    assert b.extra["model_keys"] == {D + "model": "bilinear", R + "model": "coulomb"}
    assert fits["linear"].rms >= 2.0 * b.rms  # the wrong (single-coefficient) model
    mean = 0.5 * (t[D + "compression_N_s_per_m"] + t[D + "rebound_N_s_per_m"])
    assert rel(fits["linear"].values[D + "coefficient_N_s_per_m"], mean) < 0.05
    # friction choice by BIC: no stiction in the truth, and no low speeds to show one
    assert dfit.select({k: fits[k] for k in dfit.FRICTION}).extra["friction"] == "coulomb"
    assert fits["stribeck"].extra["supported"] is False
    assert rel(fits["table"].values[R + "coulomb_N"], t[R + "coulomb_N"]) < 0.10


def test_linear_damper_recovered():
    truth = {D + "model": "linear", D + "coefficient_N_s_per_m": 201.3, R + "model": "coulomb", R + "coulomb_N": 34.2}
    r = dfit.fit_damper(syn.damper_record(truth, seed=7), "linear")
    assert rel(r.values[D + "coefficient_N_s_per_m"], 201.3) < 0.05
    assert rel(r.values[R + "coulomb_N"], 34.2) < 0.10


def test_table_damper_recovered():
    t = syn.DAMPER_TABLE
    r = dfit.fit_damper(syn.damper_record(t, seed=8), "table")
    truth = syn.truth_fork(t).damper
    v = np.asarray(r.values[D + "velocity_mm_per_s"])
    f = np.asarray(r.values[D + "force_N"])
    assert len(v) >= 4 and np.all(np.diff(v) > 0) and np.all(np.diff(f) >= 0) and 0.0 in v
    fast = np.abs(v) >= 50
    expected = np.array([truth.force(x * 1e-3) for x in v[fast]])
    assert np.all(np.abs(f[fast] - expected) <= 0.05 * np.abs(expected) + 1.0)
    assert rel(r.values[R + "coulomb_N"], t[R + "coulomb_N"]) < 0.10


def test_stribeck_chosen_by_bic_when_low_speeds_show_it(stribeck_damper_record):
    t = syn.DAMPER_STRIBECK
    fits = dfit.fit_damper_all(stribeck_damper_record)
    best = dfit.select({k: fits[k] for k in dfit.FRICTION})
    assert best.extra["friction"] == "stribeck"
    assert best.bic < fits["coulomb"].bic - 10
    assert fits["coulomb"].rms >= 2.0 * best.rms
    assert best.extra["supported"] is True
    for key in ("coulomb_N", "breakaway_N"):
        assert rel(best.values[R + key], t[R + key]) < 0.10, key
    assert rel(best.values[D + "compression_N_s_per_m"], t[D + "compression_N_s_per_m"]) < 0.05
    assert rel(best.values[D + "rebound_N_s_per_m"], t[D + "rebound_N_s_per_m"]) < 0.05


def test_lugre_bristles_are_not_invented(stribeck_damper_record):
    r = dfit.fit_damper(stribeck_damper_record, "lugre")
    assert R + "bristle_stiffness_N_per_mm" not in r.values
    assert R + "bristle_stiffness_N_per_mm" in r.extra["unidentified"]
    assert any("pre-sliding" in n for n in r.extra["notes"])


def test_damper_overrides_load_and_set_up(bilinear_damper_record):
    for name, r in dfit.fit_damper_all(bilinear_damper_record).items():
        compose.setup(mtbmj.load_config("reference", r.overrides()))


def test_damper_mat_and_csv_give_the_same_fit(tmp_path, bilinear_damper_record):
    a = read_record(syn.write_csv(tmp_path / "damper.csv", bilinear_damper_record))
    b = read_record(syn.write_mat(tmp_path / "damper.mat", bilinear_damper_record))
    ra, rb = dfit.fit_damper(a, "bilinear"), dfit.fit_damper(b, "bilinear")
    for key, value in ra.values.items():
        assert rb.values[key] == pytest.approx(value, rel=1e-6), key
    peaks = read_record(syn.write_damper_record(tmp_path / "peaks.csv", syn.DAMPER_BILINEAR, peaks=True, seed=3))
    assert set(peaks.columns) == {"velocity", "force"}
    assert dfit.fit_damper(peaks, "bilinear").values[D + "rebound_N_s_per_m"] == pytest.approx(
        ra.values[D + "rebound_N_s_per_m"], rel=1e-3)


def test_plot_damper_returns_a_figure(bilinear_damper_record):
    fits = dfit.fit_damper_all(bilinear_damper_record)
    fig = dfit.plot_damper(bilinear_damper_record, fits)
    assert len(fig.axes) == 2

"""One time-zero rule for sled records (mtbmj/measured/time_zero.py), used by validate, fit drop and
the API: records made by the package's generators and by `mtbmj drop`, cut at random lengths,
with and without free fall and clock offset, find their touch, validate against their own
configuration within the noise and fit back to their parameters."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from mtbmj.drop.chain import resolve
from mtbmj.drop.run import run_drop
from mtbmj.identify.drop_synthetic import drop_record_columns, make_drop_record
from mtbmj.identify.dropfit import fit_drop
from mtbmj.measured.records import write_csv_text
from mtbmj.measured import sled as sled_data, time_zero
from mtbmj.validation.report import run_validation


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "mtbmj.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def s12_trace():
    """A 1.2 s S12 drop on the ODE reference, reused by the cut records below."""
    return drop_record_columns("S12", duration=1.2, engine="ode", noise_mm=0.0, fall_s=0.2, clock_offset_s=0.0)


RNG = np.random.default_rng(20261123)
CASES = [(float(RNG.uniform(0.3, 1.1)), float(RNG.choice([0.0, RNG.uniform(0.003, 0.2)])),
          float(RNG.uniform(-5.0, 50.0)), int(RNG.integers(1000))) for _ in range(8)]


@pytest.mark.parametrize("length_s, fall_s, offset_s, seed", CASES)
def test_touch_found_on_random_cuts_and_clocks(s12_trace, length_s, fall_s, offset_s, seed):
    columns, _ = s12_trace
    t = columns["time_s"]
    keep = (t >= -fall_s - 1e-9) & (t <= length_s)
    rng = np.random.default_rng(seed)
    noise = lambda n: rng.normal(0.0, 0.05, n)  # noqa: E731
    sled = columns["sled_mm"][keep] + noise(keep.sum())
    fork = columns["fork_mm"][keep] + noise(keep.sum())
    rec = sled_data.from_arrays(t[keep] + offset_s, sled, fork, name="cut")
    assert rec.touch.kind == ("free fall" if fall_s >= 0.003 else "starts at impact")
    assert rec.touch_s == pytest.approx(offset_s, abs=1e-4)
    assert rec.touch.describe() in rec.info()["time_zero"]


def test_validate_own_record_without_free_fall_is_within_the_noise():
    """The issue's case: a 0.6 s record starting at touch (after lift-off it lands again); before,
    the landing was taken for the touch and S12 was 37 mm off itself."""
    record = make_drop_record("S12", duration=0.6, engine="mujoco", seed=4)
    v = run_validation(sled_data.load(record), ["S12"], workers=1)
    assert v.record.touch.kind == "starts at impact" and v.record.touch_s == 0.0
    signal, event, worst = v.metrics["S12"].worst_amplitude()
    assert abs(worst) < 0.3, (signal, event, worst)


@pytest.mark.parametrize("fall_s, offset_s, duration", [(0.05, 7.3, 0.45), (0.4, 123.456, 0.8)])
def test_validate_logger_clock_record_against_its_own_configuration(tmp_path, fall_s, offset_s, duration):
    truth = {"fork.spring.preload_N": 231.0, "tire.impact_rate_N_per_mm": 77.0}
    make_drop_record("S12", truth, duration=duration, engine="mujoco", seed=11, fall_s=fall_s,
                     clock_offset_s=offset_s, path=tmp_path / "logger.csv")
    truth_config = resolve("S12", truth)
    v = run_validation(tmp_path / "logger.csv", [truth_config], workers=1)
    assert v.record.touch.kind == "free fall"
    assert v.record.touch_s == pytest.approx(offset_s, abs=1e-4)
    _, _, worst = v.metrics[v.configs[0]].worst_amplitude()
    assert abs(worst) < 0.3


def test_mtbmj_drop_output_cut_validates_against_itself(tmp_path):
    out = tmp_path / "drop"
    done = run_cli("drop", "S12", "--duration", "0.7", "--out", out)
    assert done.returncode == 0, done.stderr
    csv = next(p for p in out.iterdir() if p.suffix == ".csv" and "raw" not in p.name)
    lines = csv.read_text().splitlines()
    body = [ln for ln in lines if not ln.startswith("#")]
    cut = tmp_path / "cut.csv"
    cut.write_text("\n".join(body[:1 + 420]) + "\n")  # the header and 0.42 s
    v = run_validation(cut, ["S12"], workers=1)
    assert v.record.touch.kind == "starts at impact"
    _, _, worst = v.metrics["S12"].worst_amplitude()
    assert abs(worst) < 0.05  # the same engine, no noise


def test_fit_drop_logger_clock_record_recovers_two_parameters():
    """The issue's case: a logger record starting 50 ms before touch at t = 7.3 s (ODE reference,
    fitted on MuJoCo); before, 102 N/mm and 255 N for 75 N/mm and 200 N."""
    truth = {"tire.impact_rate_N_per_mm": 75.0, "fork.spring.preload_N": 200.0}
    record = make_drop_record("S12", truth, duration=0.6, engine="ode", seed=5, fall_s=0.05, clock_offset_s=7.3)
    result = fit_drop(record, "S12", free=list(truth), bounds={"tire.impact_rate_N_per_mm": (40, 120),
                                                               "fork.spring.preload_N": (120, 320)})
    for key, true in truth.items():
        assert result.values[key] == pytest.approx(true, rel=0.01), key
        low, high = result.extra["ci95"][key]
        assert low <= true <= high, key
    assert result.extra["time_zero"]["kind"] == "free fall"
    assert result.extra["time_zero"]["touch_in_file_s"] == pytest.approx(7.3, abs=1e-4)


def test_touch_given_overrides_and_is_checked():
    columns, _ = drop_record_columns("S12", duration=0.4, engine="mujoco", fall_s=0.1, clock_offset_s=2.0)
    found = time_zero.find_touch(columns["time_s"], columns["tire_mm"], "r", touch_s=2.001)
    assert found.kind == "given" and found.touch_s == 2.001
    with pytest.raises(time_zero.TouchError, match="not within the record"):
        time_zero.find_touch(columns["time_s"], columns["tire_mm"], "r", touch_s=9.0)


def test_record_starting_loaded_is_refused_in_one_line(tmp_path):
    columns, comments = drop_record_columns("S12", duration=0.6, engine="mujoco")
    keep = columns["time_s"] >= 0.03  # starts mid-impact
    path = tmp_path / "loaded.csv"
    path.write_text(write_csv_text({k: v[keep] for k, v in columns.items()}, comments))
    for args in (["validate", path, "S12"], ["fit", "drop", path, "--free", "fork.spring.preload_N"]):
        done = run_cli(*args, "--out", tmp_path / "out")
        assert done.returncode == 2
        assert len(done.stderr.strip().splitlines()) == 1 and "already deflected" in done.stderr
        assert not (tmp_path / "out").exists()
    # the same record with time zero given is accepted (the user takes the responsibility)
    rec = sled_data.read_sled(path, touch_s=0.0)
    assert rec.touch.kind == "given" and rec.time_s[0] == pytest.approx(0.03)


def test_validate_options_and_positionals_in_any_order(tmp_path):
    """The README's command shape: the record, then --presets, then a configuration file."""
    config = tmp_path / "my_fork.toml"
    config.write_text('base = "S12"\n[fork.spring]\npreload_N = 240.0\n')
    done = run_cli("validate", "example", "--presets", "S12", config, "--duration", "0.3", "--workers", "1",
                   "--out", tmp_path / "v")
    assert done.returncode == 0, done.stderr
    assert "2 configurations" in done.stdout and "time zero" in done.stdout


def test_bad_touch_option_is_one_line(tmp_path):
    done = run_cli("validate", "example", "S12", "--touch-s", "99", "--out", tmp_path / "v")
    assert done.returncode == 2 and "not within the record" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_run_drop_logged_signals_are_what_the_generator_logs():
    """Without fall, offset and noise the generator is run_drop's logged view (same filter)."""
    columns, _ = drop_record_columns("S12", duration=0.3, engine="mujoco", noise_mm=0.0, adc_bits=40)
    logged = run_drop("S12", "mujoco", duration=0.3).signals
    assert np.max(np.abs(columns["sled_mm"] - logged["sled_mm"])) < 1e-6


def test_fall_parabola_gives_touch_on_a_closed_form_record():
    """A record computed in the test: free fall from 95 mm through a 400 Hz analog-like delay
    (a ramp delayed by the filter's group delay), then a linear tire at rest; touch off a sample."""
    g, h = 9806.65, 95.0
    v = np.sqrt(2 * g * h)
    touch = 3.21234
    t = np.arange(3.0, 3.6, 0.001)
    delay = time_zero.antialias_delay_s(400.0)
    tau = t - delay - touch
    gap = np.where(tau < 0, v * tau + 0.5 * g * tau**2, 20.0 * (1 - np.exp(-tau / 0.01)))
    found = time_zero.find_touch(t, np.maximum(gap, -h), "closed form")
    assert found.kind == "free fall"
    assert found.touch_s == pytest.approx(touch, abs=2e-5)
    assert found.impact_speed_m_per_s == pytest.approx(v * 1e-3, rel=1e-3)


def test_fork_topping_time_is_where_it_reaches_full_extension():
    """The fork's topping is the start of its plateau at full extension: the same under sensor
    noise (a plateau's minimum would wander along it) and shifted with the run."""
    from mtbmj.drop.events import detect

    signals = run_drop("S12", "mujoco", duration=0.8).signals
    clean = detect(signals).get("fork", "topping")
    rng = np.random.default_rng(8)
    for seed in range(3):
        noisy = dict(signals)
        r = np.random.default_rng(seed)
        noisy["sled_mm"] = signals["sled_mm"] + r.normal(0, 0.1, signals["sled_mm"].size)
        noisy["fork_mm"] = signals["fork_mm"] + r.normal(0, 0.1, signals["fork_mm"].size)
        noisy["tire_mm"] = noisy["sled_mm"] - noisy["fork_mm"]
        assert detect(noisy).get("fork", "topping").time_s == pytest.approx(clean.time_s, abs=0.004)
    shift = float(rng.uniform(0.003, 0.02))
    late = {k: (v + shift if k == "time_s" else v) for k, v in signals.items()}
    assert detect(late, start_s=shift).get("fork", "topping").time_s == pytest.approx(clean.time_s + shift, abs=5e-4)
    # at that moment the fork is within the band of its value at full extension, and before it is not
    t, fork = signals["time_s"], signals["fork_mm"]
    assert np.interp(clean.time_s + 0.002, t, fork) <= clean.value_mm + 0.5
    assert np.interp(clean.time_s - 0.01, t, fork) > clean.value_mm + 0.3


def test_mtbmj_drop_output_fits_back_to_its_parameters(tmp_path):
    """`mtbmj drop` with two values changed (drawn at random), cut at a random length >= 0.3 s,
    fitted from the unchanged S12 on the other engine: back within 1 %."""
    import json

    rng = np.random.default_rng(31)
    truth = {"fork.spring.preload_N": round(float(rng.uniform(200, 260)), 1),
             "tire.impact_rate_N_per_mm": round(float(rng.uniform(70, 90)), 1)}
    length = float(rng.uniform(0.3, 0.6))
    sets = [a for k, v in truth.items() for a in ("--set", f"{k}={v}")]
    done = run_cli("drop", "S12", *sets, "--engine", "ode", "--duration", "0.7", "--out", tmp_path / "drop")
    assert done.returncode == 0, done.stderr
    lines = (tmp_path / "drop" / "timeseries.csv").read_text().splitlines()
    body = [ln for ln in lines if not ln.startswith("#")]
    (tmp_path / "cut.csv").write_text("\n".join(body[:1 + int(length * 1000)]) + "\n")
    done = run_cli("fit", "drop", tmp_path / "cut.csv", "--free", ",".join(truth), "--out", tmp_path / "fit")
    assert done.returncode == 0, done.stderr
    assert "the record starts at impact" in done.stdout
    fitted = json.loads((tmp_path / "fit" / "fit.json").read_text())["parameter_set"]
    for key, value in truth.items():
        assert fitted[key] == pytest.approx(value, rel=0.01), key

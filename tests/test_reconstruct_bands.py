"""When the rear moves, band by band (mtbmj/ride/reconstruct_bands.py, issue 51): the timing reported
with each band of the rear's check, on series written here (200 Hz, 120 s) whose timing is known by
construction: a terrain of band-limited noise met by the front at t and by the rear at t + lag, the
lag a wheelbase over a speed that varies, and a body part the two ends share at the same moment.
Nothing of the package makes these series; the check is that the reported shifts and correlations are
the ones built in, and that a prediction with the ride's timing is told apart from one a wheelbase
late and from one of another ride."""
from __future__ import annotations

import math

import numpy as np
from scipy.signal import butter, sosfiltfilt

from mtbmj.ride import reconstruct
from mtbmj.ride.reconstruct_bands import band_checks, timing

from helpers import WRITTEN_FS, WRITTEN_SECONDS, WRITTEN_WHEELBASE, written_clock

FS, SECONDS, WHEELBASE = WRITTEN_FS, WRITTEN_SECONDS, WRITTEN_WHEELBASE
t, speed, LAGS, valid = written_clock()  # speed m/s, LAGS s (0.17-0.24), valid: the checked samples


def noise(seed, lo=2.5, hi=8.0, scale=40.0):
    sos = butter(4, (lo, hi), btype="bandpass", fs=FS, output="sos")
    return scale * sosfiltfilt(sos, np.random.default_rng(seed).standard_normal(t.size))


def delayed(x, q=1.0):
    """x read q lags later: x(t - q lag(t))."""
    return np.interp(t - q * LAGS, t, x)


def wheels_band(rear, predicted, fork):
    bands = {tuple(b["band_Hz"]): b for b in band_checks(t, rear, predicted, delayed(fork), valid, fork=fork,
                                                          lags=LAGS)}
    return bands[(2.0, 10.0)]


def test_a_prediction_with_the_rides_timing_peaks_at_no_shift():
    """The rear meets the front's terrain a lag later; the prediction is that, with noise of its own:
    its correlation peaks at a shift of 0 lags, the fork's record correlates with the rear at the lag
    and not at once."""
    ground = noise(1)
    rear = 40.0 + delayed(ground)
    band = wheels_band(rear, 40.0 + delayed(ground) + 0.3 * noise(2), ground)
    tm = band["timing"]
    assert tm["shift_lags"] == 0.0 and tm["shift_correlation"] > 0.9
    assert tm["fork_at_lag_correlation"] > 0.95 and abs(tm["fork_now_correlation"]) < 0.3
    assert band["predicted_correlation"] > 0.9


def test_a_rear_that_answers_the_front_at_once_peaks_a_wheelbase_early():
    """A rear that moves when the front meets the terrain (the body's part, the same moment at both
    ends) and a prediction that answers a wheelbase later: the prediction correlates best read one lag
    earlier (shift -1), near zero where it is read; the fork's record correlates with the rear at
    once, not at the lag."""
    ground = noise(3)
    rear = 40.0 + ground  # at once
    band = wheels_band(rear, 40.0 + delayed(ground), ground)
    tm = band["timing"]
    assert tm["shift_lags"] == -1.0 and tm["shift_correlation"] > 0.95
    assert abs(band["predicted_correlation"]) < 0.3
    assert tm["fork_now_correlation"] > 0.95 and abs(tm["fork_at_lag_correlation"]) < 0.3
    assert not band["described"]  # predicting nothing beats a prediction that is a wheelbase late


def test_a_speed_off_by_a_fifth_moves_the_peak_by_a_fifth():
    """The rear meets the terrain at the lag of a speed 25 % higher than the one the lags are read at
    (its lag 0.8 of them): the prediction made at the stated lags peaks 0.2 lags early."""
    ground = noise(4)
    rear = 40.0 + delayed(ground, 0.8)
    tm = wheels_band(rear, 40.0 + delayed(ground), ground)["timing"]
    assert tm["shift_lags"] == -0.2 and tm["shift_correlation"] > 0.95
    by = dict((q, r) for q, r in tm["correlation_by_shift"])
    assert by[0.0] < tm["shift_correlation"] - 0.1  # at the stated lag the timing error costs correlation


def test_a_prediction_of_another_ride_has_no_peak():
    """A prediction of another draw of terrain: no shift makes it correlate (the best within 0.15)."""
    ground = noise(5)
    tm = wheels_band(40.0 + delayed(ground), 40.0 + delayed(noise(6)), ground)["timing"]
    assert abs(tm["shift_correlation"]) < 0.15


def test_the_timing_is_in_every_band_of_a_reconstruction_with_a_speed():
    """Reconstruction.checks() reports the timing in each band where the reconstruction has a speed
    (its lags wheelbase / speed(t)), and none where it has none (the band checks as before). The wheels'
    band peaks at no shift; the slower bands' correlations hardly change over a lag (their periods are
    seconds, the lag a fifth of one), so there the correlation at no shift is within 0.01 of the best."""
    ground = noise(7, 0.1, 8.0)
    rear = 40.0 + delayed(ground)
    sp = {"windows": [], "speed_at": lambda x: np.interp(x, t, speed)}
    rec = reconstruct.Reconstruction("r", "b", t, sp, t, t, valid, 40.0 + ground, 40.0 + ground, rear,
                                     rear + 0.2 * noise(8, 0.1, 8.0), 150.0, [], fork_delayed=40.0 + delayed(ground),
                                     wheelbase=WHEELBASE)
    np.testing.assert_allclose(rec.lags, LAGS)
    bands = rec.checks()["bands"]
    assert len(bands) == 3 and bands[2]["timing"]["shift_lags"] == 0.0
    for b in bands:
        by = dict((q, r) for q, r in b["timing"]["correlation_by_shift"])
        assert by[0.0] > b["timing"]["shift_correlation"] - 0.01 and by[0.0] > 0.9
    bare = reconstruct.Reconstruction("r", "b", t, {"windows": []}, t, t, valid, 40.0 + ground, 40.0 + ground, rear,
                                      rear, 150.0, [], fork_delayed=40.0 + delayed(ground))
    assert bare.lags is None and all("timing" not in b for b in bare.checks()["bands"])


def test_timing_alone_on_a_pure_delay():
    """timing() on a sine of one period read 0.5 lag late against the rear: the peak at +0.5 (the
    prediction moved later correlates best; shifts are searched from -1.5 to +0.5)."""
    x = np.sin(2 * math.pi * 3.0 * t)
    lags = np.full(t.size, 0.04)  # s; half a lag is 0.02 s, well inside the 3 Hz period (0.33 s)
    tm = timing(t, np.interp(t - 0.02, t, x), x, x, lags, valid)
    assert tm["shift_lags"] == 0.5 and tm["shift_correlation"] > 0.999


def test_the_fork_at_once_is_reported_beside_and_does_not_judge():
    """A rear that is the fork's record at the same moment, scaled and offset (0.6 x + 12 mm): the fork
    at once reproduces it (its RMS 0), the delayed fork does not; a prediction equal to the rear still
    passes and one equal to the delayed fork's fit does not (the verdict is the two baselines' alone)."""
    ground = noise(9, 0.3, 8.0)
    fork = 40.0 + ground
    rear = 12.0 + 0.6 * fork
    sp = {"windows": [], "speed_at": lambda x: np.interp(x, t, speed)}

    def checks(predicted):
        return reconstruct.Reconstruction("r", "b", t, sp, t, t, valid, fork, fork, rear, predicted, 150.0, [],
                                          fork_delayed=delayed(fork), wheelbase=WHEELBASE).checks()

    right = checks(rear.copy())
    assert right["fork_at_once_rms_mm"] < 1e-6 and right["baseline_delayed_fork_rms_mm"] > 5.0
    assert right["passes"]
    late = checks(12.0 + 0.6 * delayed(fork))
    assert not late["passes"] and late["fork_at_once_rms_mm"] < 1e-6


def test_the_share_met_at_once_is_the_one_mixed_in():
    """at_once_share on series written here: a rear that is 0.3 of a prediction met at once and 0.7 of
    one met at the lag, with an offset of its own (the share is timing, never a height), gives 0.3; a
    rear beyond either end is clipped to 0 or 1; two predictions that do not differ give 0."""
    from mtbmj.ride.reconstruct import at_once_share

    ground = noise(10, 0.3, 8.0)
    at_lag, at_once = 40.0 + delayed(ground), 45.0 + ground
    rear = 0.7 * at_lag + 0.3 * at_once + 9.0
    assert abs(at_once_share(rear, at_lag, at_once, valid) - 0.3) < 1e-9
    assert at_once_share(at_lag + 0.5 * (at_lag - at_once), at_lag, at_once, valid) == 0.0
    assert at_once_share(at_once + 0.5 * (at_once - at_lag), at_lag, at_once, valid) == 1.0
    assert at_once_share(rear, at_lag, at_lag.copy(), valid) == 0.0
    noisy = rear + 0.5 * noise(11, 0.3, 8.0)  # a rear with noise of its own: the share still found
    assert abs(at_once_share(noisy, at_lag, at_once, valid) - 0.3) < 0.05


def test_the_rears_ground_met_at_once_is_mixed_from_the_two_timings():
    """reconstruct_bike.rear_ground: none at once is the ground a lag behind; all at once is the ground
    under the front at the same moment; a share between mixes the two linearly."""
    from mtbmj.ride.reconstruct_bike import rear_ground

    ground = noise(12, 0.3, 8.0) * 1e-3
    np.testing.assert_allclose(rear_ground(t, LAGS, ground), delayed(ground))
    np.testing.assert_allclose(rear_ground(t, LAGS, ground, 1.0), ground)
    np.testing.assert_allclose(rear_ground(t, LAGS, ground, 0.25), 0.75 * delayed(ground) + 0.25 * ground)


def test_the_share_met_at_once_from_the_command_line_is_reported_not_judged(tmp_path):
    """``mtbmj reconstruct RIDE --at-once``: ``reconstruction.json`` carries ``at_once_fit`` (its share within
    0-1, the rear's error with it, marked not judged) and the verdict is the one without it."""
    import json

    from mtbmj.cli import main

    out, plain = tmp_path / "at_once", tmp_path / "plain"
    assert main(["reconstruct", "example", "--bike", "sst", "--at-once", "--out", str(out)]) == 0
    assert main(["reconstruct", "example", "--bike", "sst", "--out", str(plain)]) == 0
    d, p = (json.loads((o / "reconstruction.json").read_text()) for o in (out, plain))
    fit = d["at_once_fit"]
    assert 0.0 <= fit["share"] <= 1.0 and fit["judged"] is False and fit["rear_predicted_rms_mm"] > 0.0
    assert d["checks"]["verdict"] == p["checks"]["verdict"] and p.get("at_once_fit") is None


def test_the_checks_are_worked_out_once_and_again_where_a_field_is_set_anew(monkeypatch):
    """``checks()`` is asked several times of one reconstruction (its own refinement, advice's gate, its
    summary): worked out once while its fields stay the objects they were; set the prediction anew and
    it is worked out again (a rear predicted as the rear itself then passes where a poor one failed);
    a caller's change to the answer does not reach the next caller's."""
    ground = noise(7, 0.1, 8.0)
    rear = 40.0 + delayed(ground)
    rec = reconstruct.Reconstruction("r", "b", t, {"windows": []}, t, t, valid, 40.0 + ground, 40.0 + ground, rear,
                                     40.0 + noise(9, 0.1, 8.0), 150.0, [], fork_delayed=40.0 + delayed(ground))
    worked = []
    real = reconstruct.Reconstruction._checked
    monkeypatch.setattr(reconstruct.Reconstruction, "_checked", lambda self: worked.append(1) or real(self))
    first = rec.checks()
    assert not first["passes"] and rec.checks() == first and len(worked) == 1
    first["passes"] = "changed by a caller"
    first["bands"].clear()
    assert rec.checks()["passes"] is False and rec.checks()["bands"] and len(worked) == 1
    rec.rear_predicted = rear.copy()
    again = rec.checks()
    assert len(worked) == 2 and again["passes"] and again["rear_predicted_rms_mm"] == 0.0

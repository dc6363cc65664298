"""The speed's windows the rest of the ride contradicts (mtbmj/ride/reconstruct_speed.py:
``drop_unsupported``, issue 51 item 1), on window lists written here and on the shared ride whose
lone 1.42 m/s window among about 9.5 squeezed the reconstructed terrain under it until the
recorded bike crashed on it."""
from __future__ import annotations

import os
from argparse import Namespace

import numpy as np
import pytest

from mtbmj.ride.reconstruct_speed import FAR, OUTLIER, drop_unsupported

from conftest import SHARED_DATA


def windows_of(speeds, sd=0.1):
    """(windows, standard errors, reasons) as speed_from_lag keeps them: one every 2.5 s."""
    return ([(2.5 * k, v, 0.5) for k, v in enumerate(speeds)], [None if v is None else sd for v in speeds],
            [None if v is not None else "below the correlation" for v in speeds])


def kept(speeds, sd=0.1):
    w, s, why = windows_of(speeds, sd)
    drop_unsupported(w, s, why)
    return [v for _, v, _ in w], why


def test_a_window_both_overlapping_neighbours_contradict_gives_no_speed():
    speeds, why = kept([9.0, 9.2, 5.0, 9.1, 9.3])
    assert speeds == [9.0, 9.2, None, 9.1, 9.3]
    assert "where the two windows it overlaps give 9.20 and 9.10" in why[2]
    # within OUTLIER of the neighbours' mean it stands (a rider slowing within 5 s)
    assert kept([9.0, 9.2, 9.15 * (1 - 0.9 * OUTLIER), 9.1, 9.3])[0][2] is not None
    # neighbours that disagree with each other (speeding up) decide nothing about the one between
    assert kept([4.0, 5.0, 9.0, 7.5, 8.0])[0] == [4.0, 5.0, 9.0, 7.5, 8.0]
    # a window whose own uncertainty covers the difference stands
    assert kept([9.0, 9.2, 6.5, 9.1, 9.3], sd=1.0)[0][2] == 6.5


def test_a_lone_window_far_off_the_rides_median_gives_no_speed():
    ride = [None, 10.8, None, None, 9.5, None, 8.6, None, None, 1.42, None, None, 9.9, None]
    speeds, why = kept(ride)
    assert speeds[9] is None and "1.42 m/s, alone" in why[9] and "6.8 times off" in why[9]
    assert [v for i, v in enumerate(speeds) if i != 9] == [v for i, v in enumerate(ride) if i != 9]
    # the same window with a neighbour near it is supported: a slow stretch two windows saw
    supported = ride[:9] + [1.42, 1.6] + ride[11:]
    assert kept(supported)[0][9:11] == [1.42, 1.6]
    # within FAR of the median it stands alone; with fewer than three other windows nothing decides
    assert kept([None, 9.5, None, 9.0, None, 9.2 / (0.95 * FAR), None, 9.9])[0][5] is not None
    assert kept([None, 6.0, None, None, None, 1.3, None])[0] == [None, 6.0, None, None, None, 1.3, None]


@pytest.mark.shared_data("sst", "00649.SST")
def test_the_shared_rides_lone_slow_window_is_dropped_and_the_recorded_bike_rides_its_terrain():
    """00649: its 1.42 m/s window (42.5-47.5 s; the others 8.6-10.8) is dropped with its reason, and
    the recorded setting, calibrated, rides the whole reconstructed terrain without a crash (with the
    window kept, the terrain under it was squeezed 6.8 times and the bike looped out at 46.8 s; the
    advice's own check refuses the ride, which is set aside here to reach the run)."""
    from mtbmj.cli.telemetry import ride_record
    from mtbmj.ride import advise, reconstruct as rc

    record = ride_record(os.path.join(SHARED_DATA, "sst", "00649.SST"), Namespace(bike="sst", fork_max_mm=None,
                                                                                 shock_max_mm=None))
    checks = rc.Reconstruction.checks
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(rc.Reconstruction, "checks", lambda self: {**checks(self), "passes": True,
                                                               "samples_checked_percent": 100.0,
                                                               "rear_predicted_rms_percent_of_used": 0.0})
        ride = advise.prepare(record, "sst", calibrated=True)
    # the two ends' lag: the estimate itself, or its first where the speed was found again from the rear
    # predicted (with the windows tracked between the strict ones the first pass's rear and both naive
    # baselines are level on this ride, 14.6 mm against 14.6 and 14.7, so whether it is found again can
    # turn on a tenth of a millimetre)
    first = ride.rec.speed.get("first", ride.rec.speed)
    speeds = {round(w[0], 1): w[1] for w in first["windows"]}
    assert speeds[42.5] is None and "alone" in first["why"][17] and first["kinds"][17] is None
    assert all(8.0 < v < 11.0 for v in speeds.values() if v is not None)
    run = advise.simulate(ride.bike, ride.base_over, ride.terrain, ride.speed, ride.sim_s, "recorded", ride.lead_s,
                          ride.profile)
    assert run.crash is None, run.crash


def rear_series(seed=4, seconds=30.0, rate=1000.0):
    """A rear's travel made here (mm on t): bumps of random height, length and place along a trail,
    each met by the rear a lag L / v(t) after the front, at a speed v(t) = 6 + 1.2 sin(2 pi t / 20)
    m/s (its distance integrated in closed form), and the same bumps met on a second, wrong lag
    (the first estimate's) by a prediction: (t, recorded, predicted, the first lags, the true speed)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * rate)) / rate
    wheelbase = 1.2
    along = lambda time: 6.0 * time - 1.2 * 20.0 / (2 * np.pi) * (np.cos(2 * np.pi * time / 20.0) - 1.0)  # noqa: E731
    speed = lambda time: 6.0 + 1.2 * np.sin(2 * np.pi * time / 20.0)  # noqa: E731
    centres = np.sort(rng.uniform(-5.0, along(seconds), 400))
    heights, lengths = rng.uniform(5.0, 40.0, centres.size), rng.uniform(0.3, 1.5, centres.size)

    def travel(s):  # mm at the places s (m) along the trail
        u = np.clip((s[:, None] - centres[None, :]) / lengths[None, :] + 0.5, 0.0, 1.0)
        return (heights[None, :] * np.sin(np.pi * u) ** 2).sum(axis=1)

    recorded = travel(along(t) - wheelbase)  # the rear a wheelbase behind the front
    first = np.full(t.size, wheelbase / 6.0)  # the first estimate: one speed, 6 m/s
    predicted = travel(along(t - first))  # the rear predicted over the front's terrain laid at the first lags
    return t, recorded, predicted, first, speed, wheelbase


def test_the_speed_found_again_from_the_rear_predicted_follows_the_ride():
    """``refine``: the lag left between a rear record and a prediction laid at a constant first lag
    (one speed, 6 m/s, where the ride's goes 4.8-7.2 m/s) gives the speed along the ride: every
    window that gives one within issue 51's 3 % of the made speed at its centre (2.5 % at most when
    written, in the window where the speed falls fastest and the first estimate is 20 % off), most
    windows give one, and the profile follows the ride."""
    from mtbmj.ride.reconstruct_speed import refine

    t, recorded, predicted, first, speed, wheelbase = rear_series()
    found = refine(t, recorded, predicted, first, wheelbase)
    w = found["window_s"]
    good = [(a, v) for a, v, _ in found["windows"] if v is not None]
    assert len(good) >= 0.8 * len(found["windows"])
    for a, v in good:
        assert v == pytest.approx(float(speed(a + 0.5 * w)), rel=0.03), (a, v)
    inside = (t > 3.0) & (t < 27.0)
    assert np.max(np.abs(found["speed_at"](t[inside]) / speed(t[inside]) - 1.0)) < 0.03
    assert np.max(np.abs(6.0 / speed(t[inside]) - 1.0)) > 0.2  # the first estimate was that far off


def test_a_rear_that_is_not_the_predictions_gives_no_speed_found_again():
    """The wrong input: a rear record of another trail (other bumps) against the prediction; and a
    rear standing still. Neither aligns: no window gives a speed, and refine says so in one line."""
    from mtbmj.ride.reconstruct_speed import ReconstructError, refine

    t, recorded, predicted, first, _, wheelbase = rear_series()
    _, other, _, _, _, _ = rear_series(seed=99)
    with pytest.raises(ReconstructError, match="do not align at any lag"):
        refine(t, other, predicted, first, wheelbase)
    with pytest.raises(ReconstructError, match="standing"):
        refine(t, np.full(t.size, 20.0), predicted, first, wheelbase)


def test_the_rears_flight_is_left_out_of_the_speed_found_again():
    """``reconstruct_speed.refine``'s ``flights``, on series made here: the rear's record and the rear
    predicted are the same motion (6-20 Hz, the first estimate's lag right: 6 m/s on a 1.2 m
    wheelbase) but for a flight, where the model's rear wheel leaves 20 ms before the ride's and
    springs out from there; both land together. Without the front's flight the window over it reads
    the model's take-off as the speed (2.3 % off when written); given it, every window gives a speed
    within 0.5 % of the true one (0.37 % at most when written)."""
    from mtbmj.ride.reconstruct_speed import refine

    dt, wheelbase, v, land = 1e-3, 1.2, 6.0, 10.4
    t = np.arange(0.0, 20.0, dt)
    lag = wheelbase / v
    rng = np.random.default_rng(5)
    hz, phase = rng.uniform(6.0, 20.0, 40), rng.uniform(0.0, 2.0 * np.pi, 40)
    motion = 2.0 * np.sin(2.0 * np.pi * hz[:, None] * t[None, :] + phase[:, None]).sum(axis=0) / np.sqrt(20.0)

    def flight(off):  # mm: the rear wheel leaves at ``off`` s, its travel springing out ringing, lands at ``land``
        s = t - off
        return np.where((s > 0.0) & (t < land), -40.0 * (1.0 - np.exp(-s / 0.02) * np.cos(2.0 * np.pi * 10.0 * s)), 0.0)

    recorded, predicted, lags = motion + flight(10.0), motion + flight(9.98), np.full(t.size, lag)
    off = lambda sp: [abs(s / v - 1.0) for _, s, _ in sp["windows"] if s is not None]  # noqa: E731
    kept_in = refine(t, recorded, predicted, lags, wheelbase)
    assert max(off(kept_in)) > 0.02  # the check can fail: the model's take-off read as the ride's speed
    left_out = refine(t, recorded, predicted, lags, wheelbase, flights=[(10.0 - lag, land - lag)])
    assert len(off(left_out)) == len(left_out["windows"]) and max(off(left_out)) < 0.005

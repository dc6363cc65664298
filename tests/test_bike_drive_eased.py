"""The whole bike's rider eases off the push as the front lifts (``controllers.drive.eased``, issue 52).

Before, the rider's speed controller pushed at its limits whenever the rear tyre was on the ground,
whatever the frame's pitch: a front wheel thrown up by a rock's face and a bike slowed by it were
driven back up to speed on the rear wheel alone, the push pitching the bike past its balance point
(looped out). A rider stops pedalling when the front comes up unasked."""
import math
import pathlib

import numpy as np
import pytest

from mtbmj.controllers.drive import LIFT_EASE_DEG, eased


def test_the_push_is_cut_from_all_to_none_across_the_lift_angles_with_the_front_in_the_air():
    """``eased`` against its definition written out here: the push kept while the front tyre carries
    load or the drive holds back; with the front in the air, a share 1 - (pitch - lo) / (hi - lo) of
    it, clipped to 0..1."""
    lo, hi = 10.0, 20.0
    for deg, share in ((-5.0, 1.0), (0.0, 1.0), (10.0, 1.0), (12.5, 0.75), (15.0, 0.5), (19.0, 0.1), (20.0, 0.0),
                       (45.0, 0.0)):
        assert eased(300.0, math.radians(deg), False, lo, hi) == pytest.approx(300.0 * share, abs=1e-9)
        assert eased(300.0, math.radians(deg), True, lo, hi) == 300.0  # the front on the ground: untouched
        assert eased(-200.0, math.radians(deg), False, lo, hi) == -200.0  # holding back: untouched
    assert eased(300.0, math.radians(15.0), False, *LIFT_EASE_DEG) == pytest.approx(300.0 * (1.0 - (15.0 - LIFT_EASE_DEG[0]) / (LIFT_EASE_DEG[1] - LIFT_EASE_DEG[0])))


def _ledge_bike(folder: pathlib.Path) -> str:
    from helpers import bike_text

    bike = folder / "bike.toml"
    bike.write_text(bike_text(5.0))  # the advice tests' bike with its fork far too soft (issue 52's case)
    return str(bike)


def _ledge():
    """A ledge written here: level ground, then a face 0.3 m high rising over 0.6 m at 10 m, level on top."""
    from mtbmj.rolling.terrain import Terrain

    return Terrain("ledge", np.array([-60.0, 10.0, 10.6, 200.0]), np.array([0.0, 0.0, 0.3, 0.3]), 0.0, 20.0, {})


def test_a_bike_thrown_up_by_a_ledge_is_not_driven_over_backwards(tmp_path, monkeypatch):
    """The soft-forked bike at 6.8 m/s into a 0.3 m ledge (written here): its front thrown up, the rider's
    drive that pushes on with the front in the air (the drive before: never eased) loops it out; eased,
    it rides on, its pitch within 2 deg of the same bike coasting over the ledge with no drive at all
    (the reference no push can pitch; measured 26.0 against 25.1 deg, the old drive looped out at
    2.29 s), and it holds no push while the front is in the air more than the lift angles' top."""
    from mtbmj.bike import callback, callback_compiled
    from mtbmj.bike.run import run_bike

    bike = _ledge_bike(tmp_path)
    coast = run_bike(bike, _ledge(), 6.8, duration=4.0, drive="coast")
    assert coast.summary.get("crash") is None
    eased_run = run_bike(bike, _ledge(), 6.8, duration=4.0, drive="rider")
    assert eased_run.summary.get("crash") is None
    raw = eased_run.raw
    assert raw["pitch_deg"].max() > LIFT_EASE_DEG[1]  # the ledge does throw the front up past the lift angles
    assert raw["pitch_deg"].max() <= coast.raw["pitch_deg"].max() + 2.0
    lifted = (raw["front_tire_N"] <= 0.0) & (raw["pitch_deg"] >= LIFT_EASE_DEG[1])
    assert lifted.any() and raw["drive_force_N"][lifted].max() <= 0.0
    assert raw["speed_m_per_s"][-1] == pytest.approx(6.8, abs=0.2)  # and the rider is back at his speed after
    # the drive before (never eased): the same ride loops out
    for module in (callback, callback_compiled):
        monkeypatch.setattr(module, "LIFT_EASE_DEG", (1e3, 1e3 + 1.0))
    old = run_bike(bike, _ledge(), 6.8, duration=4.0, drive="rider")
    assert old.summary.get("crash") is not None and old.summary["crash"]["kind"] == "looped out"

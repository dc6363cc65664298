"""The telemetry sensors' calibration from a bike file (issue 41 item 1): a ride recorded with other
sensor arms than the SST example's decodes to its own travel when the bike file gives them
([sensors]), and to something else without; a triangle that cannot close is refused naming the key.
The counts are written in tests/helpers.py by inverting the sensors' geometry (law of cosines), not by the reader."""
from __future__ import annotations

import numpy as np
import pytest

from mtbmj.cli import main

from helpers import SENSORS_TOML, write_v3


def _ride(path, seconds=40.0, rate=1000):
    t = np.arange(int(seconds * rate)) / rate
    fork = 60.0 + 50.0 * np.sin(2 * np.pi * 1.3 * t)  # 10-110 mm
    shock = 20.0 + 15.0 * np.sin(2 * np.pi * 1.1 * t)  # 5-35 mm
    write_v3(path, fork, shock, rate=rate)


BIKE = f"""base = "sst"
{SENSORS_TOML}"""


def test_the_bike_files_sensors_decode_the_ride(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    _ride(tmp_path / "ride.SST")
    (tmp_path / "bike.toml").write_text(BIKE)
    assert main(["telemetry", "ride.SST", "--bike", "bike.toml", "--out", "tel"]) == 0
    import re

    def fork_max(text):
        return float(re.search(r"fork max \d+ % \(([\d.]+) of 180 mm\)", text).group(1))

    # the sine's own maximum, 110 mm, within the encoder's resolution (2 pi / 4096 of a 150 mm arm: 0.23 mm)
    assert fork_max(capsys.readouterr().out) == pytest.approx(110.0, abs=0.25)
    assert main(["telemetry", "ride.SST", "--bike", "sst", "--out", "tel2"]) == 0  # the example's sensors
    assert abs(fork_max(capsys.readouterr().out) - 110.0) > 5.0


@pytest.mark.parametrize("text,said", [
    ("[sensors]\nfork_arm_mm = 100\nfork_max_mm = 250\n", "sensors.fork_max_mm: 250 mm is not shorter than the two arms"),
    ("[sensors]\nfork_arm_mm = 100\n", "sensors.fork_max_mm: 234.156 mm is not shorter than the two arms (200 mm)"),
    ("[sensors]\nshock_arm1_mm = 50\nshock_arm2_mm = 60\nshock_max_mm = 200\n", "that triangle does not close"),
    ("[sensors]\nshock_arm1_mm = -5\n", "sensors.shock_arm1_mm: must be a positive number"),
])
def test_a_sensor_that_cannot_be_is_refused(tmp_path, monkeypatch, capsys, text, said):
    monkeypatch.chdir(tmp_path)
    _ride(tmp_path / "ride.SST", seconds=1.0)
    (tmp_path / "bike.toml").write_text('base = "sst"\n' + text)  # a key changed on the SST bike's sensors
    assert main(["telemetry", "ride.SST", "--bike", "bike.toml", "--out", "tel"]) == 2
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err

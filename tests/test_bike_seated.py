"""``mtbmj bike --seated``: the rider on the saddle, held rigid on the frame at
``rider.seated_com_mm``. The static tyre loads carry the whole weight and balance its moment about
the rear axle, summed here body by body from the bike file (the seated rider's centre of mass, not
the standing one's); a bike file with no seated rider is refused naming the key."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from mtbmj.bike import spec as spec_mod
from mtbmj.bike.model import frame_body
from mtbmj.cli import main

PRESET = Path(spec_mod.__file__).resolve().parent / "presets" / "sst.toml"


def test_the_seated_rider_loads_the_tyres_by_its_own_centre_of_mass(tmp_path, capsys):
    out = tmp_path / "seated"
    assert main(["bike", "sst", "flat", "--speed", "3", "--duration", "0.2", "--seated", "--out", str(out)]) == 0
    assert "bike sst (seated)" in capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    spec = spec_mod.load("sst")
    g = 9.81  # the presets' gravity (fork configuration S12)
    front, rear = s["static_front_load_N"], s["static_rear_load_N"]
    assert front + rear == pytest.approx(spec.total_mass * g, rel=1e-4)
    # the moment about the rear contact at rest, every body where the first row of the time series
    # puts it: the frame's pitch, the fork's travel along its axis, the swingarm turned to the rear
    # wheel's travel about the main pivot (solved here), the contacts under the axles (flat ground)
    lines = [line for line in (out / "timeseries.csv").read_text().splitlines() if not line.startswith("#")]
    row = dict(zip(lines[0].split(","), map(float, lines[1].split(","))))
    th, X = math.radians(float(row["pitch_deg"])), float(row["x_m"])
    world = lambda p: X + math.cos(th) * p[0] - math.sin(th) * p[1]
    a = spec.head_angle
    fork = float(row["front_travel_mm"]) * 1e-3
    front_axle = (spec.front_axle[0] - fork * math.cos(a), spec.front_axle[1] + fork * math.sin(a))
    rho = np.subtract(spec.rear_axle, spec.pivot)

    def arm(phi):  # the rear axle turned by phi (rear wheel up) about the pivot, frame coordinates
        c, sn = math.cos(phi), math.sin(phi)
        return spec.pivot[0] + c * rho[0] + sn * rho[1], spec.pivot[1] - sn * rho[0] + c * rho[1]

    w = float(row["rear_travel_mm"]) * 1e-3
    phi = brentq(lambda f: arm(f)[1] - spec.rear_axle[1] - w, -0.5, 0.8)
    rear_axle = arm(phi)
    m_frame, c_frame, _ = frame_body(spec)
    r = spec.rider
    bodies = [(m_frame, c_frame), (r.mass, r.seated_com), (spec.fork_lower_mass + spec.front_wheel_mass, front_axle),
              (spec.rear_wheel_mass, rear_axle), (spec.swingarm_mass, tuple((np.add(spec.pivot, rear_axle)) / 2))]
    assert sum(m for m, _ in bodies) == pytest.approx(spec.total_mass)
    x_rear = world(rear_axle)
    moment = sum(m * g * (world(p) - x_rear) for m, p in bodies)
    assert front * (world(front_axle) - x_rear) == pytest.approx(moment, rel=2e-3)
    assert main(["bike", "sst", "flat", "--speed", "3", "--duration", "0.2", "--out", str(tmp_path / "standing")]) == 0
    standing = json.loads((tmp_path / "standing" / "summary.json").read_text())
    assert standing["static_front_load_N"] > front + 100.0  # seated, the weight moves to the rear
    assert not math.isclose(standing["static_rear_load_N"], rear, rel_tol=0.05)


def test_a_bike_without_a_seated_rider_is_refused(tmp_path, capsys):
    bike = tmp_path / "standing.toml"
    bike.write_text("\n".join(line for line in PRESET.read_text().splitlines() if not line.startswith(("seated_com", "seat_tube_angle_deg", "saddle_height_mm"))))
    out = tmp_path / "out"
    assert main(["bike", str(bike), "flat", "--speed", "3", "--seated", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rider.seated_com_mm" in err[0]
    assert not out.exists()


def test_the_active_rider_seated_is_said_in_the_headline():
    """``--seated --rider active``: the body sits on the saddle unheld (no lock), and the headline (the
    command's line), which said "(seated)" only beside a lock, said nothing of it. The same run's
    headline without the info's "seated" (the manifest's engine_info) says none (the check can fail)."""
    from mtbmj.bike.run import run_bike

    result = run_bike("trail", "flat", 4.0, duration=0.05, rider="active", seated=True)
    assert result.info["seated"] is True and result.info["rider"] == "active"
    assert result.headline().startswith("bike trail (seated) (rider 85.0 kg")
    del result.info["seated"]
    assert result.headline().startswith("bike trail (rider 85.0 kg")

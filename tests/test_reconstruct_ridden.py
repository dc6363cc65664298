"""The shared ride 00100.SST ridden on its own reconstruction as a user runs it (issue 51, item 4):
``mtbmj reconstruct RIDE --bike sst --out DIR`` then ``mtbmj bike sst DIR/terrain.csv --speed-profile
DIR/speed.csv``. The rider came home; the model goes over the bars on the pit the reconstruction
finds at 116-119 m (docs/rolling.md, "00100"). A strict xfail until that is mended, beside what was
measured of the cause: the found ground cropped around the pit, edited in the test (the pit's fall
made shallower with its exit kept; the exit flattened with the fall kept), each ridden by the same
command at the record's speed there."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtbmj.cli import main

FROM_M = 100.0  # the found terrain cropped from here (a level lead-in before it) ...
TO_M = 150.0  # ... to here
LEAD_IN_M = 5.0


@pytest.fixture(scope="module")
def found(tmp_path_factory):
    """00100.SST reconstructed as a user runs it (the folder ``mtbmj reconstruct`` writes)."""
    from conftest import SHARED_DATA

    out = tmp_path_factory.mktemp("pit51") / "rec"
    ride = str(Path(SHARED_DATA) / "sst_v2" / "00100.SST")
    assert main(["reconstruct", ride, "--bike", "sst", "--out", str(out)]) == 0
    return out


class Crashed(Exception):
    """The run crashed (what the strict xfail below waits for; any other failure fails the test)."""


def _crash(out: Path, code: int):
    """The crash ``summary.json`` names (None: it rode whole), the command's exit status ``code`` agreeing
    (3 for a crash)."""
    crash = json.loads((out / "summary.json").read_text())["crash"]
    assert code == (0 if crash is None else 3), (code, crash)
    return crash


def _face(x, z):
    """(index of the found pit's face's foot, its fall m): the largest fall between two samples at
    110-120 m (the edge the whole bike bridges at the take-off)."""
    at = np.flatnonzero((x >= 110.0) & (x <= 120.0))
    i = at[np.argmin(np.diff(z[at[0]:at[-1] + 1]))]
    return i + 1, float(z[i] - z[i + 1])


def _ride_crop(tmp: Path, name: str, x, z, speed: float):
    """The bike command over ``z`` (m on ``x``) from ``FROM_M`` to ``TO_M`` after a level lead-in, at
    ``speed`` m/s; the crash summary.json names (None: it rode whole)."""
    keep = (x >= FROM_M) & (x <= TO_M)
    z0 = float(np.interp(FROM_M, x, z))
    xs = np.r_[0.0, LEAD_IN_M - 1e-3, x[keep] - FROM_M + LEAD_IN_M]
    zs = np.r_[z0, z0, z[keep]]
    csv = tmp / f"{name}.csv"
    np.savetxt(csv, np.c_[xs, zs * 1e3], delimiter=",", header="distance_m,height_mm", comments="", fmt="%.6f")
    out = tmp / f"ride_{name}"
    code = main(["bike", "sst", str(csv), "--speed", f"{speed:.3f}", "--duration", "5", "--out", str(out),
                 "--quiet", "--no-figure"])
    return _crash(out, code)


@pytest.mark.slow  # a reconstruction through the whole bike (20-40 s) and a 38 s ride (15 s)
@pytest.mark.shared_data("sst_v2", "00100.SST")
@pytest.mark.xfail(strict=True, raises=Crashed, reason=(
    "measured on 4807a27: the passive rider goes over the bars at 16.44 s of the run (front axle near 118 m, "
    "pitch -45 deg): the found ground falls 1.20 m at a 90 deg face at 115.9 m (its flight read -1.20 m, 0.97 "
    "allowed, left as read), its floor sinks 0.13 m more and climbs 1.9 m over 119-125 m (up to 39 deg); "
    "the bike leaves the lip at +5.5 deg, its front hangs while the rear rolls to the edge and it lands the "
    "front at -35 deg. The active rider (--rider active, the same crop at 6.85 m/s: its drive does not hold "
    "a speed profile) goes over the bars too (3.42 s). Measured again on land51 with a flight's fall bounded by its "
    "landing in the terrain to ride (mtbmj/ride/reconstruct_landing.py): the rear lands first at 3.70 m/s, V^2/2g "
    "0.70 m, 1.17 with its uncertainty, so the 1.20 m fall is cut by 0.03 m only and the run still goes over the "
    "bars at 16.44 s. Measured again on flight51 with the flight's duration bounding it too: the rear's take-off "
    "window 15.300-15.404 s, at most 0.434 s in the air, allows 1.22 m for its own fall of 1.23, so the cut stays "
    "0.033 m and the run goes over the bars at 16.437 s (pitch -45.1 deg). Read again on pit100 (docs/rolling.md, "
    "'00100 read again from its record'): both ends left within 0.011 s of each other over ground found level "
    "(the rider lifted the bike; rolling off the face puts the rear a wheelbase, 0.18 s, later), so the fall is at "
    "most V^2/2g, 0.70 m as read and 1.01 with the reading's share, which pit51's crop does not ride; the exit "
    "climb is the quarter car's reference, its hard stop's kick at 15.85 s (7.91 m/s) the integral's drift. Tried on "
    "hop51 (docs/rolling.md, 'A hop tried at 00100's pit'): an open-loop hop on the active rider's targets at the "
    "muscles' limits unloads both ends at a made lip within 0.001 s but hops the bike 0.08 s, the frame turning nose "
    "down (27-47 deg/s); on the crop it goes over the bars or lands the front first at -35 to -42 deg"))
def test_00100_rides_whole_on_its_own_reconstruction_as_a_user_runs_it(found, tmp_path):
    """The rider came home through all of 00100.SST, so the recorded setting at the speed found should
    ride the terrain found without a crash."""
    out = tmp_path / "bike"
    code = main(["bike", "sst", str(found / "terrain.csv"), "--speed-profile", str(found / "speed.csv"),
                 "--out", str(out), "--quiet", "--no-figure"])
    crash = _crash(out, code)
    if crash is not None:
        raise Crashed(crash["line"])


@pytest.mark.slow  # the reconstruction of the test above (shared by the module) and three 5 s rides of 2 s each
@pytest.mark.shared_data("sst_v2", "00100.SST")
def test_00100_crashes_on_the_found_pit_s_fall_with_its_exit_and_on_neither_alone(found, tmp_path):
    """What in the ground found crashes: cropped at 100-150 m and ridden at the record's speed at the
    face (6.85 m/s), as found it goes over the bars (the baseline that must fail); the same ground with
    all past the face's foot raised so that it falls 0.5 m (what a whole bike falls from a level take-off
    in the 0.32 s both of the record's ends hang out, 1/2 g T^2) rides whole, exit climb and all (raised
    so it falls 0.9 m it still goes over the bars, 0.7 m it loops out on the climb: measured when written);
    and the whole 1.2 m fall kept onto ground levelled at the floor past the face rides whole too (pitch
    -39 deg at the landing, 6 deg from the crash). Neither the fall's depth nor the exit alone crashes it:
    a mend lowers either."""
    terrain = np.genfromtxt(found / "terrain.csv", delimiter=",", names=True)
    speed = np.genfromtxt(found / "speed.csv", delimiter=",", names=True)
    x, z = terrain["distance_m"], 1e-3 * terrain["height_mm"]
    foot, fall = _face(x, z)
    assert 1.0 < fall < 1.5 and 115.0 < x[foot] < 117.0, (fall, x[foot])  # the pit found, as measured
    v = float(np.interp(x[foot], speed["distance_m"], speed["speed_m_per_s"]))
    past = np.arange(x.size) >= foot
    as_found = _ride_crop(tmp_path, "as_found", x, z, v)
    shallow = _ride_crop(tmp_path, "fall_0.5m", x, np.where(past, z + (fall - 0.5), z), v)
    level = _ride_crop(tmp_path, "exit_level", x, np.where(past, z[foot], z), v)
    assert as_found is not None and as_found["kind"] == "over the bars", as_found
    assert shallow is None, shallow
    assert level is None, level

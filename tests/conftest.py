import os

# Headless: dm_control must not look for a display; nothing in the drop tests renders.
os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco
import pytest

from mtbmj.workers import one_blas_thread

# Two test processes on two cores: BLAS threads beside them spin against the other when the machine
# is busier still (five test files of reconstructions and calibrations took 113 s instead of 67 beside
# another process's tests; on a quiet machine 62-71 s either way); each test process, as the package's
# own pool workers and executable, does its linear algebra on one thread.
one_blas_thread()


@pytest.fixture(autouse=True)
def no_leaked_callback():
    """Every test starts and must end with no MuJoCo control callback installed."""
    mujoco.set_mjcb_control(None)
    yield
    leaked = mujoco.get_mjcb_control()
    mujoco.set_mjcb_control(None)
    assert leaked is None, "a MuJoCo control callback leaked out of the test"


@pytest.fixture(autouse=True)
def no_mujoco_log_written():
    """No test leaves MuJoCo's warning log (MUJOCO_LOG.TXT, which MuJoCo's default warning handler
    appends to in the working directory) behind: the package routes MuJoCo's warnings to its own
    messages, and a test that makes MuJoCo warn outside a run must do the same."""
    log = os.path.join(os.getcwd(), "MUJOCO_LOG.TXT")
    before = os.path.exists(log)
    yield
    if not before and os.path.exists(log):
        os.remove(log)
        pytest.fail("MuJoCo wrote MUJOCO_LOG.TXT into the working directory during this test")


# The shared telemetry (``../shared/data``) sits beside a clone, not in it: a test that reads it is
# marked ``@pytest.mark.shared_data("sst_v2", "00083.SST", ...)`` and is skipped, with the reason,
# where the folder or one of the files named is absent (a fresh clone alone).
SHARED_DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), os.pardir, "shared", "data")


def pytest_runtest_setup(item):
    for mark in item.iter_markers("shared_data"):
        folder, *files = mark.args
        where = os.path.normpath(os.path.join(SHARED_DATA, folder))
        missing = [f for f in files or [""] if not os.path.exists(os.path.join(where, f))]
        if missing:
            pytest.skip(f"needs the shared data {where}{os.sep}{missing[0]}, which is not beside this clone")


# The longest test files first. pytest-xdist's ``--dist loadfile`` hands each process the next file in
# collection order as it finishes one (with ``--no-loadscope-reorder``: by default it sorts the files by
# their number of tests, which put the few long advice and replay tests last, one process running them
# alone for many minutes while the other had finished); so the longest start first and the many short
# files fill the end. Seconds each file's tests took on two processes (2026-12-07, the suite's and the
# slow checks' runs on one machine, tests over 0.2 s); a file not listed keeps its place after these. Only the order
# depends on it: a stale number costs time, never a result.
FILE_SECONDS = {
    "test_bounce_replay.py": 3236, "test_bike_reference_rider.py": 488, "test_advise_carried.py": 452,
    "test_bike_rider_mends.py": 314, "test_advise_calibrate.py": 302, "test_advise.py": 302,
    "test_bounce_predict.py": 248, "test_advise_pool.py": 231, "test_bike_active_profile.py": 230,
    "test_bounce_rebound_clicks.py": 201, "test_reconstruct_whole_bike.py": 174, "test_advise_trails.py": 166,
    "test_advise_travel.py": 164, "test_bike_pedal_leg.py": 139, "test_rolling_reference.py": 131,
    "test_bike_pedal.py": 114, "test_bike_reference.py": 114, "test_fuzz.py": 95, "test_bike_rider_landing.py": 87,
    "test_guest.py": 79, "test_envelope.py": 74, "test_every_rig.py": 72, "test_numeric_gate.py": 70,
    "test_reconstruct_checks.py": 65, "test_reconstruct_loop.py": 62, "test_compiled.py": 58,
    "test_reconstruct_given.py": 56, "test_bike_energy_rider.py": 52, "test_fit_cli.py": 51,
}


def pytest_collection_modifyitems(session, config, items):
    """The longest files first (``FILE_SECONDS``), each file's tests kept together in their order."""
    items.sort(key=lambda item: -FILE_SECONDS.get(os.path.basename(str(item.path)), 0.0))  # a stable sort

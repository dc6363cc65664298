import os

# Headless: dm_control must not look for a display; nothing in the drop tests renders.
os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco
import pytest


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

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

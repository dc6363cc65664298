"""The levers that make MuJoCo's step of the bike cheaper without changing it (issue 52, item 7):
MuJoCo's timers off while a run steps (``mtbmj.runpath.loop.untimed``), the passive stage skipped
while a model has no springs or dampers of MuJoCo's (``loop.passive_skipped``), the camera and the light
left out of the stepped bike (``mtbmj.bike.model.NOT_STEPPED``).

The reference is the unchanged path, made here by undoing each lever (the clock left on, the passive
stage left on, the camera and light kept): whole bike runs over the rock garden compared to the bit,
states, sensors and every output column. That the comparison can fail is shown on the same run with
its start moved by 1e-9 m/s, and on a model that has a spring, whose motion the passive flags change.
"""
import contextlib

import mujoco
import numpy as np
import pytest
from mujoco import rollout

from mtbmj.bike import model as model_mod
from mtbmj.bike import run as bike_run
from mtbmj.bike.summary import signals
from mtbmj.runpath import loop

PASSIVE = int(mujoco.mjtDisableBit.mjDSBL_SPRING) | int(mujoco.mjtDisableBit.mjDSBL_DAMPER)
SPRING = """
<mujoco>
  <option timestep="0.002" integrator="RK4"/>
  <worldbody>
    <body><joint name="z" type="slide" axis="0 0 1" stiffness="4000" damping="2"/>
      <geom type="sphere" size="0.05" mass="1"/></body>
  </worldbody>
</mujoco>
"""


def _step(model, data, n=400):
    state = np.empty(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return rollout.rollout(model, data, state[None, :], nstep=n)


def test_untimed_turns_mujocos_clock_off_and_puts_it_back():
    hook = loop._time_hook()
    if hook is None:
        pytest.skip("MuJoCo's library not found beside the mujoco package: untimed changes nothing")
    model = mujoco.MjModel.from_xml_string(SPRING)
    data = mujoco.MjData(model)
    saved = hook.value
    assert saved is not None  # the mujoco package's clock: what the lever removes
    _step(model, data)
    step = data.timer[int(mujoco.mjtTimer.mjTIMER_STEP)]
    assert step.number == 400 and step.duration > 0.0  # outside the block MuJoCo times its stages
    with loop.untimed():
        assert hook.value is None
        mujoco.mj_resetData(model, data)
        _step(model, data)
        assert step.number == 400 and step.duration == 0.0
    assert hook.value == saved
    with pytest.raises(RuntimeError), loop.untimed():
        raise RuntimeError("a run that fails")
    assert hook.value == saved  # put back after an error too


def test_the_passive_stage_is_skipped_only_where_the_model_has_no_passive_force():
    spring = mujoco.MjModel.from_xml_string(SPRING)
    with loop.passive_skipped(spring):
        assert not spring.opt.disableflags & PASSIVE  # a model with a spring is left as it is
    free = mujoco.MjModel.from_xml_string(SPRING.replace(' stiffness="4000" damping="2"', ""))
    with loop.passive_skipped(free):
        assert free.opt.disableflags & PASSIVE == PASSIVE
    assert not free.opt.disableflags & PASSIVE  # put back after the block
    gravcomp = mujoco.MjModel.from_xml_string(SPRING.replace(' stiffness="4000" damping="2"', "").replace(
        "<body>", '<body gravcomp="1">'))
    with loop.passive_skipped(gravcomp):
        assert not gravcomp.opt.disableflags & PASSIVE
    # a spring given after the model was built (as bounce_replay gives the seated rider's saddle) is judged
    # when the stepping starts: it pushes (the stage decided at the build left it out: a strict regression)
    free.jnt_stiffness[0] = 4000.0
    with loop.passive_skipped(free):
        assert not free.opt.disableflags & PASSIVE
    # the flags do change a model with a spring: the comparison below can tell a passive force left out
    data = mujoco.MjData(spring)
    data.qpos[0] = 0.05
    kept, _ = _step(spring, data)
    spring.opt.disableflags |= PASSIVE
    mujoco.mj_resetData(spring, data)
    data.qpos[0] = 0.05
    dropped, _ = _step(spring, data)
    assert np.max(np.abs(kept - dropped)) > 1e-3


@contextlib.contextmanager
def _unchanged_path():
    """Every lever undone: the clock on while stepping, the passive stage on, the camera and light kept."""
    saved = loop.untimed, loop.passive_skipped, model_mod.NOT_STEPPED
    loop.untimed = contextlib.nullcontext
    loop.passive_skipped = lambda model: contextlib.nullcontext()
    model_mod.NOT_STEPPED = ("geoms", "tendons")
    try:
        yield
    finally:
        loop.untimed, loop.passive_skipped, model_mod.NOT_STEPPED = saved


def _run(nudge=0.0):
    """The bike over the rock garden at 5 m/s, compiled callback: (states, sensors, outputs, model)."""
    p = bike_run.prepare("sst", "rock_garden", 5.0, callback="auto")
    p.data.qvel[p.bike.dof_index("bike_x")] += nudge
    states, sensors = bike_run.simulate(p, 3.0)
    return states, sensors, signals(p, states, sensors), p.bike.model


def test_a_bike_run_with_every_lever_equals_the_unchanged_path_to_the_bit():
    with _unchanged_path():
        states0, sensors0, raw0, model0 = _run()
    states, sensors, raw, model = _run()
    assert model0.ncam == 1 and model0.nlight == 1  # undone
    assert model.ncam == 0 and model.nlight == 0 and not loop.has_passive(model)  # the levers on
    assert model.nv == model0.nv and model.nu == model0.nu and model.nsensordata == model0.nsensordata
    assert states.shape == states0.shape and len(states) > 5000  # 3 s at the coarse step, refined near the rocks
    assert np.array_equal(states, states0) and np.array_equal(sensors, sensors0)
    for key in bike_run.COLUMNS:
        assert np.array_equal(raw[key], raw0[key]), key
    # the same comparison tells a start 1e-9 m/s faster apart: it can fail
    nudged, _, _, _ = _run(1e-9)
    assert not np.array_equal(nudged, states)


def test_the_drawn_model_keeps_its_camera_light_and_passive_stage():
    p = bike_run.prepare("sst", "flat", 4.0)
    drawn = p.visual_model()
    assert drawn.ncam == 1 and drawn.nlight == 1 and drawn.ngeom > 0  # what a video draws
    assert not drawn.opt.disableflags & PASSIVE  # a spring given to its tendons pushes (tests/test_bike_limbs.py)
    assert p.bike.model.ncam == 0 and p.bike.model.ngeom == 0

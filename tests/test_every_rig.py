"""Every rig and preset on the one run path (issue 38 item 6, as dm_control's suite test walks every
domain and task): each run is deterministic, finite, raises no warning, and agrees with its ODE
reference within its cross-check's tolerance; a diverging run of each rig is refused the same way,
in one line naming the rig and the time."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import mtbmj
from mtbmj.errors import RunError
from mtbmj.rigs import RIGS

CASES = [(rig.name, preset) for rig in RIGS for preset in rig.presets()]


def _run(rig: str, name: str):
    """(the run's signals, its cross-check as a callable): the rig's short example over a feature,
    through the registry's one face (no branch per rig)."""
    face = RIGS[rig]
    r = face.run(name, **face.example)
    return r.raw, lambda: face.crosscheck(name, **face.example)


def _columns(raw: dict) -> dict:
    return {k: np.asarray(v) for k, v in raw.items() if isinstance(v, np.ndarray) and v.dtype.kind == "f"}


@pytest.mark.slow
@pytest.mark.parametrize("rig,name", CASES, ids=[f"{r}-{n}" for r, n in CASES])
def test_every_rig_and_preset_is_deterministic_finite_quiet_and_agrees_with_its_reference(rig, name):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning of any kind (a MuJoCo warning would end the run)
        first, check = _run(rig, name)
        second, _ = _run(rig, name)
    a, b = _columns(first), _columns(second)
    assert a.keys() == b.keys() and len(a) >= 5
    for column in a:
        assert np.all(np.isfinite(a[column])), column
        assert np.array_equal(a[column], b[column]), f"{column} differs between two runs"
    result = check()
    assert result.passed, result.line()


def _diverging(rig: str, tmp_path, monkeypatch):
    """A run of ``rig`` that leaves the model's envelope."""
    if rig == "drop":
        return lambda: mtbmj.run_drop("S1", overrides={"sled.drop_height_mm": 1e25})
    if rig == "bike":
        path = tmp_path / "stiff_arms.toml"
        path.write_text('base = "sst"\n[rider]\narm_damping_N_s_per_m = 1e7\n')
        return lambda: mtbmj.run_bike(str(path), "square_edge", speed_m_per_s=5.0)
    from mtbmj.controllers import fork as fork_mod

    original = fork_mod.ForkLaw.force

    def blows_up(self, x, v, *args, **kwargs):  # a fork law that blows up past 10 mm
        f = original(self, x, v, *args, **kwargs)
        return f * 1e300 if x > 0.01 else f

    monkeypatch.setattr(fork_mod.ForkLaw, "force", blows_up)
    return lambda: mtbmj.run_roll("square_edge", 5.0, callback="python", duration=1.0)


@pytest.mark.parametrize("rig,words", [("drop", "drop"), ("roll", "rolling"), ("bike", "bike")])
def test_a_diverging_run_of_every_rig_is_refused_the_same_way(rig, words, tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(tmp_path)
    run = _diverging(rig, tmp_path, monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the plausibility warning of the 1e7 damping
        with pytest.raises(RunError) as err:
            run()
    text = str(err.value)
    assert text.startswith(f"{words} run diverged before t = ") and "\n" not in text
    captured = capfd.readouterr()
    assert "WARNING" not in captured.out + captured.err
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_the_registry_lists_every_rig_package_once_with_its_face():
    """Every package on the rigs' floor (tests/test_layout.py's FLOORS, read from its text so no
    test module is imported) has its ``rig.RIG`` in the registry, in the floor's order; each face
    names its command, its presets and a short example its ``prepare`` takes as written."""
    import importlib
    import re
    from pathlib import Path

    text = (Path(__file__).parent / "test_layout.py").read_text()
    floor = re.search(r'\("rigs", \(([^)]*)\)\)', text).group(1)
    packages = re.findall(r'"(mtbmj\.\w+)"', floor)
    assert packages == ["mtbmj.drop", "mtbmj.rolling", "mtbmj.bike"]
    assert [importlib.import_module(p + ".rig").RIG for p in packages] == list(RIGS)
    assert [rig.command for rig in RIGS] == ["drop", "roll", "bike"]
    for rig in RIGS:
        assert len(rig.presets()) >= 2 and "auto" in rig.callbacks
        assert rig.prepare(rig.presets()[0], **rig.example) is not None


def test_the_registry_refuses_a_second_rig_of_one_name_and_names_the_known_ones():
    from mtbmj.runpath.rig import Registry

    registry = Registry()
    registry.register(RIGS["bike"])
    with pytest.raises(ValueError, match="registered already"):
        registry.register(RIGS["bike"])
    with pytest.raises(KeyError, match="known: bike"):
        registry["tricycle"]
    assert registry.names() == ["bike"] and len(registry) == 1

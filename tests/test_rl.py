"""The dm_control environment as a user meets it (the ``[rl]`` extra): docs/rolling.md's example runs
as written and prints what that page says, every observation is documented, and importing it
on a headless machine is silent and leaves a user's ``MUJOCO_GL`` alone."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.rl
pytest.importorskip("dm_control", reason="dm_control is the [rl] extra")

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "docs" / "rolling.md").read_text()  # the page that shows the dm_control example


def _headless_env(**extra):
    drop = ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY", "PYTHONPATH")  # as a user's shell has
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update(extra)
    return env


def _example() -> str:
    start = README.index("<!-- example: dm_control -->")
    match = re.search(r"```python\n(.*?)```", README[start:], flags=re.DOTALL)
    return match.group(1)


def test_readme_example_runs_as_written_and_prints_what_the_readme_says(tmp_path):
    done = subprocess.run([sys.executable, "-c", _example()], cwd=tmp_path, env=_headless_env(),
                          capture_output=True, text=True, check=False, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # no GLFW "DISPLAY missing" noise, no warnings
    lines = done.stdout.strip().splitlines()
    assert [line.split(":")[0] for line in lines] == ["skyhook", "random"]
    means = {}
    for line in lines:
        name, steps, mean, lowest = re.fullmatch(
            r"(\w+): (\d+) steps, mean reward ([\d.]+), lowest ([\d.]+)", line).groups()
        assert int(steps) == 250
        assert 0.0 < float(lowest) <= float(mean) <= 1.0
        means[name] = float(mean)
        assert f"`{line}`" in re.sub(r"\s+", " ", README), line  # the README quotes the output exactly
    assert means["skyhook"] > means["random"]  # the controller rides more smoothly than chance


def test_every_observation_is_documented():
    from mtbmj.rolling import env as E

    e = E.load("root:at_m=0.3", 4.0, duration=0.01)
    observation = e.reset().observation
    rows = dict(re.findall(r"^\| `(\w+)` \| (\d+) \|", README, flags=re.MULTILINE))
    assert set(rows) == set(observation), set(rows) ^ set(observation)
    for name, value in observation.items():
        assert int(rows[name]) == value.size, name
        assert f"``{name}`` ({value.size},)" in E.__doc__, name


@pytest.mark.parametrize("given, display, expected", [
    (None, None, "headless"), ("osmesa", None, "osmesa"), ("egl", ":0", "egl"), (None, ":0", None)])
def test_mujoco_gl_default_only_when_unset_and_headless(given, display, expected, tmp_path):
    env = _headless_env()
    if given:
        env["MUJOCO_GL"] = given
    if display:
        env["DISPLAY"] = display
    code = "import os, mtbmj.rolling.env; print(os.environ.get('MUJOCO_GL'))"
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                          check=False, timeout=300)
    assert done.returncode == 0, done.stderr
    value = done.stdout.strip()
    if expected == "headless":
        assert value in ("egl", "osmesa", "disable")
        assert done.stderr == ""
    else:
        assert value == str(expected)

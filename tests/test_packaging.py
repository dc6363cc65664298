"""A non-editable install puts everything under ``mtbmj`` and works from outside the repository."""
import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

CHECK = """
import importlib.util, pathlib, sys
import mtbmj, mtbmj.controllers, mtbmj.validation, mtbmj.mjcf
assert pathlib.Path(mtbmj.__file__).is_relative_to(pathlib.Path(sys.argv[1])), mtbmj.__file__
assert importlib.util.find_spec("controllers") is None, "bare controllers module installed"
assert importlib.util.find_spec("validation") is None, "bare validation module installed"
import mujoco
for scene in mtbmj.mjcf.scenes():
    mujoco.MjModel.from_xml_path(str(scene))
assert len(mtbmj.mjcf.scenes()) >= 1
assert "S14" in mtbmj.preset_names()
r = mtbmj.run_drop("S12", duration=0.05)
print("ok", len(r.time))
"""


@pytest.mark.slow
def test_wheel_installs_under_mtbmj_only(tmp_path):
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(wheels), str(REPO)], check=True, cwd=tmp_path)
    wheel = next(wheels.glob("mtbmj-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    top = {n.split("/")[0] for n in names}
    assert top <= {"mtbmj", f"{wheel.name.split('-')[0]}-{wheel.name.split('-')[1]}.dist-info"}, top
    for expected in ("mtbmj/mjcf/drop_scene.xml", "mtbmj/mjcf/drop.xml", "mtbmj/presets/S12.toml",
                     "mtbmj/controllers/spring.py", "mtbmj/validation/report.py"):
        assert expected in names

    # A fresh venv whose dependencies come from this environment's site-packages through a
    # plain path entry (so no editable finder of this checkout is active), the wheel installed
    # into it non-editably, and the check run from a directory outside the repository.
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    site = next((venv / "lib").glob("python*/site-packages"))
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(site), str(wheel)],
                   check=True)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH",)}
    env["MUJOCO_GL"] = "disable"
    python = venv / "bin" / "python"
    done = subprocess.run([str(python), "-c", CHECK, str(site)], cwd=tmp_path, env=env,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("ok")

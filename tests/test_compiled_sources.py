"""A compiled artifact is keyed on every source compiled into it: numba's disk cache must not serve
machine code of a function that has since been edited, in controllers/ or outside it (the bike's
compiled callback compiles plain functions of mtbmj/measured/leverage.py and mtbmj/rolling/tire.py).

The slow test installs a scratch copy of the package (the installed layout: controllers/ as
mtbmj/controllers), runs a bike with the compiled callback, edits one compiled function, runs again
in a fresh process on the same numba cache, and checks that the compiled result follows the edit:
it equals the Python callback's result of the edited code. Before the stamp covered these files the
second run loaded the old machine code (75.67 mm against the Python callback's 93.26 mm).
"""
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_stamp_reaches_every_compiled_source():
    numba = pytest.importorskip("numba")  # noqa: F841
    from mtbmj.controllers import jit, kernels

    bike_cc = pytest.importorskip("mtbmj.bike.callback_compiled")
    if getattr(bike_cc, "_dispatch", None) is None:
        pytest.skip("the compiled bike callback is not defined here")
    sources = jit.compiled_sources(bike_cc._dispatch)
    names = {Path(p).name for p in sources}
    assert {"leverage.py", "callback_compiled.py", "drive.py", "native_data.py"} <= names, names
    # the straight stretches of the shared patch search (mtbmj/rolling/tire.py, not controllers/tire.py)
    assert any(Path(p).parts[-2:] == ("rolling", "tire.py") for p in sources), sources
    fork = {Path(p).name for p in jit.compiled_sources(kernels.fork_force)}
    assert {"kernels.py", "spring.py", "damper.py"} <= fork, fork
    # the stamp changes with any of those files' contents (and only through them and controllers/)
    assert jit.sources_stamp(bike_cc._dispatch) != jit.sources_stamp(kernels.fork_force)


def _scratch_install(dest: Path) -> Path:
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")
    shutil.copytree(ROOT / "mtbmj", dest / "mtbmj", ignore=ignore)
    for sub in ("controllers", "validation", "mjcf"):
        shutil.copytree(ROOT / sub, dest / "mtbmj" / sub, ignore=ignore)
    return dest


CHILD = textwrap.dedent("""
    import json, sys, warnings
    warnings.simplefilter("error")  # a fallback to the Python path would not test the compiled one
    from mtbmj.bike.run import run_bike
    r = run_bike("sst", "root", 4.0, duration=0.8, callback=sys.argv[1])
    print(json.dumps({"callback": r.info["callback"], "rear_mm": float(r.raw["rear_travel_mm"].max()),
                      "front_mm": float(r.raw["front_travel_mm"].max())}))
""")


def _run(scratch: Path, callback: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(scratch), NUMBA_CACHE_DIR=str(scratch / "numba-cache"))
    proc = subprocess.run([sys.executable, "-c", CHILD, callback], cwd=scratch, env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["callback"] == callback
    return out


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert text.count(old) == 1, old
    path.write_text(text.replace(old, new))


@pytest.mark.slow
def test_an_edit_of_a_compiled_function_reaches_the_compiled_run(tmp_path):
    pytest.importorskip("numba")
    from mtbmj.controllers import jit

    if not jit.CACHE:
        pytest.skip("numba keeps no disk cache here")
    scratch = _scratch_install(tmp_path)
    before = _run(scratch, "compiled")  # compiles and caches
    assert _run(scratch, "compiled") == before  # served from the cache, the same
    # outside controllers/: the leverage curve's ratio, read by the compiled callback for the shock
    _edit(scratch / "mtbmj" / "measured" / "leverage.py",
          "    return r[i] + (r[i + 1] - r[i]) * (w - w_tab[i]) / (w_tab[i + 1] - w_tab[i])",
          "    return 1.25 * (r[i] + (r[i + 1] - r[i]) * (w - w_tab[i]) / (w_tab[i + 1] - w_tab[i]))")
    edited = _run(scratch, "compiled")
    python = _run(scratch, "python")
    assert abs(edited["rear_mm"] - before["rear_mm"]) > 0.5  # the edit matters ...
    assert edited["rear_mm"] == pytest.approx(python["rear_mm"], abs=0.02)  # ... and the compiled run follows it
    # inside controllers/: the rider's drive law, edited to push nothing
    _edit(scratch / "mtbmj" / "controllers" / "drive.py", "        f = -brake\n    return f\n",
          "        f = -brake\n    return 0.0 * f\n")
    coasting = _run(scratch, "compiled")
    assert coasting != edited
    assert coasting["rear_mm"] == pytest.approx(_run(scratch, "python")["rear_mm"], abs=0.02)


@pytest.mark.parametrize("module,prefix,width", [
    ("mtbmj.rolling.search_compiled", "R_", "INT_WIDTH"),
    ("mtbmj.rolling.search_compiled", "F_", "F_PATCHES"),
    ("mtbmj.bike.callback_compiled", "R_", "INT_WIDTH"),
    ("mtbmj.bike.callback_compiled", "F_", "FLOAT_WIDTH"),
    ("mtbmj.drop.engine_fast", "Q_", "Q_WIDTH"),
])
def test_a_compiled_slot_s_rows_are_its_list_of_names_and_its_width_follows(module, prefix, width):
    """Each compiled slot's rows (the module's ``R_``/``F_``/``Q_`` names, read from its source)
    are 0, 1, ... in the order the names are listed, each once, and the width (where the next part
    of the row starts) is one past the last: no row numbered by hand, none left spare or shared."""
    import ast
    import importlib

    mod = importlib.import_module(module)
    tree = ast.parse(Path(mod.__file__).read_text())
    listed = []
    for node in tree.body:
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Tuple) \
                and isinstance(node.value, ast.Call) and getattr(node.value.func, "id", "") == "range":
            names = [e.id for e in node.targets[0].elts]
            if all(n.startswith(prefix) for n in names):
                listed += names
    assert listed, f"{module}: no {prefix} row list"
    assert [getattr(mod, n) for n in listed] == list(range(len(listed)))
    assert getattr(mod, width) == len(listed), f"{module}.{width} is not one past the last {prefix} row"

"""mtbmj as a guest in someone else's process and on someone else's machine: a read-only install
run by a user without a writable home, optional extras missing, the user's matplotlib backend,
help texts."""
import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import mtbmj
from mtbmj import cli
from mtbmj.cli import common

REPO = Path(__file__).resolve().parents[1]
LIBRARY = [p for d in ("mtbmj", "controllers", "validation") for p in (REPO / d).rglob("*.py")]

# A drop through the Python API; warnings are errors, so the Python-law fallback (which warns) or
# any stray warning fails the run. Prints whether the kernels are cached on disk.
DROP = """
import sys, warnings
warnings.simplefilter("error")
import mtbmj
from mtbmj.controllers import compiled
r = mtbmj.run_drop("S12", duration=0.3)
assert compiled.unavailable_reason() is None, compiled.unavailable_reason()
r.to_csv(sys.argv[1])
print("cache", compiled.CACHE)
"""


def _clean_env(**extra):
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "PYOPENGL_PLATFORM")}
    env.update(MUJOCO_GL="disable", **extra)
    return env


def _reference_csv(tmp_path) -> bytes:
    path = tmp_path / "reference.csv"
    mtbmj.run_drop("S12", duration=0.3).to_csv(path)
    return path.read_bytes()


def test_no_numba_cache_directory_compiles_in_memory(tmp_path):
    """numba finds no place for its cache (what a read-only install and a missing home give; here
    by leaving it only the zip-file locator): the compiled laws still run, uncached, with the
    same numbers as the cached ones and nothing on stderr."""
    out = tmp_path / "run.csv"
    env = _clean_env(HOME=str(tmp_path / "no" / "home"), NUMBA_CACHE_LOCATOR_CLASSES="ZipCacheLocator")
    done = subprocess.run([sys.executable, "-c", DROP, str(out)], cwd=tmp_path, env=env, capture_output=True,
                          text=True, check=False, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert done.stdout.split() == ["cache", "False"]
    assert out.read_bytes() == _reference_csv(tmp_path)
    assert not (tmp_path / "no").exists()


def _read_only_mounts_work() -> bool:
    if not shutil.which("unshare") or os.geteuid() != 0:
        return False
    probe = subprocess.run(["unshare", "-m", "--propagation", "private", "true"], capture_output=True, check=False, timeout=30)
    return probe.returncode == 0


@pytest.mark.skipif(not _read_only_mounts_work(), reason="needs root and mount namespaces to make a read-only tree")
def test_read_only_install_without_a_home_runs_the_cli(tmp_path):
    """The repository (where this install's files live) and the user's home on read-only
    mounts, as for a service user on a read-only image: drop and roll run and write only --out."""
    home = tmp_path / "ro"
    home.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    main = "import sys; from mtbmj.cli import main; sys.exit(main(sys.argv[1:]))"
    commands = [[sys.executable, "-c", main, "drop", "S12", "--duration", "0.3", "--out", str(out / "drop")],
                [sys.executable, "-c", main, "roll", "washboard", "--speed", "5", "--duration", "0.3",
                 "--out", str(out / "roll")]]
    script = " && ".join([f"mount --bind {REPO} {REPO}", f"mount -o remount,bind,ro {REPO}",
                          f"mount --bind {home} {home}", f"mount -o remount,bind,ro {home}"]
                         + [" ".join(f"'{a}'" for a in c) for c in commands])
    # nothing new can be cached here (the install is read-only), so numba compiles in memory what
    # its cache lacks, and the compile notice (stderr, after MTBMJ_COMPILE_NOTICE_S, 3 s) came or
    # not with the machine's speed (it came once in CI): this test is about what is written and
    # read, so the notice waits longer; the notice itself is tested in tests/test_engine_fast.py
    env = _clean_env(HOME=str(home / "user"), MTBMJ_COMPILE_NOTICE_S="600")
    done = subprocess.run(["unshare", "-m", "--propagation", "private", "sh", "-c", script], cwd=tmp_path, env=env,
                          capture_output=True, text=True, check=False, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert sorted(p.name for p in out.iterdir()) == ["drop", "roll"]
    assert list(home.iterdir()) == []
    ours = mtbmj.run_drop("S12", duration=0.3)
    assert (out / "drop" / "timeseries.csv").read_bytes() == ours.csv_bytes()


# --- optional extras ---------------------------------------------------------------------------

def _argv(case, d):
    return [a.format(d=d) for a in case]


EXTRA_CASES = [
    (["sweep", "S12", "--vary", "fork.spring.preload_N=150:300:3", "--out", "{d}/out"], "pandas", "sweep"),
    (["sweep", "S12", "--vary", "fork.spring.preload_N=150:300:3", "--out", "{d}/out"], "pyarrow", "sweep"),
    (["sweep", "S12", "--vary", "fork.spring.preload_N=150:300:3", "--traces", "--out", "{d}/out"], "h5py", "sweep"),
    (["sweep", "S12", "--vary", "fork.spring.preload_N=150:300:3", "--backend", "dask",
      "--scheduler", "tcp://127.0.0.1:1", "--out", "{d}/out"], "distributed", "dask"),
    (["sensitivity", "S12", "--vary", "fork.spring.preload_N=150:300", "--vary", "tire.impact_rate_N_per_mm=74:86",
      "--output", "fork_peak1_mm", "--samples", "8", "--out", "{d}/out"], "SALib", "sweep"),
    (["render", "S1", "--out", "{d}/out/v.mp4", "--duration", "0.1"], "imageio_ffmpeg", "video"),
]


@pytest.mark.parametrize("argv, module, extra", EXTRA_CASES, ids=[f"{c[0][0]}-{c[1]}" for c in EXTRA_CASES])
def test_a_missing_extra_is_one_line_before_any_work(argv, module, extra, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, module, None)  # import fails as if it were not installed
    assert cli.main(_argv(argv, tmp_path)) == common.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"pip install 'mtbmj[{extra}]'" in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()  # nothing computed, nothing written


def test_gif_needs_no_extra(tmp_path, monkeypatch):
    """GIF is written with Pillow alone; only MP4 asks for the [video] extra."""
    from mtbmj.rolling import render

    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    assert render.check_output(tmp_path / "v.gif", 64, 48, 20.0) == ".gif"
    with pytest.raises(mtbmj.errors.MtbmjError, match=r"mtbmj\[video\]"):
        render.check_output(tmp_path / "v.mp4", 64, 48, 20.0)


# --- matplotlib --------------------------------------------------------------------------------

def test_library_code_never_switches_the_backend_nor_uses_pyplot():
    """No ``matplotlib.use`` call and no pyplot import anywhere in the installed code."""
    offences = []
    for path in LIBRARY:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "use" \
                    and isinstance(node.func.value, ast.Name) and node.func.value.id == "matplotlib":
                offences.append(f"{path.relative_to(REPO)}:{node.lineno} matplotlib.use")
            names = [a.name for a in node.names] if isinstance(node, (ast.Import, ast.ImportFrom)) else []
            module = node.module if isinstance(node, ast.ImportFrom) else ""
            if "matplotlib.pyplot" in names or module == "matplotlib.pyplot" or \
                    (module == "matplotlib" and "pyplot" in names):
                offences.append(f"{path.relative_to(REPO)}:{node.lineno} pyplot")
    assert not offences, offences


PLOTS = """
import sys
import matplotlib
matplotlib.use(sys.argv[1])
import mtbmj
from mtbmj.drop import study
r = mtbmj.run_drop("S1", duration=0.05)
figures = [r.plot(), study.group_figure({"S1": {"mujoco": r}}, "t", ["S1"]),
           mtbmj.run_roll("flat", 2.0, duration=0.05).plot()]
for k, fig in enumerate(figures):
    fig.savefig(f"{sys.argv[2]}/{k}.png")
assert matplotlib.get_backend().lower() == sys.argv[1].lower(), matplotlib.get_backend()
assert "matplotlib.pyplot" not in sys.modules
print(len(figures))
"""


@pytest.mark.parametrize("backend", ["pdf", "svg"])
def test_plots_keep_the_users_backend(backend, tmp_path):
    done = subprocess.run([sys.executable, "-c", PLOTS, backend, str(tmp_path)], env=_clean_env(),
                          capture_output=True, text=True, check=False, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "3"
    for k in range(3):
        with open(tmp_path / f"{k}.png", "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"


# --- help texts --------------------------------------------------------------------------------

def _parsers(parser):
    yield parser
    for action in parser._actions:
        if action.__class__.__name__ == "_SubParsersAction":
            for sub in action.choices.values():
                yield from _parsers(sub)


def test_help_texts_print_no_stray_escapes():
    """Every command's --help as argparse prints it: no doubled ``%%``, no unformatted ``%(``."""
    for parser in _parsers(cli.build_parser()):
        text = parser.format_help()
        assert "%%" not in text and "%(" not in text, parser.prog


def test_no_dm_control_names_the_rl_extra():
    """Without dm_control the environment module says which extra brings it."""
    code = ("import sys; sys.modules['dm_control'] = None\n"
            "try:\n    import mtbmj.rolling.env\nexcept ImportError as e:\n    print(e)\n")
    done = subprocess.run([sys.executable, "-c", code], env=_clean_env(), capture_output=True, text=True, check=False, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "pip install 'mtbmj[rl]'" in done.stdout

"""The package's layout: subsystems in subpackages, all command-line code in ``mtbmj.cli``, and no
import cycles between modules (lazy imports inside functions and the packages' lazy export tables
included)."""
from __future__ import annotations

import ast
import functools
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# repository folder -> installed package (pyproject's package-dir)
PACKAGE_DIRS = {"mtbmj": "mtbmj", "controllers": "mtbmj.controllers", "validation": "mtbmj.validation",
                "mjcf": "mtbmj.mjcf"}
MAX_TOP_LEVEL_MODULES = 12


@functools.lru_cache(maxsize=None)
def _parsed(path: Path, stamp: tuple) -> ast.Module:
    return ast.parse(path.read_text(), str(path))


def parsed(path: Path) -> ast.Module:
    """``path``'s syntax tree, parsed once per file as it is on disk (its size and time: a file written by a
    test parses again); the tests below read every module's several times (about 2 s a pass)."""
    st = path.stat()
    return _parsed(path, (st.st_size, st.st_mtime_ns))


def modules() -> dict[str, Path]:
    """Installed module name -> source file, for every module of the package."""
    found = {}
    for folder, package in PACKAGE_DIRS.items():
        for path in (ROOT / folder).rglob("*.py"):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join([package, *parts])] = path
    return found


def _lazy_table(tree: ast.Module) -> list[str]:
    """Module names in a package's ``_LAZY = {"name": "module[:attribute]", ...}`` export table."""
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "_LAZY" for t in node.targets):
            return [v.value.partition(":")[0] for v in node.value.values if isinstance(v, ast.Constant)]
    return []


def import_source(package: str, node: ast.ImportFrom) -> str:
    """The module a ``from ... import`` in ``package`` takes its names from (relative ones resolved)."""
    if not node.level:
        return node.module
    base = package.split(".")[: len(package.split(".")) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def import_graph() -> dict[str, set[str]]:
    """Module -> the package modules it imports, at module level or inside functions."""
    known = modules()
    graph: dict[str, set[str]] = {}
    for name, path in known.items():
        tree = parsed(path)
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges = set(_lazy_table(tree))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                edges.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                source = import_source(package, node)
                for alias in node.names:
                    sub = f"{source}.{alias.name}"
                    edges.add(sub if sub in known else source)
        graph[name] = {e for e in edges if e in known and e != name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycles():
    assert cycles(import_graph()) == []


def test_cycle_finder_finds_a_planted_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [["a", "b", "c"]]


def test_graph_sees_lazy_imports():
    # the drop engine imports the compiled laws inside a function: the graph must see it
    assert "mtbmj.controllers.compiled" in import_graph()["mtbmj.drop.engine_mujoco"]


def test_command_line_code_lives_in_the_cli_package():
    for name, path in modules().items():
        if name == "mtbmj.cli" or name.startswith("mtbmj.cli."):
            continue
        tree = parsed(path)
        imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        imported |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
        assert "argparse" not in imported, f"{name} builds a command line outside mtbmj.cli"


def test_top_level_is_small():
    top = [p for p in (ROOT / "mtbmj").glob("*.py")]
    assert len(top) <= MAX_TOP_LEVEL_MODULES, sorted(p.name for p in top)


def test_the_stop_and_rim_formula_is_written_once():
    """The hard stops' and the rim's force, k p (1 + (p/p0)^2) + c tanh(3 p/p0) dp/dt, lives in
    ``controllers/stops.py:contact_force`` only; the compiled kernels compile that function (issue
    24). A second copy of its arithmetic anywhere in the package fails here."""
    import re

    # the ramp written as a number (DAMPING_RAMP by name is the constant, which other laws share:
    # the rolling tire's damping ramp), and the stiffening term k p (1 + r r)
    copies = re.compile(r"tanh\(\s*3(\.0)?\s*\*|\*\s*\w+\s*\*\s*\(1\.0 \+ (\w+) \* \2\)")
    found = []
    for path in modules().values():
        if path.name == "stops.py" and path.parent.name == "controllers":
            continue
        for number, text in enumerate(path.read_text().splitlines(), 1):
            if copies.search(text):
                found.append(f"{path.relative_to(ROOT)}:{number}: {text.strip()}")
    assert found == []
    stops = (ROOT / "controllers" / "stops.py").read_text()
    assert len(copies.findall(stops.split('"""', 2)[2])) == 1  # contact_force's stiffening term, once
    assert stops.count("math.tanh(DAMPING_RAMP * r)") == 1  # and its damping ramp


# --- private names stay in their module (issue 24) -------------------------------------------

# Where a cross-module import of a private name is still allowed, and why; shrink to empty.
# (controllers/ was exempt while it was split into kernels, MuJoCo-data plumbing and callbacks;
# it is checked like the rest since.)
PRIVATE_IMPORTS_EXEMPT_PACKAGES: set[str] = set()
# (importer, "module:name") pairs allowed outside those packages, each with the module that still
# has to change; a pair no longer used fails test_private_import_allowances_are_all_used.
PRIVATE_IMPORTS_ALLOWED: set[tuple[str, str]] = set()


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports_in(name: str, tree: ast.Module, known) -> set[tuple[str, str]]:
    """(importer, "module:name") for each private name module ``name`` takes from another package
    module: ``from m import _x``, ``m._x`` on an imported module ``m``, or a private module
    (``m._y``) imported from outside the package that holds it (a private module is its
    package's)."""
    package = name if known[name].name == "__init__.py" else name.rpartition(".")[0]
    bound: dict[str, str] = {}  # local name -> package module
    found = set()

    def module_allowed(module: str) -> bool:  # a private module, imported from inside its package
        return name.startswith(module.rpartition(".")[0] + ".")

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name in known:
                    bound[alias.asname or alias.name.split(".")[0]] = alias.name if alias.asname else alias.name.split(".")[0]
                    last = alias.name.rpartition(".")[2]
                    if _private(last) and not module_allowed(alias.name):
                        found.add((name, alias.name))
        elif isinstance(node, ast.ImportFrom):
            source = import_source(package, node)
            for alias in node.names:
                sub = f"{source}.{alias.name}"
                if sub in known:
                    bound[alias.asname or alias.name] = sub
                    if _private(alias.name) and not module_allowed(sub):
                        found.add((name, sub))
                elif source in known and source != name and _private(alias.name):
                    found.add((name, f"{source}:{alias.name}"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and _private(node.attr):
            module = bound.get(node.value.id)
            if module is None or module == name:
                continue
            sub = f"{module}.{node.attr}"
            if sub in known:
                if not module_allowed(sub):
                    found.add((name, sub))
            else:
                found.add((name, f"{module}:{node.attr}"))
    return found


def private_imports() -> set[tuple[str, str]]:
    known = modules()
    found = set()
    for name, path in known.items():
        found |= private_imports_in(name, parsed(path), known)
    return found


def _exempt(pair: tuple[str, str]) -> bool:
    importer, target = pair
    return any(m == p or m.startswith(p + ".") for p in PRIVATE_IMPORTS_EXEMPT_PACKAGES
               for m in (importer, target.partition(":")[0]))


def test_no_module_imports_another_modules_private_names():
    found = {pair for pair in private_imports() if not _exempt(pair)}
    assert sorted(found - PRIVATE_IMPORTS_ALLOWED) == []


def test_private_import_allowances_are_all_used():
    assert sorted(PRIVATE_IMPORTS_ALLOWED - private_imports()) == []


def test_private_import_finder_finds_planted_imports():
    known = {"mtbmj.a": Path("a.py"), "mtbmj.b": Path("b.py"), "mtbmj.sub._hidden": Path("_hidden.py"),
             "mtbmj.sub": Path("__init__.py"), "mtbmj.sub.c": Path("c.py")}
    source = ("from mtbmj.b import _one, two\nfrom mtbmj import b as bee\nimport mtbmj.b\nbee._three()\n"
              "from mtbmj.sub import _hidden\n")
    assert private_imports_in("mtbmj.a", ast.parse(source), known) == {
        ("mtbmj.a", "mtbmj.b:_one"), ("mtbmj.a", "mtbmj.b:_three"), ("mtbmj.a", "mtbmj.sub._hidden")}
    # inside its package a private module is fair game, and a module's own private names too
    inside = "from mtbmj.sub import _hidden\nfrom . import _hidden as h\nh.public()\n"
    assert private_imports_in("mtbmj.sub.c", ast.parse(inside), known) == set()


# --- the drop fit stays in identify/ and drop/ (issue 24) -------------------------------------

def reach(graph: dict[str, set[str]], start: str) -> set[str]:
    """Every module ``start`` imports, directly or through others (lazy imports included)."""
    seen, stack = set(), [start]
    while stack:
        module = stack.pop()
        if module not in seen:
            seen.add(module)
            stack.extend(graph[module])
    return seen


def test_the_drop_fit_reaches_nothing_of_the_sweep():
    """The drop fit runs its drops through the drop subsystem (``run_drop``, ``drop.chain``,
    the batched engine ``drop.engine_batch``), never through ``mtbmj.sweep``."""
    graph = import_graph()
    for fit in ("mtbmj.identify.dropfit", "mtbmj.identify.drop_synthetic"):
        assert sorted(m for m in reach(graph, fit) if m == "mtbmj.sweep" or m.startswith("mtbmj.sweep.")) == [], fit


def test_the_drop_subsystem_imports_nothing_above_it():
    """The sweep and the fits run drops; drop/ runs them for both and imports neither."""
    graph = import_graph()
    above = ("mtbmj.sweep", "mtbmj.identify", "mtbmj.cli")
    for name, edges in graph.items():
        if name == "mtbmj.drop" or name.startswith("mtbmj.drop."):
            assert sorted(e for e in edges if e.startswith(above)) == [], name


def test_the_force_laws_import_nothing_above_them():
    """controllers/ is the bottom layer: the subsystems, the readout and the command line use it,
    never the other way (the rolling callbacks live in mtbmj/rolling/)."""
    graph = import_graph()
    above = ("mtbmj.drop", "mtbmj.rolling", "mtbmj.sweep", "mtbmj.identify", "mtbmj.readout", "mtbmj.ride",
             "mtbmj.bike", "mtbmj.cli", "mtbmj.validation")
    for name, edges in graph.items():
        if name.startswith("mtbmj.controllers"):
            assert sorted(e for e in edges if e.startswith(above)) == [], name


# --- floors by role (issue 50) ------------------------------------------------------------------

# The house's floors, from the ground up: a module may import only from its own floor or a lower
# one (module-level or inside a function, the lazy export tables included). A module is on the
# floor of the longest prefix listed for it. ``docs/architecture.md`` is drawn from this table.
FLOORS: list[tuple[str, tuple[str, ...]]] = [
    ("ground", ("mtbmj._package", "mtbmj.errors", "mtbmj.textfile", "mtbmj.output", "mtbmj.workers",
                "mtbmj.limits", "mtbmj.extras", "mtbmj.trace")),
    ("laws", ("mtbmj.controllers", "mtbmj.config", "mtbmj.mjcf", "mtbmj.presets")),
    # compose chooses a setup's step by the step rule: it stands with the run path
    ("run path", ("mtbmj.runpath", "mtbmj.compose")),
    ("measured data", ("mtbmj.measured",)),
    # a run's result (mtbmj/result.py: columns, files, manifest) is what a user reads from it
    ("readout", ("mtbmj.readout", "mtbmj.result")),
    ("rigs", ("mtbmj.drop", "mtbmj.rolling", "mtbmj.bike")),
    ("applications", ("mtbmj.sweep", "mtbmj.identify", "mtbmj.validation", "mtbmj.ride")),
    ("commands", ("mtbmj.cli",)),
    ("the package's face", ("mtbmj",)),  # mtbmj/__init__.py: lazy exports of the public names
]


def floor_of(module: str, floors=None) -> int:
    best, level = "", None
    for i, (_, prefixes) in enumerate(floors or FLOORS):
        for p in prefixes:
            if (module == p or module.startswith(p + ".")) and len(p) > len(best):
                best, level = p, i
    if level is None:
        raise AssertionError(f"{module} stands on no floor of FLOORS: add its folder to the table")
    return level


def moved_shims() -> dict[str, str]:
    """Modules that moved and stay importable from their old place for one release: old -> new.
    A shim holds its docstring, the import of ``moved`` and ``__getattr__ = moved(...)``, nothing
    else; it names its new place as a string, so it draws no arrow."""
    found = {}
    for name, path in modules().items():
        tree = parsed(path)
        calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and getattr(n.func, "id", None) == "moved"]
        if calls:
            body = [n for n in tree.body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
            assert len(body) == 2 and isinstance(body[0], ast.ImportFrom) and body[0].module == "mtbmj._package", \
                f"{name}: a moved module's shim holds nothing but the forwarding"
            old, new = (a.value for a in calls[0].args[:2])
            assert old == name, f"{name}: its shim names {old}"
            found[old] = new
    return found


def upward_imports(graph, floors=None) -> list[str]:
    return sorted(f"{a} (floor {floor_of(a, floors)}) -> {b} (floor {floor_of(b, floors)})"
                  for a, edges in graph.items() for b in edges if floor_of(b, floors) > floor_of(a, floors))


def test_every_import_points_to_its_own_floor_or_a_lower_one():
    assert upward_imports(import_graph()) == []


def test_the_floor_check_fails_on_a_planted_upward_import(tmp_path):
    """A scratch copy of a measured-data module with an import of the bike planted inside a
    function: the check finds it (an import inside a function is an import)."""
    import shutil

    scratch = tmp_path / "mtbmj"
    shutil.copytree(ROOT / "mtbmj" / "measured", scratch / "measured")
    (scratch / "bike").mkdir()
    (scratch / "bike" / "run.py").write_text("X = 1\n")
    planted = scratch / "measured" / "metrics.py"
    planted.write_text(planted.read_text() + "\n\ndef planted():\n    from mtbmj.bike.run import X\n    return X\n")
    known = {f"mtbmj.measured.{p.stem}": p for p in (scratch / "measured").glob("*.py") if p.stem != "__init__"}
    known["mtbmj.bike.run"] = scratch / "bike" / "run.py"
    graph = {}
    for name, path in known.items():
        tree = parsed(path)
        graph[name] = {f"{n.module}" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
                       and n.module in known and n.module != name}
    assert upward_imports(graph) == ["mtbmj.measured.metrics (floor 3) -> mtbmj.bike.run (floor 5)"]


def test_no_two_folders_import_each_other():
    """Between two subpackages the arrows run one way only (a two-way tie is two floors' worth of
    coupling on one)."""
    known = modules()  # once: it walks every folder

    def folder(m):
        parts = m.split(".")
        return ".".join(parts[:2]) if len(parts) > 2 or (len(parts) == 2 and known[m].name == "__init__.py") else m

    graph = import_graph()
    ties = {(folder(a), folder(b)) for a, edges in graph.items() for b in edges if folder(a) != folder(b)}
    assert sorted((a, b) for a, b in ties if (b, a) in ties and a < b) == []


def test_moved_modules_point_to_a_module_that_is_there():
    shims = moved_shims()
    assert "mtbmj.ride.telemetry" in shims  # the check sees the shims
    known = modules()
    for old, new in shims.items():
        assert new in known and new not in shims, (old, new)


def test_a_moved_name_is_importable_from_its_old_place_with_a_warning():
    import importlib
    import warnings

    old = importlib.import_module("mtbmj.ride.telemetry")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_sst = old.read_sst
    from mtbmj.measured.telemetry import read_sst as new

    assert read_sst is new
    assert [str(w.message).split(":")[0] for w in caught] == ["mtbmj.ride.telemetry moved to mtbmj.measured.telemetry"]
    assert caught[0].category is DeprecationWarning


# --- the test suite: shared helpers in tests/helpers.py, no test module imports another --------------

def imports_of_test_modules(folder: Path) -> list[str]:
    """``file:line module`` of every import (lazy ones inside functions included) in ``folder``'s
    test modules, conftest.py and helpers.py that takes a test module: ``test_x``, ``tests.test_x``
    or the ``tests`` package itself."""
    found = []
    for path in sorted([*folder.glob("test_*.py"), folder / "conftest.py", folder / "helpers.py"]):
        if not path.exists():
            continue
        for node in ast.walk(parsed(path)):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            else:
                continue
            for name in names:
                parts = name.split(".")
                if parts[0] == "tests" or parts[0].startswith("test_"):
                    found.append(f"{path.name}:{node.lineno} {name}")
                    break
    return found


def test_no_test_module_imports_another_test_module():
    """What several test modules use lives in tests/helpers.py (``from helpers import ...``), a
    fixture in tests/conftest.py: a test module taken as a library runs its tests twice or not at
    all depending on where pytest starts, and a ``tests.`` path collects only from the repository root."""
    assert imports_of_test_modules(ROOT / "tests") == []


def test_the_test_import_finder_finds_planted_imports(tmp_path):
    (tmp_path / "test_a.py").write_text("import os\nfrom helpers import one_line\n\n\ndef test_a():\n    pass\n")
    (tmp_path / "test_b.py").write_text("from test_a import thing\n\n\ndef f():\n    import test_a as A\n")
    (tmp_path / "test_c.py").write_text("from tests.test_a import thing\nfrom tests import test_a\n")
    (tmp_path / "helpers.py").write_text("from test_c import x\n")
    assert imports_of_test_modules(tmp_path) == ["helpers.py:1 test_c", "test_b.py:1 test_a", "test_b.py:5 test_a",
                                             "test_c.py:1 tests.test_a", "test_c.py:2 tests"]


def test_the_rl_tests_collect_without_the_test_extras():
    """CI's [rl] run installs dm-control and pytest only, then collects every test file holding an
    ``rl`` test; those import tests/helpers.py, so helpers and conftest must import without the
    test extras (hypothesis, pandas, pyarrow, h5py, SALib, dask, xdist). The stop that failed on
    hypothesis is the case this catches."""
    import subprocess
    import sys
    extras = ["hypothesis", "pandas", "pyarrow", "h5py", "SALib", "dask", "xdist", "imageio_ffmpeg"]
    script = ("import sys\n"
              f"for name in {extras!r}:\n    sys.modules[name] = None\n"
              f"sys.path.insert(0, {str(ROOT / 'tests')!r})\n"
              "import conftest, helpers\n"
              "for name in ('test_engine_mujoco', 'test_rl', 'test_rolling'):\n"
              "    try:\n        __import__(name)\n"
              "    except BaseException as skip:  # a module-level importorskip where dm_control is absent\n"
              "        if type(skip).__name__ != 'Skipped':\n            raise\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-2000:]


MAX_MODULE_LINES = 700  # issue 50: a module past this is split by role


def test_no_module_of_the_package_is_longer_than_the_limit():
    """Every module of the package (``mtbmj/``, ``controllers/``, ``validation/``) at most
    ``MAX_MODULE_LINES`` lines: a module that grows past it is split by role, as the reconstruction
    was (reconstruct.py, 745 lines, into its speed, inverse and whole-bike parts)."""
    root = Path(__file__).resolve().parents[1]
    long = {str(p.relative_to(root)): n for d in ("mtbmj", "controllers", "validation")
            for p in (root / d).rglob("*.py") if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES}
    assert long == {}


def test_the_longest_test_files_are_collected_first_each_file_whole():
    """``conftest.pytest_collection_modifyitems`` puts the files of ``FILE_SECONDS`` first, longest first,
    each file's tests together in their own order, and every other file after them in collection order."""
    from types import SimpleNamespace

    from conftest import FILE_SECONDS, pytest_collection_modifyitems

    longest, shorter = sorted(FILE_SECONDS, key=FILE_SECONDS.get, reverse=True)[:2]
    names = ["test_a_short.py", shorter, "test_b_short.py", longest]
    items = [SimpleNamespace(path=ROOT / "tests" / n, i=i) for n in names for i in range(3)]
    pytest_collection_modifyitems(None, None, items)
    got = [(it.path.name, it.i) for it in items]
    assert got == [(n, i) for n in (longest, shorter, "test_a_short.py", "test_b_short.py") for i in range(3)]
    assert all((ROOT / "tests" / n).exists() for n in FILE_SECONDS)  # no stale name: each is a file here

"""The package's layout: subsystems in subpackages, all command-line code in ``mtbmj.cli``, and no
import cycles between modules (lazy imports inside functions and the packages' lazy export tables
included)."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# repository folder -> installed package (pyproject's package-dir)
PACKAGE_DIRS = {"mtbmj": "mtbmj", "controllers": "mtbmj.controllers", "validation": "mtbmj.validation",
                "mjcf": "mtbmj.mjcf"}
MAX_TOP_LEVEL_MODULES = 12


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


def import_graph() -> dict[str, set[str]]:
    """Module -> the package modules it imports, at module level or inside functions."""
    known = modules()
    graph: dict[str, set[str]] = {}
    for name, path in known.items():
        tree = ast.parse(path.read_text(), str(path))
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges = set(_lazy_table(tree))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                edges.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module
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
        tree = ast.parse(path.read_text())
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

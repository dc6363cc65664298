"""Each law's formula is written once (issue 24): a plain function in its law module that the law
object calls and the compiled kernels compile, with the law's parameters read by name from a
layout derived from its dataclass. These tests check the rule itself, so that a copy of a formula
or a hand-kept position cannot come back unnoticed."""
from __future__ import annotations

import ast
import dataclasses
import inspect
from pathlib import Path

import numpy as np
import pytest

from mtbmj.controllers import damper, friction, lawcodes, spring, stops, tire
from mtbmj.controllers.layout import offsets, params, values

ROOT = Path(__file__).resolve().parents[1]
LAW_MODULES = (spring, damper, friction, stops, tire)
REGISTERED = [*lawcodes.SPRINGS, *lawcodes.DAMPERS, *lawcodes.FRICTIONS, friction.Sticking, stops.Rim,
              tire.ContactFloor]


def plain_functions():
    """The law modules' formulas: their public module-level functions."""
    found = {}
    for module in LAW_MODULES:
        for name in module.__all__:
            value = getattr(module, name)
            if inspect.isfunction(value) and value.__module__ == module.__name__:
                found[f"{module.__name__}.{name}"] = value
    return found


@pytest.mark.parametrize("cls", REGISTERED, ids=lambda c: c.__name__)
def test_a_layout_is_the_dataclass_numbers_then_its_derived_values(cls):
    hints = {f.name: f.type for f in dataclasses.fields(cls)}
    numbers = [name for name, kind in hints.items() if kind in ("float", "int", float, int)]
    assert params(cls) == (*numbers, *getattr(cls, "derived", ()))
    assert tuple(offsets(cls)) == tuple(range(len(params(cls))))


def test_a_field_added_to_a_law_moves_the_offsets_after_it():
    """The layout follows the dataclass: no position is kept by hand."""
    @dataclasses.dataclass(frozen=True)
    class Before:
        rate: float
        knee: float

    @dataclasses.dataclass(frozen=True)
    class After:
        rate: float
        inner: object
        cubic: float
        knee: float
        derived = ("twice",)

        @property
        def twice(self):
            return 2.0 * self.knee

    assert offsets(Before).knee == 1
    assert offsets(After).knee == 2 and offsets(After).twice == 3
    assert values(After(1.0, None, 2.0, 3.0)) == [1.0, 2.0, 3.0, 6.0]


def test_a_law_row_holds_each_parameter_where_its_layout_says():
    law = stops.EndStops(spring.TopOutSpring(spring.BilinearSpring(8e4, 1.2e5, 0.05), 3e5, 150.0),
                         0.16, 0.02, 3e3, 5e6, 2e3, 0.01)
    from mtbmj.controllers import ForkLaw

    ints, floats = lawcodes.flatten(ForkLaw(law, damper.LinearDamper(800.0), friction.NoFriction()))
    program = [(ints[lawcodes.I_SPRING + 2 * k], ints[lawcodes.I_SPRING + 2 * k + 1])
               for k in range(ints[lawcodes.I_NSPRING])]
    assert [op for op, _ in program] == [lawcodes.SP_BILINEAR, lawcodes.SP_TOPOUT, lawcodes.SP_STOPS]
    at = dict(program)
    assert floats[at[lawcodes.SP_BILINEAR] + offsets(spring.BilinearSpring).knee] == 0.05
    assert floats[at[lawcodes.SP_TOPOUT] + offsets(spring.TopOutSpring).engagement] == 150.0 / 3e5
    assert floats[at[lawcodes.SP_STOPS] + offsets(stops.EndStops).bumper_start] == pytest.approx(0.14)
    assert floats[ints[lawcodes.I_DAMPER_AT] + offsets(damper.LinearDamper).coefficient] == 800.0


def test_every_formula_has_one_compiled_twin_of_the_same_code():
    pytest.importorskip("numba")
    from mtbmj.controllers import jit, kernels  # noqa: F401  (compiles the twins)
    import mtbmj.rolling.callback_compiled  # noqa: F401

    twins = jit.compiled_twins()
    missing = [name for name, fn in plain_functions().items() if fn not in twins]
    # Python only: the stops' energy (the energy balance), the pressure relation (the
    # configuration), and sliding_level, which picks a formula by the law's type where the kernels
    # pick it by its code
    python_only = {"mtbmj.controllers.stops.stop_energy", "mtbmj.controllers.tire.static_rate_from_pressure",
                   "mtbmj.controllers.friction.sliding_level"}
    assert sorted(set(missing) - python_only) == []
    for fn, twin in twins.items():
        assert twin.py_func.__code__ is fn.__code__  # the same source, not a copy


def test_the_kernels_hold_no_formula():
    """kernels.py and the compiled callbacks only dispatch and read parameters by name: no maths
    library call, and no multiplication, division or power outside an index, except the named
    places that are not a law (the logger filter's recursion, the callbacks' own geometry)."""
    tree = ast.parse((ROOT / "controllers" / "kernels.py").read_text())
    allowed = {"modal_filter"}
    bad = []
    for fn in (n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name not in allowed):
        indices = {id(s) for n in ast.walk(fn) if isinstance(n, ast.Subscript) for s in ast.walk(n.slice)}
        for node in ast.walk(fn):
            if isinstance(node, ast.Attribute) and getattr(node.value, "id", "") == "math":
                bad.append(f"{fn.name}: math.{node.attr}")
            if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div, ast.Pow)) \
                    and id(node) not in indices:
                bad.append(f"{fn.name}: line {node.lineno}")
    assert bad == []


def test_the_law_objects_run_their_plain_functions():
    """Swap a formula for a marker: the law object's force follows (it calls the function, it does
    not carry a copy)."""
    marker = np.pi
    original = spring.bilinear_spring_force
    try:
        spring.bilinear_spring_force = lambda *args: marker
        assert spring.BilinearSpring(1.0, 2.0, 0.1).force(0.2, 0.0) == marker
    finally:
        spring.bilinear_spring_force = original
    assert spring.BilinearSpring(1.0, 2.0, 0.1).force(0.2, 0.0) == pytest.approx(0.1 + 0.2)


def test_a_kernel_cached_on_disk_is_keyed_on_the_law_sources():
    """A kernel inlines formulas from the law modules, so numba's disk cache must not serve it once
    one of them changed: its entries are stamped with the sources of all of controllers/ and of every
    file whose functions it reaches."""
    pytest.importorskip("numba")
    import hashlib

    from mtbmj.controllers import compiled, jit, kernels

    digest = hashlib.sha256()
    for path in sorted((ROOT / "controllers").glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    assert jit.LAW_SOURCES_STAMP == digest.hexdigest()
    if not jit.CACHE:
        pytest.skip("numba keeps no disk cache here")
    for cached in (kernels.fork_force, kernels.fork_forces, compiled.dispatcher()):
        # controllers/ and every other source the function reaches (tests/test_compiled_sources.py)
        fn = getattr(cached, "py_func", None) or cached._pyfunc
        assert cached._cache._impl.locator.get_source_stamp()[1] == jit.sources_stamp(fn)
        expected = hashlib.sha256(digest.hexdigest().encode())
        for path in jit.compiled_sources(fn):
            expected.update(Path(path).name.encode())
            expected.update(hashlib.sha256(Path(path).read_bytes()).hexdigest().encode())
        assert jit.sources_stamp(fn) == expected.hexdigest()

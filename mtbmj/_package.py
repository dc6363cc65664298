"""The package's version (one place; ``mtbmj.__version__`` and every manifest read it) and the lazy
exports of its packages: a package lists its public names in a table and imports the module that
holds one only when the name is first asked for, so ``import mtbmj`` stays cheap."""
from __future__ import annotations

import importlib

__version__ = "0.1.0"


def lazy_exports(package: str, table: dict[str, str], namespace: dict):
    """``(__getattr__, __dir__)`` for ``package`` (PEP 562): ``table`` maps a public name to
    ``"module"`` or ``"module:name there"``; a resolved name is kept in ``namespace``."""

    def __getattr__(name):
        try:
            module, _, attribute = table[name].partition(":")
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(module), attribute or name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(table))

    return __getattr__, __dir__


def moved(old: str, new: str, names: dict[str, str] | None = None):
    """The ``__getattr__`` (PEP 562) of a module that moved from ``old`` to ``new``: a name asked of
    the old place is taken from the new one, with a ``DeprecationWarning`` that names both. A moved
    module stays importable from its old place for one release; the shim holds nothing else
    (``tests/test_layout.py`` checks it). ``names``: a name that went elsewhere, to
    ``"module:name there"``."""

    def __getattr__(name):
        if name.startswith("__") and name.endswith("__"):
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        module, _, there = (names or {}).get(name, new).partition(":")
        value = getattr(importlib.import_module(module), there or name)
        import warnings

        warnings.warn(f"{old} moved to {module}: import {there or name} from there ({old} goes in the next release)",
                      DeprecationWarning, stacklevel=2)
        return value

    return __getattr__

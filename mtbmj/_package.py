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

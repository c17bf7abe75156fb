"""Names a package loads from their modules on first use (PEP 562 ``__getattr__``), so that
importing one light module of the package does not load the heavy libraries of the others."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(package: str, modules: dict[str, str],
               namespace: dict[str, Any]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package``: ``modules`` maps a public name to the
    (relative) module that defines it; a name loaded once is kept in ``namespace`` (the
    package's globals), so later lookups do not come back here."""
    def load(name: str) -> Any:
        module = modules.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        namespace[name] = value
        return value
    return load

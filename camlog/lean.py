"""Start-up costs a command can leave out.

pyarrow (which rerun uses for every component) checks whether a Python list it converts is
a pandas object, and to do so imports pandas, when it is installed, on its first conversion:
0.3-0.4 s of CPU, more than a short view spends on its images. Commands that never hand a
pandas object to pyarrow hide pandas from the import system before loading rerun; pyarrow
then finds it absent, as on a lean install, and treats lists as lists. Only in a process that
is camlog's own (the ``camlog`` program): pyarrow remembers the answer for the process's
life, so code that calls :func:`camlog.cli.main` in its own process keeps its pandas.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

__all__ = ["pandas_hidden", "without_pandas"]


class _Hidden:
    """A meta path finder before all others that reports a package as not installed."""

    def __init__(self, package: str) -> None:
        self.package = package

    def find_spec(self, name: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> ModuleSpec | None:
        if name == self.package or name.startswith(self.package + "."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


def without_pandas() -> None:
    """Make ``import pandas`` fail in this process unless pandas is already loaded."""
    if "pandas" in sys.modules or pandas_hidden():
        return
    sys.meta_path.insert(0, _Hidden("pandas"))


def pandas_hidden() -> bool:
    """Whether :func:`without_pandas` hides pandas in this process."""
    return any(isinstance(f, _Hidden) for f in sys.meta_path)

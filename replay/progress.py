"""Progress bars that cost nothing when they are off: ``tqdm`` is loaded only for a bar that
may show (``progress`` None shows it on a terminal, True always, False never)."""

from __future__ import annotations

from types import TracebackType
from typing import Any, Self

__all__ = ["progress_bar"]


class _NoBar:
    """What a bar offers, doing nothing."""

    def update(self, n: int = 1) -> None:
        """Count ``n`` more steps (nothing to show)."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        pass


def progress_bar(*, total: int, unit: str, desc: str, progress: bool | None) -> Any:
    """A ``tqdm`` bar that disappears when done, or a bar that does nothing (``progress``
    False)."""
    if progress is False:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, desc=desc, leave=False,
                disable=None if progress is None else not progress)

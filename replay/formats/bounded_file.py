"""A file whose reads stop at its end, for format libraries that trust length fields.

A reader asked for ``n`` bytes allocates ``n`` bytes before it reads (Python's buffered and
raw files alike), so a damaged length field of 2**64 - 1 would allocate that much. Reads
through :class:`BoundedFile` ask for at most what is left of the file: a length field can
make a read come up short, which the format library reports as damage, never allocate more
than the file holds. (It is not an :class:`io.RawIOBase`: libraries wrap those in a
``BufferedReader``, whose reads allocate what they are asked for.)
"""

from __future__ import annotations

import io
from types import TracebackType
from typing import IO, Self

__all__ = ["BoundedFile"]


class BoundedFile:
    """Read-only view of a seekable binary file whose reads are clamped to its size."""

    def __init__(self, file: IO[bytes]) -> None:
        self._file = file
        position = file.tell()
        self.size = file.seek(0, io.SEEK_END)
        file.seek(position)

    def read(self, size: int | None = -1) -> bytes:
        """At most ``size`` bytes (all that is left when negative), never past the end."""
        left = max(0, self.size - self._file.tell())
        return self._file.read(left if size is None or size < 0 else min(size, left))

    def readline(self, limit: int = 1 << 16) -> bytes:
        """One line of at most ``limit`` bytes."""
        return self._file.readline(limit)

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        """Move like the file below."""
        return self._file.seek(offset, whence)

    def tell(self) -> int:
        """Position in the file below."""
        return self._file.tell()

    def seekable(self) -> bool:
        """Always: the size is known."""
        return True

    def readable(self) -> bool:
        """Always."""
        return True

    def close(self) -> None:
        """Close the file below."""
        self._file.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

"""Records that hold numpy arrays: equality by value, and the size of an image's pixels."""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["ArrayFields", "PixelShape", "Pixels"]

#: image pixels in the layout of their encoding: (H, W) or (H, W, C)
Pixels = npt.NDArray[Any]


class ArrayFields:
    """Equality of a dataclass whose fields hold numpy arrays: arrays equal in dtype and
    values, sequences as tuples, anything else by ``==``; such records are not hashable."""

    __slots__ = ()

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self))  # type: ignore[arg-type]

    __hash__ = None  # type: ignore[assignment]


def _same(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and bool(np.array_equal(a, b))
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return tuple(a) == tuple(b)
    return bool(a == b)


class PixelShape:
    """``width`` and ``height`` of a record holding ``pixels`` ``(H, W)`` or ``(H, W, C)``."""

    __slots__ = ()
    pixels: Pixels

    @property
    def width(self) -> int:
        """Image width in pixels."""
        return int(self.pixels.shape[1])

    @property
    def height(self) -> int:
        """Image height in pixels."""
        return int(self.pixels.shape[0])

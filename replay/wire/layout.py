"""An image message's pixel buffer (rows of ``step`` bytes) cut into a pixel array."""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..buffer_layout import check_buffer
from ..frames import raw_encoding
from ..messages import Image

__all__ = ["image_from_buffer"]


def image_from_buffer(stamp_ns: int, frame_id: str, *, width: int, height: int, encoding: str,
                      step: int, data: bytes | memoryview | np.ndarray, bigendian: bool
                      ) -> Image:
    """The Image of a raw buffer in the layout its encoding has in the frame decoders'
    table: row padding dropped, big-endian values made native."""
    buf = np.frombuffer(data, dtype=np.uint8) if not isinstance(data, np.ndarray) else \
        data.view(np.uint8).reshape(-1)
    buffer_rows = check_buffer(encoding, width=width, height=height, step=step, size=buf.size)
    raw = raw_encoding(encoding)
    dtype, channels = raw.dtype, raw.channels
    row = width * channels * dtype.itemsize
    rows = buf[: step * buffer_rows].reshape(buffer_rows, step)[:, :row]
    order: Literal["<", ">"] = ">" if bigendian else "<"
    pixels = np.ascontiguousarray(rows).view(dtype.newbyteorder(order))
    if order == ">":
        pixels = pixels.astype(dtype)
    shape = (buffer_rows, width) if channels == 1 else (buffer_rows, width, channels)
    return Image(stamp_ns, frame_id, encoding, pixels.reshape(shape))

"""An image message's pixel buffer (rows of ``step`` bytes) cut into a pixel array."""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..buffer_layout import LAYOUTS, check_buffer
from ..messages import Image

__all__ = ["image_from_buffer"]


def image_from_buffer(stamp_ns: int, frame_id: str, *, width: int, height: int, encoding: str,
                      step: int, data: bytes | memoryview | np.ndarray, bigendian: bool
                      ) -> Image:
    """The Image of a raw buffer in its encoding's layout (:mod:`replay.buffer_layout`): row
    padding dropped, big-endian values made native."""
    buf = np.frombuffer(data, dtype=np.uint8) if not isinstance(data, np.ndarray) else \
        data.view(np.uint8).reshape(-1)
    buffer_rows = check_buffer(encoding, width=width, height=height, step=step, size=buf.size)
    layout = LAYOUTS[encoding]
    dtype, channels = np.dtype(layout.value), layout.channels
    row = width * channels * dtype.itemsize
    rows = buf[: step * buffer_rows].reshape(buffer_rows, step)[:, :row]
    order: Literal["<", ">"] = ">" if bigendian else "<"
    pixels = np.ascontiguousarray(rows).view(dtype.newbyteorder(order))
    if order == ">":
        pixels = pixels.astype(dtype)
    shape = (buffer_rows, width) if channels == 1 else (buffer_rows, width, channels)
    return Image(stamp_ns, frame_id, encoding, pixels.reshape(shape))

"""An image message's pixel buffer (rows of ``step`` bytes) cut into a pixel array."""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import EncodingError
from ..frames import raw_encoding
from ..messages import Image

__all__ = ["image_from_buffer"]


def image_from_buffer(stamp_ns: int, frame_id: str, *, width: int, height: int, encoding: str,
                      step: int, data: bytes | memoryview | np.ndarray, bigendian: bool
                      ) -> Image:
    """The Image of a raw buffer in the layout its encoding has in the frame decoders'
    table: row padding dropped, big-endian values made native."""
    raw = raw_encoding(encoding)
    dtype, channels = raw.dtype, raw.channels
    row = width * channels * dtype.itemsize
    buf = np.frombuffer(data, dtype=np.uint8) if not isinstance(data, np.ndarray) else \
        data.view(np.uint8).reshape(-1)
    # semi-planar YUV: chroma rows below the luma rows; nv24's chroma rows are two luma
    # rows long, which only unpadded rows (step == width) cut right
    planes = height * raw.rows
    if planes.denominator != 1 or (raw.rows.denominator == 1 < raw.rows and step != row):
        raise EncodingError(f"{encoding} of {width}x{height} with step {step}: nv21 needs an "
                            "even height, nv24 unpadded rows")
    buffer_rows = int(planes)
    if width < 0 or height < 0 or step < row or buf.size < step * buffer_rows:
        raise EncodingError(
            f"image buffer of {buf.size} bytes too small for {width}x{height} {encoding} "
            f"(step {step})"
        )
    rows = buf[: step * buffer_rows].reshape(buffer_rows, step)[:, :row]
    order: Literal["<", ">"] = ">" if bigendian else "<"
    pixels = np.ascontiguousarray(rows).view(dtype.newbyteorder(order))
    if order == ">":
        pixels = pixels.astype(dtype)
    shape = (buffer_rows, width) if channels == 1 else (buffer_rows, width, channels)
    return Image(stamp_ns, frame_id, encoding, pixels.reshape(shape))

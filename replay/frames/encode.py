"""The one table of frame encoders: :class:`Frame` -> an Image or CompressedImage message.

Every raw encoding whose table entry converts nothing (``Raw.convert`` is None) can be
written: the frame is brought to the entry's colour order and bit depth. Compressed formats
are one function each.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from ..errors import EncodingError
from ..messages import CompressedImage, Image
from .compressed import encode_compressed_depth, encode_still, original_encoding
from .decode import DECODERS, Raw
from .frame import Color, Frame, Pixels
from .lookup import table_entry

__all__ = ["ENCODERS", "decompress", "encode_compressed", "encode_image", "natural_encoding"]

#: (source colour, target colour) -> name of OpenCV's conversion (OpenCV itself is imported by
#: the first conversion, not by opening a log)
_COLOR_CODES: dict[tuple[Color, Color], str] = {
    (Color.RGB, Color.BGR): "COLOR_RGB2BGR", (Color.BGR, Color.RGB): "COLOR_BGR2RGB",
    (Color.RGB, Color.RGBA): "COLOR_RGB2RGBA", (Color.RGB, Color.BGRA): "COLOR_RGB2BGRA",
    (Color.BGR, Color.RGBA): "COLOR_BGR2RGBA", (Color.BGR, Color.BGRA): "COLOR_BGR2BGRA",
    (Color.RGBA, Color.RGB): "COLOR_RGBA2RGB", (Color.RGBA, Color.BGR): "COLOR_RGBA2BGR",
    (Color.RGBA, Color.BGRA): "COLOR_RGBA2BGRA", (Color.BGRA, Color.RGB): "COLOR_BGRA2RGB",
    (Color.BGRA, Color.BGR): "COLOR_BGRA2BGR", (Color.BGRA, Color.RGBA): "COLOR_BGRA2RGBA",
    (Color.RGB, Color.MONO): "COLOR_RGB2GRAY", (Color.BGR, Color.MONO): "COLOR_BGR2GRAY",
    (Color.RGBA, Color.MONO): "COLOR_RGBA2GRAY", (Color.BGRA, Color.MONO): "COLOR_BGRA2GRAY",
    (Color.MONO, Color.RGB): "COLOR_GRAY2RGB", (Color.MONO, Color.BGR): "COLOR_GRAY2BGR",
    (Color.MONO, Color.RGBA): "COLOR_GRAY2RGBA", (Color.MONO, Color.BGRA): "COLOR_GRAY2BGRA",
}


def _pixels_as(frame: Frame, raw: Raw) -> Pixels:
    """The frame's pixels in ``raw``'s colour order and dtype."""
    px = frame.pixels
    if px.dtype != raw.dtype:
        if raw.dtype == np.uint8:
            px = frame.to8()
        elif raw.dtype == np.uint16 and px.dtype == np.uint8:
            px = px.astype(np.uint16) * 257  # 0..255 -> 0..65535
        else:
            raise EncodingError(f"cannot write {px.dtype} {frame.color} pixels as {raw.dtype}")
    source = Color.MONO if frame.color is Color.DEPTH else frame.color
    target = Color.MONO if raw.color is Color.DEPTH else raw.color
    if source is target:
        return px
    import cv2

    return np.asarray(cv2.cvtColor(px, getattr(cv2, _COLOR_CODES[source, target])))


def _raw_encoder(encoding: str, raw: Raw) -> Callable[[Frame], Image]:
    def encode(frame: Frame) -> Image:
        return Image(frame.stamp_ns, frame.frame_id, encoding, _pixels_as(frame, raw))
    return encode


#: (typed record, encoding or format) -> encoder (compressed ones take keyword options)
ENCODERS: dict[tuple[type, str], Callable[..., Any]] = {
    **{(Image, encoding): _raw_encoder(encoding, raw)
       for (kind, encoding), raw in DECODERS.items()
       if isinstance(raw, Raw) and raw.convert is None},
    (CompressedImage, "jpeg"): partial(encode_still, fmt="jpeg"),
    (CompressedImage, "png"): partial(encode_still, fmt="png"),
    (CompressedImage, "compressedDepth"): encode_compressed_depth,
}


def natural_encoding(frame: Frame) -> str:
    """The raw encoding that holds the frame as it is: its source encoding when that one
    does, else the first table entry with its colour order and dtype."""
    candidates = [frame.source] + [e for (t, e) in DECODERS if t is Image]
    for encoding in candidates:
        raw = DECODERS.get((Image, encoding))
        if isinstance(raw, Raw) and raw.convert is None and raw.color is frame.color \
                and raw.dtype == frame.pixels.dtype and raw.depth_unit_m == frame.depth_unit_m:
            return encoding
    raise EncodingError(f"no raw encoding holds {frame.pixels.dtype} {frame.color} frames")


def encode_image(frame: Frame, encoding: str | None = None) -> Image:
    """An Image message of the frame in ``encoding`` (default: :func:`natural_encoding`,
    which keeps the pixels without a copy)."""
    if encoding is None:
        return Image(frame.stamp_ns, frame.frame_id, natural_encoding(frame), frame.pixels)
    encoder = table_entry(ENCODERS, Image, encoding, error=EncodingError,
                          unknown="cannot write images as", choices="writable: {}")
    image: Image = encoder(frame)
    return image


def encode_compressed(frame: Frame, fmt: str = "jpeg", *, jpeg_quality: int = 90
                      ) -> CompressedImage:
    """A CompressedImage of the frame in ``fmt`` (``jpeg`` or ``png``)."""
    encoder = table_entry(ENCODERS, CompressedImage, fmt, error=EncodingError,
                          unknown="unsupported compression", choices="use {}", sep=" or ")
    original = frame.source if (Image, frame.source) in DECODERS else ""
    message: CompressedImage = encoder(frame, original=original, jpeg_quality=jpeg_quality)
    return message


def decompress(message: CompressedImage, frame: Frame) -> Image:
    """The raw image a compressed message's frame came from: in the original encoding its
    format string names when that one can be written (image_transport's decompression),
    else in the frame's natural encoding."""
    original = original_encoding(message.format)
    if (Image, original) in ENCODERS:
        return encode_image(frame, original)
    return encode_image(frame)

"""How an image message's buffer holds its pixels, per raw encoding: the value type, values
per pixel and buffer rows per image row, and the check that a buffer holds a whole image.

Numbers only, without numpy, so that ``camlog info`` checks a log's first image without
loading numpy; :data:`replay.frames.raw.RAW_ENCODINGS` takes each encoding's layout from here.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from .errors import EncodingError, UnsupportedEncodingError

__all__ = ["LAYOUTS", "BufferLayout", "check_buffer", "layout_of"]

#: numpy dtype name of a value -> its bytes
VALUE_BYTES = {"uint8": 1, "uint16": 2, "int16": 2, "float32": 4}


@dataclass(frozen=True, slots=True)
class BufferLayout:
    """``channels`` values of type ``value`` (a numpy dtype name) per pixel; semi-planar YUV
    (nv21, nv24) holds its chroma plane below the luma plane: its buffer has ``rows`` times
    as many rows of ``width`` values as the image has rows."""

    value: str
    channels: int
    rows: Fraction = Fraction(1)

    @property
    def pixel_bytes(self) -> int:
        """Bytes of one pixel's values."""
        return VALUE_BYTES[self.value] * self.channels


#: ROS bayer patterns (the colours of the top-left 2x2 block)
BAYER_PATTERNS = ("rggb", "bggr", "gbrg", "grbg")

#: raw encoding name -> its buffer layout
LAYOUTS: dict[str, BufferLayout] = {
    **{name: BufferLayout("uint8", 3) for name in ("rgb8", "bgr8", "8UC3")},
    **{name: BufferLayout("uint8", 4) for name in ("rgba8", "bgra8", "8UC4")},
    **{name: BufferLayout("uint16", 3) for name in ("rgb16", "bgr16")},
    **{name: BufferLayout("uint16", 4) for name in ("rgba16", "bgra16")},
    **{name: BufferLayout("uint8", 1) for name in ("mono8", "8UC1")},
    **{name: BufferLayout("uint16", 1) for name in ("mono16", "16UC1")},
    **{name: BufferLayout("uint8", 2)
       for name in ("8UC2", "yuv422", "uyvy", "yuv422_yuy2", "yuyv")},
    "16SC1": BufferLayout("int16", 1),
    "32FC1": BufferLayout("float32", 1),
    **{f"bayer_{pattern}8": BufferLayout("uint8", 1) for pattern in BAYER_PATTERNS},
    **{f"bayer_{pattern}16": BufferLayout("uint16", 1) for pattern in BAYER_PATTERNS},
    "nv21": BufferLayout("uint8", 1, Fraction(3, 2)),
    "nv24": BufferLayout("uint8", 1, Fraction(3)),
}


def layout_of(encoding: str) -> BufferLayout:
    """The layout of a raw encoding; :class:`UnsupportedEncodingError` naming the supported
    ones."""
    layout = LAYOUTS.get(encoding)
    if layout is None:
        raise UnsupportedEncodingError(f"unsupported image encoding {encoding!r} "
                                       f"(supported: {', '.join(sorted(LAYOUTS))})")
    return layout


def check_buffer(encoding: str, *, width: int, height: int, step: int, size: int) -> int:
    """Rows of ``step`` bytes that a ``size``-byte buffer of a ``width`` x ``height`` image
    in ``encoding`` holds its pixels in; :class:`EncodingError` when it cannot hold them."""
    layout = layout_of(encoding)
    row = width * layout.pixel_bytes
    # semi-planar YUV: chroma rows below the luma rows; nv24's chroma rows are two luma
    # rows long, which only unpadded rows (step == width) cut right
    planes = height * layout.rows
    if planes.denominator != 1 or (layout.rows.denominator == 1 < layout.rows and step != row):
        raise EncodingError(f"{encoding} of {width}x{height} with step {step}: nv21 needs an "
                            "even height, nv24 unpadded rows")
    buffer_rows = int(planes)
    if width < 0 or height < 0 or step < row or size < step * buffer_rows:
        raise EncodingError(
            f"image buffer of {size} bytes too small for {width}x{height} {encoding} "
            f"(step {step})"
        )
    return buffer_rows

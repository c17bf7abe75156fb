"""Raw image encodings (``sensor_msgs/Image``, ``foxglove.RawImage``): the layout of each
buffer and the frame it makes. A new raw encoding is one :data:`RAW_ENCODINGS` entry and
its buffer's layout in :data:`replay.buffer_layout.LAYOUTS`.

The entries say how ROS's image_encodings.hpp and cv_bridge read the encodings: 3- and
4-channel 8UC are BGR(A), 16UC1 is depth in millimetres and 32FC1 depth in metres (REP 118);
nv21 and nv24 are V4L2's semi-planar YUV 4:2:0 and 4:4:4 (image_encodings.hpp links there).
This module knows no message type (the typed records check their pixels against it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Protocol

import numpy as np

from ..buffer_layout import LAYOUTS
from ..errors import EncodingError
from .frame import Color, Frame, Pixels

__all__ = ["RAW_ENCODINGS", "Raw", "RawImage"]


class RawImage(Protocol):
    """What a raw image message offers a decoder (``replay.messages.Image``)."""

    @property
    def stamp_ns(self) -> int:
        """Header stamp."""
        ...

    @property
    def frame_id(self) -> str:
        """Header frame."""
        ...

    @property
    def encoding(self) -> str:
        """Raw encoding name."""
        ...

    @property
    def pixels(self) -> Pixels:
        """The buffer in the encoding's layout."""
        ...


@dataclass(frozen=True, slots=True)
class Raw:
    """One raw image encoding: ``channels`` values of ``dtype`` per pixel, decoded to a
    ``color`` frame by ``convert`` (None: the pixels as they are); ``rows`` buffer rows per
    image row (see :class:`replay.buffer_layout.BufferLayout`)."""

    dtype: np.dtype[Any]
    channels: int
    color: Color
    convert: Callable[[Pixels], Pixels] | None = None
    depth_unit_m: float | None = None
    rows: Fraction = Fraction(1)

    def image_rows(self, buffer_rows: int) -> int:
        """Rows of the image held in ``buffer_rows`` rows of this encoding's buffer
        (:class:`EncodingError` when they hold no whole image)."""
        height = buffer_rows / self.rows
        if height.denominator != 1 or (self.rows.denominator > 1 and height % 2):
            raise EncodingError(f"{buffer_rows} buffer rows hold no whole image "
                                f"({self.rows} rows per image row, even heights)")
        return int(height)

    def __call__(self, image: RawImage) -> Frame:
        """The frame of one image message of this encoding."""
        pixels = image.pixels if self.convert is None else self.convert(image.pixels)
        return Frame(image.stamp_ns, image.frame_id, pixels, self.color, image.encoding,
                     self.depth_unit_m)


def _cv(code: str) -> Callable[[Pixels], Pixels]:
    """OpenCV's colour conversion named ``code`` (a ``cv2`` constant) as a ``convert`` step;
    OpenCV is imported by the first conversion, not by opening a log."""
    def convert(pixels: Pixels) -> Pixels:
        import cv2

        try:
            return np.asarray(cv2.cvtColor(pixels, getattr(cv2, code)))
        except cv2.error as err:  # e.g. an odd size where chroma is shared by pixel pairs
            raise EncodingError(f"cannot convert {pixels.shape[1]}x{pixels.shape[0]} pixels "
                                f"with OpenCV's {code}: {err.err}") from None
    return convert


def _nv24_to_rgb(pixels: Pixels) -> Pixels:
    """NV24 (a luma plane, then a plane of interleaved U, V for every pixel) to RGB with
    the BT.601 limited-range formula OpenCV uses for nv21 and UYVY: each pixel becomes a
    UYVY pair of two equal pixels, which OpenCV converts."""
    height = pixels.shape[0] // 3
    luma, chroma = pixels[:height], pixels[height:].reshape(height, -1, 2)
    pairs = np.empty((height, 2 * luma.shape[1], 2), np.uint8)
    pairs[:, 0::2, 0], pairs[:, 1::2, 0] = chroma[:, :, 0], chroma[:, :, 1]  # U, V
    pairs[:, 0::2, 1] = pairs[:, 1::2, 1] = luma
    return np.ascontiguousarray(_cv("COLOR_YUV2RGB_UYVY")(pairs)[:, 0::2])


def _first_channel(pixels: Pixels) -> Pixels:
    return np.ascontiguousarray(pixels[:, :, 0])


#: ROS bayer pattern (the colours of the top-left 2x2 block) -> OpenCV demosaicing to RGB
_BAYER = {"rggb": "COLOR_BayerRGGB2RGB", "bggr": "COLOR_BayerBGGR2RGB",
          "gbrg": "COLOR_BayerGBRG2RGB", "grbg": "COLOR_BayerGRBG2RGB"}


def _raw(encoding: str, color: Color, convert: Callable[[Pixels], Pixels] | None = None, *,
         depth_unit_m: float | None = None) -> Raw:
    """The entry of ``encoding``: its buffer's layout (:data:`LAYOUTS`), decoded to a
    ``color`` frame by ``convert``."""
    layout = LAYOUTS[encoding]
    return Raw(np.dtype(layout.value), layout.channels, color, convert, depth_unit_m,
               layout.rows)


#: raw encoding name -> its entry
RAW_ENCODINGS: dict[str, Raw] = {
    "rgb8": _raw("rgb8", Color.RGB),
    "bgr8": _raw("bgr8", Color.BGR),
    "rgba8": _raw("rgba8", Color.RGBA),
    "bgra8": _raw("bgra8", Color.BGRA),
    "rgb16": _raw("rgb16", Color.RGB),
    "bgr16": _raw("bgr16", Color.BGR),
    "rgba16": _raw("rgba16", Color.RGBA),
    "bgra16": _raw("bgra16", Color.BGRA),
    "mono8": _raw("mono8", Color.MONO),
    "mono16": _raw("mono16", Color.MONO),
    "8UC1": _raw("8UC1", Color.MONO),
    "8UC2": _raw("8UC2", Color.MONO, _first_channel),
    "8UC3": _raw("8UC3", Color.BGR),
    "8UC4": _raw("8UC4", Color.BGRA),
    "16UC1": _raw("16UC1", Color.DEPTH, depth_unit_m=0.001),
    "16SC1": _raw("16SC1", Color.MONO),
    "32FC1": _raw("32FC1", Color.DEPTH, depth_unit_m=1.0),
    **{name: _raw(name, Color.RGB, _cv(code))
       for pattern, code in _BAYER.items() for name in (f"bayer_{pattern}8", f"bayer_{pattern}16")},
    "yuv422": _raw("yuv422", Color.RGB, _cv("COLOR_YUV2RGB_UYVY")),
    "uyvy": _raw("uyvy", Color.RGB, _cv("COLOR_YUV2RGB_UYVY")),
    "yuv422_yuy2": _raw("yuv422_yuy2", Color.RGB, _cv("COLOR_YUV2RGB_YUY2")),
    "yuyv": _raw("yuyv", Color.RGB, _cv("COLOR_YUV2RGB_YUY2")),
    "nv21": _raw("nv21", Color.RGB, _cv("COLOR_YUV2RGB_NV21")),
    "nv24": _raw("nv24", Color.RGB, _nv24_to_rgb),
}

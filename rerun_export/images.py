"""Camera images as rerun archetypes: raw pixels, JPEG re-encoded, or compressed passed through.

A ``CompressedImage`` (JPEG or PNG) goes into the recording as ``EncodedImage`` without being
decoded. Raw frames become ``EncodedImage`` JPEGs when a quality is given and they have 8-bit
channels (OpenCV encodes; 16-bit images stay raw since JPEG cannot hold them), ``Image`` in
their own colour order otherwise, and depth frames ``DepthImage`` with their metre scale.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal

import cv2
import numpy as np
import rerun as rr

from replay.errors import EncodingError
from replay.frames import Color, Frame, decode_frame
from replay.messages import CompressedImage, CompressedVideo, Image, Message

from .columns import ImageRow

__all__ = ["COLOR_MODELS", "complete", "encoded_image", "image_row", "is_keyframe", "media_type",
           "rerun_image", "still_frame", "video_sample"]

#: CompressedVideo format -> rerun's codec
VIDEO_CODECS = {"h264": rr.VideoCodec.H264, "h265": rr.VideoCodec.H265}

#: colour order -> rerun colour model
COLOR_MODELS: dict[Color, Literal["RGB", "BGR", "RGBA", "BGRA", "L"]] = {
    Color.RGB: "RGB", Color.BGR: "BGR", Color.RGBA: "RGBA", Color.BGRA: "BGRA",
    Color.MONO: "L",
}


def media_type(data: bytes) -> str | None:
    """``image/jpeg`` or ``image/png`` from the magic bytes; None for anything else."""
    if data[:3] == b"\xff\xd8\xff":
        return "image/jpeg"
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        return "image/png"
    return None


def complete(data: bytes, kind: str) -> bool:
    """Whether JPEG or PNG bytes end as their format requires (a file cut short does not:
    JPEG's EOI marker, PNG's empty IEND chunk with its CRC).

    >>> complete(b"\\xff\\xd8\\xff\\xe0\\xff\\xd9", "image/jpeg")
    True
    >>> complete(b"\\xff\\xd8\\xff\\xe0", "image/jpeg")
    False
    """
    if kind == "image/jpeg":
        return data.rstrip(b"\x00").endswith(b"\xff\xd9")
    return data[-12:-4] == b"\x00\x00\x00\x00IEND"


def encoded_image(message: CompressedImage, *, draw_order: float | None = None) -> Any:
    """``rr.EncodedImage`` holding the compressed bytes as they are (None: unknown format,
    or bytes cut short, which the caller decodes to find out)."""
    kind = media_type(message.data)
    if kind is None or not complete(message.data, kind):
        return None
    return rr.EncodedImage(contents=message.data, media_type=kind, draw_order=draw_order)


def rerun_image(
    frame: Frame, *, jpeg_quality: int | None = None, draw_order: float | None = None
) -> Any:
    """``rr.Image`` of the pixels in their colour order, ``rr.DepthImage`` (with its metre
    scale) for depth, or a JPEG ``rr.EncodedImage`` when ``jpeg_quality`` is set and the
    image has 8-bit colour or grey channels."""
    pixels = frame.pixels
    if frame.color is Color.DEPTH:
        assert frame.depth_unit_m is not None
        return rr.DepthImage(pixels, meter=1.0 / frame.depth_unit_m, draw_order=draw_order)
    if jpeg_quality is not None and pixels.dtype == np.uint8:
        array = pixels if frame.color is Color.MONO else frame.bgr8()
        ok, buf = cv2.imencode(".jpg", array, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
        if ok:
            return rr.EncodedImage(contents=buf.tobytes(), media_type="image/jpeg",
                                   draw_order=draw_order)
    return rr.Image(pixels, color_model=COLOR_MODELS[frame.color], draw_order=draw_order)


def image_row(frame: Frame, *, draw_order: float | None = None) -> ImageRow | None:
    """The pixels of a colour or grey frame as a row that can go to rerun in a column
    (:mod:`rerun_export.columns`); None for depth, which needs its metre scale."""
    if frame.color is Color.DEPTH:
        return None
    return ImageRow(frame.pixels, COLOR_MODELS[frame.color], draw_order)


def still_frame(message: Message) -> Frame:
    """The frame of a still image message (ValueError for any other message)."""
    if not isinstance(message, Image | CompressedImage):
        raise ValueError(f"expected an image, got {type(message).__name__}")
    return decode_frame(message)


def is_keyframe(message: Message) -> bool:
    """Whether a message is a video sample holding an IDR picture (Annex B: H.264 NAL type
    5, H.265 16-21)."""
    if not isinstance(message, CompressedVideo):
        return False
    data = message.data
    start = data.find(b"\x00\x00\x01")
    while start >= 0 and start + 3 < len(data):
        header = data[start + 3]
        if message.format == "h264" and header & 0x1F == 5:
            return True
        if message.format == "h265" and 16 <= (header >> 1) & 0x3F <= 21:
            return True
        start = data.find(b"\x00\x00\x01", start + 3)
    return False


def video_sample(message: Message) -> Any:
    """``rr.VideoStream`` holding a compressed video sample as it is (rerun decodes); None
    for any other message."""
    if not isinstance(message, CompressedVideo):
        return None
    codec = VIDEO_CODECS.get(message.format)
    if codec is None:
        raise EncodingError(f"rerun cannot play {message.format!r} video")
    return rr.VideoStream(codec=codec, sample=message.data, is_keyframe=is_keyframe(message))


def image_archetype(message: Image | CompressedImage, jpeg_quality: int | None,
                    encode: Callable[..., Any], *, draw_order: float | None = None) -> Any:
    """What rerun gets for one image: its encoded bytes as they are, a raw image row, or a
    JPEG made by ``encode`` (a worker thread) when ``jpeg_quality`` is given."""
    if isinstance(message, CompressedImage):
        archetype = encoded_image(message, draw_order=draw_order)
        if archetype is not None:
            return archetype
    frame = decode_frame(message)
    if jpeg_quality is None:
        row = image_row(frame, draw_order=draw_order)
        if row is not None:
            return row
    if frame.pixels.dtype == np.uint8:  # JPEG: encoded on a worker thread
        return encode(rerun_image, frame, draw_order=draw_order, jpeg_quality=jpeg_quality)
    return rerun_image(frame, jpeg_quality=jpeg_quality, draw_order=draw_order)

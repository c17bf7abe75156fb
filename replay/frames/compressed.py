"""Compressed still images (JPEG, PNG) to frames and back, through OpenCV."""

from __future__ import annotations

import struct

import numpy as np

from ..errors import EncodingError
from ..messages import CompressedImage
from .frame import Color, Frame, Pixels
from .rvl import decode_rvl

__all__ = [
    "compressed_kind",
    "decode_compressed_depth",
    "decode_still",
    "encode_compressed_depth",
    "encode_still",
    "original_encoding",
]

#: compressed_depth_image_transport's ConfigHeader: int32 format, float32 depthParam[2]
DEPTH_HEADER = struct.Struct("<iff")
#: what follows that header in the RVL variant, before the stream: uint32 width, height
RVL_SIZE = struct.Struct("<II")
#: its defaults for 32FC1: depth_quantization 100, depth_max 10 m
DEPTH_QUANTIZATION, DEPTH_MAX_M = 100.0, 10.0

#: cv2.imdecode's channel count -> colour order
_DECODED_COLORS = {1: Color.MONO, 3: Color.BGR, 4: Color.BGRA}
#: colour order -> name of OpenCV's conversion to BGR (what ``cv2.imencode`` takes; alpha
#: dropped); OpenCV itself is imported by the first decode or encode, not by opening a log
_TO_BGR = {Color.RGB: "COLOR_RGB2BGR", Color.RGBA: "COLOR_RGBA2BGR", Color.BGRA: "COLOR_BGRA2BGR"}


def compressed_kind(message: CompressedImage) -> str:
    """The decoder key of a ``format`` string (image_transport's ``rgb8; jpeg compressed
    bgr8``, Foxglove's ``jpeg``...), from the bytes' magic when the string names nothing.

    >>> compressed_kind(CompressedImage(0, "cam", "bgr8; jpeg compressed bgr8", b""))
    'jpeg'
    """
    fmt = message.format.lower()
    if "compresseddepth" in fmt:
        return "compressedDepth"
    for kind, names in (("png", ("png",)), ("jpeg", ("jpeg", "jpg"))):
        if any(name in fmt for name in names):
            return kind
    if message.data[:3] == b"\xff\xd8\xff":
        return "jpeg"
    if message.data[:8] == b"\x89PNG\r\n\x1a\n":
        return "png"
    return fmt.split(";")[0].strip()


def original_encoding(fmt: str) -> str:
    """The raw encoding image_transport names before ``;`` in a format string ('' if none).

    >>> original_encoding("rgb8; jpeg compressed bgr8")
    'rgb8'
    """
    head, sep, _ = fmt.partition(";")
    return head.strip() if sep else ""


def decode_still(message: CompressedImage) -> Frame:
    """Decode JPEG or PNG bytes to a frame in OpenCV's order (BGR, BGRA or grey; 8 or
    16 bit), without converting colours."""
    import cv2

    buf = np.frombuffer(message.data, dtype=np.uint8)
    array = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if buf.size else None
    if array is None:
        raise EncodingError(f"cannot decode compressed image (format {message.format!r})")
    if array.dtype not in (np.uint8, np.uint16):
        raise EncodingError(f"unsupported compressed image depth {array.dtype}")
    channels = 1 if array.ndim == 2 else array.shape[2]
    return Frame(message.stamp_ns, message.frame_id, array, _DECODED_COLORS[channels],
                 compressed_kind(message))


def encode_still(frame: Frame, fmt: str, *, original: str = "", jpeg_quality: int = 90
                 ) -> CompressedImage:
    """JPEG or PNG of a frame; the ``format`` string follows image_transport
    (``rgb8; jpeg compressed bgr8``: the ``original`` raw encoding, default the one
    compressed). 16-bit images (grey, colour, depth) go to PNG only."""
    import cv2

    px = frame.pixels
    if px.dtype not in (np.uint8, np.uint16) or (fmt == "jpeg" and px.dtype != np.uint8):
        raise EncodingError(f"JPEG cannot hold {frame.source or frame.color} {px.dtype} "
                            "images; use png" if fmt == "jpeg" else
                            f"PNG cannot hold {px.dtype} images")
    bits = 8 * px.dtype.itemsize
    if frame.color is Color.DEPTH:
        array, kind = px, "16UC1" if bits == 16 else "8UC1"
    elif frame.color is Color.MONO:
        array, kind = px, f"mono{bits}"
    else:
        to_bgr = None if frame.color is Color.BGR else getattr(cv2, _TO_BGR[frame.color])
        array = px if to_bgr is None else cv2.cvtColor(px, to_bgr)
        kind = f"bgr{bits}"
    params = [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality] if fmt == "jpeg" else []
    ok, buf = cv2.imencode(".jpg" if fmt == "jpeg" else ".png", array, params)
    if not ok:
        raise EncodingError(f"cannot encode {frame.source or frame.color} image as {fmt}")
    return CompressedImage(frame.stamp_ns, frame.frame_id,
                           f"{original or kind}; {fmt} compressed {kind}", buf.tobytes())


def decode_compressed_depth(message: CompressedImage) -> Frame:
    """compressed_depth_image_transport's ``compressedDepth`` format: a 12-byte header
    (int32 format, float32 depthParam[2]) then a 16-bit PNG, or (``compressedDepth rvl``)
    uint32 width and height and an RVL stream, holding 16UC1 depth as it is (millimetres)
    or 32FC1 depth as quantised inverse depth ``a / depth + b`` (0: none)."""
    original = original_encoding(message.format) or "16UC1"
    data = message.data
    if len(data) <= DEPTH_HEADER.size:
        raise EncodingError(f"compressedDepth message of {len(data)} bytes has no image")
    _, quant_a, quant_b = DEPTH_HEADER.unpack_from(data)
    image = _depth_rvl(message) if "rvl" in message.format.lower() else _depth_png(message)
    if original == "16UC1":
        return Frame(message.stamp_ns, message.frame_id, image, Color.DEPTH, "compressedDepth",
                     0.001)
    if original != "32FC1":
        raise EncodingError(f"compressedDepth of {original!r} (16UC1 or 32FC1 expected)")
    with np.errstate(divide="ignore"):
        depth = quant_a / (image.astype(np.float32) - np.float32(quant_b))
    depth = np.where(image > 0, depth, np.nan).astype(np.float32)
    return Frame(message.stamp_ns, message.frame_id, depth, Color.DEPTH, "compressedDepth", 1.0)


def _depth_png(message: CompressedImage) -> Pixels:
    """The 16-bit image of a compressedDepth PNG message."""
    import cv2

    image = cv2.imdecode(np.frombuffer(message.data, np.uint8, offset=DEPTH_HEADER.size),
                         cv2.IMREAD_UNCHANGED)
    if image is None or image.dtype != np.uint16 or image.ndim != 2:
        raise EncodingError(f"cannot decode compressedDepth image (format {message.format!r})")
    return image


def _depth_rvl(message: CompressedImage) -> Pixels:
    """The 16-bit image of a compressedDepth RVL message."""
    data = message.data
    if len(data) < DEPTH_HEADER.size + RVL_SIZE.size:
        raise EncodingError(f"compressedDepth RVL message of {len(data)} bytes has no size")
    width, height = RVL_SIZE.unpack_from(data, DEPTH_HEADER.size)
    return decode_rvl(data[DEPTH_HEADER.size + RVL_SIZE.size:], width, height)


def encode_compressed_depth(frame: Frame, *, original: str = "", jpeg_quality: int = 90
                            ) -> CompressedImage:
    """A depth frame in compressed_depth_image_transport's PNG layout (lossless for
    16UC1; 32FC1 quantised as that transport does, with its default parameters)."""
    del original, jpeg_quality  # the depth encoding decides
    if frame.color is not Color.DEPTH:
        raise EncodingError(f"compressedDepth holds depth images, not {frame.color}")
    if frame.pixels.dtype == np.uint16 and frame.depth_unit_m == 0.001:
        encoding, quant_a, quant_b, png = "16UC1", 0.0, 0.0, frame.pixels
    else:
        depth_m = frame.pixels.astype(np.float32) * np.float32(frame.depth_unit_m or 1.0)
        quant_a = DEPTH_QUANTIZATION * (DEPTH_QUANTIZATION + 1.0)
        quant_b = 1.0 - quant_a / DEPTH_MAX_M
        valid = np.isfinite(depth_m) & (depth_m > 0) & (depth_m < DEPTH_MAX_M)
        with np.errstate(divide="ignore", invalid="ignore"):
            inverse = np.where(valid, quant_a / depth_m + quant_b, 0.0)
        encoding, png = "32FC1", np.clip(np.round(inverse), 0, 65535).astype(np.uint16)
    import cv2

    ok, buf = cv2.imencode(".png", png)
    if not ok:
        raise EncodingError("cannot encode depth as PNG")
    header = DEPTH_HEADER.pack(0, quant_a, quant_b)
    return CompressedImage(frame.stamp_ns, frame.frame_id,
                           f"{encoding}; compressedDepth png", header + buf.tobytes())

"""Camera images as rerun archetypes: raw pixels, JPEG re-encoded, or compressed passed through.

A ``CompressedImage`` (JPEG or PNG) goes into the recording as ``EncodedImage`` without being
decoded. Raw 8-bit images become ``EncodedImage`` JPEGs when a quality is given (OpenCV
encodes; 16-bit images stay raw since JPEG cannot hold them), ``Image`` otherwise.
"""

from __future__ import annotations

from typing import Any, Literal

import cv2
import numpy as np
import rerun as rr

from ..messages import CompressedImage, Image

__all__ = ["COLOR_MODELS", "encoded_image", "media_type", "rerun_image"]

#: ROS encoding -> rerun colour model
COLOR_MODELS: dict[str, Literal["RGB", "BGR", "RGBA", "BGRA", "L"]] = {
    "rgb8": "RGB", "8UC3": "RGB", "bgr8": "BGR", "rgba8": "RGBA", "bgra8": "BGRA",
    "mono8": "L", "8UC1": "L", "mono16": "L", "16UC1": "L",
}
#: ROS encoding -> OpenCV conversion to what ``cv2.imencode`` takes (BGR or mono)
_TO_BGR = {
    "rgb8": cv2.COLOR_RGB2BGR, "8UC3": cv2.COLOR_RGB2BGR, "rgba8": cv2.COLOR_RGBA2BGR,
    "bgra8": cv2.COLOR_BGRA2BGR,
}


def media_type(data: bytes) -> str | None:
    """``image/jpeg`` or ``image/png`` from the magic bytes; None for anything else."""
    if data[:3] == b"\xff\xd8\xff":
        return "image/jpeg"
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        return "image/png"
    return None


def encoded_image(message: CompressedImage, *, draw_order: float | None = None) -> Any:
    """``rr.EncodedImage`` holding the compressed bytes as they are (None: unknown format)."""
    kind = media_type(message.data)
    if kind is None:
        return None
    return rr.EncodedImage(contents=message.data, media_type=kind, draw_order=draw_order)


def rerun_image(
    image: Image, *, jpeg_quality: int | None = None, draw_order: float | None = None
) -> Any:
    """``rr.Image`` of the pixels, or a JPEG ``rr.EncodedImage`` when ``jpeg_quality`` is set
    and the image has 8-bit channels."""
    pixels = image.pixels
    if jpeg_quality is not None and pixels.dtype == np.uint8:
        conversion = _TO_BGR.get(image.encoding)
        array = cv2.cvtColor(pixels, conversion) if conversion is not None else pixels
        ok, buf = cv2.imencode(".jpg", array, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
        if ok:
            return rr.EncodedImage(contents=buf.tobytes(), media_type="image/jpeg",
                                   draw_order=draw_order)
    return rr.Image(pixels, color_model=COLOR_MODELS[image.encoding], draw_order=draw_order)

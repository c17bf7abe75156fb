"""The one table of frame decoders: (message kind, encoding or format) -> :class:`Frame`.

A raw ``sensor_msgs/Image`` encoding is one :class:`Raw` entry (in :mod:`.raw`): the layout
of its buffer (dtype and channels, which the wire layer uses to cut the message's bytes
into an array) and the frame it makes (colour order, an optional conversion such as
debayering, the depth unit). A compressed format is one function from the message to a
frame; a video format one decoder class.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np

from ..errors import EncodingError, UnsupportedEncodingError
from ..messages import CompressedImage, CompressedVideo, Image, Message
from .compressed import compressed_kind, decode_compressed_depth, decode_still
from .frame import Frame
from .lookup import table_entry
from .raw import RAW_ENCODINGS, Raw
from .video import VideoDecoder

__all__ = ["DECODERS", "IMAGE_ENCODINGS", "FrameStream", "Raw", "decode_frame", "raw_encoding"]

#: (typed record, encoding or compressed kind) -> decoder (for video: a decoder class, one
#: instance per stream); the raw entries are :data:`RAW_ENCODINGS`
DECODERS: dict[tuple[type, str], Callable[[Any], Any]] = {
    **{(Image, name): raw for name, raw in RAW_ENCODINGS.items()},
    (CompressedImage, "jpeg"): decode_still,
    (CompressedImage, "png"): decode_still,
    (CompressedImage, "compressedDepth"): decode_compressed_depth,
    # video: a decoder per stream (each picture needs the ones before it); see FrameStream
    (CompressedVideo, "h264"): VideoDecoder,
    (CompressedVideo, "h265"): VideoDecoder,
}


#: raw encoding -> (dtype, channels) of its buffer
IMAGE_ENCODINGS: dict[str, tuple[np.dtype[Any], int]] = {
    encoding: (decoder.dtype, decoder.channels)
    for (kind, encoding), decoder in DECODERS.items() if isinstance(decoder, Raw)
}


def raw_encoding(encoding: str) -> Raw:
    """The table entry of a raw encoding; :class:`EncodingError` naming the supported ones."""
    return cast(Raw, table_entry(DECODERS, Image, encoding, error=UnsupportedEncodingError,
                                 unknown="unsupported image encoding"))


def decode_frame(message: Image | CompressedImage) -> Frame:
    """The frame of any still image message (raw in any supported encoding, JPEG, PNG,
    compressedDepth); video needs a :class:`FrameStream`."""
    if isinstance(message, Image):
        return raw_encoding(message.encoding)(message)
    if not isinstance(message, CompressedImage):
        raise EncodingError(f"{type(message).__name__} is not a still image message")
    kind = compressed_kind(message)
    decoder = table_entry(DECODERS, CompressedImage, kind, error=UnsupportedEncodingError,
                          unknown="unsupported compressed image format", shown=message.format)
    frame: Frame = decoder(message)
    return frame


class FrameStream:
    """Decodes the image messages of one topic, in order, to frames: still images one by
    one, video through one decoder for the whole stream."""

    def __init__(self) -> None:
        self._video: Callable[[CompressedVideo], Frame | None] | None = None

    def decode(self, message: Message) -> Frame | None:
        """The frame of the next message (None: a video picture not decodable yet)."""
        if not isinstance(message, CompressedVideo):
            if not isinstance(message, Image | CompressedImage):
                raise EncodingError(f"{type(message).__name__} is not an image message")
            return decode_frame(message)
        if self._video is None:
            factory = table_entry(DECODERS, CompressedVideo, message.format,
                                  error=UnsupportedEncodingError,
                                  unknown="unsupported video format")
            self._video = cast(Callable[[CompressedVideo], Frame | None],
                               factory(message.format))
        return self._video(message)

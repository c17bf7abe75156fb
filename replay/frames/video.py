"""Compressed video (``foxglove.CompressedVideo``, H.264 / H.265) to frames and back, with
PyAV (the optional extra ``camlog[video]``).

Each message holds the NAL units of exactly one picture (Annex B, no B-frames), so a
decoder turns each message into one frame once it has seen a keyframe; an encoder turns
each frame into one message.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import EncodingError, UnsupportedEncodingError
from ..format_names import DEFAULT_CRF, VIDEO_CODEC_NAMES
from ..messages import CompressedVideo
from .frame import Color, Frame

__all__ = ["DEFAULT_CRF", "VIDEO_CODECS", "VideoDecoder", "VideoEncoder", "psnr_db"]

#: CompressedVideo format -> (FFmpeg decoder, FFmpeg encoder)
VIDEO_CODECS = {"h264": ("h264", "libx264"), "h265": ("hevc", "libx265")}
assert tuple(VIDEO_CODECS) == VIDEO_CODEC_NAMES


def _av() -> Any:
    try:
        import av
    except ImportError:
        raise UnsupportedEncodingError("CompressedVideo needs PyAV: "
                                       "pip install 'camlog[video]'") from None
    return av


class VideoDecoder:
    """Decodes the messages of one video stream, in order, to RGB frames."""

    def __init__(self, fmt: str) -> None:
        if fmt not in VIDEO_CODECS:
            raise UnsupportedEncodingError(f"unsupported video format {fmt!r} "
                                           f"(supported: {', '.join(VIDEO_CODECS)})")
        av = _av()
        self._av = av
        self._codec = av.CodecContext.create(VIDEO_CODECS[fmt][0], "r")
        self.format = fmt

    def __call__(self, message: CompressedVideo) -> Frame | None:
        """The frame of one message; None while no picture can be decoded yet (before
        the first keyframe)."""
        try:
            pictures = self._codec.decode(self._av.Packet(message.data))
        except self._av.error.FFmpegError as err:
            raise EncodingError(f"cannot decode {self.format} video: {err}") from None
        if not pictures:
            return None
        rgb = pictures[-1].to_ndarray(format="rgb24")
        return Frame(message.stamp_ns, message.frame_id, rgb, Color.RGB, self.format)




class VideoEncoder:
    """Encodes frames of one stream to CompressedVideo messages (one picture each,
    Annex B, no B-frames, a keyframe with its parameter sets every ``gop`` frames;
    ``crf``: x264/x265's constant rate factor, lower is better and larger)."""

    def __init__(self, fmt: str = "h264", *, crf: int = DEFAULT_CRF, gop: int = 30) -> None:
        if fmt not in VIDEO_CODECS:
            raise EncodingError(f"unsupported video format {fmt!r} "
                                f"(supported: {', '.join(VIDEO_CODECS)})")
        self._av = _av()
        self.format, self._crf, self._gop = fmt, crf, gop
        self._codec: Any = None

    def _open(self, width: int, height: int) -> Any:
        codec = self._av.CodecContext.create(VIDEO_CODECS[self.format][1], "w")
        codec.width, codec.height, codec.pix_fmt = width, height, "yuv420p"
        codec.gop_size, codec.max_b_frames = self._gop, 0
        params = "repeat-headers=1" if self.format == "h264" else "repeat-headers=1:log-level=0"
        codec.options = {"crf": str(self._crf), "preset": "veryfast", "tune": "zerolatency",
                         f"{'x264' if self.format == 'h264' else 'x265'}-params": params}
        codec.open()
        return codec

    def __call__(self, frame: Frame) -> CompressedVideo:
        """One message holding the frame's picture."""
        if frame.width % 2 or frame.height % 2:
            raise EncodingError(f"{self.format} needs even image sizes, got "
                                f"{frame.width}x{frame.height}")
        if self._codec is None:
            self._codec = self._open(frame.width, frame.height)
        elif (self._codec.width, self._codec.height) != (frame.width, frame.height):
            raise EncodingError("video frames change size")
        picture = self._av.VideoFrame.from_ndarray(np.ascontiguousarray(frame.rgb8()),
                                                   format="rgb24")
        data = b"".join(bytes(packet) for packet in self._codec.encode(picture))
        return CompressedVideo(frame.stamp_ns, frame.frame_id, self.format, data)


def psnr_db(reference: np.ndarray, decoded: np.ndarray) -> float:
    """Peak signal-to-noise ratio of 8-bit images, in dB (inf when equal)."""
    error = np.mean((reference.astype(np.float64) - decoded.astype(np.float64)) ** 2)
    return float("inf") if error == 0 else float(10 * np.log10(255.0**2 / error))

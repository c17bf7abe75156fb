"""Re-encoding the frames of one image topic (``convert --compress / --decompress``).

The first frame of a topic decides what its messages become: JPEG, H.264 and H.265 hold
8-bit images only, so a 16-bit or depth topic goes to PNG (depth to compressedDepth PNG,
lossless for 16UC1) instead, and a topic no compressed format holds losslessly (32FC1
depth) is copied as it is. Frames that do not decode are counted, not fatal. Video
re-encoding measures its quality: the PSNR of each encoded picture, decoded again,
against the frame it came from.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import EncodingError, ReplayError, UnsupportedEncodingError
from .format_names import STILL_CODECS
from .frames import (
    Color,
    Frame,
    FrameStream,
    VideoDecoder,
    VideoEncoder,
    decompress,
    encode_compressed,
    encode_image,
    psnr_db,
)
from .frames.video import DEFAULT_CRF, VIDEO_CODECS
from .messages import CompressedImage, CompressedVideo, Message

__all__ = ["STILLS", "TopicReencoder", "compressed_format_for"]

#: compressed still formats
STILLS = STILL_CODECS


def compressed_format_for(frame: Frame, wanted: str) -> str | None:
    """The format a frame's topic is stored in when ``wanted`` is asked for (None: copy
    the topic unchanged)."""
    eight_bit = frame.pixels.dtype == np.uint8 and frame.color is not Color.DEPTH
    if wanted in ("jpeg", *VIDEO_CODECS) and eight_bit:
        return wanted
    if frame.color is Color.DEPTH:
        return "compressedDepth" if frame.pixels.dtype == np.uint16 else None
    return "png" if frame.pixels.dtype in (np.uint8, np.uint16) else None


@dataclass
class TopicReencoder:
    """Turns the messages of one topic into their re-encoded form, in order.

    ``compress`` is a still or video format, or None to decompress. ``chosen`` is the
    format the topic is stored in after its first frame (None: copied unchanged)."""

    topic: str
    compress: str | None
    crf: int = DEFAULT_CRF  # video only
    chosen: str | None = None
    decided: bool = False
    undecodable: int = 0
    unsupported: str = ""  # why the topic's frames cannot be decoded at all
    psnr_sum_db: float = 0.0
    psnr_count: int = 0
    _stream: FrameStream = field(default_factory=FrameStream)
    _video: VideoEncoder | None = None
    _check: VideoDecoder | None = None

    def __call__(self, message: Message) -> Message | bool | None:
        """The re-encoded message; None when the frame is skipped (undecodable, or a video
        picture not decodable yet); False when the topic is copied unchanged."""
        try:
            frame = self._stream.decode(message)
        except EncodingError as err:
            return self.failed(err)
        if frame is None:  # a video picture before the stream's first keyframe
            self.undecodable += 1
            return None
        if not self.decided:
            self.decided = True
            self.chosen = "raw" if self.compress is None else \
                compressed_format_for(frame, self.compress)
        return False if self.chosen is None else self._encode(message, frame, self.chosen)

    def failed(self, error: ReplayError) -> bool | None:
        """What becomes of a message that did not decode: copied unchanged (False) with the
        rest of its topic when the topic's encoding is one camlog does not read, else
        counted and left out (None)."""
        if isinstance(error, UnsupportedEncodingError) and not self.decided:
            self.decided, self.chosen, self.unsupported = True, None, str(error)
        if self.decided and self.chosen is None:
            return False
        self.undecodable += 1
        return None

    def _encode(self, message: Message, frame: Frame, chosen: str) -> Message:
        if chosen == "raw":
            if isinstance(message, CompressedImage):
                return decompress(message, frame)
            return encode_image(frame)
        if chosen in VIDEO_CODECS:
            return self._encode_video(frame)
        return encode_compressed(frame, chosen)

    def _encode_video(self, frame: Frame) -> CompressedVideo:
        if self._video is None:
            self._video = VideoEncoder(self.chosen or "h264", crf=self.crf)
            self._check = VideoDecoder(self.chosen or "h264")
        assert self._check is not None
        message = self._video(frame)
        decoded = self._check(message)
        if decoded is not None:
            self.psnr_sum_db += min(psnr_db(frame.rgb8(), decoded.pixels), 99.0)
            self.psnr_count += 1
        return message

    @property
    def psnr_mean_db(self) -> float | None:
        """Mean PSNR of the video pictures written, in dB (None when none)."""
        return self.psnr_sum_db / self.psnr_count if self.psnr_count else None

    def notes(self) -> list[str]:
        """What happened to the topic, as warning lines (empty when all went as asked)."""
        lines = []
        if self.undecodable:
            lines.append(f"{self.topic}: {self.undecodable} frames did not decode (left out)")
        if self.unsupported:
            lines.append(f"{self.topic}: {self.unsupported}; copied unchanged")
        elif self.decided and self.compress is not None and self.chosen != self.compress:
            what = "copied unchanged" if self.chosen is None else f"stored as {self.chosen}"
            lines.append(f"{self.topic}: {self.compress} cannot hold its images losslessly; "
                         f"{what}")
        return lines

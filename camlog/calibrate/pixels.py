"""The camera frames of image messages, for calibration (errors name the topic)."""

from __future__ import annotations

from replay.errors import EncodingError, ReplayError, UnsupportedEncodingError
from replay.formats import LogReader, RawMessage
from replay.frames import Frame, FrameStream
from replay.messages import CompressedImage, CompressedVideo, Image

from ..errors import InputError

__all__ = ["TopicFrames"]


class TopicFrames:
    """Decodes the image messages of a log's topics, each topic in log order (a video
    picture needs the ones before it), to frames (grey for detection: ``mono8()``, BGR for
    drawing: ``bgr8()``). A message that does not decode (a cut JPEG, a raw buffer too
    short) is no frame, and is counted per topic in :attr:`undecodable`; an encoding camlog
    does not read stops the run."""

    def __init__(self) -> None:
        self._streams: dict[str, FrameStream] = {}
        self.undecodable: dict[str, int] = {}

    def __call__(self, reader: LogReader, raw: RawMessage) -> Frame | None:
        """The frame of ``raw``'s topic's next message in any encoding, still or video; None
        for a video picture before the stream's first keyframe or a message that does not
        decode."""
        where = f"{reader.path}: {raw.topic}"
        try:
            message = reader.decode(raw)
            if not isinstance(message, Image | CompressedImage | CompressedVideo):
                raise InputError(f"{where} does not hold images")
            return self._streams.setdefault(raw.topic, FrameStream()).decode(message)
        except UnsupportedEncodingError as err:
            raise InputError(f"{where}: {err}") from None
        except EncodingError:
            self.undecodable[raw.topic] = self.undecodable.get(raw.topic, 0) + 1
            return None
        except ReplayError as err:
            raise InputError(f"{where}: {err}") from None

    def warnings(self) -> list[str]:
        """One line per topic with frames that did not decode."""
        return [f"{topic}: {count} frame{'s' if count > 1 else ''} did not decode and "
                f"{'were' if count > 1 else 'was'} left out" for topic, count in
                sorted(self.undecodable.items())]

"""camlog's log layer: typed camera messages, MCAP / rosbag2 / ROS1 logs, replay.

Names are loaded from their modules on first use, so that importing one light module of the
package (``replay.errors``, ``replay.selection``) does not load numpy, OpenCV or rosbags.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .errors import (
    EncodingError,
    ImageFolderError,
    LogFormatError,
    LogReadError,
    LogWriteError,
    OptionError,
    OutputError,
    RecordError,
    ReplayError,
    TopicError,
    UnsupportedEncodingError,
)
from .lazy import lazy_names

if TYPE_CHECKING:
    from .formats import (
        FORMATS,
        FrameRecord,
        LogReader,
        LogWriter,
        RawMessage,
        Record,
        TopicInfo,
        open_reader,
        open_writer,
    )
    from .frames import IMAGE_ENCODINGS, Frame
    from .messages import (
        CameraInfo,
        CompressedImage,
        CompressedVideo,
        Image,
        Message,
        PointStamped,
        PoseStamped,
        Text,
    )

#: public name -> the module that defines it
_MODULES = {
    **dict.fromkeys(("FORMATS", "FrameRecord", "LogReader", "LogWriter", "RawMessage",
                     "Record", "TopicInfo", "open_reader", "open_writer"), ".formats"),
    **dict.fromkeys(("IMAGE_ENCODINGS", "Frame"), ".frames"),
    **dict.fromkeys(("CameraInfo", "CompressedImage", "CompressedVideo", "Image", "Message",
                     "PointStamped", "PoseStamped", "Text"), ".messages"),
}


_load = lazy_names(__name__, _MODULES, globals())


def __getattr__(name: str) -> Any:
    """Load a public name (or ``__version__``) from its module on first use."""
    if name == "__version__":
        from ._version import VERSION

        return VERSION
    return _load(name)


__all__ = [
    "FORMATS",
    "IMAGE_ENCODINGS",
    "CameraInfo",
    "CompressedImage",
    "CompressedVideo",
    "EncodingError",
    "Frame",
    "FrameRecord",
    "Image",
    "ImageFolderError",
    "LogFormatError",
    "LogReadError",
    "LogReader",
    "LogWriteError",
    "LogWriter",
    "Message",
    "OptionError",
    "OutputError",
    "PointStamped",
    "PoseStamped",
    "RawMessage",
    "Record",
    "RecordError",
    "ReplayError",
    "Text",
    "TopicError",
    "TopicInfo",
    "UnsupportedEncodingError",
    "open_reader",
    "open_writer",
]

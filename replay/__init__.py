"""camlog's log layer: typed camera messages, MCAP / rosbag2 / ROS1 logs, replay, export."""

from ._version import VERSION
from .errors import (
    EncodingError,
    ImageFolderError,
    LogFormatError,
    LogReadError,
    LogWriteError,
    OptionError,
    OutputError,
    ReplayError,
    TopicError,
    ViewerError,
)
from .formats import (
    FORMATS,
    LogReader,
    LogWriter,
    RawMessage,
    Record,
    TopicInfo,
    open_reader,
    open_writer,
)
from .messages import (
    IMAGE_ENCODINGS,
    CameraInfo,
    CompressedImage,
    Image,
    Message,
    PointStamped,
    PoseStamped,
    Text,
)

__version__ = VERSION

__all__ = [
    "FORMATS",
    "IMAGE_ENCODINGS",
    "CameraInfo",
    "CompressedImage",
    "EncodingError",
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
    "ReplayError",
    "Text",
    "TopicError",
    "TopicInfo",
    "ViewerError",
    "open_reader",
    "open_writer",
]

"""Names of wire serializations and message types, and which typed record each type decodes
to, by name: importable without numpy or rosbags, so that opening and summarising a log
(``camlog info``) loads neither. :mod:`replay.wire` maps the names to the record classes.
"""

from __future__ import annotations

__all__ = [
    "CAMERA_INFO_TYPES",
    "CDR",
    "DECODABLE",
    "FRAME_TYPES",
    "JSON",
    "PROTOBUF",
    "RECORD_KINDS",
    "ROS1",
    "normalize_msgtype",
]

#: message encodings of a log's channels
CDR = "cdr"
ROS1 = "ros1"
PROTOBUF = "protobuf"
JSON = "json"

#: type (schema) name -> the name of the :mod:`replay.messages` record its messages decode to
RECORD_KINDS: dict[str, str] = {
    "sensor_msgs/msg/Image": "Image",
    "sensor_msgs/msg/CompressedImage": "CompressedImage",
    "sensor_msgs/msg/CameraInfo": "CameraInfo",
    "geometry_msgs/msg/PoseStamped": "PoseStamped",
    "geometry_msgs/msg/PointStamped": "PointStamped",
    "std_msgs/msg/String": "Text",
    "foxglove.RawImage": "Image",
    "foxglove.CompressedImage": "CompressedImage",
    "foxglove.CompressedVideo": "CompressedVideo",
    "foxglove.CameraCalibration": "CameraInfo",
}
#: type names whose messages decode to camera frames
FRAME_TYPES = frozenset(name for name, kind in RECORD_KINDS.items()
                        if kind in ("Image", "CompressedImage", "CompressedVideo"))
#: type names whose messages decode to camera models
CAMERA_INFO_TYPES = frozenset(name for name, kind in RECORD_KINDS.items() if kind == "CameraInfo")
#: ROS types camlog has records for
DECODABLE = frozenset(name for name in RECORD_KINDS if "/msg/" in name)


def normalize_msgtype(name: str) -> str:
    """``sensor_msgs/Image`` (ROS1 spelling) -> ``sensor_msgs/msg/Image``."""
    parts = name.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else name

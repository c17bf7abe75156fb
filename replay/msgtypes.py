"""Names of wire serializations and message types, and which typed record each type decodes
to, by name: importable without numpy or rosbags, so that opening and summarising a log
(``camlog info``) loads neither. :mod:`replay.wire` maps the names to the record classes.
"""

from __future__ import annotations

__all__ = [
    "CAMERA_INFO",
    "CAMERA_INFO_TYPES",
    "CDR",
    "COMPRESSED_IMAGE",
    "DECODABLE",
    "FOXGLOVE_CAMERA_CALIBRATION",
    "FOXGLOVE_COMPRESSED_IMAGE",
    "FOXGLOVE_COMPRESSED_VIDEO",
    "FOXGLOVE_RAW_IMAGE",
    "FRAME_TYPES",
    "IMAGE",
    "JSON",
    "POINT_STAMPED",
    "POSE_STAMPED",
    "PROTOBUF",
    "RECORD_KINDS",
    "ROS1",
    "STRING",
    "normalize_msgtype",
]

#: message encodings of a log's channels
CDR = "cdr"
ROS1 = "ros1"
PROTOBUF = "protobuf"
JSON = "json"

#: ROS 2 message types camlog has records for
IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POINT_STAMPED = "geometry_msgs/msg/PointStamped"
STRING = "std_msgs/msg/String"
#: Foxglove schemas camlog has records for
FOXGLOVE_RAW_IMAGE = "foxglove.RawImage"
FOXGLOVE_COMPRESSED_IMAGE = "foxglove.CompressedImage"
FOXGLOVE_COMPRESSED_VIDEO = "foxglove.CompressedVideo"
FOXGLOVE_CAMERA_CALIBRATION = "foxglove.CameraCalibration"

#: type (schema) name -> the name of the :mod:`replay.messages` record its messages decode to
RECORD_KINDS: dict[str, str] = {
    IMAGE: "Image",
    COMPRESSED_IMAGE: "CompressedImage",
    CAMERA_INFO: "CameraInfo",
    POSE_STAMPED: "PoseStamped",
    POINT_STAMPED: "PointStamped",
    STRING: "Text",
    FOXGLOVE_RAW_IMAGE: "Image",
    FOXGLOVE_COMPRESSED_IMAGE: "CompressedImage",
    FOXGLOVE_COMPRESSED_VIDEO: "CompressedVideo",
    FOXGLOVE_CAMERA_CALIBRATION: "CameraInfo",
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

"""Serialization of typed records, separate from pixels: ROS 2 CDR and ROS1 through
rosbags' typestore, Foxglove's protobuf and JSON camera schemas, and the MCAP decoder
factories every reader decodes through."""

from ..msgtypes import CDR, DECODABLE, JSON, PROTOBUF, ROS1, normalize_msgtype
from .decoders import (
    DECODER_FACTORIES,
    FRAME_TYPES,
    RECORD_TYPES,
    Decoder,
    RosDecoderFactory,
    decoder_for,
    record_msgtype,
    ros_schema,
)
from .foxglove import foxglove_schema, to_foxglove
from .ros import (
    convert_serialization,
    deserialize,
    from_ros,
    msgtype_of,
    ros1_typestore,
    ros2_typestore,
    serialize,
    to_ros,
)

__all__ = [
    "CDR",
    "DECODABLE",
    "DECODER_FACTORIES",
    "FRAME_TYPES",
    "JSON",
    "PROTOBUF",
    "RECORD_TYPES",
    "ROS1",
    "Decoder",
    "RosDecoderFactory",
    "convert_serialization",
    "decoder_for",
    "deserialize",
    "foxglove_schema",
    "from_ros",
    "msgtype_of",
    "normalize_msgtype",
    "record_msgtype",
    "ros1_typestore",
    "ros2_typestore",
    "ros_schema",
    "serialize",
    "to_foxglove",
    "to_ros",
]

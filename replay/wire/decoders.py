"""MCAP decoder factories that turn a channel's bytes into camlog's typed records.

The ``mcap`` library's :class:`~mcap.decoder.DecoderFactory` protocol (as ``mcap_ros2``
and ``mcap_protobuf`` implement it): a factory is asked once per channel, with the
channel's message encoding and schema, for a function decoding that channel's messages.
Every reader decodes through :func:`decoder_for`; a serialization is one more factory in
:data:`DECODER_FACTORIES`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import cast

from mcap.decoder import DecoderFactory
from mcap.records import Schema

from .. import messages
from ..errors import ReplayError
from ..messages import MSGTYPES, Message
from ..msgtypes import CDR, DECODABLE, FRAME_TYPES, RECORD_KINDS, ROS1, normalize_msgtype
from .foxglove import FoxgloveJsonFactory, FoxgloveProtobufFactory
from .ros import deserialize

__all__ = [
    "DECODER_FACTORIES",
    "FRAME_TYPES",
    "RECORD_TYPES",
    "Decoder",
    "RosDecoderFactory",
    "decoder_for",
    "record_msgtype",
    "ros_schema",
]

#: type (schema) name -> the typed record its messages decode to
RECORD_TYPES: dict[str, type] = {name: getattr(messages, kind)
                                 for name, kind in RECORD_KINDS.items()}


def record_msgtype(msgtype: str) -> str:
    """The ROS name of the record a type decodes to (``foxglove.RawImage`` ->
    ``sensor_msgs/msg/Image``); other names unchanged."""
    kind = RECORD_TYPES.get(msgtype)
    return msgtype if kind is None else MSGTYPES[kind]

#: bytes of one message -> its typed record
Decoder = Callable[[bytes | memoryview], Message]
#: ROS serialization -> the schema encoding of its message definitions
SCHEMA_ENCODINGS = {CDR: "ros2msg", ROS1: "ros1msg"}


class RosDecoderFactory(DecoderFactory):
    """ROS 2 CDR and ROS1 channels of the types camlog has records for, through rosbags'
    typestore (which knows the definitions by type name)."""

    def decoder_for(self, message_encoding: str, schema: Schema | None) -> Decoder | None:
        """A decoder for ``cdr`` / ``ros1`` channels of camlog's types; None otherwise."""
        if message_encoding not in SCHEMA_ENCODINGS or schema is None:
            return None
        msgtype = normalize_msgtype(schema.name)
        if msgtype not in DECODABLE:
            return None
        return partial(deserialize, msgtype=msgtype, serialization=message_encoding)


#: asked in order; the first that returns a decoder decodes the channel
DECODER_FACTORIES: list[DecoderFactory] = [
    RosDecoderFactory(), FoxgloveProtobufFactory(), FoxgloveJsonFactory()]


def ros_schema(msgtype: str, serialization: str) -> Schema:
    """The schema record of a ROS type in a log whose format keeps no schema records
    (rosbag2, ROS1): the typestore supplies the definition."""
    return Schema(id=0, name=msgtype, encoding=SCHEMA_ENCODINGS.get(serialization, ""),
                  data=b"")


def decoder_for(message_encoding: str, schema: Schema | None) -> Decoder:
    """The decoder of a channel from the first factory that has one."""
    for factory in DECODER_FACTORIES:
        decoder = factory.decoder_for(message_encoding, schema)
        if decoder is not None:
            return cast(Decoder, decoder)  # mcap's protocol types the bytes only
    name = schema.name if schema is not None and schema.name else "schemaless messages"
    where = "" if message_encoding in SCHEMA_ENCODINGS else f" ({message_encoding})"
    raise ReplayError(f"camlog has no typed record for {name}{where}")

"""Foxglove's camera schemas, protobuf and JSON, as camlog's typed records, and back.

``foxglove.RawImage``, ``CompressedImage``, ``CameraCalibration`` and ``CompressedVideo``
carry the same fields as their ROS counterparts: they decode to :class:`Image`,
:class:`CompressedImage`, :class:`CameraInfo` and :class:`CompressedVideo`. Protobuf
channels are parsed by ``mcap_protobuf`` from the schema stored in the file; JSON channels
(bytes in base64, times as ``{"sec", "nsec"}``) by :mod:`json`. Writing uses the published
``foxglove_schemas_protobuf`` classes.
"""

from __future__ import annotations

import base64
import binascii
import json
from collections.abc import Callable
from typing import Any

import numpy as np
from mcap.decoder import DecoderFactory
from mcap.exceptions import McapError
from mcap.records import Schema

from ..bounded import json_loads
from ..errors import ReplayError
from ..messages import CameraInfo, CompressedImage, CompressedVideo, Image, Message
from ..msgtypes import (
    FOXGLOVE_CAMERA_CALIBRATION,
    FOXGLOVE_COMPRESSED_IMAGE,
    FOXGLOVE_COMPRESSED_VIDEO,
    FOXGLOVE_RAW_IMAGE,
    JSON,
    PROTOBUF,
)
from .layout import image_from_buffer

__all__ = [
    "FOXGLOVE_TYPES",
    "JSON",
    "PROTOBUF",
    "FoxgloveJsonFactory",
    "FoxgloveProtobufFactory",
    "foxglove_schema",
    "to_foxglove",
]

#: field values by name, bytes as bytes, the timestamp as integer nanoseconds
Fields = dict[str, Any]


def _image(f: Fields) -> Message:
    return image_from_buffer(f["stamp_ns"], f["frame_id"], width=int(f["width"]),
                             height=int(f["height"]), encoding=f["encoding"],
                             step=int(f["step"]), data=f["data"], bigendian=False)


def _compressed(f: Fields) -> Message:
    return CompressedImage(f["stamp_ns"], f["frame_id"], str(f["format"]), bytes(f["data"]))


def _video(f: Fields) -> Message:
    return CompressedVideo(f["stamp_ns"], f["frame_id"], str(f["format"]), bytes(f["data"]))


def _calibration(f: Fields) -> Message:
    def matrix(name: str, shape: tuple[int, int], default: Any) -> Any:
        values = list(f.get(name) or [])
        return np.asarray(values, np.float64).reshape(shape) if values else default

    return CameraInfo(f["stamp_ns"], f["frame_id"], int(f["width"]), int(f["height"]),
                      str(f["distortion_model"]), np.asarray(list(f.get("D") or []), np.float64),
                      matrix("K", (3, 3), np.zeros((3, 3))), matrix("R", (3, 3), np.eye(3)),
                      matrix("P", (3, 4), np.zeros((3, 4))))


#: Foxglove schema name -> typed record builder
FOXGLOVE_TYPES: dict[str, Callable[[Fields], Message]] = {
    FOXGLOVE_RAW_IMAGE: _image,
    FOXGLOVE_COMPRESSED_IMAGE: _compressed,
    FOXGLOVE_CAMERA_CALIBRATION: _calibration,
    FOXGLOVE_COMPRESSED_VIDEO: _video,
}
_ERRORS: tuple[type[Exception], ...] = (McapError, KeyError, TypeError, ValueError,
                                        binascii.Error)
_JSON_ERRORS: tuple[type[Exception], ...] = (json.JSONDecodeError, *_ERRORS)


def _build(name: str, fields: Fields) -> Message:
    try:
        return FOXGLOVE_TYPES[name](fields)
    except _ERRORS as err:
        raise ReplayError(f"cannot decode {name}: {type(err).__name__}: {err}") from None


class FoxgloveProtobufFactory(DecoderFactory):
    """Protobuf channels of Foxglove's camera schemas, parsed with the schema in the file."""

    def __init__(self) -> None:
        self._classes: dict[tuple[str, bytes], Callable[[bytes], Any]] = {}

    def decoder_for(self, message_encoding: str, schema: Schema | None
                    ) -> Callable[[bytes | memoryview], Message] | None:
        """A decoder for ``protobuf`` channels of the four Foxglove camera schemas."""
        if message_encoding != PROTOBUF or schema is None or schema.name not in FOXGLOVE_TYPES:
            return None
        # protobuf is imported by the first protobuf channel, not by opening a log
        from google.protobuf.message import DecodeError
        from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory

        errors: tuple[type[Exception], ...] = (DecodeError, *_ERRORS)
        key = (schema.name, schema.data)
        parse = self._classes.get(key)
        if parse is None:
            # mcap_protobuf caches classes by schema id, which differs between files
            try:
                parse = ProtobufDecoderFactory().decoder_for(message_encoding, schema)
            except errors as err:
                raise ReplayError(f"bad protobuf schema for {schema.name}: {err}") from None
            if parse is None:
                return None
            self._classes[key] = parse
        name = schema.name

        def decode(data: bytes | memoryview) -> Message:
            try:
                message = parse(bytes(data))
            except errors as err:
                raise ReplayError(f"cannot decode {name}: {err}") from None
            fields = {field.name: getattr(message, field.name)
                      for field in message.DESCRIPTOR.fields if field.name != "timestamp"}
            stamp = message.timestamp
            fields["stamp_ns"] = int(stamp.seconds) * 1_000_000_000 + int(stamp.nanos)
            return _build(name, fields)

        return decode


def _json_stamp_ns(value: Any) -> int:
    if not value:
        return 0
    sec = value.get("sec", value.get("seconds", 0))
    nsec = value.get("nsec", value.get("nanos", 0))
    return int(sec) * 1_000_000_000 + int(nsec)


class FoxgloveJsonFactory(DecoderFactory):
    """JSON channels of Foxglove's camera schemas (``bytes`` fields in base64)."""

    def decoder_for(self, message_encoding: str, schema: Schema | None
                    ) -> Callable[[bytes | memoryview], Message] | None:
        """A decoder for ``json`` channels of the four Foxglove camera schemas."""
        if message_encoding != JSON or schema is None or schema.name not in FOXGLOVE_TYPES:
            return None
        name = schema.name

        def decode(data: bytes | memoryview) -> Message:
            try:
                fields = json_loads(bytes(data), f"{name} JSON", ReplayError)
                if not isinstance(fields, dict):
                    raise TypeError("not a JSON object")
                fields["stamp_ns"] = _json_stamp_ns(fields.get("timestamp"))
                fields.setdefault("frame_id", "")
                if "data" in fields:
                    fields["data"] = base64.b64decode(fields["data"], validate=True)
            except _JSON_ERRORS as err:
                raise ReplayError(f"cannot decode {name} JSON: {err}") from None
            return _build(name, fields)

        return decode


def _timestamp(stamp_ns: int) -> Any:
    from google.protobuf.timestamp_pb2 import Timestamp

    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    return Timestamp(seconds=sec, nanos=nsec)


def to_foxglove(message: Message) -> Any:
    """The ``foxglove_schemas_protobuf`` message of a camera record."""
    import foxglove_schemas_protobuf.CameraCalibration_pb2 as calibration_pb2
    import foxglove_schemas_protobuf.CompressedImage_pb2 as compressed_pb2
    import foxglove_schemas_protobuf.CompressedVideo_pb2 as video_pb2
    import foxglove_schemas_protobuf.RawImage_pb2 as raw_pb2

    match message:
        case Image():
            pixels = np.ascontiguousarray(message.pixels)
            return raw_pb2.RawImage(
                timestamp=_timestamp(message.stamp_ns), frame_id=message.frame_id,
                width=message.width, height=message.height, encoding=message.encoding,
                step=pixels.nbytes // max(pixels.shape[0], 1), data=pixels.tobytes())
        case CompressedImage():
            return compressed_pb2.CompressedImage(
                timestamp=_timestamp(message.stamp_ns), frame_id=message.frame_id,
                data=message.data, format=message.format.split(";")[-1].split()[0]
                if ";" in message.format else message.format)
        case CompressedVideo():
            return video_pb2.CompressedVideo(
                timestamp=_timestamp(message.stamp_ns), frame_id=message.frame_id,
                data=message.data, format=message.format)
        case CameraInfo():
            return calibration_pb2.CameraCalibration(
                timestamp=_timestamp(message.stamp_ns), frame_id=message.frame_id,
                width=message.width, height=message.height,
                distortion_model=message.distortion_model, D=list(message.d),
                K=list(message.k.reshape(-1)), R=list(message.r.reshape(-1)),
                P=list(message.p.reshape(-1)))
    raise ReplayError(f"no Foxglove schema holds {type(message).__name__}")


def foxglove_schema(proto: Any) -> Schema:
    """The MCAP schema record (a FileDescriptorSet) of a Foxglove protobuf message."""
    from mcap_protobuf.schema import build_file_descriptor_set

    data = build_file_descriptor_set(type(proto)).SerializeToString()
    return Schema(id=0, name=proto.DESCRIPTOR.full_name, encoding=PROTOBUF, data=data)

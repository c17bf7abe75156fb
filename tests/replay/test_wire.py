"""Serialization of typed records: CDR, ROS1, and the decoder factories readers use."""

from __future__ import annotations

import numpy as np
import pytest
from mcap.records import Schema

from replay import EncodingError, Image, Message, ReplayError
from replay.wire import (
    CDR,
    ROS1,
    convert_serialization,
    decoder_for,
    deserialize,
    msgtype_of,
    ros2_typestore,
    serialize,
)

from .samples import every_kind, random_pixels

KINDS = [message for _, _, message in every_kind()]
KIND_IDS = [topic for topic, _, _ in every_kind()]


@pytest.mark.parametrize("serialization", [CDR, ROS1])
@pytest.mark.parametrize("message", KINDS, ids=KIND_IDS)
def test_serialize_round_trip(message: Message, serialization: str) -> None:
    data = serialize(message, serialization)
    assert deserialize(data, msgtype_of(message), serialization) == message


@pytest.mark.parametrize("message", KINDS, ids=KIND_IDS)
def test_convert_serialization_between_cdr_and_ros1(message: Message) -> None:
    msgtype = msgtype_of(message)
    cdr = serialize(message, CDR)
    ros1 = convert_serialization(cdr, msgtype, CDR, ROS1)
    assert ros1 == serialize(message, ROS1)
    assert convert_serialization(ros1, msgtype, ROS1, CDR) == cdr


def _ros_image(encoding: str, data: np.ndarray, *, height: int, width: int, step: int,
               bigendian: bool) -> bytes:
    types = ros2_typestore().types
    msg = types["sensor_msgs/msg/Image"](
        header=types["std_msgs/msg/Header"](
            stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="cam"
        ),
        height=height, width=width, encoding=encoding, is_bigendian=int(bigendian), step=step,
        data=data.reshape(-1).view(np.uint8),
    )
    return bytes(ros2_typestore().serialize_cdr(msg, "sensor_msgs/msg/Image"))


def test_big_endian_16_bit_image_decodes_to_native_values() -> None:
    values = np.array([[1, 256, 65535], [4660, 0, 43981]], dtype=">u2")
    data = _ros_image("mono16", values, height=2, width=3, step=6, bigendian=True)
    image = deserialize(data, "sensor_msgs/msg/Image", CDR)
    assert isinstance(image, Image)
    assert image.pixels.dtype == np.dtype("<u2")
    assert image.pixels.tolist() == values.tolist()
    assert image.stamp_ns == 1_000_000_002


def test_row_padding_is_dropped() -> None:
    pixels = random_pixels("rgb8", height=3, width=5)
    padded = np.zeros((3, 20), np.uint8)
    padded[:, :15] = pixels.reshape(3, 15)
    data = _ros_image("rgb8", padded, height=3, width=5, step=20, bigendian=False)
    image = deserialize(data, "sensor_msgs/msg/Image", CDR)
    assert isinstance(image, Image)
    assert np.array_equal(image.pixels, pixels)


def test_image_buffer_too_small_is_an_encoding_error() -> None:
    data = _ros_image("mono8", np.zeros(5, np.uint8), height=2, width=3, step=3,
                      bigendian=False)
    with pytest.raises(EncodingError, match="too small"):
        deserialize(data, "sensor_msgs/msg/Image", CDR)


def test_deserialize_rejects_unknown_types_and_garbage() -> None:
    with pytest.raises(ReplayError, match="no typed record for sensor_msgs/msg/Imu"):
        deserialize(b"\x00\x01\x00\x00", "sensor_msgs/msg/Imu", CDR)
    with pytest.raises(ReplayError, match="cannot deserialize sensor_msgs/msg/CameraInfo"):
        deserialize(b"\x00\x01\x00\x00\x01", "sensor_msgs/msg/CameraInfo", CDR)


@pytest.mark.parametrize("serialization", [CDR, ROS1])
def test_decoder_factories_decode_ros_channels_by_schema_name(serialization: str) -> None:
    image = Image(4, "cam", "mono8", random_pixels("mono8"))
    name = "sensor_msgs/Image" if serialization == ROS1 else "sensor_msgs/msg/Image"
    schema = Schema(id=1, name=name, encoding=f"{serialization[:4]}msg", data=b"")
    assert decoder_for(serialization, schema)(serialize(image, serialization)) == image


def test_decoder_factories_name_what_no_factory_decodes() -> None:
    schema = Schema(id=1, name="foo.Bar", encoding="flatbuffer", data=b"")
    with pytest.raises(ReplayError, match=r"no typed record for foo\.Bar \(flatbuffer\)"):
        decoder_for("flatbuffer", schema)
    with pytest.raises(ReplayError, match="no typed record for schemaless messages"):
        decoder_for("json", None)

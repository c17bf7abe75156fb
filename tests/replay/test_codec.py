"""Serialization of typed records and JPEG/PNG compression."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from replay import CompressedImage, EncodingError, Image, Message, ReplayError, open_reader
from replay.codec import (
    CDR,
    ROS1,
    convert_serialization,
    decode_compressed,
    deserialize,
    encode_compressed,
    msgtype_of,
    ros2_typestore,
    serialize,
)

from .samples import every_kind, random_pixels, write_log

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


def _smooth_rgb(height: int = 48, width: int = 64) -> np.ndarray:
    """Gradients JPEG reproduces closely: ``(H, W, 3)`` uint8."""
    y, x = np.mgrid[0:height, 0:width]
    return np.stack([x * 255 // width, y * 255 // height, (x + y) * 255 // (width + height)],
                    axis=-1).astype(np.uint8)


@pytest.mark.parametrize("encoding", ["rgb8", "bgr8", "mono8", "mono16"])
def test_png_round_trip_is_exact(encoding: str) -> None:
    image = Image(5, "cam", encoding, random_pixels(encoding, height=10, width=12))
    compressed = encode_compressed(image, "png")
    assert compressed.format.endswith("png compressed " + compressed.format.split(";")[0])
    decoded = decode_compressed(compressed)
    assert (decoded.stamp_ns, decoded.frame_id) == (5, "cam")
    match encoding:
        case "bgr8":
            assert decoded.encoding == "rgb8"
            assert np.array_equal(decoded.pixels, image.pixels[:, :, ::-1])
        case _:
            assert decoded.encoding == encoding
            assert np.array_equal(decoded.pixels, image.pixels)


def test_png_of_rgba_drops_alpha_exactly() -> None:
    pixels = random_pixels("rgba8")
    decoded = decode_compressed(encode_compressed(Image(0, "cam", "rgba8", pixels), "png"))
    assert decoded.encoding == "rgb8"
    assert np.array_equal(decoded.pixels, pixels[:, :, :3])


def test_jpeg_round_trip_is_close() -> None:
    pixels = _smooth_rgb()
    compressed = encode_compressed(Image(9, "cam", "rgb8", pixels), "jpeg", jpeg_quality=95)
    assert compressed.data[:2] == b"\xff\xd8"
    decoded = decode_compressed(compressed)
    assert decoded.encoding == "rgb8" and decoded.pixels.shape == pixels.shape
    error = np.abs(decoded.pixels.astype(np.int16) - pixels.astype(np.int16))
    assert error.mean() < 2.0
    assert error.max() < 24


def test_compression_errors() -> None:
    mono16 = Image(0, "cam", "mono16", random_pixels("mono16"))
    with pytest.raises(EncodingError, match="JPEG cannot hold mono16"):
        encode_compressed(mono16, "jpeg")
    with pytest.raises(EncodingError, match="'webp'"):
        encode_compressed(mono16, "webp")
    with pytest.raises(EncodingError, match="cannot decode compressed image"):
        decode_compressed(CompressedImage(0, "cam", "jpeg", b"not a jpeg"))
    with pytest.raises(EncodingError, match="cannot decode compressed image"):
        decode_compressed(CompressedImage(0, "cam", "jpeg", b""))


@pytest.mark.parametrize("fmt", ["jpeg", "png"])
def test_compressed_images_from_a_log_decode(tmp_path: Path, fmt: str) -> None:
    pixels = _smooth_rgb()
    compressed = encode_compressed(Image(3, "cam", "rgb8", pixels), fmt)
    write_log(tmp_path / "c.mcap", [("/cam/compressed", 3, compressed)])
    with open_reader(tmp_path / "c.mcap") as reader:
        (record,) = reader.messages()
    assert record.message == compressed
    assert isinstance(record.message, CompressedImage)
    decoded = decode_compressed(record.message)
    error = np.abs(decoded.pixels.astype(np.int16) - pixels.astype(np.int16))
    assert error.max() == 0 if fmt == "png" else error.mean() < 2.0

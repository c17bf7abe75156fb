"""The type names importable without numpy agree with the typed records they name."""

from __future__ import annotations

from replay.messages import MSGTYPES, CameraInfo, CompressedImage, CompressedVideo, Image
from replay.msgtypes import CAMERA_INFO_TYPES, DECODABLE, FRAME_TYPES, normalize_msgtype
from replay.wire import RECORD_TYPES


def test_every_record_is_named_by_its_own_type() -> None:
    assert {MSGTYPES[RECORD_TYPES[name]] for name in MSGTYPES.values()} == set(MSGTYPES.values())
    assert all(RECORD_TYPES[name] is kind for kind, name in MSGTYPES.items())


def test_frame_and_camera_info_names_are_those_of_their_records() -> None:
    frames = {name for name, kind in RECORD_TYPES.items()
              if kind in (Image, CompressedImage, CompressedVideo)}
    infos = {name for name, kind in RECORD_TYPES.items() if kind is CameraInfo}
    assert (frames, infos) == (FRAME_TYPES, CAMERA_INFO_TYPES)


def test_decodable_are_the_ros_types_of_the_records() -> None:
    assert {name for name in MSGTYPES.values() if "/msg/" in name} == DECODABLE
    assert "foxglove.CompressedVideo" not in DECODABLE


def test_ros1_type_names_gain_msg() -> None:
    assert normalize_msgtype("sensor_msgs/Image") == "sensor_msgs/msg/Image"
    assert normalize_msgtype("sensor_msgs/msg/Image") == "sensor_msgs/msg/Image"
    assert normalize_msgtype("foxglove.RawImage") == "foxglove.RawImage"

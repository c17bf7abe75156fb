"""Entry checks shared by the commands that read one log and write another."""

from __future__ import annotations

from collections.abc import Iterable

from replay.formats import LogReader
from replay.messages import CameraInfo
from replay.msgtypes import CAMERA_INFO, POINT_STAMPED, POSE_STAMPED
from replay.wire import FRAME_TYPES, RECORD_TYPES

from ..errors import InputError

#: types whose messages are camera frames (ROS and Foxglove images, Foxglove video)
IMAGE_TYPES = tuple(sorted(FRAME_TYPES))
#: types with a header stamp (what a throttle can thin)
STAMPED_TYPES = (*IMAGE_TYPES, CAMERA_INFO, POINT_STAMPED, POSE_STAMPED)
#: types of camera models (ROS camera_info, Foxglove CameraCalibration)
INFO_TYPES = tuple(sorted(t for t, kind in RECORD_TYPES.items() if kind is CameraInfo))
#: a camera namespace's camera model topic, most preferred first
INFO_SUFFIXES = ("camera_info", "calibration", "camera_calibration")


def camera_info_topic(reader: LogReader, namespace: str) -> str | None:
    """The camera model topic of a camera namespace, if the log has one with messages."""
    for suffix in INFO_SUFFIXES:
        info = reader.topics.get(f"{namespace}/{suffix}")
        if info is not None and info.count and info.msgtype in INFO_TYPES:
            return info.name
    return None


def require_messages(reader: LogReader) -> None:
    """Fail unless the log holds at least one message."""
    if reader.message_count == 0:
        raise InputError(f"{reader.path} is empty (no messages)")


def require_topic(reader: LogReader, topic: str, msgtypes: Iterable[str]) -> str:
    """The type of ``topic``; fails with the topics that exist when it is missing or empty."""
    info = reader.topics.get(topic)
    if info is None or info.count == 0:
        listed = ", ".join(sorted(t for t, i in reader.topics.items() if i.count)) or "none"
        what = "has no topic" if info is None else "has no messages on"
        raise InputError(f"{reader.path} {what} {topic} (topics: {listed})")
    allowed = tuple(msgtypes)
    if info.msgtype not in allowed:
        raise InputError(
            f"{reader.path}: {topic} is {info.msgtype}, expected {' or '.join(allowed)}"
        )
    return info.msgtype


def require_free_topics(reader: LogReader, topics: Iterable[str], *, hint: str) -> None:
    """Fail when an output topic already exists in the input (it would be mixed in)."""
    taken = sorted(set(topics) & set(reader.topics))
    if taken:
        raise InputError(f"{reader.path} already has {', '.join(taken)}; {hint}")

"""Entry checks shared by the commands that read one log and write another."""

from __future__ import annotations

from collections.abc import Iterable

from replay.formats import LogReader

from ..errors import InputError

IMAGE_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")
#: types with a header stamp (what a throttle can thin)
STAMPED_TYPES = (*IMAGE_TYPES, "sensor_msgs/msg/CameraInfo", "geometry_msgs/msg/PointStamped",
                 "geometry_msgs/msg/PoseStamped")


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

"""ROS serializations of typed records: ROS 2 CDR and ROS1, through rosbags' typestore.

Serialization itself is done by rosbags; this module only maps fields between rosbags'
message classes and :mod:`replay.messages`. An image's bytes are cut into an array with the
layout its encoding has in :data:`replay.frames.DECODERS`.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from .. import msgtypes
from ..errors import ReplayError
from ..messages import (
    MSGTYPES,
    CameraInfo,
    CompressedImage,
    Image,
    Message,
    PointStamped,
    PoseStamped,
    Text,
)
from ..msgtypes import CDR, DECODABLE, ROS1
from .layout import image_from_buffer


@cache
def ros2_typestore() -> Typestore:
    """Typestore used to serialize ROS 2 (CDR) messages."""
    return get_typestore(Stores.ROS2_HUMBLE)


@cache
def ros1_typestore() -> Typestore:
    """Typestore used for ROS1 message definitions (Header carries ``seq``)."""
    return get_typestore(Stores.ROS1_NOETIC)


def msgtype_of(message: Message) -> str:
    """ROS 2 type name of a typed record."""
    return MSGTYPES[type(message)]


def _header(ts: Typestore, stamp_ns: int, frame_id: str) -> Any:
    time_cls = ts.types["builtin_interfaces/msg/Time"]
    header_cls = ts.types["std_msgs/msg/Header"]
    sec, nanosec = divmod(int(stamp_ns), 1_000_000_000)
    return header_cls(stamp=time_cls(sec=sec, nanosec=nanosec), frame_id=frame_id)


def _stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def to_ros(message: Message) -> Any:
    """Build the rosbags (ROS 2) message object for a typed record."""
    ts = ros2_typestore()
    types = ts.types
    match message:
        case Image():
            pixels = np.ascontiguousarray(message.pixels)
            channels = 1 if pixels.ndim == 2 else pixels.shape[2]
            row_bytes = pixels.shape[1] * pixels.itemsize * channels
            big = pixels.dtype.itemsize > 1 and pixels.dtype.byteorder == ">"
            return types[msgtypes.IMAGE](
                header=_header(ts, message.stamp_ns, message.frame_id),
                height=message.height,  # semi-planar YUV: fewer than the buffer's rows
                width=pixels.shape[1],
                encoding=message.encoding,
                is_bigendian=int(big),
                step=row_bytes,
                data=pixels.reshape(-1).view(np.uint8),
            )
        case CompressedImage():
            return types[msgtypes.COMPRESSED_IMAGE](
                header=_header(ts, message.stamp_ns, message.frame_id),
                format=message.format,
                data=np.frombuffer(message.data, dtype=np.uint8),
            )
        case CameraInfo():
            roi_cls = types["sensor_msgs/msg/RegionOfInterest"]
            x, y, h, w, rectify = message.roi
            return types[msgtypes.CAMERA_INFO](
                header=_header(ts, message.stamp_ns, message.frame_id),
                height=message.height,
                width=message.width,
                distortion_model=message.distortion_model,
                d=np.asarray(message.d, dtype=np.float64),
                k=message.k.reshape(-1).astype(np.float64),
                r=message.r.reshape(-1).astype(np.float64),
                p=message.p.reshape(-1).astype(np.float64),
                binning_x=message.binning_x,
                binning_y=message.binning_y,
                roi=roi_cls(x_offset=x, y_offset=y, height=h, width=w, do_rectify=rectify),
            )
        case PoseStamped():
            pos = message.position_m
            q = message.orientation_xyzw
            return types[msgtypes.POSE_STAMPED](
                header=_header(ts, message.stamp_ns, message.frame_id),
                pose=types["geometry_msgs/msg/Pose"](
                    position=types["geometry_msgs/msg/Point"](x=pos[0], y=pos[1], z=pos[2]),
                    orientation=types["geometry_msgs/msg/Quaternion"](
                        x=q[0], y=q[1], z=q[2], w=q[3]
                    ),
                ),
            )
        case PointStamped():
            p = message.point
            return types[msgtypes.POINT_STAMPED](
                header=_header(ts, message.stamp_ns, message.frame_id),
                point=types["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
            )
        case Text():
            return types[msgtypes.STRING](data=message.data)
    raise TypeError(f"not a camlog message: {type(message).__name__}")


def serialize(message: Message, serialization: str = CDR) -> bytes:
    """Serialize a typed record to CDR (ROS 2) or ROS1 bytes."""
    msgtype = msgtype_of(message)
    ts = ros2_typestore()
    cdr = ts.serialize_cdr(to_ros(message), msgtype)
    if serialization == CDR:
        return bytes(cdr)
    return bytes(ts.cdr_to_ros1(cdr, msgtype))


def _image_from_ros(msg: Any) -> Image:
    return image_from_buffer(
        _stamp_ns(msg.header), str(msg.header.frame_id), width=int(msg.width),
        height=int(msg.height), encoding=str(msg.encoding), step=int(msg.step),
        data=np.asarray(msg.data, dtype=np.uint8), bigendian=bool(msg.is_bigendian))


def from_ros(msg: Any) -> Message:
    """Typed record for a rosbags message object (ROS 1 or ROS 2 definitions)."""
    msgtype = msg.__msgtype__
    match msgtype:
        case msgtypes.IMAGE:
            return _image_from_ros(msg)
        case msgtypes.COMPRESSED_IMAGE:
            return CompressedImage(
                _stamp_ns(msg.header), str(msg.header.frame_id), str(msg.format),
                bytes(np.asarray(msg.data, dtype=np.uint8)),
            )
        case msgtypes.CAMERA_INFO:
            # ROS1 spells the fields D, K, R, P.
            def get(name: str) -> Any:
                return getattr(msg, name) if hasattr(msg, name) else getattr(msg, name.upper())

            roi = msg.roi
            return CameraInfo(
                stamp_ns=_stamp_ns(msg.header),
                frame_id=str(msg.header.frame_id),
                width=int(msg.width),
                height=int(msg.height),
                distortion_model=str(msg.distortion_model),
                d=np.asarray(get("d"), dtype=np.float64),
                k=np.asarray(get("k"), dtype=np.float64).reshape(3, 3),
                r=np.asarray(get("r"), dtype=np.float64).reshape(3, 3),
                p=np.asarray(get("p"), dtype=np.float64).reshape(3, 4),
                binning_x=int(msg.binning_x),
                binning_y=int(msg.binning_y),
                roi=(int(roi.x_offset), int(roi.y_offset), int(roi.height), int(roi.width),
                     bool(roi.do_rectify)),
            )
        case msgtypes.POSE_STAMPED:
            p, q = msg.pose.position, msg.pose.orientation
            return PoseStamped(
                _stamp_ns(msg.header), str(msg.header.frame_id),
                np.array([p.x, p.y, p.z]), np.array([q.x, q.y, q.z, q.w]),
            )
        case msgtypes.POINT_STAMPED:
            p = msg.point
            return PointStamped(
                _stamp_ns(msg.header), str(msg.header.frame_id), np.array([p.x, p.y, p.z])
            )
        case msgtypes.STRING:
            return Text(str(msg.data))
    raise ReplayError(f"camlog has no typed record for {msgtype}")


def deserialize(
    data: bytes | memoryview, msgtype: str, serialization: str, typestore: Typestore | None = None
) -> Message:
    """Typed record from serialized bytes; ``typestore`` defaults by serialization."""
    if msgtype not in DECODABLE:
        raise ReplayError(f"camlog has no typed record for {msgtype}")
    try:
        if serialization == CDR:
            msg = (typestore or ros2_typestore()).deserialize_cdr(data, msgtype)
        else:
            msg = (typestore or ros1_typestore()).deserialize_ros1(data, msgtype)
    except (SerdeError, ValueError, IndexError, KeyError, TypeError) as err:
        raise ReplayError(f"cannot deserialize {msgtype}: {err}") from None
    return from_ros(msg)


def convert_serialization(data: bytes | memoryview, msgtype: str, src: str,
                          dst: str) -> bytes | memoryview:
    """Re-serialize raw bytes between CDR and ROS1 wire format, byte by byte (``data`` itself
    when equal); the result is a buffer of its own, not copied again."""
    if src == dst:
        return data
    ts = ros2_typestore()
    if src == ROS1:
        return ts.ros1_to_cdr(data, msgtype)
    return ts.cdr_to_ros1(data, msgtype)

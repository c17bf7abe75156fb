"""Conversion between typed records and serialized ROS messages.

Serialization itself (CDR for ROS 2, ROS1 wire format) is done by rosbags' typestore; this
module only maps fields between rosbags' message classes and :mod:`replay.messages`.
"""

from __future__ import annotations

from functools import cache
from typing import Any, Literal

import cv2
import numpy as np
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from .errors import EncodingError, ReplayError
from .messages import (
    IMAGE_ENCODINGS,
    MSGTYPES,
    CameraInfo,
    CompressedImage,
    Image,
    Message,
    PointStamped,
    PoseStamped,
    Text,
)

#: serialization of raw bytes in a log
CDR = "cdr"
ROS1 = "ros1"


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
            return types["sensor_msgs/msg/Image"](
                header=_header(ts, message.stamp_ns, message.frame_id),
                height=pixels.shape[0],
                width=pixels.shape[1],
                encoding=message.encoding,
                is_bigendian=int(big),
                step=row_bytes,
                data=pixels.reshape(-1).view(np.uint8),
            )
        case CompressedImage():
            return types["sensor_msgs/msg/CompressedImage"](
                header=_header(ts, message.stamp_ns, message.frame_id),
                format=message.format,
                data=np.frombuffer(message.data, dtype=np.uint8),
            )
        case CameraInfo():
            roi_cls = types["sensor_msgs/msg/RegionOfInterest"]
            x, y, h, w, rectify = message.roi
            return types["sensor_msgs/msg/CameraInfo"](
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
            return types["geometry_msgs/msg/PoseStamped"](
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
            return types["geometry_msgs/msg/PointStamped"](
                header=_header(ts, message.stamp_ns, message.frame_id),
                point=types["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
            )
        case Text():
            return types["std_msgs/msg/String"](data=message.data)
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
    encoding = str(msg.encoding)
    if encoding not in IMAGE_ENCODINGS:
        raise EncodingError(f"unsupported image encoding {encoding!r}")
    dtype, channels = IMAGE_ENCODINGS[encoding]
    height, width, step = int(msg.height), int(msg.width), int(msg.step)
    row = width * channels * dtype.itemsize
    data = np.asarray(msg.data, dtype=np.uint8)
    if step < row or data.size < step * height:
        raise EncodingError(
            f"image buffer of {data.size} bytes too small for {width}x{height} {encoding} "
            f"(step {step})"
        )
    rows = data[: step * height].reshape(height, step)[:, :row]
    order: Literal["<", ">"] = ">" if msg.is_bigendian else "<"
    pixels = np.ascontiguousarray(rows).view(dtype.newbyteorder(order))
    if order == ">":
        pixels = pixels.astype(dtype)
    shape = (height, width) if channels == 1 else (height, width, channels)
    return Image(_stamp_ns(msg.header), str(msg.header.frame_id), encoding, pixels.reshape(shape))


def from_ros(msg: Any) -> Message:
    """Typed record for a rosbags message object (ROS 1 or ROS 2 definitions)."""
    msgtype = msg.__msgtype__
    match msgtype:
        case "sensor_msgs/msg/Image":
            return _image_from_ros(msg)
        case "sensor_msgs/msg/CompressedImage":
            return CompressedImage(
                _stamp_ns(msg.header), str(msg.header.frame_id), str(msg.format),
                bytes(np.asarray(msg.data, dtype=np.uint8)),
            )
        case "sensor_msgs/msg/CameraInfo":
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
        case "geometry_msgs/msg/PoseStamped":
            p, q = msg.pose.position, msg.pose.orientation
            return PoseStamped(
                _stamp_ns(msg.header), str(msg.header.frame_id),
                np.array([p.x, p.y, p.z]), np.array([q.x, q.y, q.z, q.w]),
            )
        case "geometry_msgs/msg/PointStamped":
            p = msg.point
            return PointStamped(
                _stamp_ns(msg.header), str(msg.header.frame_id), np.array([p.x, p.y, p.z])
            )
        case "std_msgs/msg/String":
            return Text(str(msg.data))
    raise ReplayError(f"camlog has no typed record for {msgtype}")


DECODABLE = frozenset(MSGTYPES.values())


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


def convert_serialization(data: bytes | memoryview, msgtype: str, src: str, dst: str) -> bytes:
    """Re-serialize raw bytes between CDR and ROS1 wire format (no-op when equal)."""
    if src == dst:
        return bytes(data)
    ts = ros2_typestore()
    if src == ROS1:
        return bytes(ts.ros1_to_cdr(data, msgtype))
    return bytes(ts.cdr_to_ros1(data, msgtype))


# --- compressed images -------------------------------------------------------------------

def decode_compressed(message: CompressedImage) -> Image:
    """Decode a JPEG/PNG CompressedImage to an Image (rgb8, mono8 or mono16)."""
    buf = np.frombuffer(message.data, dtype=np.uint8)
    array = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if buf.size else None
    if array is None:
        raise EncodingError(f"cannot decode compressed image (format {message.format!r})")
    if array.ndim == 2:
        encoding = "mono16" if array.dtype == np.uint16 else "mono8"
    elif array.shape[2] == 4:
        array, encoding = cv2.cvtColor(array, cv2.COLOR_BGRA2RGBA), "rgba8"
    else:
        array, encoding = cv2.cvtColor(array, cv2.COLOR_BGR2RGB), "rgb8"
    if array.dtype != np.uint8 and encoding != "mono16":
        raise EncodingError(f"unsupported compressed image depth {array.dtype}")
    return Image(message.stamp_ns, message.frame_id, encoding, array)


def encode_compressed(
    image: Image, fmt: str = "jpeg", *, jpeg_quality: int = 90
) -> CompressedImage:
    """Encode an Image as JPEG or PNG (the ``format`` string follows image_transport)."""
    if fmt not in ("jpeg", "png"):
        raise EncodingError(f"unsupported compression {fmt!r} (use jpeg or png)")
    array = to_bgr_or_mono(image)
    if fmt == "jpeg" and array.dtype != np.uint8:
        raise EncodingError(f"JPEG cannot hold {image.encoding} images; use png")
    params = [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality] if fmt == "jpeg" else []
    ok, buf = cv2.imencode(".jpg" if fmt == "jpeg" else ".png", array, params)
    if not ok:
        raise EncodingError(f"cannot encode {image.encoding} image as {fmt}")
    kind = "bgr8" if array.ndim == 3 else image.encoding
    return CompressedImage(image.stamp_ns, image.frame_id, f"{kind}; {fmt} compressed {kind}",
                           buf.tobytes())


def to_bgr_or_mono(image: Image) -> np.ndarray:
    """Pixels as OpenCV expects them: BGR for colour, single channel for mono."""
    px = image.pixels
    match image.encoding:
        case "rgb8":
            return cv2.cvtColor(px, cv2.COLOR_RGB2BGR)
        case "rgba8":
            return cv2.cvtColor(px, cv2.COLOR_RGBA2BGR)
        case "bgra8":
            return cv2.cvtColor(px, cv2.COLOR_BGRA2BGR)
    return px


def to_rgb8(image: Image) -> np.ndarray:
    """``(H, W, 3)`` uint8 RGB view of any supported encoding (16-bit scaled down)."""
    px = image.pixels
    match image.encoding:
        case "rgb8" | "8UC3":
            return px
        case "bgr8":
            return cv2.cvtColor(px, cv2.COLOR_BGR2RGB)
        case "rgba8":
            return cv2.cvtColor(px, cv2.COLOR_RGBA2RGB)
        case "bgra8":
            return cv2.cvtColor(px, cv2.COLOR_BGRA2RGB)
        case "mono8" | "8UC1":
            return cv2.cvtColor(px, cv2.COLOR_GRAY2RGB)
        case "mono16" | "16UC1":
            return cv2.cvtColor((px >> 8).astype(np.uint8), cv2.COLOR_GRAY2RGB)
    raise EncodingError(f"unsupported image encoding {image.encoding!r}")


def to_mono8(image: Image) -> np.ndarray:
    """``(H, W)`` uint8 grayscale of any supported encoding."""
    px = image.pixels
    match image.encoding:
        case "mono8" | "8UC1":
            return px
        case "mono16" | "16UC1":
            mono: np.ndarray = (px >> 8).astype(np.uint8)
            return mono
        case "bgr8":
            return cv2.cvtColor(px, cv2.COLOR_BGR2GRAY)
        case "bgra8":
            return cv2.cvtColor(px, cv2.COLOR_BGRA2GRAY)
        case "rgba8":
            return cv2.cvtColor(px, cv2.COLOR_RGBA2GRAY)
    return cv2.cvtColor(to_rgb8(image), cv2.COLOR_RGB2GRAY)
